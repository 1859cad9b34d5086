//! From the scene to a model ready to solve: particles (packed or read, carved), phases,
//! contacts and the network structure. Each stage records what it did and what it cost.

use std::path::Path;
use std::time::Instant;

use demcon_core::{Container, MaterialTable, ParticleSet, Region};
use demcon_graph::{
    ContactGraph, ContactParams, ContactReport, HalfBond, Laminates, Mix, assign_phase,
    assign_phase_laminate, detect_contacts,
};
use demcon_network::Network;
use demcon_packing::{PackingParams, PackingReport, RadiusDistribution, StopReason, carve, pack, read_xyzr};
use serde::Serialize;

use crate::config::*;
use crate::convert;
use crate::error::SceneError;

/// Everything the solvers need that does not depend on the physics.
#[derive(Debug, Clone)]
pub struct Model {
    /// The particles (Morton-ordered when generated), carved and with phases set.
    pub particles: ParticleSet,
    /// The container the packing was made in (faces for boundary conditions).
    pub container: Container,
    /// Volume of the solid the particles represent (m³): the container's, or the carved region's.
    pub domain_volume: f64,
    /// Solid fraction Σ V_p / domain volume, used for the representative volume V_p/φ.
    pub phi: f64,
    /// The materials, indexed by phase.
    pub materials: MaterialTable,
    /// Particles cut by a phase interface under the laminate rule, sorted by particle
    /// (empty under the centre rule).
    pub mixes: Vec<Mix>,
    /// Contacts with their geometry.
    pub graph: ContactGraph,
    /// Laplacian structure over the contacts.
    pub network: Network,
    /// What the build did.
    pub report: ModelReport,
}

impl Model {
    /// The laminate mixes indexed by particle.
    pub fn laminates(&self) -> Laminates<'_> {
        Laminates::new(self.particles.len(), &self.mixes)
    }
}

/// What building the model did and cost.
#[derive(Debug, Clone, Serialize)]
pub struct ModelReport {
    /// Packing report, when the packing was generated here.
    pub packing: Option<PackingReport>,
    /// Particles read from a file, when imported.
    pub imported_from: Option<String>,
    /// Particles removed by carving.
    pub carved_away: usize,
    /// Particles per phase (by centre).
    pub phase_counts: Vec<usize>,
    /// Volume fraction of the solid carried by each phase: Σ v_p V_p / Σ V_p (the
    /// particles' own phases, and the laminate fractions of the cut ones).
    pub phase_fractions: Vec<f64>,
    /// Particles cut by an interface (laminate rule).
    pub mixed_particles: usize,
    /// Inclusions placed (centres and radius), when the scene asks for them.
    pub inclusions: Option<InclusionReport>,
    /// Contact detection summary.
    pub contacts: ContactSummary,
    /// Wall time of each stage (s): packing, contacts, network.
    pub pack_s: f64,
    /// Contact detection (s).
    pub contacts_s: f64,
    /// Network structure (s).
    pub network_s: f64,
}

/// The inclusions of a multi-inclusion composite.
#[derive(Debug, Clone, Serialize)]
pub struct InclusionReport {
    /// Number of inclusions.
    pub count: usize,
    /// Inclusion radius (m).
    pub radius: f64,
    /// Volume fraction of the inclusion spheres in the box.
    pub fraction: f64,
    /// Fraction of the solid (by volume) the model carries in the inclusion phase (by
    /// centre, or with the laminate fractions under the laminate rule).
    pub particle_fraction: f64,
    /// Centres (m).
    pub centres: Vec<[f64; 3]>,
}

/// A serialisable summary of the contact report.
#[derive(Debug, Clone, Serialize)]
pub struct ContactSummary {
    /// Relative gap tolerance ε used.
    pub epsilon: f64,
    /// Mean coordination reached.
    pub coordination: f64,
    /// Contacts.
    pub n_contacts: usize,
    /// Particles with no contact.
    pub rattlers: usize,
    /// Particles with fewer than 2 contacts.
    pub under_two_contacts: usize,
    /// Connected components.
    pub n_components: usize,
    /// Size of the largest component.
    pub largest_component: usize,
    /// Diagnostics as text.
    pub diagnostics: Vec<String>,
}

impl ContactSummary {
    fn from(r: &ContactReport) -> Self {
        Self {
            epsilon: r.epsilon,
            coordination: r.coordination,
            n_contacts: r.n_contacts,
            rattlers: r.rattlers.len(),
            under_two_contacts: r.under_two_contacts,
            n_components: r.n_components,
            largest_component: r.largest_component,
            diagnostics: r.diagnostics.iter().map(|d| d.to_string()).collect(),
        }
    }
}

/// Particles and container from the scene's packing section (generated or read), with the
/// packing report.
pub fn make_particles(
    cfg: &SceneConfig,
    base_dir: &Path,
    progress: Option<&dyn Fn(&demcon_packing::PackProgress)>,
) -> Result<(ParticleSet, Container, Option<PackingReport>, Option<String>), SceneError> {
    match &cfg.packing {
        PackingConfig::Generate {
            container,
            count,
            phi,
            radius_cov,
            radius_range,
            allow_short,
        } => {
            let container = convert::container(container, "packing.container")?;
            let radii = match radius_range {
                _ if *radius_cov == 0.0 => RadiusDistribution::Monodisperse,
                None => RadiusDistribution::gaussian(*radius_cov),
                Some((lo, hi)) => RadiusDistribution::Gaussian {
                    cov: *radius_cov,
                    min_ratio: *lo,
                    max_ratio: *hi,
                },
            };
            let params = PackingParams::new(container, *count, *phi, radii);
            let (particles, report) = pack(&params, cfg.seed, progress)
                .map_err(|e| SceneError::Packing(format!("packing: {e}")))?;
            if report.stop != StopReason::TargetReached && !allow_short {
                return Err(SceneError::Packing(format!(
                    "the packing stopped at φ = {:.4} ({:?}) short of the target {phi}; lower `packing.phi` \
                     or set `allow_short: true`",
                    report.packing.phi, report.stop
                )));
            }
            Ok((particles, container, Some(report), None))
        }
        PackingConfig::File { path, container } => {
            let full = base_dir.join(path);
            let (particles, header) = read_xyzr(&full)
                .map_err(|e| SceneError::Packing(format!("reading {}: {e}", full.display())))?;
            let container = match (container, header) {
                (Some(c), _) => convert::container(c, "packing.container")?,
                (None, Some(c)) => c,
                (None, None) => {
                    return Err(SceneError::invalid(
                        "packing.container",
                        "none",
                        format!(
                            "{} has no container in its header: give `container` in the scene",
                            full.display()
                        ),
                    ));
                }
            };
            Ok((particles, container, None, Some(full.display().to_string())))
        }
    }
}

/// Places monodisperse, non-overlapping inclusion spheres in the container's bounding box
/// with the LS algorithm and returns them (centres, radius). `fraction` is their volume
/// fraction, `size_ratio` the box edge over the inclusion diameter.
pub fn place_inclusions(
    container: &Container,
    fraction: f64,
    size_ratio: f64,
    seed: u64,
) -> Result<(Vec<demcon_core::Vec3>, f64), SceneError> {
    if !(fraction > 0.0 && fraction < 0.6) {
        return Err(SceneError::invalid(
            "phases.Inclusions.fraction",
            fraction,
            "must be in (0, 0.6)",
        ));
    }
    if !(size_ratio.is_finite() && size_ratio >= 1.0) {
        return Err(SceneError::invalid(
            "phases.Inclusions.size_ratio",
            size_ratio,
            "must be ≥ 1 (box edge / diameter)",
        ));
    }
    let b = container.bounds();
    let e = b.extent();
    let edge = e.x.min(e.y).min(e.z);
    let d = edge / size_ratio;
    let sphere_v = std::f64::consts::PI / 6.0 * d * d * d;
    let count = ((fraction * b.volume() / sphere_v).round() as usize).max(1);
    let boxc = Container::Box {
        size: [e.x, e.y, e.z],
    };
    let mut params = PackingParams::new(boxc, count, fraction, RadiusDistribution::Monodisperse);
    params.max_wall_s = 120.0;
    let (spheres, report) = pack(&params, seed ^ 0x9e37_79b9_7f4a_7c15, None)
        .map_err(|e| SceneError::Packing(format!("placing inclusions: {e}")))?;
    if report.stop != StopReason::TargetReached {
        return Err(SceneError::invalid(
            "phases.Inclusions.fraction",
            fraction,
            format!(
                "the inclusions could not be placed: reached φ = {:.4} ({:?}) with {count} spheres",
                report.packing.phi, report.stop
            ),
        ));
    }
    let centres = spheres.centres.iter().map(|c| c + b.min).collect();
    Ok((centres, spheres.radii[0]))
}

/// Applies the scene's phase assignments in order.
fn apply_phases(
    cfg: &SceneConfig,
    particles: &mut ParticleSet,
    container: &Container,
    materials: &MaterialTable,
    mixes: &mut Vec<Mix>,
) -> Result<Option<InclusionReport>, SceneError> {
    let mut inclusions = None;
    let mut assign = |particles: &mut ParticleSet, region: &Region, phase: u16| match cfg.phase_rule {
        PhaseRuleConfig::Centre => {
            assign_phase(particles, region, phase);
        }
        PhaseRuleConfig::Laminate => {
            assign_phase_laminate(particles, region, phase, mixes, HalfBond::Laminate);
        }
        PhaseRuleConfig::Segment => {
            assign_phase_laminate(particles, region, phase, mixes, HalfBond::Segment);
        }
    };
    for (i, ph) in cfg.phases.iter().enumerate() {
        match ph {
            PhaseConfig::Region { material, region } => {
                let field = format!("phases[{i}]");
                let phase = materials
                    .phase_of(material)
                    .map_err(|e| SceneError::at(&format!("{field}.material"), e))?;
                let region = convert::region(region, &format!("{field}.region"))?;
                assign(particles, &region, phase);
            }
            PhaseConfig::Inclusions {
                material,
                fraction,
                size_ratio,
            } => {
                let phase = materials
                    .phase_of(material)
                    .map_err(|e| SceneError::at(&format!("phases[{i}].material"), e))?;
                let (centres, radius) = place_inclusions(container, *fraction, *size_ratio, cfg.seed)?;
                let union = Region::Union(
                    centres
                        .iter()
                        .map(|c| Region::Sphere { centre: *c, radius })
                        .collect(),
                );
                assign(particles, &union, phase);
                let b = container.bounds();
                inclusions = Some(InclusionReport {
                    count: centres.len(),
                    radius,
                    fraction: centres.len() as f64 * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3)
                        / b.volume(),
                    particle_fraction: 0.0, // set once all phases are applied
                    centres: centres.iter().map(|c| [c.x, c.y, c.z]).collect(),
                });
            }
        }
    }
    materials
        .check_phases(&particles.phases)
        .map_err(|e| SceneError::at("phases", e))?;
    if let Some(inc) = inclusions.as_mut() {
        let phase = cfg
            .phases
            .iter()
            .rev()
            .find_map(|p| match p {
                PhaseConfig::Inclusions { material, .. } => materials.phase_of(material).ok(),
                _ => None,
            })
            .unwrap_or(0);
        let f = Laminates::new(particles.len(), mixes).phase_fractions(particles, materials.materials.len());
        inc.particle_fraction = f.get(phase as usize).copied().unwrap_or(0.0);
    }
    Ok(inclusions)
}

/// Re-assigns the phases of a built model (same packing and contacts): every particle back
/// to phase 0 with no mix, then each `(region, phase)` in order under `rule`; updates the
/// report's phase counts, carried fractions and cut-particle count. For studies that compare
/// phase layouts or rules on one packing.
pub fn set_region_phases(model: &mut Model, regions: &[(Region, u16)], rule: PhaseRuleConfig) {
    model.particles.phases.iter_mut().for_each(|p| *p = 0);
    model.mixes.clear();
    for (region, phase) in regions {
        match rule {
            PhaseRuleConfig::Centre => {
                assign_phase(&mut model.particles, region, *phase);
            }
            PhaseRuleConfig::Laminate => {
                assign_phase_laminate(
                    &mut model.particles,
                    region,
                    *phase,
                    &mut model.mixes,
                    HalfBond::Laminate,
                );
            }
            PhaseRuleConfig::Segment => {
                assign_phase_laminate(
                    &mut model.particles,
                    region,
                    *phase,
                    &mut model.mixes,
                    HalfBond::Segment,
                );
            }
        }
    }
    let n_phases = model.materials.materials.len();
    let mut counts = vec![0; n_phases];
    for &p in &model.particles.phases {
        if (p as usize) < n_phases {
            counts[p as usize] += 1;
        }
    }
    model.report.phase_counts = counts;
    model.report.phase_fractions = model.laminates().phase_fractions(&model.particles, n_phases);
    model.report.mixed_particles = model.mixes.len();
}

/// Contact parameters from the scene.
pub fn contact_params(c: &ContactsConfig) -> Result<ContactParams, SceneError> {
    match (c.coordination, c.tolerance) {
        (Some(_), Some(_)) => Err(SceneError::invalid(
            "contacts",
            "both coordination and tolerance",
            "give one of `coordination` (target mean Z) or `tolerance` (relative gap)",
        )),
        (None, Some(t)) => Ok(ContactParams::relative(t)),
        (Some(z), None) => Ok(ContactParams::target(z)),
        (None, None) => Ok(ContactParams::target(7.5)),
    }
}

/// Builds the model: particles, carving, phases, contacts, network structure.
pub fn build_model(
    cfg: &SceneConfig,
    base_dir: &Path,
    progress: Option<&dyn Fn(&demcon_packing::PackProgress)>,
) -> Result<Model, SceneError> {
    let materials = convert::materials(&cfg.materials)?;
    let contact_params = contact_params(&cfg.contacts)?;
    let t0 = Instant::now();
    let (mut particles, container, packing, imported_from) = make_particles(cfg, base_dir, progress)?;
    let pack_s = t0.elapsed().as_secs_f64();
    let mut domain_volume = container.volume();
    let mut carved_away = 0;
    if let Some(rc) = &cfg.carve {
        let region = convert::region(rc, "carve")?;
        let (kept, _) = match cfg.carve_rule {
            CarveRuleConfig::WholeSphere => carve(&particles, &region),
            CarveRuleConfig::Centre => particles.retain(|i| region.contains_point(&particles.centres[i])),
        };
        carved_away = particles.len() - kept.len();
        if kept.is_empty() {
            return Err(SceneError::invalid(
                "carve",
                "region",
                "no particle lies inside the carving region",
            ));
        }
        particles = kept;
        domain_volume = region.volume(256);
    }
    let mut mixes = Vec::new();
    let inclusions = apply_phases(cfg, &mut particles, &container, &materials, &mut mixes)?;
    let phase_fractions =
        Laminates::new(particles.len(), &mixes).phase_fractions(&particles, materials.materials.len());
    let t1 = Instant::now();
    let graph = detect_contacts(&particles, &container, &contact_params)?;
    let contacts_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let network = Network::new(particles.len(), &graph.pairs)?;
    let network_s = t2.elapsed().as_secs_f64();
    let mut phase_counts = vec![0; materials.materials.len()];
    for &p in &particles.phases {
        phase_counts[p as usize] += 1;
    }
    let phi = particles.solid_volume() / domain_volume;
    Ok(Model {
        report: ModelReport {
            packing,
            imported_from,
            carved_away,
            phase_counts,
            phase_fractions,
            mixed_particles: mixes.len(),
            inclusions,
            contacts: ContactSummary::from(&graph.report),
            pack_s,
            contacts_s,
            network_s,
        },
        particles,
        container,
        domain_volume,
        phi,
        materials,
        mixes,
        graph,
        network,
    })
}
