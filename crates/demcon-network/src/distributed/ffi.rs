//! Hand-written declarations of the few PETSc (3.18) and MPI functions the distributed solve
//! calls, checked against Debian's `petsc-dev` headers. Two C types differ between builds
//! and are read from the headers by `build.rs`: `PetscInt` (`petsc_int64` when PETSc was
//! configured with 64-bit indices) and `MPI_Comm` (`petsc_mpi_comm_int` for MPICH's `int`;
//! Open MPI's is a pointer). The communicator is never built here: it is PETSc's global
//! `PETSC_COMM_WORLD`, read after `PetscInitialize`.
#![allow(unsafe_code, non_camel_case_types, non_snake_case, dead_code)]

use std::ffi::{c_char, c_int, c_void};

/// `PetscErrorCode`: 0 on success.
pub type PetscErrorCode = c_int;
/// `PetscInt` (row and column indices, counts).
#[cfg(not(petsc_int64))]
pub type PetscInt = i32;
/// `PetscInt` (row and column indices, counts).
#[cfg(petsc_int64)]
pub type PetscInt = i64;
/// `PetscScalar` and `PetscReal` of a real double build (checked by `build.rs`).
pub type PetscScalar = f64;
/// `PetscReal`.
pub type PetscReal = f64;
/// `PetscBool` (a C enum: `PETSC_FALSE` = 0, `PETSC_TRUE` = 1).
pub type PetscBool = c_int;
/// `PetscLogDouble`.
pub type PetscLogDouble = f64;
/// `MPI_Comm` of MPICH.
#[cfg(petsc_mpi_comm_int)]
pub type MpiComm = c_int;
/// `MPI_Comm` of Open MPI (`struct ompi_communicator_t *`).
#[cfg(not(petsc_mpi_comm_int))]
pub type MpiComm = *mut c_void;

/// Opaque PETSc objects (`Mat`, `Vec`, `KSP`, `PC`, `VecScatter` are pointers to them).
pub type Mat = *mut c_void;
/// `Vec`.
pub type Vec_ = *mut c_void;
/// `KSP`.
pub type Ksp = *mut c_void;
/// `PC`.
pub type Pc = *mut c_void;
/// `VecScatter`.
pub type VecScatter = *mut c_void;
/// `IS` (an index set).
pub type Is = *mut c_void;

pub const PETSC_TRUE: PetscBool = 1;
/// `PETSC_DEFAULT` as a real argument.
pub const PETSC_DEFAULT_REAL: PetscReal = -2.0;
/// `InsertMode::INSERT_VALUES`.
pub const INSERT_VALUES: c_int = 1;
/// `ScatterMode::SCATTER_FORWARD`.
pub const SCATTER_FORWARD: c_int = 0;
/// `MatAssemblyType::MAT_FINAL_ASSEMBLY`.
pub const MAT_FINAL_ASSEMBLY: c_int = 0;
/// `MatOption::MAT_SYMMETRIC`.
pub const MAT_SYMMETRIC: c_int = 1;
/// `MatOption::MAT_SPD`.
pub const MAT_SPD: c_int = 15;
/// `KSPNormType::KSP_NORM_UNPRECONDITIONED`.
pub const KSP_NORM_UNPRECONDITIONED: c_int = 2;
/// `KSPConvergedReason::KSP_DIVERGED_ITS`.
pub const KSP_DIVERGED_ITS: c_int = -3;
/// `KSPConvergedReason::KSP_DIVERGED_NANORINF`.
pub const KSP_DIVERGED_NANORINF: c_int = -9;

/// `PetscCopyMode::PETSC_COPY_VALUES`.
pub const PETSC_COPY_VALUES: c_int = 0;
/// `NormType::NORM_2`.
pub const NORM_2: c_int = 1;

pub const MATMPIAIJ: &std::ffi::CStr = c"mpiaij";
pub const KSPCG: &std::ffi::CStr = c"cg";
pub const PCGAMG: &std::ffi::CStr = c"gamg";

unsafe extern "C" {
    /// PETSc's world communicator (a global of libpetsc, set by `PetscInitialize`).
    pub static PETSC_COMM_WORLD: MpiComm;

    pub fn PetscInitializeNoArguments() -> PetscErrorCode;
    pub fn PetscInitialized(flag: *mut PetscBool) -> PetscErrorCode;
    pub fn PetscFinalized(flag: *mut PetscBool) -> PetscErrorCode;
    pub fn PetscFinalize() -> PetscErrorCode;
    pub fn PetscErrorMessage(
        code: c_int,
        text: *mut *const c_char,
        specific: *mut *mut c_char,
    ) -> PetscErrorCode;
    pub fn PetscMemoryGetCurrentUsage(bytes: *mut PetscLogDouble) -> PetscErrorCode;

    pub fn MPI_Comm_rank(comm: MpiComm, rank: *mut c_int) -> c_int;
    pub fn MPI_Comm_size(comm: MpiComm, size: *mut c_int) -> c_int;

    pub fn MatCreate(comm: MpiComm, a: *mut Mat) -> PetscErrorCode;
    pub fn MatSetSizes(a: Mat, m: PetscInt, n: PetscInt, big_m: PetscInt, big_n: PetscInt) -> PetscErrorCode;
    pub fn MatSetType(a: Mat, t: *const c_char) -> PetscErrorCode;
    pub fn MatMPIAIJSetPreallocation(
        a: Mat,
        d_nz: PetscInt,
        d_nnz: *const PetscInt,
        o_nz: PetscInt,
        o_nnz: *const PetscInt,
    ) -> PetscErrorCode;
    pub fn MatSetValues(
        a: Mat,
        m: PetscInt,
        idxm: *const PetscInt,
        n: PetscInt,
        idxn: *const PetscInt,
        v: *const PetscScalar,
        mode: c_int,
    ) -> PetscErrorCode;
    pub fn MatAssemblyBegin(a: Mat, t: c_int) -> PetscErrorCode;
    pub fn MatAssemblyEnd(a: Mat, t: c_int) -> PetscErrorCode;
    pub fn MatSetOption(a: Mat, op: c_int, flg: PetscBool) -> PetscErrorCode;
    pub fn MatDestroy(a: *mut Mat) -> PetscErrorCode;

    pub fn VecCreateMPI(comm: MpiComm, n: PetscInt, big_n: PetscInt, v: *mut Vec_) -> PetscErrorCode;
    pub fn VecSet(v: Vec_, alpha: PetscScalar) -> PetscErrorCode;
    pub fn VecCopy(x: Vec_, y: Vec_) -> PetscErrorCode;
    pub fn VecGetArray(v: Vec_, a: *mut *mut PetscScalar) -> PetscErrorCode;
    pub fn VecRestoreArray(v: Vec_, a: *mut *mut PetscScalar) -> PetscErrorCode;
    pub fn VecGetArrayRead(v: Vec_, a: *mut *const PetscScalar) -> PetscErrorCode;
    pub fn VecRestoreArrayRead(v: Vec_, a: *mut *const PetscScalar) -> PetscErrorCode;
    pub fn VecDestroy(v: *mut Vec_) -> PetscErrorCode;
    pub fn VecScatterCreateToAll(v: Vec_, ctx: *mut VecScatter, all: *mut Vec_) -> PetscErrorCode;
    pub fn VecScatterBegin(ctx: VecScatter, x: Vec_, y: Vec_, mode: c_int, dir: c_int) -> PetscErrorCode;
    pub fn VecScatterEnd(ctx: VecScatter, x: Vec_, y: Vec_, mode: c_int, dir: c_int) -> PetscErrorCode;
    pub fn VecScatterDestroy(ctx: *mut VecScatter) -> PetscErrorCode;
    pub fn VecScatterCreate(x: Vec_, ix: Is, y: Vec_, iy: Is, ctx: *mut VecScatter) -> PetscErrorCode;
    pub fn ISCreateGeneral(
        comm: MpiComm,
        n: PetscInt,
        idx: *const PetscInt,
        mode: c_int,
        is: *mut Is,
    ) -> PetscErrorCode;
    pub fn ISDestroy(is: *mut Is) -> PetscErrorCode;
    pub fn VecGetOwnershipRange(v: Vec_, lo: *mut PetscInt, hi: *mut PetscInt) -> PetscErrorCode;
    pub fn VecDuplicate(v: Vec_, w: *mut Vec_) -> PetscErrorCode;
    pub fn VecNorm(v: Vec_, t: c_int, norm: *mut PetscReal) -> PetscErrorCode;
    pub fn VecAXPY(y: Vec_, alpha: PetscScalar, x: Vec_) -> PetscErrorCode;
    pub fn VecAYPX(y: Vec_, beta: PetscScalar, x: Vec_) -> PetscErrorCode;
    pub fn MatMult(a: Mat, x: Vec_, y: Vec_) -> PetscErrorCode;

    pub fn KSPCreate(comm: MpiComm, ksp: *mut Ksp) -> PetscErrorCode;
    pub fn KSPSetOperators(ksp: Ksp, a: Mat, p: Mat) -> PetscErrorCode;
    pub fn KSPSetType(ksp: Ksp, t: *const c_char) -> PetscErrorCode;
    pub fn KSPGetPC(ksp: Ksp, pc: *mut Pc) -> PetscErrorCode;
    pub fn PCSetType(pc: Pc, t: *const c_char) -> PetscErrorCode;
    pub fn KSPSetNormType(ksp: Ksp, t: c_int) -> PetscErrorCode;
    pub fn KSPSetTolerances(
        ksp: Ksp,
        rtol: PetscReal,
        abstol: PetscReal,
        dtol: PetscReal,
        maxits: PetscInt,
    ) -> PetscErrorCode;
    pub fn KSPSetFromOptions(ksp: Ksp) -> PetscErrorCode;
    pub fn KSPGetType(ksp: Ksp, t: *mut *const c_char) -> PetscErrorCode;
    pub fn PCGetType(pc: Pc, t: *mut *const c_char) -> PetscErrorCode;
    pub fn KSPSetUp(ksp: Ksp) -> PetscErrorCode;
    pub fn KSPSolve(ksp: Ksp, b: Vec_, x: Vec_) -> PetscErrorCode;
    pub fn KSPGetConvergedReason(ksp: Ksp, reason: *mut c_int) -> PetscErrorCode;
    pub fn KSPGetIterationNumber(ksp: Ksp, its: *mut PetscInt) -> PetscErrorCode;
    pub fn KSPGetResidualNorm(ksp: Ksp, rnorm: *mut PetscReal) -> PetscErrorCode;
    pub fn KSPDestroy(ksp: *mut Ksp) -> PetscErrorCode;
}
