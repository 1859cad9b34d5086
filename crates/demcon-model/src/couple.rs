//! Electro-thermal coupling: the Joule power of the electric solve heats the thermal network,
//! and with ρ_e(T) the temperatures change the resistivities.
//!
//! - Without `recouple_tolerance` (one-way): one electric solve at the materials' reference
//!   temperatures, then the thermal solve with its Joule power.
//! - Steady with `recouple_tolerance`: fixed-point rounds (electric at the last temperatures,
//!   then thermal) until no particle moved by more than the tolerance (at most
//!   [`MAX_STEADY_ROUNDS`]).
//! - Transient with `recouple_tolerance`: one time-accurate run; the potential is re-solved
//!   (and the Joule sources replaced) after any step that leaves a particle more than the
//!   tolerance away from its temperature at the last solve.

use crate::electric::{ElectricProblem, ElectricRun, solve_electric};
use crate::error::ModelError;
use crate::model::Model;
use crate::thermal::{
    ExtraSources, ThermalBcs, ThermalProblem, ThermalRun, ThermalSetup, initial_node_temperatures,
    solve_thermal_with,
};

/// Largest number of steady fixed-point rounds before the coupling is declared unsettled.
pub const MAX_STEADY_ROUNDS: usize = 50;

/// The coupled solution.
#[derive(Debug, Clone)]
pub struct Coupled {
    /// The last electric solve (the one in force at the end); its report counts every solve.
    pub electric: ElectricRun,
    /// The thermal solution.
    pub thermal: ThermalRun,
    /// What the coupling did (rounds, re-solves), as text.
    pub diagnostics: Vec<String>,
}

/// Solves the electric and thermal problems together (see the module doc).
///
/// Errors: any solve's; a steady coupling that does not settle in [`MAX_STEADY_ROUNDS`].
pub fn couple(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    thermal: &ThermalProblem,
    electric: &ElectricProblem,
) -> Result<Coupled, ModelError> {
    // Calibrate an `Auto` C_t of the electric surfaces once, not at every re-solve.
    let e = &electric.resolved(model)?;
    let mut diagnostics = Vec::new();
    if e.recouple_tolerance.is_none()
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
    let (el, th) = match (e.recouple_tolerance, thermal.solver.is_transient()) {
        (Some(tol), true) => {
            let (el, th) = coupled_transient(model, setup, bcs, thermal, e, tol)?;
            let r = &el.report;
            diagnostics.push(format!(
                "electro-thermal coupling: {} potential solves during the transient (re-solved whenever a \
                 temperature moved by more than {tol} K since the last one), {:.3} s",
                r.solves, r.solves_wall_s
            ));
            (el, th)
        }
        (Some(tol), false) => fixed_point(model, setup, bcs, thermal, e, tol, &mut diagnostics)?,
        (None, _) => {
            let el = solve_electric(model, e, None)?;
            let th = thermal_with_joule(model, setup, bcs, thermal, &el)?;
            (el, th)
        }
    };
    Ok(Coupled {
        electric: el,
        thermal: th,
        diagnostics,
    })
}

/// The thermal solve with the Joule power of `el` as extra sources.
fn thermal_with_joule(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    thermal: &ThermalProblem,
    el: &ElectricRun,
) -> Result<ThermalRun, ModelError> {
    solve_thermal_with(
        model,
        setup,
        bcs,
        thermal,
        ExtraSources {
            initial: Some(&el.joule),
            update: &mut |_, _| Ok(None),
        },
    )
}

/// Steady fixed-point rounds until no temperature moves by more than `tol` (K).
fn fixed_point(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    thermal: &ThermalProblem,
    e: &ElectricProblem,
    tol: f64,
    diagnostics: &mut Vec<String>,
) -> Result<(ElectricRun, ThermalRun), ModelError> {
    let mut temps: Option<Vec<f64>> = None;
    let (mut solves, mut solves_s) = (0, 0.0);
    for round in 0..MAX_STEADY_ROUNDS {
        let mut el = solve_electric(model, e, temps.as_deref())?;
        let th = thermal_with_joule(model, setup, bcs, thermal, &el)?;
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
        solves += el.report.solves;
        solves_s += el.report.solves_wall_s;
        el.report.solves = solves;
        el.report.solves_wall_s = solves_s;
        if moved <= tol {
            diagnostics.push(format!(
                "electro-thermal coupling converged in {} rounds (ΔT ≤ {tol} K)",
                round + 1
            ));
            return Ok((el, th));
        }
        if round + 1 == MAX_STEADY_ROUNDS {
            return Err(ModelError::invalid(
                "electric.recouple_tolerance",
                tol,
                format!(
                    "the coupling did not settle in {MAX_STEADY_ROUNDS} rounds (last change {moved:.3e} K)"
                ),
            ));
        }
    }
    unreachable!("the last round returns")
}

/// The time-accurate ρ_e(T) coupling of a transient: the potential is solved at the initial
/// temperatures, then re-solved (and the Joule sources replaced) after any step that leaves a
/// particle more than `tol` (K) away from its temperature at the last solve. The check is
/// O(n) per step, beside the O(n Z) step. Returns the last electric solve (the one in force at
/// the end, its report counting every solve) and the thermal run.
fn coupled_transient(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    thermal: &ThermalProblem,
    e: &ElectricProblem,
    tol: f64,
) -> Result<(ElectricRun, ThermalRun), ModelError> {
    let n = model.particles.len();
    let t_init = initial_node_temperatures(model, setup, bcs, thermal.initial_temperature);
    let mut last_t = t_init[..n].to_vec();
    let mut el = solve_electric(model, e, Some(&last_t))?;
    let first_joule = el.joule.clone();
    let (mut solves, mut solves_s) = (1usize, el.report.solves_wall_s);
    let mut update = |_time: f64, temps: &[f64]| -> Result<Option<Vec<f64>>, ModelError> {
        let moved = temps[..n]
            .iter()
            .zip(&last_t)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        if moved <= tol {
            return Ok(None);
        }
        last_t.copy_from_slice(&temps[..n]);
        el = solve_electric(model, e, Some(&last_t))?;
        solves += 1;
        solves_s += el.report.solves_wall_s;
        Ok(Some(el.joule.clone()))
    };
    let th = solve_thermal_with(
        model,
        setup,
        bcs,
        thermal,
        ExtraSources {
            initial: Some(&first_joule),
            update: &mut update,
        },
    )?;
    el.report.solves = solves;
    el.report.solves_wall_s = solves_s;
    Ok((el, th))
}
