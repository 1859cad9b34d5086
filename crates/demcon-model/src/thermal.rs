//! The thermal problem on a model: transmission surfaces (C_t calibrated when asked), contact
//! and wall conductances, heat capacities, boundary conditions and sources, and the three
//! solvers (explicit, implicit, steady).

use std::cell::RefCell;

use demcon_core::{Face, Selector, TimeValue, Vec3};
use demcon_graph::{
    CellWall, InterfaceRule, SurfaceModel, Surfaces, WallContacts, conductances, contact_property_laminate,
    contact_surfaces, interface_value_split, representative_volumes,
};
use demcon_network::{Constraints, FloatingPolicy, Network, SolveParams, resolve_fixed};
use demcon_thermal::{
    CheckpointEvery, Checkpoints, ExplicitParams, ImplicitParams, ProgressFn, RepresentativeVolume, Scheme,
    SourceUpdate, ThermalSystem, TimeStep, Transient, TransientInput, TransientStart, TransientState,
    capacities, face_flux_sources, implicit_step_after, paper_dt_estimate, run_explicit_from,
    run_implicit_from, solve_steady_temperature, source_update_fn,
};
use serde::Serialize;

use crate::assembly::network_with_walls;
pub use crate::assembly::{CtSpec, SurfaceSpec, default_solve_params};
use crate::calibrate::{CalibrationBc, CtCalibration, calibrate_ct_with};
use crate::checkpoint::{Checkpointing, RunCheckpoint, not_resumable};
use crate::defects::{Physics, apply_to_contacts, apply_to_walls};
use crate::error::ModelError;
use crate::model::Model;
use crate::surroundings::{Exchange, ExchangeReport, NEWTON_MAX_ITERATIONS, NEWTON_TOLERANCE, Surroundings};

/// A thermal boundary condition, resolved on the model by [`thermal_bcs`].
#[derive(Debug, Clone, PartialEq)]
pub enum ThermalBc {
    /// The selected particles held at `value` (°C).
    FixedTemperature {
        /// Which particles.
        select: Selector,
        /// Temperature (°C).
        value: f64,
    },
    /// The face itself held at `value` (°C) through wall half-contacts.
    WallTemperature {
        /// The face.
        face: Face,
        /// Temperature (°C), constant or a table in time.
        value: TimeValue,
    },
    /// A heat flux density into the face (W/m²), shared among the particles touching it by
    /// their projected areas.
    HeatFlux {
        /// The face.
        face: Face,
        /// Flux density (W/m²), positive into the body; constant or a table in time.
        flux: TimeValue,
    },
    /// Convection to a fluid: h (T_f − T∞) (W/m²) leaves through the face ([`crate::surroundings`]).
    Convection {
        /// The face.
        face: Face,
        /// Film coefficient h (W/(m²·K)), ≥ 0.
        h: f64,
        /// Fluid temperature T∞ (°C), constant or a table in time.
        t_inf: TimeValue,
    },
    /// Radiation to surroundings: ε σ (T_f⁴ − T_s⁴) (W/m², kelvin) leaves through the face.
    Radiation {
        /// The face.
        face: Face,
        /// Emissivity ε in [0, 1].
        emissivity: f64,
        /// Surroundings' temperature T_s (°C), constant or a table in time.
        t_surroundings: TimeValue,
    },
}

/// A volumetric heat source on selected particles.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeSource {
    /// Which particles.
    pub select: Selector,
    /// Power per unit volume of solid (W/m³).
    pub power_density: TimeValue,
}

/// How the explicit step is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeStepSpec {
    /// safety × the exact positivity bound.
    Auto {
        /// Safety factor in (0, 1].
        safety: f64,
    },
    /// A given step (s).
    Fixed {
        /// Time step (s).
        dt: f64,
        /// Accept a step above the bound (divergence is then detected).
        allow_unstable: bool,
    },
    /// The paper's eq. 16 estimate (calibrated surfaces only).
    Paper {
        /// Accept it above the bound.
        allow_unstable: bool,
    },
}

/// The thermal solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ThermalSolver {
    /// Forward Euler to `t_end` (s).
    Explicit {
        /// End time (s).
        t_end: f64,
        /// Step choice.
        dt: TimeStepSpec,
    },
    /// Backward Euler or Crank–Nicolson to `t_end` (s) with step `dt` (s).
    Implicit {
        /// End time (s).
        t_end: f64,
        /// Step (s).
        dt: f64,
        /// Scheme.
        scheme: Scheme,
    },
    /// Steady state.
    Steady,
}

impl ThermalSolver {
    /// A transient (explicit or implicit)?
    pub fn is_transient(&self) -> bool {
        !matches!(self, ThermalSolver::Steady)
    }

    /// The time of the final state (s): `t_end`, or 0 for a steady solve.
    pub fn final_time(&self) -> f64 {
        match *self {
            ThermalSolver::Explicit { t_end, .. } | ThermalSolver::Implicit { t_end, .. } => t_end,
            ThermalSolver::Steady => 0.0,
        }
    }
}

/// Everything the thermal physics of a run needs, on plain types.
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalProblem {
    /// Transmission surfaces.
    pub surface: SurfaceSpec,
    /// Conductivity of a contact across two phases.
    pub interface: InterfaceRule,
    /// Boundary conditions (in the scene's order: errors name `thermal.bcs[i]`).
    pub bcs: Vec<ThermalBc>,
    /// Volumetric sources (errors name `thermal.sources[i]`).
    pub sources: Vec<VolumeSource>,
    /// Solver.
    pub solver: ThermalSolver,
    /// Initial temperature of a transient; excluded particles of a steady solve keep it (°C).
    pub initial_temperature: f64,
    /// Times (s) at which a transient's temperatures are kept.
    pub output_times: Vec<f64>,
    /// Floating clusters: excluded or refused (a transient keeps them when one has a source).
    pub floating: FloatingPolicy,
    /// The linear solver of steady and implicit solves ([`default_solve_params`] by default).
    pub solve: SolveParams,
    /// Called with (steps done, steps total) during a transient, at most ~100 times.
    pub progress: Option<ProgressFn>,
}

impl ThermalProblem {
    /// The walls of the thermal network: the faces held at a constant temperature
    /// (`WallTemperature`), and the faces held at a tabled one or exchanging heat with their
    /// surroundings (one wall per face, however many of `Convection` and `Radiation` it has),
    /// in the order of the conditions; the wall of
    /// each condition (none for `FixedTemperature` and `HeatFlux`); and the exchanges with
    /// the conditions on each.
    pub fn walls(&self) -> WallPlan {
        let mut plan = WallPlan::default();
        for (i, bc) in self.bcs.iter().enumerate() {
            let (face, held, convection, radiation) = match bc {
                ThermalBc::WallTemperature { face, value } if value.is_constant() => {
                    plan.of_bc.push(Some(plan.faces.len()));
                    plan.faces.push(*face);
                    continue;
                }
                ThermalBc::WallTemperature { face, value } => (*face, Some(value.clone()), None, None),
                ThermalBc::Convection { face, h, t_inf } => (*face, None, Some((*h, t_inf.clone())), None),
                ThermalBc::Radiation {
                    face,
                    emissivity,
                    t_surroundings,
                } => (*face, None, None, Some((*emissivity, t_surroundings.clone()))),
                ThermalBc::FixedTemperature { .. } | ThermalBc::HeatFlux { .. } => {
                    plan.of_bc.push(None);
                    continue;
                }
            };
            let x = match plan.exchanges.iter().position(|x| x.face == face) {
                Some(x) => x,
                None => {
                    plan.exchanges.push(Exchange {
                        face,
                        wall: plan.faces.len(),
                        held: None,
                        convection: None,
                        radiation: None,
                    });
                    plan.exchange_bcs.push(Vec::new());
                    plan.faces.push(face);
                    plan.exchanges.len() - 1
                }
            };
            let e = &mut plan.exchanges[x];
            e.held = held.or(e.held.take());
            e.convection = convection.or(e.convection.take());
            e.radiation = radiation.or(e.radiation.take());
            plan.exchange_bcs[x].push(i);
            plan.of_bc.push(Some(e.wall));
        }
        plan
    }
}

/// The walls of a thermal problem ([`ThermalProblem::walls`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WallPlan {
    /// The face of each wall.
    pub faces: Vec<Face>,
    /// Per boundary condition: its wall.
    pub of_bc: Vec<Option<usize>>,
    /// The faces exchanging heat with their surroundings.
    pub exchanges: Vec<Exchange>,
    /// Per exchange: its boundary conditions (indices into `bcs`).
    pub exchange_bcs: Vec<Vec<usize>>,
}

/// Conductances, capacities and volumes of the thermal network.
#[derive(Debug, Clone)]
pub struct ThermalSetup {
    /// The surface model used (C_t resolved).
    pub surface: SurfaceModel,
    /// Calibration, when C_t was `Auto`.
    pub calibration: Option<CtCalibration>,
    /// Transmission surface per contact (m²) ([`ThermalSetup::areas`]); empty under the
    /// Laguerre model, whose surfaces are the model's facet areas (not copied: 8 B per facet).
    areas: Vec<f64>,
    /// Contact conductivity λ per contact (W/(m·K)), interface rule applied.
    pub contact_lambda: Vec<f64>,
    /// Conductances (W/K): H = λ S / d per contact, then the wall links.
    pub conductances: Vec<f64>,
    /// The faces held at a temperature or exchanging heat with their surroundings, and their
    /// links to the particles.
    pub walls: WallContacts,
    /// The faces exchanging heat with their surroundings (convection, radiation).
    pub surroundings: Surroundings,
    /// The network with the wall nodes, when there are walls (else the model's is used).
    network: Option<Network>,
    /// Representative volume per particle (m³).
    pub rep_volumes: Vec<f64>,
    /// Heat capacity per node (J/K): particles, then 1 J/K for each (fixed) wall node.
    pub capacities: Vec<f64>,
    /// Particles whose neighbour count lay outside the Terreros table (clamped).
    pub clamped: usize,
    /// Haddad eq. 16 estimate of the critical step (s), for comparison only.
    pub paper_dt: Option<f64>,
}

impl ThermalSetup {
    /// Transmission surface per contact (m²): the Laguerre facet areas of `model`, or the
    /// surfaces of the contact model.
    pub fn areas<'a>(&'a self, model: &'a Model) -> &'a [f64] {
        match (&self.surface, model.graph.cells.as_deref()) {
            (SurfaceModel::Laguerre, Some(cells)) => &cells.facet_area,
            _ => &self.areas,
        }
    }

    /// The thermal network: the model's, or the one extended with wall nodes.
    pub fn network<'a>(&'a self, model: &'a Model) -> &'a Network {
        self.network.as_ref().unwrap_or_else(|| model.network())
    }

    /// The contact conductances (W/K), without the wall links.
    pub fn contact_conductances(&self) -> &[f64] {
        &self.conductances[..self.conductances.len() - self.walls.len()]
    }

    /// The wall-link conductances (W/K), in the order of [`WallContacts`]' links.
    pub fn wall_conductances(&self) -> &[f64] {
        &self.conductances[self.conductances.len() - self.walls.len()..]
    }

    /// Sets the conductances (and the exchanging faces' half-bonds) to those in force at the
    /// particle temperatures `temps` (°C): λ(T) moved them from the initial state's; the end
    /// state's flows, flux and effective conductivity read these.
    ///
    /// Errors: λ(T) ≤ 0 at a particle ([`conductances_at`]).
    pub fn set_in_force(
        &mut self,
        model: &Model,
        interface: InterfaceRule,
        temps: &[f64],
    ) -> Result<(), ModelError> {
        let (contacts, half) = conductances_at(model, &self.surface, interface, &self.walls, Some(temps))?;
        self.surroundings.set_half(&half);
        let first_link = self.conductances.len() - self.walls.len();
        self.conductances[..first_link].copy_from_slice(&contacts);
        self.conductances[first_link..].copy_from_slice(&half);
        self.surroundings
            .set_conductances(&mut self.conductances[first_link..]);
        Ok(())
    }

    /// The heat-flux dipoles (W·m) of every particle at time `t` (s) and the node
    /// temperatures `nodes` (°C, particles then walls): the network's
    /// ([`crate::flux_dipoles`]) and, on faces exchanging heat with their surroundings or
    /// held at a tabled temperature, the part of each link's heat its source carries.
    pub fn heat_dipoles(&self, model: &Model, t: f64, nodes: &[f64]) -> Vec<demcon_core::Vec3> {
        let mut d = crate::flux_dipoles(model, &self.walls, &self.conductances, nodes);
        self.surroundings
            .add_dipoles(&self.walls, t, self.wall_conductances(), nodes, &mut d);
        d
    }
}

/// Builds the thermal network values (calibrating C_t when asked): surfaces, conductances
/// with the interface rule, wall links of the `WallTemperature` faces, heat capacities
/// (laminate particles mix ρ and ρc arithmetically) and the paper's step estimate.
pub fn thermal_setup(model: &Model, problem: &ThermalProblem) -> Result<ThermalSetup, ModelError> {
    let plan = problem.walls();
    let faces = plan.faces;
    let calibration = match problem.surface {
        SurfaceSpec::Calibrated(CtSpec::Auto) => {
            let bc = if faces.is_empty() {
                CalibrationBc::Particles
            } else {
                CalibrationBc::Walls
            };
            Some(calibrate_ct_with(model, bc)?)
        }
        _ => None,
    };
    let sm = problem.surface.model(calibration.as_ref().map(|c| c.c_t));
    let (s, contact_lambda, mut g) = contact_values(model, &sm, problem.interface)?;
    let lam_phase: Vec<f64> = model.materials.materials.iter().map(|m| m.conductivity).collect();
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
    let rv = match sm {
        SurfaceModel::Laguerre => RepresentativeVolume::Given(&rep),
        _ => RepresentativeVolume::VolumeFraction(&fv),
    };
    let mut caps = capacities(&vols, &c, &rho, rv)?;
    let walls = model.wall_contacts(&faces, model.fields.bcs)?;
    let wall_s = walls.surfaces(&model.particles, &model.graph.surface_degrees(), &sm);
    let mut wall_g = walls.conductances(&wall_s, |p, e, h| lam.half_bond(p, phases, &lam_phase, e, h));
    apply_to_walls(
        &model.defect_view(),
        &walls,
        &wall_s,
        &mut wall_g,
        Physics::Thermal,
    );
    if model.conductivity_varies() {
        // λ(T): the conductances of the initial state (a steady solve iterates from them).
        let t0 = vec![problem.initial_temperature; model.particles.len()];
        (g, wall_g) = conductances_at(model, &sm, problem.interface, &walls, Some(&t0))?;
    } else if model.anisotropic() {
        (g, wall_g) = conductances_at(model, &sm, problem.interface, &walls, None)?;
    }
    let labels = plan
        .exchange_bcs
        .iter()
        .map(|b| b.iter().map(|i| format!("{}[{i}]", model.fields.bcs)).collect());
    let surroundings = Surroundings::new(
        plan.exchanges,
        labels.collect(),
        &walls,
        &wall_g,
        &model.particles,
        |f| model.container.face_area(f),
        problem.initial_temperature,
    )?;
    surroundings.set_conductances(&mut wall_g);
    let (network, g) = network_with_walls(model, &walls, g, wall_g)?;
    caps.resize(caps.len() + walls.n_walls(), 1.0);
    let paper_dt = match sm {
        SurfaceModel::Calibrated { c_t } if matches!(problem.surface, SurfaceSpec::Calibrated(_)) => {
            paper_step(model, c_t)
        }
        _ => None,
    };
    Ok(ThermalSetup {
        surface: sm,
        calibration,
        // The Laguerre surfaces are the facet areas: `areas` reads them from the model.
        areas: if matches!(sm, SurfaceModel::Laguerre) {
            Vec::new()
        } else {
            s.area
        },
        contact_lambda,
        conductances: g,
        walls,
        surroundings,
        network,
        rep_volumes: rep,
        capacities: caps,
        clamped: s.clamped,
        paper_dt,
    })
}

/// Surfaces, contact conductivities (interface rule applied) and conductances H = λ S / d
/// (W/K) of the contacts under `sm`, with the model's interface and filled-crack resistances
/// in series and its damage factors ([`crate::defects`]).
fn contact_values(
    model: &Model,
    sm: &SurfaceModel,
    interface: InterfaceRule,
) -> Result<(Surfaces, Vec<f64>, Vec<f64>), ModelError> {
    let s = contact_surfaces(&model.graph, &model.particles, sm)?;
    let lam_phase: Vec<f64> = model.materials.materials.iter().map(|m| m.conductivity).collect();
    let lambda = contact_property_laminate(
        &model.graph,
        &model.particles.phases,
        &lam_phase,
        &model.mixes,
        interface,
    )?;
    let mut g = conductances(&model.graph, &s.area, &lambda)?;
    apply_to_contacts(&model.defect_view(), &s.area, &mut g, Physics::Thermal);
    Ok((s, lambda, g))
}

/// The contact conductances (W/K) and the wall links' half-bond conductances (W/K, in link
/// order, before the films of faces exchanging heat) with every particle's conductivity along
/// each bond — eᵀ K e of an anisotropic material, λ of an isotropic one — scaled by λ(T)/λ0 at
/// its temperature in `temps` (°C, per particle; more entries are ignored; `None`: at the
/// reference temperatures), defects applied. A cut particle mixes its two phases' values
/// along the bond by its mix's rule.
///
/// Errors: λ(T) ≤ 0 (or not finite) at a particle, naming the material's coefficient, the
/// particle and its temperature.
pub fn conductances_at(
    model: &Model,
    sm: &SurfaceModel,
    rule: InterfaceRule,
    walls: &WallContacts,
    temps: Option<&[f64]>,
) -> Result<(Vec<f64>, Vec<f64>), ModelError> {
    let materials = &model.materials.materials;
    let lam = model.laminates();
    let phases = &model.particles.phases;
    // λ(T)/λ0 of each particle's phase (and its other phase when cut), checked > 0.
    let factor = |phase: u16, p: usize| -> Result<f64, ModelError> {
        let m = &materials[phase as usize];
        let Some(t) = temps.map(|t| t[p]) else {
            return Ok(1.0);
        };
        let v = m.conductivity_at(t);
        if v.is_finite() && v > 0.0 {
            Ok(v / m.conductivity)
        } else {
            Err(ModelError::invalid(
                &format!("materials[{}].conductivity_temp_coeff", m.name),
                m.conductivity_temp_coeff,
                format!(
                    "λ(T) > 0 over the temperatures met: particle {p} at {t:.6} °C gives λ = {v:.6e} W/(m·K)"
                ),
            ))
        }
    };
    let mut own = Vec::with_capacity(phases.len());
    let mut other = Vec::with_capacity(phases.len());
    for (p, &phase) in phases.iter().enumerate() {
        own.push(factor(phase, p)?);
        other.push(match lam.get(p) {
            Some(m) => Some(factor(m.other_phase, p)?),
            None => None,
        });
    }
    let axes = model.shape_axes();
    let half_bond = |p: usize, e: &Vec3, half: f64| -> f64 {
        let axis = axes.get(p).and_then(Option::as_ref);
        let along = |phase: u16| materials[phase as usize].conductivity_along_in(e, axis);
        let mine = own[p] * along(phases[p]);
        match (lam.get(p), other[p]) {
            (Some(m), Some(f)) => m.half_bond_value(mine, f * along(m.other_phase), e, half),
            _ => mine,
        }
    };
    let s = contact_surfaces(&model.graph, &model.particles, sm)?;
    let mut g: Vec<f64> = (0..model.graph.len())
        .map(|k| {
            let [p, q] = model.graph.pairs[k].map(|x| x as usize);
            let geo = &model.graph.geometry[k];
            let w = model.graph.split(k);
            let (kp, kq) = (
                half_bond(p, &geo.normal, w * geo.distance),
                half_bond(q, &(-geo.normal), (1.0 - w) * geo.distance),
            );
            interface_value_split(kp, kq, w, rule) * s.area[k] / geo.distance
        })
        .collect();
    apply_to_contacts(&model.defect_view(), &s.area, &mut g, Physics::Thermal);
    let wall_s = walls.surfaces(&model.particles, &model.graph.surface_degrees(), sm);
    let mut wall_g = walls.conductances(&wall_s, half_bond);
    apply_to_walls(
        &model.defect_view(),
        walls,
        &wall_s,
        &mut wall_g,
        Physics::Thermal,
    );
    Ok((g, wall_g))
}

/// The contact conductances H = λ S / d (W/K) under `surface` and `interface`, with C_t
/// calibrated on the model when `Auto` (a periodic model by homogenisation).
pub fn thermal_conductances(
    model: &Model,
    surface: &SurfaceSpec,
    interface: InterfaceRule,
) -> Result<(Vec<f64>, Option<CtCalibration>), ModelError> {
    let calibration = match surface {
        SurfaceSpec::Calibrated(CtSpec::Auto) => Some(calibrate_ct_with(model, CalibrationBc::Particles)?),
        _ => None,
    };
    let sm = surface.model(calibration.as_ref().map(|c| c.c_t));
    let g = if model.anisotropic() {
        conductances_at(model, &sm, interface, &WallContacts::default(), None)?.0
    } else {
        contact_values(model, &sm, interface)?.2
    };
    Ok((g, calibration))
}

/// Haddad eq. 16 estimate of the critical step (s) at C_t = `c_t`, with the smallest contact
/// distance and the largest diffusivity over the phases (a = λ/(c ρ_d), ρ_d = ρ_c/φ).
fn paper_step(model: &Model, c_t: f64) -> Option<f64> {
    let d_min = model
        .graph
        .geometry
        .iter()
        .map(|g| g.distance)
        .fold(f64::INFINITY, f64::min);
    let a = model
        .materials
        .materials
        .iter()
        .map(|m| m.conductivity * model.phi / (m.specific_heat * m.density))
        .fold(0.0, f64::max);
    let z = model.graph.coordination();
    (d_min.is_finite() && z > 0.0).then(|| paper_dt_estimate(d_min, a, z, c_t))
}

/// What a set of fixed temperatures holds.
#[derive(Debug, Clone, PartialEq)]
pub enum FixedTarget {
    /// These particles.
    Particles(Vec<u32>),
    /// Wall `w` of [`ThermalSetup::walls`].
    Wall(usize),
}

/// A set held at one temperature.
#[derive(Debug, Clone, PartialEq)]
pub struct FixedSet {
    /// What is held.
    pub target: FixedTarget,
    /// Temperature (°C).
    pub value: f64,
}

impl ThermalBcs {
    /// The sources per node (W) at time `t` (s): the constant ones and the tables' values.
    pub fn sources_at(&self, t: f64) -> Vec<f64> {
        let mut s = self.sources.clone();
        for (table, nodes) in &self.timed {
            let v = table.at(t);
            for &(p, w) in nodes {
                s[p as usize] += v * w;
            }
        }
        s
    }
}

impl FixedSet {
    /// The network nodes held.
    pub fn nodes(&self, walls: &WallContacts) -> Vec<u32> {
        match &self.target {
            FixedTarget::Particles(ids) => ids.clone(),
            FixedTarget::Wall(w) => vec![walls.node(*w)],
        }
    }

    /// The particles held (none for a wall).
    pub fn particles(&self) -> &[u32] {
        match &self.target {
            FixedTarget::Particles(ids) => ids,
            FixedTarget::Wall(_) => &[],
        }
    }
}

/// Resolved thermal boundary conditions and sources.
#[derive(Debug, Clone)]
pub struct ThermalBcs {
    /// Fixed temperatures and excluded floating clusters.
    pub constraints: Constraints,
    /// Heat sources per node (W): imposed fluxes and volumetric sources (0 on wall nodes),
    /// those constant in time.
    pub sources: Vec<f64>,
    /// Imposed fluxes and volumetric sources that follow a time table: the table (W/m² or
    /// W/m³) and the nodes it heats with their weights (m² or m³).
    pub timed: Vec<(TimeValue, Vec<(u32, f64)>)>,
    /// The fixed sets in the order of the boundary conditions.
    pub fixed_sets: Vec<FixedSet>,
    /// What the conditions do that is allowed but probably not meant (a source on a held
    /// particle, whose heat the hold absorbs).
    pub warnings: Vec<String>,
}

/// Resolves the boundary conditions and sources of `problem` on the model.
///
/// Errors: a selection that selects nothing, a heat flux on a face the container lacks, no
/// fixed temperature for a steady solve, floating clusters refused by the policy.
pub fn thermal_bcs(
    model: &Model,
    setup: &ThermalSetup,
    problem: &ThermalProblem,
) -> Result<ThermalBcs, ModelError> {
    let net = setup.network(model);
    let mut sources = vec![0.0; net.n_nodes()];
    let mut timed = Vec::new();
    let fixed_sets = boundary_conditions(model, setup, problem, &mut sources, &mut timed)?;
    add_volume_sources(model, problem, &mut sources, &mut timed)?;
    if !problem.solver.is_transient() {
        refuse_tables(model, problem)?;
    }
    // The checks below read where heat is put, whenever it is.
    let all_sources = {
        let mut s = sources.clone();
        for (_, nodes) in &timed {
            for &(p, w) in nodes {
                s[p as usize] += w;
            }
        }
        s
    };
    let mut warnings = Vec::new();
    let held_sourced = fixed_sets
        .iter()
        .flat_map(FixedSet::particles)
        .filter(|&&p| all_sources[p as usize] != 0.0)
        .count();
    if held_sourced > 0 {
        warnings.push(format!(
            "thermal: {held_sourced} particle(s) held at a fixed temperature also receive a source or an imposed \
             flux: the hold absorbs that heat (it never enters the body)"
        ));
    }
    let transient = problem.solver.is_transient();
    let exchanges = &setup.surroundings.faces;
    if fixed_sets.is_empty() && exchanges.is_empty() && !transient {
        return Err(ModelError::invalid(
            model.fields.bcs,
            "no FixedTemperature, WallTemperature, Convection or Radiation",
            "a steady thermal solve needs at least one fixed temperature or a face exchanging heat with its \
             surroundings",
        ));
    }
    // The faces exchanging heat are wall nodes held at their reference temperature.
    let sets: Vec<(Vec<u32>, f64)> = fixed_sets
        .iter()
        .map(|s| (s.nodes(&setup.walls), s.value))
        .chain(
            exchanges
                .iter()
                .map(|x| (vec![setup.walls.node(x.wall)], x.reference())),
        )
        .collect();
    // A transient is well posed on every cluster, fixed values or not: its heat capacity holds
    // it, and its sources heat it, so floating clusters are kept when one of them has a
    // source. Without sources they keep their initial temperature exactly, as excluded
    // clusters report it, so the floating policy applies (an isolated small cluster would
    // otherwise only shorten the explicit step). A steady solve always applies the policy.
    let mut constraints = resolve_fixed(net, &sets, FloatingPolicy::Keep)?;
    let heated = constraints
        .floating_kept()
        .iter()
        .any(|&p| all_sources[p as usize] != 0.0);
    if !(transient && (heated || sets.is_empty())) {
        constraints = resolve_fixed(net, &sets, problem.floating)?;
    }
    // Heat imposed on particles left out of the solve never enters the body: say how much.
    let excluded: Vec<u32> = constraints
        .excluded()
        .iter()
        .copied()
        .filter(|&p| all_sources[p as usize] != 0.0)
        .collect();
    if !excluded.is_empty() {
        let lost: f64 = excluded.iter().map(|&p| all_sources[p as usize]).sum();
        let total: f64 = all_sources.iter().map(|q| q.abs()).sum();
        warnings.push(format!(
            "thermal: {lost:.6e} W of imposed flux and sources ({:.3} % of {total:.6e} W) falls on {} particle(s) \
             excluded from the solve (floating clusters, rattlers) and does not enter the body",
            100.0 * lost.abs() / total,
            excluded.len()
        ));
    }
    Ok(ThermalBcs {
        constraints,
        sources,
        timed,
        fixed_sets,
        warnings,
    })
}

/// The fixed temperatures of `problem.bcs` (particle sets and walls), and the imposed fluxes
/// added to `sources` (W per node).
fn boundary_conditions(
    model: &Model,
    setup: &ThermalSetup,
    problem: &ThermalProblem,
    sources: &mut [f64],
    timed: &mut Vec<(TimeValue, Vec<(u32, f64)>)>,
) -> Result<Vec<FixedSet>, ModelError> {
    let wall_of = problem.walls().of_bc;
    let mut fixed_sets = Vec::new();
    for (i, bc) in problem.bcs.iter().enumerate() {
        let field = format!("{}[{i}]", model.fields.bcs);
        match bc {
            ThermalBc::FixedTemperature { select, value } => {
                let ids = select
                    .select_nonempty(
                        &model.particles,
                        &model.container,
                        &format!("{field} (FixedTemperature)"),
                    )
                    .map_err(|e| ModelError::at(&format!("{field}.select"), e))?;
                fixed_sets.push(FixedSet {
                    target: FixedTarget::Particles(ids),
                    value: *value,
                });
            }
            ThermalBc::HeatFlux { face, flux } if model.graph.cells.is_some() => {
                // Laguerre cells: each facet on the face receives the flux through its area.
                let cells = model.graph.cells.as_deref().expect("checked by the guard");
                let areas: Vec<(u32, f64)> = cells
                    .on_wall(CellWall::of(*face))
                    .map(|f| (f.particle, f.area))
                    .collect();
                if areas.is_empty() {
                    return Err(ModelError::invalid(
                        &format!("{field}.face"),
                        face.name(),
                        "a face of the container (or the carved surface) some Laguerre cell reaches",
                    ));
                }
                add_source(flux, areas, sources, timed);
            }
            ThermalBc::HeatFlux { face, flux } => {
                let ids = Selector::Face(*face)
                    .select_nonempty(&model.particles, &model.container, &format!("{field} (HeatFlux)"))
                    .map_err(|e| ModelError::at(&format!("{field}.face"), e))?;
                let area = model.container.face_area(*face).ok_or_else(|| {
                    ModelError::invalid(
                        &format!("{field}.face"),
                        face.name(),
                        "this container has no such face",
                    )
                })?;
                let s = face_flux_sources(&model.particles, &ids, area)?;
                let areas = ids.iter().map(|&p| (p, s[p as usize])).collect();
                add_source(flux, areas, sources, timed);
            }
            ThermalBc::WallTemperature { face, value } if value.is_constant() => {
                let w = wall_of[i].expect("one wall per WallTemperature, built by thermal_setup");
                debug_assert_eq!(setup.walls.faces[w], *face);
                fixed_sets.push(FixedSet {
                    target: FixedTarget::Wall(w),
                    value: value.at(0.0),
                });
            }
            // Walls held at their reference, with the sources of the run's state and time
            // ([`Surroundings`]).
            ThermalBc::WallTemperature { .. }
            | ThermalBc::Convection { .. }
            | ThermalBc::Radiation { .. } => {}
        }
    }
    Ok(fixed_sets)
}

/// Adds the volume sources of `problem.sources` (W/m³ × each particle's solid volume) to
/// `sources` (W per node).
fn add_volume_sources(
    model: &Model,
    problem: &ThermalProblem,
    sources: &mut [f64],
    timed: &mut Vec<(TimeValue, Vec<(u32, f64)>)>,
) -> Result<(), ModelError> {
    for (i, src) in problem.sources.iter().enumerate() {
        let field = format!("{}[{i}]", model.fields.sources);
        let ids = src
            .select
            .select_nonempty(&model.particles, &model.container, &field)
            .map_err(|e| ModelError::at(&format!("{field}.select"), e))?;
        let volumes = ids
            .iter()
            .map(|&p| (p, model.solid_volume_of(p as usize)))
            .collect();
        add_source(&src.power_density, volumes, sources, timed);
    }
    Ok(())
}

/// A density `value` (W/m² or W/m³) over `weights` (node, m² or m³): added to `sources` (W per
/// node) when constant, else kept with its table in `timed`.
fn add_source(
    value: &TimeValue,
    weights: Vec<(u32, f64)>,
    sources: &mut [f64],
    timed: &mut Vec<(TimeValue, Vec<(u32, f64)>)>,
) {
    if value.is_constant() {
        let v = value.at(0.0);
        for (p, w) in weights {
            sources[p as usize] += v * w;
        }
    } else {
        timed.push((value.clone(), weights));
    }
}

/// Refuses a value that follows a time table in a steady solve, naming its field.
fn refuse_tables(model: &Model, problem: &ThermalProblem) -> Result<(), ModelError> {
    let tabled = |v: &TimeValue| !v.is_constant();
    for (i, bc) in problem.bcs.iter().enumerate() {
        let (what, v) = match bc {
            ThermalBc::WallTemperature { value, .. } => ("value", value),
            ThermalBc::HeatFlux { flux, .. } => ("flux", flux),
            ThermalBc::Convection { t_inf, .. } => ("t_inf", t_inf),
            ThermalBc::Radiation { t_surroundings, .. } => ("t_surroundings", t_surroundings),
            ThermalBc::FixedTemperature { .. } => continue,
        };
        if tabled(v) {
            return Err(ModelError::invalid(
                &format!("{}[{i}].{what}", model.fields.bcs),
                "a time table",
                "a constant in a steady solve (a table needs a transient solver)",
            ));
        }
    }
    for (i, src) in problem.sources.iter().enumerate() {
        if tabled(&src.power_density) {
            return Err(ModelError::invalid(
                &format!("{}[{i}].power_density", model.fields.sources),
                "a time table",
                "a constant in a steady solve (a table needs a transient solver)",
            ));
        }
    }
    Ok(())
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
    /// Solves of a steady state: 1 when linear; with radiation (re-linearised each time) or
    /// λ(T) (conductances re-evaluated, Anderson-mixed), as many as it took.
    pub nonlinear_iterations: u64,
    /// The last solve's change: of the temperatures relative to their span (λ(T)), or of the
    /// radiating surfaces' temperatures relative to their value in kelvin; 0 when linear.
    pub nonlinear_change: f64,
    /// What each face exchanging heat with its surroundings (or held at a tabled temperature)
    /// gives off at the end.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub faces: Vec<ExchangeReport>,
}

/// Temperatures of a thermal solve.
#[derive(Debug, Clone)]
pub struct ThermalRun {
    /// Final temperatures of the particles (°C). Excluded particles keep their initial temperature.
    pub temperatures: Vec<f64>,
    /// Final temperatures of the walls (°C), in the order of [`ThermalSetup::walls`].
    pub wall_temperatures: Vec<f64>,
    /// Snapshots of the particles at the requested output times (t (s), temperatures (°C)).
    pub snapshots: Vec<(f64, Vec<f64>)>,
    /// Cost and step data.
    pub report: ThermalSolveReport,
}

impl ThermalRun {
    fn from_nodes(
        walls: &WallContacts,
        nodes: Vec<f64>,
        snapshots: Vec<(f64, Vec<f64>)>,
        report: ThermalSolveReport,
    ) -> Self {
        let (p, w) = walls.split(&nodes);
        Self {
            wall_temperatures: w.to_vec(),
            temperatures: p.to_vec(),
            snapshots,
            report,
        }
    }

    /// Temperatures of every node of the thermal network: the particles, then the walls (°C).
    pub fn node_temperatures(&self) -> Vec<f64> {
        WallContacts::join_nodes(&self.temperatures, &self.wall_temperatures)
    }
}

/// Extra sources that change during a transient: called after every time step with the time
/// (s) and the temperatures of every node (particles first, °C); returns new extra sources
/// (W per particle) for the following steps, or `None` to keep the current ones. An error
/// stops the run and is returned by [`solve_thermal`].
pub type ExtraSourceUpdate<'a> = dyn FnMut(f64, &[f64]) -> Result<Option<Vec<f64>>, ModelError> + 'a;

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

/// Extra per-particle sources of a solve (W), and how they change during a transient.
pub struct ExtraSources<'a, 'b> {
    /// Added to the boundary sources from the start.
    pub initial: Option<&'b [f64]>,
    /// Re-evaluated after every step of a transient (not called by the steady solve).
    pub update: &'b mut ExtraSourceUpdate<'a>,
}

/// Runs the thermal solver of `problem` with no extra sources.
pub fn solve_thermal(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    problem: &ThermalProblem,
) -> Result<ThermalRun, ModelError> {
    solve_thermal_with(
        model,
        setup,
        bcs,
        problem,
        ExtraSources {
            initial: None,
            update: &mut |_, _| Ok(None),
        },
    )
}

/// Runs the thermal solver of `problem` with `extra` sources (W per particle, e.g. Joule
/// heat) added to the boundary sources, re-evaluated during a transient by `extra.update`.
pub fn solve_thermal_with(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    problem: &ThermalProblem,
    extra: ExtraSources<'_, '_>,
) -> Result<ThermalRun, ModelError> {
    solve_thermal_checkpointed(model, setup, bcs, problem, extra, None)
}

/// [`solve_thermal_with`], a transient handing out checkpoints ([`RunCheckpoint`], without
/// coupling state) on the schedule of `checkpointing` and continuing from
/// `checkpointing.resume` bit for bit (`extra.initial` is then unused: the checkpoint holds
/// the sources in force). A steady solve refuses to resume.
pub fn solve_thermal_checkpointed(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    problem: &ThermalProblem,
    extra: ExtraSources<'_, '_>,
    checkpointing: Option<Checkpointing<'_, '_>>,
) -> Result<ThermalRun, ModelError> {
    let n = model.particles.len();
    let t_init = initial_node_temperatures(model, setup, bcs, problem.initial_temperature);
    let (every, resume, mut sink) = match checkpointing {
        Some(c) => (c.every, c.resume, Some(c.sink)),
        None => (CheckpointEvery::default(), None, None),
    };
    let step_sources = StepSources::new(model, setup, bcs, problem);
    let varies = step_sources.varies();
    let sources = step_sources.at(0.0, &t_init, extra.initial)?;
    let mut extra_now: Option<Vec<f64>> = match resume {
        // The extra sources in force at the checkpoint: what its sources hold beyond the
        // boundary's and the faces' (to round-off).
        Some(c) if varies && extra.initial.is_some() => {
            let own = step_sources.at(c.transient.t, &c.transient.temperatures, None)?;
            Some(c.transient.sources.iter().zip(&own).map(|(a, b)| a - b).collect())
        }
        _ => extra.initial.map(<[f64]>::to_vec),
    };
    let update = extra.update;
    let mut hook = |t: f64, temps: &[f64]| -> Result<Option<Vec<f64>>, ModelError> {
        let fresh = update(t, temps)?;
        if fresh.is_none() && !varies {
            return Ok(None);
        }
        if fresh.is_some() {
            extra_now = fresh;
        }
        step_sources.at(t, temps, extra_now.as_deref()).map(Some)
    };
    let snapshots = RefCell::new(resume.map(|c| c.snapshots.clone()).unwrap_or_default());
    let system = ThermalSystem::new(
        setup.network(model),
        &setup.conductances,
        &setup.capacities,
        &bcs.constraints,
    )?;
    let start = match resume {
        Some(c) => TransientStart::Resume(&c.transient),
        None => TransientStart::Initial(TransientInput {
            temperatures: &t_init,
            sources: &sources,
        }),
    };
    let observer = |t, v: &[f64]| {
        snapshots
            .borrow_mut()
            .push((t, WallContacts::particle_part(v, n).to_vec()))
    };
    let mut save = |state: TransientState| {
        let Some(sink) = sink.as_mut() else {
            return Ok(());
        };
        let snapshots = snapshots.borrow().clone();
        sink(RunCheckpoint {
            transient: state,
            snapshots,
            coupling: None,
        })
    };
    let checkpoints = Some(Checkpoints {
        every,
        save: &mut save,
    });
    let march = Marcher {
        model,
        setup,
        problem,
        system: &system,
        start,
    };
    let tr = match problem.solver {
        ThermalSolver::Explicit { t_end, dt } => {
            march.explicit(t_end, dt, observer, source_update_fn(&mut hook), checkpoints)?
        }
        ThermalSolver::Implicit { t_end, dt, scheme } => march.implicit(
            t_end,
            dt,
            scheme,
            observer,
            source_update_fn(&mut hook),
            checkpoints,
        )?,
        ThermalSolver::Steady => {
            if resume.is_some() {
                return Err(not_resumable(&model.fields, "Steady"));
            }
            return steady_run(
                model,
                setup,
                bcs,
                problem,
                &system,
                &bcs_sources_with(extra.initial, bcs),
            );
        }
    };
    let mut report = transient_report(&tr.report, setup.paper_dt, bcs.constraints.excluded().len());
    report.faces = setup
        .surroundings
        .report(&setup.walls, problem.solver.final_time(), &tr.temperatures);
    Ok(ThermalRun::from_nodes(
        &setup.walls,
        tr.temperatures,
        snapshots.into_inner(),
        report,
    ))
}

/// The sources of a transient step that follow the state or the time — the faces exchanging
/// heat ([`Surroundings`]: radiation, tabled temperatures), tabled fluxes and power densities —
/// re-evaluated after every step for the next one, on top of the extra sources last handed
/// out. The tables are read at the step's own time: its start for forward Euler (whose sources
/// act from there), its middle for the implicit schemes.
///
/// λ(T): the matrix keeps the conductances of the initial state; what they became at the
/// step's temperatures goes into the sources, (K₀ − K(T)) T — forward Euler exactly, the
/// implicit schemes with the change lagged by one step.
struct StepSources<'a> {
    model: &'a Model,
    setup: &'a ThermalSetup,
    bcs: &'a ThermalBcs,
    problem: &'a ThermalProblem,
    conductivity_varies: bool,
}

impl<'a> StepSources<'a> {
    fn new(
        model: &'a Model,
        setup: &'a ThermalSetup,
        bcs: &'a ThermalBcs,
        problem: &'a ThermalProblem,
    ) -> Self {
        Self {
            model,
            setup,
            bcs,
            problem,
            conductivity_varies: model.conductivity_varies(),
        }
    }

    /// Whether any source follows the state or the time.
    fn varies(&self) -> bool {
        self.setup.surroundings.varies() || !self.bcs.timed.is_empty() || self.conductivity_varies
    }

    /// The time (s) at which the step starting at `t` (s) reads its tables.
    fn when(&self, t: f64) -> Result<f64, ModelError> {
        Ok(match self.problem.solver {
            ThermalSolver::Implicit { t_end, dt, .. } => {
                t + 0.5 * implicit_step_after(t_end, dt, &self.problem.output_times, t)?
            }
            _ => t,
        })
    }

    /// The sources (W per node) of the step starting at `t` (s) from the node temperatures
    /// `temps` (°C), with `extra` (W per particle) added.
    fn at(&self, t: f64, temps: &[f64], extra: Option<&[f64]>) -> Result<Vec<f64>, ModelError> {
        let (model, setup) = (self.model, self.setup);
        let (walls, n) = (&setup.walls, model.particles.len());
        let tau = self.when(t)?;
        let mut s = self.bcs.sources_at(tau);
        if let Some(x) = extra {
            s.iter_mut().zip(x).for_each(|(a, b)| *a += b);
        }
        if !self.conductivity_varies {
            setup.surroundings.add_sources(walls, tau, temps, &mut s);
            return Ok(s);
        }
        let (contacts, half) = conductances_at(
            model,
            &setup.surface,
            self.problem.interface,
            walls,
            Some(WallContacts::particle_part(temps, n)),
        )?;
        let mut now = setup.surroundings.clone();
        now.set_half(&half);
        let mut g = [contacts, half].concat();
        let first_link = g.len() - walls.len();
        now.set_conductances(&mut g[first_link..]);
        let net = setup.network(model);
        let was = net.apply_laplacian(&setup.conductances, temps)?;
        let is = net.apply_laplacian(&g, temps)?;
        for (p, si) in s.iter_mut().enumerate().take(n) {
            *si += was[p] - is[p];
        }
        now.add_sources(walls, tau, temps, &mut s);
        Ok(s)
    }
}

/// Marches a thermal system with the problem's transient solver.
struct Marcher<'a> {
    model: &'a Model,
    setup: &'a ThermalSetup,
    problem: &'a ThermalProblem,
    system: &'a ThermalSystem<'a>,
    start: TransientStart<'a>,
}

impl Marcher<'_> {
    /// Forward Euler to `t_end` (s), its step from `dt` and the paper's estimate.
    fn explicit<U: SourceUpdate<Error = ModelError>>(
        self,
        t_end: f64,
        dt: TimeStepSpec,
        observer: impl FnMut(f64, &[f64]),
        update: U,
        checkpoints: Option<Checkpoints<'_, ModelError>>,
    ) -> Result<Transient, ModelError> {
        let params = ExplicitParams {
            t_end,
            dt: explicit_step(dt, self.setup.paper_dt, self.model.fields.solver)?,
            output_times: self.problem.output_times.clone(),
            paper_dt: self.setup.paper_dt,
            progress: self.problem.progress.clone(),
            ..ExplicitParams::default()
        };
        run_explicit_from(self.system, self.start, &params, observer, update, checkpoints)
    }

    /// Backward Euler or Crank–Nicolson to `t_end` with the step `dt` (s).
    fn implicit<U: SourceUpdate<Error = ModelError>>(
        self,
        t_end: f64,
        dt: f64,
        scheme: Scheme,
        observer: impl FnMut(f64, &[f64]),
        update: U,
        checkpoints: Option<Checkpoints<'_, ModelError>>,
    ) -> Result<Transient, ModelError> {
        let params = ImplicitParams {
            t_end,
            dt,
            scheme,
            output_times: self.problem.output_times.clone(),
            solve: self.problem.solve,
            progress: self.problem.progress.clone(),
            ..ImplicitParams::default()
        };
        run_implicit_from(self.system, self.start, &params, observer, update, checkpoints)
    }
}

/// The boundary's sources (W per node) with `extra` (W per particle) added.
fn bcs_sources_with(extra: Option<&[f64]>, bcs: &ThermalBcs) -> Vec<f64> {
    let mut s = bcs.sources.clone();
    if let Some(x) = extra {
        s.iter_mut().zip(x).for_each(|(a, b)| *a += b);
    }
    s
}

/// The model's report of a transient run (`paper_dt`: the paper's step estimate, s;
/// `excluded`: particles left out of the solve).
fn transient_report(
    r: &demcon_thermal::TransientReport,
    paper_dt: Option<f64>,
    excluded: usize,
) -> ThermalSolveReport {
    ThermalSolveReport {
        scheme: r.scheme.to_string(),
        steps: r.steps,
        dt: r.dt,
        dt_bound: r.dt_bound,
        dt_paper: paper_dt,
        iterations: r.solver_iterations,
        residual: r.max_relative_residual,
        wall_s: r.wall_s,
        contacts_per_s: r.contacts_per_s,
        energy_balance_error: r.energy_balance_error,
        excluded,
        nonlinear_iterations: 0,
        nonlinear_change: 0.0,
        faces: Vec::new(),
    }
}

/// The explicit step the caller asks for; `Paper` takes the paper's estimate (s), which only
/// the calibrated surface model has (refused at `{solver}.dt`).
fn explicit_step(spec: TimeStepSpec, paper_dt: Option<f64>, solver: &str) -> Result<TimeStep, ModelError> {
    Ok(match spec {
        TimeStepSpec::Auto { safety } => TimeStep::Auto { safety },
        TimeStepSpec::Fixed { dt, allow_unstable } => TimeStep::Fixed { dt, allow_unstable },
        TimeStepSpec::Paper { allow_unstable } => {
            let dt = paper_dt.ok_or_else(|| {
                ModelError::invalid(
                    &format!("{solver}.dt"),
                    "Paper",
                    "the paper's estimate needs the Calibrated surface model",
                )
            })?;
            TimeStep::Fixed { dt, allow_unstable }
        }
    })
}

/// The steady temperatures under `sources` (W per node, without the faces exchanging heat),
/// excluded particles at the initial temperature, with the solve's report. The solve is
/// repeated while the problem is nonlinear:
/// - radiation: re-linearised at each solution (Newton on the reduced system) until the
///   surface temperatures move by less than [`NEWTON_TOLERANCE`] ([`Surroundings`]);
/// - λ(T): the conductances re-evaluated at each iterate (Picard), the iterates mixed by
///   Anderson acceleration ([`Anderson`]), until a solve moves no temperature by more than
///   [`PICARD_TOLERANCE`] of the temperature span.
fn steady_run(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    problem: &ThermalProblem,
    system: &ThermalSystem<'_>,
    sources: &[f64],
) -> Result<ThermalRun, ModelError> {
    let net = system.network();
    let walls = &setup.walls;
    let mut around = setup.surroundings.clone();
    let mut g = system.conductances().to_vec();
    let first_link = g.len() - walls.len();
    let varies = model.conductivity_varies();
    let mut temps = vec![problem.initial_temperature; net.n_nodes()];
    bcs.constraints.impose(&mut temps);
    let mut mix = Anderson::new(ANDERSON_DEPTH);
    let (mut iterations, mut linear_iterations, mut wall_s) = (0u64, 0u64, 0.0);
    let mut last_change = 0.0f64;
    let st = loop {
        iterations += 1;
        if varies {
            let n = model.particles.len();
            let (contacts, half) = conductances_at(
                model,
                &setup.surface,
                problem.interface,
                walls,
                Some(WallContacts::particle_part(&temps, n)),
            )?;
            g[..first_link].copy_from_slice(&contacts);
            g[first_link..].copy_from_slice(&half);
            around.set_half(&half);
        }
        around.set_conductances(&mut g[first_link..]);
        let mut s = sources.to_vec();
        around.add_sources(walls, 0.0, &temps, &mut s);
        let st = solve_steady_temperature(net, &g, &bcs.constraints, &s, &problem.solve)?;
        let r = &st.solution.report;
        linear_iterations += r.iterations as u64;
        wall_s += r.wall_s + r.setup_s;
        let mut out = st.solution.values.clone();
        for &p in bcs.constraints.excluded() {
            out[p as usize] = problem.initial_temperature;
        }
        if !varies && !around.radiates() {
            temps = out;
            break st;
        }
        // How far this solve moved the temperatures (λ(T)) and the radiating surfaces.
        let (lo, hi) = out.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
        let moved = out
            .iter()
            .zip(&temps)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / (hi - lo).max(1.0);
        let next = if varies { mix.next(&temps, &out) } else { out };
        let turned = around.relinearise(walls, 0.0, &next);
        temps = next;
        last_change = if varies { moved.max(turned) } else { turned };
        let (lambda_done, radiation_done) =
            (!varies || moved <= PICARD_TOLERANCE, turned <= NEWTON_TOLERANCE);
        if lambda_done && radiation_done {
            break st;
        }
        if iterations as usize >= NEWTON_MAX_ITERATIONS {
            let (what, change, tol) = if lambda_done {
                ("surface temperatures (radiation)", turned, NEWTON_TOLERANCE)
            } else {
                ("temperatures (λ(T))", moved, PICARD_TOLERANCE)
            };
            return Err(ModelError::invalid(
                model.fields.bcs,
                format!("{what} still moving by {change:.3e} (relative) after {iterations} solves"),
                format!(
                    "a nonlinear steady state converging to {tol:e} within {NEWTON_MAX_ITERATIONS} solves (check the \
                     radiating faces, or the conductivities' temperature coefficients)"
                ),
            ));
        }
    };
    let r = &st.solution.report;
    let report = ThermalSolveReport {
        scheme: "steady".into(),
        steps: 0,
        dt: 0.0,
        dt_bound: system.stable_dt_bound().dt_max,
        dt_paper: setup.paper_dt,
        iterations: linear_iterations,
        residual: r.relative_residual,
        wall_s,
        contacts_per_s: 0.0,
        energy_balance_error: st.balance_error,
        excluded: bcs.constraints.excluded().len(),
        nonlinear_iterations: iterations,
        nonlinear_change: last_change,
        faces: around.report(walls, 0.0, &temps),
    };
    Ok(ThermalRun::from_nodes(walls, temps, Vec::new(), report))
}

/// Largest change of a temperature between two λ(T) iterates, relative to the temperature
/// span (at least 1 K), at which the steady iteration stops: a millionth, two orders below the
/// network's own error on the validation bars (`lambda-t`), where the iterates shrink ~50× per
/// solve (so the next would move them by ~2·10⁻⁸).
pub const PICARD_TOLERANCE: f64 = 1e-6;

/// Iterates the steady λ(T) iteration's Anderson acceleration mixes.
const ANDERSON_DEPTH: usize = 3;

/// Anderson acceleration of a fixed-point iteration x ← G(x) (type II, Walker & Ni 2011): the
/// next iterate G(x_k) − ΔG γ, γ minimising |f_k − ΔF γ| over the last few residuals
/// f = G(x) − x (ΔF, ΔG their differences), by the normal equations.
struct Anderson {
    depth: usize,
    /// The last G(x) and f = G(x) − x, oldest first.
    history: std::collections::VecDeque<(Vec<f64>, Vec<f64>)>,
}

impl Anderson {
    fn new(depth: usize) -> Self {
        Self {
            depth,
            history: std::collections::VecDeque::new(),
        }
    }

    /// The next iterate from `x` and its image `gx`.
    fn next(&mut self, x: &[f64], gx: &[f64]) -> Vec<f64> {
        let f: Vec<f64> = gx.iter().zip(x).map(|(g, x)| g - x).collect();
        self.history.push_back((gx.to_vec(), f));
        if self.history.len() > self.depth + 1 {
            self.history.pop_front();
        }
        let m = self.history.len() - 1;
        if m == 0 {
            return gx.to_vec();
        }
        // Differences of successive images (`image`) or residuals (not `image`).
        let diff = |i: usize, image: bool| -> Vec<f64> {
            let pick = |h: &(Vec<f64>, Vec<f64>)| if image { h.0.clone() } else { h.1.clone() };
            let (a, b) = (pick(&self.history[i + 1]), pick(&self.history[i]));
            a.iter().zip(&b).map(|(a, b)| a - b).collect()
        };
        let df: Vec<Vec<f64>> = (0..m).map(|i| diff(i, false)).collect();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
        let fk = &self.history[m].1;
        let a = nalgebra::DMatrix::from_fn(m, m, |i, j| dot(&df[i], &df[j]));
        let b = nalgebra::DVector::from_fn(m, |i, _| dot(&df[i], fk));
        // A tiny ridge keeps nearly collinear residuals solvable.
        let ridge = 1e-12 * a.diagonal().max().max(f64::MIN_POSITIVE);
        let a = a + nalgebra::DMatrix::identity(m, m) * ridge;
        let Some(gamma) = a.cholesky().map(|c| c.solve(&b)) else {
            self.history.clear();
            return gx.to_vec();
        };
        let mut next = gx.to_vec();
        for (i, &gi) in gamma.iter().enumerate() {
            let dg = diff(i, true);
            next.iter_mut().zip(&dg).for_each(|(v, d)| *v -= gi * d);
        }
        next
    }
}
