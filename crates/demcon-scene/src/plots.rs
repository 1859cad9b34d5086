//! Plots of a run (PNG): probes against time, profiles along their lines, and slices of the
//! particle fields with a colour bar and axes in mm. The same charts are drawn from a run in
//! memory ([`write_run_plots`], `outputs.plots`) or from a run's output folder
//! ([`read_run_folder`] then [`write_plots`], `demcon plot`): both go through [`PlotData`].
//!
//! Names and units of the fields are those of [`crate::output`]'s files; the drawing is
//! `demcon-plot`'s.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use demcon_core::{Axis, ParticleSet, Vec3};
use demcon_plot::{Chart, Raster, Scale, Series, draw, draw_raster};
use demcon_post::{Domain, Plane, SliceParams, read_csv, read_vtu, slice_grid};

use crate::config::{AxisConfig, OutputsConfig};
use crate::error::SceneError;
use crate::output::ParticleFields;
use crate::run::{ProbeValue, ProfileValues, RunResult};

/// The unit of a field of a run's files (probes, profiles, particles), as drawn on axes;
/// `None` for a dimensionless or unknown field. Temperatures are drawn in °C, as the
/// example scenes give them (a scene in K plots the same numbers).
pub fn field_unit(field: &str) -> Option<&'static str> {
    Some(match field {
        "temperature" => "°C",
        "potential" => "V",
        "joule_power" => "W",
        "joule_power_density" => "W/m³",
        "current_density" => "A/m²",
        "volume" => "m³",
        "heat_flux" | "halo_flux" | "flux_magnitude" | "halo_flux_magnitude" => "W/m²",
        "radius" => "m",
        f if f.starts_with("fluctuation_g") => "m",
        _ => return None,
    })
}

/// The fields of the default slices: the first of temperature and potential the run has, and
/// the Halo flux when it has one.
const DEFAULT_SLICES: [&str; 3] = ["temperature", "potential", "halo_flux"];

/// `field (unit)`, or `field` alone when it has no unit.
fn labelled(field: &str) -> String {
    match field_unit(field) {
        Some(u) => format!("{field} ({u})"),
        None => field.to_string(),
    }
}

/// Per-particle fields of a run: positions, radii, and each field as one value per particle
/// (a vector field by its magnitude).
#[derive(Debug, Clone)]
pub struct ParticleData<'a> {
    /// The particles (m): a run's own, or read from its files.
    pub particles: Cow<'a, ParticleSet>,
    /// Fields (name, value per particle): scalars, and vectors by their magnitude.
    pub fields: Vec<(String, Vec<f64>)>,
    /// Which fields are magnitudes of vectors.
    pub vectors: Vec<String>,
    /// Per particle, whether it was solved for (values of the others are not results).
    pub solved: Vec<bool>,
    /// Where the data came from (a file, or "the run"), for messages.
    pub source: String,
    /// When the fields were taken (slices say it in their titles).
    pub time: FieldTime,
}

/// When a run's particle fields were taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FieldTime {
    /// The steady state (a steady run, or one without time).
    Steady,
    /// A transient at this time (s).
    At(f64),
    /// The end of a transient whose files do not say when (`particles.csv` without
    /// `particles.pvd`, probes or profiles).
    End,
}

impl FieldTime {
    /// `t = 0.2 s`, `the end of the transient`, or nothing for a steady state.
    fn words(self) -> Option<String> {
        match self {
            Self::Steady => None,
            Self::At(t) => Some(format!("t = {} s", demcon_plot::fmt_tick(t))),
            Self::End => Some("end of the transient".into()),
        }
    }
}

impl ParticleData<'_> {
    /// The field called `name`.
    pub fn field(&self, name: &str) -> Option<&[f64]> {
        self.fields
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// What the plots are drawn from.
#[derive(Debug, Clone, Default)]
pub struct PlotData<'a> {
    /// Probe readings (any order; grouped by field, then probe).
    pub probes: Vec<ProbeValue>,
    /// Profiles (grouped by profile and field, one curve per time).
    pub profiles: Vec<ProfileValues>,
    /// Per-particle fields, when the run kept them.
    pub particles: Option<ParticleData<'a>>,
    /// The domain of the particles; `None`: the box around the spheres.
    pub domain: Option<Domain>,
    /// The effective-conductivity axis of the run, if any (default slices contain it).
    pub etc_axis: Option<Axis>,
    /// The folder the data was read from, for messages (`None` for a run in memory).
    pub folder: Option<PathBuf>,
    /// Whether the run is a transient (its probes and profiles are at times), or steady.
    pub transient: bool,
}

/// What to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotParams {
    /// Fields to slice; empty: `temperature` (or `potential`), and `halo_flux` when present.
    pub slices: Vec<String>,
    /// The slice plane's normal; `None`: chosen by [`slice_normal`] from the run's main field
    /// (temperature, else potential, else the first field sliced), one plane for all slices:
    /// the plane contains the axis along which that field varies most (the ETC axis when the
    /// run has one), or the domain's longest axis when it varies along none.
    pub axis: Option<Axis>,
    /// The slice plane's position along its normal (m); `None`: the middle of the domain.
    pub at: Option<f64>,
    /// Cells along the longer side of a slice.
    pub resolution: usize,
}

impl Default for PlotParams {
    fn default() -> Self {
        Self {
            slices: Vec::new(),
            axis: None,
            at: None,
            resolution: 200,
        }
    }
}

/// What [`write_plots`] did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Plots {
    /// The PNGs written, in order.
    pub files: Vec<PlotFile>,
    /// Charts left out and why (e.g. a single probe read at a single time: one point).
    pub skipped: Vec<String>,
}

/// One PNG written.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotFile {
    /// File name in the plot folder.
    pub name: String,
    /// What it shows, e.g. `temperature, plane z = 50 mm`.
    pub what: String,
    /// A slice's colour-bar range (lo, hi) in the field's unit.
    pub range: Option<(f64, f64)>,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> SceneError + '_ {
    move |source| SceneError::Io {
        path: path.into(),
        source,
    }
}

fn input(path: &Path, problem: impl Into<String>) -> SceneError {
    SceneError::PlotInput {
        path: path.into(),
        problem: problem.into(),
    }
}

/// The plot data of a run in memory: its probes, profiles, and the fields the default slices
/// draw (temperature, potential, |halo_flux|), on the run's own particles.
pub fn plot_data_of<'a>(r: &'a RunResult, outputs: &OutputsConfig) -> PlotData<'a> {
    let f = ParticleFields::at(r, None);
    let mut fields: Vec<(String, Vec<f64>)> = f
        .scalars
        .into_iter()
        .filter(|(n, _)| DEFAULT_SLICES.contains(n))
        .map(|(n, v)| (n.to_string(), v))
        .collect();
    let mut vectors = Vec::new();
    for (name, v) in f.vectors.iter().filter(|(n, _)| DEFAULT_SLICES.contains(n)) {
        fields.push((name.to_string(), v.iter().map(|x| x.norm()).collect()));
        vectors.push(name.to_string());
    }
    PlotData {
        probes: r.probes.clone(),
        profiles: r.profiles.clone(),
        particles: Some(ParticleData {
            particles: Cow::Borrowed(&r.model.particles),
            fields,
            vectors,
            solved: f.solved.iter().map(|&s| s != 0).collect(),
            source: "the run".into(),
            time: r.t_end.map_or(FieldTime::Steady, FieldTime::At),
        }),
        domain: Some(r.domain.clone()),
        etc_axis: outputs.etc_axis.map(|a| match a {
            AxisConfig::X => Axis::X,
            AxisConfig::Y => Axis::Y,
            AxisConfig::Z => Axis::Z,
        }),
        folder: None,
        transient: r.t_end.is_some(),
    }
}

/// Writes the default plots of a run in memory into `dir` (created if needed).
pub fn write_run_plots(r: &RunResult, outputs: &OutputsConfig, dir: &Path) -> Result<Plots, SceneError> {
    write_plots(&plot_data_of(r, outputs), &PlotParams::default(), dir)
}

/// Reads what plots need from a run's output folder: `summary.json` (which marks it as one,
/// and gives the ETC axis), `probes.csv`, `profiles.csv`, and the particle fields from
/// `particles.csv`, else `particles.vtu`, else the last of a transient's `particles_<k>.vtu`.
/// Missing optional files leave their part empty.
/// Errors name the folder or file: not a run's folder, a file that cannot be read or parsed.
pub fn read_run_folder(dir: &Path) -> Result<PlotData<'static>, SceneError> {
    if !dir.is_dir() {
        return Err(input(
            dir,
            "not a folder: give a run's output folder (`demcon run … --out DIR`)",
        ));
    }
    let summary = dir.join("summary.json");
    if !summary.is_file() {
        return Err(input(
            dir,
            "no summary.json: not a run's output folder (`demcon run SCENE --out DIR` writes one)",
        ));
    }
    let text = std::fs::read_to_string(&summary).map_err(io(&summary))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| input(&summary, format!("not valid JSON: {e}")))?;
    let etc_axis = json["etc"]["axis"]
        .as_str()
        .and_then(|a| match a.to_ascii_lowercase().as_str() {
            "x" => Some(Axis::X),
            "y" => Some(Axis::Y),
            "z" => Some(Axis::Z),
            _ => None,
        });
    let probes = match dir.join("probes.csv") {
        p if p.is_file() => read_probes(&p)?,
        _ => Vec::new(),
    };
    let profiles = match dir.join("profiles.csv") {
        p if p.is_file() => read_profiles(&p)?,
        _ => Vec::new(),
    };
    // A transient's scheme is a time scheme; a steady run's is `steady`.
    let transient = json["thermal"]["scheme"].as_str().is_some_and(|s| s != "steady");
    let series = match dir.join("particles.pvd") {
        p if p.is_file() => read_pvd(&p)?,
        _ => Vec::new(),
    };
    // The end of a transient: the series' last time, else the last probe or profile time.
    let end = if !transient {
        FieldTime::Steady
    } else if let Some((t, _)) = series.last() {
        FieldTime::At(*t)
    } else {
        let last = probes
            .iter()
            .map(|p| p.t)
            .chain(profiles.iter().map(|p| p.t))
            .fold(f64::NEG_INFINITY, f64::max);
        if last.is_finite() {
            FieldTime::At(last)
        } else {
            FieldTime::End
        }
    };
    let (csv, vtu) = (dir.join("particles.csv"), dir.join("particles.vtu"));
    let particles = if csv.is_file() {
        Some(read_particles_csv(&csv, end)?)
    } else if vtu.is_file() {
        Some(read_particles_vtu(&vtu, end)?)
    } else if let Some(last) = last_snapshot(dir)? {
        let name = last.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        let time = series
            .iter()
            .find(|(_, f)| f == name)
            .map_or(FieldTime::End, |(t, _)| FieldTime::At(*t));
        Some(read_particles_vtu(&last, time)?)
    } else {
        None
    };
    Ok(PlotData {
        probes,
        profiles,
        particles,
        domain: None,
        etc_axis,
        folder: Some(dir.into()),
        transient,
    })
}

/// The entries (time in s, file) of a ParaView collection as `demcon run` writes it.
fn read_pvd(path: &Path) -> Result<Vec<(f64, String)>, SceneError> {
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    let attr = |line: &str, name: &str| -> Option<String> {
        let start = line.find(&format!("{name}=\""))? + name.len() + 2;
        let len = line[start..].find('"')?;
        Some(line[start..start + len].to_string())
    };
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if !line.contains("<DataSet") {
            continue;
        }
        let (Some(t), Some(file)) = (attr(line, "timestep"), attr(line, "file")) else {
            return Err(input(
                path,
                format!("line {}: a DataSet without timestep or file", i + 1),
            ));
        };
        out.push((number(path, i + 1, "timestep", &t)?, file));
    }
    Ok(out)
}

/// The last of a transient's per-time files `particles_<k>.vtu` (greatest k), if any.
fn last_snapshot(dir: &Path) -> Result<Option<PathBuf>, SceneError> {
    let mut best: Option<(u64, PathBuf)> = None;
    for entry in std::fs::read_dir(dir).map_err(io(dir))? {
        let path = entry.map_err(io(dir))?.path();
        let k = path.file_name().and_then(|n| n.to_str()).and_then(|n| {
            n.strip_prefix("particles_")?
                .strip_suffix(".vtu")?
                .parse::<u64>()
                .ok()
        });
        if let Some(k) = k
            && best.as_ref().is_none_or(|(b, _)| k > *b)
        {
            best = Some((k, path));
        }
    }
    Ok(best.map(|(_, p)| p))
}

/// The text cells of a line of our CSVs: the first cell (a name, which may hold commas) and
/// the `n` cells after it.
fn split_row(line: &str, n: usize) -> Option<(String, Vec<&str>)> {
    let mut cells: Vec<&str> = line.rsplitn(n + 1, ',').collect();
    if cells.len() != n + 1 {
        return None;
    }
    cells.reverse();
    Some((cells[0].to_string(), cells[1..].to_vec()))
}

fn number(path: &Path, line: usize, what: &str, cell: &str) -> Result<f64, SceneError> {
    cell.trim()
        .parse()
        .map_err(|_| input(path, format!("line {line}: {what} `{cell}` is not a number")))
}

/// The data rows of one of our CSVs (after its header line): line number, the first cell (a
/// name) and the `n` cells after it; a row of another shape is refused naming `columns`.
fn rows(path: &Path, n: usize, columns: &str) -> Result<Vec<(usize, String, Vec<String>)>, SceneError> {
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        if line.trim().is_empty() {
            continue;
        }
        let (name, cells) =
            split_row(line, n).ok_or_else(|| input(path, format!("line {}: expected {columns}", i + 1)))?;
        out.push((i + 1, name, cells.into_iter().map(String::from).collect()));
    }
    Ok(out)
}

/// `probes.csv`: `probe,field,t_s,value,solved`.
fn read_probes(path: &Path) -> Result<Vec<ProbeValue>, SceneError> {
    let mut out = Vec::new();
    for (line, name, c) in rows(path, 4, "probe,field,t_s,value,solved")? {
        out.push(ProbeValue {
            name,
            field: c[0].clone(),
            t: number(path, line, "t_s", &c[1])?,
            value: number(path, line, "value", &c[2])?,
            solved: c[3].trim() == "1",
        });
    }
    Ok(out)
}

/// `profiles.csv`: `profile,field,t_s,distance_m,value,solved`, one row per point.
fn read_profiles(path: &Path) -> Result<Vec<ProfileValues>, SceneError> {
    let mut out: Vec<ProfileValues> = Vec::new();
    for (line, name, c) in rows(path, 5, "profile,field,t_s,distance_m,value,solved")? {
        let t = number(path, line, "t_s", &c[1])?;
        let point = (
            number(path, line, "distance_m", &c[2])?,
            number(path, line, "value", &c[3])?,
        );
        let solved = c[4].trim() == "1";
        match out.last_mut() {
            Some(p) if p.name == name && p.field == c[0] && p.t == t => {
                p.points.push(point);
                p.solved.push(solved);
            }
            _ => out.push(ProfileValues {
                name,
                field: c[0].clone(),
                t,
                points: vec![point],
                solved: vec![solved],
            }),
        }
    }
    Ok(out)
}

/// The particle set of a file's columns, with the file named in any error.
fn particle_set(path: &Path, centres: Vec<Vec3>, radii: Vec<f64>) -> Result<ParticleSet, SceneError> {
    ParticleSet::new(centres, radii).map_err(|e| input(path, format!("bad particles: {e}")))
}

/// `particles.csv`: `x,y,z,radius,phase,solved`, scalars, vector components `<name>_x|y|z`.
fn read_particles_csv(path: &Path, time: FieldTime) -> Result<ParticleData<'static>, SceneError> {
    let (header, cols) = read_csv(path)?;
    let col = |name: &str| header.iter().position(|h| h == name).map(|k| &cols[k]);
    let (Some(x), Some(y), Some(z), Some(r)) = (col("x"), col("y"), col("z"), col("radius")) else {
        return Err(input(
            path,
            "no x, y, z and radius columns: not a run's particles.csv",
        ));
    };
    let centres = (0..x.len()).map(|i| Vec3::new(x[i], y[i], z[i])).collect();
    let particles = particle_set(path, centres, r.clone())?;
    let solved = col("solved").map_or(vec![true; x.len()], |s| s.iter().map(|&v| v != 0.0).collect());
    let mut fields = Vec::new();
    let mut vectors = Vec::new();
    for (h, c) in header.iter().zip(&cols) {
        if ["x", "y", "z", "solved"].contains(&h.as_str()) {
            continue;
        }
        if let Some(base) = h.strip_suffix("_x")
            && let (Some(cy), Some(cz)) = (col(&format!("{base}_y")), col(&format!("{base}_z")))
        {
            let m = (0..c.len())
                .map(|i| Vec3::new(c[i], cy[i], cz[i]).norm())
                .collect();
            fields.push((base.to_string(), m));
            vectors.push(base.to_string());
            continue;
        }
        let is_component = ["_y", "_z"].iter().any(|s| {
            h.strip_suffix(s)
                .is_some_and(|b| header.iter().any(|g| *g == format!("{b}_x")))
        });
        if !is_component {
            fields.push((h.clone(), c.clone()));
        }
    }
    Ok(ParticleData {
        particles: Cow::Owned(particles),
        fields,
        vectors,
        solved,
        source: path.display().to_string(),
        time,
    })
}

/// `particles.vtu` (our own format): points, radius, every point array (vectors by magnitude).
fn read_particles_vtu(path: &Path, time: FieldTime) -> Result<ParticleData<'static>, SceneError> {
    let d = read_vtu(path)?;
    let radius = d
        .array("radius")
        .ok_or_else(|| input(path, "no `radius` array: not a run's particles.vtu"))?;
    let particles = particle_set(path, d.points.clone(), radius.values.clone())?;
    let solved = d.array("solved").map_or(vec![true; d.points.len()], |s| {
        s.values.iter().map(|&v| v != 0.0).collect()
    });
    let mut fields = Vec::new();
    let mut vectors = Vec::new();
    for a in &d.arrays {
        if a.name == "solved" {
            continue;
        }
        if a.components > 1 {
            vectors.push(a.name.clone());
        }
        fields.push((a.name.clone(), a.magnitudes()));
    }
    Ok(ParticleData {
        particles: Cow::Owned(particles),
        fields,
        vectors,
        solved,
        source: path.display().to_string(),
        time,
    })
}

/// A file name part: letters, digits, `-` and `_` kept, anything else `-`.
fn file_part(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '-'
            }
        })
        .collect()
}

fn axis_name(a: Axis) -> &'static str {
    ["x", "y", "z"][a.index()]
}

/// Draws every plot `data` allows into `dir` (created if needed): one chart of probes per
/// field (against time; at a single time, one point per probe, and no chart for a single
/// probe), one chart per profile and field, and the slices of `params`, all on one plane.
/// Errors name what is missing: nothing to plot at all, a slice asked for without particle
/// fields, or a field the data does not have (the message lists those it has).
pub fn write_plots(data: &PlotData<'_>, params: &PlotParams, dir: &Path) -> Result<Plots, SceneError> {
    let here = data.folder.as_deref().unwrap_or(Path::new("the run"));
    let slices = slice_fields(data, params, here)?;
    if data.probes.is_empty() && data.profiles.is_empty() && slices.is_empty() {
        return Err(input(
            here,
            "nothing to plot: no probes.csv or profiles.csv (the scene has no outputs.probes or \
             outputs.profiles), and no temperature or potential in particles.csv or particles.vtu \
             (outputs.vtk or outputs.particles_csv)",
        ));
    }
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let mut out = plot_probes(&data.probes, data.transient, dir)?;
    out.files
        .extend(plot_profiles(&data.profiles, data.transient, dir)?);
    if let (Some(p), Some(first)) = (&data.particles, slices.first()) {
        let domain = match &data.domain {
            Some(d) => d.clone(),
            None => Domain::around(&p.particles)?,
        };
        let axis = match params.axis {
            Some(a) => a,
            None => {
                // One plane for every slice, chosen from the run's main field.
                let main = ["temperature", "potential"]
                    .into_iter()
                    .find(|f| p.field(f).is_some())
                    .unwrap_or(first);
                let values = p.field(main).expect("slice fields are checked");
                let b = domain.region.bounds();
                let extent = [0, 1, 2].map(|k| b.max[k] - b.min[k]);
                slice_normal(
                    slab_f_ratios(&p.particles, values, &p.solved),
                    extent,
                    data.etc_axis,
                )
            }
        };
        for field in &slices {
            out.files.push(plot_slice(p, &domain, field, axis, params, dir)?);
        }
    }
    Ok(out)
}

/// The fields to slice: those asked for (each checked), or the defaults present.
fn slice_fields(data: &PlotData<'_>, params: &PlotParams, here: &Path) -> Result<Vec<String>, SceneError> {
    let Some(p) = &data.particles else {
        if params.slices.is_empty() {
            return Ok(Vec::new());
        }
        return Err(input(
            here,
            format!(
                "no particles.csv or particles.vtu to slice `{}`: run with outputs.vtk: true or \
                 outputs.particles_csv: true",
                params.slices.join("`, `")
            ),
        ));
    };
    if params.slices.is_empty() {
        let [t, v, h] = DEFAULT_SLICES;
        let main = [t, v].into_iter().find(|f| p.field(f).is_some());
        let halo = p.field(h).map(|_| h);
        return Ok(main.into_iter().chain(halo).map(String::from).collect());
    }
    for f in &params.slices {
        if p.field(f).is_none() {
            let names: Vec<&str> = p.fields.iter().map(|(n, _)| n.as_str()).collect();
            return Err(input(
                Path::new(&p.source),
                format!("no field `{f}` to slice; its fields: {}", names.join(", ")),
            ));
        }
    }
    Ok(params.slices.clone())
}

/// One chart per probe field: each probe against time. When every probe of the field has a
/// single reading (a steady run, or a field read only at the end, like a transient's
/// potential), there is no time to draw against: the probes' values side by side, one point
/// per probe, and nothing at all for a single probe (one point says no more than the number
/// in `probes.csv`), which [`Plots::skipped`] names.
fn plot_probes(probes: &[ProbeValue], transient: bool, dir: &Path) -> Result<Plots, SceneError> {
    let mut fields: Vec<&str> = Vec::new();
    for p in probes {
        if !fields.contains(&p.field.as_str()) {
            fields.push(&p.field);
        }
    }
    let mut out = Plots::default();
    for field in fields {
        let rows: Vec<&ProbeValue> = probes.iter().filter(|p| p.field == field).collect();
        let mut names: Vec<&str> = Vec::new();
        for r in &rows {
            if !names.contains(&r.name.as_str()) {
                names.push(&r.name);
            }
        }
        let single = names
            .iter()
            .all(|n| rows.iter().filter(|r| r.name == *n).count() == 1);
        // A single reading per probe: when (the same for all, or several).
        let when = if !transient {
            "steady state".to_string()
        } else {
            match rows.first().map(|r| r.t) {
                Some(t) if rows.iter().all(|r| r.t == t) => format!("t = {} s", demcon_plot::fmt_tick(t)),
                _ => "each probe's last time".into(),
            }
        };
        if single && names.len() < 2 {
            out.skipped.push(format!(
                "probes_{}.png: probe {} read {field} once ({when}): one point, no chart",
                file_part(field),
                names.join(", ")
            ));
            continue;
        }
        let series = names
            .iter()
            .enumerate()
            .map(|(k, n)| {
                let mine = rows.iter().filter(|r| r.name == *n);
                let unsolved = rows.iter().any(|r| r.name == *n && !r.solved);
                let label = if unsolved {
                    format!("{n} (reads unsolved particles)")
                } else {
                    n.to_string()
                };
                if single {
                    Series::markers(&label, mine.map(|r| ((k + 1) as f64, r.value)).collect())
                } else {
                    Series::line(&label, mine.map(|r| (r.t, r.value)).collect())
                }
            })
            .collect();
        let name = format!("probes_{}.png", file_part(field));
        draw(
            &Chart {
                title: if single {
                    format!("probes: {field} ({when})")
                } else {
                    format!("probes: {field}")
                },
                x_label: if single { "probe".into() } else { "t (s)".into() },
                y_label: labelled(field),
                x_scale: if single { Scale::Categories } else { Scale::Linear },
                y_scale: Scale::Linear,
                series,
            },
            &dir.join(&name),
        )?;
        out.files.push(PlotFile {
            name,
            what: if single {
                format!("{} probe(s) of {field}, {when}", names.len())
            } else {
                format!("{} probe(s) of {field} against time", names.len())
            },
            range: None,
        });
    }
    Ok(out)
}

/// One chart per profile and field: the value against the distance along the line (mm),
/// one curve per time.
fn plot_profiles(
    profiles: &[ProfileValues],
    transient: bool,
    dir: &Path,
) -> Result<Vec<PlotFile>, SceneError> {
    let mut keys: Vec<(&str, &str)> = Vec::new();
    for p in profiles {
        if !keys.contains(&(p.name.as_str(), p.field.as_str())) {
            keys.push((&p.name, &p.field));
        }
    }
    let mut files = Vec::new();
    for (name, field) in keys {
        let curves: Vec<&ProfileValues> = profiles
            .iter()
            .filter(|p| p.name == name && p.field == field)
            .collect();
        let series = curves
            .iter()
            .map(|c| {
                let label = if transient {
                    format!("t = {} s", demcon_plot::fmt_tick(c.t))
                } else {
                    "steady state".to_string()
                };
                Series::line(&label, c.points.iter().map(|&(d, v)| (d * 1e3, v)).collect())
            })
            .collect();
        let file = format!("profile_{}_{}.png", file_part(name), file_part(field));
        draw(
            &Chart {
                title: format!("profile {name}: {field}"),
                x_label: "distance along the profile (mm)".into(),
                y_label: labelled(field),
                x_scale: Scale::Linear,
                y_scale: Scale::Linear,
                series,
            },
            &dir.join(&file),
        )?;
        files.push(PlotFile {
            name: file,
            what: format!("profile {name} of {field}, {} time(s)", curves.len()),
            range: None,
        });
    }
    Ok(files)
}

/// An F ratio above which a field is taken to vary along an axis (its slab means differ by
/// more than the scatter within the slabs explains; for pure scatter the ratio is about 1, and
/// above 4 with 10 slabs and 300 particles by chance about once in 10⁴).
const SIGNIFICANT_F: f64 = 4.0;

/// How clearly `values` vary along x, y and z over the solved particles: for each axis the
/// F ratio of a one-way analysis of variance with the particles grouped by their centres into
/// slabs across the axis (3 to 10 slabs, about 30 particles each): the spread of the slab
/// means over the scatter within the slabs. Unlike a linear fit it sees a field that rises
/// and falls again (a bump in the middle, a parabola); a field that does not vary scores
/// about 1, and 0 when there is nothing to tell (fewer than two particles per slab, or a
/// constant field).
fn slab_f_ratios(particles: &ParticleSet, values: &[f64], solved: &[bool]) -> [f64; 3] {
    let ok: Vec<usize> = (0..values.len())
        .filter(|&i| solved[i] && values[i].is_finite())
        .collect();
    let n = ok.len();
    let slabs = (n / 30).clamp(3, 10);
    if n < 2 * slabs {
        return [0.0; 3];
    }
    let mean = ok.iter().map(|&i| values[i]).sum::<f64>() / n as f64;
    let total: f64 = ok.iter().map(|&i| (values[i] - mean).powi(2)).sum();
    if total <= 0.0 {
        return [0.0; 3];
    }
    [0, 1, 2].map(|k| {
        let (lo, hi) = ok.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| {
            let x = particles.centres[i][k];
            (a.min(x), b.max(x))
        });
        if hi <= lo {
            return 0.0;
        }
        let mut sum = vec![0.0; slabs];
        let mut count = vec![0usize; slabs];
        for &i in &ok {
            let s = (((particles.centres[i][k] - lo) / (hi - lo) * slabs as f64) as usize).min(slabs - 1);
            sum[s] += values[i];
            count[s] += 1;
        }
        let between: f64 = (0..slabs)
            .filter(|&s| count[s] > 0)
            .map(|s| count[s] as f64 * (sum[s] / count[s] as f64 - mean).powi(2))
            .sum();
        let groups = count.iter().filter(|&&c| c > 0).count();
        if groups < 2 {
            return 0.0;
        }
        let within = (total - between).max(0.0);
        let ratio = (between / (groups - 1) as f64) / (within / (n - groups) as f64);
        if ratio.is_nan() { 0.0 } else { ratio }
    })
}

/// The normal of the default slice plane, from the F ratios of the field along x, y, z
/// ([`slab_f_ratios`]) and the domain's extents (m). The plane contains:
/// 1. the axis the field varies along: the ETC axis when the run has one, else the axis of
///    the largest F ratio above [`SIGNIFICANT_F`], else (a field that varies along none, like
///    the nearly uniform temperature of a cylinder heated evenly by Joule heating) the
///    domain's longest axis (z on a near tie, then y): a cylinder along z is cut through its
///    axis;
/// 2. of the two other axes, the one the field varies along too (the larger F ratio when it
///    varies along both, as a radial field in a cylinder: the plane across the axis shows the
///    rings), else the longer one, else on a near tie (5 %) x or y, so that the normal is z,
///    or x when the plane must contain z.
pub fn slice_normal(f: [f64; 3], extent: [f64; 3], etc_axis: Option<Axis>) -> Axis {
    let varies = |k: usize| f[k] > SIGNIFICANT_F;
    let near = |a: f64, b: f64| (a - b).abs() <= 0.05 * a.abs().max(b.abs());
    // Preference on ties: z, then y, then x.
    let prefer = [2usize, 1, 0];
    let along = match etc_axis {
        Some(a) => a.index(),
        None if (0..3).any(varies) => prefer
            .into_iter()
            .filter(|&k| varies(k))
            .fold(None, |best: Option<usize>, k| match best {
                Some(b) if f[b] >= f[k] => Some(b),
                _ => Some(k),
            })
            .expect("one axis varies"),
        None => {
            let longest = extent.iter().copied().fold(0.0, f64::max);
            prefer
                .into_iter()
                .find(|&k| near(extent[k], longest))
                .unwrap_or(2)
        }
    };
    let [a, b] = match along {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    };
    let normal = match (varies(a), varies(b)) {
        (true, false) => b,
        (false, true) => a,
        (true, true) => {
            if f[a] < f[b] {
                a
            } else {
                b
            }
        }
        (false, false) if near(extent[a], extent[b]) => {
            if b == 2 {
                2
            } else {
                a
            }
        }
        (false, false) => {
            if extent[a] < extent[b] {
                a
            } else {
                b
            }
        }
    };
    [Axis::X, Axis::Y, Axis::Z][normal]
}

/// The slice of `field` on the plane normal to `axis` (at `params.at`, else the middle); the
/// colour bar spans the field's range over the solved particles, cells in the pores and on
/// unsolved particles are grey; the title says the time of a transient's fields.
fn plot_slice(
    p: &ParticleData<'_>,
    domain: &Domain,
    field: &str,
    axis: Axis,
    params: &PlotParams,
    dir: &Path,
) -> Result<PlotFile, SceneError> {
    let values = p.field(field).expect("slice fields are checked");
    let source = Path::new(&p.source);
    let b = domain.region.bounds();
    let a = axis.index();
    let position = params.at.unwrap_or_else(|| {
        // The middle; a box around spheres centred on 0 is off by rounding: snap it to 0.
        let mid = 0.5 * (b.min[a] + b.max[a]);
        if mid.abs() < 1e-4 * (b.max[a] - b.min[a]) {
            0.0
        } else {
            mid
        }
    });
    if !(position >= b.min[a] && position <= b.max[a]) {
        return Err(input(
            source,
            format!(
                "the slice position {} m is outside the particles, [{}, {}] m along {}",
                demcon_plot::fmt_tick(position),
                demcon_plot::fmt_tick(b.min[a]),
                demcon_plot::fmt_tick(b.max[a]),
                axis_name(axis)
            ),
        ));
    }
    let finite: Vec<f64> = values
        .iter()
        .map(|v| if v.is_finite() { *v } else { 0.0 })
        .collect();
    let g = slice_grid(
        &p.particles,
        &finite,
        domain,
        &SliceParams {
            plane: Plane { axis, position },
            resolution: params.resolution,
        },
    )?;
    let cells: Vec<Option<f64>> = g
        .particle
        .iter()
        .map(|q| q.and_then(|q| p.solved[q as usize].then(|| values[q as usize])))
        .collect();
    let (lo, hi) = values
        .iter()
        .zip(&p.solved)
        .filter(|(v, s)| **s && v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (&v, _)| {
            (a.min(v), b.max(v))
        });
    if lo > hi || lo.is_nan() {
        return Err(input(
            source,
            format!("no solved particle has a value of `{field}`"),
        ));
    }
    let what = if p.vectors.iter().any(|v| v == field) {
        format!("|{field}|")
    } else {
        field.to_string()
    };
    let bar_label = match field_unit(field) {
        Some(u) => format!("{what} ({u})"),
        None => what.clone(),
    };
    let mut plane = format!(
        "plane {} = {} mm",
        axis_name(axis),
        demcon_plot::fmt_tick(position * 1e3)
    );
    if let Some(when) = p.time.words() {
        plane = format!("{plane}, {when}");
    }
    let name = format!("slice_{}_{}.png", file_part(field), axis_name(axis));
    let rep = draw_raster(
        &Raster {
            title: format!("{bar_label}, {plane}"),
            nx: g.shape[0],
            ny: g.shape[1],
            cells: &cells,
            origin: g.origin,
            cell: g.cell,
            axes: g.axes.map(axis_name),
            bar_label: bar_label.clone(),
            range: Some((lo, hi)),
        },
        &dir.join(&name),
    )?;
    Ok(PlotFile {
        name,
        what: format!("{bar_label}, {plane}"),
        range: Some(rep.range),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_keep_names_with_commas() {
        let (n, c) = split_row("a,b,temperature,0.5,1e0,1", 4).unwrap();
        assert_eq!(n, "a,b");
        assert_eq!(c, ["temperature", "0.5", "1e0", "1"]);
        assert!(split_row("a,1,2", 4).is_none());
    }

    #[test]
    fn the_last_snapshot_gives_the_particle_fields() {
        let dir = std::env::temp_dir().join(format!("demcon-scene-plots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("summary.json"), "{}").unwrap();
        let p = ParticleSet::new(vec![Vec3::new(0.5, 0.5, 0.5)], vec![0.5]).unwrap();
        for (k, t) in [(2, 20.0), (10, 30.0), (9, 25.0)] {
            let t = [t];
            demcon_post::write_vtu(
                dir.join(format!("particles_{k}.vtu")),
                &p,
                &[demcon_post::Field::scalars("temperature", &t)],
            )
            .unwrap();
        }
        let d = read_run_folder(&dir).unwrap();
        assert_eq!(d.particles.unwrap().field("temperature").unwrap(), [30.0]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn units_of_the_fields() {
        assert_eq!(labelled("temperature"), "temperature (°C)");
        assert_eq!(labelled("halo_flux_magnitude"), "halo_flux_magnitude (W/m²)");
        assert_eq!(labelled("coordination"), "coordination");
        assert_eq!(file_part("y axis/1"), "y-axis-1");
    }

    /// Points in a cylinder along z (radius 1, length 5) or a unit cube, from a fixed
    /// generator; and a noise of the given size per point.
    fn cloud(cylinder: bool, n: usize) -> (ParticleSet, Vec<f64>) {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut centres = Vec::new();
        let mut noise = Vec::new();
        while centres.len() < n {
            let c = if cylinder {
                Vec3::new(2.0 * next() - 1.0, 2.0 * next() - 1.0, 5.0 * next())
            } else {
                Vec3::new(next(), next(), next())
            };
            if !cylinder || c.x * c.x + c.y * c.y <= 1.0 {
                centres.push(c);
                noise.push(next() - 0.5);
            }
        }
        (ParticleSet::new(centres, vec![0.05; n]).unwrap(), noise)
    }

    fn normal_of(p: &ParticleSet, v: &[f64], extent: [f64; 3]) -> Axis {
        slice_normal(slab_f_ratios(p, v, &vec![true; v.len()]), extent, None)
    }

    /// The joule-transient case: a cylinder along z heated evenly, its temperature a scatter
    /// of a millikelvin, was cut across its axis (a uniform disc); it is cut through its axis,
    /// as is a field that varies along the axis. A radial field is cut across the axis.
    #[test]
    fn a_cylinder_is_cut_through_its_axis_unless_its_field_is_radial() {
        let (p, noise) = cloud(true, 2000);
        let extent = [2.0, 2.0, 5.0];
        let scatter: Vec<f64> = noise.iter().map(|e| 262.94 + 1e-3 * e).collect();
        assert_eq!(normal_of(&p, &scatter, extent), Axis::X);
        let along_z: Vec<f64> = p.centres.iter().zip(&noise).map(|(c, e)| c.z + 0.3 * e).collect();
        assert_eq!(normal_of(&p, &along_z, extent), Axis::X);
        let f = slab_f_ratios(&p, &along_z, &vec![true; 2000]);
        assert!(
            f[2] > 100.0 && f[0] < SIGNIFICANT_F && f[1] < SIGNIFICANT_F,
            "{f:?}"
        );
        // A field along the axis that rises and falls again (ends held cold): a linear fit
        // sees nothing, the slabs do.
        let bump: Vec<f64> = p.centres.iter().map(|c| c.z * (5.0 - c.z)).collect();
        assert_eq!(normal_of(&p, &bump, extent), Axis::X);
        let radial: Vec<f64> = p
            .centres
            .iter()
            .zip(&noise)
            .map(|(c, e)| c.x * c.x + c.y * c.y + 0.01 * e)
            .collect();
        assert_eq!(normal_of(&p, &radial, extent), Axis::Z);
    }

    #[test]
    fn a_box_is_cut_along_its_gradient() {
        let (p, noise) = cloud(false, 1000);
        let cube = [1.0; 3];
        for (k, normal) in [(0, Axis::Z), (1, Axis::Z), (2, Axis::X)] {
            let v: Vec<f64> = p
                .centres
                .iter()
                .zip(&noise)
                .map(|(c, e)| c[k] + 0.1 * e)
                .collect();
            assert_eq!(normal_of(&p, &v, cube), normal, "gradient along {k}");
        }
        // Nothing varies: the plane through the longest side (z on a tie, normal x).
        assert_eq!(normal_of(&p, &noise, cube), Axis::X);
        assert_eq!(normal_of(&p, &vec![1.0; 1000], cube), Axis::X);
        assert_eq!(normal_of(&p, &noise, [10.0, 1.0, 1.0]), Axis::Z);
        assert_eq!(normal_of(&p, &noise, [1.0, 1.0, 0.2]), Axis::Z);
        assert_eq!(normal_of(&p, &noise, [1.0, 0.2, 1.0]), Axis::Y);
        // The ETC axis wins over the field.
        let f = [1.0, 500.0, 1.0];
        assert_eq!(slice_normal(f, cube, Some(Axis::Z)), Axis::X);
        assert_eq!(slice_normal(f, cube, None), Axis::Z);
        // Two axes vary: the plane holds both.
        assert_eq!(slice_normal([90.0, 1.0, 40.0], cube, None), Axis::Y);
    }

    #[test]
    fn field_times_read() {
        assert_eq!(FieldTime::Steady.words(), None);
        assert_eq!(FieldTime::At(260.0).words().unwrap(), "t = 260 s");
        assert_eq!(FieldTime::At(0.2).words().unwrap(), "t = 0.2 s");
    }

    #[test]
    fn a_single_probe_read_once_draws_nothing() {
        let dir = std::env::temp_dir().join(format!("demcon-scene-probes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let reading = |name: &str, t: f64, value: f64| ProbeValue {
            name: name.into(),
            field: "potential".into(),
            t,
            value,
            solved: true,
        };
        // A transient's potential read at the end only: one point.
        let one = [reading("centre", 260.0, 0.005)];
        let out = plot_probes(&one, true, &dir).unwrap();
        assert!(out.files.is_empty(), "{out:?}");
        assert!(
            out.skipped[0].contains("centre") && out.skipped[0].contains("t = 260 s"),
            "{out:?}"
        );
        assert!(!dir.join("probes_potential.png").exists());
        // Two probes of a steady run: their values side by side, no time axis.
        let two = [reading("a", 0.0, 0.002), reading("b", 0.0, 0.008)];
        let out = plot_probes(&two, false, &dir).unwrap();
        assert_eq!(out.files[0].what, "2 probe(s) of potential, steady state");
        // Against time when there is time.
        let series = [reading("a", 1.0, 0.002), reading("a", 2.0, 0.004)];
        let out = plot_probes(&series, true, &dir).unwrap();
        assert_eq!(out.files[0].what, "1 probe(s) of potential against time");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
