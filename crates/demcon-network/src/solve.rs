//! Steady and shifted solves of the network: parameters, reports, and the prepared
//! linear system shared by the conjugate-gradient and Cholesky paths.

use std::time::Instant;

use demcon_core::check::{check_finite, check_len};
use rayon::prelude::*;

use crate::amg::{self, Amg, AmgInfo, Coarsening};
use crate::constraints::{Constraints, NodeKind};
use crate::csr::Csr;
use crate::error::SolveError;
use crate::ic::{self, Mic};
use crate::network::Network;
use crate::par::{CHUNK, chunks_map, chunks_map2, dot, ordered_sum};
use crate::pcg::{self, Krylov, Stop};
use crate::sell::RowSell;
use crate::{cholesky, distributed};

/// How the linear system is solved; the tolerance and the iteration limit of the iterative
/// methods are [`SolveParams::rel_tol`] and [`SolveParams::max_iter`]. Every iterative method
/// runs the crate's one conjugate gradient (or PETSc's) and stops when ‖b − Ax‖/‖b‖ ≤
/// `rel_tol` on the true residual, not only the recursive one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Jacobi-preconditioned conjugate gradient on the whole network, with fused parallel
    /// sweeps (deterministic for any thread count).
    Cg,
    /// Conjugate gradient preconditioned by aggregation algebraic multigrid on the free-node
    /// block, deterministic for any thread count: plain aggregation with a K-cycle and
    /// flexible CG for unshifted systems (steady, electric, homogenisation: a cheap setup),
    /// smoothed aggregation with a V-cycle for shifted ones (implicit steps: a cheap cycle).
    /// The hierarchy is built once per [`LinearSystem`] (cost in [`SolveReport::setup_s`],
    /// kind in [`LinearSystem::amg_info`]) and reused by every solve; a few tens of
    /// iterations at any size where Jacobi-PCG needs hundreds.
    AmgCg,
    /// Conjugate gradient preconditioned by the modified diagonal incomplete Cholesky
    /// factorisation (MIC, relaxation ω = 0.8): M = (D + L) D⁻¹ (D + L)ᵀ with only D computed,
    /// so M's row sums follow A's. Its two triangular sweeps are sequential, but it needs
    /// several times fewer iterations than Jacobi-PCG: the method for small systems
    /// (10³–10⁴ unknowns).
    IcCg,
    /// Chooses by the number of unknowns: MIC-PCG ([`Method::IcCg`]) below
    /// [`AUTO_AMG_MIN_UNKNOWNS`], where its sequential sweeps are cheap and its setup is
    /// negligible (5·10³ nodes: ~3 ms against ~6 ms for Jacobi-PCG and ~7 ms for multigrid),
    /// multigrid ([`Method::AmgCg`]) from there on (10⁵ nodes: 2–3× faster than MIC-PCG;
    /// 10⁶: ~10× faster than Jacobi-PCG). [`SolveReport::method`] names the method that ran.
    #[default]
    Auto,
    /// Direct sparse Cholesky (faer, AMD ordering). The factorisation is reused by every
    /// solve of one [`LinearSystem`]; practical to ~10⁵ unknowns. Ignores `rel_tol` and
    /// `max_iter`.
    Cholesky,
    /// PETSc's conjugate gradient preconditioned by its smoothed-aggregation multigrid
    /// (KSPCG + PCGAMG) on the free block distributed over the MPI ranks by contiguous row
    /// ranges ([`crate::distributed`]); needs the `petsc` feature and a running
    /// [`crate::distributed::Session`] on every rank, and every rank must set up and solve
    /// the same systems in the same order. The matrix and the hierarchy are built once per
    /// [`LinearSystem`]. Restarted from the true residual like the others: every rank ends
    /// with the whole solution.
    Distributed,
}

/// Relaxation ω of [`Method::IcCg`]'s modified incomplete Cholesky (0 = DIC, 1 = row sums
/// kept). Measured on packing-like networks (iterations to 1e-8 at 5·10³ nodes): ω = 0: 70,
/// 0.8: 67, 0.95: 69, 0.99: 87, 1: 517; with conductances spread over a decade ω ≤ 0.8 is
/// best (65–66 against 123 at 0.99).
const MIC_RELAXATION: f64 = 0.8;

/// Unknowns from which [`Method::Auto`] uses multigrid (measured crossover on packing
/// networks: at 10⁴ nodes MIC-PCG and multigrid both take ~15 ms, see
/// `docs/performance.md`).
pub const AUTO_AMG_MIN_UNKNOWNS: usize = 10_000;

/// Largest |b_i| (W or A) a solve accepts, b being the right-hand side with the fixed values
/// moved to it (sources + Σ conductance × fixed value). Above it, ‖b‖² and the products of
/// conjugate gradient may overflow f64 (‖b‖² ≤ n·10³⁰⁰ stays finite to n = 10⁸): such inputs
/// are refused with [`SolveError::InvalidParameter`] rather than rescaled — rescale the
/// units instead (e.g. mW, kK).
pub const MAX_RHS_ENTRY: f64 = 1e150;

/// Restarts without a decrease of the best true residual (by at least
/// [`STAGNATION_DECREASE`]) after which an iterative solve stops as stagnated.
pub const STAGNATION_WINDOW: usize = 5;

/// A restart counts as progress when it brings the best true relative residual below this
/// fraction of its previous value.
pub const STAGNATION_DECREASE: f64 = 0.9;

/// Safety factor of the round-off floor [`SolveReport::attainable`]: the computed residual
/// of a row of k entries carries an error of up to k·ε·(|b_i| + Σ_j |a_ij x_j|), about
/// √k·ε· that on average; packings have k ≈ 7–14.
const ATTAINABLE_FACTOR: f64 = 8.0;

impl Method {
    /// Short name, for reports.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Cg => "jacobi-pcg",
            Self::IcCg => "mic-pcg",
            Self::AmgCg => "amg-pcg",
            Self::Auto => "auto",
            Self::Cholesky => "cholesky",
            Self::Distributed => distributed::METHOD,
        }
    }

    /// The concrete method [`Method::Auto`] picks for `n_unknowns` (other methods are
    /// returned unchanged).
    pub fn resolve(&self, n_unknowns: usize) -> Method {
        match *self {
            Self::Auto if n_unknowns >= AUTO_AMG_MIN_UNKNOWNS => Self::AmgCg,
            Self::Auto => Self::IcCg,
            m => m,
        }
    }
}

/// Inputs of a solve besides the system itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveParams {
    /// Solution method.
    pub method: Method,
    /// Relative residual tolerance ‖b − Ax‖/‖b‖ of the iterative methods, in (0, 1).
    pub rel_tol: f64,
    /// Iteration limit of the iterative methods, ≥ 1.
    pub max_iter: usize,
}

/// [`Method::Auto`] to a relative residual of 1e-8 (at most 20 000 iterations).
impl Default for SolveParams {
    fn default() -> Self {
        Self::new(Method::Auto, 1e-8, 20_000)
    }
}

impl SolveParams {
    /// `method` to a relative residual of `rel_tol` in at most `max_iter` iterations.
    pub const fn new(method: Method, rel_tol: f64, max_iter: usize) -> Self {
        Self {
            method,
            rel_tol,
            max_iter,
        }
    }

    /// Refuses a tolerance outside (0, 1) or no iterations (iterative methods only).
    fn validate(&self) -> Result<(), SolveError> {
        if self.method == Method::Cholesky {
            return Ok(());
        }
        let rel_tol = self.rel_tol;
        if !(rel_tol.is_finite() && rel_tol > 0.0 && rel_tol < 1.0) {
            return Err(SolveError::invalid(
                "method.rel_tol",
                rel_tol,
                "must be in (0, 1), e.g. 1e-8",
            ));
        }
        if self.max_iter == 0 {
            return Err(SolveError::invalid("method.max_iter", 0, "must be ≥ 1"));
        }
        Ok(())
    }

    /// When an iterative solve of right-hand-side norm `b_norm` stops.
    fn stop(&self, b_norm: f64) -> Stop {
        Stop {
            b_norm,
            rel_tol: self.rel_tol,
            max_iter: self.max_iter,
        }
    }
}

/// What a solve did and what it cost.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveReport {
    /// Method name ([`Method::name`]).
    pub method: &'static str,
    /// Iterations (0 for Cholesky).
    pub iterations: usize,
    /// True relative residual ‖b − Ax‖₂/‖b‖₂ over the unknowns, with the fixed values moved
    /// to b (0 when b = 0).
    pub relative_residual: f64,
    /// Wall time of this solve (s), excluding [`Self::setup_s`].
    pub wall_s: f64,
    /// Wall time of preparing the system (s): gathering values and, for Cholesky, the
    /// factorisation. Shared by every solve of one [`LinearSystem`].
    pub setup_s: f64,
    /// Number of unknowns.
    pub n_unknowns: usize,
    /// Number of excluded (floating) nodes.
    pub n_excluded: usize,
    /// `Some(floor)` when the tolerance was not met but the iteration stopped (stagnated or
    /// ran out of iterations) at a relative residual within the round-off floor
    /// `floor` ≈ 8 ε ‖|b| + |A||x|‖/‖b‖ (dimensionless) that f64 arithmetic can resolve for
    /// this system and solution (high conductivity contrast raises it): the result is
    /// accepted as accurate to the arithmetic. `None` when the tolerance was met.
    pub attainable: Option<f64>,
}

/// A nodal solution.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// Value at every node (K or V). Fixed nodes carry their fixed value. Excluded nodes
    /// carry their initial guess when one was given, else 0; they are listed in
    /// [`Self::excluded`] and must not be read as results.
    pub values: Vec<f64>,
    /// Excluded (floating) nodes, sorted.
    pub excluded: Vec<u32>,
    /// Cost and accuracy.
    pub report: SolveReport,
}

/// Conductances of a [`LinearSystem`] as its products on the whole network read them.
#[derive(Debug)]
pub(crate) enum EntryValues<'a> {
    /// One per compressed-row entry, in row order: for the methods whose every iteration
    /// runs on the whole network (Jacobi-PCG).
    Entries(Vec<f64>),
    /// One per edge, read through each entry's edge: half the bytes, for the methods that
    /// iterate on their own copy of the free block and only form a few residuals here
    /// (multigrid, MIC, Cholesky). Borrowed from the caller: no copy beside its vector.
    Edges(&'a [f64]),
}

/// The system (D + K) x = b restricted to the free nodes of `constraints`, with the fixed
/// values moved to the right-hand side; prepared once, solved for many right-hand sides
/// (implicit time steps, several load cases).
///
/// D is an optional non-negative diagonal (e.g. C_p/Δt, W/K) — absent for a steady solve.
#[derive(Debug)]
pub struct LinearSystem<'a> {
    pub(crate) net: &'a Network,
    pub(crate) constraints: &'a Constraints,
    /// Conductances (W/K or S) as the products on the whole network read them.
    pub(crate) values: EntryValues<'a>,
    /// Diagonal Σg + D at every node.
    pub(crate) diag: Vec<f64>,
    /// 1/diag at free nodes, 0 elsewhere (Jacobi preconditioner and free mask).
    pub(crate) inv_diag: Vec<f64>,
    pub(crate) free: Vec<bool>,
    /// The free nodes next to a fixed node, sorted: the only rows of b_eff that differ
    /// from b ([`Self::lifted_rhs`]).
    lift_rows: Vec<u32>,
    /// The parameters, [`Method::Auto`] resolved.
    params: SolveParams,
    /// What the method prepared once for every solve.
    prepared: Prepared,
    setup_s: f64,
}

/// What a method prepares once per [`LinearSystem`]; the compact methods keep the free nodes
/// in unknown order beside it.
#[derive(Debug)]
enum Prepared {
    /// Jacobi-PCG: the inverse diagonal, kept by the system itself.
    Jacobi,
    /// The multigrid hierarchy of the free block ([`Method::AmgCg`]).
    Amg(Amg, Vec<u32>),
    /// The modified incomplete Cholesky factor of the free block ([`Method::IcCg`]).
    Mic(Mic, Vec<u32>),
    /// The PETSc solver of the free block ([`Method::Distributed`]).
    Petsc(distributed::Solver, Vec<u32>),
    /// The sparse Cholesky factor ([`Method::Cholesky`]).
    Cholesky(cholesky::Factor),
}

impl<'a> LinearSystem<'a> {
    /// Prepares the system: checks inputs, gathers conductances into row order and, for
    /// [`Method::Cholesky`], factorises.
    ///
    /// `conductances`: one per edge (W/K or S), finite and > 0. `shift`: optional D, one
    /// finite value ≥ 0 per node (W/K or S).
    ///
    /// # Errors
    /// Bad input (lengths, values, method parameters); [`SolveError::FloatingCluster`] when
    /// floating clusters were kept ([`crate::FloatingPolicy::Keep`]) and a node of them has
    /// no positive shift (the system would be singular); factorisation failures.
    pub fn new(
        net: &'a Network,
        conductances: &'a [f64],
        shift: Option<&[f64]>,
        constraints: &'a Constraints,
        params: &SolveParams,
    ) -> Result<Self, SolveError> {
        let start = Instant::now();
        check_system(net, conductances, shift, constraints, params)?;
        let method = params.method.resolve(constraints.n_free());
        let values = match method {
            Method::Cg | Method::Auto => EntryValues::Entries(net.entry_values(conductances)),
            Method::AmgCg | Method::IcCg | Method::Cholesky | Method::Distributed => {
                EntryValues::Edges(conductances)
            }
        };
        let mut diag = net.row_sums(conductances);
        if let Some(d) = shift {
            diag.par_iter_mut()
                .zip(d.par_iter())
                .with_min_len(CHUNK)
                .for_each(|(a, b)| *a += b);
        }
        let free: Vec<bool> = constraints.kinds().iter().map(|k| *k == NodeKind::Free).collect();
        // A free node of degree 0 with no shift is a floating cluster of one: already
        // caught above, so diag > 0 on free nodes.
        let inv_diag = diag
            .iter()
            .zip(&free)
            .map(|(&d, &f)| if f && d > 0.0 { 1.0 / d } else { 0.0 })
            .collect();
        let mut lift_rows: Vec<u32> = constraints
            .fixed_nodes()
            .iter()
            .flat_map(|&p| {
                let p = p as usize;
                net.cols()[net.row_ptr()[p]..net.row_ptr()[p + 1]].iter().copied()
            })
            .filter(|&q| free[q as usize])
            .collect();
        lift_rows.sort_unstable();
        lift_rows.dedup();
        let mut sys = Self {
            net,
            constraints,
            values,
            diag,
            inv_diag,
            free,
            lift_rows,
            params: SolveParams { method, ..*params },
            prepared: Prepared::Jacobi,
            setup_s: 0.0,
        };
        sys.prepared = sys.prepare(shift.is_some())?;
        sys.setup_s = start.elapsed().as_secs_f64();
        Ok(sys)
    }

    /// What the method prepares once for every solve: the multigrid hierarchy (plain for an
    /// unshifted system, smoothed for a `shifted` one), the incomplete or the sparse Cholesky
    /// factor, or PETSc's solver.
    fn prepare(&self, shifted: bool) -> Result<Prepared, SolveError> {
        Ok(match self.params.method {
            Method::Cholesky => Prepared::Cholesky(cholesky::Factor::new(self)?),
            Method::AmgCg => {
                // One solve, or a few (steady, electric, homogenisation): plain aggregation and a
                // K-cycle, under a third of the setup, its finest level assembled straight into
                // the sliced layout. Shifted systems are implicit time steps, solved hundreds of
                // times: smoothed aggregation, the faster cycle.
                let (amg, nodes) = if shifted {
                    let (a0, nodes) = self.free_block();
                    (Amg::new(a0, Coarsening::Smoothed)?, nodes)
                } else {
                    let (a0, nodes) = self.free_block_sell();
                    let diag = nodes
                        .par_iter()
                        .with_min_len(CHUNK)
                        .map(|&p| self.diag[p as usize])
                        .collect();
                    (Amg::plain_from_sell(a0, diag)?, nodes)
                };
                // The setup's temporaries were freed in many sizes: hand what the allocator
                // keeps resident back to the system before the solve allocates its vectors.
                demcon_core::release_free_memory();
                Prepared::Amg(amg, nodes)
            }
            Method::IcCg => {
                let (mic, nodes) = self.incomplete_factor()?;
                Prepared::Mic(mic, nodes)
            }
            Method::Distributed => {
                let nodes: Vec<u32> = (0..self.free.len() as u32)
                    .filter(|&p| self.free[p as usize])
                    .collect();
                Prepared::Petsc(distributed::Solver::new(self, &nodes)?, nodes)
            }
            Method::Cg | Method::Auto => Prepared::Jacobi,
        })
    }

    /// Number of unknowns.
    pub fn n_unknowns(&self) -> usize {
        self.constraints.n_free()
    }

    /// The method this system runs ([`Method::Auto`] resolved).
    pub fn method(&self) -> Method {
        self.params.method
    }

    /// Shape of the multigrid hierarchy ([`Method::AmgCg`] only): levels, operator and grid
    /// complexity.
    pub fn amg_info(&self) -> Option<AmgInfo> {
        match &self.prepared {
            Prepared::Amg(a, _) => Some(a.info()),
            _ => None,
        }
    }

    /// [`Method::IcCg`]'s factor of the free block and the free nodes in unknown order
    /// (one sequential pass over the rows: cheaper than [`Self::free_block`] at the small
    /// sizes this method is for).
    fn incomplete_factor(&self) -> Result<(Mic, Vec<u32>), SolveError> {
        let n = self.net.n_nodes();
        let mut index = vec![u32::MAX; n];
        let mut nodes = Vec::with_capacity(self.constraints.n_free());
        for (p, &f) in self.free.iter().enumerate() {
            if f {
                index[p] = nodes.len() as u32;
                nodes.push(p as u32);
            }
        }
        let (row_ptr, cols) = (self.net.row_ptr(), self.net.cols());
        let index = &index;
        // Node order is kept, so the columns stay sorted.
        let rows = nodes.iter().map(|&p| {
            (row_ptr[p as usize]..row_ptr[p as usize + 1])
                .filter(move |&e| index[cols[e] as usize] != u32::MAX)
                .map(move |e| (index[cols[e] as usize] as usize, -self.entry_value(e)))
        });
        let diag = nodes.iter().map(|&p| self.diag[p as usize]).collect();
        Ok((Mic::from_rows(diag, rows, MIC_RELAXATION)?, nodes))
    }

    /// The free-node block of D + K in compressed rows (unknowns numbered in node order,
    /// parallel edges merged, diagonal stored) and the node of each unknown.
    fn free_block(&self) -> (Csr, Vec<u32>) {
        let rows = FreeRows::new(self);
        let n = rows.nodes.len();
        let a = Csr::from_row_lengths(n, n, || (), |_, k| rows.len(k), |_, k, c, v| rows.fill(k, c, v));
        (a, rows.nodes)
    }

    /// The same block assembled straight into the sliced layout ([`RowSell`]), for a
    /// plain-aggregation hierarchy.
    fn free_block_sell(&self) -> (RowSell, Vec<u32>) {
        let rows = FreeRows::new(self);
        let a = RowSell::from_rows(
            rows.nodes.len(),
            || (),
            |_, k| rows.len(k),
            |_, k, c, v| rows.fill(k, c, v),
        );
        (a, rows.nodes)
    }

    /// Wall time spent preparing (and factorising) the system (s).
    pub fn setup_s(&self) -> f64 {
        self.setup_s
    }

    /// Solves (D + K) x = b on the free nodes, x = fixed value on fixed nodes.
    ///
    /// `rhs`: b, one value per node (W or A injected; for an implicit step D·x_old + Q).
    /// Entries at fixed and excluded nodes are ignored. `x0`: optional initial guess (warm
    /// start for CG; ignored by Cholesky except at excluded nodes).
    ///
    /// Iterative methods stop when ‖b − Ax‖ ≤ rel_tol ‖b‖ on the true residual. A solve
    /// whose true residual stops decreasing ([`STAGNATION_WINDOW`] restarts without
    /// progress) or that runs out of iterations is accepted when its residual is within the
    /// round-off floor ([`SolveReport::attainable`] says so), and fails otherwise.
    ///
    /// # Errors
    /// Bad input, including |b_i| > [`MAX_RHS_ENTRY`] (b with the fixed values moved to it);
    /// [`SolveError::NotConverged`] (out of iterations) and [`SolveError::Stagnated`] above
    /// the round-off floor; [`SolveError::NonFinite`] when NaN or ∞ appears.
    pub fn solve(&self, rhs: &[f64], x0: Option<&[f64]>) -> Result<Solution, SolveError> {
        let start = Instant::now();
        let n = self.net.n_nodes();
        check_len("rhs", rhs.len(), n)?;
        check_finite("rhs", rhs)?;
        let mut x = match x0 {
            Some(v) => {
                check_len("x0", v.len(), n)?;
                check_finite("x0", v)?;
                v.to_vec()
            }
            None => vec![0.0; n],
        };
        self.constraints.impose(&mut x);
        // ‖b_eff‖: the residual with the free unknowns at zero.
        let mut r = self.lifted_rhs(rhs, &x);
        let b_norm = dot(&r, &r).sqrt();
        self.check_rhs(&r, b_norm)?;
        if x0.is_some() {
            // Residual at the initial guess.
            self.residual(rhs, &x, &mut r);
        }
        let (iterations, rel, attainable) = if b_norm == 0.0 {
            x.iter_mut()
                .zip(&self.free)
                .filter(|(_, f)| **f)
                .for_each(|(v, _)| *v = 0.0);
            (0, 0.0, None)
        } else {
            self.iterate(rhs, &mut x, &mut r, b_norm)?
        };
        if let Some(p) = x.iter().position(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                method: self.method().name(),
                iteration: iterations,
                what: if self.free[p] {
                    "solution value"
                } else {
                    "fixed value"
                },
                value: x[p],
            });
        }
        Ok(Solution {
            values: x,
            excluded: self.constraints.excluded().to_vec(),
            report: SolveReport {
                method: self.method().name(),
                iterations,
                relative_residual: rel,
                wall_s: start.elapsed().as_secs_f64(),
                setup_s: self.setup_s,
                n_unknowns: self.n_unknowns(),
                n_excluded: self.constraints.excluded().len(),
                attainable,
            },
        })
    }

    /// Refuses a right-hand side b_eff (in `r`, norm `b_norm`) that f64 cannot carry through
    /// CG: an entry above [`MAX_RHS_ENTRY`] or a non-finite norm.
    fn check_rhs(&self, r: &[f64], b_norm: f64) -> Result<(), SolveError> {
        let (p, big) =
            r.iter().enumerate().fold(
                (0, 0.0f64),
                |(p, m), (i, v)| if v.abs() > m { (i, v.abs()) } else { (p, m) },
            );
        if big > MAX_RHS_ENTRY || !b_norm.is_finite() {
            return Err(SolveError::invalid(
                format!("right-hand side at node {p} (source + Σ conductance × fixed value)"),
                format!("{:e}", r[p]),
                format!(
                    "|b| must be ≤ {MAX_RHS_ENTRY:e} (W or A) so that ‖b‖² stays finite; rescale the units of the sources, fixed values or conductances"
                ),
            ));
        }
        Ok(())
    }

    /// Round-off floor of the true relative residual at `x`: 8 ε ‖|b| + |A||x|‖₂/‖b‖ over
    /// the free rows (dimensionless).
    pub(crate) fn attainable(&self, b: &[f64], x: &[f64], b_norm: f64) -> f64 {
        let sq: f64 = (0..x.len())
            .filter(|&i| self.free[i])
            .map(|i| {
                let (lo, hi) = (self.net.row_ptr()[i], self.net.row_ptr()[i + 1]);
                let off: f64 = (lo..hi)
                    .map(|e| (self.entry_value(e) * x[self.net.cols()[e] as usize]).abs())
                    .sum();
                let t = b[i].abs() + (self.diag[i] * x[i]).abs() + off;
                t * t
            })
            .sum();
        ATTAINABLE_FACTOR * f64::EPSILON * sq.sqrt() / b_norm
    }

    /// b_eff = b − A x with the free unknowns at zero (x's values are read at the fixed nodes
    /// only), 0 off the free rows: b itself except on the rows next to a fixed node
    /// ([`Self::lift_rows`]), so only those are summed: Σ g_ij x_j over their fixed j, in
    /// the row's order.
    fn lifted_rhs(&self, b: &[f64], x: &[f64]) -> Vec<f64> {
        let mut r: Vec<f64> = b
            .par_iter()
            .zip(self.free.par_iter())
            .with_min_len(CHUNK)
            .map(|(&v, &f)| if f { v } else { 0.0 })
            .collect();
        let (row_ptr, cols, kinds) = (self.net.row_ptr(), self.net.cols(), self.constraints.kinds());
        for &i in &self.lift_rows {
            let i = i as usize;
            let lift: f64 = (row_ptr[i]..row_ptr[i + 1])
                .filter(|&e| kinds[cols[e] as usize] == NodeKind::Fixed)
                .map(|e| self.entry_value(e) * x[cols[e] as usize])
                .sum();
            r[i] = b[i] + lift;
        }
        r
    }

    /// r = b − A x on free rows (x holds fixed values at fixed nodes), 0 elsewhere.
    pub(crate) fn residual(&self, b: &[f64], x: &[f64], r: &mut [f64]) {
        chunks_map(r, |c, rc| {
            let base = c * CHUNK;
            for (k, ri) in rc.iter_mut().enumerate() {
                let i = base + k;
                *ri = if self.free[i] {
                    b[i] - self.row_apply(i, x)
                } else {
                    0.0
                };
            }
        });
    }

    /// The conductance of compressed-row entry e (W/K or S).
    #[inline]
    pub(crate) fn entry_value(&self, e: usize) -> f64 {
        match &self.values {
            EntryValues::Entries(v) => v[e],
            EntryValues::Edges(g) => g[self.net.entry_edges()[e] as usize],
        }
    }

    /// (A x)_i for one row.
    #[inline]
    pub(crate) fn row_apply(&self, i: usize, x: &[f64]) -> f64 {
        let (lo, hi) = (self.net.row_ptr()[i], self.net.row_ptr()[i + 1]);
        let cols = &self.net.cols()[lo..hi];
        let vals = match &self.values {
            EntryValues::Entries(v) => &v[lo..hi],
            EntryValues::Edges(g) => {
                // Entry k to partial sum k mod 4, as below: the same sums in the same order.
                let mut acc = [0.0f64; 4];
                for (k, (&q, &e)) in cols.iter().zip(&self.net.entry_edges()[lo..hi]).enumerate() {
                    acc[k % 4] += g[e as usize] * x[q as usize];
                }
                return self.diag[i] * x[i] - ((acc[0] + acc[1]) + (acc[2] + acc[3]));
            }
        };
        // Four independent partial sums: a row has ~7 entries, and one accumulator would
        // serialise them on the floating-point add latency. Fixed order: deterministic.
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
        self.diag[i] * x[i] - ((acc[0] + acc[1]) + (acc[2] + acc[3]))
    }

    /// q = A p on free rows (0 elsewhere); returns p·q. `p` must be 0 off the free nodes.
    pub(crate) fn apply_dot(&self, p: &[f64], q: &mut [f64]) -> f64 {
        let partials = chunks_map(q, |c, qc| {
            let base = c * CHUNK;
            let mut acc = 0.0;
            for (k, qi) in qc.iter_mut().enumerate() {
                let i = base + k;
                *qi = if self.free[i] {
                    let v = self.row_apply(i, p);
                    acc += v * p[i];
                    v
                } else {
                    0.0
                };
            }
            acc
        });
        ordered_sum(&partials)
    }

    /// Runs the prepared method from x, `r` = b − A x (norm of b: `b_norm`); returns the
    /// iterations, the true relative residual and the round-off floor when only that was met.
    fn iterate(
        &self,
        b: &[f64],
        x: &mut [f64],
        r: &mut [f64],
        b_norm: f64,
    ) -> Result<(usize, f64, Option<f64>), SolveError> {
        let stop = self.params.stop(b_norm);
        let abs_tol = stop.rel_tol * b_norm;
        match &self.prepared {
            Prepared::Cholesky(factor) => {
                factor.solve(self, r, x);
                self.residual(b, x, r);
                Ok((0, dot(r, r).sqrt() / b_norm, None))
            }
            Prepared::Jacobi => pcg::restart(self, b, x, r, stop, |x: &mut [f64], r: &mut [f64], _, left| {
                pcg::cg(&mut Jacobi::new(self), x, r, abs_tol, left)
            }),
            Prepared::Amg(amg, nodes) => {
                let inner = pcg::compact(nodes, |rc, _, left| amg::solve(amg, rc, abs_tol, left));
                pcg::restart(self, b, x, r, stop, inner)
            }
            Prepared::Mic(mic, nodes) => {
                // The inner solve measures its residual after the preconditioner, so it aims at
                // the true residual's required reduction and is restarted on the correction
                // (ten times deeper each time) until the true residual meets the tolerance.
                let mut depth = 1.0;
                let inner = pcg::compact(nodes, |rc, r_norm, left| {
                    let reduction = (depth * abs_tol / r_norm).min(0.5);
                    depth *= 0.1;
                    ic::solve(mic, rc, reduction, left)
                });
                pcg::restart(self, b, x, r, stop, inner)
            }
            Prepared::Petsc(solver, nodes) => {
                // PETSc's KSPCG + PCGAMG, asked for the reduction that meets the tolerance.
                // Every rank runs the same loop on the same gathered vectors, so every rank
                // takes the same decisions.
                let inner = pcg::compact(nodes, |rc, r_norm, left| solver.solve(rc, abs_tol / r_norm, left));
                pcg::restart(self, b, x, r, stop, inner)
            }
        }
    }
}

/// Jacobi-PCG on the whole network: q = A p over the free rows, z = D⁻¹ r made in the pass
/// that updates r.
struct Jacobi<'s, 'a> {
    sys: &'s LinearSystem<'a>,
    /// r·z of the last [`Krylov::descend`].
    rz: f64,
}

impl<'s, 'a> Jacobi<'s, 'a> {
    fn new(sys: &'s LinearSystem<'a>) -> Self {
        Self { sys, rz: 0.0 }
    }

    /// z = D⁻¹ r on free nodes; returns r·z.
    fn precondition_all(&self, r: &[f64], z: &mut [f64]) -> f64 {
        let partials = chunks_map(z, |c, zc| {
            let range = c * CHUNK..c * CHUNK + zc.len();
            let mut rz = 0.0;
            for ((zi, ri), di) in zc
                .iter_mut()
                .zip(&r[range.clone()])
                .zip(&self.sys.inv_diag[range])
            {
                *zi = ri * di;
                rz += ri * *zi;
            }
            rz
        });
        partials.iter().sum()
    }
}

impl Krylov for Jacobi<'_, '_> {
    fn name(&self) -> &'static str {
        Method::Cg.name()
    }

    fn apply_dot(&mut self, p: &[f64], q: &mut [f64]) -> f64 {
        self.sys.apply_dot(p, q)
    }

    /// r −= α q and z = D⁻¹ r in one pass.
    fn descend(&mut self, alpha: f64, q: &[f64], r: &mut [f64], z: &mut Vec<f64>) -> f64 {
        let inv_diag = &self.sys.inv_diag;
        let partials = chunks_map2(r, z, |c, rc, zc| {
            let range = c * CHUNK..c * CHUNK + rc.len();
            let (qc, dc) = (&q[range.clone()], &inv_diag[range]);
            let (mut rz, mut rr) = (0.0, 0.0);
            for k in 0..rc.len() {
                rc[k] -= alpha * qc[k];
                zc[k] = rc[k] * dc[k];
                rz += rc[k] * zc[k];
                rr += rc[k] * rc[k];
            }
            (rz, rr)
        });
        let (rz, rr) = partials.iter().fold((0.0, 0.0), |(a, b), (c, d)| (a + c, b + d));
        self.rz = rz;
        rr
    }

    fn precondition(&mut self, r: &[f64], z: &mut Vec<f64>, _q: Option<&[f64]>, descended: bool) -> [f64; 2] {
        if descended {
            [self.rz, 0.0]
        } else {
            [self.precondition_all(r, z), 0.0]
        }
    }
}

/// The rows of the free-node block of D + K: unknowns numbered in node order, parallel edges
/// merged, the diagonal stored, columns sorted.
struct FreeRows<'s, 'a> {
    sys: &'s LinearSystem<'a>,
    /// Unknown of each node (`u32::MAX`: not free).
    index: Vec<u32>,
    /// Node of each unknown.
    nodes: Vec<u32>,
}

impl<'s, 'a> FreeRows<'s, 'a> {
    fn new(sys: &'s LinearSystem<'a>) -> Self {
        let mut index = vec![u32::MAX; sys.net.n_nodes()];
        let mut nodes = Vec::with_capacity(sys.constraints.n_free());
        for (p, &f) in sys.free.iter().enumerate() {
            if f {
                index[p] = nodes.len() as u32;
                nodes.push(p as u32);
            }
        }
        Self { sys, index, nodes }
    }

    /// The free neighbours of node p in unknown numbering (sorted: node order is kept),
    /// with their entries; parallel edges are consecutive.
    fn free_entries(&self, p: usize) -> impl Iterator<Item = (u32, usize)> + '_ {
        let (row_ptr, cols) = (self.sys.net.row_ptr(), self.sys.net.cols());
        (row_ptr[p]..row_ptr[p + 1]).filter_map(move |e| {
            let j = self.index[cols[e] as usize];
            (j != u32::MAX).then_some((j, e))
        })
    }

    /// Entries of unknown k's row: its distinct free neighbours and the diagonal.
    fn len(&self, k: usize) -> usize {
        let mut last = u32::MAX;
        1 + self
            .free_entries(self.nodes[k] as usize)
            .filter(|&(j, _)| std::mem::replace(&mut last, j) != j)
            .count()
    }

    /// Writes unknown k's row ([`Self::len`] entries) in column order.
    fn fill(&self, k: usize, c: &mut [u32], v: &mut [f64]) {
        let p = self.nodes[k] as usize;
        let mut at = 0usize;
        let mut diag_done = false;
        for (j, e) in self.free_entries(p) {
            if !diag_done && j as usize > k {
                c[at] = k as u32;
                v[at] = self.sys.diag[p];
                at += 1;
                diag_done = true;
            }
            if at > 0 && c[at - 1] == j {
                v[at - 1] -= self.sys.entry_value(e);
            } else {
                c[at] = j;
                v[at] = -self.sys.entry_value(e);
                at += 1;
            }
        }
        if !diag_done {
            c[at] = k as u32;
            v[at] = self.sys.diag[p];
            at += 1;
        }
        debug_assert_eq!(at, c.len());
    }
}

/// Checks a system before it is prepared: the parameters, conductances, constraints and
/// shift, and that no kept floating cluster lacks a positive shift (singular system).
fn check_system(
    net: &Network,
    conductances: &[f64],
    shift: Option<&[f64]>,
    constraints: &Constraints,
    params: &SolveParams,
) -> Result<(), SolveError> {
    params.validate()?;
    net.check_conductances(conductances)?;
    check_len("constraints (nodes)", constraints.kinds().len(), net.n_nodes())?;
    if let Some(d) = shift {
        check_len("shift", d.len(), net.n_nodes())?;
        if let Some(p) = d.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(SolveError::invalid(
                format!("shift[{p}]"),
                d[p],
                "must be a finite number ≥ 0",
            ));
        }
    }
    let kept = constraints.floating_kept();
    let unanchored = match shift {
        None => kept.first().copied(),
        Some(d) => kept.iter().copied().find(|&p| d[p as usize] <= 0.0),
    };
    if let Some(example) = unanchored {
        let (clusters, largest) = constraints
            .diagnostics()
            .iter()
            .find_map(|d| match d {
                crate::Diagnostic::FloatingKept {
                    clusters, largest, ..
                } => Some((*clusters, *largest)),
                _ => None,
            })
            .unwrap_or((1, kept.len()));
        return Err(SolveError::FloatingCluster {
            clusters,
            nodes: kept.len(),
            largest,
            example,
        });
    }
    Ok(())
}

/// Steady solve of K x = s on the free nodes with the fixed values of `constraints`.
///
/// `sources`: imposed flow injected at each node (W or A; positive = into the network);
/// ignored at fixed and excluded nodes. Floating clusters must have been excluded (or
/// refused) by [`crate::resolve_fixed`].
///
/// # Errors
/// See [`LinearSystem::new`] and [`LinearSystem::solve`].
pub fn solve_steady(
    net: &Network,
    conductances: &[f64],
    constraints: &Constraints,
    sources: &[f64],
    params: &SolveParams,
) -> Result<Solution, SolveError> {
    let sys = LinearSystem::new(net, conductances, None, constraints, params)?;
    sys.solve(sources, None)
}

/// Shifted solve (D + K) x = b on the free nodes, e.g. one implicit time step with
/// D = C/Δt (W/K) and b = D x_old + Q (W). `x0` warm-starts CG.
///
/// # Errors
/// See [`LinearSystem::new`] and [`LinearSystem::solve`].
pub fn solve_shifted(
    net: &Network,
    conductances: &[f64],
    shift: &[f64],
    rhs: &[f64],
    constraints: &Constraints,
    x0: Option<&[f64]>,
    params: &SolveParams,
) -> Result<Solution, SolveError> {
    let sys = LinearSystem::new(net, conductances, Some(shift), constraints, params)?;
    sys.solve(rhs, x0)
}
