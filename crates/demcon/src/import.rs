//! `demcon import --from FORMAT SOURCE --out FILE`: a packing written by another DEM code
//! (PackingGeneration, LIGGGHTS/LAMMPS dump, YADE text) as a demcon `x y z r` file with its
//! container.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use demcon_packing::{
    ImportFormat, check_imported, check_writable, format_xyzr, import_packing, max_overlap, summarize,
    write_atomic,
};

use crate::container::ContainerFlags;

/// Formats accepted by `--from`.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum FromFormat {
    /// PackingGeneration (Baranau): a folder with packing.xyzd, packing.nfo, generation.conf.
    #[value(name = "packinggeneration")]
    PackingGeneration,
    /// LIGGGHTS/LAMMPS `dump custom` text with x y z radius columns (last snapshot).
    LiggghtsDump,
    /// YADE `export.text` (`#format x_y_z_r`); needs --container.
    YadeText,
}

impl From<FromFormat> for ImportFormat {
    fn from(f: FromFormat) -> Self {
        match f {
            FromFormat::PackingGeneration => ImportFormat::PackingGeneration,
            FromFormat::LiggghtsDump => ImportFormat::LiggghtsDump,
            FromFormat::YadeText => ImportFormat::YadeText,
        }
    }
}

/// Flags of `demcon import`.
#[derive(Debug, Args)]
pub struct ImportArgs {
    /// Format of the source.
    #[arg(long, value_enum)]
    from: FromFormat,
    /// Source: a folder for packinggeneration, else a file.
    source: PathBuf,
    /// Output packing file (`x y z r`, written atomically).
    #[arg(long)]
    out: PathBuf,
    /// The container, replacing the source's (coordinates are kept as imported).
    #[command(flatten)]
    container: ContainerFlags,
    /// Accept spheres that overlap by more than the Laguerre cells allow (the file is then
    /// usable by the contact models only).
    #[arg(long)]
    allow_overlap: bool,
}

/// Exit status when the imported spheres overlap by more than the Laguerre cells allow and
/// `--allow-overlap` was not given (the file is written all the same).
pub const EXIT_OVERLAP: u8 = 4;

/// Runs `demcon import`.
pub fn run(a: ImportArgs) -> anyhow::Result<ExitCode> {
    let format = ImportFormat::from(a.from);
    let given = a.container.container()?;
    check_writable(&a.out).context("--out")?;
    let imported = import_packing(format, &a.source)
        .with_context(|| format!("importing {} as {}", a.source.display(), format.name()))?;
    let mut notes = vec![format!(
        "imported from {} ({}), {} particles",
        a.source.display(),
        format.name(),
        imported.particles.len()
    )];
    notes.extend(imported.notes);
    let container = match (given, imported.container) {
        (Some(c), Some(_)) => {
            notes.push("the container is the one given on the command line, not the source's".into());
            c
        }
        (Some(c), None) => {
            notes.push("the container is the one given on the command line".into());
            c
        }
        (None, Some(c)) => c,
        (None, None) => bail!(
            "{}: the {} source gives no container: give one with --container box|cylinder|sphere|periodic \
             and --size LX,LY,LZ or --radius R [--length L] (m), as in `demcon pack`",
            a.source.display(),
            format.name()
        ),
    };
    check_imported(&imported.particles, &container)
        .with_context(|| format!("the spheres of {} do not fit the container", a.source.display()))?;
    let text = format_xyzr(&imported.particles, &container, &notes);
    write_atomic(&a.out, text.as_bytes()).context("writing the imported packing")?;
    println!("{}", summarize(&imported.particles, &container, 2.0));
    println!("written            {}", a.out.display());
    // Pairs only (and their periodic images): a sphere may stick out of a wall, the cells
    // are clipped there.
    let overlap = max_overlap(
        &imported.particles,
        container.period().is_some().then_some(&container),
    );
    let limit = demcon_graph::LaguerreParams::default().max_overlap;
    if overlap > limit {
        eprintln!(
            "{}: two spheres overlap by {overlap:.3} × the smaller radius, above the {limit} the Laguerre cells \
             (`surface: Laguerre`, the default) accept: check the source's units (positions and radii alike?) \
             or its state (a soft-sphere DEM run compressed that far?); only the contact models can use this \
             file",
            if a.allow_overlap { "warning" } else { "error" }
        );
        if !a.allow_overlap {
            eprintln!("pass --allow-overlap to accept it");
            return Ok(ExitCode::from(EXIT_OVERLAP));
        }
    }
    Ok(ExitCode::SUCCESS)
}
