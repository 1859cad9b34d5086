//! Scene builders shared by the electric-paper cases (Hubert et al. 2017, §3): the AISI 304L
//! of its Table 2, the r = 1 mm, l = 5 mm cylinder (our cylinders run along z, so the
//! electrodes are the faces ZMin/ZMax), the grooved cylinder of `notch-electric-fem.json`
//! (2 mm ≤ z ≤ 3 mm, radius reduced to 0.5 mm) carved from a cylinder packing, and the
//! measurements every electric case needs (electrode layers, effective length, medians).

use demcon_core::{Face, Selector};
use demcon_graph::{ContactParams, detect_contacts};
use demcon_scene::config::*;

use super::common::*;

/// Electric resistivity ρ_e of AISI 304L (Ω·m), Hubert 2017 Table 2.
pub const RHO_E: f64 = 0.73e-6;
/// Thermal conductivity λ of AISI 304L (W/(m·K)), Hubert 2017 Table 2.
pub const LAMBDA: f64 = 15.0;
/// Density ρ_c (kg/m³), Hubert 2017 Table 2.
pub const DENSITY: f64 = 7900.0;
/// Specific heat c (J/(kg·K)), Hubert 2017 Table 2.
pub const SPECIFIC_HEAT: f64 = 500.0;
/// Cylinder radius (m), Hubert 2017 §3.1.
pub const RADIUS: f64 = 1e-3;
/// Cylinder length (m), Hubert 2017 §3.1.
pub const LENGTH: f64 = 5e-3;
/// Groove: first and last z (m) of the reduced section (`notch-electric-fem.json`).
pub const GROOVE_Z: (f64, f64) = (2e-3, 3e-3);
/// Radius (m) of the reduced section.
pub const GROOVE_RADIUS: f64 = 0.5e-3;
/// Volume fraction of the grooved cylinder in its cylinder: (4 · 1² + 1 · 0.5²) / 5.
pub const GROOVED_VOLUME_RATIO: f64 = (4.0 + 0.25) / 5.0;

/// AISI 304L with ρ_e(T) constant (β = 0), as the paper and the FEM reference.
pub fn steel_304l() -> MaterialConfig {
    MaterialConfig {
        name: "AISI 304L".into(),
        conductivity: LAMBDA,
        conductivity_temp_coeff: 0.0,
        conductivity_ref_temp: 20.0,
        conductivity_tensor: None,
        tensor_in_shape_frame: false,
        conductivity_table: None,
        density: DENSITY,
        specific_heat: SPECIFIC_HEAT,
        resistivity: Some(RHO_E),
        resistivity_temp_coeff: 0.0,
        resistivity_ref_temp: 20.0,
    }
}

/// The r = 1 mm, l = 5 mm cylinder container (axis z, 0 ≤ z ≤ l).
pub fn cylinder() -> ContainerConfig {
    ContainerConfig::Cylinder {
        radius: RADIUS,
        length: LENGTH,
    }
}

/// The grooved cylinder as a carving region: the cylinder minus a ring (2 mm ≤ z ≤ 3 mm,
/// 0.5 mm ≤ r ≤ 2 mm).
///
/// The ring's hole is a cylinder LONGER than the ring (it runs from z = 1 mm to 4 mm): regions
/// combine signed distances by max/min, which is exact inside but only a bound outside, and a
/// hole exactly as long as the ring would make the ring look closer than it is to particles
/// under the groove (directly below z = 2 mm or above z = 3 mm at r < 0.5 mm), so carving would
/// remove a whole layer across the reduced section and disconnect it. With the longer hole the
/// only over-removal is in the small square zone around the two groove edges.
pub fn grooved_region() -> RegionConfig {
    let body = RegionConfig::Cylinder {
        base: (0.0, 0.0, 0.0),
        axis: AxisConfig::Z,
        radius: RADIUS,
        length: LENGTH,
    };
    let ring_outer = RegionConfig::Cylinder {
        base: (0.0, 0.0, GROOVE_Z.0),
        axis: AxisConfig::Z,
        radius: 2.0 * RADIUS,
        length: GROOVE_Z.1 - GROOVE_Z.0,
    };
    let hole = RegionConfig::Cylinder {
        base: (0.0, 0.0, GROOVE_Z.0 - 1e-3),
        axis: AxisConfig::Z,
        radius: GROOVE_RADIUS,
        length: GROOVE_Z.1 - GROOVE_Z.0 + 2e-3,
    };
    let ring = RegionConfig::Difference(Box::new(ring_outer), Box::new(hole));
    RegionConfig::Difference(Box::new(body), Box::new(ring))
}

/// A Gaussian-0.3 LS packing of `count` particles in the cylinder, aiming at φ = 0.64 and
/// accepting the jammed state short of it: in a cylinder only ~13 mean radii wide the wall
/// layers jam near φ ≈ 0.62 at 5000 particles (the reached φ is in each case's table).
pub fn cylinder_packing(count: usize) -> PackingConfig {
    match packing(cylinder(), count) {
        PackingConfig::Generate {
            container,
            count,
            phi,
            radius_cov,
            radius_range,
            ..
        } => PackingConfig::Generate {
            container,
            count,
            phi,
            radius_cov,
            radius_range,
            allow_short: true,
        },
        other => other,
    }
}

/// Electrodes: 0 V on the particles touching ZMin, `v0` (V) on those touching ZMax (the
/// paper's "particles touching each end face").
pub fn end_electrodes(v0: f64) -> Vec<ElectrodeConfig> {
    vec![
        ElectrodeConfig {
            select: Some(SelectorConfig::Face(FaceConfig::ZMin)),
            potential: 0.0.into(),
            ..Default::default()
        },
        ElectrodeConfig {
            select: Some(SelectorConfig::Face(FaceConfig::ZMax)),
            potential: v0.into(),
            ..Default::default()
        },
    ]
}

/// Electrodes on the end faces themselves: 0 V on ZMin, `v0` (V) on ZMax, each linked to
/// the particles touching it by half-contacts σ S / h.
pub fn face_electrodes(v0: f64) -> Vec<ElectrodeConfig> {
    vec![
        ElectrodeConfig {
            face: Some(FaceConfig::ZMin),
            potential: 0.0.into(),
            ..Default::default()
        },
        ElectrodeConfig {
            face: Some(FaceConfig::ZMax),
            potential: v0.into(),
            ..Default::default()
        },
    ]
}

/// An electric scene (no thermal physics, no files) on the cylinder packing of `count`
/// particles, optionally carved, with the electric surface model `surface`.
pub fn electric_scene(
    name: &str,
    seed: u64,
    count: usize,
    carve: Option<RegionConfig>,
    surface: SurfaceConfig,
    v0: f64,
) -> SceneConfig {
    SceneConfig {
        name: name.into(),
        seed,
        packing: cylinder_packing(count),
        carve,
        carve_rule: CarveRuleConfig::WholeSphere,
        contacts: ContactsConfig {
            coordination: Some(7.5),
            tolerance: None,
        },
        surface: SurfaceConfig::TerrerosAlpha,
        materials: vec![steel_304l()],
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
        thermal: None,
        electric: Some(ElectricConfig {
            electrodes: end_electrodes(v0),
            eta: 1.0,
            surface: Some(surface),
            recouple_tolerance: None,
            current: None,
            homogenize: false,
        }),
        outputs: OutputsConfig {
            vtk: false,
            ..OutputsConfig::default()
        },
    }
}

/// The two electrode layers of a model (particles touching ZMin, ZMax).
pub fn electrode_layers(model: &Model) -> anyhow::Result<(Vec<u32>, Vec<u32>)> {
    let lo =
        Selector::Face(Face::ZMin).select_nonempty(&model.particles, &model.container, "ZMin electrode")?;
    let hi =
        Selector::Face(Face::ZMax).select_nonempty(&model.particles, &model.container, "ZMax electrode")?;
    Ok((lo, hi))
}

/// Distance (m) along z between the mean centres of the two electrode layers: the length
/// the network actually spans (the centres sit about one mean radius inside each face).
pub fn effective_length(model: &Model, lo: &[u32], hi: &[u32]) -> f64 {
    let mean_z = |ids: &[u32]| {
        ids.iter()
            .map(|&i| model.particles.centres[i as usize].z)
            .sum::<f64>()
            / ids.len() as f64
    };
    mean_z(hi) - mean_z(lo)
}

/// `model` with a new contact graph (and network), its report updated.
fn with_graph(model: &Model, graph: demcon_graph::ContactGraph) -> anyhow::Result<Model> {
    let mut m = model.clone();
    let c = &mut m.report.contacts;
    c.epsilon = graph.report.epsilon;
    c.coordination = graph.report.coordination;
    c.n_contacts = graph.report.n_contacts;
    c.rattlers = graph.report.rattlers.len();
    c.under_two_contacts = graph.report.under_two_contacts;
    c.n_components = graph.report.n_components;
    c.largest_component = graph.report.largest_component;
    c.diagnostics = graph.report.diagnostics.iter().map(|d| d.to_string()).collect();
    m.set_graph(graph)?;
    Ok(m)
}

/// The same particles with their contacts re-detected for the target mean coordination `z`
/// (e.g. the electric paper's Z ≈ 6.2 on a packing built with the heat paper's 7.5).
pub fn with_coordination(model: &Model, z: f64) -> anyhow::Result<Model> {
    let graph = detect_contacts(&model.particles, &model.container, &ContactParams::target(z))?;
    with_graph(model, graph)
}

/// How a shape is cut out of a packing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Carving {
    /// Keep the spheres wholly inside (the scene's `carve`, `demcon_packing::carve`): the
    /// kept solid ends a fraction of a radius inside a cut surface.
    WholeSphere,
    /// Keep the particles whose CENTRE is inside: their representative cells tile the region
    /// on average (the unbiased cut of a homogeneous packing).
    Centre,
}

/// Cuts `region` out of the uncarved `full` model and rebuilds contacts (target Z = 7.5)
/// and network on what is kept; the domain volume becomes the region's.
pub fn carved(full: &Model, region: &RegionConfig, how: Carving) -> anyhow::Result<Model> {
    let region = scene_region(region, "carve")?;
    let p = &full.particles;
    let (kept, _) = match how {
        Carving::WholeSphere => demcon_packing::carve(p, &region),
        Carving::Centre => p.retain(|i| region.contains_point(&p.centres[i])),
    };
    let graph = detect_contacts(&kept, &full.container, &ContactParams::target(7.5))?;
    let mut m = full.clone();
    m.report.carved_away = p.len() - kept.len();
    m.report.phase_counts = vec![kept.len()];
    m.domain_volume = region.volume(256);
    m.phi = kept.solid_volume() / m.domain_volume;
    m.particles = kept;
    with_graph(&m, graph)
}

/// Median of a non-empty slice (the mean of the two middle values for an even count).
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use demcon_core::Vec3;

    fn region() -> demcon_core::Region {
        scene_region(&grooved_region(), "carve").unwrap()
    }

    #[test]
    fn the_groove_keeps_the_reduced_section_and_removes_the_ring() {
        let r = region();
        let rad = 0.05e-3;
        // In the reduced section, on the axis and just under and over the groove planes.
        for z in [1.95e-3, 2.0e-3, 2.5e-3, 3.0e-3, 3.05e-3] {
            assert!(r.contains_sphere(&Vec3::new(0.0, 0.0, z), rad), "z = {z}");
            assert!(r.contains_sphere(&Vec3::new(0.3e-3, 0.0, z), rad), "z = {z}");
        }
        // In the ring, or crossing its surface.
        assert!(!r.contains_sphere(&Vec3::new(0.8e-3, 0.0, 2.5e-3), rad));
        assert!(!r.contains_sphere(&Vec3::new(0.47e-3, 0.0, 2.5e-3), rad));
        assert!(!r.contains_sphere(&Vec3::new(0.8e-3, 0.0, 1.97e-3), rad));
        // Far from the groove, the whole cylinder.
        assert!(r.contains_sphere(&Vec3::new(0.9e-3, 0.0, 1.0e-3), rad));
        assert!(!r.contains_sphere(&Vec3::new(0.97e-3, 0.0, 1.0e-3), rad));
    }

    #[test]
    fn median_of_odd_and_even() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
    }
}
