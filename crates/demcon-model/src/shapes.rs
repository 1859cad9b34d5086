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
