//! `time-tables` — a face temperature that follows a time table (issue 35), against Duhamel's
//! superposition of the exact solution.
//!
//! The bar of `surroundings` (`bar.rs`: L = 0.1 m, a = 10⁻⁵ m²/s, Laguerre cells, 3 packings) at 0 °C,
//! x = L and the lateral faces adiabatic; x = 0 held (`WallTemperature`) at the table
//! `[(0, 0), (0, A), (t₁, A), (t_end, A + B (t_end − t₁))]`: a step to A = 50 °C at t = 0, then a
//! ramp of B from t₁ (Fo = 0.2), `outputs.times_at_breakpoints` so the steps land on t₁. Exact:
//! T = A U(x, t) + B R(x, t − t₁) H(t − t₁), with U the unit step response of the slab,
//! U = 1 − Σ 4/((2n+1)π) sin(λ_n x) exp(−λ_n² a t), λ_n = (2n+1)π/(2L), and R = ∫ U dt its
//! ramp response; 2000 terms (the first omitted below 10⁻⁴⁰ at Fo = 0.05).
//!
//! Schemes: forward Euler at the automatic step (the table read at each step's start) and
//! backward Euler at ΔFo = 10⁻³ (read at each step's middle). Crank–Nicolson is not used: a
//! jump of a held value rings in its undamped stiff modes (docs/scenes.md says so).
//!
//! Compared: the largest |T_p − T(x_p, t)| over the particles at Fo = 0.05, 0.1, 0.2 (the
//! breakpoint), 0.3 and 0.5 (`--quick`: to 0.3 on 5·10³ sites; `--full`: 10⁴ and 4·10⁴),
//! relative to the largest held value. Tolerances chosen before the
//! runs: forward Euler 0.3 % (the network's spatial error, larger than the smooth transient's
//! 0.06 % near the step's steep early front); backward Euler 1 % (its first-order time error
//! at ΔFo = 10⁻³ on the step's early decay).

use demcon_model::Model;
use demcon_scene::config::*;

use super::bar::{DIFFUSIVITY, L, bar_scene};
use super::common::*;
use super::study::Study;
use crate::{CaseOutcome, Comparison, Ctx};

/// The step (K) and the ramp's slope (K per L²/a).
const A: f64 = 50.0;
const B: f64 = 200.0;
/// Fourier number of the ramp's start.
const FO_RAMP: f64 = 0.2;
const FOURIER: [f64; 5] = [0.05, 0.1, 0.2, 0.3, 0.5];
const EXPLICIT_TOL: f64 = 3e-3;
const IMPLICIT_TOL: f64 = 1e-2;
const TERMS: usize = 2000;

/// U(x, t) of the slab held at 1 from t = 0 at x = 0, adiabatic at x = L, initially 0.
fn step_response(x: f64, t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    1.0 - (0..TERMS)
        .map(|n| {
            let k = (2 * n + 1) as f64 * std::f64::consts::PI;
            let lam = k / (2.0 * L);
            4.0 / k * (lam * x).sin() * (-lam * lam * DIFFUSIVITY * t).exp()
        })
        .sum::<f64>()
}

/// R(x, τ) = ∫₀^τ U(x, t) dt (K·s per K).
fn ramp_response(x: f64, tau: f64) -> f64 {
    if tau <= 0.0 {
        return 0.0;
    }
    tau - (0..TERMS)
        .map(|n| {
            let k = (2 * n + 1) as f64 * std::f64::consts::PI;
            let lam = k / (2.0 * L);
            let r = lam * lam * DIFFUSIVITY;
            4.0 / k * (lam * x).sin() * (1.0 - (-r * tau).exp()) / r
        })
        .sum::<f64>()
}

/// The exact temperature (°C) at x (m) and t (s).
fn exact(x: f64, t: f64) -> f64 {
    let t_ref = L * L / DIFFUSIVITY;
    let slope = B / t_ref;
    A * step_response(x, t) + slope * ramp_response(x, t - FO_RAMP * t_ref)
}

struct Row {
    particles: usize,
    explicit: f64,
    implicit: f64,
    explicit_s: f64,
    implicit_s: f64,
}

fn errors(model: &Model, cfg: &SceneConfig, scale: f64) -> anyhow::Result<(f64, f64)> {
    // The comparisons are at the requested output times (the breakpoints add none here).
    let r = run_with(cfg, model)?;
    let th = r
        .thermal
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("no thermal run"))?;
    let t_ref = L * L / DIFFUSIVITY;
    let mut worst = 0.0f64;
    for (t, temps) in &th.snapshots {
        let fo = t / t_ref;
        if !FOURIER.iter().any(|f| (f - fo).abs() < 1e-9) {
            continue;
        }
        for (v, c) in temps.iter().zip(&model.particles.centres) {
            worst = worst.max((v - exact(c.x, *t)).abs() / scale);
        }
    }
    Ok((worst, th.report.wall_s))
}

/// One packing of `n` sites, to Fo = `fo_end`.
fn measure(n: usize, seed: u64, fo_end: f64) -> anyhow::Result<Row> {
    let t_ref = L * L / DIFFUSIVITY;
    let t_end = fo_end * t_ref;
    let t1 = FO_RAMP * t_ref;
    let v_end = A + B * (fo_end - FO_RAMP);
    let table = TimedConfig::Table(vec![(0.0, 0.0), (0.0, A), (t1, A), (t_end, v_end)]);
    let held = ThermalBcConfig::WallTemperature {
        face: FaceConfig::XMin,
        value: table,
    };
    let scene = |solver| {
        let mut s = bar_scene(n, seed, vec![held.clone()], solver);
        s.outputs.times = FOURIER
            .iter()
            .filter(|&&f| f <= fo_end)
            .map(|f| f * t_ref)
            .collect();
        s.outputs.times_at_breakpoints = true;
        s
    };
    let explicit = scene(ThermalSolverConfig::Explicit {
        t_end,
        dt: TimeStepConfig::Auto { safety: 0.9 },
    });
    let implicit = scene(ThermalSolverConfig::Implicit {
        t_end,
        dt: 1e-3 * t_ref,
        scheme: ImplicitSchemeConfig::BackwardEuler,
    });
    let model = model_of(&explicit)?;
    let (e, e_s) = errors(&model, &explicit, v_end)?;
    let (i, i_s) = errors(&model, &implicit, v_end)?;
    Ok(Row {
        particles: model.particles.len(),
        explicit: e,
        implicit: i,
        explicit_s: e_s,
        implicit_s: i_s,
    })
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    // Quick: 5·10³ sites to Fo = 0.3 (forward Euler's step falls as h²).
    let sizes = ctx.pick(vec![5_000], vec![10_000, 40_000]);
    let fo_end = ctx.pick(0.3, FOURIER[FOURIER.len() - 1]);
    let study = Study::run(&sizes, |_| 3, ctx.seed, |n, seed, _| measure(n, seed, fo_end))?;
    let mut out = CaseOutcome::new("time-tables", ctx.mode);
    out.n_particles = study.rows().map(|r| r.particles).max().unwrap_or(0);
    out.tables.push(study.packings_table(
        format!(
            "Bar held at a step then a ramp: largest |T_p − T(x_p, t)| over the particles at Fo = 0.05 … \
             {fo_end}, relative to the largest held value, vs Duhamel's superposition"
        ),
        |r| r.particles,
        |c| {
            c.column("forward Euler (auto step)", |(_, r): &(u64, &Row)| {
                format!("{:.3} %", 100.0 * r.explicit)
            })
            .column("backward Euler (ΔFo = 10⁻³)", |(_, r)| {
                format!("{:.3} %", 100.0 * r.implicit)
            })
            .column("time: forward / backward (s)", |(_, r)| {
                format!("{:.2} / {:.2}", r.explicit_s, r.implicit_s)
            })
        },
    ));
    let largest = study.largest();
    let source = "Duhamel superposition of the exact slab solution, 2000 terms";
    let e = study.spread(largest, |r| r.explicit);
    let i = study.spread(largest, |r| r.implicit);
    out.compare(Comparison::at_most(
        &format!("forward Euler, max error at N = {largest}"),
        e.max,
        EXPLICIT_TOL,
        source,
    ));
    out.compare(Comparison::at_most(
        &format!("backward Euler, max error at N = {largest}"),
        i.max,
        IMPLICIT_TOL,
        source,
    ));
    out.metric("explicit_error_mean", e.mean);
    out.metric("implicit_error_mean", i.mean);
    Ok(out)
}
