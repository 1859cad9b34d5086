//! Thermal part of a scene: surfaces (with the C_t calibration), conductances, heat
//! capacities, boundary conditions and the three solvers.

use std::time::Instant;

use demcon_core::{Axis, Container, Face, Selector};
use demcon_graph::{
    InterfaceRule, SurfaceModel, conductances, contact_property_laminate, contact_surfaces,
    representative_volumes, surface_calibrated, terreros_alpha,
};
use demcon_network::{Constraints, FloatingPolicy, Method, SolveParams, SolveReport, resolve_fixed};
use demcon_thermal::{
    ExplicitParams, ImplicitParams, RepresentativeVolume, Scheme, TimeStep, capacities, face_flux_sources,
    paper_dt_estimate, run_explicit, run_implicit, solve_steady_temperature,
};
use demcon_thermal::{ThermalSystem, TransientInput, source_update_fn};
use serde::Serialize;

use crate::config::*;
use crate::convert;
use crate::error::SceneError;
use crate::model::Model;

/// Default steady/implicit solver: MIC-PCG below 10⁴ unknowns, smoothed-aggregation
/// AMG-PCG above (`Method::Auto`), to a relative residual of 1e-10.
pub fn default_solve_params() -> SolveParams {
    SolveParams {
        method: Method::Auto {
            rel_tol: 1e-10,
            max_iter: 200_000,
        },
    }
}

/// Result of a C_t calibration (Haddad 2021 §2.1, eqs. 7–9).
#[derive(Debug, Clone, Serialize)]
pub struct CtCalibration {
    /// Calibrated C_t = C_t,arb λ / λ_e (C_t,arb = 1), with L the sample length (the paper's definition).
    pub c_t: f64,
    /// The same with L the distance between the mean centres of the two boundary layers.
    pub c_t_centres: f64,
    /// How it was measured: `flux-y` (box), `flux-z` (cylinder) or `source` (sphere, uniform source).
    pub method: String,
    /// Effective conductivity measured with C_t,arb = 1 (W/(m·K)).
    pub lambda_e_arb: f64,
    /// Material conductivity λ (W/(m·K)).
    pub lambda: f64,
    /// Temperature rise measured (K).
    pub delta_t: f64,
    /// Steady-solve report.
    #[serde(skip)]
    pub solve: Option<SolveReport>,
    /// Steady-solve wall time (s).
    pub solve_s: f64,
    /// Steady-solve iterations.
    pub iterations: usize,
}

fn model_for(cfg: &SurfaceConfig, c_t: Option<f64>) -> SurfaceModel {
    match cfg {
        SurfaceConfig::TerrerosAlpha => SurfaceModel::TerrerosAlpha,
        SurfaceConfig::Calibrated { .. } => SurfaceModel::Calibrated {
            c_t: c_t.unwrap_or(1.0),
        },
    }
}

fn interface_rule(i: InterfaceConfig) -> InterfaceRule {
    match i {
        InterfaceConfig::Harmonic => InterfaceRule::HarmonicMean,
        InterfaceConfig::Arithmetic => InterfaceRule::ArithmeticMean,
    }
}

/// Particles touching the two faces normal to `axis` (min side, max side).
fn axis_faces(axis: Axis) -> (Face, Face) {
    match axis {
        Axis::X => (Face::XMin, Face::XMax),
        Axis::Y => (Face::YMin, Face::YMax),
        Axis::Z => (Face::ZMin, Face::ZMax),
    }
}

/// Cross-section area (m²) of the container normal to `axis` and its length along it (m).
pub fn section_and_length(container: &Container, axis: Axis) -> Option<(f64, f64)> {
    let e = container.bounds().extent();
    let k = axis.index();
    match container {
        Container::Box { .. } | Container::Periodic { .. } => Some((e.x * e.y * e.z / e[k], e[k])),
        Container::Cylinder { radius, length } if axis == Axis::Z => {
            Some((std::f64::consts::PI * radius * radius, *length))
        }
        _ => None,
    }
}

/// Turns steady temperatures into (λ_e with the sample length, λ_e with the centre-to-centre length).
type Measure = Box<dyn Fn(&[f64]) -> (f64, f64)>;

/// [`calibrate_ct_with`] the paper's way ([`CalibrationBc::Particles`]).
pub fn calibrate_ct(model: &Model) -> Result<CtCalibration, SceneError> {
    calibrate_ct_with(model, CalibrationBc::Particles)
}

/// How the boundary temperatures of a calibration are applied.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum CalibrationBc {
    /// On the particles touching the faces (Haddad 2021 §2.1).
    Particles,
    /// On the faces themselves, through wall half-contacts (`WallTemperature`).
    Walls,
}

/// Calibrates C_t on the model's own packing (never copied from the paper) with C_t,arb = 1
/// (the whole network, wall links included, scales linearly with C_t).
///
/// [`CalibrationBc::Particles`], the paper's protocol: a flux on the top face and a fixed
/// temperature on the bottom particles (box: along y; cylinder: along its axis z), steady
/// state, λ_e = φ L / ΔT with ΔT the mean top-layer rise. [`CalibrationBc::Walls`]: the two
/// faces held at 0 and 1 through wall links, λ_e = Q L / (A ΔT) from the heat flow Q. For a
/// sphere container (both variants) a uniform volumetric source q with the surface held at 0
/// gives the mean temperature rise q R² / (15 λ_e). C_t = λ / λ_e.
pub fn calibrate_ct_with(model: &Model, bc: CalibrationBc) -> Result<CtCalibration, SceneError> {
    if bc == CalibrationBc::Walls {
        return calibrate_ct_walls(model);
    }
    let t0 = Instant::now();
    let lambda = 1.0;
    let graph = &model.graph;
    let s = contact_surfaces(graph, &model.particles, &SurfaceModel::Calibrated { c_t: 1.0 })?;
    let lam = vec![lambda; graph.pairs.len()];
    let g = conductances(graph, &s.area, &lam)?;
    let n = model.particles.len();
    let (method, fixed_ids, sources, measure): (String, Vec<u32>, Vec<f64>, Measure) = match model.container {
        Container::Sphere { radius } => {
            let ids = Selector::Face(Face::Outer)
                .select_nonempty(
                    &model.particles,
                    &model.container,
                    "calibration: fixed temperature on the sphere surface",
                )
                .map_err(|e| SceneError::at("surface.c_t", e))?;
            let q = 1.0; // W/m³ of solid
            let src: Vec<f64> = (0..n)
                .map(|p| q * model.particles.volume(p) / model.phi)
                .collect();
            let fixed: Vec<bool> = {
                let mut f = vec![false; n];
                ids.iter().for_each(|&i| f[i as usize] = true);
                f
            };
            let vols: Vec<f64> = (0..n).map(|p| model.particles.volume(p)).collect();
            let meas = move |t: &[f64]| {
                // Volume-weighted mean over all particles (fixed ones at 0) of the rise.
                let (mut s, mut w) = (0.0, 0.0);
                for p in 0..t.len() {
                    s += vols[p] * if fixed[p] { 0.0 } else { t[p] };
                    w += vols[p];
                }
                let mean = s / w;
                let lam_e = q * radius * radius / (15.0 * mean);
                (lam_e, lam_e)
            };
            ("source".to_string(), ids, src, Box::new(meas))
        }
        Container::Box { .. } | Container::Cylinder { .. } => {
            let axis = if matches!(model.container, Container::Box { .. }) {
                Axis::Y
            } else {
                Axis::Z
            };
            let (lo, hi) = axis_faces(axis);
            let (area, length) = section_and_length(&model.container, axis).expect("box or cylinder");
            let what = |f: Face| format!("calibration: particles touching face {}", f.name());
            let bottom = Selector::Face(lo)
                .select_nonempty(&model.particles, &model.container, &what(lo))
                .map_err(|e| SceneError::at("surface.c_t", e))?;
            let top = Selector::Face(hi)
                .select_nonempty(&model.particles, &model.container, &what(hi))
                .map_err(|e| SceneError::at("surface.c_t", e))?;
            let q = 1.0; // W/m²
            let src = face_flux_sources(&model.particles, &top, q * area)?;
            let k = axis.index();
            let mean_pos = |ids: &[u32]| {
                ids.iter()
                    .map(|&i| model.particles.centres[i as usize][k])
                    .sum::<f64>()
                    / ids.len() as f64
            };
            let l_centres = mean_pos(&top) - mean_pos(&bottom);
            let radii: Vec<f64> = top.iter().map(|&i| model.particles.radii[i as usize]).collect();
            let top_ids = top.clone();
            let meas = move |t: &[f64]| {
                // Projected-area-weighted mean temperature of the top layer (the flux
                // is shared the same way).
                let (mut s, mut w) = (0.0, 0.0);
                for (j, &i) in top_ids.iter().enumerate() {
                    let a = radii[j] * radii[j];
                    s += a * t[i as usize];
                    w += a;
                }
                let dt = s / w;
                (q * length / dt, q * l_centres / dt)
            };
            (
                format!("flux-{}", if axis == Axis::Y { "y" } else { "z" }),
                bottom,
                src,
                Box::new(meas),
            )
        }
        Container::Periodic { .. } => {
            return Err(SceneError::invalid(
                "surface.c_t",
                "Auto",
                "C_t calibration needs a box, cylinder or sphere container; give `c_t: Value(..)` for periodic packings",
            ));
        }
    };
    let constraints = resolve_fixed(&model.network, &[(fixed_ids, 0.0)], FloatingPolicy::Exclude)?;
    let steady = solve_steady_temperature(
        &model.network,
        &g,
        &constraints,
        &sources,
        &default_solve_params(),
    )?;
    let (lam_e, lam_e_c) = measure(&steady.solution.values);
    let report = steady.solution.report.clone();
    let delta_t = steady.solution.values.iter().copied().fold(0.0, f64::max);
    let _ = t0;
    Ok(CtCalibration {
        c_t: lambda / lam_e,
        c_t_centres: lambda / lam_e_c,
        method,
        lambda_e_arb: lam_e,
        lambda,
        delta_t,
        solve_s: report.wall_s + report.setup_s,
        iterations: report.iterations,
        solve: Some(report),
    })
}

fn calibrate_ct_walls(model: &Model) -> Result<CtCalibration, SceneError> {
    let sm = SurfaceModel::Calibrated { c_t: 1.0 };
    let s = contact_surfaces(&model.graph, &model.particles, &sm)?;
    let lam = vec![1.0; model.graph.pairs.len()];
    let g = conductances(&model.graph, &s.area, &lam)?;
    let n = model.particles.len();
    let (method, walls, sources): (&str, Vec<(Face, f64)>, Vec<f64>) = match model.container {
        Container::Sphere { .. } => {
            let src = (0..n).map(|p| model.particles.volume(p) / model.phi).collect();
            ("source-wall", vec![(Face::Outer, 0.0)], src)
        }
        Container::Box { .. } => (
            "walls-y",
            vec![(Face::YMin, 0.0), (Face::YMax, 1.0)],
            vec![0.0; n],
        ),
        Container::Cylinder { .. } => (
            "walls-z",
            vec![(Face::ZMin, 0.0), (Face::ZMax, 1.0)],
            vec![0.0; n],
        ),
        Container::Periodic { .. } => {
            return Err(SceneError::invalid(
                "surface.c_t",
                "Auto",
                "C_t calibration needs a box, cylinder or sphere container; give `c_t: Value(..)` for periodic packings",
            ));
        }
    };
    let (net, g_ext, links) = extended_network(model, &sm, &g, &|_, _, _| 1.0, &walls, "thermal.bcs")?;
    let net = net.as_ref().unwrap_or(&model.network);
    let mut src = sources;
    src.resize(net.n_nodes(), 0.0);
    let sets: Vec<(Vec<u32>, f64)> = links.iter().map(|w| (vec![w.node], w.value)).collect();
    let constraints = resolve_fixed(net, &sets, FloatingPolicy::Exclude)?;
    let steady = solve_steady_temperature(net, &g_ext, &constraints, &src, &default_solve_params())?;
    let t = &steady.solution.values;
    let lam_e = match model.container {
        Container::Sphere { radius } => {
            let excluded: std::collections::BTreeSet<u32> = constraints.excluded().iter().copied().collect();
            let (mut sum, mut w) = (0.0, 0.0);
            for (p, &tp) in t.iter().enumerate().take(n) {
                let v = model.particles.volume(p);
                if !excluded.contains(&(p as u32)) {
                    sum += v * tp;
                }
                w += v;
            }
            radius * radius / (15.0 * sum / w)
        }
        _ => {
            let axis = if matches!(model.container, Container::Box { .. }) {
                Axis::Y
            } else {
                Axis::Z
            };
            let (area, length) = section_and_length(&model.container, axis).expect("box or cylinder");
            let q = demcon_network::boundary_flow(net, &g_ext, t, &[links[1].node])?;
            q * length / area
        }
    };
    let report = steady.solution.report.clone();
    Ok(CtCalibration {
        c_t: 1.0 / lam_e,
        c_t_centres: 1.0 / lam_e,
        method: method.to_string(),
        lambda_e_arb: lam_e,
        lambda: 1.0,
        delta_t: t.iter().copied().fold(0.0, f64::max),
        solve_s: report.wall_s + report.setup_s,
        iterations: report.iterations,
        solve: Some(report),
    })
}

/// A container face held at a temperature, linked to the particles touching it.
#[derive(Debug, Clone)]
pub struct WallLinks {
    /// The face.
    pub face: Face,
    /// Its value: temperature (°C) or potential (V).
    pub value: f64,
    /// Its node in the thermal network (after the particles).
    pub node: u32,
    /// Particles linked to it.
    pub particles: Vec<u32>,
    /// Link conductances λ_p S_p / h_p (W/K; S for an electrode).
    pub conductances: Vec<f64>,
}

/// The network with wall nodes (or `None`: the model's), all conductances (W/K), the walls.
pub type ExtendedNetwork = (Option<demcon_network::Network>, Vec<f64>, Vec<WallLinks>);

/// The network with one extra node per wall: the particles' contacts followed by the wall
/// links, each a half-contact λ_p(n) S_p / h_p from a particle touching the face (h_p its
/// centre-to-face distance, at least half its radius; S_p its own transmission surface of
/// model `sm`; λ_p(n) its conductivity along the face normal n). Returns `None` for the
/// network when there is no wall (the model's is used). `half_bond(p, e, h)` is particle p's
/// conductivity along the unit vector e over a half-bond of length h (W/(m·K) for heat, S/m
/// for current; a laminate particle's depends on e); `walls` the faces and their values (°C
/// or V); `field` names the scene entry in errors (`thermal.bcs`, `electric.electrodes`).
pub fn extended_network(
    model: &Model,
    sm: &SurfaceModel,
    contact_g: &[f64],
    half_bond: &dyn Fn(usize, &demcon_core::Vec3, f64) -> f64,
    walls: &[(Face, f64)],
    field: &str,
) -> Result<ExtendedNetwork, SceneError> {
    if walls.is_empty() {
        return Ok((None, contact_g.to_vec(), Vec::new()));
    }
    let n = model.particles.len();
    let degrees = model.graph.degrees();
    let mut edges = model.graph.pairs.clone();
    let mut g = contact_g.to_vec();
    let mut links = Vec::new();
    for (k, &(face, value)) in walls.iter().enumerate() {
        let node = (n + k) as u32;
        let ids = Selector::Face(face)
            .select_nonempty(
                &model.particles,
                &model.container,
                &format!("wall {} ({field})", face.name()),
            )
            .map_err(|e| SceneError::at(field, e))?;
        let mut gs = Vec::with_capacity(ids.len());
        for &p in &ids {
            let pu = p as usize;
            let r = model.particles.radii[pu];
            let h = model
                .container
                .face_distance(face, &model.particles.centres[pu])
                .unwrap_or(r)
                .max(0.5 * r);
            let area = match *sm {
                SurfaceModel::Calibrated { c_t } => surface_calibrated(c_t, r),
                SurfaceModel::TerrerosAlpha => terreros_alpha(degrees[pu] + 1).alpha * r * r,
            };
            let e = face_normal(&model.container, face, &model.particles.centres[pu]);
            let gp = half_bond(pu, &e, h) * area / h;
            edges.push([p, node]);
            g.push(gp);
            gs.push(gp);
        }
        links.push(WallLinks {
            face,
            value,
            node,
            particles: ids,
            conductances: gs,
        });
    }
    let net = demcon_network::Network::new(n + walls.len(), &edges)?;
    Ok((Some(net), g, links))
}

/// Outward unit normal of a container face at (the particle centred at) `c`.
fn face_normal(container: &Container, face: Face, c: &demcon_core::Vec3) -> demcon_core::Vec3 {
    use demcon_core::Vec3;
    match face {
        Face::XMin => -Vec3::x(),
        Face::XMax => Vec3::x(),
        Face::YMin => -Vec3::y(),
        Face::YMax => Vec3::y(),
        Face::ZMin => -Vec3::z(),
        Face::ZMax => Vec3::z(),
        Face::Outer => {
            let r = match container {
                Container::Cylinder { .. } => Vec3::new(c.x, c.y, 0.0),
                _ => *c,
            };
            if r.norm() > 0.0 { r.normalize() } else { Vec3::x() }
        }
    }
}

/// Conductances, capacities and volumes of the thermal network.
#[derive(Debug, Clone)]
pub struct ThermalSetup {
    /// The surface model used (C_t resolved).
    pub surface: SurfaceModel,
    /// Calibration, when C_t was `Auto`.
    pub calibration: Option<CtCalibration>,
    /// Transmission surface per contact (m²).
    pub areas: Vec<f64>,
    /// Contact conductivity λ per contact (W/(m·K)), interface rule applied.
    pub contact_lambda: Vec<f64>,
    /// Conductances (W/K): H = λ S / d per contact, then the wall links.
    pub conductances: Vec<f64>,
    /// The network with the wall nodes, when there are walls (else the model's is used).
    pub network: Option<demcon_network::Network>,
    /// Walls held at a temperature.
    pub walls: Vec<WallLinks>,
    /// Representative volume per particle (m³).
    pub rep_volumes: Vec<f64>,
    /// Heat capacity per node (J/K): particles, then 1 J/K for each (fixed) wall node.
    pub capacities: Vec<f64>,
    /// Particles whose neighbour count lay outside the Terreros table (clamped).
    pub clamped: usize,
    /// Haddad eq. 16 estimate of the critical step (s), for comparison only.
    pub paper_dt: Option<f64>,
}

/// Builds the thermal network values for a surface model (calibrating C_t when asked).
pub fn thermal_setup(
    model: &Model,
    surface: &SurfaceConfig,
    interface: InterfaceConfig,
    thermal: &ThermalConfig,
) -> Result<ThermalSetup, SceneError> {
    let walls: Vec<(Face, f64)> = thermal
        .bcs
        .iter()
        .filter_map(|bc| match bc {
            ThermalBcConfig::WallTemperature { face, value } => Some((convert::face(*face), *value)),
            _ => None,
        })
        .collect();
    let (c_t, calibration) = match surface {
        SurfaceConfig::Calibrated { c_t: CtConfig::Auto } => {
            let bc = if walls.is_empty() {
                CalibrationBc::Particles
            } else {
                CalibrationBc::Walls
            };
            let cal = calibrate_ct_with(model, bc)?;
            (Some(cal.c_t), Some(cal))
        }
        SurfaceConfig::Calibrated {
            c_t: CtConfig::Value(v),
        } => {
            if !(v.is_finite() && *v > 0.0) {
                return Err(SceneError::invalid(
                    "surface.c_t",
                    v,
                    "must be a finite number > 0",
                ));
            }
            (Some(*v), None)
        }
        SurfaceConfig::TerrerosAlpha => (None, None),
    };
    let sm = model_for(surface, c_t);
    let s = contact_surfaces(&model.graph, &model.particles, &sm)?;
    let lam_phase: Vec<f64> = model.materials.materials.iter().map(|m| m.conductivity).collect();
    let contact_lambda = contact_property_laminate(
        &model.graph,
        &model.particles.phases,
        &lam_phase,
        &model.mixes,
        interface_rule(interface),
    )?;
    let g = conductances(&model.graph, &s.area, &contact_lambda)?;
    let rep = representative_volumes(&model.graph, &model.particles, &sm, model.phi)?;
    let vols: Vec<f64> = (0..model.particles.len())
        .map(|p| model.particles.volume(p))
        .collect();
    let fv: Vec<f64> = vols.iter().zip(&rep).map(|(v, r)| (v / r).min(1.0)).collect();
    // Laminate particles: ρ and ρc mix arithmetically (c = ρc/ρ).
    let lam = model.laminates();
    let phases = &model.particles.phases;
    let rho_phase: Vec<f64> = model.materials.materials.iter().map(|m| m.density).collect();
    let rc_phase: Vec<f64> = model
        .materials
        .materials
        .iter()
        .map(|m| m.density * m.specific_heat)
        .collect();
    let rho: Vec<f64> = (0..vols.len())
        .map(|p| lam.arithmetic(p, phases, &rho_phase))
        .collect();
    let c: Vec<f64> = (0..vols.len())
        .map(|p| lam.arithmetic(p, phases, &rc_phase) / rho[p])
        .collect();
    let mut caps = capacities(&vols, &c, &rho, RepresentativeVolume::VolumeFraction(&fv))?;
    let half_bond = |p: usize, e: &demcon_core::Vec3, h: f64| lam.half_bond(p, phases, &lam_phase, e, h);
    let (network, g, walls) = extended_network(model, &sm, &g, &half_bond, &walls, "thermal.bcs")?;
    caps.resize(caps.len() + walls.len(), 1.0);
    let paper_dt = c_t.and_then(|ct| {
        let d_min = model
            .graph
            .geometry
            .iter()
            .map(|g| g.distance)
            .fold(f64::INFINITY, f64::min);
        // Diffusivity of the particle material a = λ/(c ρ_d), ρ_d = ρ_c/φ (Haddad eq. 10–16);
        // the largest over the phases.
        let a = model
            .materials
            .materials
            .iter()
            .map(|m| m.conductivity * model.phi / (m.specific_heat * m.density))
            .fold(0.0, f64::max);
        let z = model.graph.coordination();
        (d_min.is_finite() && z > 0.0).then(|| paper_dt_estimate(d_min, a, z, ct))
    });
    Ok(ThermalSetup {
        surface: sm,
        calibration,
        areas: s.area,
        contact_lambda,
        conductances: g,
        network,
        walls,
        rep_volumes: rep,
        capacities: caps,
        clamped: s.clamped,
        paper_dt,
    })
}

impl ThermalSetup {
    /// The thermal network: the model's, or the one extended with wall nodes.
    pub fn network<'a>(&'a self, model: &'a Model) -> &'a demcon_network::Network {
        self.network.as_ref().unwrap_or(&model.network)
    }
}

/// Resolved thermal boundary conditions and sources.
#[derive(Debug, Clone)]
pub struct ThermalBcs {
    /// Fixed temperatures and excluded floating clusters.
    pub constraints: Constraints,
    /// Heat sources per particle (W): imposed fluxes and volumetric sources.
    pub sources: Vec<f64>,
    /// Named fixed sets (label, ids, value °C) — for reporting and ETC.
    pub fixed_sets: Vec<(String, Vec<u32>, f64)>,
}

/// Floating policy of the scene.
pub fn floating_policy(f: FloatingConfig) -> FloatingPolicy {
    match f {
        FloatingConfig::Exclude => FloatingPolicy::Exclude,
        FloatingConfig::Fail => FloatingPolicy::Fail,
    }
}

/// Resolves the thermal boundary conditions of `cfg` on the model.
pub fn thermal_bcs(
    model: &Model,
    setup: &ThermalSetup,
    cfg: &ThermalConfig,
    floating: FloatingConfig,
) -> Result<ThermalBcs, SceneError> {
    let net = setup.network(model);
    let mut sources = vec![0.0; net.n_nodes()];
    let mut walls = setup.walls.iter();
    let mut sets = Vec::new();
    let mut fixed_sets = Vec::new();
    for (i, bc) in cfg.bcs.iter().enumerate() {
        let field = format!("thermal.bcs[{i}]");
        match bc {
            ThermalBcConfig::FixedTemperature { select, value } => {
                if !value.is_finite() {
                    return Err(SceneError::invalid(
                        &format!("{field}.value"),
                        value,
                        "must be a finite temperature",
                    ));
                }
                let sel = convert::selector(select, &model.materials, &format!("{field}.select"))?;
                let ids = sel
                    .select_nonempty(
                        &model.particles,
                        &model.container,
                        &format!("{field} (FixedTemperature)"),
                    )
                    .map_err(|e| SceneError::at(&format!("{field}.select"), e))?;
                fixed_sets.push((format!("{select:?}"), ids.clone(), *value));
                sets.push((ids, *value));
            }
            ThermalBcConfig::HeatFlux { face, flux } => {
                if !flux.is_finite() {
                    return Err(SceneError::invalid(
                        &format!("{field}.flux"),
                        flux,
                        "must be a finite flux density (W/m²)",
                    ));
                }
                let f = convert::face(*face);
                let ids = Selector::Face(f)
                    .select_nonempty(&model.particles, &model.container, &format!("{field} (HeatFlux)"))
                    .map_err(|e| SceneError::at(&format!("{field}.face"), e))?;
                let area = face_area(&model.container, f).ok_or_else(|| {
                    SceneError::invalid(
                        &format!("{field}.face"),
                        f.name(),
                        "this container has no such face",
                    )
                })?;
                let s = face_flux_sources(&model.particles, &ids, flux * area)?;
                sources.iter_mut().zip(&s).for_each(|(a, b)| *a += b);
            }
            ThermalBcConfig::WallTemperature { face, value } => {
                if !value.is_finite() {
                    return Err(SceneError::invalid(
                        &format!("{field}.value"),
                        value,
                        "must be a finite temperature",
                    ));
                }
                let w = walls
                    .next()
                    .expect("one wall link per WallTemperature, built by thermal_setup");
                debug_assert_eq!(w.face, convert::face(*face));
                fixed_sets.push((format!("Wall({:?})", face), vec![w.node], *value));
                sets.push((vec![w.node], *value));
            }
        }
    }
    for (i, src) in cfg.sources.iter().enumerate() {
        let field = format!("thermal.sources[{i}]");
        if !src.power_density.is_finite() {
            return Err(SceneError::invalid(
                &format!("{field}.power_density"),
                src.power_density,
                "must be finite (W/m³)",
            ));
        }
        let sel = convert::selector(&src.select, &model.materials, &format!("{field}.select"))?;
        let ids = sel
            .select_nonempty(&model.particles, &model.container, &field)
            .map_err(|e| SceneError::at(&format!("{field}.select"), e))?;
        for &p in &ids {
            sources[p as usize] += src.power_density * model.particles.volume(p as usize) / model.phi;
        }
    }
    if sets.is_empty()
        && !matches!(
            cfg.solver,
            ThermalSolverConfig::Explicit { .. } | ThermalSolverConfig::Implicit { .. }
        )
    {
        return Err(SceneError::invalid(
            "thermal.bcs",
            "no FixedTemperature or WallTemperature",
            "a steady thermal solve needs at least one fixed temperature",
        ));
    }
    let policy = match cfg.solver {
        // A transient run is well posed without fixed values: heat capacity holds each cluster.
        ThermalSolverConfig::Explicit { .. } | ThermalSolverConfig::Implicit { .. } if sets.is_empty() => {
            FloatingPolicy::Keep
        }
        _ => floating_policy(floating),
    };
    let constraints = resolve_fixed(net, &sets, policy)?;
    Ok(ThermalBcs {
        constraints,
        sources,
        fixed_sets,
    })
}

/// Area (m²) of a container face.
pub fn face_area(c: &Container, f: Face) -> Option<f64> {
    use std::f64::consts::PI;
    match (c, f) {
        (Container::Box { size }, _) if f != Face::Outer => {
            let k = match f {
                Face::XMin | Face::XMax => 0,
                Face::YMin | Face::YMax => 1,
                _ => 2,
            };
            Some(size[0] * size[1] * size[2] / size[k])
        }
        (Container::Cylinder { radius, .. }, Face::ZMin | Face::ZMax) => Some(PI * radius * radius),
        (Container::Cylinder { radius, length }, Face::Outer) => Some(2.0 * PI * radius * length),
        (Container::Sphere { radius }, Face::Outer) => Some(4.0 * PI * radius * radius),
        _ => None,
    }
}

/// What a thermal solve did and cost.
#[derive(Debug, Clone, Serialize)]
pub struct ThermalSolveReport {
    /// `forward-euler`, `backward-euler`, `crank-nicolson` or `steady`.
    pub scheme: String,
    /// Time steps (transient).
    pub steps: u64,
    /// Time step (s) (transient).
    pub dt: f64,
    /// Exact forward-Euler positivity bound min_p C_p / Σ H (s).
    pub dt_bound: f64,
    /// Haddad eq. 16 estimate (s).
    pub dt_paper: Option<f64>,
    /// Linear-solver iterations (implicit, steady).
    pub iterations: u64,
    /// Largest relative residual of the linear solves.
    pub residual: f64,
    /// Wall time (s).
    pub wall_s: f64,
    /// Explicit throughput (contact updates per second).
    pub contacts_per_s: f64,
    /// Energy balance error (fraction).
    pub energy_balance_error: f64,
    /// Particles excluded from the solve (floating clusters).
    pub excluded: usize,
}

/// Temperatures of a thermal solve.
#[derive(Debug, Clone)]
pub struct ThermalRun {
    /// Final temperatures of the particles (°C). Excluded particles keep their initial temperature.
    pub temperatures: Vec<f64>,
    /// Final temperatures of every network node: the particles, then the wall nodes (°C).
    pub node_temperatures: Vec<f64>,
    /// Snapshots at the requested output times (t, temperatures).
    pub snapshots: Vec<(f64, Vec<f64>)>,
    /// Cost and step data.
    pub report: ThermalSolveReport,
}

impl ThermalRun {
    /// A run from the final temperatures of every node (particles first, then wall nodes).
    fn from_nodes(
        n: usize,
        nodes: Vec<f64>,
        snapshots: Vec<(f64, Vec<f64>)>,
        report: ThermalSolveReport,
    ) -> Self {
        Self {
            temperatures: nodes[..n].to_vec(),
            node_temperatures: nodes,
            snapshots,
            report,
        }
    }
}

/// Runs the thermal solver of `solver` with `extra_sources` (W per particle, e.g. Joule heat)
/// added to the boundary sources.
pub fn solve_thermal(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    solver: &ThermalSolverConfig,
    initial: f64,
    output_times: &[f64],
    extra_sources: Option<&[f64]>,
) -> Result<ThermalRun, SceneError> {
    solve_thermal_with(
        model,
        setup,
        bcs,
        solver,
        initial,
        output_times,
        extra_sources,
        &mut |_, _| Ok(None),
    )
}

/// Extra sources that change during a transient: called after every time step with the time
/// (s) and the temperatures of every node (particles first, °C); returns new extra sources
/// (W per particle) for the following steps, or `None` to keep the current ones. An error
/// stops the run and is returned by [`solve_thermal_with`].
pub type ExtraSourceUpdate<'a> = dyn FnMut(f64, &[f64]) -> Result<Option<Vec<f64>>, SceneError> + 'a;

/// The initial temperature of every node of the thermal network (°C): `initial`, with the
/// fixed values imposed.
pub fn initial_node_temperatures(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    initial: f64,
) -> Vec<f64> {
    let mut t = vec![initial; setup.network(model).n_nodes()];
    bcs.constraints.impose(&mut t);
    t
}

/// [`solve_thermal`] whose extra sources are re-evaluated during a transient by `update`
/// (not called by the steady solve).
#[allow(clippy::too_many_arguments)]
pub fn solve_thermal_with(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    solver: &ThermalSolverConfig,
    initial: f64,
    output_times: &[f64],
    extra_sources: Option<&[f64]>,
    update: &mut ExtraSourceUpdate<'_>,
) -> Result<ThermalRun, SceneError> {
    let n = model.particles.len();
    let mut sources = bcs.sources.clone();
    if let Some(x) = extra_sources {
        sources.iter_mut().zip(x).for_each(|(a, b)| *a += b);
    }
    // The scene's error that stopped a run, returned instead of the solver's.
    let mut stopped: Option<SceneError> = None;
    let mut hook = |t: f64, temps: &[f64]| -> Result<Option<Vec<f64>>, demcon_thermal::ThermalError> {
        match update(t, temps) {
            Ok(None) => Ok(None),
            Ok(Some(extra)) => {
                let mut s = bcs.sources.clone();
                s.iter_mut().zip(&extra).for_each(|(a, b)| *a += b);
                Ok(Some(s))
            }
            Err(e) => {
                stopped = Some(e);
                Err(demcon_thermal::ThermalError::invalid(
                    "source update",
                    t,
                    "the run was stopped by the coupled solve",
                ))
            }
        }
    };
    if !initial.is_finite() {
        return Err(SceneError::invalid(
            "thermal.initial_temperature",
            initial,
            "must be finite",
        ));
    }
    let net = setup.network(model);
    let t_init = initial_node_temperatures(model, setup, bcs, initial);
    let mut snapshots = Vec::new();
    let excluded = bcs.constraints.excluded().len();
    let g = &setup.conductances;
    let caps = &setup.capacities;
    let report_of = |r: &demcon_thermal::TransientReport| ThermalSolveReport {
        scheme: r.scheme.to_string(),
        steps: r.steps,
        dt: r.dt,
        dt_bound: r.dt_bound,
        dt_paper: setup.paper_dt,
        iterations: r.solver_iterations,
        residual: r.max_relative_residual,
        wall_s: r.wall_s,
        contacts_per_s: r.contacts_per_s,
        energy_balance_error: r.energy_balance_error,
        excluded,
    };
    let tr = match *solver {
        ThermalSolverConfig::Explicit { t_end, dt } => {
            let step = match dt {
                TimeStepConfig::Auto { safety } => TimeStep::Auto { safety },
                TimeStepConfig::Fixed { dt, allow_unstable } => TimeStep::Fixed { dt, allow_unstable },
                TimeStepConfig::Paper { allow_unstable } => {
                    let dt = setup.paper_dt.ok_or_else(|| {
                        SceneError::invalid(
                            "thermal.solver.dt",
                            "Paper",
                            "the paper's estimate needs the Calibrated surface model",
                        )
                    })?;
                    TimeStep::Fixed { dt, allow_unstable }
                }
            };
            let params = ExplicitParams {
                t_end,
                dt: step,
                output_times: output_times.to_vec(),
                paper_dt: setup.paper_dt,
                ..ExplicitParams::default()
            };
            ThermalSystem::new(net, g, caps, &bcs.constraints).and_then(|system| {
                let input = TransientInput {
                    temperatures: &t_init,
                    sources: &sources,
                };
                let observer = |t, v: &[f64]| snapshots.push((t, v[..n].to_vec()));
                run_explicit(&system, input, &params, observer, source_update_fn(&mut hook))
            })
        }
        ThermalSolverConfig::Implicit { t_end, dt, scheme } => {
            let params = ImplicitParams {
                t_end,
                dt,
                scheme: match scheme {
                    ImplicitSchemeConfig::BackwardEuler => Scheme::BackwardEuler,
                    ImplicitSchemeConfig::CrankNicolson => Scheme::CrankNicolson,
                },
                output_times: output_times.to_vec(),
                solve: default_solve_params(),
            };
            ThermalSystem::new(net, g, caps, &bcs.constraints).and_then(|system| {
                let input = TransientInput {
                    temperatures: &t_init,
                    sources: &sources,
                };
                let observer = |t, v: &[f64]| snapshots.push((t, v[..n].to_vec()));
                run_implicit(&system, input, &params, observer, source_update_fn(&mut hook))
            })
        }
        ThermalSolverConfig::Steady => {
            let st = solve_steady_temperature(net, g, &bcs.constraints, &sources, &default_solve_params())?;
            let mut temps = st.solution.values;
            for &p in bcs.constraints.excluded() {
                temps[p as usize] = initial;
            }
            let r = &st.solution.report;
            let bound = demcon_thermal::stable_dt_bound(net, g, caps, &bcs.constraints)?;
            let report = ThermalSolveReport {
                scheme: "steady".into(),
                steps: 0,
                dt: 0.0,
                dt_bound: bound.dt_max,
                dt_paper: setup.paper_dt,
                iterations: r.iterations as u64,
                residual: r.relative_residual,
                wall_s: r.wall_s + r.setup_s,
                contacts_per_s: 0.0,
                energy_balance_error: st.balance_error,
                excluded,
            };
            return Ok(ThermalRun::from_nodes(n, temps, snapshots, report));
        }
    };
    // A scene error raised in the hook is returned in place of the solver's "stopped".
    let tr = match (tr, stopped) {
        (_, Some(e)) => return Err(e),
        (r, None) => r?,
    };
    Ok(ThermalRun::from_nodes(
        n,
        tr.temperatures,
        snapshots,
        report_of(&tr.report),
    ))
}
