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
}

/// What to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotParams {
    /// Fields to slice; empty: `temperature` (or `potential`), and `halo_flux` when present.
    pub slices: Vec<String>,
    /// The slice plane's normal; `None`: z, or x when the field changes most along z (the ETC
    /// axis if the run has one, else the steepest axis of the field's least-squares fit), so
    /// that the plane contains the gradient.
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
        }),
        domain: Some(r.domain.clone()),
        etc_axis: outputs.etc_axis.map(|a| match a {
            AxisConfig::X => Axis::X,
            AxisConfig::Y => Axis::Y,
            AxisConfig::Z => Axis::Z,
        }),
        folder: None,
    }
}

/// Writes the default plots of a run in memory into `dir` (created if needed).
pub fn write_run_plots(
    r: &RunResult,
    outputs: &OutputsConfig,
    dir: &Path,
) -> Result<Vec<PlotFile>, SceneError> {
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
    let (csv, vtu) = (dir.join("particles.csv"), dir.join("particles.vtu"));
    let particles = if csv.is_file() {
        Some(read_particles_csv(&csv)?)
    } else if vtu.is_file() {
        Some(read_particles_vtu(&vtu)?)
    } else if let Some(last) = last_snapshot(dir)? {
        Some(read_particles_vtu(&last)?)
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
    })
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
fn read_particles_csv(path: &Path) -> Result<ParticleData<'static>, SceneError> {
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
    })
}

/// `particles.vtu` (our own format): points, radius, every point array (vectors by magnitude).
fn read_particles_vtu(path: &Path) -> Result<ParticleData<'static>, SceneError> {
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
/// field, one chart per profile and field, and the slices of `params`. Errors name what is
/// missing: nothing to plot at all, a slice asked for without particle fields, or a field the
/// data does not have (the message lists those it has).
pub fn write_plots(
    data: &PlotData<'_>,
    params: &PlotParams,
    dir: &Path,
) -> Result<Vec<PlotFile>, SceneError> {
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
    let mut files = plot_probes(&data.probes, dir)?;
    files.extend(plot_profiles(&data.profiles, dir)?);
    if let Some(p) = &data.particles {
        for field in &slices {
            files.push(plot_slice(data, p, field, params, dir)?);
        }
    }
    Ok(files)
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

/// One chart per probe field: each probe against time (a transient), or each probe's value
/// as a point (a single time: the steady state).
fn plot_probes(probes: &[ProbeValue], dir: &Path) -> Result<Vec<PlotFile>, SceneError> {
    let mut fields: Vec<&str> = Vec::new();
    for p in probes {
        if !fields.contains(&p.field.as_str()) {
            fields.push(&p.field);
        }
    }
    let mut files = Vec::new();
    for field in fields {
        let rows: Vec<&ProbeValue> = probes.iter().filter(|p| p.field == field).collect();
        let mut names: Vec<&str> = Vec::new();
        for r in &rows {
            if !names.contains(&r.name.as_str()) {
                names.push(&r.name);
            }
        }
        let steady = names
            .iter()
            .all(|n| rows.iter().filter(|r| r.name == *n).count() == 1);
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
                if steady {
                    Series::markers(&label, mine.map(|r| ((k + 1) as f64, r.value)).collect())
                } else {
                    Series::line(&label, mine.map(|r| (r.t, r.value)).collect())
                }
            })
            .collect();
        let name = format!("probes_{}.png", file_part(field));
        draw(
            &Chart {
                title: format!("probes: {}{}", field, if steady { " (final state)" } else { "" }),
                x_label: if steady { "probe".into() } else { "t (s)".into() },
                y_label: labelled(field),
                x_scale: if steady { Scale::Categories } else { Scale::Linear },
                y_scale: Scale::Linear,
                series,
            },
            &dir.join(&name),
        )?;
        files.push(PlotFile {
            name,
            what: format!("{} probe(s) of {field}", names.len()),
            range: None,
        });
    }
    Ok(files)
}

/// One chart per profile and field: the value against the distance along the line (mm),
/// one curve per time.
fn plot_profiles(profiles: &[ProfileValues], dir: &Path) -> Result<Vec<PlotFile>, SceneError> {
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
                let label = if curves.len() == 1 {
                    "final state".to_string()
                } else {
                    format!("t = {} s", demcon_plot::fmt_tick(c.t))
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

/// The axis along which `values` change most over the solved particles: the least-squares
/// slope along each axis times the particles' extent along it (z on a tie or a constant field).
fn steepest_axis(particles: &ParticleSet, values: &[f64], solved: &[bool]) -> Axis {
    let ok: Vec<usize> = (0..values.len())
        .filter(|&i| solved[i] && values[i].is_finite())
        .collect();
    let n = ok.len().max(1) as f64;
    let mean_v = ok.iter().map(|&i| values[i]).sum::<f64>() / n;
    let change = |k: usize| {
        let x: Vec<f64> = ok.iter().map(|&i| particles.centres[i][k]).collect();
        let mean_x = x.iter().sum::<f64>() / n;
        let (mut sxv, mut sxx) = (0.0, 0.0);
        for (xi, &i) in x.iter().zip(&ok) {
            sxv += (xi - mean_x) * (values[i] - mean_v);
            sxx += (xi - mean_x) * (xi - mean_x);
        }
        let extent = x.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
            - x.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        if sxx > 0.0 {
            (sxv / sxx).abs() * extent
        } else {
            0.0
        }
    };
    let c = [change(0), change(1), change(2)];
    if c[0] > c[1] && c[0] > c[2] {
        Axis::X
    } else if c[1] > c[2] && c[1] >= c[0] {
        Axis::Y
    } else {
        Axis::Z
    }
}

/// The slice of `field` on the plane of `params`; the colour bar spans the field's range
/// over the solved particles, cells in the pores and on unsolved particles are grey.
fn plot_slice(
    data: &PlotData<'_>,
    p: &ParticleData<'_>,
    field: &str,
    params: &PlotParams,
    dir: &Path,
) -> Result<PlotFile, SceneError> {
    let values = p.field(field).expect("slice fields are checked");
    let source = Path::new(&p.source);
    let domain = match &data.domain {
        Some(d) => d.clone(),
        None => Domain::around(&p.particles)?,
    };
    // The default plane contains the direction along which the field changes most.
    let along = data
        .etc_axis
        .unwrap_or_else(|| steepest_axis(&p.particles, values, &p.solved));
    let axis = params
        .axis
        .unwrap_or(if along == Axis::Z { Axis::X } else { Axis::Z });
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
        &domain,
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
    let plane = format!(
        "plane {} = {} mm",
        axis_name(axis),
        demcon_plot::fmt_tick(position * 1e3)
    );
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

    #[test]
    fn the_steepest_axis_follows_the_field() {
        let centres: Vec<Vec3> = (0..27)
            .map(|i| Vec3::new((i % 3) as f64, ((i / 3) % 3) as f64, (i / 9) as f64))
            .collect();
        let p = ParticleSet::new(centres.clone(), vec![0.4; 27]).unwrap();
        let all = vec![true; 27];
        for (k, axis) in [(0, Axis::X), (1, Axis::Y), (2, Axis::Z)] {
            let v: Vec<f64> = centres
                .iter()
                .map(|c| 3.0 * c[k] + 0.1 * c[(k + 1) % 3])
                .collect();
            assert_eq!(steepest_axis(&p, &v, &all), axis);
        }
        assert_eq!(steepest_axis(&p, &[1.0; 27], &all), Axis::Z);
    }
}
