//! `demcon info FILE`: the report of a packing file (its notes, N, φ, bulk φ, radii, overlaps).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;
use demcon_packing::{max_overlap, read_xyzr_file, summarize};

/// Flags of `demcon info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Packing file (`x y z r`).
    file: PathBuf,
    /// Width of the wall layer left out of the bulk volume fraction (mean diameters).
    #[arg(long, default_value_t = 2.0)]
    bulk_margin: f64,
}

/// Runs `demcon info`.
pub fn run(a: InfoArgs) -> anyhow::Result<ExitCode> {
    let f = read_xyzr_file(&a.file).with_context(|| format!("reading packing {}", a.file.display()))?;
    println!("file               {}", a.file.display());
    for note in &f.notes {
        println!("note               {note}");
    }
    match &f.container {
        Some(c) => println!("{}", summarize(&f.particles, c, a.bulk_margin)),
        None => {
            let s = f.particles.radius_stats();
            println!(
                "particles          {} (no `# container` line: volume fraction unknown)",
                f.particles.len()
            );
            println!(
                "radius (m)         mean {:.5e}  std {:.5e}  min {:.5e}  max {:.5e}",
                s.mean, s.std, s.min, s.max
            );
            println!(
                "largest overlap    {:.2e} of the smaller radius",
                max_overlap(&f.particles, None)
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
