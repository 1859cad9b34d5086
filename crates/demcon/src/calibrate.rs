//! `demcon calibrate`: the C_t calibration of Haddad 2021 §2.1 on our own packings — either
//! the packing of a scene (several seeds) or an imported `x y z r` file.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Args;
use demcon_model::calibrate_ct;
use demcon_scene::config::{ContactsConfig, PackingConfig};
use demcon_scene::{Scene, build_model};

/// Arguments of `demcon calibrate`.
#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// A scene whose packing and contact settings are used (its physics is ignored).
    #[arg(conflicts_with = "packing")]
    pub scene: Option<PathBuf>,
    /// An `x y z r` packing file instead of a scene (box, cylinder or sphere container in its header).
    #[arg(long)]
    pub packing: Option<PathBuf>,
    /// Target mean coordination number for the contacts (with --packing).
    #[arg(long, default_value_t = 7.5)]
    pub coordination: f64,
    /// Number of realisations (seeds seed, seed+1, …) for a generated packing.
    #[arg(long, default_value_t = 4)]
    pub realisations: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Runs the subcommand.
pub fn run(args: CalibrateArgs) -> Result<ExitCode> {
    if args.realisations == 0 {
        bail!("invalid --realisations 0: give at least 1 (seeds seed, seed+1, …)");
    }
    crate::set_threads(args.threads)?;
    let (mut scene, realisations) = match (&args.scene, &args.packing) {
        (Some(path), None) => {
            let s = Scene::load(path).with_context(|| format!("loading scene {}", path.display()))?;
            let k = if matches!(s.config().packing, PackingConfig::File { .. }) {
                1
            } else {
                args.realisations
            };
            (s, k)
        }
        (None, Some(file)) => {
            let text = format!(
                "(packing: File(path: {:?}), contacts: (coordination: {}), materials: [(name: \"m\", conductivity: 1.0, density: 1.0, specific_heat: 1.0)], \
                 thermal: (bcs: [], solver: Explicit(t_end: 1.0, dt: Auto(safety: 0.9))))",
                file.display().to_string(),
                args.coordination
            );
            (Scene::parse(&text, file, PathBuf::new())?, 1)
        }
        _ => bail!("give a scene file or --packing FILE"),
    };
    if let (PackingConfig::File { .. }, Some(_)) = (&scene.config().packing, &args.packing) {
        scene = scene.edit(|c| {
            c.contacts = ContactsConfig {
                coordination: Some(args.coordination),
                tolerance: None,
            }
        })?;
    }
    let base_seed = scene.config().seed;
    let mut values = Vec::new();
    println!(
        "{:>5} {:>9} {:>10} {:>9} {:>8} {:>8} {:>10}",
        "seed", "N", "C_t", "C_t(ctr)", "Z", "ε", "solve (s)"
    );
    for k in 0..realisations {
        scene = scene.edit(|c| c.seed = base_seed + k)?;
        let model = build_model(&scene, None).context("building the packing and contacts")?;
        let cal = calibrate_ct(&model).context("calibrating C_t")?;
        println!(
            "{:>5} {:>9} {:>10.5} {:>9.5} {:>8.3} {:>8.4} {:>10.3}",
            scene.config().seed,
            model.particles.len(),
            cal.c_t,
            cal.c_t_centres,
            model.graph.coordination(),
            model.graph.report.epsilon,
            cal.solve_s
        );
        values.push(cal.c_t);
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let std = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    println!(
        "C_t = {mean:.5} (CoV {:.3} % over {} realisation(s)); the paper's 0.806 (1e5) / 0.834 (1e6) are for comparison only",
        100.0 * std / mean,
        values.len()
    );
    Ok(ExitCode::SUCCESS)
}
