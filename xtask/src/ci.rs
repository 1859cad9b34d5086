//! `cargo xtask ci`: the checks CI runs (`.ci/run` calls this).

use anyhow::Result;

use crate::cargo;

/// Tidy checks (layers, file headers), format check, clippy with warnings as errors,
/// workspace tests; `--quick-validate` also runs `cargo xtask validate --quick`.
pub fn run(rest: &[String]) -> Result<()> {
    crate::tidy::run()?;
    crate::run(cargo().args(["fmt", "--all", "--", "--check"]))?;
    crate::run(cargo().args(["clippy", "--workspace", "--all-targets", "--", "-D", "warnings"]))?;
    crate::run(cargo().args(["test", "--workspace"]))?;
    if rest.iter().any(|a| a == "--quick-validate") {
        crate::validate(&["--quick".to_string()])?;
    }
    Ok(())
}
