//! The network's linear systems solved by PETSc over MPI ([`crate::Method::Distributed`]):
//! conjugate gradient preconditioned by PETSc's smoothed-aggregation algebraic multigrid
//! (KSPCG + PCGAMG) on a row-distributed matrix (MATMPIAIJ), behind the `petsc` cargo
//! feature.
//!
//! # Design
//! - **Every rank holds the whole model.** Each MPI rank runs the same pipeline (scene,
//!   packing, contacts, conductances, constraints) and builds the same [`crate::LinearSystem`];
//!   only the solve is distributed. So the geometry's memory is not distributed yet: the
//!   matrix, the multigrid hierarchy and the Krylov vectors are (see `docs/distributed.md`).
//! - **Partition.** The unknowns (free nodes, numbered in node order: the packings are
//!   Morton-sorted, so a contiguous range is a compact block of space) are cut into one
//!   contiguous range per rank, balanced by nonzeros ([`partition`]); each rank inserts only
//!   its own rows of the reduced system (fixed values eliminated as in the serial path).
//! - **Same stopping rule as the serial path.** KSP measures the unpreconditioned residual
//!   (`KSP_NORM_UNPRECONDITIONED`) and is asked for the reduction that brings the true
//!   residual to ‖b − Ax‖ ≤ rel_tol ‖b‖; after each KSP solve the correction is gathered to
//!   every rank, the true residual is recomputed on the whole network, and the solve is
//!   restarted from it when it is not yet met — the restart loop of [`crate::Method::AmgCg`].
//!   Every rank thus ends with the same solution and the same report, so the rest of the
//!   pipeline (flows, post-processing) continues identically on all of them.
//! - **Set-up once, solve many times.** The matrix is assembled and the KSP (with the GAMG
//!   hierarchy) set up in [`crate::LinearSystem::new`]; every [`crate::LinearSystem::solve`]
//!   (each implicit step of one Δt, each ρ_e(T) iteration's right-hand side) reuses them.
//! - **A thin hand-written FFI** (`ffi.rs`, about 40 functions) rather than bindgen: no
//!   libclang at build time, and the two build-dependent C types (`PetscInt`, `MPI_Comm`)
//!   are read from the installed headers by `build.rs`. Every `PetscErrorCode` becomes a
//!   [`SolveError::Petsc`]; nothing panics on a PETSc failure.
//!
//! Without the feature, [`Session::init`] and any distributed system fail with
//! [`SolveError::DistributedUnavailable`], which names the build command.

use std::sync::Mutex;

use crate::error::SolveError;

#[cfg(feature = "petsc")]
mod ffi;
#[cfg(feature = "petsc")]
mod petsc;

#[cfg(feature = "petsc")]
pub(crate) use petsc::Solver;

/// Name of [`crate::Method::Distributed`] in reports.
pub const METHOD: &str = "petsc-cg-gamg";

/// Whether this build has the distributed solve (the `petsc` feature).
pub const AVAILABLE: bool = cfg!(feature = "petsc");

/// The message of [`SolveError::DistributedUnavailable`] without the feature.
#[cfg(not(feature = "petsc"))]
fn unavailable() -> SolveError {
    SolveError::DistributedUnavailable {
        why: "this demcon was built without PETSc; rebuild with `cargo build --release -p demcon --features petsc` \
              (needs `apt-get install petsc-dev openmpi-bin`), or run without --distributed"
            .into(),
    }
}

/// This process's MPI/PETSc session: `PetscInitialize` on [`Session::init`], `PetscFinalize`
/// when dropped. Create one before the first distributed system and keep it alive until the
/// last is dropped; at most one per process (PETSc cannot be initialised twice).
#[derive(Debug)]
pub struct Session {
    rank: usize,
    size: usize,
}

impl Session {
    /// Initialises PETSc (and MPI) on `PETSC_COMM_WORLD`. Run as a plain process (not under
    /// `mpirun`) it is a world of one rank.
    ///
    /// # Errors
    /// [`SolveError::DistributedUnavailable`] without the `petsc` feature or when a session
    /// was already created in this process; [`SolveError::Petsc`] when PETSc fails to start.
    pub fn init() -> Result<Session, SolveError> {
        #[cfg(feature = "petsc")]
        {
            let (rank, size) = petsc::initialize()?;
            record(|s| s.ranks = size);
            Ok(Session { rank, size })
        }
        #[cfg(not(feature = "petsc"))]
        Err(unavailable())
    }

    /// This process's rank in `PETSC_COMM_WORLD` (0-based).
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// Number of ranks.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Gathers every rank's peak resident memory (`bytes` of this rank) to every rank, in
    /// rank order, and records the smallest and largest in [`stats`]. Collective: every rank
    /// calls it once, at the same point.
    ///
    /// # Errors
    /// [`SolveError::Petsc`] when the exchange fails.
    pub fn gather_peak_memory(&self, bytes: f64) -> Result<Vec<f64>, SolveError> {
        #[cfg(feature = "petsc")]
        {
            let all = petsc::all_gather(&[bytes])?;
            let lo = all.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = all.iter().copied().fold(0.0, f64::max);
            record(|s| s.peak_rss_bytes = (lo, hi));
            Ok(all)
        }
        #[cfg(not(feature = "petsc"))]
        {
            let _ = bytes;
            Err(unavailable())
        }
    }

    /// Every rank's `values` (the same count on each), concatenated in rank order, on every
    /// rank. Collective.
    ///
    /// # Errors
    /// [`SolveError::Petsc`] when the exchange fails.
    pub fn all_gather(&self, values: &[f64]) -> Result<Vec<f64>, SolveError> {
        #[cfg(feature = "petsc")]
        {
            petsc::all_gather(values)
        }
        #[cfg(not(feature = "petsc"))]
        {
            let _ = values;
            Err(unavailable())
        }
    }

    /// The sums over the ranks of `values` (the same count on each), added in rank order so
    /// that every rank gets the same bits whatever the timing. Collective.
    ///
    /// # Errors
    /// [`SolveError::Petsc`] when the exchange fails.
    pub fn sum(&self, values: &[f64]) -> Result<Vec<f64>, SolveError> {
        let all = self.all_gather(values)?;
        let m = values.len();
        let mut out = vec![0.0; m];
        for part in all.chunks(m.max(1)) {
            for (o, v) in out.iter_mut().zip(part) {
                *o += v;
            }
        }
        Ok(out)
    }

    /// Resident memory of this process now (bytes), as PETSc measures it; `None` when it
    /// cannot tell.
    pub fn memory_bytes(&self) -> Option<f64> {
        #[cfg(feature = "petsc")]
        {
            petsc::memory_bytes()
        }
        #[cfg(not(feature = "petsc"))]
        None
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        #[cfg(feature = "petsc")]
        petsc::finalize();
    }
}

/// The ghost exchange of a vector laid out by blocks: rank r owns a run of consecutive global
/// entries (ranks in order) and reads the entries of other ranks at its ghosts' global indices.
/// Made once per layout (a PETSc scatter), used for every vector laid out so.
pub struct Halo {
    #[cfg(feature = "petsc")]
    inner: petsc::Exchange,
}

impl std::fmt::Debug for Halo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Halo")
    }
}

impl Halo {
    /// This rank owns `owned` entries and reads `ghosts` (global indices). Collective.
    ///
    /// # Errors
    /// Without the feature; an index past PETSc's `PetscInt`; PETSc's failures (an index past
    /// the global length among them).
    pub fn new(_session: &Session, owned: usize, ghosts: &[usize]) -> Result<Self, SolveError> {
        #[cfg(feature = "petsc")]
        {
            Ok(Self {
                inner: petsc::Exchange::new(owned, ghosts)?,
            })
        }
        #[cfg(not(feature = "petsc"))]
        {
            let _ = (owned, ghosts);
            Err(unavailable())
        }
    }

    /// The ghosts' values (in the order given to [`Halo::new`]) of the vector whose owned
    /// entries on this rank are `owned`. Collective.
    ///
    /// # Errors
    /// `owned` of the wrong length; PETSc's failures.
    pub fn exchange(&self, owned: &[f64]) -> Result<Vec<f64>, SolveError> {
        #[cfg(feature = "petsc")]
        {
            self.inner.exchange(owned)
        }
        #[cfg(not(feature = "petsc"))]
        {
            let _ = owned;
            Err(unavailable())
        }
    }
}

/// A symmetric positive definite system assembled by blocks: each rank gives its own rows
/// (consecutive global rows, ranks in order) with the global indices of their columns, and
/// gets back its own part of the solution; no rank holds the whole system or solution
/// (KSPCG + PCGAMG, the true residual ‖b − A x‖ ≤ rel_tol ‖b‖ by PETSc's product).
pub struct BlockSystem {
    #[cfg(feature = "petsc")]
    inner: petsc::BlockSolver,
}

impl std::fmt::Debug for BlockSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("BlockSystem")
    }
}

/// Writes global row k of a [`BlockSystem`]: its columns' global indices and their values
/// (both cleared first; the diagonal among them, each column once).
pub type BlockRow<'a> = dyn Fn(usize, &mut Vec<i64>, &mut Vec<f64>) + 'a;

/// What [`BlockSystem::solve`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockSolveReport {
    /// CG iterations over all KSP solves.
    pub iterations: usize,
    /// KSP solves (restarts from the true residual count).
    pub ksp_solves: usize,
    /// The true relative residual reached, ‖b − A x‖ / ‖b‖.
    pub relative_residual: f64,
}

impl BlockSystem {
    /// Assembles this rank's rows `first..first + rows` of a `total`-row system and sets up
    /// the solver; `row(k, columns, values)` writes global row k (clearing both vectors first:
    /// the diagonal among the columns, each column once). Collective.
    ///
    /// # Errors
    /// Without the feature; sizes past `PetscInt`; PETSc's failures.
    pub fn new(
        _session: &Session,
        first: usize,
        rows: usize,
        total: usize,
        row: &BlockRow<'_>,
    ) -> Result<Self, SolveError> {
        #[cfg(feature = "petsc")]
        {
            Ok(Self {
                inner: petsc::BlockSolver::new(first, rows, total, row)?,
            })
        }
        #[cfg(not(feature = "petsc"))]
        {
            let _ = (first, rows, total, row);
            Err(unavailable())
        }
    }

    /// Solves A x = b (`b` and the x returned: this rank's rows) to `rel_tol` in at most
    /// `max_iter` CG iterations. Collective.
    ///
    /// # Errors
    /// [`SolveError::NotConverged`]; PETSc's failures.
    pub fn solve(
        &self,
        b: &[f64],
        rel_tol: f64,
        max_iter: usize,
    ) -> Result<(Vec<f64>, BlockSolveReport), SolveError> {
        #[cfg(feature = "petsc")]
        {
            let (x, d) = self.inner.solve(b, rel_tol, max_iter)?;
            Ok((
                x,
                BlockSolveReport {
                    iterations: d.iterations,
                    ksp_solves: d.ksp_solves,
                    relative_residual: d.rel_residual,
                },
            ))
        }
        #[cfg(not(feature = "petsc"))]
        {
            let _ = (b, rel_tol, max_iter);
            Err(unavailable())
        }
    }
}

/// What the distributed solves of this process cost so far (every rank counts its own; the
/// iteration counts are the same on every rank).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DistributedStats {
    /// Ranks of the session (0 before [`Session::init`]).
    pub ranks: usize,
    /// PETSc's Krylov method and preconditioner of the last system, as set up (`"cg + gamg"`
    /// unless `PETSC_OPTIONS` changed them, e.g. `-pc_type hypre`).
    pub solver: String,
    /// Distributed systems set up (one per steady solve, per Δt of an implicit run, per
    /// ρ_e(T) re-solve).
    pub systems: usize,
    /// KSP solves (a restart from the true residual counts as one more).
    pub ksp_solves: usize,
    /// CG iterations over all KSP solves.
    pub iterations: usize,
    /// Wall time building this rank's rows and assembling the MATMPIAIJ (s).
    pub assembly_s: f64,
    /// Wall time of the KSP set-up, the GAMG hierarchy included (s).
    pub setup_s: f64,
    /// Wall time inside KSPSolve (s).
    pub solve_s: f64,
    /// Wall time scattering the right-hand side in and gathering the solution to every rank (s).
    pub gather_s: f64,
    /// Unknowns of the largest system.
    pub max_unknowns: usize,
    /// Fewest and most rows one rank owned in the largest system.
    pub rows_per_rank: (usize, usize),
    /// Unknowns owned by other ranks that this rank's rows of the largest system read (the
    /// halo each matrix product receives: 8 bytes each).
    pub ghosts: usize,
    /// Smallest and largest peak resident memory over the ranks (bytes), once
    /// [`Session::gather_peak_memory`] ran; (0, 0) before.
    pub peak_rss_bytes: (f64, f64),
}

static STATS: Mutex<DistributedStats> = Mutex::new(DistributedStats {
    ranks: 0,
    solver: String::new(),
    systems: 0,
    ksp_solves: 0,
    iterations: 0,
    assembly_s: 0.0,
    setup_s: 0.0,
    solve_s: 0.0,
    gather_s: 0.0,
    max_unknowns: 0,
    rows_per_rank: (0, 0),
    ghosts: 0,
    peak_rss_bytes: (0.0, 0.0),
});

/// The totals of this process's distributed solves so far.
pub fn stats() -> DistributedStats {
    match STATS.lock() {
        Ok(s) => s.clone(),
        Err(p) => p.into_inner().clone(),
    }
}

/// Adds to the totals.
#[cfg_attr(not(feature = "petsc"), allow(dead_code))]
pub(crate) fn record(f: impl FnOnce(&mut DistributedStats)) {
    match STATS.lock() {
        Ok(mut s) => f(&mut s),
        Err(p) => f(&mut p.into_inner()),
    }
}

/// Cuts rows `0..row_nnz.len()` into `ranks` contiguous ranges of about equal nonzeros;
/// returns the `ranks + 1` boundaries (first 0, last the number of rows). Every range holds at
/// least one row when `ranks ≤ rows`.
pub fn partition(row_nnz: &[usize], ranks: usize) -> Vec<usize> {
    let n = row_nnz.len();
    let ranks = ranks.max(1);
    let total: usize = row_nnz.iter().sum();
    let mut bounds = Vec::with_capacity(ranks + 1);
    bounds.push(0);
    let (mut row, mut prefix) = (0usize, 0usize);
    for r in 1..ranks {
        // The first row whose prefix of nonzeros reaches r/ranks of the total (u128: no
        // overflow of prefix × ranks).
        while row < n && (prefix as u128) * (ranks as u128) < (r as u128) * (total as u128) {
            prefix += row_nnz[row];
            row += 1;
        }
        let prev = bounds[r - 1];
        // At least one row for this range and for each one after it.
        let b = row.max(prev + 1).min(n.saturating_sub(ranks - r)).max(prev);
        bounds.push(b);
    }
    bounds.push(n);
    bounds
}

/// Stand-in for the PETSc solver in a build without the feature: setting it up fails.
#[cfg(not(feature = "petsc"))]
#[derive(Debug)]
pub(crate) struct Solver;

#[cfg(not(feature = "petsc"))]
impl Solver {
    pub(crate) fn new(_sys: &crate::LinearSystem<'_>, _nodes: &[u32]) -> Result<Self, SolveError> {
        Err(unavailable())
    }

    pub(crate) fn solve(
        &self,
        _rc: &[f64],
        _rtol: f64,
        _max_iter: usize,
    ) -> Result<(Vec<f64>, usize), SolveError> {
        Err(unavailable())
    }
}

#[cfg(test)]
mod tests {
    use super::partition;

    #[test]
    fn partition_balances_nonzeros_and_covers_rows() {
        // Rows of 1 and 9 nonzeros alternate: 50 rows, 250 nonzeros.
        let nnz: Vec<usize> = (0..50).map(|i| if i % 2 == 0 { 1 } else { 9 }).collect();
        let b = partition(&nnz, 4);
        assert_eq!(b.len(), 5);
        assert_eq!((b[0], b[4]), (0, 50));
        for r in 0..4 {
            let part: usize = nnz[b[r]..b[r + 1]].iter().sum();
            assert!((part as f64 - 62.5).abs() <= 9.0, "range {r}: {part} nonzeros");
        }
    }

    #[test]
    fn partition_gives_every_rank_a_row() {
        // One heavy row first: a pure nonzero split would leave ranks empty.
        let mut nnz = vec![1usize; 4];
        nnz[0] = 1000;
        let b = partition(&nnz, 4);
        assert_eq!(b, vec![0, 1, 2, 3, 4]);
        assert_eq!(partition(&[3, 3], 1), vec![0, 2]);
    }

    /// Without the feature the method is refused with the build command, not a panic.
    #[cfg(not(feature = "petsc"))]
    #[test]
    fn without_the_feature_the_method_names_the_build_command() {
        use crate::{FloatingPolicy, LinearSystem, Method, Network, SolveError, SolveParams, resolve_fixed};
        let net = Network::new(3, &[[0, 1], [1, 2]]).unwrap();
        let bcs = resolve_fixed(&net, &[(vec![0], 0.0), (vec![2], 1.0)], FloatingPolicy::Fail).unwrap();
        let params = SolveParams::new(Method::Distributed, 1e-8, 10);
        let err = LinearSystem::new(&net, &[1.0, 1.0], None, &bcs, &params).unwrap_err();
        assert!(
            matches!(&err, SolveError::DistributedUnavailable { why } if why.contains("--features petsc")),
            "{err}"
        );
        assert!(matches!(
            super::Session::init(),
            Err(SolveError::DistributedUnavailable { .. })
        ));
    }
}
