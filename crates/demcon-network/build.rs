//! Build script of demcon-network: with the `petsc` feature, finds PETSc (pkg-config's
//! `PETSc`, or `PETSC_DIR`/`PETSC_ARCH`) and the MPI it was built with, links both, and reads
//! from their headers the two sizes the hand-written declarations of `src/distributed/ffi.rs`
//! depend on: `PetscInt` (32 or 64 bits) and `MPI_Comm` (an `int` in MPICH, a pointer in
//! Open MPI). Without the feature it does nothing.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(petsc_int64)");
    println!("cargo::rustc-check-cfg=cfg(petsc_mpi_comm_int)");
    println!("cargo::rerun-if-env-changed=PETSC_DIR");
    println!("cargo::rerun-if-env-changed=PETSC_ARCH");
    println!("cargo::rerun-if-env-changed=PKG_CONFIG_PATH");
    println!("cargo::rerun-if-env-changed=PKG_CONFIG_LIBDIR");
    if env::var_os("CARGO_FEATURE_PETSC").is_none() {
        return;
    }
    if let Err(e) = configure() {
        // A build error, not a panic message: cargo prints it as the reason the build failed.
        println!("cargo::error={e}");
        std::process::exit(1);
    }
}

/// Include directories, library directories and libraries of one pkg-config package.
#[derive(Default)]
struct Flags {
    include: Vec<PathBuf>,
    lib_dirs: Vec<PathBuf>,
    libs: Vec<String>,
}

fn configure() -> Result<(), String> {
    let petsc = match env::var_os("PETSC_DIR") {
        Some(dir) => from_petsc_dir(Path::new(&dir))?,
        None => pkg_config("PETSc")
            .or_else(|_| pkg_config("petsc"))
            .map_err(|e| {
                format!(
                    "the `petsc` feature needs PETSc ≥ 3.18 and MPI: {e}. On Debian/Ubuntu: \
                 `apt-get install petsc-dev openmpi-bin`; elsewhere set PETSC_DIR (and PETSC_ARCH) \
                 to a PETSc installation"
                )
            })?,
    };
    // MPI_Comm_rank/size are called directly: link the MPI library too (pkg-config `mpi` of
    // Debian's mpi-default-dev; PETSc's own flags when it has none).
    let mpi = pkg_config("mpi").unwrap_or_default();
    let mut include = petsc.include.clone();
    include.extend(mpi.include.iter().cloned());
    include.extend(
        [
            "/usr/include",
            "/usr/lib/x86_64-linux-gnu/openmpi/include",
            "/usr/include/mpich",
        ]
        .map(PathBuf::from),
    );

    let conf = find(&include, "petscconf.h")?;
    let conf_text = std::fs::read_to_string(&conf).map_err(|e| format!("reading {}: {e}", conf.display()))?;
    if conf_text.contains("#define PETSC_USE_COMPLEX 1") {
        return Err(format!(
            "{} is a complex-scalar PETSc; demcon needs real double scalars (Debian: petsc-dev, not petsc-complex-dev)",
            conf.display()
        ));
    }
    if !conf_text.contains("#define PETSC_USE_REAL_DOUBLE 1") {
        return Err(format!(
            "{} is not a double-precision PETSc; demcon needs real double scalars",
            conf.display()
        ));
    }
    if conf_text.contains("#define PETSC_USE_64BIT_INDICES 1") {
        println!("cargo::rustc-cfg=petsc_int64");
    }
    let mpi_h = find(&include, "mpi.h")?;
    let mpi_text =
        std::fs::read_to_string(&mpi_h).map_err(|e| format!("reading {}: {e}", mpi_h.display()))?;
    if mpi_text.contains("typedef int MPI_Comm;") {
        println!("cargo::rustc-cfg=petsc_mpi_comm_int");
    } else if !mpi_text.contains("*MPI_Comm;") {
        return Err(format!(
            "cannot tell the type of MPI_Comm from {} (known: MPICH's int, Open MPI's pointer)",
            mpi_h.display()
        ));
    }
    for d in petsc.lib_dirs.iter().chain(&mpi.lib_dirs) {
        println!("cargo::rustc-link-search=native={}", d.display());
    }
    for l in petsc.libs.iter().chain(&mpi.libs) {
        println!("cargo::rustc-link-lib={l}");
    }
    println!("cargo::rerun-if-changed={}", conf.display());
    Ok(())
}

fn find(dirs: &[PathBuf], file: &str) -> Result<PathBuf, String> {
    dirs.iter()
        .map(|d| d.join(file))
        .find(|p| p.is_file())
        .ok_or_else(|| format!("{file} not found in {dirs:?}"))
}

fn pkg_config(name: &str) -> Result<Flags, String> {
    pkg_config_in(name, None)
}

/// `pkg-config --cflags --libs name`, with `extra` prepended to `PKG_CONFIG_PATH`.
fn pkg_config_in(name: &str, extra: Option<&Path>) -> Result<Flags, String> {
    let mut cmd = Command::new("pkg-config");
    if let Some(dir) = extra {
        let old = env::var("PKG_CONFIG_PATH").unwrap_or_default();
        cmd.env("PKG_CONFIG_PATH", format!("{}:{old}", dir.display()));
    }
    let out = cmd
        .args(["--cflags", "--libs", name])
        .output()
        .map_err(|e| format!("running pkg-config: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "pkg-config finds no `{name}` ({})",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let mut f = Flags::default();
    for word in String::from_utf8_lossy(&out.stdout).split_whitespace() {
        if let Some(d) = word.strip_prefix("-I") {
            f.include.push(d.into());
        } else if let Some(d) = word.strip_prefix("-L") {
            f.lib_dirs.push(d.into());
        } else if let Some(l) = word.strip_prefix("-l") {
            f.libs.push(l.into());
        }
    }
    Ok(f)
}

fn from_petsc_dir(dir: &Path) -> Result<Flags, String> {
    let arch = env::var("PETSC_ARCH").unwrap_or_default();
    let prefix = if arch.is_empty() {
        dir.to_path_buf()
    } else {
        dir.join(&arch)
    };
    let pc = prefix.join("lib/pkgconfig");
    // Only this installation's PETSc.pc: never fall back to another PETSc on the system.
    if pc.join("PETSc.pc").is_file()
        && let Ok(f) = pkg_config_in("PETSc", Some(&pc))
    {
        return Ok(f);
    }
    if !prefix.join("include/petscconf.h").is_file() {
        return Err(format!(
            "PETSC_DIR={} (PETSC_ARCH={arch:?}) has no include/petscconf.h",
            dir.display()
        ));
    }
    Ok(Flags {
        include: vec![prefix.join("include"), dir.join("include")],
        lib_dirs: vec![prefix.join("lib")],
        libs: vec!["petsc".into()],
    })
}
