//! The `demcon` binary: a thin dispatcher to one module per subcommand.

mod calibrate;
mod container;
mod import;
mod info;
mod mpi;
mod pack;
mod plot;
mod progress;
mod run;
mod signals;
mod tile;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// demcon: heat and electric conduction in dense random sphere packings (DEM).
#[derive(Debug, Parser)]
#[command(name = "demcon", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Make a dense random packing by the Lubachevsky–Stillinger algorithm.
    Pack(Box<pack::PackArgs>),
    /// Copy a periodic packing file NX × NY × NZ times into a larger periodic packing.
    Tile(tile::TileArgs),
    /// Print the report of a packing file (`x y z r`).
    Info(info::InfoArgs),
    /// Convert a packing from PackingGeneration, LIGGGHTS/LAMMPS or YADE into a demcon file.
    Import(import::ImportArgs),
    /// Run a scene file (RON): packing, contacts, thermal and/or electric solve, outputs.
    Run(run::RunArgs),
    /// Calibrate the transmission-surface constant C_t on our own packings (Haddad 2021 §2.1).
    Calibrate(calibrate::CalibrateArgs),
    /// Draw PNG charts of a run's output folder: probes, profiles, slices of particle fields.
    Plot(plot::PlotArgs),
}

/// Sets the size of the global worker pool (default: all cores).
pub(crate) fn set_threads(threads: Option<usize>) -> anyhow::Result<()> {
    if let Some(n) = threads {
        // Bounded: --threads 10000 would spawn 10 000 threads.
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        if n == 0 || n > 4 * cores.max(2) {
            anyhow::bail!(
                "invalid --threads {n}: must be between 1 and {} (4 × the {cores} cores of this machine)",
                4 * cores.max(2)
            );
        }
        rayon::ThreadPoolBuilder::new().num_threads(n).build_global()?;
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Pack(args) => pack::run(*args),
        Command::Tile(args) => tile::run(args),
        Command::Info(args) => info::run(args),
        Command::Import(args) => import::run(args),
        Command::Run(args) => run::run(args),
        Command::Calibrate(args) => calibrate::run(args),
        Command::Plot(args) => plot::run(args),
    };
    // A run stopped by a signal exits from the signal thread once it has cleaned up.
    signals::hold_if_stopping();
    match result {
        Ok(code) => code,
        Err(e) => {
            report_error(&e);
            if mpi::silent() {
                // A rank other than 0: let rank 0 print first (`mpi::LINGER`); still here
                // after it, this rank failed alone and says why.
                std::thread::sleep(mpi::LINGER);
                let rank = mpi::launch().map_or(0, |l| l.rank);
                eprintln!("error (rank {rank}): {}", error_chain(&e));
            }
            ExitCode::FAILURE
        }
    }
}

/// Prints a failed command's error once: a distributed run reports before PETSc finalizes
/// (`run.rs`), and `main` then prints nothing more. A distributed run's ranks fail alike:
/// rank 0 says why, the others stay quiet.
pub(crate) fn report_error(e: &anyhow::Error) {
    if mpi::first_report() && !mpi::silent() {
        eprintln!("error: {}", error_chain(e));
    }
}

/// The error and its causes joined by ": ", each cause once: a cause whose text the message
/// already carries (an error that prints its source) is not repeated.
fn error_chain(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !msg.contains(&c) {
            msg.push_str(": ");
            msg.push_str(&c);
        }
    }
    path_once(&msg)
}

/// `msg` with a file path said once where a context names it right before the error that
/// names it again (`reading p.xyzr: p.xyzr:3: …` → `reading p.xyzr:3: …`).
fn path_once(msg: &str) -> String {
    let mut out = String::with_capacity(msg.len());
    let mut rest = msg;
    while let Some(k) = rest.find(": ") {
        let (head, tail) = (&rest[..k], &rest[k + 2..]);
        let path = head.rsplit(' ').next().unwrap_or("");
        let path_like =
            path.len() > 1 && (path.contains('/') || path.contains('.')) && path.parse::<f64>().is_err();
        if path_like && tail.starts_with(path) {
            out.push_str(&head[..head.len() - path.len()]);
            rest = tail;
        } else {
            out.push_str(head);
            out.push_str(": ");
            rest = tail;
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::path_once;

    #[test]
    fn a_path_named_twice_in_a_row_is_said_once() {
        assert_eq!(
            path_once("running scene s.ron: packing: reading p.xyzr: p.xyzr:3: `x` is not a finite number"),
            "running scene s.ron: packing: reading p.xyzr:3: `x` is not a finite number"
        );
        assert_eq!(
            path_once("loading scene /a/b.ron: /a/b.ron:3:80: unknown field"),
            "loading scene /a/b.ron:3:80: unknown field"
        );
        assert_eq!(
            path_once("value 0.5: 0.5 is too small"),
            "value 0.5: 0.5 is too small"
        );
        assert_eq!(path_once("a: b: c"), "a: b: c");
    }
}
