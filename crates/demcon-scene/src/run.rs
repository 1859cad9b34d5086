//! The run pipeline, as named stages: packing → phases → tessellation or contacts → network →
//! thermal setup (surfaces, walls, capacities, boundary conditions) → solve (thermal, electric,
//! or both coupled) → flux → halo → probes (ETC, probes, profiles). Each stage is timed (wall
//! time and memory) by [`Stages`]; outputs are written by [`crate::write_outputs`]. The
//! physics lives in `demcon-model`; this file only sequences it on the scene's [`Problem`].

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use demcon_core::{StageObserver, Stages, Vec3};
use demcon_graph::WallContacts;
use demcon_model::{
    Checkpointing, ElectricRun, EtcValue, ExtraSources, HomogenizeRun, Model, ModelError, RunCheckpoint,
    ThermalBcs, ThermalProblem, ThermalRun, ThermalSetup, couple_checkpointed, homogenize_electric,
    homogenize_thermal, solve_electric, solve_thermal_checkpointed, thermal_bcs, thermal_setup,
};
use demcon_post::{Domain, HaloReport, ProbeIndex, halo_flux_blocked};
use demcon_thermal::CheckpointEvery;
use serde::Serialize;

use crate::build::build_model_staged;
use crate::checkpoint::{Fingerprint, read_checkpoint, write_checkpoint};
use crate::config::*;
use crate::convert::{self, HomogenizePlan, PostPlan, Problem};
use crate::error::SceneError;
use crate::scene::Scene;

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
    /// Whether every particle the value is read from was solved for (false: the reading
    /// includes particles excluded from the solve, e.g. a floating cluster of a steady run,
    /// whose values are not results).
    pub solved: bool,
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
    /// Per point: read from solved particles only (see [`ProbeValue::solved`]).
    pub solved: Vec<bool>,
}

/// Everything a run produced, in memory.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// The model (particles, contacts, network).
    pub model: Model,
    /// Thermal network values, when the scene has thermal physics.
    pub thermal_setup: Option<ThermalSetup>,
    /// Resolved thermal boundary conditions and sources.
    pub thermal_bcs: Option<ThermalBcs>,
    /// Thermal solution.
    pub thermal: Option<ThermalRun>,
    /// Electric solution.
    pub electric: Option<ElectricRun>,
    /// Per-particle physical heat flux (W/m²).
    pub flux: Option<Vec<Vec3>>,
    /// Halo-smoothed flux (W/m²) and whether each particle's Halo is cut by the boundary.
    pub halo: Option<Halo>,
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
    /// Wall time of each stage.
    pub stages: Stages,
    /// Wall time of the post-processing (s).
    pub post_s: f64,
    /// Wall time of the whole run (s).
    pub wall_s: f64,
    /// Where the run continued from, when it was resumed from a checkpoint.
    pub resumed: Option<Resumed>,
    /// The effective tensors of a periodic homogenisation.
    pub homogenization: Option<Homogenization>,
    /// A transient's fields at its output times before the end, for the VTK time series (the
    /// end's fields are the run's own).
    pub series: Vec<SeriesEntry>,
    /// The end time of a transient (s); `None` for a steady run or without thermal physics.
    pub t_end: Option<f64>,
    /// The Laguerre cells as polyhedra, when the outputs ask for `cells.vtu`.
    pub cells: Option<demcon_post::Polyhedra>,
}

/// A transient's fields at one output time before its end.
#[derive(Debug, Clone)]
pub struct SeriesEntry {
    /// Time (s).
    pub t: f64,
    /// Index of the temperatures in [`ThermalRun::snapshots`].
    pub snapshot: usize,
    /// Per-particle heat flux (W/m²), when the outputs ask for it.
    pub flux: Option<Vec<Vec3>>,
    /// Halo-smoothed flux (W/m²) and whether each particle's Halo is cut by the boundary.
    pub halo: Option<(Vec<Vec3>, Vec<bool>)>,
    /// Whether the run's (final) electric solution holds at this time too: true unless the
    /// potential is re-solved during the transient (`recouple_tolerance`, electrode tables).
    pub electric: bool,
}

/// The effective tensors of a periodic homogenisation.
#[derive(Debug, Clone)]
pub struct Homogenization {
    /// Thermal conductivity tensor (W/(m·K)), when `thermal.solver` is `Homogenize`.
    pub thermal: Option<HomogenizeRun>,
    /// Electric conductivity tensor (S/m), when `electric.homogenize` is set.
    pub electric: Option<HomogenizeRun>,
}

/// Where a resumed run continued from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Resumed {
    /// Steps done before (by the interrupted run).
    pub steps: u64,
    /// Time reached (s).
    pub t: f64,
}

/// Options of a run.
#[derive(Default)]
pub struct RunOptions<'a> {
    /// Packing progress callback.
    pub progress: Option<&'a dyn Fn(&demcon_packing::PackProgress)>,
    /// Transient progress callback: (steps done, steps total), at most ~100 calls per run.
    pub transient_progress: Option<demcon_thermal::ProgressFn>,
    /// Sees every stage start and end (wall time, memory): a progress display.
    pub stages: Option<Arc<dyn StageObserver>>,
    /// Checkpoints of the transient (written on the scene's `thermal.checkpoint` schedule) and
    /// resuming from one; none without it.
    pub checkpoint: Option<CheckpointOptions<'a>>,
}

/// Checkpoints of a run: the file, whether to continue from it, and a hook after each write.
pub struct CheckpointOptions<'a> {
    /// The checkpoint file ([`crate::checkpoint::checkpoint_path`] of the output folder),
    /// written on the scene's schedule (`thermal.checkpoint`; never without it). It is left in
    /// place when the run fails or is killed; the caller removes it once the outputs are
    /// written ([`crate::checkpoint::remove_checkpoint`]).
    pub path: PathBuf,
    /// Continue the interrupted run whose checkpoint is `path` (refused when there is none, or
    /// it was written for another scene or packing, or the scene is steady). Without it, a run
    /// refuses to start while `path` exists: it would overwrite an interrupted run's state.
    pub resume: bool,
    /// Called after each checkpoint is written, with the steps done and the time reached (s):
    /// `Break` stops the run there ([`SceneError::Stopped`]), leaving the checkpoint as a kill
    /// would.
    pub after_write: Option<&'a dyn Fn(u64, f64) -> ControlFlow<()>>,
}

/// Runs a scene end to end (in memory; see [`crate::write_outputs`] for files). With
/// [`RunOptions::checkpoint`], a transient writes checkpoints on the scene's schedule, or
/// continues from one bit for bit: the resumed run's results equal the uninterrupted run's
/// (wall times aside).
pub fn run(scene: &Scene, opts: &RunOptions<'_>) -> Result<RunResult, SceneError> {
    let t0 = Instant::now();
    let cfg = scene.config();
    // The checkpoint to continue from, checked against the scene before the build.
    let resume = match &opts.checkpoint {
        Some(ck) => checkpoint_to_resume(cfg, ck)?,
        None => None,
    };
    let mut stages = Stages::new(opts.stages.clone());
    let model = build_model_staged(scene, opts.progress, &mut stages)?;
    let plan = match &opts.checkpoint {
        Some(ck) => {
            let fingerprint = Fingerprint::of_scene(cfg).with_packing(&model);
            if let Some((written, _)) = &resume {
                written.check_packing(&fingerprint, &ck.path)?;
            }
            Some(CheckpointPlan {
                path: &ck.path,
                fingerprint,
                every: convert::checkpoint_every(cfg).unwrap_or_default(),
                resume: resume.map(|(_, c)| c),
                after_write: ck.after_write,
            })
        }
        None => None,
    };
    let resumed = plan.as_ref().and_then(|p| p.resume.as_ref()).map(|c| Resumed {
        steps: c.transient.steps,
        t: c.transient.t,
    });
    let mut result = run_stages(scene, model, stages, opts.transient_progress.clone(), plan)?;
    result.resumed = resumed;
    result.wall_s = t0.elapsed().as_secs_f64();
    Ok(result)
}

/// The checkpoint `ck` asks to resume from, read and checked against the scene; none for a
/// fresh run, which refuses to overwrite an interrupted run's checkpoint.
fn checkpoint_to_resume(
    cfg: &SceneConfig,
    ck: &CheckpointOptions<'_>,
) -> Result<Option<(Fingerprint, RunCheckpoint)>, SceneError> {
    if !ck.resume {
        if ck.path.exists() {
            return Err(SceneError::Checkpoint {
                path: ck.path.clone(),
                problem:
                    "holds the state of an interrupted run: continue it with --resume, or remove the file \
                          to start over"
                        .into(),
            });
        }
        return Ok(None);
    }
    match &cfg.thermal {
        None => {
            return Err(SceneError::invalid(
                "thermal",
                "none",
                "a pure electric scene solves a steady state: there is nothing to resume (only a transient, \
                 thermal.solver Explicit or Implicit, can be resumed)",
            ));
        }
        Some(t)
            if matches!(
                t.solver,
                ThermalSolverConfig::Steady | ThermalSolverConfig::Homogenize
            ) =>
        {
            return Err(SceneError::invalid(
                "thermal.solver",
                format!("{:?}", t.solver),
                "a steady solve has nothing to resume (only a transient, Explicit or Implicit, can be resumed)",
            ));
        }
        Some(_) => {}
    }
    let (written, state) = read_checkpoint(&ck.path)?;
    written.check_scene(&Fingerprint::of_scene(cfg), &ck.path)?;
    Ok(Some((written, state)))
}

/// Checkpoints of one run, resolved: the file, what it is written for, the schedule, the
/// state to continue from.
struct CheckpointPlan<'a> {
    path: &'a Path,
    fingerprint: Fingerprint,
    every: CheckpointEvery,
    resume: Option<RunCheckpoint>,
    after_write: Option<&'a dyn Fn(u64, f64) -> ControlFlow<()>>,
}

/// Runs the physics and post-processing of `scene` on an already built model (so one packing
/// can serve several solvers).
pub fn run_on_model(scene: &Scene, model: Model) -> Result<RunResult, SceneError> {
    run_stages(scene, model, Stages::default(), None, None)
}

/// The stages after the build.
fn run_stages(
    scene: &Scene,
    mut model: Model,
    mut stages: Stages,
    progress: Option<demcon_thermal::ProgressFn>,
    checkpoints: Option<CheckpointPlan<'_>>,
) -> Result<RunResult, SceneError> {
    let t0 = Instant::now();
    let mut problem = scene.problem().clone();
    if let Some(t) = problem.thermal.as_mut() {
        t.progress = progress;
    }
    let mut diagnostics = scene.warnings().to_vec();
    diagnostics.extend(model_diagnostics(&model));
    if let Some(plan) = &problem.homogenize {
        if let Some(cells) = model.graph.cells.as_deref() {
            diagnostics.extend(anisotropy_warnings(&model, &cells.facet_area));
        }
        let h = stages.time("homogenize", || homogenize(&model, plan))?;
        let cells = cell_polyhedra(&mut stages, &model, &problem)?;
        return Ok(RunResult {
            thermal_setup: None,
            thermal_bcs: None,
            thermal: None,
            electric: None,
            flux: None,
            halo: None,
            etc: None,
            probes: Vec::new(),
            profiles: Vec::new(),
            domain: Domain::of_container(&model.container)?,
            diagnostics,
            post_s: 0.0,
            stages,
            wall_s: t0.elapsed().as_secs_f64(),
            resumed: None,
            homogenization: Some(h),
            series: Vec::new(),
            t_end: None,
            cells,
            model,
        });
    }
    let thermal = match &problem.thermal {
        Some(tp) => Some(stages.time("thermal setup", || {
            let setup = setup_thermal(&model, tp, &mut diagnostics)?;
            // With walls the thermal solve and its post-processing read their own network
            // (wall nodes included): free the model's until a solve reads it (0.17 kB per
            // particle for a Laguerre graph).
            if !setup.0.walls.is_empty() && problem.electric.is_none() {
                model.release_network();
            }
            Ok::<_, SceneError>(setup)
        })?),
        None => None,
    };
    let (thermal_run, electric) = stages.time("solve", || {
        solve(&model, &problem, thermal.as_ref(), checkpoints, &mut diagnostics)
    })?;
    let (mut thermal_setup, thermal_bcs) = thermal.unzip();
    // λ(T): the flows, the flux, the ETC and the files read the conductances of the end state.
    if let (Some(setup), Some(th), Some(tp)) =
        (thermal_setup.as_mut(), thermal_run.as_ref(), &problem.thermal)
        && model.conductivity_varies()
    {
        setup.set_in_force(&model, tp.interface, &th.temperatures)?;
    }
    let t_post = Instant::now();
    let post = post_process(
        &mut stages,
        &PostInputs {
            model: &model,
            problem: &problem,
            setup: thermal_setup.as_ref(),
            bcs: thermal_bcs.as_ref(),
            th: thermal_run.as_ref(),
            el: electric.as_ref(),
        },
    )?;
    if let Some(e) = &post.etc {
        diagnostics.extend(e.warnings.iter().cloned());
    }
    Ok(RunResult {
        model,
        thermal_setup,
        thermal_bcs,
        thermal: thermal_run,
        electric,
        flux: post.flux,
        halo: post.halo,
        etc: post.etc,
        probes: post.probes,
        profiles: post.profiles,
        domain: post.domain,
        diagnostics,
        post_s: t_post.elapsed().as_secs_f64(),
        stages,
        wall_s: t0.elapsed().as_secs_f64(),
        resumed: None,
        homogenization: None,
        series: post.series,
        cells: post.cells,
        t_end: problem
            .thermal
            .as_ref()
            .filter(|t| t.solver.is_transient())
            .map(|t| t.solver.final_time()),
    })
}

/// The periodic homogenisation of the plan: the thermal tensor, the electric one, or both.
fn homogenize(model: &Model, plan: &HomogenizePlan) -> Result<Homogenization, SceneError> {
    let thermal = match &plan.thermal {
        Some((surface, rule)) => Some(homogenize_thermal(model, surface, *rule, &plan.solve)?),
        None => None,
    };
    let electric = match &plan.electric {
        Some((surface, rule)) => Some(homogenize_electric(model, surface, *rule, &plan.solve)?),
        None => None,
    };
    Ok(Homogenization { thermal, electric })
}

/// What building the model found: contact diagnostics, carved particles.
/// The inconsistency of an anisotropic material's two-point flux above which a run warns
/// ([`Model::anisotropy_consistency`], relative to |K|).
const ANISOTROPY_WARNING: f64 = 0.01;

/// A warning per anisotropic material whose two-point flux on this model's bonds (surfaces
/// `areas`, m²) is further than [`ANISOTROPY_WARNING`] from its tensor.
fn anisotropy_warnings(model: &Model, areas: &[f64]) -> Vec<String> {
    model
        .anisotropy_consistency(areas)
        .into_iter()
        .filter(|(_, err)| *err > ANISOTROPY_WARNING)
        .map(|(name, err)| {
            format!(
                "material `{name}`: its conductivity tensor enters each bond as eᵀ K e, and on these cells the \
                 network conducts as a tensor {:.1} % (of |K|) away from K (the bonds are not K-orthogonal: \
                 random cells; a lattice along K's axes is exact) — effective values and fields of this material \
                 carry that error (validation case `anisotropy`)",
                100.0 * err
            )
        })
        .collect()
}

fn model_diagnostics(model: &Model) -> Vec<String> {
    let mut d = model.report.contacts.diagnostics.clone();
    if model.report.carved_away > 0 {
        d.push(format!("{} particles carved away", model.report.carved_away));
    }
    if let Some(r) = &model.report.defects {
        if r.cut_by_cracks + r.broken_bonds > 0 {
            d.push(format!(
                "{} contacts cut by cracks, {} broken bonds cut ({} components once cut)",
                r.cut_by_cracks, r.broken_bonds, r.components_after_cuts
            ));
        }
        if r.broken_not_contacts > 0 {
            d.push(format!(
                "{} pairs of cut_contacts are not contacts of the model (ignored)",
                r.broken_not_contacts
            ));
        }
        if !model.defects.spec.interfaces.is_empty() && r.interface_contacts == 0 {
            d.push(
                "interfaces: no contact crosses a listed interface (the materials never meet in this body): \
                 the interface resistances change nothing"
                    .into(),
            );
        }
        if !model.defects.spec.damage.is_empty() && r.damaged_contacts == 0 {
            d.push(
                "damage: no contact lies in a damage region (outside the body?): nothing is damaged".into(),
            );
        }
        d.extend(r.warnings.iter().cloned());
    }
    d
}

/// Thermal setup and boundary conditions (C_t calibrated here when `Auto`).
fn setup_thermal(
    model: &Model,
    tp: &ThermalProblem,
    diagnostics: &mut Vec<String>,
) -> Result<(ThermalSetup, ThermalBcs), SceneError> {
    let setup = thermal_setup(model, tp)?;
    if setup.clamped > 0 {
        diagnostics.push(format!(
            "{} particles outside the Terreros table's 4–20 neighbours (α clamped)",
            setup.clamped
        ));
    }
    let bcs = thermal_bcs(model, &setup, tp)?;
    diagnostics.extend(bcs.warnings.iter().cloned());
    diagnostics.extend(anisotropy_warnings(model, setup.areas(model)));
    diagnostics.extend(
        bcs.constraints
            .diagnostics()
            .iter()
            .map(|d| format!("thermal: {d}")),
    );
    Ok((setup, bcs))
}

/// The thermal solve, the electric solve, or both coupled; a transient writes the checkpoints
/// of `checkpoints` and continues from its state.
fn solve(
    model: &Model,
    problem: &Problem,
    thermal: Option<&(ThermalSetup, ThermalBcs)>,
    checkpoints: Option<CheckpointPlan<'_>>,
    diagnostics: &mut Vec<String>,
) -> Result<(Option<ThermalRun>, Option<ElectricRun>), SceneError> {
    // Why a checkpoint stopped the run (a write that failed, or `after_write`).
    let mut stopped: Option<SceneError> = None;
    let mut sink = |c: RunCheckpoint| -> Result<(), ModelError> {
        let Some(plan) = checkpoints.as_ref() else {
            return Ok(());
        };
        let (steps, t) = (c.transient.steps, c.transient.t);
        let stop = match write_checkpoint(plan.path, &plan.fingerprint, &c) {
            Err(e) => Some(e),
            Ok(()) => match plan.after_write.map(|f| f(steps, t)) {
                Some(ControlFlow::Break(())) => Some(SceneError::Stopped {
                    steps,
                    t,
                    path: plan.path.into(),
                }),
                _ => None,
            },
        };
        match stop {
            None => Ok(()),
            Some(e) => {
                stopped = Some(e);
                Err(ModelError::invalid("checkpoint", t, "the run was stopped"))
            }
        }
    };
    let checkpointing = checkpoints.as_ref().map(|p| Checkpointing {
        every: p.every,
        resume: p.resume.as_ref(),
        sink: &mut sink,
    });
    let solved = match (&problem.thermal, thermal, &problem.electric) {
        (Some(tp), Some((setup, bcs)), Some(ep)) => {
            couple_checkpointed(model, setup, bcs, tp, ep, checkpointing).map(|c| {
                diagnostics.extend(c.diagnostics);
                (Some(c.thermal), Some(c.electric))
            })
        }
        (Some(tp), Some((setup, bcs)), None) => {
            let extra = ExtraSources {
                initial: None,
                update: &mut |_, _| Ok(None),
            };
            solve_thermal_checkpointed(model, setup, bcs, tp, extra, checkpointing).map(|t| (Some(t), None))
        }
        (None, _, Some(ep)) => solve_electric(model, ep, None).map(|e| (None, Some(e))),
        _ => unreachable!("validated: a scene has thermal or electric physics, and thermal physics a setup"),
    };
    if let Some(e) = stopped {
        return Err(e);
    }
    let (th, el) = solved?;
    if let Some(el) = &el {
        diagnostics.extend(el.diagnostics.iter().cloned());
    }
    if let Some(r) = th.as_ref().map(|t| &t.report)
        && r.scheme == "forward-euler"
        && r.dt > r.dt_bound
    {
        diagnostics.push(format!(
            "thermal: the explicit step dt = {:.3e} s is {:.2}× the stability bound {:.3e} s (allow_unstable): \
             the run was watched for divergence, but its accuracy is not guaranteed",
            r.dt,
            r.dt / r.dt_bound,
            r.dt_bound
        ));
    }
    Ok((th, el))
}

/// What the post-processing computed.
struct Post {
    series: Vec<SeriesEntry>,
    cells: Option<demcon_post::Polyhedra>,
    flux: Option<Vec<Vec3>>,
    halo: Option<Halo>,
    etc: Option<EtcValue>,
    probes: Vec<ProbeValue>,
    profiles: Vec<ProfileValues>,
    domain: Domain,
}

/// A field sampled by probes and profiles.
struct SampledField {
    /// `temperature`, `potential`, `flux_magnitude`, `halo_flux_magnitude`.
    name: &'static str,
    /// Time (s).
    t: f64,
    /// Value per particle.
    values: Vec<f64>,
    /// 1 where the particle was solved for, 0 where it was excluded.
    solved: std::rc::Rc<Vec<f64>>,
}

/// What the post-processing reads: the model, the scene and the solutions.
struct PostInputs<'a> {
    model: &'a Model,
    problem: &'a Problem,
    setup: Option<&'a ThermalSetup>,
    bcs: Option<&'a ThermalBcs>,
    th: Option<&'a ThermalRun>,
    el: Option<&'a ElectricRun>,
}

/// Flux, Halo, ETC, probes and profiles (only what the outputs ask for), timed as the stages
/// `flux`, `halo` and `probes`.
fn post_process(stages: &mut Stages, inp: &PostInputs<'_>) -> Result<Post, SceneError> {
    let PostInputs {
        model,
        problem,
        setup,
        th,
        ..
    } = *inp;
    let plan = &problem.post;
    let domain = match &problem.model.carve {
        Some((region, _)) => Domain::of_region(region.clone()),
        None => Domain::of_container(&model.container)?,
    };
    let (mut flux, mut halo) = (None, None);
    if let (true, Some(th), Some(s)) = (plan.flux, th, setup) {
        let end = problem.thermal.as_ref().map_or(0.0, |t| t.solver.final_time());
        let d = stages.time("flux", || s.heat_dipoles(model, end, &th.node_temperatures()));
        flux = Some(demcon_model::flux_density(&d, &s.rep_volumes));
        if let Some(params) = &plan.halo {
            halo = Some(stages.time("halo", || halo_of(model, &d, s, &domain, params))?);
        }
    }
    let mut series = Vec::new();
    if let (true, Some(th), Some(s)) = (plan.series, th, setup) {
        let end = problem.thermal.as_ref().map_or(0.0, |t| t.solver.final_time());
        let before_end = th.snapshots.iter().enumerate().filter(|(_, (t, _))| *t < end);
        let electric_fixed = problem
            .electric
            .as_ref()
            .is_some_and(|e| e.recouple_tolerance.is_none() && !e.tabled());
        series = stages.time("series", || {
            before_end
                .map(|(k, (t, temps))| {
                    let (flux, halo) = match plan.flux {
                        true => {
                            let nodes = WallContacts::join_nodes(temps, &th.wall_temperatures);
                            let (f, h) = flux_and_halo(model, s, *t, &nodes, plan.halo.as_ref(), &domain)?;
                            (Some(f), h.map(|(h, cut, _)| (h, cut)))
                        }
                        false => (None, None),
                    };
                    Ok(SeriesEntry {
                        t: *t,
                        snapshot: k,
                        flux,
                        halo,
                        electric: electric_fixed,
                    })
                })
                .collect::<Result<Vec<_>, SceneError>>()
        })?;
    }
    let mut post = stages.time("probes", || probes_and_fields(inp, domain, flux, halo))?;
    post.series = series;
    post.cells = cell_polyhedra(stages, model, problem)?;
    Ok(post)
}

/// The Laguerre cells of every particle as polyhedra, timed as the stage `cells`, when the
/// outputs ask for them (validation refuses `cells_vtk` without Laguerre cells).
fn cell_polyhedra(
    stages: &mut Stages,
    model: &Model,
    problem: &Problem,
) -> Result<Option<demcon_post::Polyhedra>, SceneError> {
    let (true, Some(lp)) = (problem.post.cells, &problem.model.laguerre) else {
        return Ok(None);
    };
    let carve = problem.model.carve.as_ref().map(|c| &c.0);
    stages.time("cells", || {
        let all: Vec<u32> = (0..model.particles.len() as u32).collect();
        let cells = demcon_graph::cell_polyhedra(&model.particles, &model.container, carve, lp, &all)?;
        let mut out = demcon_post::Polyhedra::new();
        for (verts, faces) in cells {
            out.push(verts, faces);
        }
        Ok(Some(out))
    })
}

/// The Halo-smoothed flux (W/m²), whether each particle's Halo is cut by the boundary, and
/// the report.
pub type Halo = (Vec<Vec3>, Vec<bool>, HaloReport);

/// The per-particle heat flux (W/m²) of the node temperatures `nodes` (particles, then walls),
/// and its Halo average when `halo` is given.
fn flux_and_halo(
    model: &Model,
    s: &ThermalSetup,
    t: f64,
    nodes: &[f64],
    halo: Option<&demcon_post::HaloParams>,
    domain: &Domain,
) -> Result<(Vec<Vec3>, Option<Halo>), SceneError> {
    let d = s.heat_dipoles(model, t, nodes);
    let halo = halo
        .map(|params| halo_of(model, &d, s, domain, params))
        .transpose()?;
    Ok((demcon_model::flux_density(&d, &s.rep_volumes), halo))
}

/// The Halo average of the flux of the dipoles `d`.
fn halo_of(
    model: &Model,
    d: &[Vec3],
    s: &ThermalSetup,
    domain: &Domain,
    params: &demcon_post::HaloParams,
) -> Result<Halo, SceneError> {
    // A Halo does not average across a crack (the flux jumps there, as across a phase
    // interface): members behind a crack are left out.
    let block = |a: &Vec3, b: &Vec3| model.defects.crack_between(a, b, &model.container);
    let blocked: Option<demcon_post::HaloBlock<'_>> = model.defects.has_cracks().then_some(&block);
    let h = halo_flux_blocked(&model.particles, d, &s.rep_volumes, domain, params, blocked)?;
    Ok((h.flux, h.truncated, h.report))
}

/// ETC, probes and profiles of the post-processing, on the flux and Halo already computed.
fn probes_and_fields(
    inp: &PostInputs<'_>,
    domain: Domain,
    flux: Option<Vec<Vec3>>,
    halo: Option<Halo>,
) -> Result<Post, SceneError> {
    let PostInputs {
        model,
        problem,
        setup,
        bcs,
        th,
        el,
    } = *inp;
    let plan = &problem.post;
    // Joule heat enters the thermal balance as sources the resolved conditions do not show.
    let joule = problem.electric.as_ref().is_some_and(|e| e.eta > 0.0);
    let etc = match (plan.etc_axis, th, setup, bcs) {
        (Some(ax), Some(th), Some(s), Some(b)) => Some(demcon_model::effective_conductivity(
            model,
            ax,
            s,
            b,
            &th.node_temperatures(),
            joule,
        )?),
        _ => None,
    };
    let final_time = problem.thermal.as_ref().map_or(0.0, |t| t.solver.final_time());
    let n = model.particles.len();
    let mask = |excluded: &mut dyn Iterator<Item = u32>| {
        let mut m = vec![1.0; n];
        excluded
            .filter(|&p| (p as usize) < n)
            .for_each(|p| m[p as usize] = 0.0);
        std::rc::Rc::new(m)
    };
    let thermal_solved = mask(&mut bcs.iter().flat_map(|b| b.constraints.excluded().iter().copied()));
    let electric_solved = mask(&mut el.iter().flat_map(|e| e.excluded.iter().copied()));
    let mut fields: Vec<SampledField> = Vec::new();
    let mut field = |name, t, values, solved: &std::rc::Rc<Vec<f64>>| {
        fields.push(SampledField {
            name,
            t,
            values,
            solved: solved.clone(),
        })
    };
    if let Some(th) = th {
        for (t, v) in &th.snapshots {
            field("temperature", *t, v.clone(), &thermal_solved);
        }
        if th.snapshots.last().map(|s| s.0) != Some(final_time) {
            field(
                "temperature",
                final_time,
                th.temperatures.clone(),
                &thermal_solved,
            );
        }
    }
    if let Some(el) = el {
        // The potential in force at the end: solved once at t = 0, unless a transient re-solves
        // it as ρ_e(T) follows the temperatures or an electrode's table changes (then it is
        // the end state's).
        let recoupled = problem.thermal.as_ref().is_some_and(|t| t.solver.is_transient())
            && problem
                .electric
                .as_ref()
                .is_some_and(|e| e.recouple_tolerance.is_some() || e.tabled());
        let t = if recoupled { final_time } else { 0.0 };
        field("potential", t, el.potentials.clone(), &electric_solved);
    }
    if let Some(f) = &flux {
        let v = f.iter().map(|v| v.norm()).collect();
        field("flux_magnitude", final_time, v, &thermal_solved);
    }
    if let Some((h, _, _)) = &halo {
        let v = h.iter().map(|v| v.norm()).collect();
        field("halo_flux_magnitude", final_time, v, &thermal_solved);
    }
    let rep = setup.map(|s| s.rep_volumes.clone()).unwrap_or_else(|| {
        (0..model.particles.len())
            .map(|p| model.solid_volume_of(p))
            .collect()
    });
    let index = ProbeIndex::new(&model.particles, &rep, &domain)?;
    let (probes, profiles) = sample(&index, plan, &fields)?;
    Ok(Post {
        series: Vec::new(),
        cells: None,
        flux,
        halo,
        etc,
        probes,
        profiles,
        domain,
    })
}

/// Probe readings and profiles of every sampled field.
fn sample(
    index: &ProbeIndex,
    plan: &PostPlan,
    fields: &[SampledField],
) -> Result<(Vec<ProbeValue>, Vec<ProfileValues>), SceneError> {
    let mut probes = Vec::new();
    let mut profiles = Vec::new();
    // A reading is solved when the solved mask (1 or 0 per particle) reads exactly 1 there.
    let all_solved = |x: f64| x >= 1.0 - 1e-12;
    for (i, p) in plan.probes.iter().enumerate() {
        let err = |e: demcon_post::PostError| {
            SceneError::invalid(
                &format!("outputs.probes[{i}] ({})", p.name),
                format!("({:?}, {:?}, {:?})", p.point.x, p.point.y, p.point.z),
                e.to_string(),
            )
        };
        for f in fields {
            let value = index.probe(&f.values, &p.point, &p.method).map_err(err)?;
            let solved = all_solved(index.probe(&f.solved, &p.point, &p.method).map_err(err)?);
            probes.push(ProbeValue {
                name: p.name.clone(),
                field: f.name.into(),
                t: f.t,
                value,
                solved,
            });
        }
    }
    for (i, p) in plan.profiles.iter().enumerate() {
        let err = |e: demcon_post::PostError| {
            SceneError::invalid(
                &format!("outputs.profiles[{i}] ({})", p.name),
                "line",
                e.to_string(),
            )
        };
        for f in fields {
            let points = index.profile(&f.values, &p.line, &p.method).map_err(err)?;
            let mask = index.profile(&f.solved, &p.line, &p.method).map_err(err)?;
            profiles.push(ProfileValues {
                name: p.name.clone(),
                field: f.name.into(),
                t: f.t,
                points,
                solved: mask.iter().map(|&(_, m)| all_solved(m)).collect(),
            });
        }
    }
    Ok((probes, profiles))
}
