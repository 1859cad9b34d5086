//! `demcon plot OUT`: PNG charts from a run's output folder — probes against time, profiles
//! along their lines, and slices of the particle fields with a colour bar and axes in mm.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use demcon_core::Axis;
use demcon_scene::plots::{PlotParams, read_run_folder, write_plots};

/// A slice plane's normal.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum AxisArg {
    /// Plane normal to x.
    X,
    /// Plane normal to y.
    Y,
    /// Plane normal to z.
    Z,
}

/// Flags of `demcon plot`.
#[derive(Debug, Args)]
pub struct PlotArgs {
    /// A run's output folder (`demcon run SCENE --out OUT`).
    run: PathBuf,
    /// Field to slice (repeatable), e.g. `temperature`, `potential`, `halo_flux`; default:
    /// temperature (or potential), and halo_flux when the run has it.
    #[arg(long = "slice", value_name = "FIELD")]
    slices: Vec<String>,
    /// Normal of the slice plane (default: the plane contains the axis along which the
    /// temperature, else the potential, varies most, or the domain's longest axis when it
    /// varies along none: a cylinder along z is cut through its axis).
    #[arg(long, value_enum)]
    axis: Option<AxisArg>,
    /// Position of the slice plane along its normal (m; default: the middle of the particles).
    #[arg(long, value_name = "POS_M")]
    at: Option<f64>,
    /// Cells along the longer side of a slice.
    #[arg(long, default_value_t = PlotParams::default().resolution)]
    resolution: usize,
    /// Folder for the PNGs (default: OUT/plots).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Runs `demcon plot`.
pub fn run(a: PlotArgs) -> anyhow::Result<ExitCode> {
    if !(10..=2000).contains(&a.resolution) {
        bail!(
            "invalid --resolution {}: must be between 10 and 2000 cells",
            a.resolution
        );
    }
    if let Some(at) = a.at
        && !at.is_finite()
    {
        bail!("invalid --at {at}: must be a finite position (m)");
    }
    // The error names the folder or the file.
    let data = read_run_folder(&a.run)?;
    let params = PlotParams {
        slices: a.slices,
        axis: a.axis.map(|x| match x {
            AxisArg::X => Axis::X,
            AxisArg::Y => Axis::Y,
            AxisArg::Z => Axis::Z,
        }),
        at: a.at,
        resolution: a.resolution,
    };
    let dir = a.out.unwrap_or_else(|| a.run.join("plots"));
    let plots = write_plots(&data, &params, &dir).with_context(|| format!("plotting {}", a.run.display()))?;
    for f in &plots.files {
        let range = f
            .range
            .map_or(String::new(), |(lo, hi)| format!(", colour bar {lo} … {hi}"));
        println!("{}: {}{range}", dir.join(&f.name).display(), f.what);
    }
    for s in &plots.skipped {
        println!("not drawn: {s}");
    }
    Ok(ExitCode::SUCCESS)
}
