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

/// `values` of every rank (the same count on each), concatenated in rank order, on every rank
/// (collective).
pub(super) fn all_gather(values: &[f64]) -> Result<Vec<f64>, SolveError> {
    let m = to_int(values.len(), "values gathered per rank")?;
    let (mut v, mut all, mut sc): (Vec_, Vec_, VecScatter) =
        (ptr::null_mut(), ptr::null_mut(), ptr::null_mut());
    // SAFETY: `m` entries per rank; the three objects are destroyed below on every path.
    let result = unsafe {
        (|| {
            check(ffi::VecCreateMPI(world(), m, -1, &mut v), "VecCreateMPI")?;
            write_local(v, values)?;
            check(
                ffi::VecScatterCreateToAll(v, &mut sc, &mut all),
                "VecScatterCreateToAll",
            )?;
            scatter(sc, v, all)?;
            let mut size: c_int = 0;
            check(ffi::MPI_Comm_size(world(), &mut size), "MPI_Comm_size")?;
            read_local(all, size.max(0) as usize * values.len())
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

/// Copies `values` into this rank's entries of `v` (exactly that many).
///
/// # Safety
/// `v` is a live vector with `values.len()` local entries.
unsafe fn write_local(v: Vec_, values: &[f64]) -> Result<(), SolveError> {
    let mut a: *mut f64 = ptr::null_mut();
    // SAFETY: VecGetArray hands out the local entries until VecRestoreArray.
    unsafe {
        check(ffi::VecGetArray(v, &mut a), "VecGetArray")?;
        if !values.is_empty() {
            std::slice::from_raw_parts_mut(a, values.len()).copy_from_slice(values);
        }
        check(ffi::VecRestoreArray(v, &mut a), "VecRestoreArray")
    }
}

/// This rank's `n` entries of `v`.
///
/// # Safety
/// `v` is a live vector with `n` local entries.
unsafe fn read_local(v: Vec_, n: usize) -> Result<Vec<f64>, SolveError> {
    let mut a: *const f64 = ptr::null();
    // SAFETY: VecGetArrayRead hands out the local entries until VecRestoreArrayRead.
    unsafe {
        check(ffi::VecGetArrayRead(v, &mut a), "VecGetArrayRead")?;
        let out = if n > 0 {
            std::slice::from_raw_parts(a, n).to_vec()
        } else {
            Vec::new()
        };
        check(ffi::VecRestoreArrayRead(v, &mut a), "VecRestoreArrayRead")?;
        Ok(out)
    }
}

/// A forward scatter of `x` into `y` by `sc`.
///
/// # Safety
/// Live handles that `sc` was made for.
unsafe fn scatter(sc: VecScatter, x: Vec_, y: Vec_) -> Result<(), SolveError> {
    // SAFETY: as the caller promises.
    unsafe {
        check(
            ffi::VecScatterBegin(sc, x, y, ffi::INSERT_VALUES, ffi::SCATTER_FORWARD),
            "VecScatterBegin",
        )?;
        check(
            ffi::VecScatterEnd(sc, x, y, ffi::INSERT_VALUES, ffi::SCATTER_FORWARD),
            "VecScatterEnd",
        )
    }
}

/// The objects of a ghost exchange: this rank's owned entries, its ghosts' copies, the scatter.
struct HaloHandles {
    owned: Vec_,
    ghosts: Vec_,
    sc: VecScatter,
}

// SAFETY: as `Handles`: used by one thread at a time behind the Mutex of `Exchange`.
unsafe impl Send for HaloHandles {}

impl Drop for HaloHandles {
    fn drop(&mut self) {
        if !running() {
            return;
        }
        // SAFETY: created by PETSc or null; destroyed once, on every rank in the same order.
        unsafe {
            ffi::VecScatterDestroy(&mut self.sc);
            ffi::VecDestroy(&mut self.ghosts);
            ffi::VecDestroy(&mut self.owned);
        }
    }
}

/// The ghost exchange of a vector laid out by blocks ([`super::Halo`]).
pub(crate) struct Exchange {
    h: Mutex<HaloHandles>,
    owned: usize,
    ghosts: usize,
}

impl Exchange {
    /// Rank r owns `owned` consecutive entries (ranks in order) and reads those at the global
    /// indices `ghosts`. Collective.
    pub(crate) fn new(owned: usize, ghosts: &[usize]) -> Result<Self, SolveError> {
        let mut h = HaloHandles {
            owned: ptr::null_mut(),
            ghosts: ptr::null_mut(),
            sc: ptr::null_mut(),
        };
        let idx: Vec<PetscInt> = ghosts
            .iter()
            .map(|&g| to_int(g, "ghost index"))
            .collect::<Result<_, _>>()?;
        let ng = to_int(ghosts.len(), "ghosts of a rank")?;
        let (mut ix, mut iy) = (ptr::null_mut(), ptr::null_mut());
        // SAFETY: index arrays of the stated lengths, copied by PETSc; the index sets are
        // destroyed below on every path, the rest by `HaloHandles::drop`.
        let made = unsafe {
            (|| {
                check(
                    ffi::VecCreateMPI(world(), to_int(owned, "owned entries")?, -1, &mut h.owned),
                    "VecCreateMPI",
                )?;
                check(ffi::VecCreateMPI(world(), ng, -1, &mut h.ghosts), "VecCreateMPI")?;
                let (mut lo, mut hi): (PetscInt, PetscInt) = (0, 0);
                check(
                    ffi::VecGetOwnershipRange(h.ghosts, &mut lo, &mut hi),
                    "VecGetOwnershipRange",
                )?;
                let to: Vec<PetscInt> = (lo..hi).collect();
                check(
                    ffi::ISCreateGeneral(world(), ng, idx.as_ptr(), ffi::PETSC_COPY_VALUES, &mut ix),
                    "ISCreateGeneral",
                )?;
                check(
                    ffi::ISCreateGeneral(world(), ng, to.as_ptr(), ffi::PETSC_COPY_VALUES, &mut iy),
                    "ISCreateGeneral",
                )?;
                check(
                    ffi::VecScatterCreate(h.owned, ix, h.ghosts, iy, &mut h.sc),
                    "VecScatterCreate",
                )
            })()
        };
        // SAFETY: created above or null.
        unsafe {
            ffi::ISDestroy(&mut ix);
            ffi::ISDestroy(&mut iy);
        }
        made?;
        Ok(Self {
            h: Mutex::new(h),
            owned,
            ghosts: ghosts.len(),
        })
    }

    /// The ghosts' values, given this rank's owned ones. Collective.
    pub(crate) fn exchange(&self, owned: &[f64]) -> Result<Vec<f64>, SolveError> {
        if owned.len() != self.owned {
            return Err(SolveError::LengthMismatch {
                what: "owned values of a ghost exchange".into(),
                expected: self.owned,
                got: owned.len(),
            });
        }
        let h = match self.h.lock() {
            Ok(h) => h,
            Err(p) => p.into_inner(),
        };
        // SAFETY: live handles of the stated local sizes.
        unsafe {
            write_local(h.owned, owned)?;
            scatter(h.sc, h.owned, h.ghosts)?;
            read_local(h.ghosts, self.ghosts)
        }
    }
}

/// PETSc's objects of one system.
struct Handles {
    a: Mat,
    b: Vec_,
    x: Vec_,
    scatter: VecScatter,
    x_all: Vec_,
    ksp: Ksp,
    /// Residual and correction of a block system's restarts (null for a replicated one).
    r: Vec_,
    d: Vec_,
}

impl Handles {
    /// No object yet (each is created by PETSc later; null is what the Destroy functions skip).
    fn empty() -> Self {
        Self {
            a: ptr::null_mut(),
            b: ptr::null_mut(),
            x: ptr::null_mut(),
            scatter: ptr::null_mut(),
            x_all: ptr::null_mut(),
            ksp: ptr::null_mut(),
            r: ptr::null_mut(),
            d: ptr::null_mut(),
        }
    }
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
            ffi::VecDestroy(&mut self.d);
            ffi::VecDestroy(&mut self.r);
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
        let mut h = Handles::empty();
        assemble(&mut h, (m, big_n), lo..hi, (&d_nnz, &o_nnz), &row)?;
        // SAFETY: `h.x` was created by `assemble`.
        unsafe {
            check(
                ffi::VecScatterCreateToAll(h.x, &mut h.scatter, &mut h.x_all),
                "VecScatterCreateToAll",
            )?;
        }
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
        // SAFETY: `h.b` holds this rank's `hi − lo` rows.
        unsafe { write_local(h.b, &rc[self.lo..self.hi])? };
        let mut gather_s = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        // SAFETY: live handles of this system.
        let iterations = unsafe { run_ksp(&h, h.b, h.x, rtol, maxits)? };
        let solve_s = t1.elapsed().as_secs_f64();
        let t2 = Instant::now();
        // SAFETY: the scattered copy holds all n entries on every rank.
        let delta = unsafe {
            scatter(h.scatter, h.x, h.x_all)?;
            read_local(h.x_all, self.n)?
        };
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

/// KSPSolve of A x = b from x = 0 to the relative reduction `rtol` of the unpreconditioned
/// residual in at most `maxits` iterations; returns the iterations. Running out of iterations
/// is not an error (the caller judges the true residual); a breakdown is.
///
/// # Safety
/// Live handles: `h`'s KSP set up, `b` and `x` laid out as its matrix's rows.
unsafe fn run_ksp(h: &Handles, b: Vec_, x: Vec_, rtol: f64, maxits: PetscInt) -> Result<usize, SolveError> {
    let (mut reason, mut its): (c_int, PetscInt) = (0, 0);
    // SAFETY: as the caller promises; scalars written by PETSc.
    unsafe {
        check(ffi::VecSet(x, 0.0), "VecSet")?;
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
        check(ffi::KSPSolve(h.ksp, b, x), "KSPSolve")?;
        check(
            ffi::KSPGetConvergedReason(h.ksp, &mut reason),
            "KSPGetConvergedReason",
        )?;
        check(
            ffi::KSPGetIterationNumber(h.ksp, &mut its),
            "KSPGetIterationNumber",
        )?;
    }
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
    Ok(iterations)
}

/// What a block system's solve did ([`BlockSolver::solve`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BlockSolve {
    pub iterations: usize,
    pub ksp_solves: usize,
    pub rel_residual: f64,
}

/// A system whose rows each rank assembles from its own block of the model, with the
/// columns' global indices: the rows of rank r are `first..first + m`, ranks in order.
pub(crate) struct BlockSolver {
    h: Mutex<Handles>,
    m: usize,
}

impl BlockSolver {
    /// Assembles this rank's rows `first..first + m` of the `total` (`row(k, columns,
    /// values)` for a global row k) and sets up KSPCG + PCGAMG. Collective.
    pub(crate) fn new(
        first: usize,
        m: usize,
        total: usize,
        row64: &super::BlockRow<'_>,
    ) -> Result<Self, SolveError> {
        let wide = std::cell::RefCell::new(Vec::new());
        let row = |k: usize, c: &mut Vec<PetscInt>, v: &mut Vec<f64>| {
            let mut w = wide.borrow_mut();
            row64(k, &mut w, v);
            c.clear();
            // Checked against the total below (`to_int`), so every column fits.
            c.extend(w.iter().map(|&j| j as PetscInt));
        };
        let row: &Row<'_> = &row;
        if !running() {
            return Err(SolveError::DistributedUnavailable {
                why: "PETSc is not initialised: create a demcon_network::distributed::Session first".into(),
            });
        }
        let t0 = Instant::now();
        let (d_nnz, o_nnz, n_ghosts) = preallocation(first..first + m, row);
        let mut h = Handles::empty();
        let sizes = (to_int(m, "rows of a rank")?, to_int(total, "unknowns")?);
        assemble(&mut h, sizes, first..first + m, (&d_nnz, &o_nnz), row)?;
        drop((d_nnz, o_nnz));
        // SAFETY: `h.x` was created by `assemble`.
        unsafe {
            check(ffi::VecDuplicate(h.x, &mut h.r), "VecDuplicate")?;
            check(ffi::VecDuplicate(h.x, &mut h.d), "VecDuplicate")?;
        }
        let assembly_s = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let solver = set_up_ksp(&mut h)?;
        let setup_s = t1.elapsed().as_secs_f64();
        let rows = all_gather(&[m as f64])?;
        record(|s| {
            s.systems += 1;
            s.solver = solver;
            s.assembly_s += assembly_s;
            s.setup_s += setup_s;
            if total >= s.max_unknowns {
                s.max_unknowns = total;
                let lo = rows.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = rows.iter().copied().fold(0.0, f64::max);
                s.rows_per_rank = (lo as usize, hi as usize);
                s.ghosts = n_ghosts;
            }
        });
        Ok(Self { h: Mutex::new(h), m })
    }

    /// Solves A x = b (`b` this rank's rows) until ‖b − A x‖ ≤ `rel_tol` ‖b‖, the true
    /// residual computed by PETSc's product with the assembled rows; returns this rank's x.
    /// A KSP solve that stops short is restarted from the true residual (as the serial
    /// methods' restart loop does) while each restart at least halves it, in at most
    /// `max_iter` iterations in all. Collective.
    ///
    /// Errors: [`SolveError::NotConverged`] when the tolerance is not met; PETSc's failures.
    pub(crate) fn solve(
        &self,
        b: &[f64],
        rel_tol: f64,
        max_iter: usize,
    ) -> Result<(Vec<f64>, BlockSolve), SolveError> {
        if b.len() != self.m {
            return Err(SolveError::LengthMismatch {
                what: "block right-hand side".into(),
                expected: self.m,
                got: b.len(),
            });
        }
        let h = match self.h.lock() {
            Ok(h) => h,
            Err(p) => p.into_inner(),
        };
        let t0 = Instant::now();
        let mut done = BlockSolve {
            iterations: 0,
            ksp_solves: 0,
            rel_residual: 0.0,
        };
        let (mut b_norm, mut r_norm) = (0.0, 0.0);
        // SAFETY: live handles of this system; vectors of `m` local rows.
        unsafe {
            write_local(h.b, b)?;
            check(ffi::VecNorm(h.b, ffi::NORM_2, &mut b_norm), "VecNorm")?;
            check(ffi::VecSet(h.x, 0.0), "VecSet")?;
            check(ffi::VecCopy(h.b, h.r), "VecCopy")?;
        }
        if b_norm == 0.0 {
            return Ok((vec![0.0; self.m], done));
        }
        let mut current = 1.0;
        loop {
            let left = max_iter.saturating_sub(done.iterations);
            if current <= rel_tol || left == 0 {
                break;
            }
            let maxits = to_int(left.min(i32::MAX as usize), "max_iter")?;
            // SAFETY: as above.
            unsafe {
                done.iterations += run_ksp(&h, h.r, h.d, rel_tol / current, maxits)?.max(1);
                check(ffi::VecAXPY(h.x, 1.0, h.d), "VecAXPY")?;
                check(ffi::MatMult(h.a, h.x, h.r), "MatMult")?;
                check(ffi::VecAYPX(h.r, -1.0, h.b), "VecAYPX")?;
                check(ffi::VecNorm(h.r, ffi::NORM_2, &mut r_norm), "VecNorm")?;
            }
            done.ksp_solves += 1;
            let next = r_norm / b_norm;
            if !next.is_finite() {
                return Err(SolveError::NonFinite {
                    method: super::METHOD,
                    iteration: done.iterations,
                    what: "true residual norm",
                    value: next,
                });
            }
            let stalled = next > 0.5 * current;
            current = next;
            if stalled {
                break;
            }
        }
        done.rel_residual = current;
        let solve_s = t0.elapsed().as_secs_f64();
        record(|s| {
            s.ksp_solves += done.ksp_solves;
            s.iterations += done.iterations;
            s.solve_s += solve_s;
        });
        if current > rel_tol {
            return Err(SolveError::NotConverged {
                method: super::METHOD,
                iterations: done.iterations,
                relative_residual: current,
                tolerance: rel_tol,
            });
        }
        // SAFETY: as above.
        let x = unsafe { read_local(h.x, self.m)? };
        Ok((x, done))
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
