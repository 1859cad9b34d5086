//! `demcon info FILE`: the report of a packing file (its notes, N, φ, bulk φ, radii, overlaps);
//! the container flags of `pack` give the container of a file without a `# container` line.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;
use demcon_packing::{check_imported, max_overlap, read_xyzr_file, summarize};

use crate::container::ContainerFlags;

/// Flags of `demcon info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Packing file (`x y z r`).
    file: PathBuf,
    /// Width of the wall layer left out of the bulk volume fraction (mean diameters).
    #[arg(long, default_value_t = 2.0)]
    bulk_margin: f64,
    /// The container, for a file without a `# container` line (or replacing it).
    #[command(flatten)]
    container: ContainerFlags,
}

/// Runs `demcon info`.
pub fn run(a: InfoArgs) -> anyhow::Result<ExitCode> {
    let given = a.container.container()?;
    let mut f = read_xyzr_file(&a.file).with_context(|| format!("reading packing {}", a.file.display()))?;
    if let Some(c) = given {
        check_imported(&f.particles, &c)
            .with_context(|| format!("the spheres of {} do not fit --container", a.file.display()))?;
        if f.container.is_some() {
            f.notes
                .push("the container is the one given on the command line, not the file's".into());
        }
        f.container = Some(c);
    }
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
