//! Shaped-inclusion phases: a list of spheroids and cylinders ([`PhaseSpec::Shapes`]) or shapes
//! placed at random to a volume fraction ([`PhaseSpec::RandomShapes`]), turned into the region
//! whose level set the phase rules cut (with the periodic images in a periodic box), and what
//! `summary.json` reports of them.
//!
//! [`PhaseSpec::Shapes`]: crate::PhaseSpec::Shapes
//! [`PhaseSpec::RandomShapes`]: crate::PhaseSpec::RandomShapes

use demcon_core::{Container, Inclusion, Region};
use demcon_packing::{ShapeParams, ShapeReport, periodic_images, place_shapes};
use nalgebra::Matrix3;
use serde::Serialize;

use crate::error::ModelError;

/// The shapes of one phase entry, for `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct ShapesReport {
    /// The phase entry (index into the scene's phases).
    pub entry: usize,
    /// The shapes' phase (index into the material table).
    pub phase: u16,
    /// Number of shapes (periodic images not counted).
    pub count: usize,
    /// Their exact volume over the container's bounding box (in a walled box every shape lies
    /// inside it; in a periodic box the images fill in what crosses the faces).
    pub fraction: f64,
    /// Orientation tensor ⟨u uᵀ⟩ of their axes, volume-weighted (row-major).
    pub orientation_tensor: [[f64; 3]; 3],
    /// How the random placement went, for [`crate::PhaseSpec::RandomShapes`].
    pub placement: Option<ShapeReport>,
    /// The shapes themselves (m; without periodic images), for drawing (`inclusions.vtp`); not
    /// in `summary.json`.
    #[serde(skip)]
    pub shapes: Vec<Inclusion>,
}

/// The volume-weighted orientation tensor of `shapes` (row-major; zero when empty).
pub fn orientation_tensor(shapes: &[Inclusion]) -> [[f64; 3]; 3] {
    let mut a = Matrix3::zeros();
    let mut total = 0.0;
    for s in shapes {
        let (u, v) = (s.axis(), s.volume());
        a += v * u * u.transpose();
        total += v;
    }
    if total > 0.0 {
        a /= total;
    }
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[(i, j)]))
}

/// Checks that every shape of a phase entry lies where it may: its centre inside the container's
/// bounding box, and in a walled container the whole shape inside it (refusals name
/// `{field}.shapes[k]`).
pub fn check_placement(container: &Container, shapes: &[Inclusion], field: &str) -> Result<(), ModelError> {
    let b = container.bounds();
    let periodic = container.period().is_some();
    for (k, s) in shapes.iter().enumerate() {
        let c = s.centre();
        let sb = s.bounds();
        let outside = if periodic {
            !b.contains(&c)
        } else {
            (0..3).any(|i| sb.min[i] < b.min[i] || sb.max[i] > b.max[i])
        };
        if outside {
            return Err(ModelError::invalid(
                &format!("{field}.shapes[{k}]"),
                format!(
                    "centre ({:e}, {:e}, {:e}) m, extent [{:e}, {:e}] × [{:e}, {:e}] × [{:e}, {:e}] m",
                    c.x, c.y, c.z, sb.min.x, sb.max.x, sb.min.y, sb.max.y, sb.min.z, sb.max.z
                ),
                if periodic {
                    format!(
                        "a centre inside the periodic box [{:e}, {:e}] × [{:e}, {:e}] × [{:e}, {:e}] m (a shape may \
                         cross its faces)",
                        b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z
                    )
                } else {
                    format!(
                        "the whole shape inside the container's box [{:e}, {:e}] × [{:e}, {:e}] × [{:e}, {:e}] m",
                        b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z
                    )
                },
            ));
        }
    }
    Ok(())
}

/// The region of a phase entry's shapes: their union, with the periodic images that reach into
/// a periodic box (which spans `[0, L]`).
pub fn shapes_region(container: &Container, shapes: &[Inclusion]) -> Region {
    let members = match container.period() {
        Some(period) => periodic_images(shapes, period),
        None => shapes.to_vec(),
    };
    Region::Union(members.into_iter().map(Region::Inclusion).collect())
}

/// Places shapes at random for a phase entry in the model's container (a `Box` or `Periodic`;
/// the container of `params` is replaced by it). Refusals name `{field}.…`.
pub fn random_shapes(
    container: &Container,
    params: &ShapeParams,
    seed: u64,
    field: &str,
) -> Result<(Vec<Inclusion>, ShapeReport), ModelError> {
    if !matches!(container, Container::Box { .. } | Container::Periodic { .. }) {
        return Err(ModelError::invalid(
            field,
            format!("a {} container", container.kind()),
            "random shapes are placed in a Box or a Periodic box",
        ));
    }
    let p = ShapeParams {
        container: *container,
        ..params.clone()
    };
    place_shapes(&p, seed).map_err(|e| match e {
        demcon_packing::PackingError::Invalid(demcon_core::CoreError::InvalidParameter {
            field: f,
            value,
            allowed,
        }) => ModelError::invalid(&format!("{field}.{f}"), value, allowed),
        other => ModelError::Packing(format!("{field}: {other}")),
    })
}

/// Per particle, the unit axis of the shape whose frame its material's tensor is read in
/// ([`demcon_core::Material::tensor_in_shape_frame`]): for a particle whose phase (or, cut by
/// an interface, whose other phase) is such a material, the shape of that phase's entries
/// nearest it by signed distance (minimum image); `None` elsewhere. Empty when no material
/// reads its tensor in a shape's frame.
pub fn shape_axes(
    particles: &demcon_core::ParticleSet,
    container: &Container,
    materials: &[demcon_core::Material],
    mixes: &[demcon_graph::Mix],
    reports: &[ShapesReport],
) -> Vec<Option<demcon_core::Vec3>> {
    let framed = |phase: u16| {
        materials
            .get(phase as usize)
            .is_some_and(|m| m.tensor_in_shape_frame)
    };
    if !reports.iter().any(|r| framed(r.phase)) {
        return Vec::new();
    }
    let finders: Vec<(u16, ShapeFinder)> = reports
        .iter()
        .filter(|r| framed(r.phase))
        .map(|r| (r.phase, ShapeFinder::new(&r.shapes, container)))
        .collect();
    let other: std::collections::HashMap<u32, u16> =
        mixes.iter().map(|m| (m.particle, m.other_phase)).collect();
    (0..particles.len())
        .map(|p| {
            let x = &particles.centres[p];
            let phases = [Some(particles.phases[p]), other.get(&(p as u32)).copied()];
            finders
                .iter()
                .filter(|(phase, _)| phases.contains(&Some(*phase)))
                .filter_map(|(_, f)| f.nearest(x))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, axis)| axis)
        })
        .collect()
}

/// The shapes of one entry binned by centre on a grid of cells no narrower than their largest
/// diameter, so that a shape holding a point, or within a radius of it, is in one of the 27
/// bins round the point's.
struct ShapeFinder<'a> {
    shapes: &'a [Inclusion],
    lo: demcon_core::Vec3,
    cell: f64,
    dims: [i64; 3],
    bins: std::collections::HashMap<[i64; 3], Vec<usize>>,
    period: Option<[f64; 3]>,
}

impl<'a> ShapeFinder<'a> {
    fn new(shapes: &'a [Inclusion], container: &Container) -> Self {
        let b = container.bounds();
        let extent = b.max - b.min;
        let cell = shapes
            .iter()
            .map(|s| 2.0 * s.circumradius())
            .fold(f64::MIN_POSITIVE, f64::max);
        let dims = [0, 1, 2].map(|k| ((extent[k] / cell).floor() as i64).max(1));
        let mut f = Self {
            shapes,
            lo: b.min,
            cell,
            dims,
            bins: std::collections::HashMap::new(),
            period: container.period(),
        };
        for (i, s) in shapes.iter().enumerate() {
            let key = f.bin(&s.centre());
            f.bins.entry(key).or_default().push(i);
        }
        f
    }

    fn bin(&self, x: &demcon_core::Vec3) -> [i64; 3] {
        [0, 1, 2].map(|k| (((x[k] - self.lo[k]) / self.cell).floor() as i64).clamp(0, self.dims[k] - 1))
    }

    /// The signed distance (m) to the nearest shape of the 27 bins round `x`, and its axis.
    fn nearest(&self, x: &demcon_core::Vec3) -> Option<(f64, demcon_core::Vec3)> {
        let home = self.bin(x);
        let mut keys = Vec::with_capacity(27);
        for d in 0..27i64 {
            let off = [d % 3 - 1, (d / 3) % 3 - 1, d / 9 - 1];
            let key = [0, 1, 2].map(|k| {
                let i = home[k] + off[k];
                if self.period.is_some() {
                    i.rem_euclid(self.dims[k])
                } else {
                    i
                }
            });
            if !keys.contains(&key) {
                keys.push(key);
            }
        }
        keys.iter()
            .filter_map(|key| self.bins.get(key))
            .flatten()
            .map(|&i| {
                let s = &self.shapes[i];
                let c = s.centre();
                let mut d = x - c;
                if let Some(l) = self.period {
                    for k in 0..3 {
                        d[k] -= l[k] * (d[k] / l[k]).round();
                    }
                }
                (s.signed_distance(&(c + d)), s.axis())
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }
}
