//! `multi-inclusion-etc` — Haddad et al. 2021 §5.1, Fig. 17: epoxy (0.195 W/(m·K)) filled
//! with monodisperse, non-overlapping silica spheres (1.5 W/(m·K)), cube edge / sphere
//! diameter = 6, volume fractions f = 0.1 … 0.5 (41 … 206 spheres placed by the LS algorithm
//! in the walled cube), T = 25 °C on y = 0 and 35 °C on y = L, steady state.
//!
//! Compared quantity: the ETC (W/(m·K)) against the FFT homogenisation of
//! `shared/refs/multi-inclusion-fft.json` (periodic, 3 realisations, extrapolated to zero voxel
//! size), with Maxwell and the third-order estimate beside. The ETC is 0.195 · λ_e/λ_hom, with
//! λ_hom measured on the same packing with one phase (so that the discretisation error of the
//! homogeneous matrix, which the C_t calibration only makes ≈ 1 under another boundary
//! condition, cancels), C_t from our own calibration; the Terreros α model is reported beside.
//!
//! Particle count: the paper used 8·10⁶ particles (≈ 20 000 per inclusion). Here a ladder of
//! N at f = 0.3 on one inclusion layout shows where the ETC stops moving (within 0.5 %, the
//! paper's DE–FFT agreement, of the finest N), and the sweep over f runs at that N.
//!
//! Tolerance: the paper reports < 0.5 % from its own FFT. Ours is not its FFT, and the
//! reference's notes say that fixed temperatures on two faces with adiabatic sides raise the
//! ETC by 0.3–0.7 % over periodic conditions, and that spheres confined by walls (as the LS
//! placement in a walled box does) raise it by 0.5–1.1 %: up to ≈ 1.8 % above the periodic
//! FFT from the setup alone. We accept 2.5 % over all f in `--full` (3 realisations).
//! `--quick` (one realisation of 2·10⁴ particles, ≈ 50 per sphere) is far from converged:
//! a sphere is a clump of ≈ 50 particles assigned by their centres, and at f ≥ 0.3 the gaps
//! between neighbouring spheres are thinner than a particle, so the clumps touch and the ETC
//! comes out 7–15 % high. Quick gates only the dilute fractions f = 0.1, 0.2 at 5 % and
//! reports the rest (`max_rel_error_vs_fft` over all f is always reported).

use std::time::Instant;

use demcon_graph::assign_phase;
use demcon_scene::config::*;
use demcon_scene::model::place_inclusions;
use demcon_scene::thermal::calibrate_ct;
use serde_json::{Map, Value};

use super::common::*;
use super::haddad2021_inclusion_etc::{etc_of, phase_fraction, slab_scene, with_surface};
use crate::analytic::{maxwell, third_order};
use crate::chart::{Chart, Scale, Series, draw};
use crate::{CaseOutcome, Comparison, Ctx, Table};

/// Epoxy conductivity (W/(m·K)).
pub const LAMBDA_EPOXY: f64 = 0.195;
/// Silica conductivity (W/(m·K)).
pub const LAMBDA_SILICA: f64 = 1.5;
/// Cube edge / inclusion diameter.
pub const SIZE_RATIO: f64 = 6.0;

/// Epoxy and silica (density and heat capacity do not enter the steady state).
pub fn materials() -> Vec<MaterialConfig> {
    vec![
        material("epoxy", LAMBDA_EPOXY, 1200.0, 1000.0),
        material("silica", LAMBDA_SILICA, 2200.0, 740.0),
    ]
}

/// The matrix-only slab; inclusions are added to its model by [`with_inclusions`].
pub fn base_scene(n: usize, seed: u64) -> SceneConfig {
    slab_scene("multi-inclusion-etc", seed, n, materials(), Vec::new())
}

/// A clone of `model` with silica inclusions at fraction `f` placed exactly as the scene's
/// `PhaseConfig::Inclusions` does (LS placement in the container's box, then every particle
/// whose centre lies in a sphere gets phase 1); returns the model and the number of spheres.
pub fn with_inclusions(model: &Model, f: f64, seed: u64) -> anyhow::Result<(Model, usize)> {
    let (centres, radius) = place_inclusions(&model.container, f, SIZE_RATIO, seed)?;
    let mut m = model.clone();
    let union = demcon_core::Region::Union(
        centres
            .iter()
            .map(|c| demcon_core::Region::Sphere { centre: *c, radius })
            .collect(),
    );
    assign_phase(&mut m.particles, &union, 1);
    Ok((m, centres.len()))
}

/// ETC of one packing at the fractions `fs`: (f, spheres, particle fraction, ETC calibrated,
/// ETC Terreros if asked), with the cost.
struct PackingRun {
    n: usize,
    rows: Vec<(f64, usize, f64, f64, Option<f64>)>,
    build_s: f64,
    solve_s: f64,
    iterations: u64,
    lambda_hom: f64,
}

fn run_packing(
    n: usize,
    seed: u64,
    fs: &[f64],
    terreros: bool,
    built: Option<(&Model, f64)>,
) -> anyhow::Result<(PackingRun, Model)> {
    let t0 = Instant::now();
    let base = base_scene(n, seed);
    let (model, build_s) = match built {
        Some((m, s)) => (m.clone(), s),
        None => (model_of(&base)?, t0.elapsed().as_secs_f64()),
    };
    let cal = calibrate_ct(&model)?;
    let cfg = with_surface(&base, Some(cal.c_t));
    let hom = etc_of(&cfg, model.clone())?;
    let (mut solve_s, mut iterations) = (cal.solve_s + hom.solve_s, cal.iterations as u64 + hom.iterations);
    let ter = if terreros {
        let cfg_t = with_surface(&base, None);
        let h = etc_of(&cfg_t, model.clone())?;
        Some((cfg_t, h.lambda_e))
    } else {
        None
    };
    let mut rows = Vec::new();
    for &f in fs {
        let (m, count) = with_inclusions(&model, f, seed)?;
        let pf = phase_fraction(&m, 1);
        let e = etc_of(&cfg, m.clone())?;
        solve_s += e.solve_s;
        iterations += e.iterations;
        let et = match &ter {
            Some((cfg_t, h)) => Some(LAMBDA_EPOXY * etc_of(cfg_t, m)?.lambda_e / h),
            None => None,
        };
        rows.push((f, count, pf, LAMBDA_EPOXY * e.lambda_e / hom.lambda_e, et));
    }
    Ok((
        PackingRun {
            n: model.particles.len(),
            rows,
            build_s,
            solve_s,
            iterations,
            lambda_hom: hom.lambda_e / LAMBDA_EPOXY,
        },
        model,
    ))
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let mut out = CaseOutcome::new("multi-inclusion-etc", ctx.mode);
    let fft = crate::refs::multi_inclusion_fft();
    let table = fft["by_volume_fraction"]
        .as_object()
        .ok_or_else(|| anyhow::anyhow!("multi-inclusion-fft.json: no by_volume_fraction"))?;
    let mut refs: Vec<(f64, f64, f64)> = table
        .iter()
        .map(|(k, v)| {
            Ok((
                k.parse::<f64>()?,
                v["fft"]
                    .as_f64()
                    .ok_or_else(|| anyhow::anyhow!("no FFT value at f = {k}"))?,
                v["fft_std_between_realisations"].as_f64().unwrap_or(f64::NAN),
            ))
        })
        .collect::<anyhow::Result<_>>()?;
    refs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let fs: Vec<f64> = refs.iter().map(|r| r.0).collect();

    // 1. Convergence ladder at f = 0.3 on one inclusion layout.
    let ladder_n = ctx.pick(
        vec![5_000, 20_000],
        vec![30_000, 60_000, 120_000, 250_000, 500_000],
    );
    let f_ladder = 0.3;
    let mut ladder = Vec::new();
    let mut models = Vec::new();
    for &n in &ladder_n {
        let t0 = Instant::now();
        let (r, m) = run_packing(n, ctx.seed, &[f_ladder], false, None)?;
        ladder.push((r, t0.elapsed().as_secs_f64()));
        models.push((n, m));
    }
    let finest = ladder.last().expect("ladder").0.rows[0].3;
    // The smallest N from which every finer rung stays within 0.5 % of the finest; the finest
    // rung itself proves nothing, so "converged" needs a coarser rung that qualifies.
    let conv_idx = (0..ladder.len())
        .find(|&i| {
            ladder[i..]
                .iter()
                .all(|(r, _)| (r.rows[0].3 - finest).abs() / finest <= 0.005)
        })
        .unwrap_or(ladder.len() - 1);
    let converged = conv_idx + 1 < ladder.len();
    let n_conv = ladder[conv_idx].0.n;
    let n_sweep = ctx.pick(20_000, ladder_n[conv_idx]);

    // 2. Sweep over f at n_sweep, several realisations.
    let realisations = ctx.pick(1u64, 3);
    let mut runs = Vec::new();
    for k in 0..realisations {
        // Realisation 0 reuses the ladder's packing of the same size (same seed).
        let built = models
            .iter()
            .zip(&ladder)
            .find(|((n, _), _)| k == 0 && *n == n_sweep)
            .map(|((_, m), (r, _))| (m, r.build_s));
        runs.push(run_packing(n_sweep, ctx.seed + k, &fs, k == 0, built)?.0);
    }
    out.n_particles = ladder
        .iter()
        .map(|(r, _)| r.n)
        .chain(runs.iter().map(|r| r.n))
        .max()
        .unwrap_or(0);

    let mut etc = Map::new();
    let mut rows = Vec::new();
    let mut max_err = 0.0f64;
    let mut max_err_ter = 0.0f64;
    for (i, &(f, fft_v, fft_sd)) in refs.iter().enumerate() {
        let vals: Vec<f64> = runs.iter().map(|r| r.rows[i].3).collect();
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        let sd = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / vals.len() as f64).sqrt();
        let ter = runs[0].rows[i].4.unwrap_or(f64::NAN);
        let e = (mean - fft_v).abs() / fft_v;
        max_err = max_err.max(e);
        max_err_ter = max_err_ter.max((ter - fft_v).abs() / fft_v);
        etc.insert(format!("{f}"), Value::from(mean));
        let mx = LAMBDA_EPOXY * maxwell(1.0, LAMBDA_SILICA / LAMBDA_EPOXY, f);
        let to = LAMBDA_EPOXY * third_order(1.0, LAMBDA_SILICA / LAMBDA_EPOXY, f);
        let pf = runs.iter().map(|r| r.rows[i].2).sum::<f64>() / runs.len() as f64;
        rows.push((f, runs[0].rows[i].1, pf, mean, sd, ter, fft_v, fft_sd, mx, to));
    }
    out.metric("etc", Value::Object(etc));
    out.metric("max_rel_error_vs_fft", max_err);
    out.metric("max_rel_error_vs_fft_terreros", max_err_ter);
    out.metric(
        "max_rel_error_vs_third_order",
        rows.iter()
            .map(|r| (r.3 - r.9).abs() / r.9)
            .fold(0.0f64, f64::max),
    );
    out.metric(
        "n_converged",
        if converged {
            Value::from(n_conv)
        } else {
            Value::Null
        },
    );
    out.metric("n_sweep", n_sweep);
    out.metric("realisations", realisations);
    let mut lad = Map::new();
    for (r, _) in &ladder {
        lad.insert(r.n.to_string(), Value::from(r.rows[0].3));
    }
    out.metric("etc_f0.3_by_n", Value::Object(lad));
    out.reference("max_rel_error_vs_fft", 0.005);
    out.reference(
        "source",
        "Haddad 2021 §5.1 Fig. 17 (8·10⁶ DE, < 0.5 % from its FFT); FFT: shared/refs/multi-inclusion-fft.json",
    );
    match ctx.mode {
        crate::Mode::Full => out.compare(Comparison::at_most(
            "max |ETC − FFT|/FFT over f = 0.1 … 0.5",
            max_err,
            0.025,
            "paper < 0.5 % from its own FFT",
        )),
        crate::Mode::Quick => {
            let dilute = rows
                .iter()
                .filter(|r| r.0 <= 0.2)
                .map(|r| (r.3 - r.6).abs() / r.6)
                .fold(0.0f64, f64::max);
            out.metric("max_rel_error_vs_fft_dilute", dilute);
            out.compare(Comparison::at_most(
                "max |ETC − FFT|/FFT at f = 0.1, 0.2 (quick: ≈ 50 particles per sphere)",
                dilute,
                0.05,
                "paper < 0.5 % from its own FFT",
            ));
        }
    }

    let mut t = Table {
        title: format!(
            "ETC (W/(m·K)) against f, N = {n_sweep}, {realisations} realisation(s) (Terreros: the first)"
        ),
        header: vec![
            "f".into(),
            "spheres".into(),
            "particle fraction".into(),
            "DEM calibrated".into(),
            "± (realisations)".into(),
            "DEM Terreros α".into(),
            "FFT".into(),
            "FFT ±".into(),
            "Maxwell".into(),
            "third order".into(),
            "err vs FFT".into(),
        ],
        rows: Vec::new(),
    };
    for r in &rows {
        t.rows.push(vec![
            format!("{}", r.0),
            r.1.to_string(),
            format!("{:.4}", r.2),
            format!("{:.4}", r.3),
            format!("{:.4}", r.4),
            format!("{:.4}", r.5),
            format!("{:.4}", r.6),
            format!("{:.4}", r.7),
            format!("{:.4}", r.8),
            format!("{:.4}", r.9),
            format!("{:+.2} %", 100.0 * (r.3 - r.6) / r.6),
        ]);
    }
    out.tables.push(t);
    let mut tl = Table {
        title: format!(
            "Convergence in N at f = {f_ladder} (one inclusion layout, seed {}); converged = within 0.5 % of the finest",
            ctx.seed
        ),
        header: vec![
            "N".into(),
            "particles per inclusion".into(),
            "ETC".into(),
            "vs finest".into(),
            "vs FFT".into(),
            "λ_hom/λ".into(),
            "pack+contacts (s)".into(),
            "solves (s)".into(),
            "CG iterations".into(),
            "case wall (s)".into(),
        ],
        rows: Vec::new(),
    };
    let fft03 = refs
        .iter()
        .find(|r| r.0 == f_ladder)
        .map(|r| r.1)
        .unwrap_or(f64::NAN);
    for (r, wall) in &ladder {
        let e = r.rows[0].3;
        // Particles whose centre falls in one sphere: N × (sphere volume / cube volume).
        let d = std::f64::consts::PI / 6.0 / SIZE_RATIO.powi(3);
        tl.rows.push(vec![
            r.n.to_string(),
            format!("{:.0}", r.n as f64 * d),
            format!("{e:.4}"),
            format!("{:+.2} %", 100.0 * (e - finest) / finest),
            format!("{:+.2} %", 100.0 * (e - fft03) / fft03),
            format!("{:.4}", r.lambda_hom),
            format!("{:.1}", r.build_s),
            format!("{:.2}", r.solve_s),
            r.iterations.to_string(),
            format!("{wall:.1}"),
        ]);
    }
    out.tables.push(tl);

    let curve = |g: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        (0..=25)
            .map(|i| {
                let f = 0.02 * i as f64;
                (f, LAMBDA_EPOXY * g(f))
            })
            .collect()
    };
    let ratio = LAMBDA_SILICA / LAMBDA_EPOXY;
    draw(
        &Chart {
            title: format!("Epoxy/silica ETC against f, N = {n_sweep} (Haddad 2021 Fig. 17)"),
            x_label: "silica volume fraction f".into(),
            y_label: "ETC (W/(m·K))".into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            series: vec![
                Series::line("DEM calibrated C_t", rows.iter().map(|r| (r.0, r.3)).collect()),
                Series::line("DEM Terreros α", rows.iter().map(|r| (r.0, r.5)).collect()),
                Series::markers("FFT (periodic)", rows.iter().map(|r| (r.0, r.6)).collect()),
                Series::line("Maxwell", curve(&|f| maxwell(1.0, ratio, f))),
                Series::line("third order", curve(&|f| third_order(1.0, ratio, f))),
            ],
        },
        &ctx.out.join("multi-inclusion-etc.png"),
    )?;
    draw(
        &Chart {
            title: format!("ETC at f = {f_ladder} against N (one inclusion layout)"),
            x_label: "N (particles)".into(),
            y_label: "ETC (W/(m·K))".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
            series: vec![
                Series::line(
                    "DEM calibrated C_t",
                    ladder.iter().map(|(r, _)| (r.n as f64, r.rows[0].3)).collect(),
                ),
                Series::markers(
                    "FFT (periodic, mean of 3 layouts)",
                    ladder.iter().map(|(r, _)| (r.n as f64, fft03)).collect(),
                ),
            ],
        },
        &ctx.out.join("multi-inclusion-etc-n.png"),
    )?;
    out.charts.push("multi-inclusion-etc.png".into());
    out.charts.push("multi-inclusion-etc-n.png".into());
    out.note(format!(
        "{} mode: ladder N = {:?} at f = {f_ladder}; {}; the sweep over f runs at N = {n_sweep} with {realisations} realisation(s) (packing and inclusion layout change with the seed). \
         Inclusions are placed by the scene crate's own `place_inclusions` on a clone of one matrix model per packing, so \
         the five fractions share a packing and its contacts.",
        ctx.mode.name(),
        ladder_n,
        if converged {
            format!("the ETC stays within 0.5 % of the finest rung from N = {n_conv}")
        } else {
            "the ETC has NOT converged within the ladder (no coarser rung within 0.5 % of the finest)".to_string()
        }
    ));
    out.note(
        "The FFT reference is periodic; our sample has walls and fixed-temperature faces, which by the reference's own notes \
         raise the ETC by ≈ 0.8–1.8 % at f = 0.2–0.4 over the periodic value on the same microstructure.",
    );
    Ok(out)
}
