//! The launch rules of `demcon run --distributed` (docs/distributed.md): what the MPI launcher
//! says about this process, the thread count per rank, and which rank prints errors.
//!
//! Rules: `--distributed` needs a demcon built with `--features petsc`; run as a plain
//! process it is a world of one rank (the same result as the serial solve); under `mpirun
//! -n K` PETSc's world must have the K processes the launcher started (else the binary's MPI
//! is not the launcher's); `mpirun -n K` with K > 1 without `--distributed` is refused (every
//! process would run the whole scene and write the same folder).

use std::sync::atomic::{AtomicBool, Ordering};

/// Set on ranks other than 0: their errors are not printed (rank 0 prints the same one).
static SILENT: AtomicBool = AtomicBool::new(false);

/// Whether this process's errors stay unprinted.
pub(crate) fn silent() -> bool {
    SILENT.load(Ordering::Relaxed)
}

/// Marks this process as a rank other than 0 (`true`) or rank 0.
pub(crate) fn set_silent(silent: bool) {
    SILENT.store(silent, Ordering::Relaxed);
}

/// Set once a failed run's error has been handled ([`first_report`]).
static REPORTED: AtomicBool = AtomicBool::new(false);

/// `true` the first time only: a failed run's error is printed once.
pub(crate) fn first_report() -> bool {
    !REPORTED.swap(true, Ordering::Relaxed)
}

/// How long a rank other than 0 waits before it exits with an error. The ranks of a
/// distributed run fail alike, and mpirun aborts the whole job at the first non-zero exit:
/// rank 0 must have printed the reason by then. Inside the PETSc session MPI_Finalize
/// already orders them (rank 0 prints first); before it (a refused launch) this wait does.
/// Rank 0's own exit ends the wait (mpirun stops the job); a rank still alive after it
/// failed alone and prints its own error, naming its rank.
pub(crate) const LINGER: std::time::Duration = std::time::Duration::from_secs(2);

/// What the MPI launcher told this process through its environment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Launch {
    /// This process's rank.
    pub rank: usize,
    /// Processes started.
    pub size: usize,
    /// Processes started on this machine.
    pub local_size: usize,
}

/// The launcher's view: Open MPI (`OMPI_COMM_WORLD_*`), MPICH/Hydra (`PMI_*`) or PMIx
/// (`PMIX_RANK`); `None` when not launched by one.
pub(crate) fn launch() -> Option<Launch> {
    let var = |k: &str| std::env::var(k).ok().and_then(|v| v.trim().parse::<usize>().ok());
    let (rank, size) = [
        ("OMPI_COMM_WORLD_RANK", "OMPI_COMM_WORLD_SIZE"),
        ("PMI_RANK", "PMI_SIZE"),
    ]
    .iter()
    .find_map(|(r, s)| Some((var(r)?, var(s)?)))?;
    let local_size = var("OMPI_COMM_WORLD_LOCAL_SIZE")
        .or_else(|| var("MPI_LOCALNRANKS"))
        .unwrap_or(size)
        .max(1);
    Some(Launch {
        rank,
        size,
        local_size,
    })
}

/// Worker threads per rank when `--threads` is not given: the cores shared by the ranks of
/// this machine (at least 1), so K ranks on C cores do not run K × C threads.
pub(crate) fn threads_per_rank(local_ranks: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    (cores / local_ranks.max(1)).max(1)
}
