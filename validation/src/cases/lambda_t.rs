//! `lambda-t` — a conductivity that depends on temperature (issue 35), λ(T) = λ0 (1 + β T)
//! with β = −2·10⁻³ 1/K (λ falls 20 % from 0 to 100 °C), on the bar of `bar.rs` (Laguerre
//! cells, 3 packings).
//!
//! - **Steady**: x = 0 held at 100 °C, x = L at 0 °C (`WallTemperature`). Kirchhoff's
//!   transform u = ∫₀^T λ dT/λ0 = T + β T²/2 is linear in x, so
//!   T(x) = (√(1 + 2 β u(x)) − 1)/β exactly. Compared: the largest |T_p − T(x_p)| over the
//!   particles relative to the span; tolerance 0.1 % (chosen before the runs: the network's
//!   second-order error with the two half-bonds' λ at their own temperatures). The
//!   iteration count is checked against the 5.
//! - **Transient**: the bar at 0 °C, x = 0 held at 100 °C from t = 0, x = L adiabatic, to
//!   Fo = 0.2 (Fo = a0 t/L², a0 = λ0/ρc), compared at Fo = 0.05, 0.1, 0.2 against our own 1-D
//!   reference: finite volumes on 800 cells, forward Euler at 0.4 of its stability bound,
//!   λ at each face the harmonic mean of its cells' λ(T); its own error, 800 against 400
//!   cells, is printed (2·10⁻⁶ of the span). demcon: backward Euler at ΔFo = 2.5·10⁻⁴, the
//!   change of the conductances lagged by one step. Tolerance 0.5 % (before the runs: the
//!   lag and backward Euler, each first order in Δt, on the step's steep early front).

use demcon_scene::config::*;

use super::bar::{DIFFUSIVITY, L, LAMBDA, bar_scene};
use super::common::*;
use super::study::Study;
use crate::{CaseOutcome, Comparison, Ctx};

const BETA: f64 = -2e-3;
const T_HOT: f64 = 100.0;
const FOURIER: [f64; 3] = [0.05, 0.1, 0.2];
const D_FOURIER: f64 = 2.5e-4;
const STEADY_TOL: f64 = 1e-3;
const TRANSIENT_TOL: f64 = 5e-3;
const MAX_SOLVES: u64 = 5;

/// The bar's scene with λ(T).
fn scene(n: usize, seed: u64, bcs: Vec<ThermalBcConfig>, solver: ThermalSolverConfig) -> SceneConfig {
    let mut s = bar_scene(n, seed, bcs, solver);
    for m in &mut s.materials {
        m.conductivity_temp_coeff = BETA;
        m.conductivity_ref_temp = 0.0;
    }
    s
}

/// The steady Kirchhoff profile (°C) at x (m).
fn steady_exact(x: f64) -> f64 {
    let u = (T_HOT + 0.5 * BETA * T_HOT * T_HOT) * (1.0 - x / L);
    ((1.0 + 2.0 * BETA * u).sqrt() - 1.0) / BETA
}

/// The 1-D reference: temperatures (°C) of `cells` cells at each Fo of `FOURIER`.
pub fn reference(cells: usize) -> Vec<Vec<f64>> {
    let dx = L / cells as f64;
    let lam = |t: f64| LAMBDA * (1.0 + BETA * t);
    let rho_c = LAMBDA / DIFFUSIVITY;
    // The largest λ over [0, 100] °C is at 0 °C (β < 0).
    let dt = 0.4 * dx * dx * rho_c / (2.0 * LAMBDA);
    let t_ref = L * L / DIFFUSIVITY;
    let mut t = vec![0.0; cells];
    let mut out = Vec::new();
    let mut time = 0.0;
    for fo in FOURIER {
        let stop = fo * t_ref;
        while time < stop {
            let h = dt.min(stop - time);
            let mut flux = vec![0.0; cells + 1];
            // Held face: a half cell at 100 °C; the far face adiabatic.
            flux[0] = 2.0 * lam(T_HOT) * lam(t[0]) / (lam(T_HOT) + lam(t[0])) * (T_HOT - t[0]) / (0.5 * dx);
            for i in 1..cells {
                let (a, b) = (lam(t[i - 1]), lam(t[i]));
                flux[i] = 2.0 * a * b / (a + b) * (t[i - 1] - t[i]) / dx;
            }
            for i in 0..cells {
                t[i] += h * (flux[i] - flux[i + 1]) / (rho_c * dx);
            }
            time += h;
        }
        out.push(t.clone());
    }
    out
}

/// The reference at x (m) from cell values, linear between cell centres.
fn at(cells: &[f64], x: f64) -> f64 {
    let n = cells.len();
    let s = x / L * n as f64 - 0.5;
    if s <= 0.0 {
        // Between the held face (100 °C, at s = −0.5) and the first centre.
        return T_HOT + (cells[0] - T_HOT) * (s + 0.5) / 0.5;
    }
    let i = (s.floor() as usize).min(n - 2);
    let w = (s - i as f64).min(1.0);
    cells[i] * (1.0 - w) + cells[i + 1] * w
}

struct Row {
    particles: usize,
    steady: f64,
    solves: u64,
    transient: f64,
}

fn measure(n: usize, seed: u64, reference: &[Vec<f64>]) -> anyhow::Result<Row> {
    let held = wall(FaceConfig::XMin, T_HOT);
    let steady_cfg = scene(
        n,
        seed,
        vec![held.clone(), wall(FaceConfig::XMax, 0.0)],
        ThermalSolverConfig::Steady,
    );
    let model = model_of(&steady_cfg)?;
    let r = run_with(&steady_cfg, &model)?;
    let th = r
        .thermal
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("no thermal run"))?;
    let steady = th
        .temperatures
        .iter()
        .zip(&model.particles.centres)
        .map(|(t, c)| (t - steady_exact(c.x)).abs() / T_HOT)
        .fold(0.0, f64::max);
    let solves = th.report.nonlinear_iterations;
    let t_ref = L * L / DIFFUSIVITY;
    let mut cfg = scene(
        n,
        seed,
        vec![held],
        ThermalSolverConfig::Implicit {
            t_end: FOURIER[FOURIER.len() - 1] * t_ref,
            dt: D_FOURIER * t_ref,
            scheme: ImplicitSchemeConfig::BackwardEuler,
        },
    );
    cfg.outputs.times = FOURIER.iter().map(|f| f * t_ref).collect();
    let r = run_with(&cfg, &model)?;
    let th = r
        .thermal
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("no thermal run"))?;
    let mut transient = 0.0f64;
    for ((_, temps), cells) in th.snapshots.iter().zip(reference) {
        for (t, c) in temps.iter().zip(&model.particles.centres) {
            transient = transient.max((t - at(cells, c.x)).abs() / T_HOT);
        }
    }
    Ok(Row {
        particles: model.particles.len(),
        steady,
        solves,
        transient,
    })
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let fine = reference(800);
    let coarse = reference(400);
    let ref_error = fine
        .iter()
        .zip(&coarse)
        .flat_map(|(f, c)| {
            (0..200).map(move |k| {
                (at(f, (k as f64 + 0.5) * L / 200.0) - at(c, (k as f64 + 0.5) * L / 200.0)).abs() / T_HOT
            })
        })
        .fold(0.0, f64::max);
    let sizes = ctx.pick(vec![10_000], vec![10_000, 40_000]);
    let study = Study::run(&sizes, |_| 3, ctx.seed, |n, seed, _| measure(n, seed, &fine))?;
    let mut out = CaseOutcome::new("lambda-t", ctx.mode);
    out.n_particles = study.rows().map(|r| r.particles).max().unwrap_or(0);
    out.tables.push(study.packings_table(
        format!(
            "Bar with λ = λ0 (1 + β T), β = {BETA}: largest |T_p − T(x_p)| relative to the span; the 1-D \
             reference's own error (800 vs 400 cells) {ref_error:.1e}"
        ),
        |r| r.particles,
        |c| {
            c.column("steady vs Kirchhoff", |(_, r): &(u64, &Row)| {
                format!("{:.2e}", r.steady)
            })
            .column("steady solves", |(_, r)| r.solves.to_string())
            .column("transient vs 1-D reference", |(_, r)| {
                format!("{:.3} %", 100.0 * r.transient)
            })
        },
    ));
    out.compare(Comparison::at_most(
        "steady λ(T) bar vs the Kirchhoff profile",
        study.worst(|r| r.steady),
        STEADY_TOL,
        "exact (Kirchhoff transform)",
    ));
    out.compare(Comparison::at_most(
        "steady λ(T): solves to converge (PICARD_TOLERANCE)",
        study.worst(|r| r.solves as f64),
        MAX_SOLVES as f64,
        "issue 35: ≤ 5 nonlinear iterations",
    ));
    let largest = study.largest();
    out.compare(Comparison::at_most(
        &format!("transient λ(T) bar at N = {largest} vs the 1-D reference"),
        study.spread(largest, |r| r.transient).max,
        TRANSIENT_TOL,
        "our 1-D finite volumes, 800 cells (error stated in the table)",
    ));
    out.metric("reference_error", ref_error);
    Ok(out)
}
