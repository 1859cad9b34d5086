//! Direct solve: faer sparse Cholesky (AMD ordering) of the free-node block of D + K.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use faer::{MatMut, Side};

use crate::error::SolveError;
use crate::solve::LinearSystem;

/// The factorised free-node block and the node ↔ unknown maps.
#[derive(Debug)]
pub(crate) struct Factor {
    /// Node of each unknown.
    nodes: Vec<u32>,
    llt: Llt<usize, f64>,
}

impl Factor {
    /// Assembles the lower triangle of the free block and factorises it.
    pub(crate) fn new(sys: &LinearSystem<'_>) -> Result<Self, SolveError> {
        let net = sys.net;
        let n = net.n_nodes();
        let mut index = vec![u32::MAX; n];
        let mut nodes = Vec::new();
        for (p, &f) in sys.free.iter().enumerate() {
            if f {
                index[p] = nodes.len() as u32;
                nodes.push(p as u32);
            }
        }
        let m = nodes.len();
        let mut triplets = Vec::with_capacity(m + net.cols().len() / 2);
        for (k, &p) in nodes.iter().enumerate() {
            let p = p as usize;
            triplets.push(Triplet::new(k, k, sys.diag[p]));
            for e in net.row_ptr()[p]..net.row_ptr()[p + 1] {
                let kq = index[net.cols()[e] as usize];
                if kq != u32::MAX && (kq as usize) < k {
                    triplets.push(Triplet::new(k, kq as usize, -sys.entry_value(e)));
                }
            }
        }
        let mat = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &triplets)
            .map_err(|e| SolveError::Factorization(format!("assembly: {e:?}")))?;
        let symbolic = SymbolicLlt::try_new(mat.symbolic(), Side::Lower)
            .map_err(|e| SolveError::Factorization(format!("symbolic: {e:?}")))?;
        let llt = Llt::try_new_with_symbolic(symbolic, mat.as_ref(), Side::Lower)
            .map_err(|e| SolveError::Factorization(format!("numeric: {e:?}")))?;
        Ok(Self { nodes, llt })
    }

    /// x += A⁻¹ r on the free nodes.
    pub(crate) fn solve(&self, _sys: &LinearSystem<'_>, r: &[f64], x: &mut [f64]) {
        let mut rhs: Vec<f64> = self.nodes.iter().map(|&p| r[p as usize]).collect();
        let m = rhs.len();
        self.llt
            .solve_in_place(MatMut::from_column_major_slice_mut(&mut rhs, m, 1));
        for (&p, d) in self.nodes.iter().zip(&rhs) {
            x[p as usize] += d;
        }
    }
}
