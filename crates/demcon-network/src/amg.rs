//! Aggregation algebraic multigrid used as the preconditioner of conjugate gradient on the
//! free-node block A of D + K: smoothed aggregation with a V-cycle (SA-AMG, Vaněk–Mandel–
//! Brezina 1996), or plain aggregation with a K-cycle (below), on the same aggregates.
//!
//! Setup, per level (the finest level of a plain-aggregation hierarchy is assembled straight
//! into the sliced layout and read from it: [`Amg::plain_from_sell`]): strength of connection |a_ij| ≥ θ √(a_ii a_jj); greedy aggregation in
//! node order within fixed blocks of rows, the blocks in parallel (seeds whose strong
//! neighbours are all free, then attachment to the most strongly connected aggregate, then
//! aggregates of the leftovers; [`aggregate`]); a tentative prolongator
//! that interpolates the near-null space (the constant vector on the finest level)
//! piecewise on aggregates, normalised per aggregate; the prolongator smoothed by one damped
//! Jacobi step P = (I − ω D⁻¹A) P_tent with ω = 4/(3 ρ(D⁻¹A)); the Galerkin operator
//! A_c = Pᵀ (A P), formed in blocks of A_c's rows so that A P is never stored whole
//! ([`Csr::galerkin`]). Coarsening stops below [`MAX_COARSE`] unknowns,
//! where a dense Cholesky factor solves exactly. The cycle is a symmetric V(1,1) with
//! damped-Jacobi smoothing, so the preconditioner is symmetric positive definite and CG
//! applies. Every step uses fixed row blocks or chunks with ordered sums: results do not
//! depend on the thread count.
//!
//! Bytes per cycle (issue 12): the hierarchy's matrices (each level's operator as the
//! smoother reads it, P and R) are stored in f32 and widened on use, CG's own product keeps
//! the f64 fine operator, so the solution's accuracy is unchanged (22 iterations at 10⁶
//! either way); row pointers are u32; r·z is summed in the last smoothing sweep. Each
//! level's operator, P and R are kept in sliced-ELLPACK form ([`Sell`]) once the level's
//! Galerkin product is formed: the residual, the smoothing sweep, CG's product, the
//! restriction and the prolongation read four rows side by side (solve −26 % at 10⁶, setup
//! +5 % for the conversions; `docs/performance.md`).
//!
//! **Plain aggregation with a K-cycle** ([`Coarsening::Plain`], for a matrix solved once or a
//! few times; Notay & Vassilevski 2008, Notay 2010). The same aggregates, but the
//! prolongator is not smoothed: P[i, agg(i)] = 1, so the Galerkin operator is a sum of A's
//! entries over pairs of aggregates, restriction a sum over an aggregate's members and
//! prolongation a copy (the two smoothed Galerkin products are half of the smoothed setup at
//! 10⁶). A plain V-cycle loses much of its accuracy level by level (71 iterations against
//! 22 at 10⁶); the K-cycle recovers it: every coarse level's correction is two steps of
//! flexible CG on that level, preconditioned by the cycle below, the second skipped when the
//! first has reduced the residual four-fold. The cycle is then a nonlinear preconditioner,
//! so the outer CG is flexible: β = −(z·Ap)/(p·Ap) keeps consecutive directions A-conjugate.
//! Each level also keeps A P ([`Sell::group_columns`], a third of A's entries at 10⁶): the
//! residual after the coarse correction, b − A (x + P e), is the pre-smoothed residual r minus
//! (A P) e, so prolongation and post-smoothing take one pass over A P, gathering from the
//! coarse e, instead of a pass over A (at 10⁶ the solve 0.09–0.17 s shorter, the setup
//! 0.06–0.09 s longer: a one-off solve 2–4 % shorter, one reusing the hierarchy more). A P is
//! summed once from the level's f64 entries; its f64 rows also give the Galerkin operator,
//! Pᵀ (A P), a sum of a third as many entries as over A's rows ([`plain_transfer`]).
//! At 10⁶ unknowns, alternating with the smoothed hierarchy: 28 iterations against 22, setup
//! 0.27–0.30 s against 0.96–1.02 s, solve 0.77–0.87 s against 0.70–0.76 s, 1.04–1.15 s in all
//! against 1.66–1.74 s (`docs/performance.md` § 4).

use rayon::prelude::*;

use crate::csr::{Accumulator, Csr, Value};
use crate::error::SolveError;
use crate::par::{CHUNK, chunks_map, chunks_map2, dot, ordered_sum, ordered_sums};
use crate::pcg::{self, Krylov};
use crate::sell::{NO_GROUP, PREFETCH_AHEAD, PREFETCH_MIN_COLS, RowSell, SELL_LANES, Sell, prefetch_gathers};

/// Largest level solved directly by dense Cholesky (unknowns).
pub(crate) const MAX_COARSE: usize = 400;
/// Largest coarsest level factorised densely (unknowns); used only when coarsening stalls
/// between [`MAX_COARSE`] and this size.
const MAX_DENSE: usize = 1_000;
/// Most levels in the hierarchy (including the coarsest).
const MAX_LEVELS: usize = 12;
/// Strength-of-connection threshold θ.
/// θ = 0.02 keeps nearly every contact of a packing (|a_ij|/√(a_ii a_jj) ≈ 1/Z ≈ 0.13) and
/// drops only links much weaker than their nodes' totals (high-contrast interfaces); on the
/// 10⁵-node benchmark (12 power steps) θ = 0, 0.02, 0.05, 0.08 gave 25, 24, 26, 23
/// iterations, with operator complexity 1.33, 1.39, 1.54, 2.07.
const THETA: f64 = 0.02;
/// Coarsening must shrink a level at least by this factor, else the hierarchy stops.
const MIN_COARSENING: f64 = 0.8;
/// Power iterations for the spectral-radius estimate of D⁻¹A. The estimate (a lower bound,
/// raised by 10 %) sets ω = 4/(3ρ) for the prolongator and the smoother; 6 steps gave fewer
/// CG iterations than 12 (22 vs 24 at 10⁵ and 10⁶ nodes: the slightly larger ω smooths
/// better) and the Gershgorin bound ρ ≤ 2 more (27), at half the setup cost of 12. The
/// smoother stays convergent while the estimate exceeds 2/3 of the true ρ, far below what
/// six steps give; a non-positive-definite cycle would be reported as a breakdown.
const POWER_STEPS: usize = 6;
/// Power iterations for a plain-aggregation hierarchy: at 10⁶ unknowns 2, 3, 4 and 6 steps
/// gave 27, 28, 28 and 28 iterations (the K-cycle's line searches absorb a rougher ω), and
/// each step costs a product with the level's operator (10 ms on the finest).
const PLAIN_POWER_STEPS: usize = 3;

/// How a level's aggregates become the next coarser level ([`Amg::new`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Coarsening {
    /// Smoothed aggregation with a V(1,1)-cycle: the costlier setup, the cheaper cycle; for
    /// a hierarchy reused over many solves (implicit time steps).
    Smoothed,
    /// Plain aggregation with a K-cycle and flexible CG: a setup under a third as long, a
    /// solve 10–15 % longer at 10⁶ unknowns; for one or a few solves (steady, electric,
    /// homogenisation).
    Plain,
}

/// Size of one level of the hierarchy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AmgLevel {
    /// Unknowns on the level.
    pub rows: usize,
    /// Stored entries of the level's operator.
    pub nnz: usize,
}

/// Shape and cost of a multigrid hierarchy ([`crate::LinearSystem::amg_info`]).
#[derive(Debug, Clone, PartialEq)]
pub struct AmgInfo {
    /// Levels, finest first; the last is solved by dense Cholesky.
    pub levels: Vec<AmgLevel>,
    /// Σ nnz(A_l) / nnz(A_0): memory and work of one cycle relative to the fine operator.
    pub operator_complexity: f64,
    /// Σ rows(A_l) / rows(A_0).
    pub grid_complexity: f64,
    /// The hierarchy and cycle: "smoothed aggregation, V(1,1)" or "plain aggregation,
    /// K-cycle".
    pub cycle: &'static str,
}

/// One level above the coarsest: its operator, the Jacobi smoother, the transfer operators.
/// The matrices are stored in f32 (built in f64, rounded once): the cycle only
/// preconditions, CG's own products use the f64 fine operator, so the solution's accuracy
/// is unchanged while the cycle moves a third fewer bytes. Rounding keeps A symmetric and R
/// exactly Pᵀ, and the same rounded A serves both smoothing sweeps, so the cycle stays
/// symmetric; ω carries a 10 % margin, far above the 1e-7 relative change of rounding.
/// The operator is kept in sliced-ELLPACK form ([`Sell`]): the residual and the smoothing
/// sweep read it once each per cycle, four rows side by side.
#[derive(Debug)]
struct Level {
    a: Sell,
    /// ω_s / a_ii, the damped-Jacobi smoother.
    wdinv: Vec<f64>,
    /// Transfer to and from the next coarser level.
    transfer: Transfer,
}

impl Level {
    /// The level of operator `a` (D⁻¹ = `dinv`), smoothed by damped Jacobi with
    /// ω = 4 / (3 ρ(D⁻¹A)).
    fn new(a: Sell, dinv: &[f64], rho: f64, transfer: Transfer) -> Self {
        let omega = 4.0 / (3.0 * rho);
        Self {
            a,
            wdinv: dinv.par_iter().with_min_len(CHUNK).map(|d| omega * d).collect(),
            transfer,
        }
    }
}

/// Prolongation and restriction between a level and the next coarser one.
#[derive(Debug)]
enum Transfer {
    /// Smoothed aggregation: the prolongator P (rows: this level) and R = Pᵀ.
    Smoothed { p: Sell, r: Sell },
    /// Plain aggregation, P[i, agg(i)] = 1: prolongation copies an aggregate's value to its
    /// members, restriction sums over them. `ap` is A P, laid out as the level's operator
    /// (about a third of its entries), for the post-smoothing's residual.
    Plain { aggs: Aggregates, ap: Sell },
}

/// A level's plain aggregates: the aggregate of each node ([`NO_AGGREGATE`]: none) and the
/// members of aggregate k, `members[ptr[k]..ptr[k + 1]]`, in node order.
#[derive(Debug)]
struct Aggregates {
    agg: Vec<u32>,
    ptr: Vec<u32>,
    members: Vec<u32>,
}

impl Aggregates {
    /// The members of each of the `n_agg` aggregates of `agg`.
    fn new(agg: Vec<u32>, n_agg: usize) -> Self {
        let mut ptr = vec![0u32; n_agg + 1];
        for &k in agg.iter().filter(|&&k| k != NO_AGGREGATE) {
            ptr[k as usize + 1] += 1;
        }
        for k in 0..n_agg {
            ptr[k + 1] += ptr[k];
        }
        let mut next = ptr.clone();
        let mut members = vec![0u32; ptr[n_agg] as usize];
        for (i, &k) in agg.iter().enumerate().filter(|&(_, &k)| k != NO_AGGREGATE) {
            members[next[k as usize] as usize] = i as u32;
            next[k as usize] += 1;
        }
        Self { agg, ptr, members }
    }

    /// Number of aggregates.
    fn count(&self) -> usize {
        self.ptr.len() - 1
    }
}

impl Transfer {
    /// Unknowns of the coarser level.
    fn coarse_rows(&self) -> usize {
        match self {
            Self::Smoothed { p, .. } => p.ncols(),
            Self::Plain { aggs, .. } => aggs.count(),
        }
    }

    /// bc = R r.
    fn restrict(&self, r: &[f64], bc: &mut [f64]) {
        match self {
            Self::Smoothed { r: rm, .. } => {
                rm.map_rows(r, bc, |_, _, s| s, |_, _| 0.0);
            }
            Self::Plain { aggs, .. } => {
                let (ptr, members) = (&aggs.ptr, &aggs.members);
                let ahead = r.len() >= PREFETCH_MIN_COLS;
                chunks_map(bc, |c, out| {
                    let base = c * CHUNK;
                    for (k, o) in out.iter_mut().enumerate() {
                        let (lo, hi) = (ptr[base + k] as usize, ptr[base + k + 1] as usize);
                        if ahead {
                            // The members PREFETCH_AHEAD entries on (a later aggregate's).
                            for at in (lo..hi).step_by(SELL_LANES) {
                                prefetch_gathers(members, at + PREFETCH_AHEAD, r);
                            }
                        }
                        *o = members[lo..hi].iter().map(|&i| r[i as usize]).sum();
                    }
                });
            }
        }
    }
}

/// The plain-aggregation transfer of the level whose operator is `a` (SELL form, f64 values
/// `vals` laid out alike) and the next level's operator A_c = Pᵀ (A P): A P is summed once,
/// in f64 ([`Sell::group_columns`]); the transfer keeps it in f32, and A_c sums its rows over
/// each aggregate's members (a third of A's entries, their columns already aggregates; at
/// 10⁶ unknowns the sum over A's rows took 0.06 s).
fn plain_transfer(a: &Sell, vals: &[f64], aggs: Aggregates) -> (Csr, Transfer) {
    let (ap, ap_rows) = a.group_columns(vals, &aggs.agg, aggs.count());
    let ac = galerkin_plain(&ap_rows, &aggs);
    (ac, Transfer::Plain { aggs, ap })
}

/// Aggregate of a node left out of every aggregate (no strong connection); A P drops its
/// column ([`Sell::group_columns`]).
const NO_AGGREGATE: u32 = NO_GROUP;

/// A K-cycle step stops after its first flexible-CG step when that step has reduced the
/// level's residual norm by this factor (Notay's t = 0.25).
const K_CYCLE_TOLERANCE: f64 = 0.25;

/// A multigrid hierarchy for a symmetric positive definite matrix.
#[derive(Debug)]
pub(crate) struct Amg {
    /// The matrix's values in f64 on the layout of the first level's operator, for CG's
    /// products (`None` when the matrix is the coarsest level).
    fine: Option<Vec<f64>>,
    levels: Vec<Level>,
    coarse: Coarse,
    /// The coarsest operator (the only one when the matrix is small).
    coarse_a: Csr,
    coarsening: Coarsening,
}

/// Work vectors of one level of the cycle.
#[derive(Debug)]
pub(crate) struct Work {
    r: Vec<f64>,
    /// The smoothed level's post-smoothing output (empty on a plain level).
    tmp: Vec<f64>,
    bc: Vec<f64>,
    xc: Vec<f64>,
    /// The K-cycle's vectors on the next coarser level (empty for a V-cycle): the second
    /// correction, A times each correction, the residual after the first step.
    c2: Vec<f64>,
    v1: Vec<f64>,
    v2: Vec<f64>,
    r2: Vec<f64>,
}

impl Amg {
    /// Builds the hierarchy of `a` (square, symmetric positive definite, sorted rows with the
    /// diagonal stored).
    pub(crate) fn new(a: Csr, coarsening: Coarsening) -> Result<Self, SolveError> {
        Self::build(a, coarsening, Vec::new(), None)
    }

    /// A plain-aggregation hierarchy ([`Coarsening::Plain`]) of a matrix assembled straight
    /// into SELL form (same conditions as [`Self::new`]): the finest level's aggregates and
    /// Galerkin operator are read from that form, so no compressed-row copy of the largest
    /// matrix is made. Small matrices, and a first coarsening that stalls, take the
    /// compressed-row path.
    pub(crate) fn plain_from_sell(a: RowSell, diag: Vec<f64>) -> Result<Self, SolveError> {
        let n = a.nrows();
        if n <= MAX_COARSE {
            return Self::new(a.to_csr(), Coarsening::Plain);
        }
        check_diagonal(&diag)?;
        let dinv: Vec<f64> = diag.par_iter().with_min_len(CHUNK).map(|d| 1.0 / d).collect();
        let (agg, n_agg) = aggregate(&a, &diag);
        drop(diag);
        if n_agg == 0 || n_agg as f64 > MIN_COARSENING * n as f64 {
            return Self::new(a.to_csr(), Coarsening::Plain);
        }
        let bound = a.max_scaled_abs_row_sum(&dinv);
        let (a32, vals) = a.into_parts();
        let (ac, transfer) = plain_transfer(&a32, &vals, Aggregates::new(agg, n_agg));
        let rho = sell_spectral_radius(&a32, &dinv, bound);
        let level = Level::new(a32, &dinv, rho, transfer);
        Self::build(ac, Coarsening::Plain, vec![level], Some(vals))
    }

    /// The hierarchy below `levels` (already built, finest first; `fine`: the f64 values of
    /// the first one's operator) of `a`.
    fn build(
        a: Csr,
        coarsening: Coarsening,
        levels: Vec<Level>,
        fine: Option<Vec<f64>>,
    ) -> Result<Self, SolveError> {
        let mut levels = levels;
        let mut fine = fine;
        let mut a = a;
        // The near-null space, carried down by smoothed aggregation (plain aggregation's P
        // interpolates constants exactly without it).
        let mut b = match coarsening {
            Coarsening::Smoothed => vec![1.0; a.nrows],
            Coarsening::Plain => Vec::new(),
        };
        while a.nrows > MAX_COARSE && levels.len() + 1 < MAX_LEVELS {
            // (`levels` may already hold the finest: [`Self::plain_from_sell`].)
            let diag = diagonal(&a)?;
            let dinv: Vec<f64> = diag.iter().map(|d| 1.0 / d).collect();
            let (agg, n_agg) = aggregate(&a, &diag);
            if n_agg == 0 || n_agg as f64 > MIN_COARSENING * a.nrows as f64 {
                break;
            }
            // ρ(D⁻¹A), for the smoother's ω: before the products for smoothed aggregation,
            // whose prolongator needs it; after the conversion for plain aggregation, from
            // the SELL form's cheaper products (the Gershgorin bound, read from the rows, caps
            // it either way).
            let bound = gershgorin(&a, &dinv);
            let smoothed_rho =
                (coarsening == Coarsening::Smoothed).then(|| spectral_radius(&a, &dinv, bound));
            // The level's operator in SELL form, rounded to f32 for the smoother; the first
            // level keeps its f64 values, laid out alike, for CG.
            let (ac, a32, transfer) = match coarsening {
                Coarsening::Plain => {
                    // A P and A_c = Pᵀ (A P) are summed from the f64 values in SELL form.
                    let (a32, vals) = Sell::from_csr_with_f64(a);
                    let (ac, transfer) = plain_transfer(&a32, &vals, Aggregates::new(agg, n_agg));
                    if fine.is_none() {
                        fine = Some(vals);
                    }
                    (ac, a32, transfer)
                }
                Coarsening::Smoothed => {
                    // The fine near-null space is read once here: freed before the products.
                    let (ptent, b_c) = tentative(&agg, n_agg, &std::mem::take(&mut b));
                    let rho = smoothed_rho.unwrap_or(bound);
                    let p = smooth_prolongator(&a, &dinv, 4.0 / (3.0 * rho), &ptent, &agg);
                    drop((agg, ptent));
                    // A_c = Pᵀ (A P), in blocks of A_c's rows: A P is never stored whole.
                    // Each f64 temporary is rounded as soon as it is no longer read.
                    let r = p.transpose();
                    let ac = r.galerkin(&a, &p);
                    b = b_c;
                    let (p, r) = (Sell::from_csr(p), Sell::from_csr(r));
                    let a32 = if fine.is_none() {
                        let (a32, vals) = Sell::from_csr_with_f64(a);
                        fine = Some(vals);
                        a32
                    } else {
                        Sell::from_csr(a)
                    };
                    (ac, a32, Transfer::Smoothed { p, r })
                }
            };
            drop(diag);
            let rho = smoothed_rho.unwrap_or_else(|| sell_spectral_radius(&a32, &dinv, bound));
            levels.push(Level::new(a32, &dinv, rho, transfer));
            a = ac;
        }
        // Coarsening can stall above the dense size (e.g. free nodes joined only to fixed
        // ones): the last level is then smoothed, never factorised densely.
        let coarse = if a.nrows <= MAX_DENSE {
            Coarse::Dense(DenseCholesky::new(&a)?)
        } else {
            let diag = diagonal(&a)?;
            let dinv: Vec<f64> = diag.iter().map(|d| 1.0 / d).collect();
            let rho = spectral_radius(&a, &dinv, gershgorin(&a, &dinv));
            Coarse::Jacobi(diag.iter().map(|d| 4.0 / (3.0 * rho * d)).collect())
        };
        Ok(Self {
            fine,
            levels,
            coarse,
            coarse_a: a,
            coarsening,
        })
    }

    /// Shape of the hierarchy.
    pub(crate) fn info(&self) -> AmgInfo {
        let mut levels: Vec<AmgLevel> = self
            .levels
            .iter()
            .map(|l| AmgLevel {
                rows: l.a.nrows(),
                nnz: l.a.nnz(),
            })
            .collect();
        levels.push(AmgLevel {
            rows: self.coarse_a.nrows,
            nnz: self.coarse_a.nnz(),
        });
        let (nnz0, rows0) = (levels[0].nnz.max(1) as f64, levels[0].rows.max(1) as f64);
        AmgInfo {
            cycle: match self.coarsening {
                Coarsening::Smoothed => "smoothed aggregation, V(1,1)",
                Coarsening::Plain => "plain aggregation, K-cycle",
            },
            operator_complexity: levels.iter().map(|l| l.nnz as f64).sum::<f64>() / nnz0,
            grid_complexity: levels.iter().map(|l| l.rows as f64).sum::<f64>() / rows0,
            levels,
        }
    }

    /// q = A p with the finest operator in f64; returns p·q.
    pub(crate) fn fine_spmv_dot(&self, p: &[f64], q: &mut [f64]) -> f64 {
        match (&self.fine, self.levels.first()) {
            (Some(vals), Some(l)) => {
                ordered_sum(&l.a.map_rows_with(vals, p, q, |_, _, v| v, |i, v| v * p[i]))
            }
            _ => self.coarse_a.spmv_dot(p, q),
        }
    }

    /// Whether a coarse level's correction is a K-cycle step (else one V-cycle).
    fn k_cycle_at(&self, l: usize) -> bool {
        self.coarsening == Coarsening::Plain && l < self.levels.len()
    }

    /// Whether the preconditioner is nonlinear (some level takes a K-cycle step): the outer
    /// CG must then be flexible.
    fn flexible(&self) -> bool {
        self.k_cycle_at(1)
    }

    /// Work vectors for [`Self::cycle_with`].
    pub(crate) fn work(&self) -> Vec<Work> {
        self.levels
            .iter()
            .enumerate()
            .map(|(l, lev)| {
                let nc = lev.transfer.coarse_rows();
                let k = if self.k_cycle_at(l + 1) { nc } else { 0 };
                Work {
                    r: vec![0.0; lev.a.nrows()],
                    // (A plain level's post-smoothing updates x in place.)
                    tmp: match lev.transfer {
                        Transfer::Smoothed { .. } => vec![0.0; lev.a.nrows()],
                        Transfer::Plain { .. } => Vec::new(),
                    },
                    bc: vec![0.0; nc],
                    xc: vec![0.0; nc],
                    c2: vec![0.0; k],
                    v1: vec![0.0; k],
                    v2: vec![0.0; k],
                    r2: vec![0.0; k],
                }
            })
            .collect()
    }

    /// ω / a_ii of the finest level's smoother (`None` when the matrix is the coarsest
    /// level): the caller may apply the pre-smoothing x = ω D⁻¹ b itself, in a pass it makes
    /// anyway, and call [`Self::cycle_with`] with `presmoothed`.
    pub(crate) fn fine_smoother(&self) -> Option<&[f64]> {
        self.levels.first().map(|l| &l.wdinv[..])
    }

    /// One cycle from level `l`; returns b·x.
    fn cycle(&self, l: usize, b: &[f64], x: &mut Vec<f64>, work: &mut [Work]) -> f64 {
        self.cycle_with(l, b, x, work, None, false)[0]
    }

    /// One cycle from level `l` from a zero guess (level 0: x = M⁻¹ b); returns b·x and q·x
    /// (0 without `q`; summed as [`dot`]), the second in the same pass: flexible CG's
    /// q = Ap. With `presmoothed`, x already holds the first sweep ω D⁻¹ b
    /// ([`Self::fine_smoother`]).
    fn cycle_with(
        &self,
        l: usize,
        b: &[f64],
        x: &mut Vec<f64>,
        work: &mut [Work],
        q: Option<&[f64]>,
        presmoothed: bool,
    ) -> [f64; 2] {
        let dots = |x: &[f64]| [dot(b, x), q.map_or(0.0, |q| dot(q, x))];
        let Some(lev) = self.levels.get(l) else {
            match &self.coarse {
                Coarse::Dense(f) => f.solve(b, x),
                Coarse::Jacobi(wdinv) => {
                    // Two damped-Jacobi sweeps from zero (symmetric: a polynomial in D⁻¹A).
                    chunks_map(x, |c, xc| {
                        let range = c * CHUNK..c * CHUNK + xc.len();
                        for ((xi, bi), di) in xc.iter_mut().zip(&b[range.clone()]).zip(&wdinv[range]) {
                            *xi = di * bi;
                        }
                    });
                    let mut tmp = vec![0.0; x.len()];
                    jacobi(&self.coarse_a, wdinv, b, x, &mut tmp);
                    std::mem::swap(x, &mut tmp);
                }
            }
            return dots(x);
        };
        let Some((w, rest)) = work.split_first_mut() else {
            return dots(x);
        };

        // Pre-smoothing from x = 0: x = ω D⁻¹ b. (Folding it into the residual, which then
        // gathers ω/a_jj and b_j instead of x_j, was measured slower at 10⁶.)
        if !presmoothed {
            chunks_map(x, |c, xc| {
                let range = c * CHUNK..c * CHUNK + xc.len();
                for ((xi, bi), di) in xc.iter_mut().zip(&b[range.clone()]).zip(&lev.wdinv[range]) {
                    *xi = di * bi;
                }
            });
        }
        lev.a.map_rows(x, &mut w.r, |i, _, ax| b[i] - ax, |_, _| 0.0);
        lev.transfer.restrict(&w.r, &mut w.bc);
        if self.k_cycle_at(l + 1) {
            self.k_step(l + 1, w, rest);
        } else {
            self.cycle(l + 1, &w.bc, &mut w.xc, rest);
        }
        // Prolongation x += P e, then post-smoothing x += ω D⁻¹ (b − A x), with b·x (and q·x)
        // in the same sweep.
        let wdinv = &lev.wdinv;
        match &lev.transfer {
            Transfer::Plain { aggs, ap } => {
                let agg = &aggs.agg;
                // Both in one pass over A P instead of A: b − A (x + P e) = r − (A P) e, r
                // being the residual restricted above. A P has a third of A's entries and
                // gathers from the coarse e (`docs/performance.md` § 4). No other row reads
                // x here, so the sweep updates it in place.
                let (r, e) = (&w.r, &w.xc);
                sweep_dots(ap, e, x, b, q, |i, xi, ape| {
                    let k = agg[i];
                    let pe = if k == NO_AGGREGATE { 0.0 } else { e[k as usize] };
                    xi + pe + wdinv[i] * (r[i] - ape)
                })
            }
            Transfer::Smoothed { p, .. } => {
                p.map_rows(&w.xc, x, |_, y, s| y + s, |_, _| 0.0);
                let sums = sweep_dots(&lev.a, x, &mut w.tmp, b, q, |i, _, ax| {
                    x[i] + wdinv[i] * (b[i] - ax)
                });
                std::mem::swap(x, &mut w.tmp);
                sums
            }
        }
    }
}

impl Amg {
    /// The K-cycle's correction on level `l` (Notay & Vassilevski 2008): up to two
    /// flexible-CG steps on A_l x = `w.bc` from zero, each preconditioned by one
    /// cycle from level `l`; the result in `w.xc`. The first step's correction c₁ is scaled
    /// by its line search α₁/ρ₁; when the residual left is above [`K_CYCLE_TOLERANCE`] of
    /// the right-hand side, a second correction c₂ of that residual is made A-conjugate to
    /// c₁ and both are combined with their minimising weights.
    fn k_step(&self, l: usize, w: &mut Work, rest: &mut [Work]) {
        let a = &self.levels[l].a;
        let alpha1 = self.cycle(l, &w.bc, &mut w.xc, rest);
        let c1 = &w.xc;
        let rho1 = ordered_sum(&a.map_rows(c1, &mut w.v1, |_, _, s| s, |i, v| c1[i] * v));
        if !(rho1 > 0.0 && rho1.is_finite()) {
            // The right-hand side is zero (or at round-off): no correction.
            w.xc.fill(0.0);
            return;
        }
        let s1 = alpha1 / rho1;
        let (bc, v1) = (&w.bc, &w.v1);
        let parts = chunks_map(&mut w.r2, |c, rc| {
            let base = c * CHUNK;
            let (mut rr, mut bb) = (0.0, 0.0);
            for (k, ri) in rc.iter_mut().enumerate() {
                *ri = bc[base + k] - s1 * v1[base + k];
                rr += *ri * *ri;
                bb += bc[base + k] * bc[base + k];
            }
            [rr, bb]
        });
        let [rr, bb] = ordered_sums(&parts);
        if rr <= K_CYCLE_TOLERANCE * K_CYCLE_TOLERANCE * bb {
            w.xc.iter_mut().for_each(|x| *x *= s1);
            return;
        }
        let alpha2 = self.cycle(l, &w.r2, &mut w.c2, rest);
        let (c2, v1) = (&w.c2, &w.v1);
        let [beta, gamma] =
            ordered_sums(&a.map_rows(c2, &mut w.v2, |_, _, s| s, |i, v| [c2[i] * v, c2[i] * v1[i]]));
        let rho2 = beta - gamma * gamma / rho1;
        let (f1, f2) = if rho2 > 0.0 && rho2.is_finite() {
            (s1 - gamma * alpha2 / (rho1 * rho2), alpha2 / rho2)
        } else {
            // c₂ adds nothing c₁ did not (round-off): keep the first step.
            (s1, 0.0)
        };
        chunks_map(&mut w.xc, |c, xc| {
            let base = c * CHUNK;
            for (k, xi) in xc.iter_mut().enumerate() {
                *xi = f1 * *xi + f2 * c2[base + k];
            }
        });
    }
}

/// `out[i] = f(i, out[i], Σ_j m_ij v_j)` for every row i, with b·out and q·out (0 without
/// `q`) summed in the same pass, as [`dot`] sums them.
fn sweep_dots(
    m: &Sell,
    v: &[f64],
    out: &mut [f64],
    b: &[f64],
    q: Option<&[f64]>,
    f: impl Fn(usize, f64, f64) -> f64 + Sync + Send,
) -> [f64; 2] {
    match q {
        None => [ordered_sum(&m.map_rows(v, out, f, |i, x| b[i] * x)), 0.0],
        Some(q) => ordered_sums(&m.map_rows(v, out, f, |i, x| [b[i] * x, q[i] * x])),
    }
}

/// One damped-Jacobi sweep: out = x + ω D⁻¹ (b − A x). Returns the per-chunk partial sums
/// of b·out (in chunk order, as [`dot`] sums them).
fn jacobi<T: Value>(a: &Csr<T>, wdinv: &[f64], b: &[f64], x: &[f64], out: &mut [f64]) -> Vec<f64> {
    chunks_map(out, |c, tc| {
        let base = c * CHUNK;
        let mut bo = 0.0;
        for (k, ti) in tc.iter_mut().enumerate() {
            let i = base + k;
            *ti = x[i] + wdinv[i] * (b[i] - a.row_dot(i, x));
            bo += b[i] * *ti;
        }
        bo
    })
}

/// The diagonal of `a`; every entry must be positive.
fn diagonal(a: &Csr) -> Result<Vec<f64>, SolveError> {
    let d: Vec<f64> = (0..a.nrows)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|i| {
            let (c, v) = a.row(i);
            c.binary_search(&(i as u32)).map_or(0.0, |k| v[k])
        })
        .collect();
    check_diagonal(&d)?;
    Ok(d)
}

/// Refuses a diagonal entry that is not finite and > 0.
fn check_diagonal(d: &[f64]) -> Result<(), SolveError> {
    match d.iter().position(|x| !(x.is_finite() && *x > 0.0)) {
        None => Ok(()),
        Some(i) => Err(SolveError::Breakdown {
            method: "amg-pcg",
            iteration: 0,
            detail: format!("multigrid setup: diagonal entry {i} is {:e}", d[i]),
        }),
    }
}

/// Row access to a level's operator (f64 values) during the setup: compressed rows, or the
/// finest level assembled straight into SELL form ([`RowSell`]).
trait Rows: Sync {
    /// Rows (= columns).
    fn n(&self) -> usize;
    /// Row i's entries (column, value) in column order.
    fn entries(&self, i: usize) -> impl Iterator<Item = (u32, f64)> + '_;
}

impl Rows for Csr {
    fn n(&self) -> usize {
        self.nrows
    }

    #[inline]
    fn entries(&self, i: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let (c, v) = self.row(i);
        c.iter().copied().zip(v.iter().copied())
    }
}

impl Rows for RowSell {
    fn n(&self) -> usize {
        self.nrows()
    }

    #[inline]
    fn entries(&self, i: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        self.row(i)
    }
}

/// Rows per block of the aggregation. Fixed (not per thread), so the aggregates do not
/// depend on the thread count; at 10⁶ unknowns, 16 blocks.
const AGGREGATION_BLOCK: usize = 1 << 16;

/// Greedy aggregation on strong connections, in node order within blocks of
/// [`AGGREGATION_BLOCK`] rows, the blocks in parallel. Returns the aggregate of each node
/// ([`NO_AGGREGATE`]: none, for nodes without strong connections) and the count.
///
/// Pass 1 makes seeds of nodes whose strong neighbourhood is unaggregated and inside the
/// block; pass 2 attaches each node left to the pass-1 aggregate it is most strongly
/// connected to, in any block; pass 3 groups the rest with their unaggregated strong
/// neighbours in the block. Aggregates are numbered pass-1 ones first, each pass's in
/// block order. At 10⁶ unknowns on two threads the blocks took the aggregation from
/// 0.055–0.057 s to 0.043 s (one instrumented run); the nodes of a block's boundary that
/// cannot seed are attached in pass 2, and the iteration counts at 10⁵ and 10⁶ did not
/// change (`docs/performance.md`).
fn aggregate(a: &impl Rows, diag: &[f64]) -> (Vec<u32>, usize) {
    /// Marks a pass-3 aggregate numbered within its block until the blocks' counts are known.
    const LOCAL: u32 = 1 << 31;
    let n = a.n();
    // |a_ij| > θ √a_ii √a_jj, with the square roots taken once per node.
    let sq: Vec<f64> = diag.par_iter().with_min_len(CHUNK).map(|d| d.sqrt()).collect();
    let sq = &sq;
    let strong = |i: usize| {
        let t = THETA * sq[i];
        a.entries(i).filter_map(move |(j, x)| {
            let ju = j as usize;
            (ju != i && x.abs() > t * sq[ju]).then_some((ju, x.abs()))
        })
    };
    let mut agg = vec![NO_AGGREGATE; n];
    // Pass 1, numbered within each block.
    let seeds = each_block(&mut agg, |inside, block| {
        let base = inside.start;
        let mut count = 0u32;
        for i in inside.clone() {
            if block[i - base] != NO_AGGREGATE {
                continue;
            }
            let mut any = false;
            let mut all_free = true;
            for (j, _) in strong(i) {
                any = true;
                if !inside.contains(&j) || block[j - base] != NO_AGGREGATE {
                    all_free = false;
                    break;
                }
            }
            if any && all_free {
                block[i - base] = count;
                for (j, _) in strong(i) {
                    block[j - base] = count;
                }
                count += 1;
            }
        }
        count
    });
    let offsets = |counts: &[u32]| -> (Vec<u32>, u32) {
        let mut at = 0u32;
        let starts = counts
            .iter()
            .map(|&c| {
                at += c;
                at - c
            })
            .collect();
        (starts, at)
    };
    let (start1, n_first) = offsets(&seeds);
    each_block(&mut agg, |inside, block| {
        let s = start1[inside.start / AGGREGATION_BLOCK];
        block
            .iter_mut()
            .filter(|k| **k != NO_AGGREGATE)
            .for_each(|k| *k += s);
        0
    });
    // Pass 2: attach to the most strongly connected aggregate of pass 1 (read from a copy,
    // so that the blocks do not see each other's attachments).
    let first = agg.clone();
    each_block(&mut agg, |inside, block| {
        for (i, k) in inside.zip(block.iter_mut()) {
            if first[i] != NO_AGGREGATE {
                continue;
            }
            let mut best: Option<(f64, u32)> = None;
            for (j, s) in strong(i) {
                if first[j] != NO_AGGREGATE && best.is_none_or(|(b, _)| s > b) {
                    best = Some((s, first[j]));
                }
            }
            if let Some((_, found)) = best {
                *k = found;
            }
        }
        0
    });
    drop(first);
    // Pass 3: the rest form aggregates with their unaggregated strong neighbours in the
    // block, numbered within the block (tagged) and renumbered below.
    let rest = each_block(&mut agg, |inside, block| {
        let base = inside.start;
        let mut count = 0u32;
        for i in inside.clone() {
            if block[i - base] != NO_AGGREGATE || strong(i).next().is_none() {
                continue;
            }
            block[i - base] = LOCAL | count;
            for (j, _) in strong(i) {
                if inside.contains(&j) && block[j - base] == NO_AGGREGATE {
                    block[j - base] = LOCAL | count;
                }
            }
            count += 1;
        }
        count
    });
    let (start3, n_rest) = offsets(&rest);
    each_block(&mut agg, |inside, block| {
        let s = n_first + start3[inside.start / AGGREGATION_BLOCK];
        block
            .iter_mut()
            .filter(|k| **k != NO_AGGREGATE && **k & LOCAL != 0)
            .for_each(|k| *k = s + (*k & !LOCAL));
        0
    });
    (agg, (n_first + n_rest) as usize)
}

/// `f(rows, block)` on each [`AGGREGATION_BLOCK`] of `agg`, in parallel (`rows`: the block's
/// node indices); the counts it returns, in block order.
fn each_block(
    agg: &mut [u32],
    f: impl Fn(std::ops::Range<usize>, &mut [u32]) -> u32 + Sync + Send,
) -> Vec<u32> {
    agg.par_chunks_mut(AGGREGATION_BLOCK)
        .enumerate()
        .map(|(b, block)| {
            let base = b * AGGREGATION_BLOCK;
            f(base..base + block.len(), block)
        })
        .collect()
}

/// The Galerkin operator of plain aggregation, Pᵀ (A P) with P[i, agg(i)] = 1, from A P in
/// compressed rows ([`Sell::group_columns`], f64 sums): (A_c)_kl = Σ (A P)_il over the
/// members i of aggregate k, in member order.
fn galerkin_plain(ap: &Csr, aggs: &Aggregates) -> Csr {
    let Aggregates { ptr, members, .. } = aggs;
    let n_agg = aggs.count();
    Csr::from_rows(
        n_agg,
        n_agg,
        || Accumulator::new(n_agg),
        |acc, k, cols, vals| {
            for &i in &members[ptr[k] as usize..ptr[k + 1] as usize] {
                let (c, v) = ap.row(i as usize);
                for (&l, &x) in c.iter().zip(v) {
                    acc.add(k, l, x);
                }
            }
            acc.drain_sorted_append(cols, vals);
        },
    )
}

/// Tentative prolongator: P[i, agg(i)] = B_i / ‖B‖_agg; coarse near-null space ‖B‖_agg.
fn tentative(agg: &[u32], n_agg: usize, b: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut norm2 = vec![0.0; n_agg];
    for (&k, &bi) in agg.iter().zip(b) {
        if k != NO_AGGREGATE {
            norm2[k as usize] += bi * bi;
        }
    }
    let norms: Vec<f64> = norm2.iter().map(|v| v.sqrt()).collect();
    let ptent = agg
        .iter()
        .zip(b)
        .map(|(&k, &bi)| {
            if k == NO_AGGREGATE {
                0.0
            } else {
                bi / norms[k as usize]
            }
        })
        .collect();
    (ptent, norms)
}

/// P = (I − ω D⁻¹ A) P_tent, P_tent given by its one value per row and the aggregates.
fn smooth_prolongator(a: &Csr, dinv: &[f64], omega: f64, ptent: &[f64], agg: &[u32]) -> Csr {
    let n_agg = agg
        .iter()
        .filter(|&&k| k != NO_AGGREGATE)
        .map(|&k| k as usize + 1)
        .max()
        .unwrap_or(0);
    // Built in place (count, then fill): P has as many rows as A.
    Csr::from_row_lengths(
        a.nrows,
        n_agg,
        || Accumulator::new(n_agg),
        |acc, i| {
            std::iter::once(i as u32)
                .chain(a.row(i).0.iter().copied())
                .map(|j| agg[j as usize])
                .filter(|&k| k != NO_AGGREGATE && acc.mark(i, k))
                .count()
        },
        |acc, i, cols, vals| {
            if agg[i] != NO_AGGREGATE {
                acc.add(i, agg[i], ptent[i]);
            }
            let s = -omega * dinv[i];
            let (c, v) = a.row(i);
            for (&j, &x) in c.iter().zip(v) {
                let k = agg[j as usize];
                if k != NO_AGGREGATE {
                    acc.add(i, k, s * x * ptent[j as usize]);
                }
            }
            acc.drain_sorted_into(cols, vals);
        },
    )
}

/// The Gershgorin bound of ρ(D⁻¹A): max_i Σ_j |a_ij| / a_ii.
fn gershgorin(a: &Csr, dinv: &[f64]) -> f64 {
    (0..a.nrows)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|i| a.row(i).1.iter().map(|v| v.abs()).sum::<f64>() * dinv[i])
        .reduce(|| 0.0, f64::max)
}

/// Estimate of ρ(D⁻¹A) from [`POWER_STEPS`] power iterations on the compressed rows
/// ([`power_estimate`]).
fn spectral_radius(a: &Csr, dinv: &[f64], bound: f64) -> f64 {
    power_estimate(a.nrows, POWER_STEPS, bound, |x, y| {
        // y = D⁻¹ A x with the partial sums of x·Ax, x·Dx and y·y, per chunk.
        ordered_sums(&chunks_map(y, |c, yc| {
            let base = c * CHUNK;
            let (mut xax, mut xdx, mut yy) = (0.0, 0.0, 0.0);
            for (k, yi) in yc.iter_mut().enumerate() {
                let i = base + k;
                let ax = a.row_dot(i, x);
                xax += x[i] * ax;
                xdx += x[i] * x[i] / dinv[i];
                *yi = ax * dinv[i];
                yy += *yi * *yi;
            }
            [xax, xdx, yy]
        }))
    })
}

/// As [`spectral_radius`] with [`PLAIN_POWER_STEPS`] products of the SELL form (f32 values:
/// the estimate only sets ω).
fn sell_spectral_radius(a: &Sell, dinv: &[f64], bound: f64) -> f64 {
    power_estimate(a.nrows(), PLAIN_POWER_STEPS, bound, |x, y| {
        ordered_sums(&a.map_rows(
            x,
            y,
            |i, _, ax| ax * dinv[i],
            |i, yi| [x[i] * yi / dinv[i], x[i] * x[i] / dinv[i], yi * yi],
        ))
    })
}

/// Estimate of ρ(D⁻¹A): the largest of `steps` power-iteration Rayleigh quotients (in the D
/// inner product), raised by 10 %, capped by `bound` (Gershgorin's). `step(x, y)` sets
/// y = D⁻¹ A x and returns x·Ax, x·Dx and y·y.
fn power_estimate(
    n: usize,
    steps: usize,
    bound: f64,
    mut step: impl FnMut(&[f64], &mut [f64]) -> [f64; 3],
) -> f64 {
    // Fixed pseudo-random start vector (deterministic).
    let mut x: Vec<f64> = (0..n)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|i| {
            let h = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            ((h >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        })
        .collect();
    let mut y = vec![0.0; n];
    let mut est = 0.0f64;
    for _ in 0..steps {
        let [xax, xdx, yy] = step(&x, &mut y);
        if xdx > 0.0 {
            est = est.max(xax / xdx);
        }
        let norm = yy.sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            break;
        }
        x.par_iter_mut()
            .zip(y.par_iter())
            .with_min_len(CHUNK)
            .for_each(|(xi, yi)| *xi = yi / norm);
    }
    if est > 0.0 {
        (1.1 * est).min(bound)
    } else {
        bound.max(1.0)
    }
}

/// Solver of the coarsest level.
#[derive(Debug)]
enum Coarse {
    /// Exact: dense LDLᵀ (at most [`MAX_DENSE`] unknowns).
    Dense(DenseCholesky),
    /// Coarsening stalled above [`MAX_DENSE`] unknowns: two damped-Jacobi sweeps
    /// (ω/a_ii stored).
    Jacobi(Vec<f64>),
}

/// Dense LDLᵀ factor of the coarsest operator (row-major unit lower triangle L, pivots D;
/// no square roots, so exactly representable solutions such as uniform fields come out
/// exact).
#[derive(Debug)]
struct DenseCholesky {
    n: usize,
    l: Vec<f64>,
    d: Vec<f64>,
}

impl DenseCholesky {
    fn new(a: &Csr) -> Result<Self, SolveError> {
        let n = a.nrows;
        let mut l = vec![0.0; n * n];
        for i in 0..n {
            let (c, v) = a.row(i);
            for (&j, &x) in c.iter().zip(v) {
                if (j as usize) <= i {
                    l[i * n + j as usize] = x;
                }
            }
        }
        let mut d = vec![0.0; n];
        // Row-oriented LDLᵀ: w_k = L_jk d_k is reused for the entries below the pivot.
        let mut w = vec![0.0; n];
        for j in 0..n {
            let mut dj = l[j * n + j];
            for k in 0..j {
                w[k] = l[j * n + k] * d[k];
                dj -= l[j * n + k] * w[k];
            }
            if !(dj > 0.0 && dj.is_finite()) {
                return Err(SolveError::Breakdown {
                    method: "amg-pcg",
                    iteration: 0,
                    detail: format!("coarsest-level factorisation: pivot {j} of {n} is {dj:e}"),
                });
            }
            d[j] = dj;
            l[j * n + j] = 1.0;
            for i in j + 1..n {
                let mut s = l[i * n + j];
                for k in 0..j {
                    s -= l[i * n + k] * w[k];
                }
                l[i * n + j] = s / dj;
            }
        }
        Ok(Self { n, l, d })
    }

    /// x = A⁻¹ b.
    fn solve(&self, b: &[f64], x: &mut [f64]) {
        let n = self.n;
        for (i, bi) in b.iter().enumerate().take(n) {
            let (done, rest) = x.split_at_mut(i);
            let row = &self.l[i * n..i * n + i];
            rest[0] = bi - row.iter().zip(done.iter()).map(|(l, v)| l * v).sum::<f64>();
        }
        for (xi, di) in x.iter_mut().zip(&self.d) {
            *xi /= di;
        }
        for i in (0..n).rev() {
            let (head, tail) = x.split_at_mut(i + 1);
            let s: f64 = tail
                .iter()
                .enumerate()
                .map(|(k, v)| self.l[(i + 1 + k) * n + i] * v)
                .sum();
            head[i] -= s;
        }
    }
}

/// CG on the free block preconditioned by one multigrid cycle ([`pcg::cg`]): the fine
/// operator's product, the cycle, and the residual update that makes the fine smoother's
/// first sweep z = ω D⁻¹ r in the same pass.
struct Cycled<'h> {
    amg: &'h Amg,
    work: Vec<Work>,
    /// ω D⁻¹ of the finest level (none when the hierarchy is its coarse solve alone).
    smoother: Option<&'h [f64]>,
}

impl Krylov for Cycled<'_> {
    fn name(&self) -> &'static str {
        "amg-pcg"
    }

    fn apply_dot(&mut self, p: &[f64], q: &mut [f64]) -> f64 {
        self.amg.fine_spmv_dot(p, q)
    }

    fn descend(&mut self, alpha: f64, q: &[f64], r: &mut [f64], z: &mut Vec<f64>) -> f64 {
        let smoother = self.smoother;
        let partials = chunks_map2(r, z, |c, rc, zc| {
            let range = c * CHUNK..c * CHUNK + rc.len();
            let mut rr = 0.0;
            match smoother {
                Some(wdinv) => {
                    for (((ri, zi), qi), di) in
                        rc.iter_mut().zip(zc).zip(&q[range.clone()]).zip(&wdinv[range])
                    {
                        *ri -= alpha * qi;
                        *zi = di * *ri;
                        rr += *ri * *ri;
                    }
                }
                None => {
                    for (ri, qi) in rc.iter_mut().zip(&q[range]) {
                        *ri -= alpha * qi;
                        rr += *ri * *ri;
                    }
                }
            }
            rr
        });
        ordered_sum(&partials)
    }

    fn precondition(&mut self, r: &[f64], z: &mut Vec<f64>, q: Option<&[f64]>, descended: bool) -> [f64; 2] {
        let presmoothed = descended && self.smoother.is_some();
        self.amg.cycle_with(0, r, z, &mut self.work, q, presmoothed)
    }

    /// The K-cycle is nonlinear: β = −(z·q)/(p·q) keeps the new direction A-conjugate to the
    /// last (z·q summed in the cycle's last sweep).
    fn flexible(&self) -> bool {
        self.amg.flexible()
    }
}

/// Solves `a` δ = `rhs` from δ = 0 by multigrid-preconditioned CG, until ‖rhs − a δ‖ ≤
/// `abs_tol` (recursive residual) or `max_iter` iterations. Returns (δ, iterations).
pub(crate) fn solve(
    amg: &Amg,
    rhs: &[f64],
    abs_tol: f64,
    max_iter: usize,
) -> Result<(Vec<f64>, usize), SolveError> {
    let mut x = vec![0.0; rhs.len()];
    if let (true, Coarse::Dense(f)) = (amg.levels.is_empty(), &amg.coarse) {
        // The hierarchy is one exact factor: solve directly.
        f.solve(rhs, &mut x);
        return Ok((x, 1));
    }
    // Copies in parallel chunks (fresh pages first touched by both threads).
    let mut r: Vec<f64> = rhs.par_iter().with_min_len(CHUNK).copied().collect();
    let mut cycled = Cycled {
        amg,
        work: amg.work(),
        smoother: amg.fine_smoother(),
    };
    let iterations = pcg::cg(&mut cycled, &mut x, &mut r, abs_tol, max_iter)?;
    Ok((x, iterations))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1-D Dirichlet Laplacian of n unknowns (tridiagonal 2, −1).
    fn laplace_1d(n: usize) -> Csr {
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
                v.push(2.0);
                if i + 1 < n {
                    c.push(i as u32 + 1);
                    v.push(-1.0);
                }
            },
        )
    }

    #[test]
    fn stalled_coarsening_falls_back_to_smoothing_not_a_dense_factor() {
        // 5000 unknowns without off-diagonal entries: nothing to aggregate.
        let n = 5000;
        let a = Csr::from_rows(
            n,
            n,
            || (),
            |_, i, c, v| {
                c.push(i as u32);
                v.push(1.0 + (i % 3) as f64);
            },
        );
        let sliced = || Amg::plain_from_sell(RowSell::from_csr_rows(&a), diagonal(&a).unwrap()).unwrap();
        for (coarsening, amg) in [
            (
                Coarsening::Smoothed,
                Amg::new(a.clone(), Coarsening::Smoothed).unwrap(),
            ),
            (Coarsening::Plain, Amg::new(a.clone(), Coarsening::Plain).unwrap()),
            // Assembled in sliced form: the stalled first coarsening takes the same path.
            (Coarsening::Plain, sliced()),
        ] {
            assert!(matches!(amg.coarse, Coarse::Jacobi(_)));
            assert_eq!(amg.info().levels.len(), 1);
            // One level: the preconditioner is linear, CG is not flexible.
            assert!(!amg.flexible());
            let rhs: Vec<f64> = (0..n).map(|i| (i % 7) as f64).collect();
            let (x, its) = solve(&amg, &rhs, 1e-12, 50).unwrap();
            let mut r = vec![0.0; n];
            a.residual(&rhs, &x, &mut r);
            assert!(dot(&r, &r).sqrt() <= 1e-10, "{coarsening:?}: {its} iterations");
        }
    }

    /// 2-D 5-point Laplacian on m × m nodes, with varying weights and a small shift.
    fn laplace_2d(m: usize) -> Csr {
        let w = |i: usize, j: usize| 1.0 + ((i * 31 + j * 17) % 5) as f64;
        Csr::from_rows(
            m * m,
            m * m,
            || (),
            |_, i, c, v| {
                let (x, y) = (i % m, i / m);
                let mut e: Vec<(usize, f64)> = Vec::new();
                let mut d = 0.1;
                for (ok, j) in [
                    (y > 0, i.wrapping_sub(m)),
                    (x > 0, i.wrapping_sub(1)),
                    (x + 1 < m, i + 1),
                    (y + 1 < m, i + m),
                ] {
                    if ok {
                        e.push((j, -w(i.min(j), i.max(j))));
                        d += w(i.min(j), i.max(j));
                    }
                }
                e.push((i, d));
                e.sort_by_key(|p| p.0);
                for (j, x) in e {
                    c.push(j as u32);
                    v.push(x);
                }
            },
        )
    }

    #[test]
    fn aggregation_in_blocks_covers_every_node_and_ignores_the_thread_count() {
        // 300 × 300 nodes: two aggregation blocks.
        let m = 300;
        let a = laplace_2d(m);
        assert!(a.nrows > AGGREGATION_BLOCK);
        let diag = diagonal(&a).unwrap();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| aggregate(&a, &diag))
        };
        let (agg, n_agg) = run(1);
        assert_eq!(run(2), (agg.clone(), n_agg));
        // Every node is in an aggregate (all have strong neighbours); every aggregate has
        // members, and a block boundary does not leave a trail of single nodes.
        let mut size = vec![0usize; n_agg];
        for &k in &agg {
            assert!((k as usize) < n_agg, "{k} of {n_agg}");
            size[k as usize] += 1;
        }
        assert!(size.iter().all(|&s| s > 0));
        let singles = size.iter().filter(|&&s| s == 1).count();
        assert!(
            singles * 100 < n_agg,
            "{singles} single-node aggregates of {n_agg}"
        );
        assert!(n_agg * 3 < m * m, "{n_agg} aggregates");
    }

    #[test]
    fn plain_galerkin_operator_is_pt_a_p() {
        let m = 30;
        let a = laplace_2d(m);
        let diag = diagonal(&a).unwrap();
        let (agg, n_agg) = aggregate(&a, &diag);
        assert!(n_agg > 1 && n_agg < m * m / 2, "{n_agg} aggregates");
        let (a32, vals) = Sell::from_csr_with_f64(a.clone());
        let (ac, transfer) = plain_transfer(&a32, &vals, Aggregates::new(agg.clone(), n_agg));
        // The same products with P as a matrix.
        let p = Csr::from_rows(
            m * m,
            n_agg,
            || (),
            |_, i, c, v| {
                if agg[i] != NO_AGGREGATE {
                    c.push(agg[i]);
                    v.push(1.0);
                }
            },
        );
        let want = p.transpose().galerkin(&a, &p);
        assert_eq!(
            (ac.ptr.clone(), ac.cols.clone()),
            (want.ptr.clone(), want.cols.clone())
        );
        for (x, y) in ac.vals.iter().zip(&want.vals) {
            assert!((x - y).abs() <= 1e-12 * y.abs().max(1.0), "{x} against {y}");
        }
        // The stored A P (f32 sums of A's f64 entries) is A times P; restriction sums over
        // members: R = Pᵀ.
        let Transfer::Plain { ap, .. } = &transfer else {
            unreachable!("a plain transfer")
        };
        let xc: Vec<f64> = (0..n_agg).map(|k| (k % 7) as f64).collect();
        let (mut x, mut got, mut want) = (vec![0.0; m * m], vec![0.0; m * m], vec![0.0; m * m]);
        p.spmv(&xc, &mut x);
        a.spmv(&x, &mut want);
        ap.map_rows(&xc, &mut got, |_, _, s| s, |_, _| 0.0);
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            // Rounding A and A P to f32: within 2 ε₃₂ Σ_j |a_ij| max |x_j|.
            let bound = 1.2e-7 * a.row(i).1.iter().map(|v| v.abs()).sum::<f64>() * 6.0;
            assert!((g - w).abs() <= bound, "{g} against {w}");
        }
        let r: Vec<f64> = (0..m * m).map(|i| (i % 11) as f64 - 5.0).collect();
        let mut bc = vec![0.0; n_agg];
        transfer.restrict(&r, &mut bc);
        assert!((dot(&bc, &xc) - dot(&r, &x)).abs() <= 1e-9 * dot(&r, &r).sqrt());
    }

    #[test]
    fn hierarchy_assembled_in_sliced_form_is_the_compressed_rows_one() {
        // The same aggregates, Galerkin operators and ω either way, so the same iterates.
        let a = laplace_2d(120);
        let diag = diagonal(&a).unwrap();
        let from_sell = Amg::plain_from_sell(RowSell::from_csr_rows(&a), diag).unwrap();
        let from_csr = Amg::new(a.clone(), Coarsening::Plain).unwrap();
        assert!(from_csr.levels.len() >= 2);
        assert_eq!(
            from_sell
                .info()
                .levels
                .iter()
                .map(|l| (l.rows, l.nnz))
                .collect::<Vec<_>>(),
            from_csr
                .info()
                .levels
                .iter()
                .map(|l| (l.rows, l.nnz))
                .collect::<Vec<_>>()
        );
        let b: Vec<f64> = (0..a.nrows).map(|i| ((i * 7) % 13) as f64 - 6.0).collect();
        let (x1, it1) = solve(&from_sell, &b, 1e-10 * dot(&b, &b).sqrt(), 200).unwrap();
        let (x2, it2) = solve(&from_csr, &b, 1e-10 * dot(&b, &b).sqrt(), 200).unwrap();
        assert_eq!((it1, &x1), (it2, &x2));
    }

    #[test]
    fn dense_cholesky_solves_exactly() {
        let a = laplace_1d(7);
        let f = DenseCholesky::new(&a).unwrap();
        let b: Vec<f64> = (0..7).map(|i| i as f64 - 3.0).collect();
        let mut x = vec![0.0; 7];
        f.solve(&b, &mut x);
        let mut r = vec![0.0; 7];
        a.residual(&b, &x, &mut r);
        assert!(r.iter().all(|v| v.abs() < 1e-12), "{r:?}");
    }

    #[test]
    fn hierarchy_coarsens_and_preconditions_a_long_chain() {
        let n = 20_000;
        let a = laplace_1d(n);
        for coarsening in [Coarsening::Smoothed, Coarsening::Plain] {
            let amg = Amg::new(a.clone(), coarsening).unwrap();
            let info = amg.info();
            assert!(info.levels.len() >= 3, "{info:?}");
            assert!(info.levels.last().unwrap().rows <= MAX_COARSE);
            assert!(info.operator_complexity < 2.5, "{info:?}");
            assert_eq!(amg.flexible(), coarsening == Coarsening::Plain);
            let rhs: Vec<f64> = (0..n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
            let norm = dot(&rhs, &rhs).sqrt();
            let (x, its) = solve(&amg, &rhs, 1e-10 * norm, 200).unwrap();
            let mut r = vec![0.0; n];
            a.residual(&rhs, &x, &mut r);
            assert!(dot(&r, &r).sqrt() <= 2e-10 * norm, "{coarsening:?}");
            // Unpreconditioned CG needs ~n/2 iterations on this chain.
            assert!(its < 60, "{coarsening:?}: {its} iterations");
        }
    }
}
