//! Conjugate gradient preconditioned by a modified diagonal incomplete Cholesky factor
//! (MIC), in Eisenstat's form: the method for small systems.
//!
//! With A = L + D_A + Lᵀ on the free block (L strictly lower in node order), the
//! preconditioner is M = (D + L) D⁻¹ (D + L)ᵀ, where only the diagonal D is computed:
//!
//! D_i = A_ii − Σ_{k<i} a_ik [(1 − ω) a_ik + ω U_k] / D_k,  U_k = Σ_{j>k} a_kj.
//!
//! ω = 0 is DIC (IC(0) restricted to the diagonal, OpenFOAM's "DIC"); ω = 1 keeps M's row
//! sums equal to A's (the dropped fill goes back on the diagonal); ω slightly below 1 keeps
//! the pivots away from zero. A and M share every off-diagonal entry, so (Eisenstat 1981)
//! with P = D + L and K = 2D − D_A,
//!
//! P⁻¹ A P⁻ᵀ = P⁻ᵀ + P⁻¹ (I − K P⁻ᵀ),
//!
//! and CG on the symmetric Â = S P⁻¹ A P⁻ᵀ S (S = D^½) costs one backward and one forward
//! sweep per iteration — no separate product with A. The sweeps are sequential, so this is
//! for systems of up to ~10⁴ unknowns, where it needs a third of Jacobi-PCG's iterations at
//! about the same cost per iteration.

use crate::csr::Csr;
use crate::error::SolveError;
use crate::pcg::{self, Krylov};

/// Smallest accepted pivot, relative to the row's diagonal; smaller ones are reset to A_ii.
const PIVOT_FLOOR: f64 = 1e-3;

/// Triangular halves of the free block and the incomplete factor's diagonal.
#[derive(Debug, Clone)]
pub(crate) struct Mic {
    /// Strictly lower part: row pointers, columns, values (a_ij < 0).
    lower: Csr,
    /// Strictly upper part.
    upper: Csr,
    /// 1/D_i.
    inv_d: Vec<f64>,
    /// S_i = √D_i.
    s: Vec<f64>,
    /// K_i = 2 D_i − a_ii.
    k: Vec<f64>,
    /// Pivots reset to a_ii (0 on the M-matrices of conductance networks with ω < 1).
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) floored: usize,
}

impl Mic {
    /// Factorises the free block `a` (diagonal stored, sorted columns) with relaxation ω.
    #[cfg(test)]
    pub(crate) fn new(a: &Csr, omega: f64) -> Result<Self, SolveError> {
        let mut diag = vec![0.0; a.nrows];
        let rows = (0..a.nrows).map(|i| {
            let (c, v) = a.row(i);
            c.iter().map(|&j| j as usize).zip(v.iter().copied())
        });
        let rows: Vec<Vec<(usize, f64)>> = rows
            .enumerate()
            .map(|(i, r)| {
                r.filter(|&(j, v)| {
                    if j == i {
                        diag[i] += v;
                    }
                    j != i
                })
                .collect()
            })
            .collect();
        Self::from_rows(diag, rows, omega)
    }

    /// Factorises the matrix given by its diagonal and its off-diagonal rows (`rows[i]`
    /// yields (column, value) sorted by column; repeated columns are summed) with
    /// relaxation ω.
    pub(crate) fn from_rows<R, E>(diag: Vec<f64>, rows: R, omega: f64) -> Result<Self, SolveError>
    where
        R: IntoIterator<Item = E>,
        E: IntoIterator<Item = (usize, f64)>,
    {
        let n = diag.len();
        let mut lower = Triangle::with_rows(n);
        let mut upper = Triangle::with_rows(n);
        for (i, row) in rows.into_iter().enumerate() {
            for (j, v) in row {
                if j < i {
                    lower.push(j, v);
                } else {
                    upper.push(j, v);
                }
            }
            lower.end_row();
            upper.end_row();
        }
        let (lower, upper) = (lower.finish(n), upper.finish(n));
        let u_sum: Vec<f64> = (0..n).map(|i| upper.row(i).1.iter().sum()).collect();
        let mut d = vec![0.0; n];
        let mut floored = 0;
        for i in 0..n {
            let a_ii = diag[i];
            if !(a_ii > 0.0 && a_ii.is_finite()) {
                return Err(SolveError::Breakdown {
                    method: "mic-pcg",
                    iteration: 0,
                    detail: format!("diagonal {a_ii:e} at unknown {i}"),
                });
            }
            let (cols, vals) = lower.row(i);
            let mut di = a_ii;
            for (&k, &a_ik) in cols.iter().zip(vals) {
                let k = k as usize;
                di -= a_ik * ((1.0 - omega) * a_ik + omega * u_sum[k]) / d[k];
            }
            if di.is_nan() || di <= PIVOT_FLOOR * a_ii {
                di = a_ii;
                floored += 1;
            }
            d[i] = di;
        }
        Ok(Self {
            lower,
            upper,
            inv_d: d.iter().map(|v| 1.0 / v).collect(),
            s: d.iter().map(|v| v.sqrt()).collect(),
            k: d.iter().zip(&diag).map(|(di, ai)| 2.0 * di - ai).collect(),
            floored,
        })
    }

    /// Solves (D + L) w = y (forward sweep).
    fn forward(&self, y: &[f64], w: &mut [f64]) {
        for i in 0..w.len() {
            let (cols, vals) = self.lower.row(i);
            w[i] = (y[i] - sum4(cols, vals, w)) * self.inv_d[i];
        }
    }

    /// Solves (D + Lᵀ) t = y (backward sweep).
    fn backward(&self, y: &[f64], t: &mut [f64]) {
        for i in (0..t.len()).rev() {
            let (cols, vals) = self.upper.row(i);
            t[i] = (y[i] - sum4(cols, vals, t)) * self.inv_d[i];
        }
    }

    /// q = Â v = S (t + w), t = P⁻ᵀ S v, w = P⁻¹ (S v − K t); returns v·q. `y`, `t`, `w`
    /// are work vectors.
    fn apply(&self, v: &[f64], q: &mut [f64], y: &mut [f64], t: &mut [f64], w: &mut [f64]) -> f64 {
        for ((yi, vi), si) in y.iter_mut().zip(v).zip(&self.s) {
            *yi = si * vi;
        }
        self.backward(y, t);
        for ((yi, ti), ki) in y.iter_mut().zip(t.iter()).zip(&self.k) {
            *yi -= ki * ti;
        }
        self.forward(y, w);
        let mut vq = 0.0;
        for i in 0..q.len() {
            q[i] = self.s[i] * (t[i] + w[i]);
            vq += v[i] * q[i];
        }
        vq
    }
}

/// Row-by-row builder of one triangle, merging repeated columns (parallel edges).
struct Triangle {
    ptr: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<f64>,
}

impl Triangle {
    fn with_rows(n: usize) -> Self {
        let mut ptr = Vec::with_capacity(n + 1);
        ptr.push(0);
        Self {
            ptr,
            cols: Vec::with_capacity(4 * n),
            vals: Vec::with_capacity(4 * n),
        }
    }

    fn push(&mut self, j: usize, v: f64) {
        let row_start = *self.ptr.last().unwrap_or(&0);
        if self.cols.len() > row_start && self.cols.last() == Some(&(j as u32)) {
            *self.vals.last_mut().expect("same length as cols") += v;
        } else {
            self.cols.push(j as u32);
            self.vals.push(v);
        }
    }

    fn end_row(&mut self) {
        self.ptr.push(self.cols.len());
    }

    fn finish(self, n: usize) -> Csr {
        Csr {
            nrows: n,
            ncols: n,
            ptr: self
                .ptr
                .into_iter()
                .map(|p| u32::try_from(p).expect("entries fit a u32 row pointer"))
                .collect(),
            cols: self.cols,
            vals: self.vals,
        }
    }
}

/// Σ vals_e x[cols_e] with four partial sums (rows have ~7 entries; one accumulator would
/// serialise them on the add latency). Fixed order: deterministic.
#[inline(always)]
fn sum4(cols: &[u32], vals: &[f64], x: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (c4, v4) = (cols.chunks_exact(4), vals.chunks_exact(4));
    let (cr, vr) = (c4.remainder(), v4.remainder());
    for (c, v) in c4.zip(v4) {
        for l in 0..4 {
            acc[l] += v[l] * x[c[l] as usize];
        }
    }
    for (l, (&q, &g)) in cr.iter().zip(vr).enumerate() {
        acc[l] += g * x[q as usize];
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// CG on Â = S P⁻¹ A P⁻ᵀ S ([`pcg::cg`] with M = I): two triangular sweeps per product,
/// sequential like the updates of r (small systems).
struct Eisenstat<'m> {
    m: &'m Mic,
    /// Work vectors of [`Mic::apply`].
    y: Vec<f64>,
    t: Vec<f64>,
    w: Vec<f64>,
    /// r̂·r̂ of the last [`Krylov::descend`].
    rr: f64,
}

impl Krylov for Eisenstat<'_> {
    fn name(&self) -> &'static str {
        "mic-pcg"
    }

    fn apply_dot(&mut self, p: &[f64], q: &mut [f64]) -> f64 {
        self.m.apply(p, q, &mut self.y, &mut self.t, &mut self.w)
    }

    fn descend(&mut self, alpha: f64, q: &[f64], r: &mut [f64], _z: &mut Vec<f64>) -> f64 {
        let mut rr = 0.0;
        for (ri, qi) in r.iter_mut().zip(q) {
            *ri -= alpha * qi;
            rr += *ri * *ri;
        }
        self.rr = rr;
        rr
    }

    fn precondition(
        &mut self,
        r: &[f64],
        _z: &mut Vec<f64>,
        _q: Option<&[f64]>,
        descended: bool,
    ) -> [f64; 2] {
        if !descended {
            self.rr = r.iter().map(|v| v * v).sum();
        }
        [self.rr, 0.0]
    }

    fn identity(&self) -> bool {
        true
    }
}

/// Solves A δ = rhs (compact free-block numbering) by CG on Â until the transformed residual
/// has fallen by `reduction`; returns δ and the iterations. The caller checks the true
/// residual and calls again on the correction if needed.
pub(crate) fn solve(
    m: &Mic,
    rhs: &[f64],
    reduction: f64,
    max_iter: usize,
) -> Result<(Vec<f64>, usize), SolveError> {
    let n = rhs.len();
    // r̂ = S P⁻¹ b.
    let mut r = vec![0.0; n];
    m.forward(rhs, &mut r);
    r.iter_mut().zip(&m.s).for_each(|(ri, si)| *ri *= si);
    let abs_tol = reduction * r.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut x = vec![0.0; n];
    let mut k = Eisenstat {
        m,
        y: vec![0.0; n],
        t: vec![0.0; n],
        w: vec![0.0; n],
        rr: 0.0,
    };
    let iterations = pcg::cg(&mut k, &mut x, &mut r, abs_tol, max_iter)?;
    // δ = P⁻ᵀ S x̂.
    x.iter_mut().zip(&m.s).for_each(|(xi, si)| *xi *= si);
    let mut t = std::mem::take(&mut k.t);
    m.backward(&x, &mut t);
    Ok((t, iterations))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1-D chain Laplacian with both ends tied to ground (an M-matrix).
    fn chain(n: usize) -> Csr {
        Csr::from_rows(
            n,
            n,
            || (),
            |_, i, c, v| {
                if i > 0 {
                    c.push(i as u32 - 1);
                    v.push(-1.0);
                }
                c.push(i as u32);
                v.push(2.0 + 0.01 * i as f64);
                if i + 1 < n {
                    c.push(i as u32 + 1);
                    v.push(-1.0);
                }
            },
        )
    }

    #[test]
    fn tridiagonal_factor_is_exact_and_solves_in_one_iteration() {
        // IC(0) of a tridiagonal matrix has no fill: M = A, so Â = I.
        let a = chain(50);
        let m = Mic::new(&a, 0.0).unwrap();
        assert_eq!(m.floored, 0);
        let b: Vec<f64> = (0..50).map(|i| (i as f64 * 0.3).sin()).collect();
        let (x, its) = solve(&m, &b, 1e-12, 100).unwrap();
        assert!(its <= 2, "{its} iterations");
        let mut r = vec![0.0; 50];
        a.residual(&b, &x, &mut r);
        let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(rn < 1e-10, "residual {rn:e}");
    }

    #[test]
    fn solves_a_random_network_to_the_requested_reduction() {
        // A 12³ grid with varying conductances and a grounded layer: fill is dropped.
        let side = 12usize;
        let n = side * side * side;
        let idx = |x: usize, y: usize, z: usize| (x * side + y) * side + z;
        let g = |a: usize, b: usize| 1.0 + ((a * 7 + b * 13) % 10) as f64 * 0.3;
        let a = Csr::from_rows(
            n,
            n,
            || (),
            |_, i, c, v| {
                let (x, y, z) = (i / (side * side), (i / side) % side, i % side);
                let mut nb = Vec::new();
                if x > 0 {
                    nb.push(idx(x - 1, y, z));
                }
                if x + 1 < side {
                    nb.push(idx(x + 1, y, z));
                }
                if y > 0 {
                    nb.push(idx(x, y - 1, z));
                }
                if y + 1 < side {
                    nb.push(idx(x, y + 1, z));
                }
                if z > 0 {
                    nb.push(idx(x, y, z - 1));
                }
                if z + 1 < side {
                    nb.push(idx(x, y, z + 1));
                }
                nb.push(i);
                nb.sort_unstable();
                let mut diag = if x == 0 { 1.0 } else { 0.0 };
                for &j in &nb {
                    if j != i {
                        diag += g(i.min(j), i.max(j));
                    }
                }
                for j in nb {
                    c.push(j as u32);
                    v.push(if j == i { diag } else { -g(i.min(j), i.max(j)) });
                }
            },
        );
        let b: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        for omega in [0.0, 0.97] {
            let m = Mic::new(&a, omega).unwrap();
            assert_eq!(m.floored, 0);
            let (x, its) = solve(&m, &b, 1e-10, 1000).unwrap();
            let mut r = vec![0.0; n];
            a.residual(&b, &x, &mut r);
            let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
            let bn = b.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!(rn / bn < 1e-8, "ω = {omega}: residual {:e} after {its}", rn / bn);
            assert!(its < 60, "ω = {omega}: {its} iterations");
        }
    }
}
