//! Calibration of the transmission-surface constant C_t on the model's own packing
//! (Haddad 2021 §2.1, eqs. 7–9), never copied from the paper.
//!
//! With C_t,arb = 1 the whole network (wall links included) scales linearly with C_t, so one
//! steady solve gives λ_e,arb and C_t = λ / λ_e,arb (λ = 1 W/(m·K) here).
//! - [`CalibrationBc::Particles`], the paper's protocol: a flux q on the top face and the
//!   bottom particles held at 0 (box: along y; cylinder: along its axis z); λ_e = q L / ΔT with
//!   ΔT the projected-area-weighted mean rise of the top layer.
//! - [`CalibrationBc::Walls`]: the two faces held at 0 and 1 through wall links;
//!   λ_e = Q L / (A ΔT) from the heat flow Q.
//! - A sphere container (both variants): a uniform volumetric source q with the surface held
//!   at 0 gives the mean temperature rise q R² / (15 λ_e).

use demcon_core::{Axis, Container, Face, Selector};
use demcon_graph::{SurfaceModel, conductances, contact_surfaces};
use demcon_network::{FloatingPolicy, SolveReport, homogenize, resolve_fixed};
use demcon_thermal::{face_flux_sources, solve_steady_temperature};
use serde::Serialize;

use crate::assembly::{default_solve_params, network_with_walls};
use crate::error::ModelError;
use crate::model::Model;

/// Result of a C_t calibration.
#[derive(Debug, Clone, Serialize)]
pub struct CtCalibration {
    /// Calibrated C_t = C_t,arb λ / λ_e (C_t,arb = 1), with L the sample length (the paper's definition).
    pub c_t: f64,
    /// The same with L the distance between the mean centres of the two boundary layers.
    pub c_t_centres: f64,
    /// How it was measured: `flux-y` / `flux-z` / `source` (particles), `walls-y` / `walls-z` /
    /// `source-wall` (walls).
    pub method: String,
    /// Effective conductivity measured with C_t,arb = 1 (W/(m·K)).
    pub lambda_e_arb: f64,
    /// Material conductivity λ (W/(m·K)).
    pub lambda: f64,
    /// Largest temperature rise of the solve (K).
    pub delta_t: f64,
    /// Steady-solve report.
    #[serde(skip)]
    pub solve: Option<SolveReport>,
    /// Steady-solve wall time (s).
    pub solve_s: f64,
    /// Steady-solve iterations.
    pub iterations: usize,
}

/// How the boundary temperatures of a calibration are applied.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum CalibrationBc {
    /// On the particles touching the faces (Haddad 2021 §2.1).
    Particles,
    /// On the faces themselves, through wall half-contacts (`WallTemperature`).
    Walls,
}

/// [`calibrate_ct_with`] the paper's way ([`CalibrationBc::Particles`]).
pub fn calibrate_ct(model: &Model) -> Result<CtCalibration, ModelError> {
    calibrate_ct_with(model, CalibrationBc::Particles)
}

/// A periodic packing: the homogenised tensor of the network with λ = 1 W/(m·K) everywhere
/// and C_t,arb = 1; C_t = 1 / (mean of its diagonal).
fn calibrate_periodic(model: &Model, volume: f64) -> Result<CtCalibration, ModelError> {
    let start = std::time::Instant::now();
    let s = contact_surfaces(
        &model.graph,
        &model.particles,
        &SurfaceModel::Calibrated { c_t: 1.0 },
    )?;
    let g = conductances(&model.graph, &s.area, &vec![1.0; model.graph.len()])?;
    let branches: Vec<_> = (0..model.graph.len()).map(|k| model.graph.branch(k)).collect();
    let h = homogenize(model.network(), &g, &branches, volume, &default_solve_params())?;
    let lambda_e = h.diagonal().iter().sum::<f64>() / 3.0;
    let c_t = 1.0 / lambda_e;
    Ok(CtCalibration {
        c_t,
        c_t_centres: c_t,
        method: "homogenized".into(),
        lambda_e_arb: lambda_e,
        lambda: 1.0,
        delta_t: 0.0,
        iterations: h.solves.iter().map(|r| r.iterations).sum(),
        solve: Some(h.solves[0].clone()),
        solve_s: start.elapsed().as_secs_f64(),
    })
}

/// The axis a calibration runs along: y for a box, z for a cylinder, none for a sphere (a
/// uniform source); a periodic box cannot be calibrated.
fn calibration_axis(container: &Container) -> Result<Option<Axis>, ModelError> {
    match container {
        Container::Box { .. } => Ok(Some(Axis::Y)),
        Container::Cylinder { .. } => Ok(Some(Axis::Z)),
        Container::Sphere { .. } => Ok(None),
        Container::Periodic { .. } => unreachable!("periodic packings are calibrated by homogenisation"),
    }
}

/// Calibrates C_t on the model's own packing (see the module doc for the two protocols).
pub fn calibrate_ct_with(model: &Model, bc: CalibrationBc) -> Result<CtCalibration, ModelError> {
    if let Some(l) = model.container.period() {
        return calibrate_periodic(model, l[0] * l[1] * l[2]);
    }
    let axis = calibration_axis(&model.container)?;
    let sm = SurfaceModel::Calibrated { c_t: 1.0 };
    let s = contact_surfaces(&model.graph, &model.particles, &sm)?;
    let g = conductances(&model.graph, &s.area, &vec![1.0; model.graph.pairs.len()])?;
    match bc {
        CalibrationBc::Particles => calibrate_particles(model, axis, g),
        CalibrationBc::Walls => calibrate_walls(model, axis, &sm, g),
    }
}

/// Particle-held calibration (the paper's protocol) with unit-λ conductances `g`.
fn calibrate_particles(model: &Model, axis: Option<Axis>, g: Vec<f64>) -> Result<CtCalibration, ModelError> {
    let particles = &model.particles;
    let select = |f: Face, what: &str| {
        Selector::Face(f)
            .select_nonempty(particles, &model.container, what)
            .map_err(|e| ModelError::at(&format!("{}.c_t", model.fields.surface), e))
    };
    let (method, fixed_ids, sources, lam_e, lam_e_centres);
    let q = 1.0; // W/m³ of solid (sphere) or W/m² (flux)
    let solve = |fixed: &[u32], src: &[f64]| {
        let constraints = resolve_fixed(model.network(), &[(fixed.to_vec(), 0.0)], FloatingPolicy::Exclude)?;
        Ok::<_, ModelError>(solve_steady_temperature(
            model.network(),
            &g,
            &constraints,
            src,
            &default_solve_params(),
        )?)
    };
    let steady = match axis {
        None => {
            let Container::Sphere { radius } = model.container else {
                unreachable!("calibration_axis: no axis only for a sphere")
            };
            fixed_ids = select(
                Face::Outer,
                "calibration: fixed temperature on the sphere surface",
            )?;
            sources = (0..particles.len())
                .map(|p| q * particles.volume(p) / model.phi)
                .collect::<Vec<f64>>();
            let steady = solve(&fixed_ids, &sources)?;
            // Volume-weighted mean over all particles (fixed ones at 0) of the rise.
            let mut fixed = vec![false; particles.len()];
            fixed_ids.iter().for_each(|&i| fixed[i as usize] = true);
            let (mut sum, mut w) = (0.0, 0.0);
            for (p, &t) in steady.solution.values.iter().enumerate() {
                let v = particles.volume(p);
                sum += v * if fixed[p] { 0.0 } else { t };
                w += v;
            }
            lam_e = q * radius * radius / (15.0 * (sum / w));
            lam_e_centres = lam_e;
            method = "source".to_string();
            steady
        }
        Some(axis) => {
            let (lo, hi) = Face::pair(axis);
            let (area, length) = model.container.section_and_length(axis).expect("box or cylinder");
            let what = |f: Face| format!("calibration: particles touching face {}", f.name());
            fixed_ids = select(lo, &what(lo))?;
            let top = select(hi, &what(hi))?;
            sources = face_flux_sources(particles, &top, q * area)?;
            let steady = solve(&fixed_ids, &sources)?;
            let k = axis.index();
            let mean_pos = |ids: &[u32]| {
                ids.iter().map(|&i| particles.centres[i as usize][k]).sum::<f64>() / ids.len() as f64
            };
            let l_centres = mean_pos(&top) - mean_pos(&fixed_ids);
            // Projected-area-weighted mean temperature of the top layer (the flux is shared
            // the same way).
            let (mut sum, mut w) = (0.0, 0.0);
            for &i in &top {
                let r = particles.radii[i as usize];
                let a = r * r;
                sum += a * steady.solution.values[i as usize];
                w += a;
            }
            let dt = sum / w;
            lam_e = q * length / dt;
            lam_e_centres = q * l_centres / dt;
            method = format!("flux-{}", if axis == Axis::Y { "y" } else { "z" });
            steady
        }
    };
    let report = steady.solution.report.clone();
    Ok(CtCalibration {
        c_t: 1.0 / lam_e,
        c_t_centres: 1.0 / lam_e_centres,
        method,
        lambda_e_arb: lam_e,
        lambda: 1.0,
        delta_t: steady.solution.values.iter().copied().fold(0.0, f64::max),
        solve_s: report.wall_s + report.setup_s,
        iterations: report.iterations,
        solve: Some(report),
    })
}

/// Wall-held calibration with unit-λ contact conductances `g`.
fn calibrate_walls(
    model: &Model,
    axis: Option<Axis>,
    sm: &SurfaceModel,
    g: Vec<f64>,
) -> Result<CtCalibration, ModelError> {
    let n = model.particles.len();
    let (method, faces, values, sources) = match axis {
        None => (
            "source-wall".to_string(),
            vec![Face::Outer],
            vec![0.0],
            (0..n).map(|p| model.particles.volume(p) / model.phi).collect(),
        ),
        Some(axis) => {
            let (lo, hi) = Face::pair(axis);
            (
                format!("walls-{}", if axis == Axis::Y { "y" } else { "z" }),
                vec![lo, hi],
                vec![0.0, 1.0],
                vec![0.0; n],
            )
        }
    };
    let walls = model.wall_contacts(&faces, model.fields.bcs)?;
    let wall_s = walls.surfaces(&model.particles, &model.graph.surface_degrees(), sm);
    let wall_g = walls.conductances(&wall_s, |_, _, _| 1.0);
    let (net, g) = network_with_walls(model, &walls, g, wall_g)?;
    let net = net.as_ref().unwrap_or_else(|| model.network());
    let mut src: Vec<f64> = sources;
    src.resize(net.n_nodes(), 0.0);
    let sets: Vec<(Vec<u32>, f64)> = (0..walls.n_walls())
        .map(|w| (vec![walls.node(w)], values[w]))
        .collect();
    let constraints = resolve_fixed(net, &sets, FloatingPolicy::Exclude)?;
    let steady = solve_steady_temperature(net, &g, &constraints, &src, &default_solve_params())?;
    let t = &steady.solution.values;
    let lam_e = match (axis, model.container) {
        (None, Container::Sphere { radius }) => {
            let mut excluded = vec![false; net.n_nodes()];
            constraints
                .excluded()
                .iter()
                .for_each(|&p| excluded[p as usize] = true);
            let (mut sum, mut w) = (0.0, 0.0);
            for (p, &tp) in t.iter().enumerate().take(n) {
                let v = model.particles.volume(p);
                if !excluded[p] {
                    sum += v * tp;
                }
                w += v;
            }
            radius * radius / (15.0 * sum / w)
        }
        (Some(axis), _) => {
            let (area, length) = model.container.section_and_length(axis).expect("box or cylinder");
            let q = demcon_network::boundary_flow(net, &g, t, &[walls.node(1)])?;
            q * length / area
        }
        (None, _) => unreachable!("calibration_axis: no axis only for a sphere"),
    };
    let report = steady.solution.report.clone();
    Ok(CtCalibration {
        c_t: 1.0 / lam_e,
        c_t_centres: 1.0 / lam_e,
        method,
        lambda_e_arb: lam_e,
        lambda: 1.0,
        delta_t: t.iter().copied().fold(0.0, f64::max),
        solve_s: report.wall_s + report.setup_s,
        iterations: report.iterations,
        solve: Some(report),
    })
}
