//! The electric problem on a model: resistivities (optionally ρ_e(T)), transmission surfaces,
//! contact conductances S/(ρ_e d), electrodes on particles or on container faces, the
//! potential solve and the Joule power per particle.

use demcon_core::{Face, Selector, TimeValue, Vec3};
use demcon_electric::{
    ElectricError, ElectricParams, ElectricSolution, ParticleConductivities, contact_conductances,
    give_link_joule_to_particles, joule_power, solve_potential,
};
use demcon_graph::{InterfaceRule, SurfaceModel, WallContacts, contact_surfaces, representative_volumes};
use demcon_network::FloatingPolicy;
use serde::Serialize;

use crate::assembly::{CtSpec, SurfaceSpec, network_with_walls};
use crate::calibrate::calibrate_ct;
use crate::defects::{Physics, apply_to_contacts, apply_to_walls};
use crate::error::ModelError;
use crate::model::Model;

/// Where an electrode holds its potential.
#[derive(Debug, Clone, PartialEq)]
pub enum ElectrodeAt {
    /// On the selected particles.
    Particles(Selector),
    /// On a container face, linked to the particles touching it by half-contacts.
    Face(Face),
}

/// A fixed potential.
#[derive(Debug, Clone, PartialEq)]
pub struct Electrode {
    /// Where.
    pub at: ElectrodeAt,
    /// Potential (V), constant or a table in time (a transient's electrodes: [`ElectricProblem::at`]).
    pub potential: TimeValue,
}

/// Everything the electric physics of a run needs, on plain types.
#[derive(Debug, Clone, PartialEq)]
pub struct ElectricProblem {
    /// Transmission surfaces of the electric network.
    pub surface: SurfaceSpec,
    /// Conductivity of a contact across two phases.
    pub interface: InterfaceRule,
    /// Electrodes (errors name `electric.electrodes[i]`).
    pub electrodes: Vec<Electrode>,
    /// A current (A) imposed from the first electrode into the body and out through the
    /// second (exactly two): the second keeps its potential, the first's is found (the value
    /// it gives is not used). `None`: the electrodes hold their potentials.
    pub current: Option<f64>,
    /// Share of each branch's Joule power given to its particles, in [0, 1].
    pub eta: f64,
    /// Floating clusters: excluded or refused.
    pub floating: FloatingPolicy,
    /// Re-solve with ρ_e(T) when a temperature moved more than this (K); `None`: one-way.
    pub recouple_tolerance: Option<f64>,
    /// The linear solver ([`crate::default_solve_params`] by default).
    pub solve: demcon_network::SolveParams,
}

impl ElectricProblem {
    /// The faces carrying an electrode, in order.
    pub fn face_electrodes(&self) -> Vec<Face> {
        self.electrodes
            .iter()
            .filter_map(|e| match e.at {
                ElectrodeAt::Face(f) => Some(f),
                ElectrodeAt::Particles(_) => None,
            })
            .collect()
    }

    /// Whether an electrode's potential follows a time table.
    pub fn tabled(&self) -> bool {
        self.electrodes.iter().any(|e| !e.potential.is_constant())
    }

    /// The problem at time `t` (s): every electrode's potential its value then.
    pub fn at(&self, t: f64) -> ElectricProblem {
        let mut p = self.clone();
        for e in &mut p.electrodes {
            e.potential = TimeValue::Constant(e.potential.at(t));
        }
        p
    }

    /// The electrodes' potentials at time `t` (V), in order.
    pub fn potentials_at(&self, t: f64) -> Vec<f64> {
        self.electrodes.iter().map(|e| e.potential.at(t)).collect()
    }

    /// The problem with an `Auto` C_t of its surfaces replaced by the value calibrated on
    /// `model` (so a coupled run calibrates once, not at every re-solve).
    pub fn resolved(&self, model: &Model) -> Result<ElectricProblem, ModelError> {
        let mut p = self.clone();
        if let SurfaceSpec::Calibrated(CtSpec::Auto) = p.surface
            && let SurfaceModel::Calibrated { c_t } = electric_surface_model(model, &p.surface)?
        {
            p.surface = SurfaceSpec::Calibrated(CtSpec::Value(c_t));
        }
        Ok(p)
    }
}

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
    /// The face electrodes and their links.
    pub walls: WallContacts,
    /// The potential of each face electrode (V), in the order of `walls`.
    pub wall_potentials: Vec<f64>,
    /// The transmission-surface model of the electric network (C_t resolved).
    pub surface: SurfaceModel,
    /// Representative volume per particle under `surface` (m³): the Laguerre cell's, or
    /// V_p/φ (calibrated), V_p/f_v(n_p) (Terreros α).
    pub rep_volumes: Vec<f64>,
    /// Joule power per particle (W), η applied: the heat the particle receives.
    pub joule: Vec<f64>,
    /// Summary.
    pub report: ElectricReport,
    /// Findings (floating clusters…).
    pub diagnostics: Vec<String>,
}

impl ElectricRun {
    /// Potentials of every node of the electric network (V): the particles, then the face
    /// electrodes.
    pub fn node_potentials(&self) -> Vec<f64> {
        WallContacts::join_nodes(&self.potentials, &self.wall_potentials)
    }

    /// The current density j_p of every particle (A/m², the direction the current flows: from
    /// high to low potential), by the heat flux's construction ([`crate::flux_dipoles`] over
    /// the contacts and the electrode links, divided by twice [`ElectricRun::rep_volumes`]):
    /// exact in a uniform field on Laguerre cells. 0 on excluded (floating) particles.
    pub fn current_density(&self, model: &Model) -> Vec<Vec3> {
        let d = crate::flux_dipoles(model, &self.walls, &self.conductances, &self.node_potentials());
        crate::flux_density(&d, &self.rep_volumes)
    }
}

/// Summary of an electric solve.
#[derive(Debug, Clone, Serialize)]
pub struct ElectricReport {
    /// Equivalent resistance ΔV/I (Ω), two electrodes only.
    pub resistance_ohm: Option<f64>,
    /// The potential of each electrode (V), in the order given; under an imposed current the
    /// first one's is the solve's.
    pub electrode_potentials: Vec<f64>,
    /// Current entering (A).
    pub current_in: f64,
    /// Current leaving (A).
    pub current_out: f64,
    /// |I_in − I_out| / I_in.
    pub current_mismatch: f64,
    /// Total Joule power (W): Σ I²/G over the branches (contacts and electrode links), the
    /// power the current dissipates, = ΔV·I between two electrodes; whatever η.
    pub joule_w: f64,
    /// The part of it that heats the particles (W): η · `joule_w`, = Σ of the per-particle
    /// Joule power.
    pub joule_heat_w: f64,
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
pub fn electric_surface_model(model: &Model, surface: &SurfaceSpec) -> Result<SurfaceModel, ModelError> {
    Ok(match surface {
        SurfaceSpec::Calibrated(CtSpec::Auto) => SurfaceModel::Calibrated {
            c_t: calibrate_ct(model)?.c_t,
        },
        s => s.model(None),
    })
}

/// Electric conductivities of every particle ([`demcon_electric::particle_conductivities`]);
/// `temperatures` (°C), when given, evaluate ρ_e(T), else each material's ρ_e at its reference
/// temperature.
pub fn particle_conductivities(
    model: &Model,
    temperatures: Option<&[f64]>,
) -> Result<ParticleConductivities, ModelError> {
    demcon_electric::particle_conductivities(
        &model.materials.materials,
        &model.particles.phases,
        &model.laminates(),
        temperatures,
    )
    .map_err(refusal)
}

/// A bad value of the electric physics as a refusal at the field it names (a material's
/// resistivity), the other errors unchanged.
fn refusal(e: ElectricError) -> ModelError {
    match e {
        ElectricError::InvalidParameter {
            field,
            value,
            allowed,
        } => ModelError::invalid(&field, value, allowed),
        e => e.into(),
    }
}

/// Contact conductances 1/R_pq = S_pq / (ρ_e,pq d_pq) (S). `temperatures` (°C), when given,
/// evaluate ρ_e(T) per particle; the contact value combines the two particles' conductivities
/// by the interface rule (two half-bonds in series for the harmonic mean).
pub fn electric_conductances(
    model: &Model,
    surface: &SurfaceSpec,
    interface: InterfaceRule,
    temperatures: Option<&[f64]>,
) -> Result<Vec<f64>, ModelError> {
    let sm = electric_surface_model(model, surface)?;
    let sigma = particle_conductivities(model, temperatures)?;
    conductances_with_defects(model, &sm, interface, &sigma)
}

/// [`contact_conductances`] on the model's contacts, its defects applied.
fn conductances_with_defects(
    model: &Model,
    sm: &SurfaceModel,
    rule: InterfaceRule,
    sigma: &ParticleConductivities,
) -> Result<Vec<f64>, ModelError> {
    let s = contact_surfaces(&model.graph, &model.particles, sm)?;
    let mut g = contact_conductances(&model.graph, &s.area, sigma, rule);
    apply_to_contacts(&model.defect_view(), &s.area, &mut g, Physics::Electric);
    Ok(g)
}

/// The nodes and potential (V, at t = 0) of each electrode: its selected particles, or the wall
/// node of its face (`walls`, one per face electrode in order).
fn electrode_nodes(
    model: &Model,
    problem: &ElectricProblem,
    walls: &WallContacts,
) -> Result<Vec<(Vec<u32>, f64)>, ModelError> {
    let mut next_wall = 0..walls.n_walls();
    let mut electrodes: Vec<(Vec<u32>, f64)> = Vec::new();
    for (i, e) in problem.electrodes.iter().enumerate() {
        match &e.at {
            ElectrodeAt::Particles(sel) => {
                let field = format!("{}[{i}].select", model.fields.electrodes);
                let ids = sel
                    .select_nonempty(&model.particles, &model.container, &format!("electrode {i}"))
                    .map_err(|err| ModelError::at(&field, err))?;
                electrodes.push((ids, e.potential.at(0.0)));
            }
            ElectrodeAt::Face(_) => {
                let w = next_wall.next().expect("one wall per face electrode");
                electrodes.push((vec![walls.node(w)], e.potential.at(0.0)));
            }
        }
    }
    Ok(electrodes)
}

/// The solution carrying `current` (A) from the first of two `electrodes` to the second: a
/// unit difference solved by `solve`, then scaled (Kirchhoff is linear); with the electrodes'
/// potentials (V).
fn solve_at_current(
    model: &Model,
    problem: &ElectricProblem,
    current: f64,
    electrodes: &mut [(Vec<u32>, f64)],
    solve: impl Fn(&[(Vec<u32>, f64)]) -> Result<ElectricSolution, ElectricError>,
) -> Result<(ElectricSolution, Vec<f64>), ModelError> {
    let [(_, first), (_, ground)] = &mut electrodes[..] else {
        return Err(ModelError::invalid(
            model.fields.electrodes,
            format!("{} electrode(s)", problem.electrodes.len()),
            "exactly two electrodes with an imposed current (it enters by the first, leaves by the second)",
        ));
    };
    *first = *ground + 1.0;
    let ground = *ground;
    let unit = solve(electrodes)?;
    let i_unit = unit.electrode_currents[0];
    if !(i_unit.is_finite() && i_unit > 0.0) {
        return Err(ModelError::invalid(
            model.fields.electrodes,
            format!("{i_unit:e} A at a 1 V difference"),
            "two electrodes a current can flow between (the body joins them)",
        ));
    }
    let factor = current / i_unit;
    Ok((unit.rescaled(ground, factor), vec![ground + factor, ground]))
}

/// The electric network of a model: the conductances of its contacts and of its face
/// electrodes' links, and the network extended by one node per face electrode.
#[derive(Debug, Clone)]
pub struct ElectricNetwork {
    /// The network with the face electrodes' nodes (`None`: no face electrode, the model's).
    pub network: Option<demcon_network::Network>,
    /// Conductances 1/R (S): the contacts, then the face-electrode links.
    pub conductances: Vec<f64>,
    /// The face electrodes and their links.
    pub walls: WallContacts,
    /// The transmission-surface model (C_t resolved).
    pub surface: SurfaceModel,
}

/// The electric network of `model` under `problem` (`temperatures`, °C, feed ρ_e(T)): what
/// [`solve_electric`] solves, for a caller that assembles it itself (an MPI rank's block).
pub fn electric_network(
    model: &Model,
    problem: &ElectricProblem,
    temperatures: Option<&[f64]>,
) -> Result<ElectricNetwork, ModelError> {
    let sm = electric_surface_model(model, &problem.surface)?;
    let sigma = particle_conductivities(model, temperatures)?;
    let g = conductances_with_defects(model, &sm, problem.interface, &sigma)?;
    let faces = problem.face_electrodes();
    let walls = model.wall_contacts(&faces, model.fields.electrodes)?;
    let wall_s = walls.surfaces(&model.particles, &model.graph.surface_degrees(), &sm);
    let mut wall_g = walls.conductances(&wall_s, |p, e, h| sigma.half_bond(p, e, h));
    apply_to_walls(
        &model.defect_view(),
        &walls,
        &wall_s,
        &mut wall_g,
        Physics::Electric,
    );
    let (network, conductances) = network_with_walls(model, &walls, g, wall_g)?;
    Ok(ElectricNetwork {
        network,
        conductances,
        walls,
        surface: sm,
    })
}

/// Solves the potential with the problem's electrodes; `temperatures` (°C) feed ρ_e(T).
///
/// Face electrodes add one node per face to the network, held at the potential and linked to
/// the particles touching the face by half-contacts σ_p S_p / h_p ([`WallContacts`], the
/// construction of the thermal `WallTemperature`). The Joule power of such a link goes wholly
/// to its particle (the face is not a particle).
pub fn solve_electric(
    model: &Model,
    problem: &ElectricProblem,
    temperatures: Option<&[f64]>,
) -> Result<ElectricRun, ModelError> {
    let start = std::time::Instant::now();
    let n = model.particles.len();
    let m = model.graph.len();
    let ElectricNetwork {
        network: ext,
        conductances: g,
        walls,
        surface: sm,
    } = electric_network(model, problem, temperatures)?;
    let net = ext.as_ref().unwrap_or_else(|| model.network());
    let mut electrodes = electrode_nodes(model, problem, &walls)?;
    let params = ElectricParams {
        floating: problem.floating,
        solve: problem.solve,
    };
    let (sol, held) = match problem.current {
        None => (
            solve_potential(net, &g, &electrodes, &params)?,
            electrodes.iter().map(|e| e.1).collect::<Vec<f64>>(),
        ),
        Some(current) => {
            let solve = |e: &[(Vec<u32>, f64)]| solve_potential(net, &g, e, &params);
            solve_at_current(model, problem, current, &mut electrodes, solve)?
        }
    };
    let mut joule = joule_power(net, &g, &sol.potentials, problem.eta)?;
    // The power dissipated, Σ G Δu² over every branch (electrode links included), whatever η.
    let dissipated: f64 = net
        .edges()
        .iter()
        .zip(&g)
        .map(|(&[p, q], g)| {
            let du = sol.potentials[p as usize] - sol.potentials[q as usize];
            g * du * du
        })
        .sum();
    // A wall link's power: the half booked to the wall node goes to the particle too.
    let links = walls
        .wall_of_links()
        .enumerate()
        .map(|(k, w)| (walls.particle[k], walls.node(w), g[m + k]));
    give_link_joule_to_particles(&mut joule, &sol.potentials, problem.eta, links);
    // The wall nodes keep no Joule heat (their half went to the particle above).
    let joule = WallContacts::split_nodes(joule, n).0;
    let (potentials, wall_potentials) = WallContacts::split_nodes(sol.potentials, n);
    let rep_volumes = representative_volumes(&model.graph, &model.particles, &sm, model.phi)?;
    let r = &sol.report;
    Ok(ElectricRun {
        report: ElectricReport {
            resistance_ohm: sol.resistance_ohm,
            electrode_potentials: held,
            current_in: sol.current_in,
            current_out: sol.current_out,
            current_mismatch: sol.current_mismatch,
            joule_w: dissipated,
            joule_heat_w: joule.iter().sum(),
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
        walls,
        wall_potentials,
        surface: sm,
        rep_volumes,
        joule,
    })
}
