//! The conductance network: nodes, edges, and the compressed-row structure of its weighted
//! Laplacian, built once; conductance values are supplied per solve.

use demcon_core::Components;
use demcon_core::check::{check_finite, check_len};
use rayon::prelude::*;

use crate::error::SolveError;
use crate::par::CHUNK;

/// A conductance network: `n_nodes` nodes joined by undirected edges.
///
/// The structure of its weighted Laplacian K (K_pp = Σ_q g_pq, K_pq = −g_pq) is stored in
/// compressed rows: row p lists its neighbours q (sorted by index, then by edge) and the edge
/// that joins them. Conductances g (W/K or S, one per edge) are passed to each solve, so the
/// same structure serves thermal and electric problems and changing values costs no rebuild.
/// Several edges between the same two nodes act in parallel.
#[derive(Debug, Clone)]
pub struct Network {
    n_nodes: usize,
    edges: Vec<[u32; 2]>,
    row_ptr: Vec<usize>,
    cols: Vec<u32>,
    entry_edge: Vec<u32>,
}

impl Network {
    /// Builds the network and the compressed-row structure of its Laplacian.
    ///
    /// `edges[e] = [p, q]` joins nodes p and q (p ≠ q, both < `n_nodes`).
    ///
    /// # Errors
    /// [`SolveError::NodeOutOfRange`] for an index ≥ `n_nodes`, [`SolveError::SelfLoop`] for
    /// p = q, [`SolveError::InvalidParameter`] when `n_nodes` or the edge count exceed `u32`.
    pub fn new(n_nodes: usize, edges: &[[u32; 2]]) -> Result<Self, SolveError> {
        if n_nodes > u32::MAX as usize {
            return Err(SolveError::invalid(
                "n_nodes",
                n_nodes,
                "must fit in u32 (≤ 4 294 967 295)",
            ));
        }
        if edges.len() > u32::MAX as usize {
            return Err(SolveError::invalid("edges.len()", edges.len(), "must fit in u32"));
        }
        let mut degree = vec![0usize; n_nodes];
        for (e, &[p, q]) in edges.iter().enumerate() {
            for node in [p, q] {
                if node as usize >= n_nodes {
                    return Err(SolveError::NodeOutOfRange {
                        what: format!("edges[{e}]"),
                        node: node as u64,
                        n_nodes,
                    });
                }
            }
            if p == q {
                return Err(SolveError::SelfLoop { edge: e, node: p });
            }
            degree[p as usize] += 1;
            degree[q as usize] += 1;
        }
        let mut row_ptr = Vec::with_capacity(n_nodes + 1);
        row_ptr.push(0usize);
        for d in &degree {
            let last = *row_ptr.last().unwrap_or(&0);
            row_ptr.push(last + d);
        }
        let nnz = row_ptr[n_nodes];
        let mut fill: Vec<usize> = row_ptr[..n_nodes].to_vec();
        let mut pairs = vec![(0u32, 0u32); nnz];
        for (e, &[p, q]) in edges.iter().enumerate() {
            let (p, q) = (p as usize, q as usize);
            pairs[fill[p]] = (q as u32, e as u32);
            fill[p] += 1;
            pairs[fill[q]] = (p as u32, e as u32);
            fill[q] += 1;
        }
        // Sort each row by neighbour (then edge): better locality, fixed order.
        let mut slices: Vec<&mut [(u32, u32)]> = Vec::with_capacity(n_nodes);
        let mut rest: &mut [(u32, u32)] = &mut pairs;
        for d in &degree {
            let (head, tail) = rest.split_at_mut(*d);
            slices.push(head);
            rest = tail;
        }
        slices
            .into_par_iter()
            .with_min_len(1024)
            .for_each(|row| row.sort_unstable());
        let (cols, entry_edge) = pairs.into_iter().unzip();
        Ok(Self {
            n_nodes,
            edges: edges.to_vec(),
            row_ptr,
            cols,
            entry_edge,
        })
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.n_nodes
    }

    /// Number of edges (contacts).
    pub fn n_edges(&self) -> usize {
        self.edges.len()
    }

    /// The edges, as given.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// Row pointers of the compressed-row structure (length `n_nodes + 1`): the
    /// neighbours of node p are `cols()[row_ptr()[p]..row_ptr()[p + 1]]`.
    pub fn row_ptr(&self) -> &[usize] {
        &self.row_ptr
    }

    /// Neighbour of each compressed-row entry.
    pub fn cols(&self) -> &[u32] {
        &self.cols
    }

    /// Edge index of each compressed-row entry.
    pub fn entry_edges(&self) -> &[u32] {
        &self.entry_edge
    }

    /// Number of edges at node p.
    pub fn degree(&self, p: usize) -> usize {
        self.row_ptr[p + 1] - self.row_ptr[p]
    }

    /// Checks a conductance vector: one finite, strictly positive value per edge (W/K or S).
    ///
    /// # Errors
    /// [`SolveError::LengthMismatch`] or [`SolveError::InvalidParameter`] naming the edge.
    pub fn check_conductances(&self, conductances: &[f64]) -> Result<(), SolveError> {
        check_len("conductances", conductances.len(), self.n_edges())?;
        let bad = |g: &f64| !(g.is_finite() && *g > 0.0);
        // The first bad entry: its chunk found in parallel (10⁶-node networks: ~4·10⁶ edges).
        let first = conductances
            .par_chunks(CHUNK)
            .position_first(|c| c.iter().any(bad))
            .and_then(|c| {
                let at = c * CHUNK;
                conductances[at..].iter().position(bad).map(|k| at + k)
            });
        match first {
            None => Ok(()),
            Some(e) => Err(SolveError::invalid(
                format!("conductances[{e}] (edge {:?})", self.edges[e]),
                conductances[e],
                "must be a finite number > 0 (drop the edge instead of giving it zero conductance)",
            )),
        }
    }

    /// Conductances gathered into compressed-row order (one per entry).
    pub fn entry_values(&self, conductances: &[f64]) -> Vec<f64> {
        self.entry_edge
            .par_iter()
            .with_min_len(CHUNK)
            .map(|&e| conductances[e as usize])
            .collect()
    }

    /// Diagonal of the Laplacian: Σ_q g_pq for each node p (W/K or S).
    pub fn row_sums(&self, conductances: &[f64]) -> Vec<f64> {
        (0..self.n_nodes)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(|p| {
                self.entry_edge[self.row_ptr[p]..self.row_ptr[p + 1]]
                    .iter()
                    .map(|&e| conductances[e as usize])
                    .sum()
            })
            .collect()
    }

    /// y = K x, the Laplacian applied to a nodal vector: y_p = Σ_q g_pq (x_p − x_q), the net
    /// flow leaving node p (W or A when x is in K or V).
    ///
    /// # Errors
    /// Length mismatches, non-finite or non-positive conductances, non-finite `x`.
    pub fn apply_laplacian(&self, conductances: &[f64], x: &[f64]) -> Result<Vec<f64>, SolveError> {
        self.check_conductances(conductances)?;
        check_len("x", x.len(), self.n_nodes)?;
        check_finite("x", x)?;
        Ok((0..self.n_nodes)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(|p| {
                let range = self.row_ptr[p]..self.row_ptr[p + 1];
                self.cols[range.clone()]
                    .iter()
                    .zip(&self.entry_edge[range])
                    .map(|(&q, &e)| conductances[e as usize] * (x[p] - x[q as usize]))
                    .sum()
            })
            .collect())
    }

    /// Connected components (structural: every edge counts), labelled by decreasing size,
    /// ties by smallest node ([`Components`]).
    pub fn components(&self) -> Components {
        Components::from_pairs(self.n_nodes, &self.edges)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_sorted_rows_and_rejects_bad_edges() {
        let net = Network::new(4, &[[2, 0], [0, 1], [1, 2]]).unwrap();
        assert_eq!(net.row_ptr(), &[0, 2, 4, 6, 6]);
        assert_eq!(&net.cols()[0..2], &[1, 2]);
        assert_eq!(&net.entry_edges()[0..2], &[1, 0]);
        assert_eq!(net.degree(3), 0);
        assert!(matches!(
            Network::new(3, &[[0, 3]]),
            Err(SolveError::NodeOutOfRange { node: 3, .. })
        ));
        assert!(matches!(
            Network::new(3, &[[1, 1]]),
            Err(SolveError::SelfLoop { edge: 0, node: 1 })
        ));
    }

    #[test]
    fn laplacian_row_sums_vanish_and_it_is_symmetric() {
        let edges = [[0, 1], [1, 2], [2, 3], [3, 0], [0, 2], [1, 3], [1, 3]];
        let g = [1.0, 2.0, 0.5, 3.0, 0.25, 1.5, 0.5];
        let net = Network::new(4, &edges).unwrap();
        // K·1 = 0 (row sums vanish).
        let k1 = net.apply_laplacian(&g, &[1.0; 4]).unwrap();
        assert!(k1.iter().all(|v| v.abs() < 1e-14));
        // Symmetry: e_i·K e_j = e_j·K e_i.
        let col = |j: usize| {
            let mut x = [0.0; 4];
            x[j] = 1.0;
            net.apply_laplacian(&g, &x).unwrap()
        };
        for i in 0..4 {
            for j in 0..4 {
                assert_eq!(col(j)[i], col(i)[j]);
            }
        }
        // Parallel edges add.
        assert_eq!(col(1)[3], -2.0);
        assert_eq!(net.row_sums(&g)[1], 1.0 + 2.0 + 1.5 + 0.5);
    }

    #[test]
    fn conductances_are_checked() {
        let net = Network::new(2, &[[0, 1]]).unwrap();
        assert!(matches!(
            net.check_conductances(&[0.0]),
            Err(SolveError::InvalidParameter { .. })
        ));
        assert!(matches!(
            net.check_conductances(&[f64::NAN]),
            Err(SolveError::InvalidParameter { .. })
        ));
        assert!(matches!(
            net.check_conductances(&[1.0, 2.0]),
            Err(SolveError::LengthMismatch { .. })
        ));
    }

    #[test]
    fn components_are_labelled_by_size_then_smallest_node() {
        let net = Network::new(6, &[[4, 5], [0, 2], [2, 3]]).unwrap();
        let c = net.components();
        assert_eq!(c.labels, vec![0, 2, 0, 0, 1, 1]);
        assert_eq!(c.sizes, vec![3, 2, 1]);
        assert_eq!(c.count(), 3);
    }
}
