//! `cargo xtask ci`: the checks CI runs (`.ci/run` calls this).

use anyhow::Result;

use crate::cargo;

/// Tidy checks (layers, file headers), format check, clippy with warnings as errors,
/// workspace tests; `--quick-validate` also runs `cargo xtask validate --quick`; `--petsc`
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
