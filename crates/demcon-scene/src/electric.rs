//! Electric part of a scene: resistivities (optionally temperature-dependent), surfaces,
//! contact conductances S/(ρ_e d), electrodes, the potential solve and its Joule power.

use demcon_electric::{ElectricParams, joule_power, solve_potential};
use demcon_graph::{InterfaceRule, SurfaceModel, contact_surfaces, interface_value};
use serde::Serialize;

use crate::config::*;
use crate::convert;
use crate::error::SceneError;
use crate::model::Model;
use crate::thermal::{default_solve_params, extended_network, floating_policy};

/// What the electric solve gave.
#[derive(Debug, Clone)]
pub struct ElectricRun {
    /// Potential per particle (V); excluded (floating) particles carry 0 and are listed.
    pub potentials: Vec<f64>,
    /// Excluded particles.
    pub excluded: Vec<u32>,
    /// Current per contact (A), positive from p to q, then per face-electrode link (particle
    /// to face).
    pub branch_currents: Vec<f64>,
    /// Conductances 1/R (S): the contacts, then the face-electrode links.
    pub conductances: Vec<f64>,
    /// Joule power per particle (W), η applied.
    pub joule: Vec<f64>,
    /// Summary.
    pub report: ElectricReport,
    /// Findings (floating clusters…).
    pub diagnostics: Vec<String>,
}

/// Summary of an electric solve.
#[derive(Debug, Clone, Serialize)]
pub struct ElectricReport {
    /// Equivalent resistance ΔV/I (Ω), two electrodes only.
    pub resistance_ohm: Option<f64>,
    /// Current entering (A).
    pub current_in: f64,
    /// Current leaving (A).
    pub current_out: f64,
    /// |I_in − I_out| / I_in.
    pub current_mismatch: f64,
    /// Total Joule power (W).
    pub joule_w: f64,
    /// Solver.
    pub method: String,
    /// CG iterations.
    pub iterations: usize,
    /// Relative residual.
    pub residual: f64,
    /// Wall time of the solve (s).
    pub wall_s: f64,
    /// Potential solves in the run: 1 without ρ_e(T) coupling; with it, one per fixed-point
    /// round (steady) or the first plus every re-solve during the transient.
    pub solves: usize,
    /// Wall time of all those solves, conductances with ρ_e(T) and Joule power included (s).
    pub solves_wall_s: f64,
}

/// The surface model of the electric network (C_t calibrated on the model when `Auto`).
pub fn electric_surface_model(model: &Model, surface: &SurfaceConfig) -> Result<SurfaceModel, SceneError> {
    Ok(match surface {
        SurfaceConfig::TerrerosAlpha => SurfaceModel::TerrerosAlpha,
        SurfaceConfig::Calibrated {
            c_t: CtConfig::Value(c),
        } => SurfaceModel::Calibrated { c_t: *c },
        SurfaceConfig::Calibrated { c_t: CtConfig::Auto } => {
            let cal = crate::thermal::calibrate_ct(model)?;
            SurfaceModel::Calibrated { c_t: cal.c_t }
        }
    })
}

/// Electric conductivities σ = 1/ρ_e(T_p) of every particle (S/m): its own phase's and, for a
/// particle cut by a phase interface (`phase_rule` other than Centre), the other phase's with
/// the mix that combines them along a half-bond.
pub struct ParticleConductivities {
    /// σ of the particle's own phase (S/m).
    pub own: Vec<f64>,
    /// The interface mix and σ of the other phase (S/m), for cut particles.
    pub other: Vec<Option<(demcon_graph::Mix, f64)>>,
}

impl ParticleConductivities {
    /// Particle p's conductivity along the unit vector `e` over a half-bond of length `half`
    /// (m) (S/m).
    pub fn half_bond(&self, p: usize, e: &demcon_core::Vec3, half: f64) -> f64 {
        match &self.other[p] {
            Some((m, s)) => m.half_bond_value(self.own[p], *s, e, half),
            None => self.own[p],
        }
    }
}

/// Electric conductivities of every particle; `temperatures` (°C), when given, evaluate
/// ρ_e(T), else each material's ρ_e at its reference temperature.
pub fn particle_conductivities(
    model: &Model,
    temperatures: Option<&[f64]>,
) -> Result<ParticleConductivities, SceneError> {
    let n = model.particles.len();
    // σ = 1/ρ_e(T_p) of a phase at a particle's temperature.
    let sigma_of = |phase: u16, p: usize| -> Result<f64, SceneError> {
        let m = &model.materials.materials[phase as usize];
        let t = temperatures.map(|t| t[p]).unwrap_or(m.resistivity_ref_temp);
        let rho = m.resistivity_at(t).ok_or_else(|| {
            SceneError::invalid(
                &format!("materials[{}].resistivity", m.name),
                "none",
                "an electric scene needs it",
            )
        })?;
        if !(rho.is_finite() && rho > 0.0) {
            return Err(SceneError::invalid(
                &format!("materials[{}].resistivity", m.name),
                rho,
                format!("ρ_e(T = {t:.3}) must stay > 0: check resistivity_temp_coeff"),
            ));
        }
        Ok(1.0 / rho)
    };
    let lam = model.laminates();
    let mut own = Vec::with_capacity(n);
    let mut other = Vec::with_capacity(n);
    for p in 0..n {
        own.push(sigma_of(model.particles.phases[p], p)?);
        other.push(match lam.get(p) {
            Some(m) => Some((*m, sigma_of(m.other_phase, p)?)),
            None => None,
        });
    }
    Ok(ParticleConductivities { own, other })
}

/// Contact conductances 1/R_pq = S_pq / (ρ_e,pq d_pq) (S). `temperatures` (°C), when given,
/// evaluate ρ_e(T) per particle; the contact value combines the two particles' conductivities
/// by the interface rule (two half-bonds in series for the harmonic mean).
pub fn electric_conductances(
    model: &Model,
    surface: &SurfaceConfig,
    interface: InterfaceConfig,
    temperatures: Option<&[f64]>,
) -> Result<Vec<f64>, SceneError> {
    let sm = electric_surface_model(model, surface)?;
    let sigma = particle_conductivities(model, temperatures)?;
    contact_conductances(model, &sm, interface, &sigma)
}

fn contact_conductances(
    model: &Model,
    sm: &SurfaceModel,
    interface: InterfaceConfig,
    sigma: &ParticleConductivities,
) -> Result<Vec<f64>, SceneError> {
    let s = contact_surfaces(&model.graph, &model.particles, sm)?;
    let rule = match interface {
        InterfaceConfig::Harmonic => InterfaceRule::HarmonicMean,
        InterfaceConfig::Arithmetic => InterfaceRule::ArithmeticMean,
    };
    Ok(model
        .graph
        .pairs
        .iter()
        .zip(&model.graph.geometry)
        .zip(&s.area)
        .map(|((&[p, q], geo), &a)| {
            let (p, q) = (p as usize, q as usize);
            let half = 0.5 * geo.distance;
            let (sp, sq) = (
                sigma.half_bond(p, &geo.normal, half),
                sigma.half_bond(q, &(-geo.normal), half),
            );
            interface_value(sp, sq, rule) * a / geo.distance
        })
        .collect())
}

/// Solves the potential with the scene's electrodes; `temperatures` feed ρ_e(T).
///
/// Face electrodes add one node per face to the network (after the particles), held at the
/// potential and linked to the particles touching the face by half-contacts σ_p S_p / h_p
/// (the construction of the thermal `WallTemperature`, [`extended_network`]). The Joule
/// power of such a link goes wholly to its particle (the face is not a particle).
pub fn solve_electric(
    model: &Model,
    cfg: &ElectricConfig,
    interface: InterfaceConfig,
    floating: FloatingConfig,
    temperatures: Option<&[f64]>,
) -> Result<ElectricRun, SceneError> {
    let start = std::time::Instant::now();
    let n = model.particles.len();
    let sm = electric_surface_model(model, &cfg.surface)?;
    let sigma = particle_conductivities(model, temperatures)?;
    let g = contact_conductances(model, &sm, interface, &sigma)?;
    let faces: Vec<(demcon_core::Face, f64)> = cfg
        .electrodes
        .iter()
        .filter_map(|e| e.face.map(|f| (convert::face(f), e.potential)))
        .collect();
    let half_bond = |p: usize, e: &demcon_core::Vec3, h: f64| sigma.half_bond(p, e, h);
    let (ext, g, walls) = extended_network(model, &sm, &g, &half_bond, &faces, "electric.electrodes")?;
    let net = ext.as_ref().unwrap_or(&model.network);
    let mut walls_iter = walls.iter();
    let mut electrodes = Vec::new();
    for (i, e) in cfg.electrodes.iter().enumerate() {
        match (&e.select, &e.face) {
            (Some(select), None) => {
                let field = format!("electric.electrodes[{i}].select");
                let sel = convert::selector(select, &model.materials, &field)?;
                let ids = sel
                    .select_nonempty(&model.particles, &model.container, &format!("electrode {i}"))
                    .map_err(|err| SceneError::at(&field, err))?;
                electrodes.push((ids, e.potential));
            }
            (None, Some(_)) => {
                let w = walls_iter.next().expect("one wall per face electrode");
                electrodes.push((vec![w.node], e.potential));
            }
            _ => {
                return Err(SceneError::invalid(
                    &format!("electric.electrodes[{i}]"),
                    "select and face",
                    "give exactly one of `select` or `face`",
                ));
            }
        }
    }
    let params = ElectricParams {
        floating: floating_policy(floating),
        solve: default_solve_params(),
    };
    let sol = solve_potential(net, &g, &electrodes, &params)?;
    let mut joule = joule_power(net, &g, &sol.potentials, cfg.eta)?;
    // A wall link's power: the half booked to the wall node goes to the particle too.
    for w in &walls {
        let u_w = sol.potentials[w.node as usize];
        for (&p, &gw) in w.particles.iter().zip(&w.conductances) {
            let du = sol.potentials[p as usize] - u_w;
            joule[p as usize] += 0.5 * cfg.eta * gw * du * du;
        }
    }
    joule.truncate(n);
    let mut potentials = sol.potentials;
    potentials.truncate(n);
    let r = &sol.report;
    Ok(ElectricRun {
        report: ElectricReport {
            resistance_ohm: sol.resistance_ohm,
            current_in: sol.current_in,
            current_out: sol.current_out,
            current_mismatch: sol.current_mismatch,
            joule_w: joule.iter().sum(),
            method: r.method.to_string(),
            iterations: r.iterations,
            residual: r.relative_residual,
            wall_s: r.wall_s + r.setup_s,
            solves: 1,
            solves_wall_s: start.elapsed().as_secs_f64(),
        },
        diagnostics: sol.diagnostics.iter().map(|d| format!("electric: {d}")).collect(),
        potentials,
        excluded: sol.excluded,
        branch_currents: sol.branch_currents,
        conductances: g,
        joule,
    })
}
