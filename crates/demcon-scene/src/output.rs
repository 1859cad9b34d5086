//! Files of a run: `summary.json`, `probes.csv`, `profiles.csv`, `particles.csv`, the VTK
//! files for ParaView (`particles.vtu`, or a transient's `particles.pvd` series; the contact
//! network `contacts.vtp`/`.pvd`; the Laguerre cells `cells.vtu`) and the plots, written as
//! one folder that replaces the previous run's whole (`docs/outputs.md`).
//! Values that are not results (particles excluded from a solve) are never written as NaN: a
//! `solved` column flags them.

use std::borrow::Cow;
use std::path::Path;

use demcon_core::StageRecord;
use demcon_core::Vec3;
use demcon_post::{Field, Polyhedra, write_csv, write_lines_vtp, write_polyhedra_vtu, write_pvd, write_vtu};
use serde::Serialize;
use serde_json::json;

use crate::error::SceneError;
use crate::run::{RunResult, SeriesEntry};

pub(crate) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> SceneError + '_ {
    move |source| SceneError::Io {
        path: path.into(),
        source,
    }
}

/// Writes `bytes` to `path` through a temporary file and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SceneError> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).map_err(io(&tmp))?;
    std::fs::rename(&tmp, path).map_err(io(path))?;
    Ok(())
}

#[derive(Serialize)]
struct Stats {
    n_particles: usize,
    domain_volume_m3: f64,
    phi: f64,
}

/// The run summary as JSON (also what `summary.json` holds).
pub fn summary_json(name: &str, r: &RunResult) -> serde_json::Value {
    summary_with(name, r, r.stages.records())
}

/// One stage as `summary.json` lists it: wall time (s), resident size after it and its peak
/// (MB = 10⁶ bytes), and whether that peak is the stage's own or the process's so far.
fn stage_json(s: &StageRecord) -> serde_json::Value {
    let mb = |b: Option<u64>| b.map(|b| b as f64 / 1e6);
    json!({
        "stage": s.stage,
        "wall_s": s.wall_s,
        "rss_mb": mb(s.rss_bytes),
        "peak_rss_mb": mb(s.peak_rss_bytes),
        "peak_is_stage": s.peak_is_stage,
    })
}

/// The summary with the given stage list (the run's, plus the writing of the outputs).
fn summary_with(name: &str, r: &RunResult, stages: &[StageRecord]) -> serde_json::Value {
    let m = &r.model;
    let peak = stages.iter().filter_map(|s| s.peak_rss_bytes).max();
    json!({
        "scene": name,
        "model": Stats { n_particles: m.particles.len(), domain_volume_m3: m.domain_volume, phi: m.phi },
        "build": m.report,
        "c_t": r.thermal_setup.as_ref().and_then(|s| match s.surface {
            demcon_graph::SurfaceModel::Calibrated { c_t } => Some(c_t),
            _ => None,
        }).or_else(|| homogenized_calibration(r).map(|c| c.c_t)),
        "calibration": r.thermal_setup.as_ref().and_then(|s| s.calibration.clone())
            .or_else(|| homogenized_calibration(r).cloned()),
        "thermal": r.thermal.as_ref().map(|t| &t.report),
        "electric": r.electric.as_ref().map(|e| &e.report),
        "etc": r.etc,
        "etc_tensor": r.homogenization.as_ref().and_then(|h| h.thermal.as_ref()).map(|t| t.report.tensor),
        "conductivity_tensor": r.homogenization.as_ref().and_then(|h| h.electric.as_ref()).map(|e| e.report.tensor),
        "homogenization": r.homogenization.as_ref().map(|h| json!({
            "thermal": h.thermal.as_ref().map(|t| &t.report),
            "electric": h.electric.as_ref().map(|e| &e.report),
        })),
        "halo": r.halo.as_ref().map(|h| h.2),
        "probes": r.probes,
        "profiles": r.profiles,
        "diagnostics": r.diagnostics,
        "stages": stages.iter().map(stage_json).collect::<Vec<_>>(),
        "memory": json!({
            "peak_rss_mb": peak.map(|b| b as f64 / 1e6),
            "peak_bytes_per_particle": peak.map(|b| b as f64 / m.particles.len().max(1) as f64),
        }),
        "distributed": distributed_json(),
        "post_s": r.post_s,
        "wall_s": r.wall_s,
    })
}

/// The distributed solves of this process (`demcon run --distributed`): ranks, systems,
/// iterations and this rank's assembly, set-up, solve and gather times (s); null when none ran.
pub(crate) fn distributed_json() -> serde_json::Value {
    let s = demcon_network::distributed::stats();
    if s.ranks == 0 {
        return serde_json::Value::Null;
    }
    json!({
        "method": demcon_network::distributed::METHOD,
        "petsc_solver": s.solver,
        "ranks": s.ranks,
        "systems": s.systems,
        "ksp_solves": s.ksp_solves,
        "iterations": s.iterations,
        "assembly_s": s.assembly_s,
        "setup_s": s.setup_s,
        "solve_s": s.solve_s,
        "gather_s": s.gather_s,
        "max_unknowns": s.max_unknowns,
        "rows_per_rank": [s.rows_per_rank.0, s.rows_per_rank.1],
        "ghosts_rank0": s.ghosts,
        "peak_rss_mb_per_rank": [s.peak_rss_bytes.0 / 1e6, s.peak_rss_bytes.1 / 1e6],
    })
}

/// The C_t calibration of a thermal homogenisation, when it made one.
fn homogenized_calibration(r: &RunResult) -> Option<&demcon_model::CtCalibration> {
    r.homogenization.as_ref()?.thermal.as_ref()?.calibration.as_ref()
}

/// The file that marks a folder as a demcon run's output folder (which a new run may replace).
pub const RUN_MARKER: &str = ".demcon-run";

/// The parent folder and the name of an output folder.
pub(crate) fn split_dir(dir: &Path) -> Result<(&Path, &std::ffi::OsStr), SceneError> {
    let invalid = || {
        SceneError::invalid(
            "--out",
            dir.display(),
            "give a named output folder (e.g. out/slab), not `.`, `..` or a root",
        )
    };
    let name = dir.file_name().ok_or_else(invalid)?;
    let parent = dir.parent().map_or(Path::new("."), |p| {
        if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        }
    });
    Ok((parent, name))
}

/// Checks, before any work, that `dir` can receive a run's outputs: it is new, empty, or the
/// output folder of an earlier run (it holds [`RUN_MARKER`] or `summary.json`, and will be
/// replaced whole); and its parent folder exists (or can be created) and is writable.
pub fn check_output_dir(dir: &Path) -> Result<(), SceneError> {
    let (parent, _) = split_dir(dir)?;
    if dir.exists() {
        if !dir.is_dir() {
            return Err(SceneError::invalid(
                "--out",
                dir.display(),
                "exists and is not a folder: give a folder for the outputs",
            ));
        }
        let mut entries = std::fs::read_dir(dir).map_err(io(dir))?;
        let is_run = dir.join(RUN_MARKER).exists() || dir.join("summary.json").exists();
        if !is_run && entries.next().is_some() {
            return Err(SceneError::invalid(
                "--out",
                dir.display(),
                "is a folder with other files in it: give a new or empty folder, or an earlier run's \
                 output folder (which is replaced whole)",
            ));
        }
    }
    std::fs::create_dir_all(parent).map_err(io(parent))?;
    // Unique within the process too: two runs of one process (threads, tests) may check the
    // same parent at once, and one would remove the other's probe.
    static PROBES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = PROBES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let probe = parent.join(format!(".demcon-write-test-{}-{n}", std::process::id()));
    std::fs::write(&probe, b"").map_err(io(parent))?;
    std::fs::remove_file(&probe).map_err(io(&probe))?;
    Ok(())
}

/// Writes every output the scene asks for into the folder `dir`, as a whole: the files are
/// written into a temporary sibling folder which then replaces `dir` (an earlier run's folder
/// is removed), so a folder never mixes two runs and a killed run leaves the old one or the
/// new one. Returns the files written. `dir` must pass [`check_output_dir`].
pub fn write_outputs(
    name: &str,
    outputs: &crate::config::OutputsConfig,
    r: &RunResult,
    dir: &Path,
) -> Result<Vec<String>, SceneError> {
    check_output_dir(dir)?;
    let (parent, base) = split_dir(dir)?;
    let tag = |what: &str| {
        let mut n = std::ffi::OsString::from(".");
        n.push(base);
        n.push(format!(".{what}-{}", std::process::id()));
        parent.join(n)
    };
    let (tmp, old) = (tag("partial"), tag("old"));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).map_err(io(&tmp))?;
    let written = match write_files(name, outputs, r, &tmp) {
        Ok(w) => w,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&tmp);
            return Err(e);
        }
    };
    write_atomic(&tmp.join(RUN_MARKER), name.as_bytes())?;
    if dir.exists() {
        std::fs::rename(dir, &old).map_err(io(dir))?;
    }
    std::fs::rename(&tmp, dir).map_err(io(dir))?;
    if old.exists() {
        std::fs::remove_dir_all(&old).map_err(io(&old))?;
    }
    Ok(written)
}

/// Writes the output files into the (new, empty) folder `dir`.
fn write_files(
    name: &str,
    outputs: &crate::config::OutputsConfig,
    r: &RunResult,
    dir: &Path,
) -> Result<Vec<String>, SceneError> {
    let reset = demcon_core::reset_peak_resident();
    let t0 = std::time::Instant::now();
    let mut written = Vec::new();
    let fields = ParticleFields::at(r, None);
    write_particles_and_contacts(outputs, r, &fields, dir, &mut written)?;
    if let Some(cells) = &r.cells {
        write_cells(r, cells, &dir.join("cells.vtu"))?;
        written.push("cells.vtu".into());
    }
    // The shapes a random placement drew, as a shapes file (`Shapes(file: ..)` reads it back).
    for rep in r.model.report.shapes.iter().filter(|s| s.placement.is_some()) {
        let name = format!("shapes-{}.txt", rep.entry);
        let about = format!(
            "phases[{}]: {} shapes placed at random (fraction {}), m; `Shapes(file: \"{name}\")` reads them back",
            rep.entry, rep.count, rep.fraction
        );
        let path = dir.join(&name);
        write_atomic(
            &path,
            crate::shapes::format_shapes(&rep.shapes, &about).as_bytes(),
        )?;
        written.push(name);
    }
    if outputs.vtk && !r.model.report.shapes.is_empty() {
        write_inclusions(r, &dir.join("inclusions.vtp"))?;
        written.push("inclusions.vtp".into());
    }
    if outputs.particles_csv {
        fields.write_csv(r, &dir.join("particles.csv"))?;
        written.push("particles.csv".into());
    }
    write_probe_tables(r, dir, &mut written)?;
    if outputs.plots {
        // Plots are a convenience: a failure is reported in the list, not fatal to the run.
        match crate::plots::write_run_plots(r, outputs, &dir.join("plots")) {
            Ok(_) => written.push("plots/".into()),
            Err(e) => written.push(format!("no plots ({e})")),
        }
    }
    let (rss_bytes, peak_rss_bytes) = demcon_core::resident_bytes();
    let mut stages = r.stages.records().to_vec();
    stages.push(StageRecord {
        stage: "outputs",
        wall_s: t0.elapsed().as_secs_f64(),
        rss_bytes,
        peak_rss_bytes,
        peak_is_stage: reset,
    });
    let summary = serde_json::to_vec_pretty(&summary_with(name, r, &stages)).expect("summary serialises");
    write_atomic(&dir.join("summary.json"), &summary)?;
    written.push("summary.json".into());
    Ok(written)
}

/// `particles` and `contacts` as VTK files: one file of a steady run, or a `.pvd` series of
/// a transient's output times then its end.
fn write_particles_and_contacts(
    outputs: &crate::config::OutputsConfig,
    r: &RunResult,
    fields: &ParticleFields<'_>,
    dir: &Path,
    written: &mut Vec<String>,
) -> Result<(), SceneError> {
    match r.t_end {
        // A transient: the series of the output times before the end, then the end.
        Some(t_end) => {
            let times: Vec<Option<&SeriesEntry>> = r.series.iter().map(Some).chain([None]).collect();
            let time = |e: &Option<&SeriesEntry>| e.map_or(t_end, |e| e.t);
            if outputs.vtk {
                let mut entries = Vec::new();
                for (k, e) in times.iter().enumerate() {
                    let file = format!("particles_{k:04}.vtu");
                    let earlier;
                    let f = match e {
                        Some(_) => {
                            earlier = ParticleFields::at(r, *e);
                            &earlier
                        }
                        None => fields,
                    };
                    write_vtu(dir.join(&file), &r.model.particles, &f.vtk())?;
                    entries.push((time(e), file));
                }
                write_pvd(dir.join("particles.pvd"), &entries)?;
                written.push(format!("particles.pvd ({} times)", entries.len()));
            }
            if outputs.contacts_vtk {
                let network = ContactNetwork::of(r)?;
                let mut entries = Vec::new();
                for (k, e) in times.iter().enumerate() {
                    let file = format!("contacts_{k:04}.vtp");
                    network.write(r, *e, &dir.join(&file))?;
                    entries.push((time(e), file));
                }
                write_pvd(dir.join("contacts.pvd"), &entries)?;
                written.push(format!("contacts.pvd ({} times)", entries.len()));
            }
        }
        None => {
            if outputs.vtk {
                write_vtu(dir.join("particles.vtu"), &r.model.particles, &fields.vtk())?;
                written.push("particles.vtu".into());
            }
            if outputs.contacts_vtk {
                ContactNetwork::of(r)?.write(r, None, &dir.join("contacts.vtp"))?;
                written.push("contacts.vtp".into());
            }
        }
    }
    Ok(())
}

/// `probes.csv` and `profiles.csv`, when the scene asks for probes or profiles.
fn write_probe_tables(r: &RunResult, dir: &Path, written: &mut Vec<String>) -> Result<(), SceneError> {
    if !r.probes.is_empty() {
        let mut s = String::from("probe,field,t_s,value,solved\n");
        for p in &r.probes {
            let solved = u8::from(p.solved);
            s.push_str(&format!(
                "{},{},{},{:.10e},{solved}\n",
                p.name, p.field, p.t, p.value
            ));
        }
        write_atomic(&dir.join("probes.csv"), s.as_bytes())?;
        written.push("probes.csv".into());
    }
    if !r.profiles.is_empty() {
        let mut s = String::from("profile,field,t_s,distance_m,value,solved\n");
        for p in &r.profiles {
            for ((d, v), ok) in p.points.iter().zip(&p.solved) {
                let solved = u8::from(*ok);
                s.push_str(&format!(
                    "{},{},{},{d:.10e},{v:.10e},{solved}\n",
                    p.name, p.field, p.t
                ));
            }
        }
        write_atomic(&dir.join("profiles.csv"), s.as_bytes())?;
        written.push("profiles.csv".into());
    }
    Ok(())
}

/// The per-particle fields of a run at one time, as the VTU and the CSV write them.
pub(crate) struct ParticleFields<'a> {
    /// 1 where the particle was solved for, 0 where a solve excluded it.
    pub(crate) solved: Vec<i32>,
    /// Contacts per particle.
    degree: Vec<i32>,
    /// Scalar fields (name, value per particle).
    pub(crate) scalars: Vec<(&'static str, Vec<f64>)>,
    /// Vector fields (name, value per particle).
    pub(crate) vectors: Vec<(&'static str, Cow<'a, [Vec3]>)>,
    /// 1 where the particle's Halo is cut by the boundary.
    halo_cut: Option<Vec<i32>>,
    /// 1 where the particle is on a crack face (an end of a contact a crack crosses), when the
    /// model has cracks.
    crack_face: Option<Vec<i32>>,
}

impl<'a> ParticleFields<'a> {
    /// The fields at the end of the run (`at` = `None`) or at an earlier output time of a
    /// transient: its temperatures, flux and Halo, and the electric fields when the end's
    /// solution held then too.
    pub(crate) fn at(r: &'a RunResult, at: Option<&'a SeriesEntry>) -> Self {
        let m = &r.model;
        let n = m.particles.len();
        let mut solved = vec![1i32; n];
        let mut excluded: Vec<u32> = Vec::new();
        if let Some(e) = &r.electric {
            excluded.extend(&e.excluded);
        }
        if let (Some(b), Some(s)) = (&r.thermal_bcs, &r.thermal_setup) {
            excluded.extend(
                b.constraints
                    .excluded()
                    .iter()
                    .filter(|&&p| s.walls.is_particle(p)),
            );
        }
        for &p in &excluded {
            solved[p as usize] = 0;
        }
        let degree: Vec<i32> = m.graph.degrees().iter().map(|&d| d as i32).collect();
        let mut scalars: Vec<(&str, Vec<f64>)> = Vec::new();
        // Laminate rule: the fraction of each particle's volume in its own phase (1 unless an
        // interface cuts it) and the phase on the other side (its own phase if none).
        let lam = m.laminates();
        scalars.push((
            "phase_fraction",
            (0..n)
                .map(|p| lam.get(p).map_or(1.0, |x| 1.0 - x.other_fraction))
                .collect(),
        ));
        scalars.push((
            "other_phase",
            (0..n)
                .map(|p| lam.get(p).map_or(m.particles.phases[p], |x| x.other_phase) as f64)
                .collect(),
        ));
        // Conforming seeds (the last `m.seeds` particles) are sites that put the spheres'
        // surfaces on facets, not particles of the packing: 1 marks them.
        if m.seeds > 0 {
            scalars.push((
                "surface_seed",
                (0..n).map(|p| f64::from(u8::from(p + m.seeds >= n))).collect(),
            ));
        }
        // The volume each particle stands for (m³): the Laguerre cell's, or the representative
        // volume of the contact models (V_p/φ, V_p/f_v): the thermal network's when the run has
        // heat (its capacities and flux divide by it), else the electric network's.
        let volume: Vec<f64> = match (&r.thermal_setup, &r.electric) {
            (Some(s), _) => s.rep_volumes.clone(),
            (None, Some(e)) => e.rep_volumes.clone(),
            (None, None) => (0..n).map(|p| m.solid_volume_of(p)).collect(),
        };
        if let Some(t) = &r.thermal {
            let temps = at.map_or(&t.temperatures, |e| &t.snapshots[e.snapshot].1);
            scalars.push(("temperature", temps.clone()));
        }
        let mut vectors: Vec<(&str, Cow<'a, [Vec3]>)> = Vec::new();
        if let Some(e) = r.electric.as_ref().filter(|_| at.is_none_or(|e| e.electric)) {
            scalars.push(("potential", e.potentials.clone()));
            scalars.push(("joule_power", e.joule.clone()));
            // W per particle is no density: a slice would show large particles as hot spots.
            scalars.push((
                "joule_power_density",
                e.joule.iter().zip(&volume).map(|(w, v)| w / v).collect(),
            ));
            // The heat flux's construction (contacts at their facets' centroids, electrode
            // links, the electric network's representative volumes): exact in a uniform field.
            vectors.push(("current_density", Cow::Owned(e.current_density(m))));
        }
        scalars.push(("volume", volume));
        if let Some(t) = r.homogenization.as_ref().and_then(|h| h.thermal.as_ref()) {
            // The temperature fluctuation under a unit mean gradient along each axis (m = K per K/m).
            let [x, y, z] = &t.fluctuations;
            scalars.push(("fluctuation_gx", x.clone()));
            scalars.push(("fluctuation_gy", y.clone()));
            scalars.push(("fluctuation_gz", z.clone()));
        }
        let (flux, halo) = match at {
            Some(e) => (e.flux.as_deref(), e.halo.as_ref().map(|(h, cut)| (h, cut))),
            None => (r.flux.as_deref(), r.halo.as_ref().map(|(h, cut, _)| (h, cut))),
        };
        if let Some(f) = flux {
            vectors.push(("heat_flux", Cow::Borrowed(f)));
        }
        if let Some((h, _)) = halo {
            vectors.push(("halo_flux", Cow::Borrowed(h)));
        }
        let halo_cut = halo.map(|(_, cut)| cut.iter().map(|&b| i32::from(b)).collect());
        let on_crack = m.crack_face_particles();
        let crack_face = (!on_crack.is_empty()).then(|| {
            let mut f = vec![0i32; n];
            on_crack.iter().for_each(|&p| f[p as usize] = 1);
            f
        });
        Self {
            solved,
            degree,
            scalars,
            vectors,
            halo_cut,
            crack_face,
        }
    }

    /// The fields of `particles.vtu`.
    fn vtk(&self) -> Vec<Field<'_>> {
        let mut fields = vec![
            Field::ints("coordination", &self.degree),
            Field::ints("solved", &self.solved),
        ];
        for (name, v) in &self.scalars {
            fields.push(Field::scalars(name, v));
        }
        for (name, v) in &self.vectors {
            fields.push(Field::vectors(name, v));
        }
        if let Some(c) = &self.halo_cut {
            fields.push(Field::ints("halo_truncated", c));
        }
        if let Some(c) = &self.crack_face {
            fields.push(Field::ints("crack_face", c));
        }
        fields
    }

    /// Writes `particles.csv`: position, radius, phase, solved, every scalar, every vector
    /// component.
    fn write_csv(&self, r: &RunResult, path: &Path) -> Result<(), SceneError> {
        let p = &r.model.particles;
        let coord = |k: usize| -> Vec<f64> { p.centres.iter().map(|c| c[k]).collect() };
        let (x, y, z) = (coord(0), coord(1), coord(2));
        let phase: Vec<f64> = p.phases.iter().map(|&q| q as f64).collect();
        let solved: Vec<f64> = self.solved.iter().map(|&s| s as f64).collect();
        let mut header = vec!["x", "y", "z", "radius", "phase", "solved"];
        let mut cols: Vec<&[f64]> = vec![&x, &y, &z, &p.radii, &phase, &solved];
        for (name, v) in &self.scalars {
            header.push(name);
            cols.push(v);
        }
        let comps = vector_columns(self.vectors.iter().map(|(name, v)| (*name, &**v)));
        for (name, v) in &comps {
            header.push(name);
            cols.push(v);
        }
        write_csv(path, &header, &cols)?;
        Ok(())
    }
}

/// The CSV columns of vector fields: `<name>_x`, `<name>_y`, `<name>_z` of each.
pub(crate) fn vector_columns<'v>(
    vectors: impl Iterator<Item = (&'v str, &'v [Vec3])>,
) -> Vec<(String, Vec<f64>)> {
    vectors
        .flat_map(|(name, v)| {
            (0..3).map(move |k| {
                (
                    format!("{name}_{}", ["x", "y", "z"][k]),
                    v.iter().map(|u| u[k]).collect(),
                )
            })
        })
        .collect()
}

/// Pieces of each shape's meridian in `inclusions.vtp` (a spheroid: 2 · 16 · 7 triangles).
const SHAPE_RINGS: usize = 8;

/// Writes `inclusions.vtp`: the shaped inclusions' surfaces as triangles (m; periodic images
/// not drawn), with cell data `phase` (the material index), `entry` (the phase entry) and
/// `shape` (the shape's index in its entry).
fn write_inclusions(r: &RunResult, path: &std::path::Path) -> Result<(), SceneError> {
    let (mut points, mut triangles) = (Vec::new(), Vec::new());
    let (mut phase, mut entry, mut shape) = (Vec::new(), Vec::new(), Vec::new());
    for rep in &r.model.report.shapes {
        for (k, s) in rep.shapes.iter().enumerate() {
            let (p, t) = s.surface_mesh(SHAPE_RINGS);
            let base = points.len() as u32;
            points.extend(p);
            triangles.extend(t.iter().map(|t| t.map(|i| i + base)));
            for _ in 0..t.len() {
                phase.push(i32::from(rep.phase));
                entry.push(rep.entry as i32);
                shape.push(k as i32);
            }
        }
    }
    let fields = [
        demcon_post::Field {
            name: "phase",
            data: demcon_post::FieldData::Ints(&phase),
        },
        demcon_post::Field {
            name: "entry",
            data: demcon_post::FieldData::Ints(&entry),
        },
        demcon_post::Field {
            name: "shape",
            data: demcon_post::FieldData::Ints(&shape),
        },
    ];
    demcon_post::write_triangles_vtp(path, &points, &triangles, &fields)?;
    Ok(())
}

/// What a line of `contacts.vtp` is (its `kind` cell value).
#[derive(Clone, Copy)]
#[repr(i32)]
enum LineKind {
    /// A contact (or Laguerre facet) between two particles.
    Contact = 0,
    /// A particle's link to a face held at a temperature.
    ThermalWall = 1,
    /// A particle's link to a face electrode.
    Electrode = 2,
    /// A contact an open crack cut (no longer in the network).
    CutByCrack = 3,
    /// A broken bond of `cut_contacts` (no longer in the network).
    BrokenBond = 4,
}

/// The contact network of a run as `contacts.vtp` draws it: the lines — the contacts, then the
/// thermal wall links, then the face-electrode links, then the contacts cracks and broken bonds
/// removed — and their values that do not change in time. A contact across a periodic boundary ends at the image of its second particle; a wall
/// link ends where it meets its face (a Laguerre facet's centroid, else the particle's centre
/// moved by the link's half-length along the face's normal).
struct ContactNetwork {
    /// Particle centres, then one end point per line that needs its own (m).
    points: Vec<Vec3>,
    lines: Vec<[u32; 2]>,
    kind: Vec<i32>,
    /// The contact's marks (`demcon_model::defects::MARK_*`: interface 1, damaged 2, filled
    /// crack 4); 0 on the other lines.
    marks: Vec<i32>,
    /// Centre-to-centre distance, or the link's half-length (m).
    length: Vec<f64>,
    /// Transmission surface (m²): the thermal network's, or the electric one's without heat.
    surface: Vec<f64>,
    /// Thermal conductance (W/K); 0 on electrode links.
    thermal: Option<Vec<f64>>,
    /// Electric conductance (S); 0 on thermal wall links.
    electric: Option<Vec<f64>>,
}

impl ContactNetwork {
    fn of(r: &RunResult) -> Result<Self, SceneError> {
        let m = &r.model;
        let g = &m.graph;
        let (particles, n) = (&m.particles, m.particles.len());
        let mut points = particles.centres.clone();
        let mut lines = Vec::with_capacity(g.pairs.len());
        for (k, &[p, q]) in g.pairs.iter().enumerate() {
            let end = particles.centres[p as usize] + g.branch(k);
            let q = if (end - particles.centres[q as usize]).norm() > 1e-9 * particles.radii[p as usize] {
                points.push(end);
                (points.len() - 1) as u32
            } else {
                q
            };
            lines.push([p, q]);
        }
        let contacts = lines.len();
        let mut kind = vec![LineKind::Contact as i32; contacts];
        let mut length: Vec<f64> = g.geometry.iter().map(|c| c.distance).collect();
        let degrees = g.degrees();
        let setup = r.thermal_setup.as_ref();
        let electric = r.electric.as_ref();
        let mut surface = match (setup, electric) {
            (Some(s), _) => s.areas(m).to_vec(),
            (None, Some(e)) => demcon_graph::contact_surfaces(g, particles, &e.surface)?.area,
            (None, None) => vec![0.0; contacts],
        };
        let mut links =
            |walls: &demcon_graph::WallContacts, sm: &demcon_graph::SurfaceModel, what: LineKind| {
                let surfaces = walls.surfaces(particles, &degrees, sm);
                for (k, (&p, s)) in walls.particle.iter().zip(surfaces).enumerate() {
                    let lever = walls
                        .lever
                        .get(k)
                        .copied()
                        .unwrap_or(walls.half_length[k] * walls.normal[k]);
                    points.push(particles.centres[p as usize] + lever);
                    lines.push([p, (points.len() - 1) as u32]);
                    kind.push(what as i32);
                    length.push(walls.half_length[k]);
                    surface.push(s);
                }
                walls.len()
            };
        let thermal_links = setup.map_or(0, |s| links(&s.walls, &s.surface, LineKind::ThermalWall));
        let electrode_links = electric.map_or(0, |e| links(&e.walls, &e.surface, LineKind::Electrode));
        // The contacts removed by open cracks and broken bonds: drawn, conducting nothing (their
        // temperature drop is the jump across the crack).
        let cut = m.cut_contacts();
        for c in cut {
            let [p, q] = c.pair;
            let mut d = particles.centres[q as usize] - particles.centres[p as usize];
            if let Some(period) = m.container.period() {
                for k in 0..3 {
                    d[k] -= period[k] * (d[k] / period[k]).round();
                }
            }
            let end = particles.centres[p as usize] + d;
            let q = if d == particles.centres[q as usize] - particles.centres[p as usize] {
                q
            } else {
                points.push(end);
                (points.len() - 1) as u32
            };
            lines.push([p, q]);
            kind.push(match c.cause {
                demcon_model::CutCause::Crack { .. } => LineKind::CutByCrack as i32,
                demcon_model::CutCause::Broken => LineKind::BrokenBond as i32,
            });
            length.push(d.norm());
            surface.push(0.0);
        }
        let zeros = |k: usize| vec![0.0; k];
        let thermal = setup.map(|s| {
            [
                s.contact_conductances(),
                s.wall_conductances(),
                &zeros(electrode_links),
                &zeros(cut.len()),
            ]
            .concat()
        });
        let electric = electric.map(|e| {
            let (c, w) = e.conductances.split_at(contacts);
            [c, &zeros(thermal_links), w, &zeros(cut.len())].concat()
        });
        let mut marks: Vec<i32> = m.contact_marks().iter().map(|&b| i32::from(b)).collect();
        marks.resize(lines.len(), 0);
        debug_assert!(points.len() >= n);
        Ok(Self {
            points,
            lines,
            kind,
            marks,
            length,
            surface,
            thermal,
            electric,
        })
    }

    /// Writes `contacts.vtp` at the end of the run (`at` = `None`) or at an earlier output time:
    /// heat flow (W, from the line's first end to its second) and temperature drop (K) there;
    /// current (A, same direction) and Joule power I²/G (W, before the heat fraction η) when
    /// the end's electric solution held then.
    fn write(&self, r: &RunResult, at: Option<&SeriesEntry>, path: &Path) -> Result<(), SceneError> {
        let m = &r.model;
        let contacts = m.graph.pairs.len();
        let mut fields = vec![
            Field::ints("kind", &self.kind),
            Field::ints("marks", &self.marks),
            Field::scalars("length", &self.length),
            Field::scalars("surface", &self.surface),
        ];
        let (flow, mut drop): (Vec<f64>, Vec<f64>);
        if let (Some(g), Some(th), Some(s)) = (&self.thermal, &r.thermal, &r.thermal_setup) {
            let temps = at.map_or(&th.temperatures, |e| &th.snapshots[e.snapshot].1);
            let wall = |w: usize| th.wall_temperatures[w];
            drop = m
                .graph
                .pairs
                .iter()
                .map(|&[p, q]| temps[p as usize] - temps[q as usize])
                .collect();
            for (k, w) in s.walls.wall_of_links().enumerate() {
                drop.push(temps[s.walls.particle[k] as usize] - wall(w));
            }
            let electrode_links = r.electric.as_ref().map_or(0, |e| e.walls.len());
            drop.resize(drop.len() + electrode_links, 0.0);
            drop.extend(
                m.cut_contacts()
                    .iter()
                    .map(|c| temps[c.pair[0] as usize] - temps[c.pair[1] as usize]),
            );
            flow = drop.iter().zip(g).map(|(d, g)| d * g).collect();
            fields.push(Field::scalars("thermal_conductance", g));
            fields.push(Field::scalars("heat_flow", &flow));
            fields.push(Field::scalars("temperature_drop", &drop));
        }
        let (current, joule): (Vec<f64>, Vec<f64>);
        if let (Some(g), Some(e)) = (
            &self.electric,
            r.electric.as_ref().filter(|_| at.is_none_or(|a| a.electric)),
        ) {
            let thermal_links = r.thermal_setup.as_ref().map_or(0, |s| s.walls.len());
            let (c, w) = e.branch_currents.split_at(contacts);
            current = [
                c,
                &vec![0.0; thermal_links],
                w,
                &vec![0.0; m.cut_contacts().len()],
            ]
            .concat();
            joule = current
                .iter()
                .zip(g)
                .map(|(i, g)| if *g > 0.0 { i * i / g } else { 0.0 })
                .collect();
            fields.push(Field::scalars("electric_conductance", g));
            fields.push(Field::scalars("current", &current));
            fields.push(Field::scalars("joule_power", &joule));
        }
        write_lines_vtp(path, &self.points, &self.lines, &fields)?;
        Ok(())
    }
}

/// Writes `cells.vtu`: the Laguerre cell of every particle as a polyhedron, with the cell data
/// `particle` (index), `phase`, `volume` (m³, the tessellation's) and the end's `temperature`
/// (°C) and `potential` (V) when solved.
fn write_cells(r: &RunResult, cells: &Polyhedra, path: &Path) -> Result<(), SceneError> {
    let m = &r.model;
    let id: Vec<i32> = (0..m.particles.len() as i32).collect();
    let phase: Vec<i32> = m.particles.phases.iter().map(|&p| i32::from(p)).collect();
    let mut fields = vec![Field::ints("particle", &id), Field::ints("phase", &phase)];
    if let Some(c) = m.graph.cells.as_deref() {
        fields.push(Field::scalars("volume", &c.volume));
    }
    if let Some(t) = &r.thermal {
        fields.push(Field::scalars("temperature", &t.temperatures));
    }
    if let Some(e) = &r.electric {
        fields.push(Field::scalars("potential", &e.potentials));
    }
    write_polyhedra_vtu(path, cells, &fields)?;
    Ok(())
}
