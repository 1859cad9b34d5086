//! Scene builders and comparison helpers shared by every case, and the one gateway to
//! `demcon-scene` and `demcon-model`: besides each case's `use demcon_scene::config::*`, the
//! cases name those crates' items only through the re-exports and adapters below, so a move
//! of those items is one edit here.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use demcon_scene::config::*;
use demcon_scene::{Scene, build_model, run_on_model};

pub use demcon_model::{
    CalibrationBc, CutCause, CutContact, FixedSet, ThermalBcs, calibrate_ct, calibrate_ct_with,
    place_inclusions,
};
pub use demcon_scene::convert::region as scene_region;
pub use demcon_scene::{Model, RunResult, SceneConfig, SceneError, write_outputs};

/// A surface model read with a phase rule: the models the interface cases run side by side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RuleVariant {
    /// Transmission-surface model.
    pub surface: Surface,
    /// Where the interface lies in a cut particle.
    pub rule: PhaseRuleConfig,
}

impl RuleVariant {
    /// The model `surface` with the phase rule `rule`.
    pub const fn new(surface: Surface, rule: PhaseRuleConfig) -> Self {
        Self { surface, rule }
    }

    /// Its id: the surface's, `sep`, the rule's (`centre`, `laminate`, `segment`, `conforming`).
    pub fn id(self, sep: &str) -> String {
        let rule = match self.rule {
            PhaseRuleConfig::Centre => "centre",
            PhaseRuleConfig::Laminate => "laminate",
            PhaseRuleConfig::Segment => "segment",
            PhaseRuleConfig::Conforming => "conforming",
        };
        format!("{}{sep}{rule}", self.surface.id())
    }
}

/// The three transmission-surface models every case runs side by side (DESIGN.md §1, §3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Surface {
    /// S = C_t π R_m², C_t from our own calibration on the same packing (Haddad 2021).
    Calibrated,
    /// S = √(α(n_p) R_p² α(n_q) R_q²) (Terreros 2013, Hubert 2017).
    Terreros,
    /// The facets of the Laguerre (power) cells, clipped by the container and the carving
    /// region (ours): exact for a linear field.
    Laguerre,
}

impl Surface {
    /// The three models, the headline (Laguerre) first. Laguerre is the headline because of
    /// its consistency property (a linear field solves its network exactly: no calibration, no
    /// bias in a homogeneous body, walls are cell faces), chosen so before any of its numbers
    /// were seen (issue 10 §4).
    pub const ALL: [Surface; 3] = [Surface::Laguerre, Surface::Terreros, Surface::Calibrated];

    /// Short id used in metric names: `laguerre`, `terreros`, `calibrated`.
    pub fn id(self) -> &'static str {
        match self {
            Surface::Calibrated => "calibrated",
            Surface::Terreros => "terreros",
            Surface::Laguerre => "laguerre",
        }
    }

    /// Name for tables and legends.
    pub fn label(self) -> &'static str {
        match self {
            Surface::Calibrated => "calibrated C_t",
            Surface::Terreros => "Terreros α",
            Surface::Laguerre => "Laguerre",
        }
    }

    /// The scene's surface: the calibrated model at `c_t` when given (else `Auto`: the scene
    /// calibrates on its own packing), Terreros α, or the Laguerre cells.
    pub fn config(self, c_t: Option<f64>) -> SurfaceConfig {
        match self {
            Surface::Calibrated => SurfaceConfig::Calibrated {
                c_t: c_t.map_or(CtConfig::Auto, CtConfig::Value),
            },
            Surface::Terreros => SurfaceConfig::TerrerosAlpha,
            Surface::Laguerre => SurfaceConfig::Laguerre,
        }
    }

    /// Whether the model needs the Laguerre cells as its network (else the contacts).
    pub fn needs_cells(self) -> bool {
        self == Surface::Laguerre
    }
}

/// `cfg` with the surface model `s` for every physics it runs: the thermal `surface` and
/// `electric.surface` alike (a scene refuses a Laguerre/contact mix).
pub fn with_surface_model(cfg: &SceneConfig, s: Surface, c_t: Option<f64>) -> SceneConfig {
    let mut c = cfg.clone();
    c.surface = s.config(c_t);
    if let Some(e) = c.electric.as_mut() {
        e.surface = Some(s.config(c_t));
    }
    c
}

/// The model `cfg` builds on the particles of `model`, without packing again: `cfg`'s
/// carving, phases and network — the contacts, or the Laguerre cells when `cfg` asks for
/// them. The way to put the Laguerre network on a packing first built with contacts (same
/// particles, so the models compare on one microstructure). Particles already carved by the
/// same region are all kept by carving them again.
pub fn rebuild_on(cfg: &SceneConfig, model: &Model) -> anyhow::Result<Model> {
    let params = Scene::from_config(cfg.clone(), PathBuf::new())?
        .problem()
        .model
        .clone();
    // The phases come from `cfg` alone: every particle starts from phase 0.
    let mut particles = model.particles.clone();
    particles.phases.iter_mut().for_each(|p| *p = 0);
    let packed = demcon_model::Packed {
        particles,
        container: model.container,
        report: model.report.packing.clone(),
        imported_from: model.report.imported_from.clone(),
        pack_s: model.report.pack_s,
    };
    Ok(demcon_model::build_model(packed, &params)?)
}

/// The Laguerre model of the packing of `model` for the scene `cfg` (its surface is set to
/// Laguerre here): [`rebuild_on`].
pub fn laguerre_model(cfg: &SceneConfig, model: &Model) -> anyhow::Result<Model> {
    let mut cfg = with_surface_model(cfg, Surface::Laguerre, None);
    // Re-phased under each rule by the callers: built by centre unless the scene says.
    cfg.phase_rule.get_or_insert(PhaseRuleConfig::Centre);
    rebuild_on(&cfg, model)
}

/// Σ area (m²) of the Laguerre cells' facets on `face`: the section the network actually has
/// there (the container's, up to the tangent planes that follow a curved wall); `None` for a
/// model without cells.
pub fn wall_facet_area(model: &Model, face: FaceConfig) -> Option<f64> {
    let cells = model.graph.cells.as_deref()?;
    let face = demcon_scene::convert::face(face);
    Some(
        cells
            .on_wall(demcon_graph::CellWall::Face(face))
            .map(|f| f.area)
            .sum(),
    )
}

/// The closure defect of the Laguerre cells along `axis` (0, 1, 2 for x, y, z): the largest
/// over the cells of |Σ_facets S n · e_axis| / Σ_facets S, with the areas the NETWORK uses
/// (shared facets: the graph's area; wall facets: theirs). A linear field along the axis
/// solves the network exactly iff this is 0 (up to round-off) in every cell; `None` for a
/// model without cells. A wall facet is read as its area times its (summed) unit normal, exact
/// when its planes share their component along the axis: flat faces, and the tangent planes of
/// a cylinder's mantle along its axis — not the planes that follow a carving region's edges.
pub fn closure_defect(model: &Model, axis: usize) -> Option<f64> {
    let cells = model.graph.cells.as_deref()?;
    let n = model.particles.len();
    let (mut flux, mut total) = (vec![0.0; n], vec![0.0; n]);
    for (k, &[p, q]) in model.graph.pairs.iter().enumerate() {
        let s = cells.facet_area[k];
        let e = model.graph.geometry[k].normal[axis];
        flux[p as usize] += s * e;
        flux[q as usize] -= s * e;
        total[p as usize] += s;
        total[q as usize] += s;
    }
    for w in &cells.walls {
        flux[w.particle as usize] += w.area * w.normal[axis];
        total[w.particle as usize] += w.area;
    }
    Some(
        flux.iter()
            .zip(&total)
            .map(|(f, t)| f.abs() / t)
            .fold(0.0, f64::max),
    )
}

/// Wall time (s) of building a model's network: contact detection, or the tessellation.
pub fn network_s(model: &Model) -> f64 {
    model.report.contacts_s + model.report.network_s
}

/// The mean and the largest value of a quantity over independent packings (DESIGN.md §3: a
/// headline figure is both, never one seed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    /// Mean over the packings.
    pub mean: f64,
    /// Largest value.
    pub max: f64,
    /// Number of packings.
    pub count: usize,
}

impl Spread {
    /// Mean and max of `values`: NaN for none, and NaN when any value is NaN (a failed
    /// packing must not vanish from a headline figure).
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let (mut sum, mut max, mut count, mut nan) = (0.0, f64::NEG_INFINITY, 0, false);
        for v in values {
            nan |= v.is_nan();
            sum += v;
            max = max.max(v);
            count += 1;
        }
        if count == 0 || nan {
            return Self {
                mean: f64::NAN,
                max: f64::NAN,
                count,
            };
        }
        Self {
            mean: sum / count as f64,
            max,
            count,
        }
    }

    /// `{"mean": …, "max": …, "packings": …}` for the JSON metrics.
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({ "mean": self.mean, "max": self.max, "packings": self.count })
    }

    /// `mean / max` as percentages, for tables.
    pub fn percent(&self) -> String {
        format!("{:.3} / {:.3} %", 100.0 * self.mean, 100.0 * self.max)
    }
}

/// [`demcon_model::set_region_phases`] with the scene's phase rule.
pub fn set_region_phases(
    model: &mut Model,
    regions: &[(demcon_core::Region, u16)],
    rule: PhaseRuleConfig,
) -> anyhow::Result<()> {
    Ok(demcon_model::set_region_phases(
        model,
        regions,
        demcon_scene::convert::phase_rule(rule),
    )?)
}

/// [`demcon_model::electric_conductances`] (S) with the scene's surface and interface rule.
pub fn electric_conductances(
    model: &Model,
    surface: &SurfaceConfig,
    interface: InterfaceConfig,
    temperatures: Option<&[f64]>,
) -> Result<Vec<f64>, demcon_model::ModelError> {
    use demcon_scene::convert;
    demcon_model::electric_conductances(
        model,
        &convert::surface(surface),
        convert::interface(interface),
        temperatures,
    )
}

/// Haddad 2021 Table 1 "steel" (ρ = 7800 kg/m³, λ = 33 W/(m·K), c = 0.9 J/(kg·K): the
/// paper's unphysically small c sets its 0.05–0.2 s time scale).
pub fn table1_steel() -> MaterialConfig {
    material("steel", 33.0, 7800.0, 0.9)
}

/// A thermal-only material.
pub fn material(name: &str, conductivity: f64, density: f64, specific_heat: f64) -> MaterialConfig {
    MaterialConfig {
        name: name.into(),
        conductivity,
        conductivity_temp_coeff: 0.0,
        conductivity_ref_temp: 20.0,
        conductivity_tensor: None,
        tensor_in_shape_frame: false,
        conductivity_table: None,
        density,
        specific_heat,
        resistivity: None,
        resistivity_temp_coeff: 0.0,
        resistivity_ref_temp: 20.0,
    }
}

/// Overall volume fraction of a walled packing of `n` particles whose bulk (away from the
/// walls) is at the papers' φ ≈ 0.64: the layer next to a hard wall is less dense, by about
/// 0.5 n^(-1/3) overall on our LS packings (measured: overall 0.625 ↔ bulk 0.6435 at
/// n = 2·10⁴). Asking 0.64 overall of a small walled packing would mean jamming it.
pub fn walled_phi(n: usize) -> f64 {
    0.64 - 0.5 * (n as f64).powf(-1.0 / 3.0)
}

/// A Gaussian-0.3 LS packing recipe of `count` particles in `container` with its bulk at
/// φ ≈ 0.64 (see [`walled_phi`]; a periodic box gets 0.64 exactly).
pub fn packing(container: ContainerConfig, count: usize) -> PackingConfig {
    let phi = match container {
        ContainerConfig::Periodic { .. } => 0.64,
        _ => walled_phi(count),
    };
    PackingConfig::Generate {
        container,
        count,
        phi,
        radius_cov: 0.3,
        radius_range: None,
        allow_short: false,
    }
}

/// A Gaussian-0.3 LS packing recipe of `count` particles in a periodic cube of edge `edge`
/// (m) at φ = 0.6: dense enough for every surface model, far enough from jamming to pack fast
/// (the Laguerre network needs no particular density).
pub fn periodic_packing(edge: f64, count: usize) -> PackingConfig {
    PackingConfig::Generate {
        container: ContainerConfig::Periodic {
            size: (edge, edge, edge),
        },
        count,
        phi: 0.6,
        radius_cov: 0.3,
        radius_range: None,
        allow_short: false,
    }
}

/// Fixed temperature on a face.
pub fn fixed(face: FaceConfig, value: f64) -> ThermalBcConfig {
    ThermalBcConfig::FixedTemperature {
        select: SelectorConfig::Face(face),
        value,
    }
}

/// Writes a simple-cubic lattice of `dims` touching spheres of diameter `d` (m), in a box of
/// the same size, to `dir/<name>-lattice-<nx>x<ny>x<nz>.xyzr` and returns the path.
pub fn write_cubic_lattice(
    dir: &std::path::Path,
    name: &str,
    dims: [usize; 3],
    d: f64,
) -> anyhow::Result<PathBuf> {
    let [nx, ny, nz] = dims;
    let mut centres = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                centres.push(demcon_core::Vec3::new(
                    (i as f64 + 0.5) * d,
                    (j as f64 + 0.5) * d,
                    (k as f64 + 0.5) * d,
                ));
            }
        }
    }
    let n = centres.len();
    let p = demcon_core::ParticleSet::new(centres, vec![0.5 * d; n])?;
    let c = demcon_core::Container::Box {
        size: [nx as f64 * d, ny as f64 * d, nz as f64 * d],
    };
    std::fs::create_dir_all(dir)?;
    let path = dir.join(format!("{name}-lattice-{nx}x{ny}x{nz}.xyzr"));
    demcon_packing::write_xyzr(&path, &p, &c)?;
    Ok(path)
}

/// A scene skeleton: packing, Z = 7.5 contacts, calibrated surfaces (C_t from our own
/// calibration), materials, thermal physics, no files.
pub fn thermal_scene(
    name: &str,
    seed: u64,
    packing: PackingConfig,
    materials: Vec<MaterialConfig>,
    thermal: ThermalConfig,
) -> SceneConfig {
    SceneConfig {
        name: name.into(),
        seed,
        packing,
        carve: None,
        carve_rule: CarveRuleConfig::WholeSphere,
        contacts: ContactsConfig {
            coordination: Some(7.5),
            tolerance: None,
        },
        surface: SurfaceConfig::Calibrated { c_t: CtConfig::Auto },
        materials,
        phases: Vec::new(),
        phase_rule: Some(PhaseRuleConfig::Centre),
        interface: InterfaceConfig::Harmonic,
        interfaces: Vec::new(),
        grain_boundaries: Vec::new(),
        cracks: Vec::new(),
        damage: Vec::new(),
        cut_contacts: None,
        floating: FloatingConfig::Exclude,
        linear_solver: Default::default(),
        thermal: Some(thermal),
        electric: None,
        outputs: OutputsConfig {
            vtk: false,
            ..OutputsConfig::default()
        },
    }
}

/// A generated packing: particles, container, the packer's report and its cost (s).
type CachedPacking = (
    demcon_core::ParticleSet,
    demcon_core::Container,
    Option<demcon_packing::PackingReport>,
    f64,
);

/// Cached packings by key, with how often each was reused.
type PackingCache = HashMap<String, (Arc<CachedPacking>, usize)>;

/// The packings generated so far in this process, by packing section and seed. The cases
/// share many (the same cube, N and seeds), and a packing is a pure function of its section
/// and seed (same seed ⇒ the same file, for any thread count: the packer's determinism
/// tests), so a case given a cached packing computes exactly what it would have computed
/// after packing again.
static PACKINGS: std::sync::OnceLock<std::sync::Mutex<PackingCache>> = std::sync::OnceLock::new();

/// Packings made and reused by [`model_of`] in this process, and the packing time the reuse
/// saved (s): (made, reused, saved_s).
pub fn packing_cache_stats() -> (usize, usize, f64) {
    PACKINGS
        .get()
        .and_then(|c| c.lock().ok())
        .map_or((0, 0, 0.0), |c| {
            let reused: usize = c.values().map(|e| e.1).sum();
            let saved = c.values().map(|e| e.1 as f64 * e.0.3).sum();
            (c.len(), reused, saved)
        })
}

/// The packing of `cfg`'s section and seed, generated once per process; whether it was
/// reused.
fn cached_packing(cfg: &SceneConfig) -> anyhow::Result<(Arc<CachedPacking>, bool)> {
    let key = packing_key(cfg);
    let cache = PACKINGS.get_or_init(Default::default);
    if let Some(hit) = cache
        .lock()
        .map_err(|_| anyhow::anyhow!("packing cache poisoned"))?
        .get_mut(&key)
    {
        hit.1 += 1;
        return Ok((hit.0.clone(), true));
    }
    let t0 = std::time::Instant::now();
    let (particles, container, report, _) =
        demcon_scene::build::particles_of_section(&cfg.packing, cfg.seed, std::path::Path::new(""), None)?;
    let entry = Arc::new((particles, container, report, t0.elapsed().as_secs_f64()));
    cache
        .lock()
        .map_err(|_| anyhow::anyhow!("packing cache poisoned"))?
        .insert(key, (entry.clone(), 0));
    Ok((entry, false))
}

/// Makes the generated packings of `cfgs` that this process has not made yet, as many at a
/// time as rayon has threads, largest first, so that the case's later [`model_of`] calls
/// find them made. For cases that need several packings: the packer runs on one thread, so
/// one at a time leaves the other cores idle. A packing is a pure function of its section
/// and seed, so the packings, and everything computed from them, are those made one by one;
/// each one's `pack_s` is its own wall time, measured beside the others (sharing the memory
/// bandwidth). Of several errors, the one of the largest packing (then the earliest in
/// `cfgs`) is returned.
pub fn prepack(cfgs: &[SceneConfig]) -> anyhow::Result<()> {
    let mut todo: Vec<(usize, SceneConfig)> = Vec::new();
    let mut keys = std::collections::HashSet::new();
    for cfg in cfgs {
        let PackingConfig::Generate { count, .. } = cfg.packing else {
            continue;
        };
        if cfg.cut_contacts.is_some() {
            continue;
        }
        // The key `model_of` will look up: of the validated scene.
        let scene = Scene::from_config(cfg.clone(), PathBuf::new())?;
        if keys.insert(packing_key(scene.config())) && !is_cached(scene.config()) {
            todo.push((count, scene.config().clone()));
        }
    }
    todo.sort_by_key(|(count, _)| std::cmp::Reverse(*count));
    let Some(largest) = todo.first().map(|(count, _)| *count) else {
        return Ok(());
    };
    let threads = rayon::current_num_threads().min(todo.len());
    // A `--full` case can pack for many minutes before its next line: say so.
    eprintln!(
        "   making {} packing(s) first, {threads} at a time (the largest of {largest} particles)",
        todo.len()
    );
    let started = std::time::Instant::now();
    let result = pack_all(&todo, threads);
    eprintln!("   packings made in {:.1} s", started.elapsed().as_secs_f64());
    result
}

/// Makes the packings of `todo` (validated scenes, each with its particle count) on `threads`
/// threads, each taking the next one in the list; the first error in the list's order.
fn pack_all(todo: &[(usize, SceneConfig)], threads: usize) -> anyhow::Result<()> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let errors = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some((_, cfg)) = todo.get(k) else { break };
                    if let Err(e) = cached_packing(cfg) {
                        errors.lock().unwrap_or_else(|p| p.into_inner()).push((k, e));
                    }
                }
            });
        }
    });
    let mut errors = errors.into_inner().unwrap_or_else(|p| p.into_inner());
    errors.sort_by_key(|(k, _)| *k);
    errors.into_iter().next().map_or(Ok(()), |(_, e)| Err(e))
}

/// The packing cache's key of a (validated) scene: its packing section and seed.
fn packing_key(cfg: &SceneConfig) -> String {
    format!("{:?}|{}", cfg.packing, cfg.seed)
}

/// Whether the packing of `cfg` has been made in this process.
fn is_cached(cfg: &SceneConfig) -> bool {
    PACKINGS
        .get()
        .and_then(|c| c.lock().ok())
        .is_some_and(|c| c.contains_key(&packing_key(cfg)))
}

/// Validates a scene built in code and builds its model. A generated packing is made once
/// per process and reused by every later scene with the same packing section and seed
/// ([`PACKINGS`]); `report.pack_s` keeps what it cost to make.
pub fn model_of(cfg: &SceneConfig) -> anyhow::Result<Model> {
    Ok(model_of_timed(cfg)?.0)
}

/// [`model_of`] and what the model costs to build from scratch (s): the wall time of this
/// call, plus the packing's own cost when the packing was reused.
pub fn model_of_timed(cfg: &SceneConfig) -> anyhow::Result<(Model, f64)> {
    let t0 = std::time::Instant::now();
    let scene = Scene::from_config(cfg.clone(), PathBuf::new())?;
    if !matches!(cfg.packing, PackingConfig::Generate { .. }) || cfg.cut_contacts.is_some() {
        let model = build_model(&scene, None)?;
        return Ok((model, t0.elapsed().as_secs_f64()));
    }
    let (packing, reused) = cached_packing(scene.config())?;
    let params = scene.problem().model.clone();
    let packed = demcon_model::Packed {
        particles: packing.0.clone(),
        container: packing.1,
        report: packing.2.clone(),
        imported_from: None,
        pack_s: packing.3,
    };
    let model = demcon_model::build_model(packed, &params)?;
    let reused_s = if reused { packing.3 } else { 0.0 };
    Ok((model, t0.elapsed().as_secs_f64() + reused_s))
}

/// Re-phases a built model with the `Spheres` phases and the phase rule of `cfg` (same
/// packing and network; for comparing phase rules on one network).
pub fn set_phases_like(model: &mut Model, cfg: &SceneConfig) -> anyhow::Result<()> {
    let mut regions = Vec::new();
    for (i, ph) in cfg.phases.iter().enumerate() {
        let PhaseConfig::Spheres {
            material,
            radius,
            centres,
        } = ph
        else {
            anyhow::bail!("phases[{i}]: only Spheres phases can be re-applied");
        };
        let phase = cfg
            .materials
            .iter()
            .position(|m| &m.name == material)
            .ok_or_else(|| anyhow::anyhow!("phases[{i}]: no material {material}"))?;
        let centres: Vec<demcon_core::Vec3> = centres
            .iter()
            .map(|&(x, y, z)| demcon_core::Vec3::new(x, y, z))
            .collect();
        let reach = model.particles.radii.iter().copied().fold(0.0, f64::max);
        let region = demcon_model::spheres_region(
            &model.container,
            *radius,
            &centres,
            reach,
            &format!("phases[{i}]"),
        )?;
        regions.push((region, phase as u16));
    }
    set_region_phases(model, &regions, demcon_scene::convert::phase_rule_of(cfg))
}

/// Sets the thermal conductance h (W/(m²·K); ∞ makes them perfect) of every listed interface
/// of a built model: a sweep over h on one network, without rebuilding it.
pub fn set_interface_conductance(model: &mut Model, h: f64) {
    for i in &mut model.defects.spec.interfaces {
        i.conductance = h;
    }
}

/// `model` with the interfaces, cracks and damage regions of `cfg` applied to its graph
/// (no packing or tessellation again; `model` must have none): [`demcon_model::with_defects`].
pub fn with_scene_defects(model: &Model, cfg: &SceneConfig) -> anyhow::Result<Model> {
    with_scene_defects_rule(model, cfg, false)
}

/// [`with_scene_defects`] with open cracks cutting whole Laguerre facets (the segment rule)
/// when `whole_facets`, else by the covered part of each facet (the default).
pub fn with_scene_defects_rule(
    model: &Model,
    cfg: &SceneConfig,
    whole_facets: bool,
) -> anyhow::Result<Model> {
    let materials = demcon_scene::convert::materials(&cfg.materials)?;
    let mut spec = demcon_scene::convert::defect_spec(cfg, &materials)?;
    spec.whole_facet_cuts = whole_facets;
    Ok(demcon_model::with_defects(model, &spec)?)
}

/// A periodic cube of two materials: its edge (m), its site count, the matrix's λ
/// (W/(m·K)) and the inclusions' λ over the matrix's.
#[derive(Debug, Clone, Copy)]
pub struct TwoPhaseCell {
    /// Edge of the cube (m).
    pub edge: f64,
    /// Packing sites.
    pub count: usize,
    /// The matrix's conductivity (W/(m·K)).
    pub lambda_m: f64,
    /// The inclusions' conductivity over the matrix's.
    pub contrast: f64,
}

/// A periodic homogenisation scene of `cell`, Laguerre cells: a matrix with `shapes`
/// (disjoint), the phases under `rule`.
pub fn shapes_scene(
    name: &str,
    seed: u64,
    cell: TwoPhaseCell,
    shapes: Vec<ShapeConfig>,
    rule: PhaseRuleConfig,
) -> SceneConfig {
    let TwoPhaseCell {
        edge,
        count,
        lambda_m,
        contrast,
    } = cell;
    let mut s = thermal_scene(
        name,
        seed,
        periodic_packing(edge, count),
        vec![
            material("matrix", lambda_m, 1000.0, 1000.0),
            material("shapes", lambda_m * contrast, 1000.0, 1000.0),
        ],
        homogenize_thermal(),
    );
    s.surface = SurfaceConfig::Laguerre;
    s.phases = vec![PhaseConfig::Shapes {
        material: "shapes".into(),
        shapes,
        file: None,
        disjoint: true,
    }];
    s.phase_rule = Some(rule);
    s
}

/// Runs `cfg` (a `Homogenize` scene) on `model` and returns the thermal effective tensor
/// (W/(m·K), row-major).
pub fn thermal_tensor(cfg: &SceneConfig, model: &Model) -> anyhow::Result<[[f64; 3]; 3]> {
    let r = run_with(cfg, model)?;
    Ok(r.homogenization
        .as_ref()
        .and_then(|h| h.thermal.as_ref())
        .ok_or_else(|| anyhow::anyhow!("the homogenisation produced no thermal tensor"))?
        .report
        .tensor)
}

/// Runs the physics of `cfg` on a clone of `model`.
pub fn run_with(cfg: &SceneConfig, model: &Model) -> anyhow::Result<RunResult> {
    let scene = Scene::from_config(cfg.clone(), PathBuf::new())?;
    Ok(run_on_model(&scene, model.clone())?)
}

/// Volume-weighted layer averages of `values` along axis `k` over `[lo, hi]` in `bins`
/// layers: (mean coordinate, mean value) of each non-empty layer, skipping `skip` particles.
pub fn layer_profile(
    model: &Model,
    values: &[f64],
    k: usize,
    lo: f64,
    hi: f64,
    bins: usize,
    skip: &[bool],
) -> Vec<(f64, f64)> {
    let mut acc = vec![(0.0, 0.0, 0.0); bins];
    for (p, c) in model.particles.centres.iter().enumerate() {
        if skip[p] {
            continue;
        }
        let b = (((c[k] - lo) / (hi - lo)) * bins as f64).floor();
        if b < 0.0 || b >= bins as f64 {
            continue;
        }
        let v = model.particles.volume(p);
        let a = &mut acc[b as usize];
        a.0 += v * c[k];
        a.1 += v * values[p];
        a.2 += v;
    }
    acc.into_iter()
        .filter(|a| a.2 > 0.0)
        .map(|a| (a.0 / a.2, a.1 / a.2))
        .collect()
}

/// Mask of the fixed-temperature particles of a run (walls hold no particle).
pub fn fixed_mask(model: &Model, fixed_sets: &[FixedSet]) -> Vec<bool> {
    let mut m = vec![false; model.particles.len()];
    for set in fixed_sets {
        for &i in set.particles() {
            m[i as usize] = true;
        }
    }
    m
}

/// Mask of the particles that are not the continuum's answer in a thermal run:
/// fixed-temperature particles and floating clusters (reached by no fixed value) — excluded
/// from a steady solve, or kept by a transient, where they evolve on their own.
pub fn unsolved_mask(model: &Model, bcs: &ThermalBcs) -> Vec<bool> {
    let mut m = fixed_mask(model, &bcs.fixed_sets);
    let c = &bcs.constraints;
    for &i in c.excluded().iter().chain(c.floating_kept()) {
        if let Some(x) = m.get_mut(i as usize) {
            *x = true;
        }
    }
    m
}

/// A fixed temperature held on a face itself (wall half-contacts), demcon's default boundary.
pub fn wall(face: FaceConfig, value: f64) -> ThermalBcConfig {
    ThermalBcConfig::WallTemperature {
        face,
        value: value.into(),
    }
}

/// The JSON key of a metric keyed by particle count: the count in decimal, unrounded
/// (`20000`), as the metric names documented in the report expect.
pub fn key(n: usize) -> String {
    n.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small scene (only its packing section and seed count matter here).
    fn small(seed: u64, count: usize) -> SceneConfig {
        super::super::composite::slab_scene(
            "prepack",
            seed,
            count,
            super::super::composite::epoxy_silica(),
            Vec::new(),
        )
    }

    /// Packings made ahead, several at a time, are the ones a case would make one by one.
    #[test]
    fn prepacked_packings_are_those_made_one_by_one() {
        let scenes: Vec<SceneConfig> = (0..3).map(|k| small(9100 + k, 300 + 50 * k as usize)).collect();
        // The same scene twice is made once.
        let mut with_repeat = scenes.clone();
        with_repeat.push(scenes[0].clone());
        prepack(&with_repeat).unwrap();
        for cfg in &scenes {
            let scene = Scene::from_config(cfg.clone(), PathBuf::new()).unwrap();
            assert!(is_cached(scene.config()));
            let cached = model_of(cfg).unwrap();
            let (direct, ..) = demcon_scene::build::make_particles(&scene, None).unwrap();
            assert_eq!(cached.particles.centres, direct.centres);
            assert_eq!(cached.particles.radii, direct.radii);
        }
    }

    /// A packing that cannot be made is reported, naming the field and the value.
    #[test]
    fn prepack_reports_a_bad_scene() {
        let mut bad = small(9200, 300);
        if let PackingConfig::Generate { phi, .. } = &mut bad.packing {
            *phi = 1.5;
        }
        let err = prepack(&[small(9201, 300), bad]).unwrap_err().to_string();
        assert!(err.contains("phi") && err.contains("1.5"), "{err}");
    }
}

/// The models of the crack cases that cut a built network or follow the cracks: the Laguerre
/// cells following the cracks (`Conforming`, the headline since issue 32: a model built with
/// each crack set), the Laguerre cells cut by the covered part of each facet, Terreros α
/// (segment rule).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CrackVariant {
    /// The Laguerre cells following the cracks.
    Conforming,
    /// The Laguerre cells, the covered part of each facet cut.
    Laguerre,
    /// Terreros α, the contacts whose segment crosses a crack cut.
    Terreros,
}

impl CrackVariant {
    /// The three, the headline first.
    pub const ALL: [CrackVariant; 3] = [
        CrackVariant::Conforming,
        CrackVariant::Laguerre,
        CrackVariant::Terreros,
    ];

    /// Its transmission-surface model.
    pub fn surface(self) -> Surface {
        match self {
            CrackVariant::Terreros => Surface::Terreros,
            _ => Surface::Laguerre,
        }
    }

    /// Id in metric names.
    pub fn id(self) -> &'static str {
        match self {
            CrackVariant::Conforming => "laguerre_conforming",
            m => m.surface().id(),
        }
    }

    /// Label in tables.
    pub fn label(self) -> &'static str {
        match self {
            CrackVariant::Conforming => "Laguerre, conforming cells",
            m => m.surface().label(),
        }
    }
}

/// The thermal physics of a periodic homogenisation: no boundary condition, no source,
/// `Homogenize` (the three load cases of the effective tensor).
pub fn homogenize_thermal() -> ThermalConfig {
    ThermalConfig {
        initial_temperature: 0.0,
        bcs: Vec::new(),
        sources: Vec::new(),
        solver: ThermalSolverConfig::Homogenize,
        checkpoint: None,
    }
}
