//! The Jacobi-preconditioned CG of faer (`faer::matrix_free::conjugate_gradient`) run around
//! this crate's parallel operator, for comparison with the fused hand-written PCG.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::matrix_free::conjugate_gradient::{
    CgError, CgParams, conjugate_gradient, conjugate_gradient_scratch,
};
use faer::matrix_free::{InitialGuessStatus, LinOp, Precond};
use faer::reborrow::ReborrowMut;
use faer::{MatMut, MatRef, Par};

use crate::error::SolveError;
use crate::par::dot;
use crate::solve::{LinearSystem, Progress};

/// A = D + K on the free nodes (rows off the free set are zero).
#[derive(Debug)]
struct Operator<'s, 'a> {
    sys: &'s LinearSystem<'a>,
}

/// Jacobi preconditioner: 1/A_ii on free nodes.
#[derive(Debug)]
struct Jacobi<'s> {
    inv_diag: &'s [f64],
}

/// Runs `f(input, output)` on each column, copying when a column is not contiguous.
fn per_column(mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, mut f: impl FnMut(&[f64], &mut [f64])) {
    for j in 0..rhs.ncols() {
        let input: Vec<f64>;
        let src: &[f64] = match rhs.col(j).try_as_col_major() {
            Some(c) => c.as_slice(),
            None => {
                input = rhs.col(j).iter().copied().collect();
                &input
            }
        };
        let mut dst = out.rb_mut().col_mut(j);
        match dst.rb_mut().try_as_col_major_mut() {
            Some(d) => f(src, d.as_slice_mut()),
            None => {
                let mut tmp = vec![0.0; src.len()];
                f(src, &mut tmp);
                for (i, v) in tmp.into_iter().enumerate() {
                    dst[i] = v;
                }
            }
        }
    }
}

impl LinOp<f64> for Operator<'_, '_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.sys.net.n_nodes()
    }
    fn ncols(&self) -> usize {
        self.sys.net.n_nodes()
    }
    fn apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _s: &mut MemStack) {
        per_column(out, rhs, |p, q| {
            self.sys.apply_dot(p, q);
        });
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, s: &mut MemStack) {
        self.apply(out, rhs, par, s);
    }
}

impl LinOp<f64> for Jacobi<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.inv_diag.len()
    }
    fn ncols(&self) -> usize {
        self.inv_diag.len()
    }
    fn apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _s: &mut MemStack) {
        per_column(out, rhs, |r, z| {
            for ((zi, ri), di) in z.iter_mut().zip(r).zip(self.inv_diag) {
                *zi = ri * di;
            }
        });
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, s: &mut MemStack) {
        self.apply(out, rhs, par, s);
    }
}

impl Precond<f64> for Jacobi<'_> {}

/// Solves for the correction with faer's CG; `r` holds b − A x on entry.
pub(crate) fn solve(
    sys: &LinearSystem<'_>,
    b: &[f64],
    x: &mut [f64],
    r: &mut [f64],
    b_norm: f64,
    rel_tol: f64,
    max_iter: usize,
) -> Result<(usize, f64, Option<f64>), SolveError> {
    const NAME: &str = "faer-cg";
    let n = x.len();
    let op = Operator { sys };
    let pre = Jacobi {
        inv_diag: &sys.inv_diag,
    };
    // The operator parallelises itself; faer runs sequentially around it (faster).
    let par = Par::Seq;
    let mut buf = MemBuffer::try_new(conjugate_gradient_scratch(&pre, &op, 1, par))
        .map_err(|_| SolveError::Factorization("out of memory for CG scratch".into()))?;
    let mut iterations = 0usize;
    let mut progress = Progress::new(NAME, dot(r, r).sqrt() / b_norm)?;
    while progress.go_on(rel_tol, iterations, max_iter) {
        let r_norm = dot(r, r).sqrt();
        let mut delta = vec![0.0; n];
        let params = CgParams {
            // `Zero` is broken in faer 0.24.4: pass a zeroed guess as `MaybeNonZero`.
            initial_guess: InitialGuessStatus::MaybeNonZero,
            abs_tolerance: 0.0,
            rel_tolerance: (rel_tol * b_norm / r_norm).min(0.5),
            max_iters: max_iter - iterations,
            ..Default::default()
        };
        let result = conjugate_gradient(
            MatMut::from_column_major_slice_mut(&mut delta, n, 1),
            &pre,
            &op,
            MatRef::from_column_major_slice(r, n, 1),
            params,
            |_| {},
            par,
            MemStack::new(&mut buf),
        );
        match result {
            Ok(info) => iterations += info.iter_count.max(1),
            Err(CgError::NoConvergence { .. }) => iterations = max_iter,
            // The system is positive definite by construction (conductances > 0, every
            // free cluster anchored): faer's p·Ap ≤ 0 test is hit by round-off at the
            // floor. Keep the iterate; the restart logic judges the true residual.
            Err(CgError::NonPositiveDefiniteOperator | CgError::NonPositiveDefinitePreconditioner) => {
                iterations += 1;
            }
        }
        if let Some(d) = delta.iter().find(|d| !d.is_finite()) {
            return Err(SolveError::NonFinite {
                method: NAME,
                iteration: iterations,
                what: "correction",
                value: *d,
            });
        }
        for (xi, di) in x.iter_mut().zip(&delta) {
            *xi += di;
        }
        sys.residual(b, x, r);
        progress.restarted(dot(r, r).sqrt() / b_norm, x, iterations)?;
    }
    progress.finish(sys, b, x, r, b_norm, rel_tol, iterations)
}
