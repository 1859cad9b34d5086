//! `cargo xtask`: project automation in Rust (no loose shell scripts).
//!
//! - `cargo xtask ci` — exactly what `.ci/run` runs: format check, clippy with warnings as
//!   errors, the workspace tests (which include the tidy checks); `--petsc` adds the
//!   distributed solve's clippy and tests (PETSc, MPI and `mpirun` installed).
//! - `cargo xtask tidy` — the architecture checks alone: the layer picture of the crate
//!   graph, faer only in demcon-network, RON only in demcon-scene, `//!` file headers.
//! - `cargo xtask validate [CASE…] [--quick | --full] [--out DIR]` — the papers' validation
//!   cases in release mode; writes `<case>.json`, charts and `REPORT.md`.
//! - `cargo xtask bench [NAME]` — the criterion benchmarks.
//! - `cargo xtask fuzz [--runs N] [--seed S] [--timeout SECS]` — a fuzz campaign of the
//!   binary on mutated scenes, packing files and `pack` flags (counts panics, hangs,
//!   non-finite outputs, outputs left by failed runs); `fuzz --metamorphic [--runs N]` runs
//!   the metamorphic suite (physics invariances on random scenes) with N cases per property.

mod ci;
mod fuzz;
mod tidy;

use std::process::Command;

use anyhow::{Result, bail};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (cmd, rest) = match args.split_first() {
        Some((c, r)) => (c.as_str(), r.to_vec()),
        None => ("help", Vec::new()),
    };
    match cmd {
        "ci" => ci::run(&rest),
        "tidy" => tidy::run(),
        "fuzz" => fuzz::run(&rest),
        "validate" => validate(&rest),
        "bench" => bench(&rest),
        "help" | "--help" | "-h" => {
            println!(
                "usage: cargo xtask <command>\n\n  ci [--petsc]               format check, clippy -D warnings, cargo test --workspace\n                             (--petsc: also the distributed solve's, docs/distributed.md)\n  \
                 tidy                       layer rules of the crate graph, file headers\n  \
                 validate [CASE…] [--quick|--full] [--out DIR] [--list]\n                             run the validation cases (release build)\n  \
                 bench [NAME]               run the criterion benchmarks (all, or benches/NAME.rs)\n  \
                 fuzz [--runs N] [--seed S] [--timeout SECS] [--out DIR]\n                             fuzz the binary (mutated scenes, packings, pack flags)\n  fuzz --metamorphic [--runs N]\n                             physics invariances on N random scenes per property"
            );
            Ok(())
        }
        other => bail!("unknown xtask command `{other}`; try `cargo xtask help`"),
    }
}

/// Runs a command, failing with its name if it fails.
pub(crate) fn run(cmd: &mut Command) -> Result<()> {
    eprintln!("$ {cmd:?}");
    let status = cmd.status()?;
    if !status.success() {
        bail!("command failed ({status}): {cmd:?}");
    }
    Ok(())
}

pub(crate) fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

pub(crate) fn validate(rest: &[String]) -> Result<()> {
    run(cargo()
        .args([
            "run",
            "--release",
            "--quiet",
            "-p",
            "validation",
            "--bin",
            "validate",
            "--",
        ])
        .args(rest))
}

fn bench(rest: &[String]) -> Result<()> {
    let mut c = cargo();
    c.args(["bench", "-p", "demcon-benches"]);
    if let Some(name) = rest.first() {
        c.args(["--bench", name]);
    }
    run(&mut c)
}
