//! The `demcon` binary: a thin dispatcher to one module per subcommand.

mod info;
mod pack;

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
    /// Print the report of a packing file (`x y z r`).
    Info(info::InfoArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Pack(args) => pack::run(*args),
        Command::Info(args) => info::run(args),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
