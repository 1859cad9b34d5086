//! Electric part of a scene: resistivities (optionally temperature-dependent), surfaces,
//! contact conductances S/(ρ_e d), electrodes, the potential solve and its Joule power.

use demcon_electric::{ElectricParams, joule_power, solve_potential};
use demcon_graph::{InterfaceRule, SurfaceModel, contact_surfaces, interface_value};
use serde::Serialize;

use crate::config::*;
use crate::convert;
use crate::error::SceneError;
use crate::model::Model;
use crate::thermal::{default_solve_params, floating_policy};

/// What the electric solve gave.
#[derive(Debug, Clone)]
pub struct ElectricRun {
    /// Potential per particle (V); excluded (floating) particles carry 0 and are listed.
    pub potentials: Vec<f64>,
    /// Excluded particles.
    pub excluded: Vec<u32>,
    /// Current per contact (A), positive from p to q.
    pub branch_currents: Vec<f64>,
    /// Contact conductances 1/R (S).
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
    let sm = match surface {
        SurfaceConfig::TerrerosAlpha => SurfaceModel::TerrerosAlpha,
        SurfaceConfig::Calibrated {
            c_t: CtConfig::Value(c),
        } => SurfaceModel::Calibrated { c_t: *c },
        SurfaceConfig::Calibrated { c_t: CtConfig::Auto } => {
            let cal = crate::thermal::calibrate_ct(model)?;
            SurfaceModel::Calibrated { c_t: cal.c_t }
        }
    };
    let s = contact_surfaces(&model.graph, &model.particles, &sm)?;
    let rule = match interface {
        InterfaceConfig::Harmonic => InterfaceRule::HarmonicMean,
        InterfaceConfig::Arithmetic => InterfaceRule::ArithmeticMean,
    };
    let n = model.particles.len();
    // σ = 1/ρ_e(T_p) of each phase at a particle's temperature.
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
    let mut sigma = Vec::with_capacity(n);
    // (mix, σ of the other phase) of the laminate particles.
    let mut other = Vec::with_capacity(n);
    for p in 0..n {
        sigma.push(sigma_of(model.particles.phases[p], p)?);
        other.push(match lam.get(p) {
            Some(m) => Some((*m, sigma_of(m.other_phase, p)?)),
            None => None,
        });
    }
    // A laminate particle's half-bond uses its conductivity along the branch.
    let along = |p: usize, e: &demcon_core::Vec3, half: f64| match &other[p] {
        Some((m, s)) => m.half_bond_value(sigma[p], *s, e, half),
        None => sigma[p],
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
            interface_value(along(p, &geo.normal, half), along(q, &(-geo.normal), half), rule) * a
                / geo.distance
        })
        .collect())
}

/// Solves the potential with the scene's electrodes; `temperatures` feed ρ_e(T).
pub fn solve_electric(
    model: &Model,
    cfg: &ElectricConfig,
    interface: InterfaceConfig,
    floating: FloatingConfig,
    temperatures: Option<&[f64]>,
) -> Result<ElectricRun, SceneError> {
    let g = electric_conductances(model, &cfg.surface, interface, temperatures)?;
    let mut electrodes = Vec::new();
    for (i, e) in cfg.electrodes.iter().enumerate() {
        let field = format!("electric.electrodes[{i}].select");
        let sel = convert::selector(&e.select, &model.materials, &field)?;
        let ids = sel
            .select_nonempty(&model.particles, &model.container, &format!("electrode {i}"))
            .map_err(|err| SceneError::at(&field, err))?;
        electrodes.push((ids, e.potential));
    }
    let params = ElectricParams {
        floating: floating_policy(floating),
        solve: default_solve_params(),
    };
    let sol = solve_potential(&model.network, &g, &electrodes, &params)?;
    let joule = joule_power(&model.network, &g, &sol.potentials, cfg.eta)?;
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
        },
        diagnostics: sol.diagnostics.iter().map(|d| format!("electric: {d}")).collect(),
        potentials: sol.potentials,
        excluded: sol.excluded,
        branch_currents: sol.branch_currents,
        conductances: g,
        joule,
    })
}
