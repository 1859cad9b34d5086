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
use demcon_graph::ghost_width_needed;
use demcon_model::{Packed, PhaseRule, ThermalBc, ThermalSolver, build_block_model, thermal_setup};
use demcon_network::distributed::{BlockSystem, Halo, Session};
use demcon_packing::tile_block;
use demcon_post::{Field, ProbeMethod, write_csv, write_vtu};
use serde_json::json;

use crate::build::tile_source;
use crate::config::{AxisConfig, PackingConfig};
use crate::error::SceneError;
use crate::output::{RUN_MARKER, check_output_dir, io, split_dir, write_atomic};
use crate::scene::Scene;

/// The first ghost width tried, in mean particle diameters; the cells' reach widens it when
/// needed (on the packings tried, 1.5 diameters is about the reach of a dense LS packing's cells).
const FIRST_GHOST_WIDTH: f64 = 1.5;

/// Most ghost widths tried before giving up (each the last one's need × 1.05).
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
    } else if p.electric.is_some() {
        "the electric physics is not distributed by blocks yet"
    } else if p.model.laguerre.is_none() {
        "the blocks need the Laguerre cells (`surface: Laguerre`)"
    } else if p.model.carve.is_some() {
        "carving cuts the whole body"
    } else if p.model.phase_rule == PhaseRule::Conforming {
        "conforming cells place seeds over the whole body (set `phase_rule: Centre`, `Laminate` or `Segment`)"
    } else if !p.model.defects.is_empty() {
        "cracks, damage and interface resistances are not distributed by blocks yet"
    } else if thermal.is_none_or(|t| !matches!(t.solver, ThermalSolver::Steady)) {
        "only a steady thermal solve is distributed by blocks yet"
    } else if thermal.is_some_and(|t| {
        !t.sources.is_empty()
            || t.bcs
                .iter()
                .any(|b| !matches!(b, ThermalBc::WallTemperature { value, .. } if value.is_constant()))
    }) {
        "only constant `WallTemperature` conditions are distributed by blocks yet"
    } else if !p.post.profiles.is_empty() || p.post.halo.is_some() || p.post.flux {
        "profiles, the heat flux and its Halo are not distributed by blocks yet"
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
    let thermal = p.thermal.as_ref().expect("block_support checked it");
    let (rank, ranks) = (session.rank(), session.size());
    let etc_axis = scene.config().outputs.etc_axis;
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
    let d_mean = 2.0 * base.radii.iter().sum::<f64>() / base.len() as f64;

    // The block, its model, and the ghost width its cells ask for (widened until enough).
    let mut width = FIRST_GHOST_WIDTH * d_mean;
    let mut rounds = 0;
    let (sites, mut model) = loop {
        rounds += 1;
        let sites = stages.time("packing", || {
            block_sites(&base, &base_c, repeat, walls, (rank, ranks), width)
        })?;
        let packed = Packed {
            particles: sites.particles.clone(),
            container: sites.container,
            report: None,
            imported_from: None,
            pack_s: 0.0,
        };
        let (model, reach) = build_block_model(packed, &p.model, sites.owned, &mut stages)?;
        let local = ghost_width_needed(&model.particles.radii[..sites.owned], &reach, r_max);
        let need = session.all_gather(&[local])?.into_iter().fold(0.0, f64::max);
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
        width = 1.05 * need;
    };
    drop(base);
    let n_owned = sites.owned;
    let halo = Halo::new(session, n_owned, &sites.ghost_ids)?;

    // The ghosts' cells are not built here: their volumes come from their owners.
    let cells = model.graph.cells.as_mut().expect("a Laguerre model");
    let ghost_volumes = halo.exchange(&cells.volume[..n_owned])?;
    cells.volume[n_owned..].copy_from_slice(&ghost_volumes);
    let setup = stages.time("thermal setup", || thermal_setup(&model, thermal))?;

    // The walls held and their temperatures (constant `WallTemperature`: `block_support`).
    let plan = thermal.walls();
    let mut wall_t = vec![f64::NAN; setup.walls.n_walls()];
    for (bc, w) in thermal.bcs.iter().zip(&plan.of_bc) {
        if let (ThermalBc::WallTemperature { value, .. }, Some(w)) = (bc, w) {
            wall_t[*w] = value.at(0.0);
        }
    }
    if wall_t.is_empty() {
        return Err(SceneError::invalid(
            "thermal.bcs",
            "no WallTemperature",
            "a steady solve by blocks needs at least one face held at a temperature",
        ));
    }

    // This rank's rows: its owned particles, every column a particle's global index; the walls'
    // temperatures move to the right-hand side. The Laguerre cells tile the box, so every
    // particle is connected and solved.
    let net = setup.network(&model);
    let (row_ptr, cols, entry_edges) = (net.row_ptr(), net.cols(), net.entry_edges());
    let g = &setup.conductances;
    let n_local = model.particles.len();
    let global = |j: usize| sites.global[j] as i64;
    let mut rhs = vec![0.0; n_owned];
    for (i, b) in rhs.iter_mut().enumerate() {
        for e in row_ptr[i]..row_ptr[i + 1] {
            let j = cols[e] as usize;
            if j >= n_local {
                *b += g[entry_edges[e] as usize] * wall_t[j - n_local];
            }
        }
    }
    let row = |k: usize, c: &mut Vec<i64>, v: &mut Vec<f64>| {
        c.clear();
        v.clear();
        let i = k - sites.first;
        let mut diag = 0.0;
        for e in row_ptr[i]..row_ptr[i + 1] {
            let j = cols[e] as usize;
            let ge = g[entry_edges[e] as usize];
            diag += ge;
            if j >= n_local {
                continue;
            }
            let col = global(j);
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
    let solve = &thermal.solve;
    let (temps, report) = stages.time("solve", || -> Result<_, SceneError> {
        let system = BlockSystem::new(session, sites.first, n_owned, sites.total, &row)?;
        Ok(system.solve(&rhs, solve.rel_tol, solve.max_iter)?)
    })?;
    let ghost_temps = halo.exchange(&temps)?;

    // The effective conductivity and the probes: sums over the ranks in rank order.
    let flows = wall_flows(&setup.walls, setup.wall_conductances(), &temps, &wall_t, n_local);
    let flows = session.sum(&flows)?;
    let etc = match etc_axis {
        Some(axis) => Some(block_etc(&plan.faces, &wall_t, &flows, &sites.container, axis)?),
        None => None,
    };
    let volumes = &setup.rep_volumes[..n_owned];
    let probes = stages.time("probes", || probe_values(session, p, &sites, &temps, volumes))?;

    // Outputs: each rank its pieces, rank 0 the summary and the `.pvtu`.
    let degree: Vec<i32> = (0..n_owned)
        .map(|i| {
            (row_ptr[i]..row_ptr[i + 1])
                .filter(|&e| (cols[e] as usize) < n_local)
                .count() as i32
        })
        .collect();
    let peak = stages.peak_rss_bytes().unwrap_or(0) as f64;
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
    let solved = vec![1i32; n_owned];
    let o = &scene.config().outputs;
    if o.vtk {
        let fields = [
            Field::ints("coordination", &degree),
            Field::ints("solved", &solved),
            Field::scalars("temperature", &temps),
            Field::scalars("volume", volumes),
        ];
        write_vtu(
            tmp.join(format!("particles/particles_{rank}.vtu")),
            &owned,
            &fields,
        )?;
    }
    if o.particles_csv {
        let c = |k: usize| -> Vec<f64> { owned.centres.iter().map(|x| x[k]).collect() };
        let phase: Vec<f64> = owned.phases.iter().map(|&q| f64::from(q)).collect();
        let ones = vec![1.0; n_owned];
        write_csv(
            tmp.join(format!("particles_{rank}.csv")),
            &[
                "x",
                "y",
                "z",
                "radius",
                "phase",
                "solved",
                "temperature",
                "volume",
            ],
            &[&c(0), &c(1), &c(2), &owned.radii, &phase, &ones, &temps, volumes],
        )?;
    }
    session.all_gather(&[0.0])?;
    let summary = json!({
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
        "solve": {
            "method": demcon_network::distributed::METHOD,
            "rel_tol": solve.rel_tol,
            "iterations": report.iterations,
            "ksp_solves": report.ksp_solves,
            "relative_residual": report.relative_residual,
        },
        "etc": etc,
        "probes": probes.clone(),
        "distributed": crate::output::distributed_json(),
        "stages_rank0": stages.records().iter().map(|s| json!({"stage": s.stage, "wall_s": s.wall_s, "peak_rss_bytes": s.peak_rss_bytes})).collect::<Vec<_>>(),
        "wall_s": t0.elapsed().as_secs_f64(),
        "warnings": Vec::<String>::new(),
    });
    let mut files = Vec::new();
    if rank == 0 {
        if o.vtk {
            write_pvtu(&tmp.join("particles.pvtu"), ranks)?;
            files.push("particles.pvtu".into());
            files.push(format!("particles/particles_{{0..{}}}.vtu", ranks - 1));
        }
        if o.particles_csv {
            files.push(format!("particles_{{0..{}}}.csv", ranks - 1));
        }
        if !probes.is_empty() {
            let mut t = String::from("probe,field,t_s,value,solved\n");
            for p in &probes {
                t.push_str(&format!(
                    "{},temperature,0,{:.10e},1\n",
                    p["name"].as_str().unwrap_or(""),
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
    drop(ghost_temps);
    Ok(BlockOutcome { files, summary })
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
) -> Result<serde_json::Value, SceneError> {
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
    Ok(json!({
        "axis": format!("{axis:?}"),
        "lambda_e": q * length / (section * dt.abs()),
        "heat_flow_w": q,
        "hot_flow_w": q_in,
        "cold_flow_w": q_out,
        "length_m": length,
        "section_m2": section,
    }))
}

/// Each probe's temperature: the nearest particle's (ties: lowest global index), or the
/// ball average weighted by the cells' volumes, gathered over the ranks.
fn probe_values(
    session: &Session,
    p: &crate::convert::Problem,
    sites: &Sites,
    temps: &[f64],
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
    let centres = &sites.particles.centres[..sites.owned];
    let mut out = Vec::new();
    for (i, probe) in p.post.probes.iter().enumerate() {
        let value = match probe.method {
            ProbeMethod::Nearest => {
                let best = centres
                    .iter()
                    .enumerate()
                    .map(|(j, c)| (dist(c, &probe.point), j))
                    .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let (d, j) = best.unwrap_or((f64::INFINITY, 0));
                let all = session.all_gather(&[
                    d,
                    (sites.first + j) as f64,
                    temps.get(j).copied().unwrap_or(0.0),
                ])?;
                all.chunks(3)
                    .min_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])))
                    .map_or(f64::NAN, |c| c[2])
            }
            ProbeMethod::BallAverage { radius } => {
                let (mut vt, mut v) = (0.0, 0.0);
                for (j, c) in centres.iter().enumerate() {
                    if dist(c, &probe.point) <= radius {
                        vt += volumes[j] * temps[j];
                        v += volumes[j];
                    }
                }
                let s = session.sum(&[vt, v])?;
                if s[1] == 0.0 {
                    return Err(SceneError::invalid(
                        &format!("outputs.probes[{i}] ({})", probe.name),
                        format!("radius {radius:e} m"),
                        "a ball that holds a particle centre",
                    ));
                }
                s[0] / s[1]
            }
        };
        out.push(
            json!({"name": probe.name, "field": "temperature", "t": 0.0, "value": value, "solved": true}),
        );
    }
    Ok(out)
}

/// Writes the `.pvtu` that joins the ranks' `particles/particles_<r>.vtu` pieces, with the
/// fields each piece holds.
fn write_pvtu(path: &Path, ranks: usize) -> Result<(), SceneError> {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <PUnstructuredGrid GhostLevel=\"0\">\n    <PPointData>\n",
    );
    for (ty, name, n) in [
        ("Float64", "radius", 1),
        ("UInt16", "phase", 1),
        ("Int32", "coordination", 1),
        ("Int32", "solved", 1),
        ("Float64", "temperature", 1),
        ("Float64", "volume", 1),
    ] {
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
