//! The run pipeline: builds only what the scene asks for, solves, post-processes.
//! Electric and thermal solvers never see each other: the Joule power vector and the
//! temperature-dependent resistivity are passed between them here.

use std::path::{Path, PathBuf};
use std::time::Instant;

use demcon_core::Vec3;
use demcon_post::{
    Domain, HaloParams, HaloPhases, HaloReport, Line, ProbeIndex, ProbeMethod, halo_flux, particle_dipoles,
};
use serde::Serialize;

use crate::config::*;
use crate::convert;
use crate::electric::{ElectricRun, solve_electric};
use crate::error::SceneError;
use crate::model::{Model, build_model};
use crate::thermal::{
    ThermalRun, ThermalSetup, section_and_length, solve_thermal, thermal_bcs, thermal_setup,
};

/// A loaded scene: its configuration and the folder relative paths are resolved against.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The parsed configuration.
    pub config: SceneConfig,
    /// Folder of the scene file.
    pub base_dir: PathBuf,
}

impl Scene {
    /// Reads and parses a RON scene file; errors carry the line and column.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.into(),
            source,
        })?;
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scene::parse(&text, path, base_dir)
    }

    /// Parses RON text (`path` is only used in messages).
    pub fn parse(text: &str, path: &Path, base_dir: PathBuf) -> Result<Scene, SceneError> {
        let config: SceneConfig = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str(text)
            .map_err(|e| SceneError::Parse {
                path: path.into(),
                line: e.span.start.line,
                col: e.span.start.col,
                message: e.code.to_string(),
            })?;
        let scene = Scene { config, base_dir };
        scene.validate()?;
        Ok(scene)
    }

    /// A scene from a configuration built in code (paths relative to `base_dir`).
    pub fn from_config(config: SceneConfig, base_dir: PathBuf) -> Result<Scene, SceneError> {
        let scene = Scene { config, base_dir };
        scene.validate()?;
        Ok(scene)
    }

    /// Checks what can be checked before any heavy work (materials, regions, selectors,
    /// solver parameters), so a typo does not surface after a long packing.
    pub fn validate(&self) -> Result<(), SceneError> {
        let c = &self.config;
        let materials = convert::materials(&c.materials)?;
        crate::model::contact_params(&c.contacts)?;
        if let Some(r) = &c.carve {
            convert::region(r, "carve")?;
        }
        // Phases name their material and region: check them before any packing.
        for (i, ph) in c.phases.iter().enumerate() {
            let (PhaseConfig::Region { material, .. } | PhaseConfig::Inclusions { material, .. }) = ph;
            materials
                .phase_of(material)
                .map_err(|e| SceneError::at(&format!("phases[{i}].material"), e))?;
            if let PhaseConfig::Region { region, .. } = ph {
                convert::region(region, &format!("phases[{i}].region"))?;
            }
        }
        // Probes must lie in the domain; with a generated packing it is known before packing.
        let domain = match (&c.carve, &c.packing) {
            (Some(r), _) => Some(convert::region(r, "carve")?),
            (None, PackingConfig::Generate { container, .. }) => {
                Some(convert::container(container, "packing.container")?.region())
            }
            _ => None,
        };
        if let Some(d) = domain {
            for (i, p) in c.outputs.probes.iter().enumerate() {
                let x = demcon_core::Vec3::new(p.point.0, p.point.1, p.point.2);
                if !d.contains_point(&x) {
                    return Err(SceneError::invalid(
                        &format!("outputs.probes[{i}].point ({})", p.name),
                        format!("{:?}", p.point),
                        "the probe point must lie inside the domain (container or carved region) (m)",
                    ));
                }
            }
        }
        if c.thermal.is_none() && c.electric.is_none() {
            return Err(SceneError::invalid(
                "thermal",
                "none",
                "a scene needs `thermal`, `electric` or both",
            ));
        }
        if let Some(t) = &c.thermal {
            for (i, bc) in t.bcs.iter().enumerate() {
                if let ThermalBcConfig::FixedTemperature { select, .. } = bc {
                    convert::selector(select, &materials, &format!("thermal.bcs[{i}].select"))?;
                }
            }
            match t.solver {
                ThermalSolverConfig::Explicit { t_end, dt } => {
                    positive_time("thermal.solver.t_end", t_end)?;
                    match dt {
                        TimeStepConfig::Auto { safety } if !(safety > 0.0 && safety <= 1.0) => {
                            return Err(SceneError::invalid(
                                "thermal.solver.dt.safety",
                                safety,
                                "must be in (0, 1]",
                            ));
                        }
                        TimeStepConfig::Fixed { dt, .. } => positive_time("thermal.solver.dt.dt", dt)?,
                        _ => {}
                    }
                }
                ThermalSolverConfig::Implicit { t_end, dt, .. } => {
                    positive_time("thermal.solver.t_end", t_end)?;
                    positive_time("thermal.solver.dt", dt)?;
                }
                ThermalSolverConfig::Steady => {}
            }
        }
        if let Some(e) = &c.electric {
            if !(0.0..=1.0).contains(&e.eta) {
                return Err(SceneError::invalid("electric.eta", e.eta, "must be in [0, 1]"));
            }
            if let Some(tol) = e.recouple_tolerance {
                if !(tol.is_finite() && tol > 0.0) {
                    return Err(SceneError::invalid(
                        "electric.recouple_tolerance",
                        tol,
                        "must be a finite temperature change > 0 (K)",
                    ));
                }
                if c.thermal.is_none() {
                    return Err(SceneError::invalid(
                        "electric.recouple_tolerance",
                        tol,
                        "re-solving with ρ_e(T) needs `thermal` physics to give the temperatures",
                    ));
                }
            }
            if e.electrodes.len() < 2 {
                return Err(SceneError::invalid(
                    "electric.electrodes",
                    format!("{} electrode(s)", e.electrodes.len()),
                    "at least two fixed potentials are needed for a current to flow",
                ));
            }
            for (i, m) in c.materials.iter().enumerate() {
                if m.resistivity.is_none() {
                    return Err(SceneError::invalid(
                        &format!("materials[{i}].resistivity"),
                        "none",
                        format!(
                            "material `{}` needs a resistivity (Ω·m) in an electric scene",
                            m.name
                        ),
                    ));
                }
            }
            for (i, el) in e.electrodes.iter().enumerate() {
                match (&el.select, &el.face) {
                    (Some(sel), None) => {
                        convert::selector(sel, &materials, &format!("electric.electrodes[{i}].select"))?;
                    }
                    (None, Some(_)) => {}
                    (sel, _) => {
                        return Err(SceneError::invalid(
                            &format!("electric.electrodes[{i}]"),
                            if sel.is_some() {
                                "both select and face"
                            } else {
                                "neither select nor face"
                            },
                            "give exactly one of `select` (particles held at the potential) or `face` (the container face held at it)",
                        ));
                    }
                }
                if !el.potential.is_finite() {
                    return Err(SceneError::invalid(
                        &format!("electric.electrodes[{i}].potential"),
                        el.potential,
                        "must be finite (V)",
                    ));
                }
            }
        }
        if let Some(k) = c.outputs.halo
            && !(k.is_finite() && k > 0.0)
        {
            return Err(SceneError::invalid(
                "outputs.halo",
                k,
                "the Halo/particle radius ratio must be > 0",
            ));
        }
        if let (Some(ph), None) = (c.outputs.halo_phases, c.outputs.halo) {
            return Err(SceneError::invalid(
                "outputs.halo_phases",
                format!("{ph:?}"),
                "only meaningful with a Halo: give `halo: Some(k)` too, or remove halo_phases",
            ));
        }
        Ok(())
    }
}

fn positive_time(field: &str, v: f64) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(field, v, "must be a finite time > 0 (s)"))
    }
}

/// A probe reading.
#[derive(Debug, Clone, Serialize)]
pub struct ProbeValue {
    /// Probe name.
    pub name: String,
    /// Field (`temperature`, `potential`, `flux_magnitude`, `halo_flux_magnitude`).
    pub field: String,
    /// Time (s); the final state of a steady run is at t = 0.
    pub t: f64,
    /// Value.
    pub value: f64,
}

/// A profile along a line.
#[derive(Debug, Clone, Serialize)]
pub struct ProfileValues {
    /// Profile name.
    pub name: String,
    /// Field.
    pub field: String,
    /// Time (s).
    pub t: f64,
    /// (distance from the start (m), value).
    pub points: Vec<(f64, f64)>,
}

/// Effective conductivity of a steady run.
#[derive(Debug, Clone, Serialize)]
pub struct EtcValue {
    /// Axis.
    pub axis: String,
    /// Heat flow through the hot face (W).
    pub heat_flow_w: f64,
    /// Cross-section (m²).
    pub area_m2: f64,
    /// Length (m).
    pub length_m: f64,
    /// Temperature difference (K).
    pub delta_t: f64,
    /// λ_e = (Q/A) L / ΔT (W/(m·K)).
    pub lambda_e: f64,
}

/// Everything a run produced, in memory.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// The model (particles, contacts, network).
    pub model: Model,
    /// Thermal network values, when the scene has thermal physics.
    pub thermal_setup: Option<ThermalSetup>,
    /// Resolved thermal boundary conditions and sources.
    pub thermal_bcs: Option<crate::thermal::ThermalBcs>,
    /// Thermal solution.
    pub thermal: Option<ThermalRun>,
    /// Electric solution.
    pub electric: Option<ElectricRun>,
    /// Per-particle physical heat flux (W/m²).
    pub flux: Option<Vec<Vec3>>,
    /// Halo-smoothed flux (W/m²) and whether each particle's Halo is cut by the boundary.
    pub halo: Option<(Vec<Vec3>, Vec<bool>, HaloReport)>,
    /// Effective conductivity.
    pub etc: Option<EtcValue>,
    /// Probe readings.
    pub probes: Vec<ProbeValue>,
    /// Profiles.
    pub profiles: Vec<ProfileValues>,
    /// Domain used for probes (container or carved region).
    pub domain: Domain,
    /// Non-fatal findings, printed by the CLI and stored in `summary.json`.
    pub diagnostics: Vec<String>,
    /// Wall time of the post-processing (s).
    pub post_s: f64,
    /// Wall time of the whole run (s).
    pub wall_s: f64,
}

/// Options of a run.
#[derive(Default)]
pub struct RunOptions<'a> {
    /// Packing progress callback.
    pub progress: Option<&'a dyn Fn(&demcon_packing::PackProgress)>,
}

/// Runs a scene end to end (in memory; see [`crate::write_outputs`] for files).
pub fn run(scene: &Scene, opts: &RunOptions<'_>) -> Result<RunResult, SceneError> {
    let t0 = Instant::now();
    let cfg = &scene.config;
    let model = build_model(cfg, &scene.base_dir, opts.progress)?;
    let mut result = run_on_model(cfg, model)?;
    result.wall_s = t0.elapsed().as_secs_f64();
    Ok(result)
}

/// Runs the physics and post-processing of `cfg` on an already built model (so one packing
/// can serve several solvers).
pub fn run_on_model(cfg: &SceneConfig, model: Model) -> Result<RunResult, SceneError> {
    let t0 = Instant::now();
    let mut diagnostics: Vec<String> = model.report.contacts.diagnostics.clone();
    if model.report.carved_away > 0 {
        diagnostics.push(format!("{} particles carved away", model.report.carved_away));
    }
    let output_times = &cfg.outputs.times;
    // Thermal setup first (C_t calibration), then the electric solve, then the thermal solve
    // with the Joule sources; with ρ_e(T), iterate until temperatures settle.
    let thermal_setup = match &cfg.thermal {
        Some(_) => {
            let s = thermal_setup(
                &model,
                &cfg.surface,
                cfg.interface,
                cfg.thermal.as_ref().expect("thermal"),
            )?;
            if s.clamped > 0 {
                diagnostics.push(format!(
                    "{} particles outside the Terreros table's 4–20 neighbours (α clamped)",
                    s.clamped
                ));
            }
            Some(s)
        }
        None => None,
    };
    let bcs = match &cfg.thermal {
        Some(t) => Some(thermal_bcs(
            &model,
            thermal_setup.as_ref().expect("setup"),
            t,
            cfg.floating,
        )?),
        None => None,
    };
    if let Some(b) = &bcs {
        diagnostics.extend(
            b.constraints
                .diagnostics()
                .iter()
                .map(|d| format!("thermal: {d}")),
        );
    }
    let mut electric: Option<ElectricRun> = None;
    let mut thermal: Option<ThermalRun> = None;
    match (&cfg.electric, &cfg.thermal) {
        (Some(e), None) => {
            electric = Some(solve_electric(&model, e, cfg.interface, cfg.floating, None)?);
        }
        (None, Some(t)) => {
            let (s, b) = (thermal_setup.as_ref().unwrap(), bcs.as_ref().unwrap());
            thermal = Some(solve_thermal(
                &model,
                s,
                b,
                &t.solver,
                t.initial_temperature,
                output_times,
                None,
            )?);
        }
        (Some(e), Some(t)) => {
            let (s, b) = (thermal_setup.as_ref().unwrap(), bcs.as_ref().unwrap());
            // Calibrate an `Auto` C_t of the electric surfaces once, not at every re-solve.
            let e = &resolved_surface(&model, e)?;
            let mut temps: Option<Vec<f64>> = None;
            let tol = e.recouple_tolerance;
            let transient = !matches!(t.solver, ThermalSolverConfig::Steady);
            // Steady with ρ_e(T): fixed-point rounds; transient with ρ_e(T): one coupled run
            // below (no rounds); without ρ_e(T): one round.
            let max_rounds = match (tol, transient) {
                (Some(_), true) => 0,
                (Some(_), false) => 50,
                (None, _) => 1,
            };
            if tol.is_none()
                && model
                    .materials
                    .materials
                    .iter()
                    .any(|m| m.resistivity_temp_coeff != 0.0)
            {
                diagnostics.push(
                    "electric: resistivity_temp_coeff is set but electric.recouple_tolerance is not: ρ_e was \
                     evaluated at resistivity_ref_temp (one-way coupling)"
                        .into(),
                );
            }
            if let (Some(tol), true) = (tol, transient) {
                let (el, th) = coupled_transient(&model, e, cfg, t, s, b, tol, output_times)?;
                let r = &el.report;
                diagnostics.push(format!(
                    "electro-thermal coupling: {} potential solves during the transient (re-solved whenever a \
                     temperature moved by more than {tol} K since the last one), {:.3} s",
                    r.solves, r.solves_wall_s
                ));
                electric = Some(el);
                thermal = Some(th);
            }
            for round in 0..max_rounds {
                let el = solve_electric(&model, e, cfg.interface, cfg.floating, temps.as_deref())?;
                let th = solve_thermal(
                    &model,
                    s,
                    b,
                    &t.solver,
                    t.initial_temperature,
                    output_times,
                    Some(&el.joule),
                )?;
                let moved = temps
                    .as_ref()
                    .map(|old| {
                        old.iter()
                            .zip(&th.temperatures)
                            .map(|(a, b)| (a - b).abs())
                            .fold(0.0, f64::max)
                    })
                    .unwrap_or(f64::INFINITY);
                temps = Some(th.temperatures.clone());
                let (solves, solves_s) = electric
                    .as_ref()
                    .map_or((0, 0.0), |p| (p.report.solves, p.report.solves_wall_s));
                let mut el = el;
                el.report.solves += solves;
                el.report.solves_wall_s += solves_s;
                electric = Some(el);
                thermal = Some(th);
                if let Some(tol) = tol {
                    if moved <= tol {
                        diagnostics.push(format!(
                            "electro-thermal coupling converged in {} rounds (ΔT ≤ {tol} K)",
                            round + 1
                        ));
                        break;
                    }
                    if round + 1 == max_rounds {
                        return Err(SceneError::invalid(
                            "electric.recouple_tolerance",
                            tol,
                            format!(
                                "the coupling did not settle in {max_rounds} rounds (last change {moved:.3e} K)"
                            ),
                        ));
                    }
                }
            }
        }
        (None, None) => unreachable!("validated: a scene has thermal or electric physics"),
    }
    if let Some(el) = &electric {
        diagnostics.extend(el.diagnostics.iter().cloned());
    }

    // Post-processing: only what the outputs ask for.
    let tp = Instant::now();
    let domain = match &cfg.carve {
        Some(r) => Domain::of_region(convert::region(r, "carve")?),
        None => Domain::of_container(&model.container)?,
    };
    let branches: Vec<Vec3> = (0..model.graph.pairs.len())
        .map(|k| model.graph.branch(k))
        .collect();
    let want_flux = cfg.outputs.flux || cfg.outputs.halo.is_some();
    let (mut flux, mut halo) = (None, None);
    if let (true, Some(th), Some(s)) = (want_flux, &thermal, &thermal_setup) {
        let m = model.graph.pairs.len();
        let mut d = particle_dipoles(
            &model.graph.pairs,
            &branches,
            &s.conductances[..m],
            &th.temperatures,
        )?;
        add_wall_dipoles(&model, s, &th.node_temperatures, &mut d);
        flux = Some(
            d.iter()
                .zip(&s.rep_volumes)
                .map(|(d, v)| -d / (2.0 * v))
                .collect::<Vec<Vec3>>(),
        );
        if let Some(k) = cfg.outputs.halo {
            let h = halo_flux(
                &model.particles,
                &d,
                &s.rep_volumes,
                &domain,
                &HaloParams {
                    ratio: k,
                    phases: match cfg.outputs.halo_phases.unwrap_or_default() {
                        HaloPhasesConfig::Same => HaloPhases::Same,
                        HaloPhasesConfig::All => HaloPhases::All,
                    },
                    ..HaloParams::default()
                },
            )?;
            halo = Some((h.flux, h.truncated, h.report));
        }
    }
    let etc = match (&cfg.outputs.etc_axis, &thermal, &thermal_setup, &bcs) {
        (Some(ax), Some(th), Some(s), Some(b)) => Some(effective_conductivity(&model, *ax, th, s, b)?),
        _ => None,
    };
    let rep = thermal_setup
        .as_ref()
        .map(|s| s.rep_volumes.clone())
        .unwrap_or_else(|| {
            (0..model.particles.len())
                .map(|p| model.particles.volume(p) / model.phi)
                .collect()
        });
    let index = ProbeIndex::new(&model.particles, &rep, &domain)?;
    let mut probes = Vec::new();
    let mut profiles = Vec::new();
    let mut fields: Vec<(String, f64, Vec<f64>)> = Vec::new();
    if let Some(th) = &thermal {
        for (t, v) in &th.snapshots {
            fields.push(("temperature".into(), *t, v.clone()));
        }
        if th.snapshots.last().map(|s| s.0) != Some(final_time(cfg)) {
            fields.push(("temperature".into(), final_time(cfg), th.temperatures.clone()));
        }
    }
    if let Some(el) = &electric {
        fields.push(("potential".into(), 0.0, el.potentials.clone()));
    }
    if let Some(f) = &flux {
        fields.push((
            "flux_magnitude".into(),
            final_time(cfg),
            f.iter().map(|v| v.norm()).collect(),
        ));
    }
    if let Some((h, _, _)) = &halo {
        fields.push((
            "halo_flux_magnitude".into(),
            final_time(cfg),
            h.iter().map(|v| v.norm()).collect(),
        ));
    }
    for (i, p) in cfg.outputs.probes.iter().enumerate() {
        let point = Vec3::new(p.point.0, p.point.1, p.point.2);
        let method = probe_method(p.method, &format!("outputs.probes[{i}].method"))?;
        for (field, t, values) in &fields {
            let value = index.probe(values, &point, &method).map_err(|e| {
                SceneError::invalid(
                    &format!("outputs.probes[{i}] ({})", p.name),
                    format!("{:?}", p.point),
                    e.to_string(),
                )
            })?;
            probes.push(ProbeValue {
                name: p.name.clone(),
                field: field.clone(),
                t: *t,
                value,
            });
        }
    }
    for (i, p) in cfg.outputs.profiles.iter().enumerate() {
        let line = Line {
            from: Vec3::new(p.from.0, p.from.1, p.from.2),
            to: Vec3::new(p.to.0, p.to.1, p.to.2),
            n_points: p.points,
        };
        let method = probe_method(p.method, &format!("outputs.profiles[{i}].method"))?;
        for (field, t, values) in &fields {
            let points = index.profile(values, &line, &method).map_err(|e| {
                SceneError::invalid(
                    &format!("outputs.profiles[{i}] ({})", p.name),
                    "line",
                    e.to_string(),
                )
            })?;
            profiles.push(ProfileValues {
                name: p.name.clone(),
                field: field.clone(),
                t: *t,
                points,
            });
        }
    }
    let post_s = tp.elapsed().as_secs_f64();
    Ok(RunResult {
        model,
        thermal_setup,
        thermal_bcs: bcs,
        thermal,
        electric,
        flux,
        halo,
        etc,
        probes,
        profiles,
        domain,
        diagnostics,
        post_s,
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

/// `e` with an `Auto` C_t of its surfaces replaced by the value calibrated on `model`.
fn resolved_surface(model: &Model, e: &ElectricConfig) -> Result<ElectricConfig, SceneError> {
    let mut e = e.clone();
    if let SurfaceConfig::Calibrated { c_t: CtConfig::Auto } = e.surface
        && let demcon_graph::SurfaceModel::Calibrated { c_t } =
            crate::electric::electric_surface_model(model, &e.surface)?
    {
        e.surface = SurfaceConfig::Calibrated {
            c_t: CtConfig::Value(c_t),
        };
    }
    Ok(e)
}

/// The time-accurate ρ_e(T) coupling of a transient: the potential is solved at the initial
/// temperatures, then re-solved (and the Joule sources replaced) after any step that leaves a
/// particle more than `tol` (K) away from its temperature at the last solve. The check is
/// O(n) per step, beside the O(n Z) step. Returns the last electric solve (the one in force at
/// the end, its report counting every solve) and the thermal run.
#[allow(clippy::too_many_arguments)]
fn coupled_transient(
    model: &Model,
    e: &ElectricConfig,
    cfg: &SceneConfig,
    t: &ThermalConfig,
    setup: &ThermalSetup,
    bcs: &crate::thermal::ThermalBcs,
    tol: f64,
    output_times: &[f64],
) -> Result<(ElectricRun, ThermalRun), SceneError> {
    let n = model.particles.len();
    let t_init = crate::thermal::initial_node_temperatures(model, setup, bcs, t.initial_temperature);
    let mut last_t = t_init[..n].to_vec();
    let mut el = solve_electric(model, e, cfg.interface, cfg.floating, Some(&last_t))?;
    let first_joule = el.joule.clone();
    let (mut solves, mut solves_s) = (1usize, el.report.solves_wall_s);
    let mut update = |_time: f64, temps: &[f64]| -> Result<Option<Vec<f64>>, SceneError> {
        let moved = temps[..n]
            .iter()
            .zip(&last_t)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        if moved <= tol {
            return Ok(None);
        }
        last_t.copy_from_slice(&temps[..n]);
        el = solve_electric(model, e, cfg.interface, cfg.floating, Some(&last_t))?;
        solves += 1;
        solves_s += el.report.solves_wall_s;
        Ok(Some(el.joule.clone()))
    };
    let th = crate::thermal::solve_thermal_with(
        model,
        setup,
        bcs,
        &t.solver,
        t.initial_temperature,
        output_times,
        Some(&first_joule),
        &mut update,
    )?;
    el.report.solves = solves;
    el.report.solves_wall_s = solves_s;
    Ok((el, th))
}

fn final_time(cfg: &SceneConfig) -> f64 {
    match cfg.thermal.as_ref().map(|t| t.solver) {
        Some(ThermalSolverConfig::Explicit { t_end, .. } | ThermalSolverConfig::Implicit { t_end, .. }) => {
            t_end
        }
        _ => 0.0,
    }
}

fn probe_method(m: ProbeMethodConfig, field: &str) -> Result<ProbeMethod, SceneError> {
    Ok(match m {
        ProbeMethodConfig::Nearest => ProbeMethod::Nearest,
        ProbeMethodConfig::Ball(r) => {
            if !(r.is_finite() && r > 0.0) {
                return Err(SceneError::invalid(field, r, "the ball radius must be > 0 (m)"));
            }
            ProbeMethod::BallAverage { radius: r }
        }
    })
}

/// λ_e = (Q/A) L / ΔT along `axis` from a steady run with fixed temperatures on the two
/// faces normal to it: Q is the heat flow out of the hot fixed set, ΔT the difference of the
/// two fixed values, L and A the container's length and cross-section.
fn effective_conductivity(
    model: &Model,
    axis: AxisConfig,
    th: &ThermalRun,
    s: &ThermalSetup,
    b: &crate::thermal::ThermalBcs,
) -> Result<EtcValue, SceneError> {
    let ax = convert::axis(axis);
    let (area, length) = section_and_length(&model.container, ax).ok_or_else(|| {
        SceneError::invalid(
            "outputs.etc_axis",
            format!("{axis:?}"),
            "the container has no flat faces normal to this axis",
        )
    })?;
    if b.fixed_sets.len() != 2 {
        return Err(SceneError::invalid(
            "outputs.etc_axis",
            format!("{axis:?}"),
            format!(
                "ETC needs exactly two fixed-temperature sets (found {})",
                b.fixed_sets.len()
            ),
        ));
    }
    let (hot, cold) = if b.fixed_sets[0].2 >= b.fixed_sets[1].2 {
        (0, 1)
    } else {
        (1, 0)
    };
    let q = demcon_network::boundary_flow(
        s.network(model),
        &s.conductances,
        &th.node_temperatures,
        &b.fixed_sets[hot].1,
    )?;
    let delta_t = b.fixed_sets[hot].2 - b.fixed_sets[cold].2;
    let lambda_e = demcon_post::effective_conductivity(q, area, length, delta_t)?;
    Ok(EtcValue {
        axis: format!("{axis:?}"),
        heat_flow_w: q,
        area_m2: area,
        length_m: length,
        delta_t,
        lambda_e,
    })
}

/// Adds the wall links' share to the particle dipoles D_p = Σ g (T_q − T_p) ℓ_pq: a link of
/// conductance g_w over the half-length h is the bond to the mirror image at 2h, of
/// conductance g_w/2 and temperature difference 2 (T_w − T_p), so it adds
/// 2 g_w (T_w − T_p) h n (n the outward normal of the face).
fn add_wall_dipoles(model: &Model, s: &ThermalSetup, node_t: &[f64], d: &mut [Vec3]) {
    for w in &s.walls {
        let tw = node_t[w.node as usize];
        for (&p, &g) in w.particles.iter().zip(&w.conductances) {
            let pu = p as usize;
            let c = model.particles.centres[pu];
            let Some(h) = model.container.face_distance(w.face, &c) else {
                continue;
            };
            let n = outward_normal(&model.container, w.face, &c);
            d[pu] += 2.0 * g * (tw - node_t[pu]) * h.max(0.5 * model.particles.radii[pu]) * n;
        }
    }
}

/// Outward unit normal of a container face at (the projection of) point `c`.
fn outward_normal(container: &demcon_core::Container, face: demcon_core::Face, c: &Vec3) -> Vec3 {
    use demcon_core::Face;
    match face {
        Face::XMin => -Vec3::x(),
        Face::XMax => Vec3::x(),
        Face::YMin => -Vec3::y(),
        Face::YMax => Vec3::y(),
        Face::ZMin => -Vec3::z(),
        Face::ZMax => Vec3::z(),
        Face::Outer => {
            let r = match container {
                demcon_core::Container::Cylinder { .. } => Vec3::new(c.x, c.y, 0.0),
                _ => *c,
            };
            let l = r.norm();
            if l > 0.0 { r / l } else { Vec3::x() }
        }
    }
}
