//! `cargo xtask ci`: the checks CI runs (`.ci/run` calls this).

use std::process::Command;

use anyhow::Result;

use crate::cargo;

/// Tidy checks (layers, file headers), format check, clippy with warnings as errors,
/// workspace tests; `--quick-validate` also runs `cargo xtask validate --quick`; `--python` the
/// Python package (built into a fresh venv, its pytest suite, the example small); `--petsc`
/// then the distributed solve's clippy and tests (needs PETSc, MPI and `mpirun`:
/// docs/distributed.md).
pub fn run(rest: &[String]) -> Result<()> {
    crate::tidy::run()?;
    crate::run(cargo().args(["fmt", "--all", "--", "--check"]))?;
    crate::run(cargo().args(["clippy", "--workspace", "--all-targets", "--", "-D", "warnings"]))?;
    crate::run(cargo().args(["test", "--workspace"]))?;
    if rest.iter().any(|a| a == "--quick-validate") {
        crate::validate(&["--quick".to_string()])?;
    }
    if rest.iter().any(|a| a == "--python") {
        python()?;
    }
    if rest.iter().any(|a| a == "--petsc") {
        let crates = ["-p", "demcon-network", "-p", "demcon-scene", "-p", "demcon"];
        crate::run(cargo().args(["clippy"]).args(crates).args([
            "--all-targets",
            "--features",
            "petsc",
            "--",
            "-D",
            "warnings",
        ]))?;
        for (krate, test) in [("demcon-network", "distributed"), ("demcon", "distributed")] {
            crate::run(cargo().args(["test", "-p", krate, "--features", "petsc", "--test", test]))?;
        }
    }
    Ok(())
}

/// The Python package (docs/python.md): a fresh virtual environment in `target/python-ci`,
/// maturin, pytest, numpy, tqdm and PyVista from PyPI, `pip install ./python`, its tests, the
/// example small.
fn python() -> Result<()> {
    let venv = std::path::Path::new("target/python-ci/venv");
    if venv.exists() {
        std::fs::remove_dir_all(venv)?;
    }
    crate::run(Command::new("python3").args(["-m", "venv"]).arg(venv))?;
    let py = venv.join("bin/python");
    let pip = |args: &[&str]| {
        crate::run(
            Command::new(&py)
                .args(["-m", "pip", "install", "--quiet"])
                .args(args),
        )
    };
    pip(&["--upgrade", "pip"])?;
    // tqdm and PyVista (optional: progress bars, RunResult.to_pyvista) so their paths are tested
    pip(&["maturin>=1.16,<2", "pytest", "numpy", "tqdm", "pyvista"])?;
    pip(&["./python"])?;
    crate::run(Command::new(&py).args(["-m", "pytest", "python/tests", "-q"]))?;
    crate::run(Command::new(&py).args([
        "examples/python/composite_sweep.py",
        "--count",
        "1500",
        "--fractions",
        "0.05",
        "0.2",
        "--seeds",
        "1",
        "2",
    ]))
}
