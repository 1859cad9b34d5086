//! The PETSc side of the distributed solve: session start and end, assembly of this rank's
//! rows into a MATMPIAIJ, KSPCG + PCGAMG set-up, solve, and the gather of the solution.
//! Every call's `PetscErrorCode` is checked and returned as [`SolveError::Petsc`].
#![allow(unsafe_code)]

use std::ffi::{CStr, c_int};
use std::ptr;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use super::ffi::{self, Ksp, Mat, PetscInt, Vec_, VecScatter};
use super::{partition, record};
use crate::error::SolveError;
use crate::solve::LinearSystem;

/// Set once a session was started in this process (PETSc cannot start twice).
static STARTED: AtomicBool = AtomicBool::new(false);

/// Turns a PETSc error code into our error, with PETSc's text for it.
fn check(code: ffi::PetscErrorCode, call: &'static str) -> Result<(), SolveError> {
    if code == 0 {
        return Ok(());
    }
    let mut text: *const std::ffi::c_char = ptr::null();
    // SAFETY: PetscErrorMessage writes a pointer to a static string (or leaves it null).
    let message = unsafe {
        if ffi::PetscErrorMessage(code, &mut text, ptr::null_mut()) == 0 && !text.is_null() {
            CStr::from_ptr(text).to_string_lossy().into_owned()
        } else {
            "unknown PETSc error".into()
        }
    };
    Err(SolveError::Petsc { call, code, message })
}

/// `PETSC_COMM_WORLD` (valid after `PetscInitialize`).
fn world() -> ffi::MpiComm {
    // SAFETY: a plain read of libpetsc's global, written only by PetscInitialize, which ran.
    unsafe { ffi::PETSC_COMM_WORLD }
}

/// Whether PETSc is initialised and not yet finalised.
fn running() -> bool {
    let (mut init, mut fin) = (0, 0);
    // SAFETY: both only write the flag.
    unsafe {
        ffi::PetscInitialized(&mut init) == 0 && ffi::PetscFinalized(&mut fin) == 0 && init != 0 && fin == 0
    }
}

/// `PetscInitialize` (options from `PETSC_OPTIONS`); returns (rank, size).
pub(super) fn initialize() -> Result<(usize, usize), SolveError> {
    if STARTED.swap(true, Ordering::SeqCst) {
        return Err(SolveError::DistributedUnavailable {
            why: "a PETSc session was already started in this process (one per process)".into(),
        });
    }
    // SAFETY: called once per process (guarded above), before any other PETSc call.
    check(unsafe { ffi::PetscInitializeNoArguments() }, "PetscInitialize")?;
    let (mut rank, mut size): (c_int, c_int) = (0, 0);
    // SAFETY: PETSc is initialised, so MPI is, and the world communicator is valid.
    unsafe {
        check(ffi::MPI_Comm_rank(world(), &mut rank), "MPI_Comm_rank")?;
        check(ffi::MPI_Comm_size(world(), &mut size), "MPI_Comm_size")?;
    }
    Ok((rank as usize, size as usize))
}

/// `PetscFinalize`, when running.
pub(super) fn finalize() {
    if running() {
        // SAFETY: every PETSc object of ours was destroyed with its system before this (the
        // session outlives them); a failure here has nobody left to report to.
        unsafe {
            ffi::PetscFinalize();
        }
    }
}

/// Resident memory of this process (bytes), by PETSc.
pub(super) fn memory_bytes() -> Option<f64> {
    let mut bytes = 0.0;
    // SAFETY: writes one double.
    (unsafe { ffi::PetscMemoryGetCurrentUsage(&mut bytes) } == 0 && bytes > 0.0).then_some(bytes)
}

/// `value` of every rank, in rank order, on every rank (collective).
pub(super) fn all_gather(value: f64) -> Result<Vec<f64>, SolveError> {
    let (mut v, mut all, mut sc): (Vec_, Vec_, VecScatter) =
        (ptr::null_mut(), ptr::null_mut(), ptr::null_mut());
    // SAFETY: one entry per rank; the three objects are destroyed below on every path.
    let result = unsafe {
        (|| {
            check(ffi::VecCreateMPI(world(), 1, -1, &mut v), "VecCreateMPI")?;
            let mut a: *mut f64 = ptr::null_mut();
            check(ffi::VecGetArray(v, &mut a), "VecGetArray")?;
            *a = value;
            check(ffi::VecRestoreArray(v, &mut a), "VecRestoreArray")?;
            check(
                ffi::VecScatterCreateToAll(v, &mut sc, &mut all),
                "VecScatterCreateToAll",
            )?;
            check(
                ffi::VecScatterBegin(sc, v, all, ffi::INSERT_VALUES, ffi::SCATTER_FORWARD),
                "VecScatterBegin",
            )?;
            check(
                ffi::VecScatterEnd(sc, v, all, ffi::INSERT_VALUES, ffi::SCATTER_FORWARD),
                "VecScatterEnd",
            )?;
            let mut size: c_int = 0;
            check(ffi::MPI_Comm_size(world(), &mut size), "MPI_Comm_size")?;
            let mut b: *const f64 = ptr::null();
            check(ffi::VecGetArrayRead(all, &mut b), "VecGetArrayRead")?;
            let out = std::slice::from_raw_parts(b, size.max(0) as usize).to_vec();
            check(ffi::VecRestoreArrayRead(all, &mut b), "VecRestoreArrayRead")?;
            Ok(out)
        })()
    };
    // SAFETY: created above or null (accepted by the Destroy functions).
    unsafe {
        ffi::VecScatterDestroy(&mut sc);
        ffi::VecDestroy(&mut all);
        ffi::VecDestroy(&mut v);
    }
    result
}

/// PETSc's objects of one system.
struct Handles {
    a: Mat,
    b: Vec_,
    x: Vec_,
    scatter: VecScatter,
    x_all: Vec_,
    ksp: Ksp,
}

// SAFETY: PETSc objects are not tied to the thread that created them; the Mutex around them
// in `Solver` keeps their use to one thread at a time.
unsafe impl Send for Handles {}

impl Drop for Handles {
    fn drop(&mut self) {
        if !running() {
            return;
        }
        // SAFETY: each handle was created by PETSc (or is null, which the Destroy functions
        // accept) and is destroyed once; every rank destroys the same objects in the same order.
        unsafe {
            ffi::KSPDestroy(&mut self.ksp);
            ffi::VecScatterDestroy(&mut self.scatter);
            ffi::VecDestroy(&mut self.x_all);
            ffi::VecDestroy(&mut self.x);
            ffi::VecDestroy(&mut self.b);
            ffi::MatDestroy(&mut self.a);
        }
    }
}

/// A [`LinearSystem`]'s free block distributed over the ranks, with its KSPCG + PCGAMG.
pub(crate) struct Solver {
    h: Mutex<Handles>,
    /// This rank's unknowns: `lo..hi`.
    lo: usize,
    hi: usize,
    n: usize,
}

impl std::fmt::Debug for Solver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("petsc::Solver")
            .field("rows", &(self.lo..self.hi))
            .field("n", &self.n)
            .finish()
    }
}

fn to_int(v: usize, what: &str) -> Result<PetscInt, SolveError> {
    PetscInt::try_from(v).map_err(|_| {
        SolveError::invalid(
            what,
            v,
            format!(
                "must fit PETSc's {}-bit PetscInt (a PETSc configured with --with-64-bit-indices lifts this)",
                8 * std::mem::size_of::<PetscInt>()
            ),
        )
    })
}

/// Writes row k of the free block: its columns and values (the diagonal among them).
type Row<'a> = dyn Fn(usize, &mut Vec<PetscInt>, &mut Vec<f64>) + 'a;

/// Preallocation of this rank's rows `rows` (`row(k, …)`): the entries per row in the
/// diagonal block and off it, and the number of distinct columns owned by other ranks.
fn preallocation(rows: std::ops::Range<usize>, row: &Row<'_>) -> (Vec<PetscInt>, Vec<PetscInt>, usize) {
    let (lo, hi) = (rows.start, rows.end);
    let (mut c, mut v) = (Vec::new(), Vec::new());
    let (mut d_nnz, mut o_nnz) = (Vec::with_capacity(hi - lo), Vec::with_capacity(hi - lo));
    // Columns owned by other ranks: the values each matrix product receives (the halo).
    let mut ghosts: Vec<PetscInt> = Vec::new();
    for k in rows {
        row(k, &mut c, &mut v);
        let d = c.iter().filter(|&&j| (lo..hi).contains(&(j as usize))).count();
        d_nnz.push(d as PetscInt);
        o_nnz.push((c.len() - d) as PetscInt);
        ghosts.extend(c.iter().filter(|&&j| !(lo..hi).contains(&(j as usize))));
    }
    ghosts.sort_unstable();
    ghosts.dedup();
    (d_nnz, o_nnz, ghosts.len())
}

/// Creates this rank's rows `rows` of the matrix (`m` local and `big_n` global rows,
/// preallocated by `nnz`: diagonal-block and off-block counts per row) from `row(k, columns,
/// values)`, and the right-hand side, solution and gathered vectors. Collective.
fn assemble(
    h: &mut Handles,
    (m, big_n): (PetscInt, PetscInt),
    rows: std::ops::Range<usize>,
    (d_nnz, o_nnz): (&[PetscInt], &[PetscInt]),
    row: &Row<'_>,
) -> Result<(), SolveError> {
    let (mut c, mut v) = (Vec::new(), Vec::new());
    // SAFETY: every pointer passed is to a live local or to a vector of the stated
    // length; the handles are created before use and destroyed by `Handles::drop`.
    unsafe {
        check(ffi::MatCreate(world(), &mut h.a), "MatCreate")?;
        check(ffi::MatSetSizes(h.a, m, m, big_n, big_n), "MatSetSizes")?;
        check(ffi::MatSetType(h.a, ffi::MATMPIAIJ.as_ptr()), "MatSetType")?;
        check(
            ffi::MatMPIAIJSetPreallocation(h.a, 0, d_nnz.as_ptr(), 0, o_nnz.as_ptr()),
            "MatMPIAIJSetPreallocation",
        )?;
        for k in rows {
            row(k, &mut c, &mut v);
            let gk = k as PetscInt;
            check(
                ffi::MatSetValues(
                    h.a,
                    1,
                    &gk,
                    c.len() as PetscInt,
                    c.as_ptr(),
                    v.as_ptr(),
                    ffi::INSERT_VALUES,
                ),
                "MatSetValues",
            )?;
        }
        check(
            ffi::MatAssemblyBegin(h.a, ffi::MAT_FINAL_ASSEMBLY),
            "MatAssemblyBegin",
        )?;
        check(
            ffi::MatAssemblyEnd(h.a, ffi::MAT_FINAL_ASSEMBLY),
            "MatAssemblyEnd",
        )?;
        check(
            ffi::MatSetOption(h.a, ffi::MAT_SYMMETRIC, ffi::PETSC_TRUE),
            "MatSetOption(MAT_SYMMETRIC)",
        )?;
        check(
            ffi::MatSetOption(h.a, ffi::MAT_SPD, ffi::PETSC_TRUE),
            "MatSetOption(MAT_SPD)",
        )?;
        check(ffi::VecCreateMPI(world(), m, big_n, &mut h.b), "VecCreateMPI")?;
        check(ffi::VecCreateMPI(world(), m, big_n, &mut h.x), "VecCreateMPI")?;
        check(
            ffi::VecScatterCreateToAll(h.x, &mut h.scatter, &mut h.x_all),
            "VecScatterCreateToAll",
        )?;
    }
    Ok(())
}

/// Creates and sets up KSPCG + PCGAMG on the assembled matrix of `h` (`PETSC_OPTIONS` may
/// change both); returns what runs, e.g. "cg + gamg". Collective.
fn set_up_ksp(h: &mut Handles) -> Result<String, SolveError> {
    // SAFETY: as above; the strings are NUL-terminated constants.
    unsafe {
        check(ffi::KSPCreate(world(), &mut h.ksp), "KSPCreate")?;
        check(ffi::KSPSetOperators(h.ksp, h.a, h.a), "KSPSetOperators")?;
        check(ffi::KSPSetType(h.ksp, ffi::KSPCG.as_ptr()), "KSPSetType(KSPCG)")?;
        let mut pc = ptr::null_mut();
        check(ffi::KSPGetPC(h.ksp, &mut pc), "KSPGetPC")?;
        check(ffi::PCSetType(pc, ffi::PCGAMG.as_ptr()), "PCSetType(PCGAMG)")?;
        check(
            ffi::KSPSetNormType(h.ksp, ffi::KSP_NORM_UNPRECONDITIONED),
            "KSPSetNormType(KSP_NORM_UNPRECONDITIONED)",
        )?;
        // `PETSC_OPTIONS` may still change the method (e.g. -pc_type hypre).
        check(ffi::KSPSetFromOptions(h.ksp), "KSPSetFromOptions")?;
        check(ffi::KSPSetUp(h.ksp), "KSPSetUp")?;
    }
    // What runs after the options: "cg + gamg" unless PETSC_OPTIONS changed it.
    let name = {
        let (mut k, mut p): (*const std::ffi::c_char, *const std::ffi::c_char) = (ptr::null(), ptr::null());
        let mut pc = ptr::null_mut();
        // SAFETY: the type names are PETSc's static strings (or null).
        unsafe {
            check(ffi::KSPGetType(h.ksp, &mut k), "KSPGetType")?;
            check(ffi::KSPGetPC(h.ksp, &mut pc), "KSPGetPC")?;
            check(ffi::PCGetType(pc, &mut p), "PCGetType")?;
            let name = |s: *const std::ffi::c_char| {
                if s.is_null() {
                    "?".to_string()
                } else {
                    CStr::from_ptr(s).to_string_lossy().into_owned()
                }
            };
            format!("{} + {}", name(k), name(p))
        }
    };
    Ok(name)
}

impl Solver {
    /// Assembles this rank's rows of the free block of `sys` (unknowns = `nodes`, in order)
    /// and sets up KSPCG + PCGAMG on it. Collective: every rank calls it with the same system.
    pub(crate) fn new(sys: &LinearSystem<'_>, nodes: &[u32]) -> Result<Self, SolveError> {
        if !running() {
            return Err(SolveError::DistributedUnavailable {
                why: "PETSc is not initialised: create a demcon_network::distributed::Session on every rank first (the CLI's --distributed does)"
                    .into(),
            });
        }
        let t0 = Instant::now();
        let n = nodes.len();
        let mut size: c_int = 0;
        // SAFETY: PETSc (hence MPI) is running.
        check(unsafe { ffi::MPI_Comm_size(world(), &mut size) }, "MPI_Comm_size")?;
        let mut rank: c_int = 0;
        // SAFETY: as above.
        check(unsafe { ffi::MPI_Comm_rank(world(), &mut rank) }, "MPI_Comm_rank")?;
        let (size, rank) = (size as usize, rank as usize);
        if size > n {
            return Err(SolveError::invalid(
                "MPI ranks",
                size,
                format!(
                    "must be at most the number of unknown rows ({n}): every rank needs rows of its own; launch fewer ranks"
                ),
            ));
        }
        let big_n = to_int(n, "unknowns")?;
        // Unknown numbering of every node (u32::MAX: not free).
        let mut index = vec![u32::MAX; sys.net.n_nodes()];
        for (k, &p) in nodes.iter().enumerate() {
            index[p as usize] = k as u32;
        }
        let (row_ptr, cols) = (sys.net.row_ptr(), sys.net.cols());
        // Row k of the free block: the diagonal and the distinct free neighbours (parallel
        // edges are consecutive in a row; columns ascend).
        let row = |k: usize, c: &mut Vec<PetscInt>, v: &mut Vec<f64>| {
            let p = nodes[k] as usize;
            c.clear();
            v.clear();
            let mut diag_done = false;
            for e in row_ptr[p]..row_ptr[p + 1] {
                let j = index[cols[e] as usize];
                if j == u32::MAX {
                    continue;
                }
                let j = j as usize;
                if !diag_done && j > k {
                    c.push(k as PetscInt);
                    v.push(sys.diag[p]);
                    diag_done = true;
                }
                if c.last() == Some(&(j as PetscInt)) {
                    if let Some(last) = v.last_mut() {
                        *last -= sys.entry_value(e);
                    }
                } else {
                    c.push(j as PetscInt);
                    v.push(-sys.entry_value(e));
                }
            }
            if !diag_done {
                c.push(k as PetscInt);
                v.push(sys.diag[p]);
            }
        };
        // Nonzeros per row, for the partition (every rank computes the same).
        let row_nnz: Vec<usize> = (0..n)
            .map(|k| {
                let p = nodes[k] as usize;
                let mut last = u32::MAX;
                1 + (row_ptr[p]..row_ptr[p + 1])
                    .map(|e| index[cols[e] as usize])
                    .filter(|&j| j != u32::MAX && std::mem::replace(&mut last, j) != j)
                    .count()
            })
            .collect();
        let bounds = partition(&row_nnz, size);
        drop(row_nnz);
        let (lo, hi) = (bounds[rank], bounds[rank + 1]);
        let m = to_int(hi - lo, "rows of a rank")?;
        let (d_nnz, o_nnz, n_ghosts) = preallocation(lo..hi, &row);
        let mut h = Handles {
            a: ptr::null_mut(),
            b: ptr::null_mut(),
            x: ptr::null_mut(),
            scatter: ptr::null_mut(),
            x_all: ptr::null_mut(),
            ksp: ptr::null_mut(),
        };
        assemble(&mut h, (m, big_n), lo..hi, (&d_nnz, &o_nnz), &row)?;
        drop((d_nnz, o_nnz, index));
        let assembly_s = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let solver = set_up_ksp(&mut h)?;
        let setup_s = t1.elapsed().as_secs_f64();
        record(|s| {
            s.systems += 1;
            s.solver = solver;
            s.assembly_s += assembly_s;
            s.setup_s += setup_s;
            if n >= s.max_unknowns {
                s.max_unknowns = n;
                let sizes = bounds.windows(2).map(|w| w[1] - w[0]);
                s.rows_per_rank = (sizes.clone().min().unwrap_or(0), sizes.max().unwrap_or(0));
                s.ghosts = n_ghosts;
            }
        });
        Ok(Self {
            h: Mutex::new(h),
            lo,
            hi,
            n,
        })
    }

    /// Solves A δ = `rc` (the whole compact right-hand side, the same on every rank) from
    /// δ = 0 until ‖rc − Aδ‖ ≤ `rtol` ‖rc‖, in at most `max_iter` iterations; returns δ on
    /// every rank and the iterations. Running out of iterations is not an error here (the
    /// caller's restart loop judges the true residual); a breakdown is.
    pub(crate) fn solve(
        &self,
        rc: &[f64],
        rtol: f64,
        max_iter: usize,
    ) -> Result<(Vec<f64>, usize), SolveError> {
        if rc.len() != self.n {
            return Err(SolveError::LengthMismatch {
                what: "distributed right-hand side".into(),
                expected: self.n,
                got: rc.len(),
            });
        }
        let h = match self.h.lock() {
            Ok(h) => h,
            Err(p) => p.into_inner(),
        };
        let maxits = to_int(max_iter.min(i32::MAX as usize), "max_iter")?;
        let t0 = Instant::now();
        let own = &rc[self.lo..self.hi];
        // SAFETY: VecGetArray hands out this rank's `hi − lo` entries until VecRestoreArray.
        unsafe {
            let mut a: *mut f64 = ptr::null_mut();
            check(ffi::VecGetArray(h.b, &mut a), "VecGetArray")?;
            if !own.is_empty() {
                std::slice::from_raw_parts_mut(a, own.len()).copy_from_slice(own);
            }
            check(ffi::VecRestoreArray(h.b, &mut a), "VecRestoreArray")?;
            check(ffi::VecSet(h.x, 0.0), "VecSet")?;
        }
        let mut gather_s = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let (mut reason, mut its): (c_int, PetscInt) = (0, 0);
        // SAFETY: live handles; scalars written by PETSc.
        unsafe {
            check(
                ffi::KSPSetTolerances(
                    h.ksp,
                    rtol.clamp(1e-300, 1.0),
                    0.0,
                    ffi::PETSC_DEFAULT_REAL,
                    maxits.max(1),
                ),
                "KSPSetTolerances",
            )?;
            check(ffi::KSPSolve(h.ksp, h.b, h.x), "KSPSolve")?;
            check(
                ffi::KSPGetConvergedReason(h.ksp, &mut reason),
                "KSPGetConvergedReason",
            )?;
            check(
                ffi::KSPGetIterationNumber(h.ksp, &mut its),
                "KSPGetIterationNumber",
            )?;
        }
        let solve_s = t1.elapsed().as_secs_f64();
        let iterations = its.max(0) as usize;
        if reason < 0 && reason != ffi::KSP_DIVERGED_ITS {
            let mut rnorm = f64::NAN;
            // SAFETY: writes one double.
            unsafe { ffi::KSPGetResidualNorm(h.ksp, &mut rnorm) };
            if reason == ffi::KSP_DIVERGED_NANORINF {
                return Err(SolveError::NonFinite {
                    method: super::METHOD,
                    iteration: iterations,
                    what: "KSP residual norm",
                    value: rnorm,
                });
            }
            return Err(SolveError::Breakdown {
                method: super::METHOD,
                iteration: iterations,
                detail: format!(
                    "KSPConvergedReason {reason} ({}), residual norm {rnorm:.3e}",
                    reason_name(reason)
                ),
            });
        }
        let t2 = Instant::now();
        let mut delta = vec![0.0; self.n];
        // SAFETY: the scattered copy holds all n entries on every rank until restored.
        unsafe {
            check(
                ffi::VecScatterBegin(h.scatter, h.x, h.x_all, ffi::INSERT_VALUES, ffi::SCATTER_FORWARD),
                "VecScatterBegin",
            )?;
            check(
                ffi::VecScatterEnd(h.scatter, h.x, h.x_all, ffi::INSERT_VALUES, ffi::SCATTER_FORWARD),
                "VecScatterEnd",
            )?;
            let mut a: *const f64 = ptr::null();
            check(ffi::VecGetArrayRead(h.x_all, &mut a), "VecGetArrayRead")?;
            if self.n > 0 {
                delta.copy_from_slice(std::slice::from_raw_parts(a, self.n));
            }
            check(ffi::VecRestoreArrayRead(h.x_all, &mut a), "VecRestoreArrayRead")?;
        }
        gather_s += t2.elapsed().as_secs_f64();
        record(|s| {
            s.ksp_solves += 1;
            s.iterations += iterations;
            s.solve_s += solve_s;
            s.gather_s += gather_s;
        });
        Ok((delta, iterations))
    }
}

/// PETSc's name of a negative `KSPConvergedReason`.
fn reason_name(reason: c_int) -> &'static str {
    match reason {
        -2 => "KSP_DIVERGED_NULL",
        -3 => "KSP_DIVERGED_ITS",
        -4 => "KSP_DIVERGED_DTOL",
        -5 => "KSP_DIVERGED_BREAKDOWN",
        -6 => "KSP_DIVERGED_BREAKDOWN_BICG",
        -7 => "KSP_DIVERGED_NONSYMMETRIC",
        -8 => "KSP_DIVERGED_INDEFINITE_PC",
        -9 => "KSP_DIVERGED_NANORINF",
        -10 => "KSP_DIVERGED_INDEFINITE_MAT",
        -11 => "KSP_DIVERGED_PC_FAILED",
        _ => "unknown",
    }
}
