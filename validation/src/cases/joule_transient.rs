//! `joule-transient` — the time-accurate two-way electro-thermal coupling of a transient
//! (issue 5: ρ_e(T) = ρ_e0 (1 + β (T − T0)) with the potential re-solved during the run
//! whenever a temperature has moved by more than `electric.recouple_tolerance` since the last
//! solve). No paper figure: the reference is an exact solution.
//!
//! Setup: a box of touching equal spheres on a simple-cubic lattice (NX × NX columns of 4 NX
//! particles, AISI 304L with β = 4e-3 1/K), every thermal face adiabatic, the two end faces
//! held at 0 and V0 through face electrodes, the same calibrated surfaces S = d² for heat and
//! current. Every column is then a chain of equal resistances (the face links σ S/(d/2)
//! count as half a contact each) and every particle dissipates the same power (an end
//! particle gets half a contact's power and a whole face link's), so the temperature stays
//! uniform, R(T) = R0 (1 + β θ) exactly, and the total heat obeys
//! C dθ/dt = V0² / (R0 (1 + β θ)): θ(t) = (sqrt(1 + 2 β P0 t / C) − 1)/β, P0 = V0²/R0, with
//! C = Σ C_p the model's own capacities and R0 the network's own resistance at T0 (measured
//! by a one-way run: the check is of the coupling, not of R). The run ends when the
//! resistance has doubled (β θ = 1, 2 β P0 t / C = 3).
//!
//! Compared quantity: the largest relative error of the mean temperature rise over 20 output
//! times, explicit (forward Euler, automatic step) and implicit (backward Euler, t_end/400),
//! and the same for the one-way model (ρ_e frozen at T0: θ = P0 t / C, 50 % high at the end).
//!
//! Tolerance, derived a priori: (1) lag — the power in force was computed at a temperature at
//! most `tol` below the current one, a relative power excess of at most β tol/(1 + β θ); since
//! f(θ) = P/C decreases with θ, errors do not grow and the excess integrates to an error of θ
//! of at most tol ln(1 + β θ) ≤ β tol θ: a relative error ≤ β tol. (2) time stepping — with
//! the sources of each step's start, θ follows forward Euler on f with step Δt (the Laplacian
//! does nothing on a uniform field), whose global error for decreasing f is at most
//! (Δt/2) ∫ |f' f| dt ≤ (β P0 Δt / (2C)) θ: a relative error ≤ β P0 Δt/(2C). The bound is
//! their sum (plus 1e-9 for rounding). We choose tol = 0.25 K, β tol = 1e-3.
//!
//! Beside it (information, no check): the same coupled implicit run on a random packing of the
//! Hubert cylinder, where the Joule power is not uniform and the capacity-weighted mean rise
//! follows the ODE only approximately.

use std::time::Instant;

use demcon_core::{Container, ParticleSet, Vec3};
use demcon_scene::config::*;

use super::common::*;
use super::cylinder::*;
use crate::{CaseOutcome, Comparison, Ctx, Table};

/// ρ_e temperature coefficient β (1/K).
const BETA: f64 = 4e-3;
/// Re-solve tolerance (K): β tol = 1e-3.
const TOL: f64 = 0.25;
/// Potential difference (V).
const V0: f64 = 0.01;
/// Initial and reference temperature (°C).
const T0: f64 = 20.0;
/// Lattice spacing = sphere diameter (m).
const D: f64 = 1e-4;
/// Output times per run.
const OUTPUTS: usize = 20;

fn steel_beta() -> MaterialConfig {
    MaterialConfig {
        resistivity_temp_coeff: BETA,
        resistivity_ref_temp: T0,
        ..steel_304l()
    }
}

/// Writes the NX × NX × 4NX lattice into `dir` and returns its path.
fn write_lattice(dir: &std::path::Path, nx: usize) -> anyhow::Result<std::path::PathBuf> {
    let nz = 4 * nx;
    let mut centres = Vec::with_capacity(nx * nx * nz);
    for k in 0..nz {
        for j in 0..nx {
            for i in 0..nx {
                centres.push(Vec3::new(
                    (i as f64 + 0.5) * D,
                    (j as f64 + 0.5) * D,
                    (k as f64 + 0.5) * D,
                ));
            }
        }
    }
    let p = ParticleSet::new(centres.clone(), vec![0.5 * D; centres.len()])?;
    let c = Container::Box {
        size: [nx as f64 * D, nx as f64 * D, nz as f64 * D],
    };
    std::fs::create_dir_all(dir)?;
    let path = dir.join(format!("joule-transient-lattice-{nx}.xyzr"));
    demcon_packing::write_xyzr(&path, &p, &c)?;
    Ok(path)
}

/// The lattice scene: adiabatic, face electrodes, S = d² (C_t = 4/π) for heat and current.
fn lattice_scene(
    path: &std::path::Path,
    solver: ThermalSolverConfig,
    tol: Option<f64>,
    times: Vec<f64>,
) -> SceneConfig {
    let surface = SurfaceConfig::Calibrated {
        c_t: CtConfig::Value(4.0 / std::f64::consts::PI),
    };
    SceneConfig {
        name: "joule-transient".into(),
        seed: 1,
        packing: PackingConfig::File {
            path: path.to_string_lossy().into_owned(),
            container: None,
        },
        carve: None,
        carve_rule: CarveRuleConfig::WholeSphere,
        phase_rule: PhaseRuleConfig::Centre,
        contacts: ContactsConfig {
            coordination: None,
            tolerance: Some(0.01),
        },
        surface,
        materials: vec![steel_beta()],
        phases: Vec::new(),
        interface: InterfaceConfig::Harmonic,
        floating: FloatingConfig::Fail,
        thermal: Some(ThermalConfig {
            initial_temperature: T0,
            bcs: Vec::new(),
            sources: Vec::new(),
            solver,
        }),
        electric: Some(ElectricConfig {
            electrodes: face_electrodes(V0),
            eta: 1.0,
            surface,
            recouple_tolerance: tol,
        }),
        outputs: OutputsConfig {
            times,
            vtk: false,
            ..OutputsConfig::default()
        },
    }
}

/// Mean rise (capacity-weighted) at each snapshot: (t, θ̄).
fn rises(r: &RunResult) -> Vec<(f64, f64)> {
    let caps = &r.thermal_setup.as_ref().expect("thermal").capacities;
    let n = r.model.particles.len();
    let c: f64 = caps[..n].iter().sum();
    r.thermal
        .as_ref()
        .expect("thermal")
        .snapshots
        .iter()
        .map(|(t, v)| {
            let s: f64 = v.iter().zip(&caps[..n]).map(|(t, c)| c * (t - T0)).sum();
            (*t, s / c)
        })
        .collect()
}

/// One coupled run's measurements.
struct Coupled {
    err: f64,
    bound: f64,
    solves: usize,
    solves_s: f64,
    thermal_s: f64,
    steps: u64,
    dt: f64,
    r_end: f64,
    spread: f64,
    balance: f64,
}

fn coupled(
    cfg: &SceneConfig,
    model: &Model,
    exact: &dyn Fn(f64) -> f64,
    beta_p0_over_c: f64,
) -> anyhow::Result<(Coupled, Vec<(f64, f64)>)> {
    let r = run_with(cfg, model)?;
    let el = r.electric.as_ref().expect("electric");
    let th = r.thermal.as_ref().expect("thermal");
    let pts = rises(&r);
    let err = pts
        .iter()
        .map(|&(t, th)| (th / exact(t) - 1.0).abs())
        .fold(0.0, f64::max);
    let dt = th.report.dt;
    let r_end = el.report.resistance_ohm.unwrap_or(f64::NAN);
    // Spread over the particles in contact (rattlers carry no current and stay at T0).
    let deg = model.graph.degrees();
    let (lo, hi) = th
        .temperatures
        .iter()
        .zip(&deg)
        .filter(|(_, d)| **d > 0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (&v, _)| {
            (a.min(v), b.max(v))
        });
    let t_last = pts.last().map_or(f64::NAN, |p| p.0);
    Ok((
        Coupled {
            err,
            bound: BETA * TOL + 0.5 * beta_p0_over_c * dt + 1e-9,
            solves: el.report.solves,
            solves_s: el.report.solves_wall_s,
            thermal_s: th.report.wall_s,
            steps: th.report.steps,
            dt,
            r_end,
            spread: (hi - lo) / exact(t_last),
            balance: th.report.energy_balance_error,
        },
        pts,
    ))
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let t_start = Instant::now();
    let nx = ctx.pick(8, 16);
    let path = write_lattice(&ctx.out, nx)?;
    let mut out = CaseOutcome::new("joule-transient", ctx.mode);
    // R0 and C from a one-way run over a short time (any t_end: only the first solve matters).
    let probe_cfg = lattice_scene(
        &path,
        ThermalSolverConfig::Implicit {
            t_end: 1e-3,
            dt: 1e-3,
            scheme: ImplicitSchemeConfig::BackwardEuler,
        },
        None,
        Vec::new(),
    );
    let model = model_of(&probe_cfg)?;
    let n = model.particles.len();
    out.n_particles = n;
    let probe = run_with(&probe_cfg, &model)?;
    let r0 = probe
        .electric
        .as_ref()
        .and_then(|e| e.report.resistance_ohm)
        .ok_or_else(|| anyhow::anyhow!("no resistance: no current flowed"))?;
    let c: f64 = probe.thermal_setup.as_ref().expect("thermal").capacities[..n]
        .iter()
        .sum();
    let p0 = V0 * V0 / r0;
    let t_end = 1.5 * c / (BETA * p0);
    let exact = move |t: f64| ((1.0 + 2.0 * BETA * p0 * t / c).sqrt() - 1.0) / BETA;
    let times: Vec<f64> = (1..=OUTPUTS).map(|k| t_end * k as f64 / OUTPUTS as f64).collect();
    let explicit = ThermalSolverConfig::Explicit {
        t_end,
        dt: TimeStepConfig::Auto { safety: 0.8 },
    };
    let implicit = ThermalSolverConfig::Implicit {
        t_end,
        dt: t_end / 400.0,
        scheme: ImplicitSchemeConfig::BackwardEuler,
    };
    let bp = BETA * p0 / c;
    let (ex, pts_ex) = coupled(
        &lattice_scene(&path, explicit, Some(TOL), times.clone()),
        &model,
        &exact,
        bp,
    )?;
    let (im, pts_im) = coupled(
        &lattice_scene(&path, implicit, Some(TOL), times.clone()),
        &model,
        &exact,
        bp,
    )?;
    // One-way: ρ_e frozen at T0 (the same run without recouple_tolerance).
    let t_ow = Instant::now();
    let ow = run_with(&lattice_scene(&path, implicit, None, times.clone()), &model)?;
    let ow_s = t_ow.elapsed().as_secs_f64();
    let pts_ow = rises(&ow);
    // The plain explicit run (no coupling, no per-step check) for the cost of the coupling.
    let ow_ex = run_with(&lattice_scene(&path, explicit, None, times.clone()), &model)?;
    let ow_ex_s = ow_ex.thermal.as_ref().expect("thermal").report.wall_s;
    let check_overhead = (ex.thermal_s - ex.solves_s) / ow_ex_s - 1.0;
    let err_ow = pts_ow
        .iter()
        .map(|&(t, th)| (th / exact(t) - 1.0).abs())
        .fold(0.0, f64::max);
    let r_end = |c: &Coupled| c.r_end / r0;

    // Information: the Hubert cylinder, random packing, face electrodes, implicit.
    let n_pack = ctx.pick(2000, 10_000);
    let mut pack_cfg = electric_scene(
        "joule-transient-packing",
        ctx.seed,
        n_pack,
        None,
        SurfaceConfig::TerrerosAlpha,
        V0,
    );
    pack_cfg.materials = vec![steel_beta()];
    pack_cfg.thermal = Some(ThermalConfig {
        initial_temperature: T0,
        bcs: Vec::new(),
        sources: Vec::new(),
        solver: ThermalSolverConfig::Implicit {
            t_end: 1e-3,
            dt: 1e-3,
            scheme: ImplicitSchemeConfig::BackwardEuler,
        },
    });
    if let Some(e) = pack_cfg.electric.as_mut() {
        e.electrodes = face_electrodes(V0);
    }
    let pack_model = model_of(&pack_cfg)?;
    let pack_probe = run_with(&pack_cfg, &pack_model)?;
    let pr0 = pack_probe
        .electric
        .as_ref()
        .and_then(|e| e.report.resistance_ohm)
        .ok_or_else(|| anyhow::anyhow!("no resistance: no current flowed"))?;
    let pn = pack_model.particles.len();
    let pc: f64 = pack_probe.thermal_setup.as_ref().expect("thermal").capacities[..pn]
        .iter()
        .sum();
    let pp0 = V0 * V0 / pr0;
    let pt_end = 1.5 * pc / (BETA * pp0);
    let pexact = move |t: f64| ((1.0 + 2.0 * BETA * pp0 * t / pc).sqrt() - 1.0) / BETA;
    if let Some(t) = pack_cfg.thermal.as_mut() {
        t.solver = ThermalSolverConfig::Implicit {
            t_end: pt_end,
            dt: pt_end / 400.0,
            scheme: ImplicitSchemeConfig::BackwardEuler,
        };
    }
    pack_cfg.outputs.times = (1..=OUTPUTS)
        .map(|k| pt_end * k as f64 / OUTPUTS as f64)
        .collect();
    if let Some(e) = pack_cfg.electric.as_mut() {
        e.recouple_tolerance = Some(TOL);
    }
    let (pk, _) = coupled(&pack_cfg, &pack_model, &pexact, BETA * pp0 / pc)?;
    let pk_spread = pk.spread;

    out.metric("max_rel_error_explicit", ex.err);
    out.metric("max_rel_error_implicit", im.err);
    out.metric("max_rel_error_one_way", err_ow);
    out.metric("bound_explicit", ex.bound);
    out.metric("bound_implicit", im.bound);
    out.metric("resolves_explicit", ex.solves);
    out.metric("resolves_implicit", im.solves);
    out.metric("resolve_wall_s_explicit", ex.solves_s);
    out.metric("resolve_wall_s_implicit", im.solves_s);
    out.metric("thermal_wall_s_explicit", ex.thermal_s);
    out.metric("thermal_wall_s_implicit", im.thermal_s);
    out.metric("one_way_wall_s", ow_s);
    out.metric("one_way_explicit_wall_s", ow_ex_s);
    out.metric("explicit_check_overhead", check_overhead);
    out.metric("r_end_over_r0_explicit", r_end(&ex));
    out.metric("r_end_over_r0_implicit", r_end(&im));
    out.metric("max_rel_error_packing_implicit", pk.err);
    out.metric("temperature_spread_packing", pk_spread);
    out.metric("temperature_spread_lattice", ex.spread.max(im.spread));
    out.metric("resolves_packing", pk.solves);
    out.metric(
        "energy_balance_error_max",
        ex.balance.max(im.balance).max(pk.balance),
    );
    out.reference(
        "theta",
        "exact: (sqrt(1 + 2 β P0 t / C) − 1)/β, R0 and C of the model",
    );
    out.compare(Comparison::at_most(
        "explicit coupled: max |θ̄/θ_exact − 1|",
        ex.err,
        ex.bound,
        "a priori: β tol (lag) + β P0 Δt/(2C) (forward Euler on θ)",
    ));
    out.compare(Comparison::at_most(
        "implicit coupled: max |θ̄/θ_exact − 1|",
        im.err,
        im.bound,
        "a priori: β tol (lag) + β P0 Δt/(2C) (sources of the step start)",
    ));
    out.compare(Comparison::at_most(
        "energy balance of the coupled runs",
        ex.balance.max(im.balance).max(pk.balance),
        1e-8,
        "the ledger integrates the sources in force over each step",
    ));
    let row = |name: &str, c: &Coupled| {
        vec![
            name.to_string(),
            format!("{:.3e}", c.err),
            format!("{:.3e}", c.bound),
            c.steps.to_string(),
            format!("{:.3e}", c.dt),
            c.solves.to_string(),
            format!("{:.3}", c.solves_s),
            format!("{:.3}", c.thermal_s),
            format!("{:.4}", c.r_end / if name.contains("packing") { pr0 } else { r0 }),
        ]
    };
    out.tables.push(Table {
        title: format!(
            "Coupled transients against the exact θ(t): lattice {nx}×{nx}×{} = {n} particles; packing N = {pn}",
            4 * nx
        ),
        header: [
            "run",
            "max rel. error",
            "a priori bound",
            "steps",
            "Δt (s)",
            "potential solves",
            "their wall (s)",
            "thermal wall incl. solves (s)",
            "R_end / R0",
        ]
        .iter()
        .map(|h| h.to_string())
        .collect(),
        rows: vec![
            row("lattice, explicit, coupled", &ex),
            row("lattice, implicit BE, coupled", &im),
            vec![
                "lattice, implicit BE, one-way (ρ_e at T0)".into(),
                format!("{err_ow:.3e}"),
                "—".into(),
                ow.thermal.as_ref().map_or(0, |t| t.report.steps).to_string(),
                format!("{:.3e}", t_end / 400.0),
                "1".into(),
                "—".into(),
                format!("{ow_s:.3}"),
                "1".into(),
            ],
            row("packing (Hubert cylinder), implicit BE, coupled", &pk),
        ],
    });
    let mut series = vec![crate::chart::Series::line(
        "exact θ(t)",
        (0..=100)
            .map(|k| {
                let t = t_end * k as f64 / 100.0;
                (t, exact(t))
            })
            .collect(),
    )];
    series.push(crate::chart::Series::markers("explicit, coupled", pts_ex));
    series.push(crate::chart::Series::markers("implicit BE, coupled", pts_im));
    series.push(crate::chart::Series::markers("one-way (ρ_e at T0)", pts_ow));
    crate::chart::draw(
        &crate::chart::Chart {
            title: "Joule heating with ρ_e(T): mean temperature rise, lattice, adiabatic".into(),
            x_label: "t (s)".into(),
            y_label: "θ = T − T0 (K)".into(),
            x_scale: crate::chart::Scale::Linear,
            y_scale: crate::chart::Scale::Linear,
            series,
        },
        &ctx.out.join("joule-transient.png"),
    )?;
    out.charts.push("joule-transient.png".into());
    out.note(format!(
        "Mode {}: lattice {nx}×{nx}×{} of d = {D} m spheres (AISI 304L, β = {BETA} 1/K), V0 = {V0} V on face electrodes, \
         R0 = {:.5e} Ω, C = {c:.4e} J/K, P0 = {p0:.4e} W, t_end = {t_end:.4e} s (R doubles), tol = {TOL} K (β tol = {:.0e}). \
         The coupling re-solves about θ_end/tol = {:.0} times when steps are small; with fewer steps than that it re-solves \
         at most once per step. The check of max|ΔT| since the last solve is O(n) per step, beside the O(n Z) step itself: \
         the coupled explicit run minus its potential solves took {:.3} s against {ow_ex_s:.3} s for the plain explicit run \
         (overhead {:+.0} %, `explicit_check_overhead`). Whole case {:.1} s.",
        ctx.mode.name(),
        4 * nx,
        r0,
        BETA * TOL,
        1.0 / (BETA * TOL),
        ex.thermal_s - ex.solves_s,
        100.0 * check_overhead,
        t_start.elapsed().as_secs_f64(),
    ));
    out.note(format!(
        "Packing (information, no check): the Hubert cylinder with {pn} particles, Terreros surfaces, face electrodes, same \
         β, tol and V0, implicit BE with t_end/400. The Joule power per particle is not uniform there (surfaces and \
         neighbour counts vary), so the temperature is not uniform (spread (T_max − T_min)/θ_end = {pk_spread:.3} over the particles in contact) and R(T) \
         differs from R0 (1 + β θ̄) by the correlation of the local dissipation with the local rise: the capacity-weighted \
         mean rise follows the ODE only approximately (max relative error {:.2e}). The lattice isolates the coupling; the \
         packing shows what a user's scene does.",
        pk.err
    ));
    Ok(out)
}
