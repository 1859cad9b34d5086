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
//!
//! Transients can hand out checkpoints and continue from one bit for bit
//! ([`couple_checkpointed`]); with re-solves the checkpoint carries the coupling's state
//! (the temperatures of the last potential solve, which is redone on resuming).

use std::cell::RefCell;

use demcon_graph::WallContacts;

use crate::checkpoint::{Checkpointing, CouplingState, RunCheckpoint, check_coupling, not_resumable};
use crate::electric::{ElectricProblem, ElectricRun, solve_electric};
use crate::error::ModelError;
use crate::model::Model;
use crate::thermal::{
    ExtraSources, ThermalBcs, ThermalProblem, ThermalRun, ThermalSetup, initial_node_temperatures,
    solve_thermal_checkpointed, solve_thermal_with,
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
    couple_checkpointed(model, setup, bcs, thermal, electric, None)
}

/// [`couple`], a transient handing out checkpoints on the schedule of `checkpointing` and
/// continuing from `checkpointing.resume` bit for bit (the electric solve in force is redone
/// from the checkpoint's coupling state, not counted again). A steady coupling refuses to
/// resume.
///
/// Errors: those of [`couple`]; a checkpoint whose coupling state does not fit the run.
pub fn couple_checkpointed(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    thermal: &ThermalProblem,
    electric: &ElectricProblem,
    checkpointing: Option<Checkpointing<'_, '_>>,
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
        (None, true) if e.tabled() => {
            // Electrode tables, ρ_e frozen: re-solved whenever a potential changes.
            let (el, th) = coupled_transient(model, setup, bcs, thermal, e, None, checkpointing)?;
            diagnostics.push(format!(
                "electric: {} potential solves during the transient (re-solved whenever an electrode's table \
                 changed its potential), {:.3} s",
                el.report.solves, el.report.solves_wall_s
            ));
            (el, th)
        }
        (Some(tol), true) => {
            let (el, th) = coupled_transient(model, setup, bcs, thermal, e, Some(tol), checkpointing)?;
            let r = &el.report;
            diagnostics.push(format!(
                "electro-thermal coupling: {} potential solves during the transient (re-solved whenever a \
                 temperature moved by more than {tol} K since the last one), {:.3} s",
                r.solves, r.solves_wall_s
            ));
            (el, th)
        }
        (Some(tol), false) => {
            if checkpointing.as_ref().is_some_and(|c| c.resume.is_some()) {
                return Err(not_resumable(
                    &model.fields,
                    "Steady (electro-thermal fixed point)",
                ));
            }
            fixed_point(model, setup, bcs, thermal, e, tol, &mut diagnostics)?
        }
        (None, _) => {
            if let Some(ck) = checkpointing.as_ref().and_then(|c| c.resume) {
                check_coupling(ck, false, model.particles.len(), &model.fields)?;
            }
            let el = solve_electric(model, e, None)?;
            let th = solve_thermal_checkpointed(
                model,
                setup,
                bcs,
                thermal,
                ExtraSources {
                    initial: Some(&el.joule),
                    update: &mut |_, _| Ok(None),
                },
                checkpointing,
            )?;
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
                model.fields.recouple_tolerance,
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
/// particle more than `tol` (K) away from its temperature at the last solve (`tol` `None`:
/// ρ_e frozen at its reference), or after which an electrode's table gives another potential
/// (the potentials read at the end of the step, for the next). The check is
/// O(n) per step, beside the O(n Z) step. Returns the last electric solve (the one in force at
/// the end, its report counting every solve) and the thermal run. Checkpoints carry the
/// temperatures of the last solve; resuming redoes that solve (uncounted).
fn coupled_transient(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    thermal: &ThermalProblem,
    e: &ElectricProblem,
    tol: Option<f64>,
    checkpointing: Option<Checkpointing<'_, '_>>,
) -> Result<(ElectricRun, ThermalRun), ModelError> {
    let n = model.particles.len();
    let resume = checkpointing.as_ref().and_then(|c| c.resume);
    // The temperatures ρ_e reads (none when frozen), and the potentials at a time.
    let rho_t = |t: &[f64]| -> Option<Vec<f64>> { tol.map(|_| t.to_vec()) };
    // A resumed run's last solve was at the checkpoint's potentials: every change re-solves.
    let t_start = resume.map_or(0.0, |ck| ck.transient.t);
    let last_t = match resume {
        Some(ck) => {
            check_coupling(ck, true, n, &model.fields)?;
            ck.coupling
                .as_ref()
                .map(|c| c.last_temperatures.clone())
                .unwrap_or_default()
        }
        None => {
            let nodes = initial_node_temperatures(model, setup, bcs, thermal.initial_temperature);
            WallContacts::particle_part(&nodes, n).to_vec()
        }
    };
    let el = solve_electric(model, &e.at(t_start), rho_t(&last_t).as_deref())?;
    let first_joule = el.joule.clone();
    let (solves, solves_s) = match resume.and_then(|ck| ck.coupling.as_ref()) {
        Some(c) => (c.solves as usize, c.solves_wall_s),
        None => (1usize, el.report.solves_wall_s),
    };
    // Shared by the source update and the checkpoints, which the solver calls in turn.
    let state = RefCell::new(Coupling {
        last_t,
        last_v: e.potentials_at(t_start),
        el,
        solves,
        solves_s,
    });
    let mut update = |time: f64, temps: &[f64]| -> Result<Option<Vec<f64>>, ModelError> {
        let mut c = state.borrow_mut();
        let temps = WallContacts::particle_part(temps, n);
        let moved = temps
            .iter()
            .zip(&c.last_t)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let v = e.potentials_at(time);
        if tol.is_none_or(|tol| moved <= tol) && v == c.last_v {
            return Ok(None);
        }
        c.last_t.copy_from_slice(temps);
        c.last_v = v;
        c.el = solve_electric(model, &e.at(time), rho_t(&c.last_t).as_deref())?;
        c.solves += 1;
        c.solves_s += c.el.report.solves_wall_s;
        Ok(Some(c.el.joule.clone()))
    };
    let extra = ExtraSources {
        initial: Some(&first_joule),
        update: &mut update,
    };
    let th = match checkpointing {
        Some(ck) => {
            let sink = ck.sink;
            let mut with_coupling = |mut r: RunCheckpoint| {
                let c = state.borrow();
                r.coupling = Some(CouplingState {
                    last_temperatures: c.last_t.clone(),
                    solves: c.solves as u64,
                    solves_wall_s: c.solves_s,
                });
                drop(c);
                sink(r)
            };
            let ck = Checkpointing {
                every: ck.every,
                resume: ck.resume,
                sink: &mut with_coupling,
            };
            solve_thermal_checkpointed(model, setup, bcs, thermal, extra, Some(ck))?
        }
        None => solve_thermal_with(model, setup, bcs, thermal, extra)?,
    };
    let Coupling {
        mut el,
        solves,
        solves_s,
        ..
    } = state.into_inner();
    el.report.solves = solves;
    el.report.solves_wall_s = solves_s;
    Ok((el, th))
}

/// The state of the time-accurate coupling during a transient.
struct Coupling {
    /// Particle temperatures of the last potential solve (°C).
    last_t: Vec<f64>,
    /// The electrodes' potentials of that solve (V).
    last_v: Vec<f64>,
    /// That solve.
    el: ElectricRun,
    /// Potential solves so far.
    solves: usize,
    /// Their wall time (s).
    solves_s: f64,
}
