//! `demcon import --from FORMAT SOURCE --out FILE`: a packing written by another DEM code
//! (PackingGeneration, LIGGGHTS/LAMMPS dump, YADE text) as a demcon `x y z r` file with its
//! container; and the container flags shared with `demcon info`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use demcon_core::Container;
use demcon_packing::{
    ImportFormat, check_imported, check_writable, format_xyzr, import_packing, summarize, write_atomic,
};

use crate::pack::ContainerKind;

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

/// The container flags of `pack`, optional: `--container KIND` with `--size` or
/// `--radius`/`--length`.
#[derive(Debug, Args)]
pub struct ContainerFlags {
    /// Container kind (box and periodic span [0, L]; cylinder along z, axis at x = y = 0;
    /// sphere centred at the origin).
    #[arg(long, value_enum)]
    container: Option<ContainerKind>,
    /// Box or periodic box edge lengths LX,LY,LZ (m).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    size: Option<Vec<f64>>,
    /// Cylinder or sphere radius (m).
    #[arg(long, allow_negative_numbers = true)]
    radius: Option<f64>,
    /// Cylinder length along z (m).
    #[arg(long, allow_negative_numbers = true)]
    length: Option<f64>,
}

impl ContainerFlags {
    /// The container the flags give, `None` without `--container`.
    pub fn container(&self) -> anyhow::Result<Option<Container>> {
        let Some(kind) = self.container else {
            if self.size.is_some() || self.radius.is_some() || self.length.is_some() {
                bail!("--size, --radius and --length need --container box|cylinder|sphere|periodic");
            }
            return Ok(None);
        };
        let size = || -> anyhow::Result<[f64; 3]> {
            match &self.size {
                Some(s) if s.len() == 3 => Ok([s[0], s[1], s[2]]),
                Some(s) => bail!("--size needs three lengths LX,LY,LZ (m), got {}", s.len()),
                None => bail!("--container {kind:?} needs --size LX,LY,LZ (m)"),
            }
        };
        let need = |v: Option<f64>, flag: &str| {
            v.with_context(|| format!("--container {kind:?} needs {flag}").to_lowercase())
        };
        let c = match kind {
            ContainerKind::Box => Container::Box { size: size()? },
            ContainerKind::Periodic => Container::Periodic { size: size()? },
            ContainerKind::Cylinder => Container::Cylinder {
                radius: need(self.radius, "--radius R (m)")?,
                length: need(self.length, "--length L (m)")?,
            },
            ContainerKind::Sphere => Container::Sphere {
                radius: need(self.radius, "--radius R (m)")?,
            },
        };
        c.validate().context("--container")?;
        Ok(Some(c))
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
}

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
    Ok(ExitCode::SUCCESS)
}
