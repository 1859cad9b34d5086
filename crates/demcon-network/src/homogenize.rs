//! Periodic homogenisation: the effective conductivity tensor of a periodic network.
//!
//! The field is u = G·x + ũ with a macroscopic gradient G and a periodic fluctuation ũ. An
//! edge e = (a, b) whose branch vector ℓ_e runs from a to (the image of) b carries the flow
//! F_e = g_e (u_a − u_b') = −g_e (ũ_b − ũ_a + G·ℓ_e) from a to b, so the fluctuation solves
//! K ũ = s with s_a = Σ_e g_e G·ℓ_e (a first) − Σ_e g_e G·ℓ_e (a second). ũ is fixed to 0 at
//! the smallest node of every connected component (the only null space of K; a finite
//! cluster then carries no flow, whatever its constant). The volume-averaged flux is
//! q̄ = (1/V) Σ_e F_e ℓ_e = −Λ G: the three gradients e_x, e_y, e_z give Λ's columns.
//!
//! All sums run over the edges in order, on one thread: the tensor does not depend on the
//! thread count.

use demcon_core::{Components, Vec3};
use nalgebra::{Matrix3, SymmetricEigen};

use crate::solve::{LinearSystem, SolveParams, SolveReport};
use crate::{FloatingPolicy, Network, SolveError, resolve_fixed};

/// The effective tensor of a periodic network and how it was obtained.
#[derive(Debug, Clone, PartialEq)]
pub struct Homogenized {
    /// Λ, row-major (W/(m·K) for heat, S/m for current): q̄ = −Λ G.
    pub tensor: [[f64; 3]; 3],
    /// max |Λ − Λᵀ| / max |Λ| (dimensionless): 0 up to the solves' accuracy.
    pub symmetry_error: f64,
    /// Eigenvalues of the symmetric part, ascending.
    pub eigenvalues: [f64; 3],
    /// The fluctuation ũ of each load case (G = e_x, e_y, e_z), per node (K per K/m = m).
    pub fluctuations: [Vec<f64>; 3],
    /// The three solves.
    pub solves: [SolveReport; 3],
    /// Connected components (one node of each held at 0).
    pub components: usize,
}

impl Homogenized {
    /// The scalar effective value along each axis, Λ_xx, Λ_yy, Λ_zz.
    pub fn diagonal(&self) -> [f64; 3] {
        [self.tensor[0][0], self.tensor[1][1], self.tensor[2][2]]
    }
}

/// The effective tensor of the periodic network `net` with edge conductances `g` (W/K or S),
/// edge branch vectors `branches` (m, from the edge's first node to the image of its second)
/// and cell volume `volume` (m³).
///
/// # Errors
/// Lengths that do not match the edges, a non-positive or non-finite volume or branch, and
/// the solver's errors.
pub fn homogenize(
    net: &Network,
    g: &[f64],
    branches: &[Vec3],
    volume: f64,
    params: &SolveParams,
) -> Result<Homogenized, SolveError> {
    net.check_conductances(g)?;
    if branches.len() != net.n_edges() {
        return Err(SolveError::invalid(
            "branches",
            format!("{} vectors", branches.len()),
            format!("one per edge ({})", net.n_edges()),
        ));
    }
    if let Some(k) = branches.iter().position(|b| !b.iter().all(|x| x.is_finite())) {
        return Err(SolveError::invalid(
            format!("branches[{k}]"),
            format!("{:?}", branches[k].as_slice()),
            "must be finite (m)",
        ));
    }
    if !(volume.is_finite() && volume > 0.0) {
        return Err(SolveError::invalid(
            "volume",
            volume,
            "must be a finite number > 0 (m³)",
        ));
    }
    let n = net.n_nodes();
    let comps = Components::from_pairs(n, net.edges());
    let mut anchor = vec![u32::MAX; comps.count()];
    for (p, &c) in comps.labels.iter().enumerate() {
        if anchor[c as usize] == u32::MAX {
            anchor[c as usize] = p as u32;
        }
    }
    let constraints = resolve_fixed(net, &[(anchor, 0.0)], FloatingPolicy::Fail)?;
    let sys = LinearSystem::new(net, g, None, &constraints, params)?;
    let mut tensor = [[0.0; 3]; 3];
    let mut fluctuations: [Vec<f64>; 3] = Default::default();
    let mut solves: Vec<SolveReport> = Vec::with_capacity(3);
    for j in 0..3 {
        let mut grad = Vec3::zeros();
        grad[j] = 1.0;
        let mut s = vec![0.0; n];
        for (e, &[a, b]) in net.edges().iter().enumerate() {
            let f = g[e] * grad.dot(&branches[e]);
            s[a as usize] += f;
            s[b as usize] -= f;
        }
        let sol = sys.solve(&s, None)?;
        let u = &sol.values;
        let mut q = Vec3::zeros();
        for (e, &[a, b]) in net.edges().iter().enumerate() {
            let flow = -g[e] * (u[b as usize] - u[a as usize] + grad.dot(&branches[e]));
            q += flow * branches[e];
        }
        q /= volume;
        for i in 0..3 {
            tensor[i][j] = -q[i];
        }
        fluctuations[j] = sol.values;
        solves.push(sol.report);
    }
    let m = Matrix3::from_fn(|i, j| tensor[i][j]);
    let scale = m.abs().max();
    let symmetry_error = if scale > 0.0 {
        (m - m.transpose()).abs().max() / scale
    } else {
        0.0
    };
    let eig = SymmetricEigen::new(0.5 * (m + m.transpose())).eigenvalues;
    let mut eigenvalues = [eig[0], eig[1], eig[2]];
    eigenvalues.sort_by(f64::total_cmp);
    let solves: [SolveReport; 3] = solves.try_into().expect("three load cases");
    Ok(Homogenized {
        tensor,
        symmetry_error,
        eigenvalues,
        fluctuations,
        solves,
        components: comps.count(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Method;

    /// A periodic simple-cubic lattice n³ of unit spacing: each node linked to its +x, +y, +z
    /// neighbour (wrapping), with conductance `g(axis)`.
    fn lattice(n: usize, g: impl Fn(usize) -> f64) -> (Network, Vec<f64>, Vec<Vec3>) {
        let id = |i: usize, j: usize, k: usize| ((i % n) + n * ((j % n) + n * (k % n))) as u32;
        let (mut edges, mut cond, mut br) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    for axis in 0..3 {
                        let (a, b) = match axis {
                            0 => (id(i, j, k), id(i + 1, j, k)),
                            1 => (id(i, j, k), id(i, j + 1, k)),
                            _ => (id(i, j, k), id(i, j, k + 1)),
                        };
                        edges.push([a, b]);
                        cond.push(g(axis));
                        let mut l = Vec3::zeros();
                        l[axis] = 1.0;
                        br.push(l);
                    }
                }
            }
        }
        (Network::new(n * n * n, &edges).unwrap(), cond, br)
    }

    fn params() -> SolveParams {
        SolveParams::new(Method::Auto, 1e-12, 10_000)
    }

    #[test]
    fn an_orthotropic_lattice_gives_its_diagonal_tensor() {
        // Unit cells of volume 1: Λ = diag(g_x, g_y, g_z) exactly, with no fluctuation.
        let (net, g, br) = lattice(4, |a| [2.0, 3.0, 5.0][a]);
        let h = homogenize(&net, &g, &br, 64.0, &params()).unwrap();
        let expect = [[2.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 5.0]];
        for (row, want) in h.tensor.iter().zip(&expect) {
            for (x, w) in row.iter().zip(want) {
                assert!((x - w).abs() < 1e-12, "{:?}", h.tensor);
            }
        }
        assert_eq!(h.eigenvalues, [2.0, 3.0, 5.0]);
        assert!(h.fluctuations.iter().all(|f| f.iter().all(|&u| u.abs() < 1e-12)));
        assert_eq!(h.components, 1);
    }

    #[test]
    fn layers_in_series_give_the_harmonic_mean_across_and_the_mean_along() {
        // Conductances alternate 1 and 4 along x between planes i → i+1 (a laminate normal
        // to x): across, 1/Λ_xx = mean(1/g) = (1 + 1/4)/2; along y and z the arithmetic
        // mean of the planes' own links (all 1 here).
        let n = 4;
        let id = |i: usize, j: usize, k: usize| ((i % n) + n * ((j % n) + n * (k % n))) as u32;
        let (mut edges, mut g, mut br) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    edges.push([id(i, j, k), id(i + 1, j, k)]);
                    g.push(if i % 2 == 0 { 1.0 } else { 4.0 });
                    br.push(Vec3::x());
                    edges.push([id(i, j, k), id(i, j + 1, k)]);
                    g.push(1.0);
                    br.push(Vec3::y());
                    edges.push([id(i, j, k), id(i, j, k + 1)]);
                    g.push(1.0);
                    br.push(Vec3::z());
                }
            }
        }
        let net = Network::new(n * n * n, &edges).unwrap();
        let h = homogenize(&net, &g, &br, 64.0, &params()).unwrap();
        assert!((h.tensor[0][0] - 1.0 / 0.625).abs() < 1e-10, "{:?}", h.tensor);
        assert!((h.tensor[1][1] - 1.0).abs() < 1e-10);
        assert!(h.symmetry_error < 1e-10);
    }

    #[test]
    fn bad_inputs_are_named() {
        let (net, g, br) = lattice(2, |_| 1.0);
        let e = homogenize(&net, &g, &br[..3], 8.0, &params()).unwrap_err();
        assert!(e.to_string().contains("branches"), "{e}");
        let e = homogenize(&net, &g, &br, 0.0, &params()).unwrap_err();
        assert!(e.to_string().contains("volume"), "{e}");
    }
}
