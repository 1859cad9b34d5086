//! `demcon run --distributed` on a tiled packing: every MPI rank builds and keeps only its own
//! block of the model (`docs/distributed.md`, "The model by blocks").
//!
//! Rank r makes its share of the tiling and the ghosts within a ghost width
//! (`demcon_packing::tile_block`), the Laguerre cells of its owned particles from those alone
//! (`demcon_model::build_block_model`), checks that the width certified every owned cell
//! (`demcon_graph::ghost_width_needed`; widened and redone otherwise), and builds the thermal
//! conductances and wall links of its block. The rows of its owned particles go to PETSc with
//! the columns' global indices ([`BlockSystem`]); the solution stays distributed, the ghosts'
//! values come by a [`Halo`] exchange, and the effective conductivity and the probes are sums
//! over the ranks added in rank order. Each rank writes its piece of the particle outputs;
//! rank 0 writes `summary.json` and the `.pvtu` that joins the pieces.
//!
//! Only what every block can do alone is done here; a scene that needs a step over the whole
//! body is named by [`block_support`], and the CLI runs it with the replicated model instead.

use std::path::Path;
use std::time::Instant;

use demcon_core::{Container, ParticleSet, Stages, Vec3};
use demcon_electric::{give_link_joule_to_particles, joule_power};
use demcon_graph::{CellWall, ghost_width_needed, tessellate_part};
use demcon_model::{
    ElectrodeAt, FLOW_MISMATCH_WARNING, ModelError, Packed, PhaseRule, ThermalBc, ThermalSolver,
    TimeStepSpec, build_block_model, electric_network, thermal_setup,
};
use demcon_network::distributed::{BlockSystem, Halo, Session};
use demcon_network::{FloatingPolicy, resolve_fixed};
use demcon_packing::tile_block;
use demcon_post::{
    Domain, Field, HaloParams, ProbeMethod, halo_flux_blocked, write_csv, write_pvd, write_vtu,
};
use demcon_thermal::{ExplicitParams, SourceUpdate, ThermalSystem, TimeStep, TransientInput, run_explicit};
use serde_json::json;

use crate::build::tile_source;
use crate::config::{AxisConfig, PackingConfig};
use crate::error::SceneError;
use crate::output::{RUN_MARKER, check_output_dir, io, split_dir, write_atomic};
use crate::run::Halo as HaloAverage;
use crate::scene::Scene;

/// A ghost width is the cells' need × (1 + this): a margin against round-off in the reach.
const GHOST_MARGIN: f64 = 0.01;

/// Most ghost widths tried before giving up (each the last one's need with the margin).
const GHOST_ROUNDS: usize = 4;

/// Why a scene cannot be run by blocks (`None`: it can): its packing is not a tiling, or it
/// needs a step over the whole body. Read before any heavy work.
pub fn block_support(scene: &Scene) -> Option<String> {
    let cfg = scene.config();
    let p = scene.problem();
    let thermal = p.thermal.as_ref();
    let o = &cfg.outputs;
    let why = if !matches!(cfg.packing, PackingConfig::Tile { .. }) {
        "the packing is not a `Tile` (a generated or read packing is made whole, on every rank)"
    } else if p.homogenize.is_some() {
        "a periodic homogenisation is not distributed"
    } else if p.electric.is_some() && thermal.is_some() {
        "the electric physics with heat (Joule heating, ρ_e(T)) is not distributed by blocks yet"
    } else if p.electric.as_ref().is_some_and(|e| {
        e.current.is_some()
            || e.recouple_tolerance.is_some()
            || e.electrodes
                .iter()
                .any(|x| !matches!(x.at, ElectrodeAt::Face(_)) || !x.potential.is_constant())
    }) {
        "by blocks, electrodes hold constant potentials on the container's faces (no imposed current, no \
         electrodes on selected particles, no time tables)"
    } else if thermal.is_none() && p.electric.is_none() {
        "there is no physics to solve"
    } else if p.model.laguerre.is_none() {
        "the blocks need the Laguerre cells (`surface: Laguerre`)"
    } else if p.model.carve.is_some() {
        "carving cuts the whole body"
    } else if p.model.phase_rule == PhaseRule::Conforming {
        "conforming cells place seeds over the whole body (set `phase_rule: Centre`, `Laminate` or `Segment`)"
    } else if p
        .model
        .materials
        .materials
        .iter()
        .any(|m| m.conductivity_varies())
    {
        "a conductivity λ(T) needs the nonlinear loop (steady) or conductances re-evaluated every step, \
         not distributed by blocks yet"
    } else if !p.model.defects.is_empty() {
        "cracks, damage and interface resistances are not distributed by blocks yet"
    } else if thermal.is_some_and(|t| matches!(t.solver, ThermalSolver::Implicit { .. })) {
        "only the steady and the explicit thermal solves are distributed by blocks yet"
    } else if !o.times.is_empty() {
        "a transient's time series (`outputs.times`) is not written by blocks yet"
    } else if thermal.is_some_and(|t| {
        !t.sources.is_empty()
            || t.bcs.iter().any(|b| match b {
                ThermalBc::WallTemperature { value, .. } => !value.is_constant(),
                ThermalBc::HeatFlux { flux, .. } => !flux.is_constant(),
                ThermalBc::Convection { t_inf, .. } => !t_inf.is_constant(),
                ThermalBc::FixedTemperature { .. } | ThermalBc::Radiation { .. } => true,
            })
    }) {
        "only constant `WallTemperature`, `HeatFlux` and `Convection` conditions are distributed by blocks \
         yet (no radiation, no time tables, no volume sources)"
    } else if !p.post.profiles.is_empty() {
        "profiles are not distributed by blocks yet"
    } else if o.contacts_vtk || o.cells_vtk || o.plots {
        "`contacts_vtk`, `cells_vtk` and `plots` need the whole model"
    } else {
        return None;
    };
    Some(why.into())
}

/// What a block run produced on this rank.
#[derive(Debug, Clone)]
pub struct BlockOutcome {
    /// Files written (rank 0's list; the others' pieces are named in it).
    pub files: Vec<String>,
    /// `summary.json`'s content.
    pub summary: serde_json::Value,
}

/// The block's sites (owned, then ghosts) with their global indices.
struct Sites {
    /// The sites until the model takes them.
    particles: ParticleSet,
    global: Vec<usize>,
    owned: usize,
    first: usize,
    total: usize,
    ghost_ids: Vec<usize>,
    container: Container,
}

/// Runs `scene` by blocks on `session`'s ranks and writes its outputs into `out` (one piece per
/// rank). Collective: every rank calls it. `scene` must pass [`block_support`].
///
/// # Errors
/// Bad input (named by field) before any heavy work, the model's and the solver's errors, a
/// ghost layer the blocks are too thin for, and file-system failures.
pub fn run_blocks(
    scene: &Scene,
    session: &Session,
    out: &Path,
    name: &str,
) -> Result<BlockOutcome, SceneError> {
    if let Some(why) = block_support(scene) {
        return Err(SceneError::invalid("--distributed", "this scene", why));
    }
    check_output_dir(out)?;
    let p = scene.problem();
    let (rank, ranks) = (session.rank(), session.size());
    let t0 = Instant::now();
    let mut stages = Stages::default();

    // The periodic packing every rank copies (small: the tiling's memory is never held).
    let crate::build::TileSource {
        particles: base,
        container: base_c,
        repeat,
        walls,
        report: pack_report,
    } = stages.time("packing", || tile_source(scene, None))?;
    let r_max = base.radii.iter().copied().fold(0.0, f64::max);

    // The block, its model, and the ghost width its cells ask for (widened until enough). The
    // first guess is what the periodic packing's own cells ask for: the tiling's interior
    // cells are their copies (walls may enlarge a cell they cut: the check below then widens).
    let lp = p.model.laguerre.as_ref().expect("block_support checked it");
    // Walled, the packing's own cells in a walled box stand for the cells the walls cut.
    let mut first = 0.0f64;
    let walled = Container::Box {
        size: base_c.period().expect("tile_source checked it"),
    };
    for c in std::iter::once(&base_c).chain(walls.then_some(&walled)) {
        let (_, reach) = stages.time("tessellation", || tessellate_part(&base, c, None, lp, base.len()))?;
        first = first.max(ghost_width_needed(&base.radii, &reach, r_max));
    }
    // A Halo reads every particle within k·R_p of its own: the ghosts must hold them too.
    let halo_reach = p.post.halo.as_ref().map_or(0.0, |h| h.ratio * r_max);
    let mut width = (1.0 + GHOST_MARGIN) * first.max(halo_reach);
    let mut rounds = 0;
    let (sites, mut model) = loop {
        rounds += 1;
        let mut sites = stages.time("packing", || {
            block_sites(&base, &base_c, repeat, walls, (rank, ranks), width)
        })?;
        let packed = Packed {
            // The model holds the sites from here on.
            particles: std::mem::take(&mut sites.particles),
            container: sites.container,
            report: None,
            imported_from: None,
            pack_s: 0.0,
        };
        let (model, reach) = build_block_model(packed, &p.model, sites.owned, &mut stages)?;
        let local = ghost_width_needed(&model.particles.radii[..sites.owned], &reach, r_max);
        let need = session
            .all_gather(&[local])?
            .into_iter()
            .fold(halo_reach, f64::max);
        if need <= width {
            break (sites, model);
        }
        if rounds == GHOST_ROUNDS {
            return Err(SceneError::invalid(
                "--distributed",
                format!("ghost width {width:.4e} m"),
                format!("the cells still reach {need:.4e} m after {GHOST_ROUNDS} widenings"),
            ));
        }
        width = (1.0 + GHOST_MARGIN) * need;
    };
    drop(base);
    let n_owned = sites.owned;
    let halo = Halo::new(session, n_owned, &sites.ghost_ids)?;

    // The ghosts' cells are not built here: their volumes come from their owners.
    let cells = model.graph.cells.as_mut().expect("a Laguerre model");
    let ghost_volumes = halo.exchange(&cells.volume[..n_owned])?;
    cells.volume[n_owned..].copy_from_slice(&ghost_volumes);

    let block = BlockModel {
        session,
        halo: &halo,
        sites: &sites,
        model: &model,
    };
    let solved = match (&p.thermal, &p.electric) {
        (Some(thermal), _) => thermal_block(&block, scene, thermal, &mut stages)?,
        (None, Some(electric)) => electric_block(&block, electric, &mut stages)?,
        (None, None) => {
            return Err(SceneError::invalid(
                "thermal",
                "none",
                "a thermal or an electric section to solve by blocks",
            ));
        }
    };
    let probe_fields: Vec<(&str, &[f64])> = solved
        .probed
        .iter()
        .map(|(name, v)| (*name, v.as_slice()))
        .collect();
    let probes = stages.time("probes", || {
        probe_values(
            session,
            (p, solved.t),
            (&sites, &model.particles),
            &probe_fields,
            &solved.volumes,
        )
    })?;

    // Outputs: each rank its pieces, rank 0 the summary and the `.pvtu`.
    let net = model.network();
    let degree: Vec<i32> = (0..n_owned).map(|i| net.degree(i) as i32).collect();
    let peak = stages.peak_rss_bytes().unwrap_or(0) as f64;
    session.gather_peak_memory(peak)?;
    let peaks = session.all_gather(&[peak, n_owned as f64, sites.ghost_ids.len() as f64])?;
    let tmp = partial_dir(out)?;
    if rank == 0 {
        let _ = std::fs::remove_dir_all(&tmp);
        std::fs::create_dir_all(tmp.join("particles")).map_err(io(&tmp))?;
    }
    session.all_gather(&[0.0])?;
    let owned = ParticleSet {
        centres: model.particles.centres[..n_owned].to_vec(),
        radii: model.particles.radii[..n_owned].to_vec(),
        phases: model.particles.phases[..n_owned].to_vec(),
    };
    let solved_flag = vec![1i32; n_owned];
    // The serial `particles.vtu`'s fields, in its order (the laminate rule's two first).
    let lam = model.laminates();
    let fraction: Vec<f64> = (0..n_owned)
        .map(|q| lam.get(q).map_or(1.0, |x| 1.0 - x.other_fraction))
        .collect();
    let other: Vec<f64> = (0..n_owned)
        .map(|q| f64::from(lam.get(q).map_or(owned.phases[q], |x| x.other_phase)))
        .collect();
    let mut scalars: Vec<(&str, &[f64])> = vec![("phase_fraction", &fraction), ("other_phase", &other)];
    scalars.extend(solved.scalars.iter().map(|(name, v)| (*name, v.as_slice())));
    scalars.push(("volume", &solved.volumes));
    let vectors: Vec<(&str, &[Vec3])> = solved
        .vectors
        .iter()
        .map(|(name, v)| (*name, v.as_slice()))
        .collect();
    let o = &scene.config().outputs;
    if o.vtk {
        let mut fields = vec![
            Field::ints("coordination", &degree),
            Field::ints("solved", &solved_flag),
        ];
        fields.extend(scalars.iter().map(|(name, v)| Field::scalars(name, v)));
        fields.extend(vectors.iter().map(|(name, v)| Field::vectors(name, v)));
        if let Some(c) = &solved.halo_cut {
            fields.push(Field::ints("halo_truncated", c));
        }
        write_vtu(
            tmp.join(format!("particles/particles_{rank}.vtu")),
            &owned,
            &fields,
        )?;
    }
    if o.particles_csv {
        let c = |k: usize| -> Vec<f64> { owned.centres.iter().map(|x| x[k]).collect() };
        let (x, y, z) = (c(0), c(1), c(2));
        let phase: Vec<f64> = owned.phases.iter().map(|&q| f64::from(q)).collect();
        let ones = vec![1.0; n_owned];
        let mut header = vec!["x", "y", "z", "radius", "phase", "solved"];
        let mut cols: Vec<&[f64]> = vec![&x, &y, &z, &owned.radii, &phase, &ones];
        for (name, v) in &scalars {
            header.push(name);
            cols.push(v);
        }
        let comps = crate::output::vector_columns(vectors.iter().copied());
        for (name, v) in &comps {
            header.push(name);
            cols.push(v);
        }
        write_csv(tmp.join(format!("particles_{rank}.csv")), &header, &cols)?;
    }
    session.all_gather(&[0.0])?;
    let mut summary = json!({
        "name": name,
        "model": "blocks",
        "ranks": ranks,
        "n_particles": sites.total,
        "ghost_width_m": width,
        "ghost_rounds": rounds,
        "owned_per_rank": peaks.chunks(3).map(|c| c[1] as usize).collect::<Vec<_>>(),
        "ghosts_per_rank": peaks.chunks(3).map(|c| c[2] as usize).collect::<Vec<_>>(),
        "peak_rss_bytes_per_rank": peaks.chunks(3).map(|c| c[0]).collect::<Vec<_>>(),
        "packing": pack_report.as_ref().map(|r| json!({"tile_particles": r.packing.n, "phi": r.packing.phi, "stop": format!("{:?}", r.stop)})),
        "probes": probes.clone(),
        "distributed": crate::output::distributed_json(),
        "stages_rank0": stages.records().iter().map(|s| json!({"stage": s.stage, "wall_s": s.wall_s, "peak_rss_bytes": s.peak_rss_bytes})).collect::<Vec<_>>(),
        "wall_s": t0.elapsed().as_secs_f64(),
        "warnings": solved.warnings,
    });
    for (key, value) in solved.summary {
        summary[key] = value;
    }
    let mut files = Vec::new();
    if rank == 0 {
        if o.vtk {
            let mut arrays = vec![
                ("Float64", "radius", 1),
                ("UInt16", "phase", 1),
                ("Int32", "coordination", 1),
                ("Int32", "solved", 1),
            ];
            arrays.extend(scalars.iter().map(|(name, _)| ("Float64", *name, 1)));
            arrays.extend(vectors.iter().map(|(name, _)| ("Float64", *name, 3)));
            if solved.halo_cut.is_some() {
                arrays.push(("Int32", "halo_truncated", 1));
            }
            write_pvtu(&tmp.join("particles.pvtu"), ranks, &arrays)?;
            files.push("particles.pvtu".into());
            // A transient's end state, at its time, as the serial run's series names it.
            if let Some(t_end) = solved.transient_end {
                write_pvd(tmp.join("particles.pvd"), &[(t_end, "particles.pvtu".into())])?;
                files.push("particles.pvd".into());
            }
            files.push(format!("particles/particles_{{0..{}}}.vtu", ranks - 1));
        }
        if o.particles_csv {
            files.push(format!("particles_{{0..{}}}.csv", ranks - 1));
        }
        if !probes.is_empty() {
            let mut t = String::from("probe,field,t_s,value,solved\n");
            for p in &probes {
                t.push_str(&format!(
                    "{},{},{},{:.10e},1\n",
                    p["name"].as_str().unwrap_or(""),
                    p["field"].as_str().unwrap_or(""),
                    p["t"].as_f64().unwrap_or(f64::NAN),
                    p["value"].as_f64().unwrap_or(f64::NAN)
                ));
            }
            write_atomic(&tmp.join("probes.csv"), t.as_bytes())?;
            files.push("probes.csv".into());
        }
        let text = serde_json::to_string_pretty(&summary).map_err(|e| SceneError::Packing(e.to_string()))?;
        write_atomic(&tmp.join("summary.json"), text.as_bytes())?;
        files.push("summary.json".into());
        write_atomic(&tmp.join(RUN_MARKER), name.as_bytes())?;
        if out.exists() {
            std::fs::remove_dir_all(out).map_err(io(out))?;
        }
        std::fs::rename(&tmp, out).map_err(io(out))?;
    }
    Ok(BlockOutcome { files, summary })
}

/// A rank's block once built: its session, ghost exchange, sites and model.
struct BlockModel<'a> {
    session: &'a Session,
    halo: &'a Halo,
    sites: &'a Sites,
    model: &'a demcon_model::Model,
}

/// What a block's physics gave, for the outputs: per owned particle.
struct Solved {
    /// Fields after the phase fractions, in the serial file's order (volume excluded).
    scalars: Vec<(&'static str, Vec<f64>)>,
    /// Vector fields, in the serial order.
    vectors: Vec<(&'static str, Vec<Vec3>)>,
    /// Whether each Halo is cut by the box, when a Halo was asked for.
    halo_cut: Option<Vec<i32>>,
    /// The fields the probes read, in the serial order.
    probed: Vec<(&'static str, Vec<f64>)>,
    /// Each owned particle's representative volume (m³): its cell's.
    volumes: Vec<f64>,
    /// The time of the state (s).
    t: f64,
    /// A transient's end time (s).
    transient_end: Option<f64>,
    /// `summary.json` entries of the physics.
    summary: Vec<(&'static str, serde_json::Value)>,
    /// Warnings.
    warnings: Vec<String>,
}

/// The rows of a block's owned nodes (particles `first..first + owned`, then its walls), every
/// column a particle's global index, the walls' values `wall_u` moved to the right-hand side
/// with `sources` (per node): each rank's part of the system, solved distributed.
fn steady_rows(
    b: &BlockModel<'_>,
    (net, g): (&demcon_network::Network, &[f64]),
    (wall_u, sources): (&[f64], &[f64]),
    solve: &demcon_network::SolveParams,
) -> Result<(Vec<f64>, serde_json::Value), SceneError> {
    let (row_ptr, cols, entry_edges) = (net.row_ptr(), net.cols(), net.entry_edges());
    let n_local = b.model.particles.len();
    let (first, owned) = (b.sites.first, b.sites.owned);
    let mut rhs = sources[..owned].to_vec();
    for (i, r) in rhs.iter_mut().enumerate() {
        for e in row_ptr[i]..row_ptr[i + 1] {
            let j = cols[e] as usize;
            if j >= n_local {
                *r += g[entry_edges[e] as usize] * wall_u[j - n_local];
            }
        }
    }
    let row = |k: usize, c: &mut Vec<i64>, v: &mut Vec<f64>| {
        c.clear();
        v.clear();
        let i = k - first;
        let mut diag = 0.0;
        for e in row_ptr[i]..row_ptr[i + 1] {
            let j = cols[e] as usize;
            let ge = g[entry_edges[e] as usize];
            diag += ge;
            if j >= n_local {
                continue;
            }
            let col = b.sites.global[j] as i64;
            match c.last() {
                Some(&last) if last == col => *v.last_mut().expect("paired with c") -= ge,
                _ => {
                    c.push(col);
                    v.push(-ge);
                }
            }
        }
        c.push(k as i64);
        v.push(diag);
    };
    let system = BlockSystem::new(b.session, first, owned, b.sites.total, &row)?;
    let (u, r) = system.solve(&rhs, solve.rel_tol, solve.max_iter)?;
    let report = json!({
        "scheme": "steady",
        "method": demcon_network::distributed::METHOD,
        "rel_tol": solve.rel_tol,
        "iterations": r.iterations,
        "ksp_solves": r.ksp_solves,
        "relative_residual": r.relative_residual,
    });
    Ok((u, report))
}

/// The thermal physics of a block: conductances, walls, imposed fluxes, the steady or explicit
/// solve, the ETC, the flux and its Halo.
fn thermal_block(
    b: &BlockModel<'_>,
    scene: &Scene,
    thermal: &demcon_model::ThermalProblem,
    stages: &mut Stages,
) -> Result<Solved, SceneError> {
    let (session, halo, sites, model) = (b.session, b.halo, b.sites, b.model);
    let p = scene.problem();
    let n_owned = sites.owned;
    let setup = stages.time("thermal setup", || thermal_setup(model, thermal))?;
    // The walls held and their temperatures (constant: `block_support`).
    let plan = thermal.walls();
    let mut wall_t = vec![f64::NAN; setup.walls.n_walls()];
    for (bc, w) in thermal.bcs.iter().zip(&plan.of_bc) {
        if let (ThermalBc::WallTemperature { value, .. }, Some(w)) = (bc, w) {
            wall_t[*w] = value.at(0.0);
        }
    }
    // A face exchanging heat by convection is a wall held at the surroundings' temperature,
    // behind the film (in its links' conductances: `thermal_setup`).
    for x in &setup.surroundings.faces {
        wall_t[x.wall] = x.reference();
    }
    if wall_t.is_empty() && matches!(thermal.solver, ThermalSolver::Steady) {
        return Err(SceneError::invalid(
            "thermal.bcs",
            "no WallTemperature or Convection",
            "a steady solve by blocks needs at least one face held at a temperature or exchanging heat",
        ));
    }
    // Imposed fluxes: each owned cell's facet on the face receives the flux through its area (W).
    let net = setup.network(model);
    let mut sources = vec![0.0; net.n_nodes()];
    let cells = model.graph.cells.as_deref().expect("a Laguerre model");
    for bc in &thermal.bcs {
        if let ThermalBc::HeatFlux { face, flux } = bc {
            for f in cells.on_wall(CellWall::of(*face)) {
                sources[f.particle as usize] += flux.at(0.0) * f.area;
            }
        }
    }
    let (temps, solve_report) = match thermal.solver {
        ThermalSolver::Explicit { t_end, dt } => stages.time("solve", || {
            explicit(
                session,
                (halo, n_owned),
                (model, &setup),
                thermal,
                (&wall_t, &sources),
                (t_end, dt),
            )
        })?,
        _ => stages.time("solve", || {
            steady_rows(b, (net, &setup.conductances), (&wall_t, &sources), &thermal.solve)
        })?,
    };

    // The effective conductivity: the heat through each held face, summed over the ranks.
    let n_local = model.particles.len();
    let flows = wall_flows(&setup.walls, setup.wall_conductances(), &temps, &wall_t, n_local);
    let flows = session.sum(&flows)?;
    let mut warnings = Vec::new();
    let etc = match scene.config().outputs.etc_axis {
        Some(axis) => {
            // As the serial ETC: heat in and out through the two held faces only.
            let refuse = |why: String| SceneError::invalid("outputs.etc_axis", format!("{axis:?}"), why);
            if let Some(x) = setup.surroundings.faces.first() {
                return Err(refuse(format!(
                    "face {} exchanges heat with its surroundings (Convection): heat leaves elsewhere than \
                     through the two held faces and no single λ_e describes the body",
                    x.face.name()
                )));
            }
            if thermal
                .bcs
                .iter()
                .any(|b| matches!(b, ThermalBc::HeatFlux { .. }))
            {
                return Err(refuse(
                    "a HeatFlux adds heat: the heat through the two held faces then differs and no single λ_e \
                     describes it; remove it for an ETC run"
                        .into(),
                ));
            }
            let (etc, w) = block_etc(&plan.faces, &wall_t, &flows, &sites.container, axis)?;
            warnings.extend(w);
            Some(etc)
        }
        None => None,
    };
    let t_end = thermal.solver.final_time();
    let (flux, halo_flux) = match p.post.flux {
        true => {
            let nodes: Vec<f64> = temps
                .iter()
                .chain(&halo.exchange(&temps)?)
                .chain(&wall_t)
                .copied()
                .collect();
            let (f, h) = stages.time("flux", || {
                block_flux(
                    (halo, n_owned),
                    (model, &setup),
                    (t_end, &nodes),
                    (p.post.halo.as_ref(), &sites.container),
                )
            })?;
            (Some(f), h)
        }
        false => (None, None),
    };
    let magnitude = |v: &[Vec3]| v.iter().map(|x| x.norm()).collect::<Vec<f64>>();
    let mut probed = vec![("temperature", temps.clone())];
    let mut vectors = Vec::new();
    if let Some(f) = flux {
        probed.push(("flux_magnitude", magnitude(&f)));
        vectors.push(("heat_flux", f));
    }
    let mut halo_cut = None;
    let mut halo_report = serde_json::Value::Null;
    if let Some((h, cut, r)) = halo_flux {
        probed.push(("halo_flux_magnitude", magnitude(&h)));
        vectors.push(("halo_flux", h));
        halo_cut = Some(cut.iter().map(|&c| i32::from(c)).collect());
        let truncated = session.sum(&[r.n_truncated as f64])?[0] as usize;
        halo_report = json!({"ratio": r.ratio, "n_truncated": truncated, "mean_members_rank0": r.mean_members,
            "min_members_rank0": r.min_members, "max_members_rank0": r.max_members, "wall_s_rank0": r.wall_s});
    }
    Ok(Solved {
        scalars: vec![("temperature", temps)],
        vectors,
        halo_cut,
        probed,
        volumes: setup.rep_volumes[..n_owned].to_vec(),
        t: t_end,
        transient_end: thermal.solver.is_transient().then_some(t_end),
        summary: vec![
            ("solve", solve_report),
            ("etc", json!(etc)),
            ("halo", halo_report),
        ],
        warnings,
    })
}

/// The electric physics of a block: conductances and face electrodes, the potential solve,
/// the electrodes' currents, the resistance, the Joule power and the current density.
fn electric_block(
    b: &BlockModel<'_>,
    electric: &demcon_model::ElectricProblem,
    stages: &mut Stages,
) -> Result<Solved, SceneError> {
    let (session, halo, sites, model) = (b.session, b.halo, b.sites, b.model);
    let n_owned = sites.owned;
    let n_local = model.particles.len();
    let en = stages.time("electric setup", || electric_network(model, electric, None))?;
    let net = en.network.as_ref().unwrap_or_else(|| model.network());
    let g = &en.conductances;
    // Face electrodes only, constant (`block_support`), in the order of their walls.
    let wall_v: Vec<f64> = electric.electrodes.iter().map(|e| e.potential.at(0.0)).collect();
    let sources = vec![0.0; net.n_nodes()];
    let (v_owned, solve_report) = stages.time("solve", || {
        steady_rows(b, (net, g), (&wall_v, &sources), &electric.solve)
    })?;
    let v_ghost = halo.exchange(&v_owned)?;
    let nodes: Vec<f64> = v_owned.iter().chain(&v_ghost).chain(&wall_v).copied().collect();
    // Each electrode's current into the body, Σ G (V_w − V_p) over its links, summed over the
    // ranks; the resistance between two electrodes as serially.
    let m = model.graph.len();
    let mut currents = vec![0.0; en.walls.n_walls()];
    for ((k, [p, node]), w) in en.walls.edges().enumerate().zip(en.walls.wall_of_links()) {
        currents[w] += g[m + k] * (nodes[node as usize] - nodes[p as usize]);
    }
    let currents = session.sum(&currents)?;
    let current_in: f64 = currents.iter().filter(|&&i| i > 0.0).sum();
    let current_out: f64 = -currents.iter().filter(|&&i| i < 0.0).sum::<f64>();
    let resistance = match wall_v.as_slice() {
        [va, vb] if va != vb && currents[0] != 0.0 => Some((va - vb) / currents[0]),
        _ => None,
    };
    // The Joule power: each branch's half to each end (the electrode links' wholly to their
    // particle), as serially; the power dissipated counts a branch between two blocks once.
    let mut joule = joule_power(net, g, &nodes, electric.eta).map_err(ModelError::from)?;
    let links = en
        .walls
        .wall_of_links()
        .enumerate()
        .map(|(k, w)| (en.walls.particle[k], en.walls.node(w), g[m + k]));
    give_link_joule_to_particles(&mut joule, &nodes, electric.eta, links);
    joule.truncate(n_owned);
    let mut dissipated = 0.0;
    for (&[p, q], ge) in net.edges().iter().zip(g) {
        let (p, q) = (p as usize, q as usize);
        let share = match (p < n_owned, q < n_owned || q >= n_local) {
            (true, true) => 1.0,
            (true, false) => 0.5,
            _ => 0.0,
        };
        let du = nodes[p] - nodes[q];
        dissipated += share * ge * du * du;
    }
    let sums = session.sum(&[dissipated, joule.iter().sum()])?;
    let volumes = model.graph.cells.as_deref().expect("a Laguerre model").volume[..n_owned].to_vec();
    let density: Vec<f64> = joule.iter().zip(&volumes).map(|(w, v)| w / v).collect();
    let d = demcon_model::flux_dipoles(model, &en.walls, g, &nodes);
    let current_density = demcon_model::flux_density(&d[..n_owned], &volumes);
    let report = json!({
        "resistance_ohm": resistance,
        "electrode_potentials": wall_v,
        "electrode_currents_a": currents,
        "current_in": current_in,
        "current_out": current_out,
        "current_mismatch": if current_in > 0.0 { (current_in - current_out).abs() / current_in } else { 0.0 },
        "joule_w": sums[0],
        "joule_heat_w": sums[1],
    });
    Ok(Solved {
        scalars: vec![
            ("potential", v_owned.clone()),
            ("joule_power", joule),
            ("joule_power_density", density),
        ],
        vectors: vec![("current_density", current_density)],
        halo_cut: None,
        probed: vec![("potential", v_owned)],
        volumes,
        t: 0.0,
        transient_end: None,
        summary: vec![("solve", solve_report), ("electric", report)],
        warnings: Vec::new(),
    })
}

/// The explicit transient of a block: the serial time march on the block's network (owned,
/// ghosts and walls), the ghosts' temperatures brought from their owners after every step; the
/// step is the whole body's (the smallest bound over the ranks). Returns the owned particles'
/// temperatures at `t_end` and what the march did.
fn explicit(
    session: &Session,
    (halo, owned): (&Halo, usize),
    (model, setup): (&demcon_model::Model, &demcon_model::ThermalSetup),
    thermal: &demcon_model::ThermalProblem,
    (wall_t, sources): (&[f64], &[f64]),
    (t_end, dt): (f64, TimeStepSpec),
) -> Result<(Vec<f64>, serde_json::Value), SceneError> {
    let net = setup.network(model);
    let sets: Vec<(Vec<u32>, f64)> = (0..wall_t.len())
        .map(|w| (vec![setup.walls.node(w)], wall_t[w]))
        .collect();
    // A transient is well posed on every cluster: a block's part away from the walls is kept.
    let constraints = resolve_fixed(net, &sets, FloatingPolicy::Keep)?;
    let system = ThermalSystem::new(net, &setup.conductances, &setup.capacities, &constraints)?;
    // The whole body's bound: each node's C/ΣH is exact on its owner and no smaller elsewhere
    // (a ghost lacks some of its links), so the smallest over the ranks is the serial one.
    let local = system.stable_dt_bound().dt_max;
    let bound = session
        .all_gather(&[local])?
        .into_iter()
        .fold(f64::INFINITY, f64::min);
    let step = match dt {
        TimeStepSpec::Auto { safety } => TimeStep::Fixed {
            dt: (safety * bound).min(t_end),
            allow_unstable: false,
        },
        TimeStepSpec::Fixed { dt, allow_unstable } => TimeStep::Fixed { dt, allow_unstable },
        TimeStepSpec::Paper { .. } => {
            return Err(SceneError::invalid(
                "thermal.solver.dt",
                "Paper",
                "the paper's estimate needs the Calibrated surface model",
            ));
        }
    };
    // The march checks a fixed step against this block's bound only.
    if let TimeStep::Fixed {
        dt,
        allow_unstable: false,
    } = step
        && dt > bound
    {
        return Err(SceneError::invalid(
            "thermal.solver.dt",
            format!("{dt:e} s"),
            format!("at most the positivity bound {bound:e} s (min C/ΣH over the body)"),
        ));
    }
    // One initial temperature and every held wall in every block (linked or not): each rank's
    // maximum-principle envelope is the whole body's.
    let mut t0 = vec![thermal.initial_temperature; net.n_nodes()];
    constraints.impose(&mut t0);
    let params = ExplicitParams {
        t_end,
        dt: step,
        output_times: thermal.output_times.clone(),
        ..ExplicitParams::default()
    };
    let mut ghosts = Ghosts { halo, owned };
    let run = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources,
        },
        &params,
        |_, _| {},
        &mut ghosts,
    )?;
    let r = &run.report;
    let report = json!({
        "scheme": "forward-euler",
        "t_end_s": t_end,
        "dt_s": r.dt,
        "steps": r.steps,
        "dt_bound_s": bound,
        "ghost_exchanges": r.steps,
    });
    Ok((run.temperatures[..ghosts.owned].to_vec(), report))
}

/// Brings the ghosts' temperatures from their owners after every step of a march.
struct Ghosts<'a> {
    halo: &'a Halo,
    owned: usize,
}

impl SourceUpdate for Ghosts<'_> {
    type Error = SceneError;

    fn update(&mut self, _t: f64, _temps: &[f64]) -> Result<Option<Vec<f64>>, SceneError> {
        Ok(None)
    }

    fn exchange(&mut self, temps: &mut [f64]) -> Result<(), SceneError> {
        let ghosts = self.halo.exchange(&temps[..self.owned])?;
        temps[self.owned..self.owned + ghosts.len()].copy_from_slice(&ghosts);
        Ok(())
    }
}

/// The hidden sibling folder the ranks write their pieces into before rank 0 moves it to `out`.
fn partial_dir(out: &Path) -> Result<std::path::PathBuf, SceneError> {
    let (parent, base) = split_dir(out)?;
    let mut n = std::ffi::OsString::from(".");
    n.push(base);
    n.push(".partial-blocks");
    Ok(parent.join(n))
}

/// Rank `rank` of `ranks`' sites for the ghost width `width`.
fn block_sites(
    base: &ParticleSet,
    base_c: &Container,
    repeat: [usize; 3],
    walls: bool,
    (rank, ranks): (usize, usize),
    width: f64,
) -> Result<Sites, SceneError> {
    let b = tile_block(base, base_c, repeat, walls, rank, ranks, width).map_err(|e| {
        let volume: f64 = base_c.volume() * repeat.iter().product::<usize>() as f64;
        let most = (volume / (2.0 * width).powi(3)).floor().max(1.0);
        SceneError::invalid(
            "MPI ranks",
            ranks,
            format!(
                "at most {most:.0} for this tiling: each block must be at least twice as thick as the ghost layer \
                 its cells need ({width:.4e} m) ({e})"
            ),
        )
    })?;
    let owned = b.owned.len();
    let mut particles = b.owned;
    particles.centres.extend_from_slice(&b.ghosts.centres);
    particles.radii.extend_from_slice(&b.ghosts.radii);
    particles.phases.extend_from_slice(&b.ghosts.phases);
    let global = (b.first..b.first + owned)
        .chain(b.ghost_ids.iter().copied())
        .collect();
    Ok(Sites {
        particles,
        global,
        owned,
        first: b.first,
        total: b.total,
        ghost_ids: b.ghost_ids,
        container: b.container,
    })
}

/// Heat entering the body through each wall from this rank's links (W).
fn wall_flows(
    walls: &demcon_graph::WallContacts,
    g: &[f64],
    temps: &[f64],
    wall_t: &[f64],
    n_local: usize,
) -> Vec<f64> {
    let mut flows = vec![0.0; walls.n_walls()];
    for ((k, [p, node]), w) in walls.edges().enumerate().zip(walls.wall_of_links()) {
        let (p, _) = (p as usize, node as usize - n_local);
        flows[w] += g[k] * (wall_t[w] - temps[p]);
    }
    flows
}

/// λ_e along `axis` from the flows through the two walls held at different temperatures on
/// the faces normal to it: the conductivity of a uniform bar of the box's section and length
/// that would carry the mean of the heat entering and leaving.
fn block_etc(
    faces: &[demcon_core::Face],
    wall_t: &[f64],
    flows: &[f64],
    container: &Container,
    axis: AxisConfig,
) -> Result<(serde_json::Value, Vec<String>), SceneError> {
    use demcon_core::Face;
    let k = match axis {
        AxisConfig::X => 0,
        AxisConfig::Y => 1,
        AxisConfig::Z => 2,
    };
    let (lo_face, hi_face) = [
        (Face::XMin, Face::XMax),
        (Face::YMin, Face::YMax),
        (Face::ZMin, Face::ZMax),
    ][k];
    let find = |f: Face| faces.iter().position(|&x| x == f);
    let (Some(lo), Some(hi), 2) = (find(lo_face), find(hi_face), faces.len()) else {
        return Err(SceneError::invalid(
            "outputs.etc_axis",
            format!("{axis:?}"),
            format!(
                "the ETC by blocks needs exactly two held faces, {} and {}, held by `WallTemperature`",
                lo_face.name(),
                hi_face.name()
            ),
        ));
    };
    let dt = wall_t[hi] - wall_t[lo];
    if dt == 0.0 {
        return Err(SceneError::invalid(
            "outputs.etc_axis",
            format!("{axis:?}"),
            "the two held faces must differ in temperature",
        ));
    }
    let (hot, cold) = if dt > 0.0 { (hi, lo) } else { (lo, hi) };
    let (q_in, q_out) = (flows[hot], -flows[cold]);
    let e = container.bounds().extent();
    let length = e[k];
    let section = e.x * e.y * e.z / length;
    let q = 0.5 * (q_in + q_out);
    let mismatch = (q_in - q_out).abs() / q_in.abs().max(q_out.abs()).max(f64::MIN_POSITIVE);
    let warnings: Vec<String> = (mismatch > FLOW_MISMATCH_WARNING)
        .then(|| {
            format!(
                "ETC: the heat entering through the hot face ({q_in:.6e} W) and leaving through the cold one \
                 ({q_out:.6e} W) differ by {mismatch:.2e} (relative): λ_e uses their mean"
            )
        })
        .into_iter()
        .collect();
    let etc = json!({
        "axis": format!("{axis:?}"),
        "lambda_e": q * length / (section * dt.abs()),
        "heat_flow_w": q,
        "hot_flow_w": q_in,
        "cold_flow_w": q_out,
        "length_m": length,
        "section_m2": section,
        "warnings": warnings,
    });
    Ok((etc, warnings))
}

/// Each probe's value of every field in `fields` (name, one value per owned particle): the
/// nearest particle's (ties: the lowest global index), or the ball average weighted by the
/// cells' volumes, gathered over the ranks; in the serial order (per probe, per field).
fn probe_values(
    session: &Session,
    (p, t): (&crate::convert::Problem, f64),
    (sites, particles): (&Sites, &ParticleSet),
    fields: &[(&str, &[f64])],
    volumes: &[f64],
) -> Result<Vec<serde_json::Value>, SceneError> {
    let period = sites.container.period();
    let dist = |a: &Vec3, b: &Vec3| {
        let mut d = a - b;
        if let Some(l) = period {
            for k in 0..3 {
                d[k] -= l[k] * (d[k] / l[k]).round();
            }
        }
        d.norm()
    };
    let centres = &particles.centres[..sites.owned];
    let mut out = Vec::new();
    for (i, probe) in p.post.probes.iter().enumerate() {
        let values: Vec<f64> = match probe.method {
            ProbeMethod::Nearest => {
                let best = centres
                    .iter()
                    .enumerate()
                    .map(|(j, c)| (dist(c, &probe.point), j))
                    .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let (d, j) = best.unwrap_or((f64::INFINITY, 0));
                let mut mine = vec![d, (sites.first + j) as f64];
                mine.extend(fields.iter().map(|(_, v)| v.get(j).copied().unwrap_or(0.0)));
                let all = session.all_gather(&mine)?;
                all.chunks(mine.len())
                    .min_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])))
                    .map_or(vec![f64::NAN; fields.len()], |c| c[2..].to_vec())
            }
            ProbeMethod::BallAverage { radius } => {
                // Σ V, then Σ V·value per field.
                let mut sums = vec![0.0; 1 + fields.len()];
                for (j, c) in centres.iter().enumerate() {
                    if dist(c, &probe.point) <= radius {
                        sums[0] += volumes[j];
                        for (k, (_, v)) in fields.iter().enumerate() {
                            sums[1 + k] += volumes[j] * v[j];
                        }
                    }
                }
                let s = session.sum(&sums)?;
                if s[0] == 0.0 {
                    return Err(SceneError::invalid(
                        &format!("outputs.probes[{i}] ({})", probe.name),
                        format!("radius {radius:e} m"),
                        "a ball that holds a particle centre",
                    ));
                }
                s[1..].iter().map(|x| x / s[0]).collect()
            }
        };
        for ((name, _), value) in fields.iter().zip(values) {
            out.push(json!({"name": probe.name, "field": name, "t": t, "value": value, "solved": true}));
        }
    }
    Ok(out)
}

/// The owned particles' heat flux (W/m²) and, with `halo`, its Halo average (W/m²) and whether
/// each Halo is cut by the box, with the Halo's report. `nodes`: the block's temperatures
/// (owned, ghosts, walls). The dipoles of the owned cells are complete; the ghosts' come from
/// their owners, so that every Halo within the ghost width reads the serial values.
fn block_flux(
    (halo, owned): (&Halo, usize),
    (model, setup): (&demcon_model::Model, &demcon_model::ThermalSetup),
    (t, nodes): (f64, &[f64]),
    (params, container): (Option<&HaloParams>, &Container),
) -> Result<(Vec<Vec3>, Option<HaloAverage>), SceneError> {
    let mut d = setup.heat_dipoles(model, t, nodes);
    let flux = demcon_model::flux_density(&d[..owned], &setup.rep_volumes[..owned]);
    let Some(params) = params else {
        return Ok((flux, None));
    };
    for k in 0..3 {
        let mine: Vec<f64> = d[..owned].iter().map(|v| v[k]).collect();
        for (g, x) in d[owned..].iter_mut().zip(halo.exchange(&mine)?) {
            g[k] = x;
        }
    }
    let domain = Domain::of_container(container)?;
    let h = halo_flux_blocked(&model.particles, &d, &setup.rep_volumes, &domain, params, None)?;
    let mut report = h.report;
    report.n_truncated = h.truncated[..owned].iter().filter(|&&b| b).count();
    Ok((
        flux,
        Some((h.flux[..owned].to_vec(), h.truncated[..owned].to_vec(), report)),
    ))
}

/// Writes the `.pvtu` that joins the ranks' `particles/particles_<r>.vtu` pieces, with the
/// point arrays each piece holds (VTK type, name, components).
fn write_pvtu(path: &Path, ranks: usize, arrays: &[(&str, &str, usize)]) -> Result<(), SceneError> {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <PUnstructuredGrid GhostLevel=\"0\">\n    <PPointData>\n",
    );
    for (ty, name, n) in arrays {
        s.push_str(&format!(
            "      <PDataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{n}\"/>\n"
        ));
    }
    s.push_str("    </PPointData>\n    <PPoints>\n      <PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n    </PPoints>\n");
    for r in 0..ranks {
        s.push_str(&format!("    <Piece Source=\"particles/particles_{r}.vtu\"/>\n"));
    }
    s.push_str("  </PUnstructuredGrid>\n</VTKFile>\n");
    write_atomic(path, s.as_bytes())
}
