//! Files of a run: `summary.json`, `probes.csv`, `profiles.csv`, `particles.csv` and
//! `particles.vtu` (ParaView), written as one folder that replaces the previous run's whole.
//! Values that are not results (particles excluded from a solve) are never written as NaN: a
//! `solved` column flags them.

use std::path::Path;

use demcon_core::StageRecord;
use demcon_post::{Field, write_csv, write_vtu};
use serde::Serialize;
use serde_json::json;

use crate::error::SceneError;
use crate::run::RunResult;

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> SceneError + '_ {
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
        "post_s": r.post_s,
        "wall_s": r.wall_s,
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
    let probe = parent.join(format!(".demcon-write-test-{}", std::process::id()));
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
    let fields = ParticleFields::of(r);
    if outputs.vtk {
        write_vtu(dir.join("particles.vtu"), &r.model.particles, &fields.vtk())?;
        written.push("particles.vtu".into());
    }
    if outputs.particles_csv {
        fields.write_csv(r, &dir.join("particles.csv"))?;
        written.push("particles.csv".into());
    }
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

/// The per-particle fields of a run, as the VTU and the CSV write them.
pub(crate) struct ParticleFields<'a> {
    /// 1 where the particle was solved for, 0 where a solve excluded it.
    pub(crate) solved: Vec<i32>,
    /// Contacts per particle.
    degree: Vec<i32>,
    /// Scalar fields (name, value per particle).
    pub(crate) scalars: Vec<(&'static str, Vec<f64>)>,
    /// Vector fields (name, value per particle).
    pub(crate) vectors: Vec<(&'static str, &'a [demcon_core::Vec3])>,
    /// 1 where the particle's Halo is cut by the boundary.
    halo_cut: Option<Vec<i32>>,
}

impl<'a> ParticleFields<'a> {
    pub(crate) fn of(r: &'a RunResult) -> Self {
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
        if let Some(t) = &r.thermal {
            scalars.push(("temperature", t.temperatures.clone()));
        }
        if let Some(e) = &r.electric {
            scalars.push(("potential", e.potentials.clone()));
            scalars.push(("joule_power", e.joule.clone()));
            // Current density magnitude from the branch currents, as the flux of eq. 20:
            // j_p = (1/(2 V_rep)) |Σ_q I_pq ℓ_pq|.
            let mut d = vec![demcon_core::Vec3::zeros(); n];
            for (k, &[p, q]) in m.graph.pairs.iter().enumerate() {
                let l = m.graph.branch(k) * e.branch_currents[k];
                d[p as usize] += l;
                d[q as usize] += l;
            }
            let vrep: Vec<f64> = (0..n).map(|p| m.solid_volume_of(p)).collect();
            scalars.push((
                "current_density",
                d.iter().zip(&vrep).map(|(v, w)| v.norm() / (2.0 * w)).collect(),
            ));
        }
        if let Some(t) = r.homogenization.as_ref().and_then(|h| h.thermal.as_ref()) {
            // The temperature fluctuation under a unit mean gradient along each axis (m = K per K/m).
            let [x, y, z] = &t.fluctuations;
            scalars.push(("fluctuation_gx", x.clone()));
            scalars.push(("fluctuation_gy", y.clone()));
            scalars.push(("fluctuation_gz", z.clone()));
        }
        let mut vectors: Vec<(&str, &[demcon_core::Vec3])> = Vec::new();
        if let Some(f) = &r.flux {
            vectors.push(("heat_flux", f));
        }
        if let Some((h, _, _)) = &r.halo {
            vectors.push(("halo_flux", h));
        }
        let halo_cut = r
            .halo
            .as_ref()
            .map(|h| h.1.iter().map(|&b| i32::from(b)).collect());
        Self {
            solved,
            degree,
            scalars,
            vectors,
            halo_cut,
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
        let comps: Vec<(String, Vec<f64>)> = self
            .vectors
            .iter()
            .flat_map(|(name, v)| {
                (0..3).map(move |k| {
                    (
                        format!("{name}_{}", ["x", "y", "z"][k]),
                        v.iter().map(|u| u[k]).collect(),
                    )
                })
            })
            .collect();
        for (name, v) in &comps {
            header.push(name);
            cols.push(v);
        }
        write_csv(path, &header, &cols)?;
        Ok(())
    }
}
