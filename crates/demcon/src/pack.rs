//! `demcon pack`: flags → `PackingParams`, a progress bar, the packing file and the report.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::Args;
use demcon_packing::{
    MemoryLimit, PackProgress, PackingParams, RadiusDistribution, check_writable, format_xyzr, pack,
    write_atomic_all,
};
use indicatif::{ProgressBar, ProgressStyle};

use crate::container::ContainerFlags;

/// Exit status when the target volume fraction was not reached and `--allow-short` was not given.
pub const EXIT_SHORT: u8 = 3;

/// Flags of `demcon pack`.
#[derive(Debug, Args)]
pub struct PackArgs {
    /// The container (required).
    #[command(flatten)]
    container: ContainerFlags,
    /// Number of particles.
    #[arg(long, allow_negative_numbers = true)]
    count: i64,
    /// Target volume fraction.
    #[arg(long, allow_negative_numbers = true)]
    phi: f64,
    /// Std/mean of the Gaussian radius distribution (0: monodisperse).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    radius_cov: f64,
    /// Smallest radius over the mean (default max(1 − 2.5·cov, 0.1)).
    #[arg(long)]
    radius_min_ratio: Option<f64>,
    /// Largest radius over the mean (default 1 + 2.5·cov).
    #[arg(long)]
    radius_max_ratio: Option<f64>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output packing file (`x y z r`, written atomically).
    #[arg(long)]
    out: PathBuf,
    /// Growth rate of the mean radius over the thermal speed.
    #[arg(long)]
    growth_rate: Option<f64>,
    /// Stop after this many events.
    #[arg(long)]
    max_events: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long)]
    max_time: Option<f64>,
    /// Reduced pressure PV/(NkT) taken as jamming.
    #[arg(long)]
    jam_pressure: Option<f64>,
    /// Neighbour-list skin, as a fraction of the mean radius.
    #[arg(long)]
    neighbour_skin: Option<f64>,
    /// Kinetic-energy rise (fraction) that triggers a thermostat rescale.
    #[arg(long)]
    thermostat_tolerance: Option<f64>,
    /// Volume fraction up to which the fast compression stage runs (0 turns it off).
    #[arg(long)]
    compression_phi: Option<f64>,
    /// Growth rate of the fast compression stage.
    #[arg(long)]
    compression_growth_rate: Option<f64>,
    /// Exit with status 0 even when the target φ was not reached (jammed or out of budget).
    #[arg(long)]
    allow_short: bool,
    /// Also write the report as JSON to this file.
    #[arg(long)]
    report_json: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

/// The packing parameters of the command line, budgets checked against the fewest events the
/// target needs (before any work).
fn packing_params(a: &PackArgs, container: demcon_core::Container) -> anyhow::Result<PackingParams> {
    let mut radii = RadiusDistribution::gaussian(a.radius_cov);
    if let RadiusDistribution::Gaussian {
        min_ratio, max_ratio, ..
    } = &mut radii
    {
        *min_ratio = a.radius_min_ratio.unwrap_or(*min_ratio);
        *max_ratio = a.radius_max_ratio.unwrap_or(*max_ratio);
    } else if a.radius_cov < 0.0 || !a.radius_cov.is_finite() {
        bail!("invalid radius-cov = {}: must be ≥ 0", a.radius_cov);
    }
    let mut params = PackingParams::new(container, a.count as usize, a.phi, radii);
    if let Some(g) = a.growth_rate {
        params.growth_rate = g;
    }
    // A budget that cannot reach the target is refused before any work.
    let floor = demcon_packing::min_events(a.count as usize, a.phi);
    let how = "at least half the fewest events per particle measured for this φ, docs/packing.md \"Budgets\"";
    if let Some(m) = a.max_events {
        if m < floor {
            bail!(
                "invalid max-events = {m}: {} particles need at least {floor} events to reach φ = {} ({how}); \
                 raise --max-events or lower --phi",
                a.count,
                a.phi
            );
        }
        params.max_events = m;
    }
    if let Some(t) = a.max_time {
        let floor_s = floor as f64 / demcon_packing::EVENT_RATE_BOUND;
        if t < floor_s {
            bail!(
                "invalid max-time = {t} s: {} particles need at least {floor} events to reach φ = {}, \
                 {floor_s:.3e} s at {:.1e} events/s, twice the fastest rate measured ({how}); raise --max-time \
                 or lower --phi",
                a.count,
                a.phi,
                demcon_packing::EVENT_RATE_BOUND
            );
        }
        params.max_wall_s = t;
    }
    if let Some(p) = a.jam_pressure {
        params.jam_pressure = p;
    }
    if let Some(k) = a.neighbour_skin {
        params.neighbour_skin = k;
    }
    if let Some(t) = a.thermostat_tolerance {
        params.thermostat_tolerance = t;
    }
    if let Some(p) = a.compression_phi {
        params.compression_phi = p;
    }
    if let Some(g) = a.compression_growth_rate {
        params.compression_growth_rate = g;
    }
    Ok(params)
}

/// Runs `demcon pack`.
pub fn run(a: PackArgs) -> anyhow::Result<ExitCode> {
    let container = a
        .container
        .container()?
        .context("--container is required: box, cylinder, sphere or periodic")?;
    if a.count <= 0 {
        bail!("invalid count = {}: must be ≥ 1", a.count);
    }
    let params = packing_params(&a, container)?;
    params.validate()?;
    params.check_memory(&MemoryLimit::current())?;
    // Every output can be written: checked before the packing, not after it.
    check_writable(&a.out).context("--out")?;
    if let Some(path) = &a.report_json {
        if path == &a.out {
            bail!("--report-json and --out name the same file {}", path.display());
        }
        check_writable(path).context("--report-json")?;
    }

    let bar = if a.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(1000);
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {msg}")
                .context("progress bar template")?,
        );
        b
    };
    let update = |p: &PackProgress| {
        bar.set_position((1000.0 * p.phi / p.target_phi) as u64);
        bar.set_message(format!(
            "φ {:.4}/{:.4}  {} events  {:.2e}/s  p* {:.2e}",
            p.phi,
            p.target_phi,
            p.events,
            p.events as f64 / p.wall_s.max(1e-9),
            p.reduced_pressure
        ));
    };
    let result = pack(&params, a.seed, Some(&update));
    bar.finish_and_clear();
    let (particles, report) = result.context("packing")?;

    let notes = vec![
        format!(
            "generator demcon-packing {} (Lubachevsky–Stillinger), seed {}, growth rate {}",
            env!("CARGO_PKG_VERSION"),
            a.seed,
            params.growth_rate
        ),
        format!(
            "target phi {} reached phi {} stop {:?}",
            params.target_phi, report.packing.phi, report.stop
        ),
    ];
    // All outputs or none: the packing and the report are written to temporaries first.
    let text = format_xyzr(&particles, &container, &notes);
    let json = match &a.report_json {
        Some(_) => serde_json::to_string_pretty(&report)?,
        None => String::new(),
    };
    let mut files: Vec<(&std::path::Path, &[u8])> = vec![(a.out.as_path(), text.as_bytes())];
    if let Some(path) = &a.report_json {
        files.push((path.as_path(), json.as_bytes()));
    }
    write_atomic_all(&files).context("writing the packing and its report")?;
    println!("{report}");
    println!("written            {}", a.out.display());
    if report.reached_target() {
        return Ok(ExitCode::SUCCESS);
    }
    eprintln!(
        "{}: target φ = {} NOT reached; stopped at φ = {:.5} ({}). The packing was written anyway.",
        if a.allow_short { "warning" } else { "error" },
        params.target_phi,
        report.packing.phi,
        report.stop
    );
    if a.allow_short {
        Ok(ExitCode::SUCCESS)
    } else {
        eprintln!("pass --allow-short to accept a packing below the target");
        Ok(ExitCode::from(EXIT_SHORT))
    }
}
