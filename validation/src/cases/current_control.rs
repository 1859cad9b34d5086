//! `current-control` — a current imposed between two electrodes instead of a potential
//! difference (issue 35), on a homogeneous bar of AISI 304L (2 × 2 × 8 mm, Laguerre cells, face
//! electrodes on z = 0 and z = L), 3 packings.
//!
//! - **Potential drop**: I = 2 A; the solve finds the first electrode's potential: ΔV = I R
//!   with R = ρ_e L/A exactly (the Laguerre network is exact in a homogeneous body). Tolerance
//!   10⁻⁹ (round-off and the linear solver's 10⁻¹⁰).
//! - **ρ_e(T) at constant current**: ρ_e = ρ_e0 (1 + β (T − T0)), β = 4·10⁻³ 1/K, every thermal
//!   face adiabatic, η = 1, the potential re-solved whenever a temperature moved by 0.25 K. In
//!   a uniform field every Laguerre cell dissipates σ E² V_cell, so the bar heats uniformly and
//!   C dθ/dt = I² R0 (1 + β θ): θ(t) = (exp(β I² R0 t / C) − 1)/β, C = ρ c V. Run until R has
//!   doubled (β θ = 1). Compared: the capacity-weighted mean rise at 20 times. Tolerance, a
//!   priori: the power lags the temperature by at most 0.25 K, a relative deficit ≤ β·0.25 =
//!   10⁻³, amplified by at most 1 + β θ = 2 as the growth feeds on itself: 2·10⁻³; backward
//!   Euler at t_end/400 adds about (λ Δt/2) λ t ≈ 6·10⁻⁴ (λ = β I² R0 / C): 3·10⁻³ in all.
//! - **A heater switched off** (an electrode's potential as a time table, ρ_e constant):
//!   V = 0.1 V until t₁ = t_end/2, then 0 (`outputs.times_at_breakpoints` lands a step on t₁):
//!   the bar's mean rise is P0 min(t, t₁)/C exactly (P0 = V²/R0, every step's power in force
//!   for all of it). Tolerance 10⁻⁸ (round-off and the solver).

use demcon_scene::config::*;

use super::common::*;
use super::study::Study;
use crate::{CaseOutcome, Comparison, Ctx};

const SIDE: f64 = 2e-3;
const LENGTH: f64 = 8e-3;
const RHO_E: f64 = 7.0e-7;
const BETA: f64 = 4e-3;
const T0: f64 = 20.0;
const CURRENT: f64 = 2.0;
/// The transient's current (A): heats the bar to β θ = 1 in a few seconds.
const HEATING_CURRENT: f64 = 60.0;
const RECOUPLE: f64 = 0.25;
const OUTPUTS: usize = 20;
const DROP_TOL: f64 = 1e-9;
const SWITCH_TOL: f64 = 1e-8;
/// The switched heater's potential (V).
const V_ON: f64 = 0.1;
const THETA_TOL: f64 = 3e-3;

fn steel() -> MaterialConfig {
    MaterialConfig {
        name: "AISI 304L".into(),
        conductivity: 15.0,
        conductivity_temp_coeff: 0.0,
        conductivity_ref_temp: 20.0,
        conductivity_tensor: None,
        tensor_in_shape_frame: false,
        conductivity_table: None,
        density: 7900.0,
        specific_heat: 500.0,
        resistivity: Some(RHO_E),
        resistivity_temp_coeff: BETA,
        resistivity_ref_temp: T0,
    }
}

fn bar(n: usize, seed: u64, current: f64, solver: ThermalSolverConfig, times: Vec<f64>) -> SceneConfig {
    let mut s = thermal_scene(
        "current-control",
        seed,
        PackingConfig::Generate {
            container: ContainerConfig::Box {
                size: (SIDE, SIDE, LENGTH),
            },
            count: n,
            phi: 0.55,
            radius_cov: 0.3,
            radius_range: None,
            allow_short: false,
        },
        vec![steel()],
        ThermalConfig {
            initial_temperature: T0,
            bcs: Vec::new(),
            sources: Vec::new(),
            solver,
            checkpoint: None,
        },
    );
    s.surface = SurfaceConfig::Laguerre;
    s.electric = Some(ElectricConfig {
        electrodes: vec![
            ElectrodeConfig {
                select: None,
                face: Some(FaceConfig::ZMin),
                potential: 0.0.into(),
            },
            ElectrodeConfig {
                select: None,
                face: Some(FaceConfig::ZMax),
                potential: 0.0.into(),
            },
        ],
        eta: 1.0,
        surface: None,
        recouple_tolerance: Some(RECOUPLE),
        homogenize: false,
        current: Some(current),
    });
    s.outputs.times = times;
    s
}

struct Row {
    particles: usize,
    drop: f64,
    switched: f64,
    theta: f64,
    solves: usize,
    spread: f64,
}

fn measure(n: usize, seed: u64) -> anyhow::Result<Row> {
    let r0 = RHO_E * LENGTH / (SIDE * SIDE);
    let c = 7900.0 * 500.0 * SIDE * SIDE * LENGTH;
    let lambda = BETA * HEATING_CURRENT * HEATING_CURRENT * r0 / c;
    let t_end = std::f64::consts::LN_2 / lambda;
    let times: Vec<f64> = (1..=OUTPUTS).map(|k| t_end * k as f64 / OUTPUTS as f64).collect();
    let implicit = ThermalSolverConfig::Implicit {
        t_end,
        dt: t_end / 400.0,
        scheme: ImplicitSchemeConfig::BackwardEuler,
    };
    // The drop: a steady thermal run keeps T = T0 everywhere (no Joule heat: η applies to the
    // transient only here, so use η = 0 and no coupling).
    let mut steady = bar(n, seed, CURRENT, implicit, Vec::new());
    if let Some(e) = steady.electric.as_mut() {
        e.eta = 0.0;
        e.recouple_tolerance = None;
    }
    let model = model_of(&steady)?;
    let r = run_with(&steady, &model)?;
    let el = r
        .electric
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("no electric run"))?;
    let v = &el.report.electrode_potentials;
    let drop = ((v[0] - v[1]) / (CURRENT * r0) - 1.0).abs();
    // The transient at constant current.
    let heated = bar(n, seed, HEATING_CURRENT, implicit, times);
    let r = run_with(&heated, &model)?;
    let theta = mean_rises(&r)?
        .iter()
        .map(|&(t, mean)| (mean / (((lambda * t).exp() - 1.0) / BETA) - 1.0).abs())
        .fold(0.0, f64::max);
    let th = r
        .thermal
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("no thermal run"))?;
    let (lo, hi) = th
        .temperatures
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let solves = r.electric.as_ref().map_or(0, |e| e.report.solves);
    let switched = switched_heater(n, seed, &model, t_end)?;
    Ok(Row {
        particles: model.particles.len(),
        drop,
        switched,
        theta,
        solves,
        spread: (hi - lo) / (1.0 / BETA),
    })
}

/// The bar heated at V_ON until t_end/2, then not: max |θ̄/θ − 1| over the output times
/// after the first.
fn switched_heater(n: usize, seed: u64, model: &demcon_model::Model, t_end: f64) -> anyhow::Result<f64> {
    let t1 = 0.5 * t_end;
    let times: Vec<f64> = (1..=OUTPUTS).map(|k| t_end * k as f64 / OUTPUTS as f64).collect();
    let mut s = bar(
        n,
        seed,
        0.0,
        ThermalSolverConfig::Implicit {
            t_end,
            dt: t_end / 400.0,
            scheme: ImplicitSchemeConfig::BackwardEuler,
        },
        times,
    );
    s.materials[0].resistivity_temp_coeff = 0.0;
    s.outputs.times_at_breakpoints = true;
    if let Some(e) = s.electric.as_mut() {
        e.current = None;
        e.recouple_tolerance = None;
        e.electrodes[1].potential =
            TimedConfig::Table(vec![(0.0, V_ON), (t1, V_ON), (t1, 0.0), (t_end, 0.0)]);
    }
    let r = run_with(&s, model)?;
    let cap: f64 = 7900.0 * 500.0 * SIDE * SIDE * LENGTH;
    let p0 = V_ON * V_ON / (RHO_E * LENGTH / (SIDE * SIDE));
    Ok(mean_rises(&r)?
        .iter()
        .map(|&(t, mean)| (mean / (p0 * t.min(t1) / cap) - 1.0).abs())
        .fold(0.0, f64::max))
}

/// The capacity-weighted mean rise above T0 (K) at each output time (s) of a run.
fn mean_rises(r: &demcon_scene::RunResult) -> anyhow::Result<Vec<(f64, f64)>> {
    let th = r
        .thermal
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("no thermal run"))?;
    let caps = &r
        .thermal_setup
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("no setup"))?
        .capacities;
    let np = r.model.particles.len();
    let cap: f64 = caps[..np].iter().sum();
    Ok(th
        .snapshots
        .iter()
        .map(|(t, temps)| {
            let sum: f64 = temps.iter().zip(&caps[..np]).map(|(v, c)| c * (v - T0)).sum();
            (*t, sum / cap)
        })
        .collect())
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let sizes = ctx.pick(vec![5_000], vec![5_000, 40_000]);
    let study = Study::run(&sizes, |_| 3, ctx.seed, |n, seed, _| measure(n, seed))?;
    let mut out = CaseOutcome::new("current-control", ctx.mode);
    out.n_particles = study.rows().map(|r| r.particles).max().unwrap_or(0);
    out.tables.push(study.packings_table(
        "Current-controlled bar: the potential found, and the coupled ρ_e(T) transient at constant current",
        |r| r.particles,
        |c| {
            c.column("|ΔV/(I ρ_e L/A) − 1|", |(_, r): &(u64, &Row)| {
                format!("{:.1e}", r.drop)
            })
            .column("ρ_e(T) at constant I: max |θ̄/θ − 1|", |(_, r)| {
                format!("{:.2e}", r.theta)
            })
            .column("potential solves", |(_, r)| r.solves.to_string())
            .column("heater switched off: max |θ̄/θ − 1|", |(_, r)| {
                format!("{:.1e}", r.switched)
            })
            .column("(T_max − T_min) β at the end", |(_, r)| {
                format!("{:.1e}", r.spread)
            })
        },
    ));
    out.compare(Comparison::at_most(
        "potential drop vs I ρ_e L/A",
        study.worst(|r| r.drop),
        DROP_TOL,
        "exact (homogeneous bar)",
    ));
    out.compare(Comparison::at_most(
        "heater switched off by an electrode table: max |θ̄/θ − 1|",
        study.worst(|r| r.switched),
        SWITCH_TOL,
        "exact: θ = P0 min(t, t₁)/C",
    ));
    out.compare(Comparison::at_most(
        "ρ_e(T) at constant current: max |θ̄/θ − 1| over 20 times",
        study.worst(|r| r.theta),
        THETA_TOL,
        "exact: θ = (exp(β I² R0 t/C) − 1)/β",
    ));
    Ok(out)
}
