//! The crate's one preconditioned conjugate gradient, and the restart loop that drives every
//! iterative method to the tolerance on the true residual.
//!
//! [`cg`] runs on a [`Krylov`] value: an operator with its preconditioner. Jacobi on the
//! whole network ([`crate::Method::Cg`]), the multigrid cycle on the free block
//! ([`crate::Method::AmgCg`]) and the modified incomplete Cholesky factor in Eisenstat's form
//! ([`crate::Method::IcCg`]) each supply the product, the preconditioner and the residual
//! update, where they fuse what their memory traffic allows; the recurrence, the flexible β,
//! the round-off breaks and the non-finite checks are written here once.
//!
//! [`restart`] runs one inner solve (one of those, or PETSc's) after another on the
//! correction until ‖b − Ax‖ ≤ rel_tol ‖b‖, and applies the rules every method shares:
//! stagnation ([`crate::STAGNATION_WINDOW`] restarts without progress), the round-off floor
//! ([`crate::SolveReport::attainable`]) and non-finite residuals.

use rayon::prelude::*;

use crate::error::SolveError;
use crate::par::{CHUNK, chunks_map, chunks_map2, dot};
use crate::solve::{LinearSystem, STAGNATION_DECREASE, STAGNATION_WINDOW};

/// An operator A and its preconditioner M, as [`cg`] uses them. Vectors are in the
/// implementor's own numbering (the whole network, or the compact free block).
pub(crate) trait Krylov {
    /// Method name, for errors.
    fn name(&self) -> &'static str;

    /// q = A p; returns p·q.
    fn apply_dot(&mut self, p: &[f64], q: &mut [f64]) -> f64;

    /// r −= α q; returns r·r. May begin z = M⁻¹ r in the same pass, for
    /// [`Self::precondition`] to finish.
    fn descend(&mut self, alpha: f64, q: &[f64], r: &mut [f64], z: &mut Vec<f64>) -> f64;

    /// z = M⁻¹ r; returns r·z and, given `q` (flexible CG), z·q (else 0). `descended`: called
    /// right after [`Self::descend`] on the same vectors.
    fn precondition(&mut self, r: &[f64], z: &mut Vec<f64>, q: Option<&[f64]>, descended: bool) -> [f64; 2];

    /// Whether M is nonlinear (a K-cycle): then β = −(z·q)/(p·q), flexible CG.
    fn flexible(&self) -> bool {
        false
    }

    /// Whether M = I (the operator is already preconditioned): z is never written and r
    /// stands for it.
    fn identity(&self) -> bool {
        false
    }
}

/// Preconditioned CG on A x = r₀ + A x₀: `x` holds x₀ and `r` the residual at x₀ on entry, the
/// iterate and its recursive residual on return. Stops when ‖r‖ ≤ `abs_tol` (recursive
/// residual, the caller judges the true one) or after `max_iter` iterations, or on a
/// non-positive r·M⁻¹r or p·Ap (round-off at the floor: A and M are positive definite by
/// construction). Returns the iterations.
///
/// # Errors
/// [`SolveError::NonFinite`] when a scalar of the recurrence is NaN or ∞.
pub(crate) fn cg(
    k: &mut impl Krylov,
    x: &mut [f64],
    r: &mut [f64],
    abs_tol: f64,
    max_iter: usize,
) -> Result<usize, SolveError> {
    let name = k.name();
    let non_finite = |iteration, what, value| SolveError::NonFinite {
        method: name,
        iteration,
        what,
        value,
    };
    let (flexible, identity) = (k.flexible(), k.identity());
    let n = x.len();
    let mut z = if identity { Vec::new() } else { vec![0.0; n] };
    let mut q = vec![0.0; n];
    let [mut rz, _] = k.precondition(r, &mut z, None, false);
    // Copies in parallel chunks (fresh pages first touched by both threads).
    let mut p: Vec<f64> = if identity { &*r } else { &z[..] }
        .par_iter()
        .with_min_len(CHUNK)
        .copied()
        .collect();
    let mut iterations = 0;
    while iterations < max_iter {
        if !rz.is_finite() {
            return Err(non_finite(iterations, "r·M⁻¹r", rz));
        }
        if rz <= 0.0 {
            break;
        }
        let pq = k.apply_dot(&p, &mut q);
        iterations += 1;
        if !pq.is_finite() {
            return Err(non_finite(iterations, "p·Ap", pq));
        }
        if pq <= 0.0 {
            break;
        }
        let alpha = rz / pq;
        let rr = k.descend(alpha, &q, r, &mut z);
        if !rr.is_finite() {
            return Err(non_finite(iterations, "recursive residual ‖r‖²", rr));
        }
        if rr.sqrt() <= abs_tol || iterations >= max_iter {
            axpy(alpha, &p, x);
            break;
        }
        let [rz_new, zq] = k.precondition(r, &mut z, flexible.then_some(&q[..]), true);
        let beta = if flexible { -zq / pq } else { rz_new / rz };
        rz = rz_new;
        let z = if identity { &*r } else { &z[..] };
        // x += α p with the old direction, then p = z + β p: one pass.
        chunks_map2(x, &mut p, |c, xc, pc| {
            let range = c * CHUNK..c * CHUNK + pc.len();
            for ((xi, pi), zi) in xc.iter_mut().zip(pc.iter_mut()).zip(&z[range]) {
                *xi += alpha * *pi;
                *pi = zi + beta * *pi;
            }
        });
    }
    Ok(iterations)
}

/// y += α x, in parallel chunks.
pub(crate) fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    chunks_map(y, |c, yc| {
        let range = c * CHUNK..c * CHUNK + yc.len();
        for (yi, xi) in yc.iter_mut().zip(&x[range]) {
            *yi += alpha * xi;
        }
    });
}

/// When an iterative solve stops: ‖b − Ax‖ ≤ `rel_tol` · `b_norm`, within `max_iter`
/// iterations.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Stop {
    /// ‖b_eff‖, the residual norm with the free unknowns at zero (W or A).
    pub(crate) b_norm: f64,
    /// Relative tolerance (dimensionless).
    pub(crate) rel_tol: f64,
    /// Iteration limit.
    pub(crate) max_iter: usize,
}

/// Runs `inner` from the true residual until ‖b − Ax‖ ≤ rel_tol ‖b‖ (`stop`); `r` holds b − A x
/// on entry. `inner(x, r, ‖r‖, iterations left)` improves x (it may overwrite r) and returns
/// its iterations. Returns (iterations, true relative residual, round-off floor when the tolerance
/// was not met but the floor was).
///
/// # Errors
/// [`SolveError::Stagnated`] or [`SolveError::NotConverged`] above the round-off floor,
/// [`SolveError::NonFinite`], and what `inner` returns.
pub(crate) fn restart(
    sys: &LinearSystem<'_>,
    b: &[f64],
    x: &mut [f64],
    r: &mut [f64],
    stop: Stop,
    mut inner: impl FnMut(&mut [f64], &mut [f64], f64, usize) -> Result<usize, SolveError>,
) -> Result<(usize, f64, Option<f64>), SolveError> {
    let Stop {
        b_norm,
        rel_tol,
        max_iter,
    } = stop;
    let mut iterations = 0usize;
    let mut progress = Progress::new(sys.method().name(), dot(r, r).sqrt() / b_norm)?;
    while progress.go_on(rel_tol, iterations, max_iter) {
        iterations += inner(x, r, progress.current * b_norm, max_iter - iterations)?.max(1);
        sys.residual(b, x, r);
        progress.restarted(dot(r, r).sqrt() / b_norm, x, iterations)?;
    }
    progress.finish(sys, b, x, r, stop, iterations)
}

/// An inner solve of [`restart`] on the compact free block: gathers r at `nodes`, asks `solve(r_compact,
/// ‖r‖, iterations left)` for a correction δ and its iterations, and adds δ to x.
pub(crate) fn compact(
    nodes: &[u32],
    mut solve: impl FnMut(&[f64], f64, usize) -> Result<(Vec<f64>, usize), SolveError>,
) -> impl FnMut(&mut [f64], &mut [f64], f64, usize) -> Result<usize, SolveError> {
    move |x: &mut [f64], r: &mut [f64], r_norm: f64, left: usize| {
        // Gathers in parallel: fresh pages are first touched by both threads (in this VM a
        // 4 KB page costs ~1.7 µs on first touch; docs/performance.md § 4).
        let rc: Vec<f64> = nodes
            .par_iter()
            .with_min_len(CHUNK)
            .map(|&p| r[p as usize])
            .collect();
        let (delta, its) = solve(&rc, r_norm, left)?;
        for (&p, d) in nodes.iter().zip(&delta) {
            x[p as usize] += d;
        }
        Ok(its)
    }
}

/// The restart loop's bookkeeping: the best true relative residual and its iterate, restarts
/// without progress, non-finite checks.
#[derive(Debug)]
struct Progress {
    method: &'static str,
    /// Current true relative residual.
    current: f64,
    /// Best true relative residual so far.
    best: f64,
    /// Copy of the iterate with `best` (taken when a restart improves on it).
    best_x: Option<Vec<f64>>,
    /// Level `best` must go below for a restart to count as progress.
    target: f64,
    /// Consecutive restarts without progress.
    stalled: usize,
}

impl Progress {
    /// Starts from the true relative residual at the initial guess.
    fn new(method: &'static str, rel: f64) -> Result<Self, SolveError> {
        if !rel.is_finite() {
            return Err(SolveError::NonFinite {
                method,
                iteration: 0,
                what: "initial relative residual",
                value: rel,
            });
        }
        Ok(Self {
            method,
            current: rel,
            best: rel,
            best_x: None,
            target: STAGNATION_DECREASE * rel,
            stalled: 0,
        })
    }

    /// Whether to run another restart: tolerance not met (NaN-safe), iterations left, not
    /// stagnated.
    fn go_on(&self, rel_tol: f64, iterations: usize, max_iter: usize) -> bool {
        (self.current.is_nan() || self.current > rel_tol)
            && iterations < max_iter
            && self.stalled < STAGNATION_WINDOW
    }

    /// Records the true relative residual `rel` at iterate `x` after a restart.
    fn restarted(&mut self, rel: f64, x: &[f64], iterations: usize) -> Result<(), SolveError> {
        if !rel.is_finite() {
            return Err(SolveError::NonFinite {
                method: self.method,
                iteration: iterations,
                what: "true relative residual",
                value: rel,
            });
        }
        self.current = rel;
        if rel < self.best {
            // One copy per improving restart (one or two in a normal solve).
            self.best = rel;
            match &mut self.best_x {
                Some(v) => v.copy_from_slice(x),
                None => self.best_x = Some(x.to_vec()),
            }
        }
        if rel < self.target {
            self.target = STAGNATION_DECREASE * rel;
            self.stalled = 0;
        } else {
            self.stalled += 1;
        }
        Ok(())
    }

    /// Ends the loop: Ok when the tolerance is met, or when the best residual is within the
    /// round-off floor (then the floor is returned); else the error that says why.
    fn finish(
        self,
        sys: &LinearSystem<'_>,
        b: &[f64],
        x: &mut [f64],
        r: &mut [f64],
        stop: Stop,
        iterations: usize,
    ) -> Result<(usize, f64, Option<f64>), SolveError> {
        let Stop { b_norm, rel_tol, .. } = stop;
        if self.current <= rel_tol {
            return Ok((iterations, self.current, None));
        }
        if let (Some(best), true) = (&self.best_x, self.current > self.best) {
            x.copy_from_slice(best);
            sys.residual(b, x, r);
        }
        let rel = dot(r, r).sqrt() / b_norm;
        let floor = sys.attainable(b, x, b_norm);
        if rel <= floor {
            return Ok((iterations, rel, Some(floor)));
        }
        if self.stalled >= STAGNATION_WINDOW {
            return Err(SolveError::Stagnated {
                method: self.method,
                iterations,
                residual: rel,
                tolerance: rel_tol,
                attainable: floor,
                window: STAGNATION_WINDOW,
            });
        }
        Err(SolveError::NotConverged {
            method: self.method,
            iterations,
            relative_residual: rel,
            tolerance: rel_tol,
        })
    }
}
