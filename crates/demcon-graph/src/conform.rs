//! Conforming seeds: sites placed in mirrored pairs across sphere surfaces, so that the
//! tessellation puts facets *on* each surface (the VoroCrust construction, Abdelkader et al.,
//! ACM TOG 39(3) 2020; `shared/DESIGN.md` §1, "Surfaces that cut cells").
//!
//! For each sphere (centre c, radius r) the surface is sampled at N Fibonacci points n_k (unit
//! normals; N from the sampling spacing `spacing · h`, h the mean site spacing) and two seeds
//! of equal weight are placed at c + (r' ∓ δ) n_k, δ = `offset · h`: their power plane is the
//! tangent plane n_k·(x − c) = r', so the cells of the inner seeds form a polyhedron around
//! the sphere whose faces are those tangent planes. r' is chosen so that the polyhedron of the
//! N tangent planes has the sphere's volume: r' = r (4π/3 / V₁)^{1/3}, V₁ the volume of
//! {x : n_k·x ≤ 1 ∀k} (without it the circumscribed polyhedron's extra volume costs +0.17 % on
//! a composite's ETC, measured on the design probe). Packing sites whose sphere comes within
//! 2δ of a seeded sphere (radius r') are removed, so no seed overlaps a site and every site
//! left is wholly on one side. Every cell is then of one phase, its facets perpendicular to their branches: a
//! homogeneous body stays exact, and the interface law sits on facets that lie on the surface.
//!
//! Spheroids and cylinders are sampled in rings along their meridian
//! (`crate::shape_samples`) and their pairs sit `shape_offset · h` from the surface (a tenth of
//! h by default: thin shapes are then resolved by more cells).
//!
//! Where another sphere comes within δ / 0.24 of a sample point, the pair closes in on the
//! surface (its offset, and its seeds' radius, 0.24 × the gap): both spheres' pairs then fit
//! side by side in the gap, so both surfaces keep their facets and the matrix between nearly
//! touching spheres keeps cells of its own. A pair squeezed
//! below 0.05 δ, a sample inside another sphere, and a pair that would overlap a seed already
//! placed are dropped (counted). In a periodic box the seeds are wrapped into the cell and the
//! distances to the surfaces are minimum-image; in a walled container (box, cylinder, sphere), a
//! pair with a seed whose ball leaves it is dropped, and the samples of a plane outside it are
//! not surface of the body (skipped, not counted). Every drop is counted in the report.

use demcon_core::{Container, CoreError, ParticleSet, Region, Vec3};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree};

use crate::crack::CrackShape;
use crate::error::GraphError;

/// The smallest seed offset, as a fraction of δ: a pair squeezed closer than this to its
/// surface (two spheres almost touching) is dropped and the gap left to the cells around.
const MIN_OFFSET: f64 = 0.05;

/// Where another surface comes within `δ / NARROW`, a pair's offset (and its seeds' radius)
/// is `NARROW × gap`: the pairs of two nearly touching spheres then fit side by side in the gap
/// between them (offset + radius on each side, 4 × 0.24 = 0.96 of the gap) without overlapping,
/// so both surfaces keep their facets and the matrix sliver its cells. Chosen by that
/// geometry; 0.4 (the pairs of the second sphere then overlap the first's and are dropped)
/// measured −1.2 % on the f = 0.5 random composites at 6·10⁴ sites, 0.24 −0.28 %.
const NARROW: f64 = 0.24;

/// The largest relative shrink of a pair's radius below its offset (see [`excess`]).
const EXCESS: f64 = 0.02;

/// How much the radius ρ of the `sample`-th pair of a surface falls below its offset d:
/// ρ = d (1 − excess). Along the pair's tangent plane both seeds have the power
/// |x − c|² − r'² + d² − ρ² (for any d and n), so with ρ = d every pair of a sphere has the same
/// power along its plane, and four cells meet on each edge of the tangent polyhedron (six or
/// more at its vertices): a degeneracy that can leave a cell "planes meeting within round-off".
/// A per-sample excess d² − ρ² ≈ 2 excess d² (a low-discrepancy sequence in the sample index, so
/// the same for a moved or permuted microstructure) breaks the tie: the facets stay on the
/// tangent planes, the polyhedron's edges are bevelled by ~0.08 excess h (≤ 2·10⁻³ h).
fn excess(sample: usize) -> f64 {
    EXCESS * ((sample as f64 + 1.0) * 0.618_033_988_749_894_8).fract()
}

/// Parameters of [`conforming_sites`], as fractions of the mean site spacing h.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConformParams {
    /// Spacing of the surface samples (fraction of h). Default 0.8.
    pub spacing: f64,
    /// Distance δ of each seed from its surface along the normal (fraction of h), for spheres,
    /// planes and cracks. Default 0.25.
    pub offset: f64,
    /// The same distance for shaped inclusions (spheroids, cylinders; fraction of h). Default
    /// 0.1: see [`SHAPE_OFFSET`].
    pub shape_offset: f64,
}

/// The default seed offset across a shaped inclusion's surface (fraction of h). The packing
/// sites within 2δ of a surface are removed, so the offset sets how thick a layer of seed cells
/// lines the surface before the packing's own cells resume, and how many cells resolve a thin
/// part. On four platelets 2.3 h thick in a periodic cell (made for the purpose, not a
/// validation microstructure), against our voxel FFT, λ_zz at contrast 0.1 read +0.86 % with
/// δ = 0.25 h, +0.62 % with 0.1 h, +0.55 % with 0.06 h (λ_xx at contrast 10: +0.37, +0.21,
/// +0.16 %); 3.7 h thick, +0.33, +0.18, +0.15 %. Thick shapes (5.8 h and more) moved by
/// ≤ 0.04 %. 0.1 takes most of the gain (`validation/notes/shapes-aligned.md`).
const SHAPE_OFFSET: f64 = 0.1;

impl Default for ConformParams {
    fn default() -> Self {
        Self {
            spacing: 0.8,
            offset: 0.25,
            shape_offset: SHAPE_OFFSET,
        }
    }
}

/// A sphere whose surface the tessellation must follow: centre (m) and radius (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereSurface {
    /// Centre (m).
    pub centre: Vec3,
    /// Radius (m).
    pub radius: f64,
}

/// A flat surface the tessellation must follow.
#[derive(Debug, Clone, PartialEq)]
pub enum PlanePatch {
    /// A rectangle normal to coordinate axis `axis` at `at` along it (m), covering `[lo, hi]`
    /// (m) on the two other axes in cyclic order (axis + 1, axis + 2): a face of an
    /// axis-aligned box region, clipped to the container.
    Rect {
        /// The normal axis (0, 1, 2 for x, y, z).
        axis: usize,
        /// Position along the normal axis (m).
        at: f64,
        /// Lower corner on the axes (axis + 1, axis + 2) mod 3 (m).
        lo: [f64; 2],
        /// Upper corner on the same axes (m).
        hi: [f64; 2],
    },
    /// A crack's surface (disc or plane polygon, any orientation).
    Crack(CrackShape),
}

impl PlanePatch {
    /// A point of the patch's plane (m), its unit normal and two unit tangents (u, v, n
    /// right-handed).
    fn frame(&self) -> (Vec3, Vec3, Vec3, Vec3) {
        match self {
            PlanePatch::Rect { axis, at, lo, hi } => {
                let [u, v] = [(axis + 1) % 3, (axis + 2) % 3];
                let mut origin = Vec3::zeros();
                origin[*axis] = *at;
                origin[u] = 0.5 * (lo[0] + hi[0]);
                origin[v] = 0.5 * (lo[1] + hi[1]);
                let unit = |k: usize| {
                    let mut e = Vec3::zeros();
                    e[k] = 1.0;
                    e
                };
                (origin, unit(*axis), unit(u), unit(v))
            }
            PlanePatch::Crack(shape) => {
                let (c, n) = shape.plane();
                let origin = shape.bounding_ball().0;
                let origin = origin - n * n.dot(&(origin - c));
                let helper = if n.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
                let u = n.cross(&helper).normalize();
                (origin, n, u, n.cross(&u))
            }
        }
    }

    /// Half-extents (m) along u and v of a box holding the patch around its origin.
    fn half_extents(&self) -> [f64; 2] {
        match self {
            PlanePatch::Rect { lo, hi, .. } => [0.5 * (hi[0] - lo[0]), 0.5 * (hi[1] - lo[1])],
            PlanePatch::Crack(shape) => [shape.bounding_ball().1; 2],
        }
    }

    /// Whether the in-plane point at (a, b) (m, along u and v from the origin) is on the patch.
    fn contains(&self, a: f64, b: f64) -> bool {
        match self {
            PlanePatch::Rect { .. } => {
                let [hu, hv] = self.half_extents();
                a.abs() <= hu && b.abs() <= hv
            }
            PlanePatch::Crack(shape) => {
                let (origin, n, u, v) = self.frame();
                shape.contains_planar(&n, &(origin + u * a + v * b))
            }
        }
    }

    /// Distance (m) from `x` to the patch; `offset` gives the minimum-image vector between two
    /// points, so a patch that spans a period is met through the box's faces. Exact for a
    /// rectangle and a disc; for a polygon the distance to its bounding disc off the polygon.
    fn distance(&self, x: &Vec3, offset: &dyn Fn(&Vec3, &Vec3) -> Vec3) -> f64 {
        let (origin, n, u, v) = self.frame();
        let d = offset(&origin, x);
        let (a, b, c) = (d.dot(&u), d.dot(&v), d.dot(&n));
        let outside = match self {
            PlanePatch::Rect { .. } => {
                let [hu, hv] = self.half_extents();
                let (du, dv) = ((a.abs() - hu).max(0.0), (b.abs() - hv).max(0.0));
                (du * du + dv * dv).sqrt()
            }
            PlanePatch::Crack(_) if self.contains(a, b) => 0.0,
            PlanePatch::Crack(_) => ((a * a + b * b).sqrt() - self.half_extents()[0]).max(0.0),
        };
        (c * c + outside * outside).sqrt()
    }

    /// The unit normal and the sample points (m): the cell centres of an equal division of
    /// the patch's box in squares of side at most `spacing`, those on the patch (so a
    /// rectangle spanning a period repeats with it).
    fn samples(&self, spacing: f64) -> (Vec3, Vec<Vec3>) {
        let (origin, n, u, v) = self.frame();
        let half = self.half_extents();
        let counts = half.map(|h| ((2.0 * h / spacing).ceil() as usize).max(1));
        let mut points = Vec::with_capacity(counts[0] * counts[1]);
        for i in 0..counts[0] {
            for j in 0..counts[1] {
                let a = -half[0] + (i as f64 + 0.5) * 2.0 * half[0] / counts[0] as f64;
                let b = -half[1] + (j as f64 + 0.5) * 2.0 * half[1] / counts[1] as f64;
                if self.contains(a, b) {
                    points.push(origin + u * a + v * b);
                }
            }
        }
        (n, points)
    }
}

/// What [`conforming_sites`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConformReport {
    /// Spheres followed.
    pub spheres: usize,
    /// Plane patches followed (box faces, voxel faces, cracks).
    pub planes: usize,
    /// Shaped inclusions followed.
    pub shapes: usize,
    /// The mean site spacing h (m) the sampling was scaled by.
    pub spacing_m: f64,
    /// Seeds placed.
    pub seeds: usize,
    /// Seeds dropped: within δ of another sphere's surface, overlapping a seed already
    /// placed, or leaving a walled container.
    pub dropped_seeds: usize,
    /// Packing sites removed because their sphere came within 2δ of a surface.
    pub removed_sites: usize,
    /// Seed pairs placed closer to their surface than δ, where another sphere came near.
    pub narrowed_pairs: usize,
    /// Largest relative correction 1 − r'/r of a sphere's tangent-plane radius.
    pub max_radius_correction: f64,
}

/// The sites of a tessellation that follows the spheres' surfaces: the packing's sites kept
/// (in their order), then the seeds.
#[derive(Debug, Clone)]
pub struct Conformed {
    /// Kept packing particles (their radii), then the seeds (radius δ).
    pub particles: ParticleSet,
    /// For each kept packing particle, its index in the input.
    pub kept: Vec<u32>,
    /// Seeds at the end of `particles`.
    pub n_seeds: usize,
    /// What was done.
    pub report: ConformReport,
}

/// Where the seeds may go: the container and, for a carved body, the carving region.
#[derive(Debug, Clone, Copy)]
pub struct Body<'a> {
    /// The container (periodic or walled).
    pub container: &'a Container,
    /// The carving region, when the body is carved out of the container.
    pub carve: Option<&'a Region>,
}

impl Body<'_> {
    /// How deep `x` lies inside the body (m): the distance to its nearest wall or to the
    /// carving region's boundary, negative outside; +∞ in a periodic box without carving.
    fn depth(&self, x: &Vec3) -> f64 {
        let carved = self.carve.map_or(f64::INFINITY, |r| -r.signed_distance(x));
        self.container.wall_distance(x).min(carved)
    }
}

/// Refuses spacing and offset outside (0, 1), a bad site spacing `h`, sphere radius or plane
/// patch, naming the field.
fn check_inputs(
    spheres: &[SphereSurface],
    planes: &[PlanePatch],
    h: f64,
    params: &ConformParams,
) -> Result<(), GraphError> {
    for (field, v) in [
        ("conform.spacing", params.spacing),
        ("conform.offset", params.offset),
        ("conform.shape_offset", params.shape_offset),
    ] {
        if !(v > 0.0 && v < 1.0) {
            return Err(
                CoreError::invalid(field, v, "must be in (0, 1) (fraction of the site spacing)").into(),
            );
        }
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(CoreError::invalid("conform.h", h, "must be a finite spacing > 0 (m)").into());
    }
    if let Some((i, s)) = spheres
        .iter()
        .enumerate()
        .find(|(_, s)| !(s.radius.is_finite() && s.radius > 0.0))
    {
        return Err(CoreError::invalid(format!("spheres[{i}].radius"), s.radius, "must be > 0 (m)").into());
    }
    if let Some((i, p)) = planes.iter().enumerate().find(|(_, p)| match p {
        PlanePatch::Rect { axis, at, lo, hi } => {
            !(*axis < 3 && at.is_finite() && (0..2).all(|k| lo[k].is_finite() && hi[k] > lo[k]))
        }
        PlanePatch::Crack(shape) => shape.validate("crack").is_err(),
    }) {
        return Err(CoreError::invalid(
            format!("planes[{i}]"),
            format!("{p:?}"),
            "must have an axis 0–2, a finite position and a non-empty rectangle (m)",
        )
        .into());
    }
    Ok(())
}

/// Places conforming seeds across every sphere of `spheres` and plane of `planes` and removes
/// the packing sites that would overlap them (see the module doc), the seeds inside `body`.
/// `h` is the mean site spacing (m): (V/N)^{1/3}.
///
/// # Errors
/// A non-finite or non-positive radius or spacing; parameters out of (0, 1).
pub fn conforming_sites(
    particles: &ParticleSet,
    body: Body,
    surfaces: Followed,
    h: f64,
    params: &ConformParams,
) -> Result<Conformed, GraphError> {
    let Followed {
        spheres,
        planes,
        shapes,
    } = surfaces;
    check_inputs(spheres, planes, h, params)?;
    let container = body.container;
    if spheres.is_empty() && planes.is_empty() && shapes.is_empty() {
        return Ok(Conformed::unchanged(particles, h));
    }
    let delta = params.offset * h;
    let shape_delta = params.shape_offset * h;
    let period = container.period();
    let offset = |a: &Vec3, b: &Vec3| min_image(period, a, b);
    let wrap = |x: Vec3| wrap_into(period, x);
    // Distance from x to the surface of sphere s (positive outside).
    let surface_distance = |x: &Vec3, s: &SphereSurface| offset(&s.centre, x).norm() - s.radius;
    let mut report = ConformReport {
        spheres: spheres.len(),
        planes: planes.len(),
        shapes: shapes.len(),
        spacing_m: h,
        ..ConformReport::default()
    };
    // Each sphere's samples and tangent-plane radius r'.
    let sample = params.spacing * h;
    let sites = SiteIndex::new(particles, container, 3.0 * h);
    let sampled = sample_spheres(particles, &sites, spheres, sample, &offset);
    // The packing sites that stay: wholly farther than 2δ from every seeded sphere (of radius
    // r', where the seeds sit at ±δ: no seed then overlaps a site).
    // The spheres indexed by their boxes (periodic images included), inflated by the farthest
    // reach of a query: a site's radius + 2δ, and the δ / NARROW within which another surface
    // narrows a pair.
    let r_max = particles.radii.iter().copied().fold(0.0, f64::max);
    let index = SphereIndex::new(
        spheres.iter().zip(&sampled).map(|(s, (_, r_t))| (s.centre, *r_t)),
        container,
        (r_max + 2.0 * delta).max(delta / NARROW),
    );
    let shaped = ShapeSurfaces::new(
        shapes,
        container,
        (r_max + 2.0 * delta).max(delta / NARROW),
        sample,
    );
    let mut seeder = Seeder {
        seeds: Vec::new(),
        seed_radii: Vec::new(),
        grid: SeedGrid::new(2.0 * delta, period),
        delta,
        shape_delta,
        period,
        body: &body,
    };
    let mut kept = seeder.kept_sites(particles, &index, spheres, &sampled, planes, &mut report);
    // … and farther than 2δ (the shapes' δ) from every shape's moved surface.
    kept.retain(|&p| {
        let reach = particles.radii[p as usize] + 2.0 * shape_delta;
        let near = shaped.within(&particles.centres[p as usize], reach);
        report.removed_sites += usize::from(near);
        !near
    });
    let shapes_gap = |at: &Vec3, skip: Option<usize>| shaped.gap(at, skip);
    let plane_gaps = PlaneGaps::new(planes, period, h);
    let plane_gap = |at: &Vec3, skip: Option<usize>| plane_gaps.gap(at, skip);
    // Spheres and planes meet the shapes as other surfaces.
    let others_gap = |at: &Vec3, skip: Option<usize>| plane_gap(at, skip).min(shapes_gap(at, None));
    seeder.seed_spheres(spheres, &sampled, &index, &others_gap, &mut report);
    // The planes: a square lattice of samples at the spheres' spacing.
    let spheres_gap = |at: &Vec3| {
        index
            .near(&wrap(*at))
            .map(|o| surface_distance(at, &spheres[o]))
            .fold(f64::INFINITY, f64::min)
    };
    for (pi, pl) in planes.iter().enumerate() {
        let (n, points) = pl.samples(sample);
        for (k, at) in points.into_iter().enumerate() {
            // A crack reaching past a wall: its part outside the body is no surface.
            if body.depth(&at) < 0.0 {
                continue;
            }
            let unsigned = index
                .near(&wrap(at))
                .map(|o| surface_distance(&at, &spheres[o]).abs())
                .fold(f64::INFINITY, f64::min);
            let gap = unsigned.min(others_gap(&at, Some(pi)));
            seeder.place(at, n, gap, seeder.delta, k, &mut report);
        }
    }
    seeder.seed_shapes(
        &shaped,
        &|at| spheres_gap(at).min(plane_gap(at, None)),
        &mut report,
    );
    let Seeder {
        seeds, seed_radii, ..
    } = seeder;
    report.seeds = seeds.len();
    let n_seeds = seeds.len();
    Ok(Conformed {
        particles: with_seeds(particles, &kept, seeds, seed_radii)?,
        kept,
        n_seeds,
        report,
    })
}

impl Conformed {
    /// Nothing to follow: every site of `particles` stays (`h`: the site spacing, m).
    fn unchanged(particles: &ParticleSet, h: f64) -> Self {
        Self {
            particles: particles.clone(),
            kept: (0..particles.len() as u32).collect(),
            n_seeds: 0,
            report: ConformReport {
                spacing_m: h,
                ..ConformReport::default()
            },
        }
    }
}

/// A sample of a shape's surface: point, outward normal and its pair's room (m; `Sample::room`).
type ShapeSample = (Vec3, Vec3, f64);

/// The shapes' samples (point, outward normal, room; m) at `sample` spacing (m), each
/// tangent plane moved in by the polyhedron's excess volume for its area and curvature, and
/// each shape's largest move (m).
fn moved_shape_samples(shapes: &[demcon_core::Inclusion], sample: f64) -> (Vec<Vec<ShapeSample>>, Vec<f64>) {
    let shrink = tangent_shrink();
    let samples: Vec<Vec<ShapeSample>> = shapes
        .iter()
        .map(|shape| {
            crate::shape_samples::surface_samples(shape, sample)
                .into_iter()
                .map(|smp| {
                    // At most 0.1 of the radius of curvature (a sphere sampled at only 12
                    // points moves by 0.09 r): where the samples are coarser than the
                    // curvature (a platelet's rim) the linear estimate would overshoot.
                    let inward =
                        (shrink * smp.area * smp.curvature).clamp(0.0, 0.1 / smp.curvature.max(1e-300));
                    (smp.at - smp.normal * inward, smp.normal, smp.room)
                })
                .collect()
        })
        .collect();
    let moved = shapes
        .iter()
        .zip(&samples)
        .map(|(shape, smp)| {
            smp.iter()
                .map(|(at, _, _)| -shape.signed_distance(at))
                .fold(0.0, f64::max)
        })
        .collect();
    (samples, moved)
}

/// The shaped inclusions, indexed by their circumscribed balls, with their moved samples.
struct ShapeSurfaces<'a> {
    shapes: &'a [demcon_core::Inclusion],
    index: SphereIndex,
    /// Per shape: its samples (point, outward normal, room; m), moved in.
    samples: Vec<Vec<ShapeSample>>,
    /// Per shape: its samples' largest inward move (m).
    moved: Vec<f64>,
    period: Option<[f64; 3]>,
}

impl<'a> ShapeSurfaces<'a> {
    /// `reach`: the farthest a query looks past a ball (m); `sample`: the sample spacing (m).
    fn new(shapes: &'a [demcon_core::Inclusion], container: &Container, reach: f64, sample: f64) -> Self {
        let index = SphereIndex::new(
            shapes.iter().map(|s| (s.centre(), s.circumradius())),
            container,
            reach,
        );
        let (samples, moved) = moved_shape_samples(shapes, sample);
        Self {
            shapes,
            index,
            samples,
            moved,
            period: container.period(),
        }
    }

    /// Signed distance (m) from `x` to shape `k`'s surface (minimum image).
    fn distance(&self, x: &Vec3, k: usize) -> f64 {
        let c = self.shapes[k].centre();
        self.shapes[k].signed_distance(&(c + min_image(self.period, &c, x)))
    }

    /// Whether `x` is within `reach` (m) of a shape's moved surface.
    fn within(&self, x: &Vec3, reach: f64) -> bool {
        self.index
            .near(&wrap_into(self.period, *x))
            .any(|k| self.distance(x, k).abs() < reach + self.moved[k])
    }

    /// The signed distance (m) from `at` to the nearest shape other than `skip`.
    fn gap(&self, at: &Vec3, skip: Option<usize>) -> f64 {
        self.index
            .near(&wrap_into(self.period, *at))
            .filter(|&k| skip != Some(k))
            .map(|k| self.distance(at, k))
            .fold(f64::INFINITY, f64::min)
    }
}

/// The unsigned distance from a point to the plane patches other than one (`skip`) and those
/// in the same plane as it (the pieces of one crack, two boxes sharing a face: one surface,
/// whose samples meet only through the seed-overlap check).
struct PlaneGaps<'a> {
    planes: &'a [PlanePatch],
    /// Each patch's origin and normal.
    frames: Vec<(Vec3, Vec3)>,
    period: Option<[f64; 3]>,
    /// The site spacing (m): coplanar within 10⁻⁹ of it.
    h: f64,
}

impl<'a> PlaneGaps<'a> {
    fn new(planes: &'a [PlanePatch], period: Option<[f64; 3]>, h: f64) -> Self {
        let frames = planes
            .iter()
            .map(|pl| {
                let (origin, n, _, _) = pl.frame();
                (origin, n)
            })
            .collect();
        Self {
            planes,
            frames,
            period,
            h,
        }
    }

    fn coplanar(&self, a: usize, b: usize) -> bool {
        let ((oa, na), (ob, nb)) = (self.frames[a], self.frames[b]);
        na.dot(&nb).abs() > 1.0 - 1e-9 && na.dot(&min_image(self.period, &oa, &ob)).abs() <= 1e-9 * self.h
    }

    /// The distance (m) from `at` to the patches other than `skip` and its plane's.
    fn gap(&self, at: &Vec3, skip: Option<usize>) -> f64 {
        let offset = |a: &Vec3, b: &Vec3| min_image(self.period, a, b);
        self.planes
            .iter()
            .enumerate()
            .filter(|&(k, _)| skip.is_none_or(|s| s != k && !self.coplanar(s, k)))
            .map(|(_, pl)| pl.distance(at, &offset))
            .fold(f64::INFINITY, f64::min)
    }
}

/// Minimum-image offset from a to b in a box of period `period` (the plain difference without).
fn min_image(period: Option<[f64; 3]>, a: &Vec3, b: &Vec3) -> Vec3 {
    let mut d = b - a;
    if let Some(l) = period {
        for k in 0..3 {
            d[k] -= l[k] * (d[k] / l[k]).round();
        }
    }
    d
}

/// `x` wrapped into the periodic cell (unchanged without a period).
fn wrap_into(period: Option<[f64; 3]>, x: Vec3) -> Vec3 {
    match period {
        Some(l) => Vec3::new(x.x.rem_euclid(l[0]), x.y.rem_euclid(l[1]), x.z.rem_euclid(l[2])),
        None => x,
    }
}

/// The inward move Δ of a tangent plane per unit (sample area × mean curvature): the one that
/// gives a sphere's tangent polyhedron the sphere's volume (r − r' of [`sample_spheres`], for
/// 1 000 samples of the unit sphere: Δ = 1 − (4π/3 / V₁)^{1/3} over an area of 4π/1000 each).
fn tangent_shrink() -> f64 {
    let n = 1000;
    let v1 = crate::laguerre::tangent_polyhedron_volume(&fibonacci_sphere(n));
    let delta = 1.0 - (4.0 / 3.0 * std::f64::consts::PI / v1).cbrt();
    delta / (4.0 * std::f64::consts::PI / n as f64)
}

/// The shape's thickness (m) behind a sample: twice the depth of the middle of the chord from
/// `at` inwards along `-normal` (the inscribed ball there; the chord itself where shorter), or
/// `reach` (m) when the chord is longer than that. A thin part (a platelet's faces, a fibre's
/// sides) is a gap its two faces' pairs share, as two nearly touching spheres share theirs:
/// each pair then sits within `NARROW` × the thickness of its face and the two fit side by side.
fn thickness(shape: &demcon_core::Inclusion, at: &Vec3, normal: &Vec3, reach: f64) -> f64 {
    let depth = |t: f64| -shape.signed_distance(&(at - normal * t));
    if depth(reach) > 0.0 && depth(0.5 * reach) >= 0.5 * reach {
        return reach;
    }
    // Convex shapes: one crossing in (0, reach], found by bisection to 2⁻⁴⁰ of `reach`.
    let (mut lo, mut hi) = (0.0, reach);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if depth(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let chord = 0.5 * (lo + hi);
    chord.min(2.0 * depth(0.5 * chord))
}

/// The distance (m) from `at` to the surfaces of `shape`'s periodic images (+∞ without a
/// period): a long shape meets its own images.
fn self_gap(shape: &demcon_core::Inclusion, at: &Vec3, period: Option<[f64; 3]>) -> f64 {
    let Some(l) = period else {
        return f64::INFINITY;
    };
    (0..27)
        .filter(|&k| k != 13)
        .map(|k| {
            let shift = Vec3::new(
                ((k % 3) as f64 - 1.0) * l[0],
                (((k / 3) % 3) as f64 - 1.0) * l[1],
                ((k / 9) as f64 - 1.0) * l[2],
            );
            shape.signed_distance(&(at - shift))
        })
        .fold(f64::INFINITY, f64::min)
}

/// The surfaces the conforming seeds follow.
#[derive(Debug, Clone, Copy, Default)]
pub struct Followed<'a> {
    /// Spheres.
    pub spheres: &'a [SphereSurface],
    /// Plane patches (box faces, voxel faces, cracks).
    pub planes: &'a [PlanePatch],
    /// Shaped inclusions (spheroids, cylinders).
    pub shapes: &'a [demcon_core::Inclusion],
}

/// The seeds placed so far, on a grid that finds their neighbours.
struct Seeder<'b> {
    seeds: Vec<Vec3>,
    seed_radii: Vec<f64>,
    grid: SeedGrid,
    /// The pair offset δ of spheres and planes (m).
    delta: f64,
    /// The pair offset δ of shapes (m).
    shape_delta: f64,
    period: Option<[f64; 3]>,
    body: &'b Body<'b>,
}

impl Seeder<'_> {
    /// The packing sites that stay: wholly farther than 2δ from every seeded sphere (of radius
    /// r', where the seeds sit at ±δ: no seed then overlaps a site) and every plane patch.
    fn kept_sites(
        &self,
        particles: &ParticleSet,
        index: &SphereIndex,
        spheres: &[SphereSurface],
        sampled: &[(Vec<Vec3>, f64)],
        planes: &[PlanePatch],
        report: &mut ConformReport,
    ) -> Vec<u32> {
        let (delta, period) = (self.delta, self.period);
        let offset = |a: &Vec3, b: &Vec3| min_image(period, a, b);
        let mut kept = Vec::new();
        for p in 0..particles.len() {
            let x = &particles.centres[p];
            let reach = particles.radii[p] + 2.0 * delta;
            let near = index.near(&wrap_into(period, *x)).any(|k| {
                let (s, (_, r_t)) = (&spheres[k], &sampled[k]);
                (offset(&s.centre, x).norm() - r_t).abs() < reach
            }) || planes.iter().any(|pl| pl.distance(x, &offset) < reach);
            if near {
                report.removed_sites += 1;
            } else {
                kept.push(p as u32);
            }
        }
        kept
    }

    /// A pair at each sample of every sphere: δ, or less where another surface comes close
    /// (`plane_gap(at, skip)`: the distance to the plane patches).
    fn seed_spheres(
        &mut self,
        spheres: &[SphereSurface],
        sampled: &[(Vec<Vec3>, f64)],
        index: &SphereIndex,
        plane_gap: &dyn Fn(&Vec3, Option<usize>) -> f64,
        report: &mut ConformReport,
    ) {
        let period = self.period;
        for (si, (s, (normals, r_t))) in spheres.iter().zip(sampled).enumerate() {
            let r_t = *r_t;
            report.max_radius_correction = report.max_radius_correction.max(1.0 - r_t / s.radius);
            for (k, n) in normals.iter().enumerate() {
                // Where another surface comes close, the pair closes in on the surface: δ at most
                // NARROW × the gap to it (so the other surface's pair fits in the gap too); a
                // sample inside another sphere is no interface and gets no pair.
                let at = s.centre + n * r_t;
                // Spheres farther than δ / NARROW leave the pair at δ: only the near ones are read.
                let others = index
                    .near(&wrap_into(period, at))
                    .filter(|&o| o != si)
                    .map(|o| min_image(period, &spheres[o].centre, &at).norm() - spheres[o].radius);
                // In a periodic box the sphere's own images are neighbours too.
                let images = period.into_iter().flat_map(|l| {
                    (0..27).filter(|&k| k != 13).map(move |k| {
                        let shift = Vec3::new(
                            (k % 3) as f64 - 1.0,
                            ((k / 3) % 3) as f64 - 1.0,
                            (k / 9) as f64 - 1.0,
                        )
                        .component_mul(&Vec3::new(l[0], l[1], l[2]));
                        (at - s.centre - shift).norm() - s.radius
                    })
                });
                let gap = others.chain(images).fold(plane_gap(&at, None), f64::min);
                self.place(at, *n, gap, self.delta, k, report);
            }
        }
    }

    /// A pair at each sample of every shape: δ, or less where another shape, its own periodic
    /// image, or another surface (`others_gap(at)`, m) comes close, where the rings are closer
    /// than the spacing (a sharp rim: pairs within half the room between rings), or where the
    /// shape is thin (its two faces share the thickness).
    fn seed_shapes(
        &mut self,
        shaped: &ShapeSurfaces,
        others_gap: &dyn Fn(&Vec3) -> f64,
        report: &mut ConformReport,
    ) {
        for (k, shape) in shaped.shapes.iter().enumerate() {
            report.max_radius_correction = report
                .max_radius_correction
                .max(shaped.moved[k] / shape.circumradius());
            for (j, &(at, normal, room)) in shaped.samples[k].iter().enumerate() {
                if self.body.depth(&at) < 0.0 {
                    report.dropped_seeds += 2;
                    continue;
                }
                let gap = others_gap(&at)
                    .min(shaped.gap(&at, Some(k)))
                    .min(self_gap(shape, &at, self.period))
                    .min(0.5 * room / NARROW)
                    .min(thickness(shape, &at, &normal, self.shape_delta / NARROW));
                self.place(
                    wrap_into(self.period, at),
                    normal,
                    gap,
                    self.shape_delta,
                    j,
                    report,
                );
            }
        }
    }

    /// Places the pair of a sample `at` on a surface of normal `n` whose nearest other surface
    /// is `gap` away (≤ 0: inside another sphere, no interface there), at the surface's offset
    /// `delta` (m) or closer.
    fn place(&mut self, at: Vec3, n: Vec3, gap: f64, delta: f64, sample: usize, report: &mut ConformReport) {
        let period = self.period;
        if gap <= 0.0 {
            report.dropped_seeds += 2;
            return;
        }
        let d = delta.min(NARROW * gap);
        let pair = [-1.0, 1.0].map(|side| wrap_into(period, at + n * (side * d)));
        // Each seed's ball inside the body (curved walls and carving included).
        let inside = pair.iter().all(|x| self.body.depth(x) >= d);
        let offset = |a: &Vec3, b: &Vec3| min_image(period, a, b);
        if !inside
            || d < MIN_OFFSET * delta
            || pair
                .iter()
                .any(|x| self.grid.too_close(x, d, &self.seeds, &self.seed_radii, &offset))
        {
            report.dropped_seeds += 2;
            return;
        }
        if d < delta {
            report.narrowed_pairs += 1;
        }
        for x in pair {
            self.grid.insert(&x, self.seeds.len());
            self.seeds.push(x);
            self.seed_radii.push(d * (1.0 - excess(sample)));
        }
    }
}

/// The kept packing sites of `particles` followed by the seeds (phase 0).
fn with_seeds(
    particles: &ParticleSet,
    kept: &[u32],
    seeds: Vec<Vec3>,
    seed_radii: Vec<f64>,
) -> Result<ParticleSet, GraphError> {
    let mut centres: Vec<Vec3> = kept.iter().map(|&p| particles.centres[p as usize]).collect();
    let mut radii: Vec<f64> = kept.iter().map(|&p| particles.radii[p as usize]).collect();
    let mut phases: Vec<u16> = kept.iter().map(|&p| particles.phases[p as usize]).collect();
    centres.extend_from_slice(&seeds);
    radii.extend_from_slice(&seed_radii);
    phases.extend(std::iter::repeat_n(0, seeds.len()));
    let mut out = ParticleSet::new(centres, radii)?;
    out.phases = phases;
    Ok(out)
}

/// Each sphere's sample normals (laid in its [`sampling_frame`], about one per `sample`² of
/// surface) and its tangent-plane radius r' (m): the radius whose tangent polyhedron holds the
/// sphere's volume.
fn sample_spheres(
    particles: &ParticleSet,
    sites: &SiteIndex,
    spheres: &[SphereSurface],
    sample: f64,
    offset: &dyn Fn(&Vec3, &Vec3) -> Vec3,
) -> Vec<(Vec<Vec3>, f64)> {
    // The tangent polyhedron's volume depends on the sample count alone: once per count.
    let mut volumes = std::collections::BTreeMap::new();
    spheres
        .iter()
        .map(|s| {
            let count = ((4.0 * std::f64::consts::PI * s.radius * s.radius)
                / (0.5 * 3f64.sqrt() * sample * sample))
                .round()
                .max(12.0) as usize;
            let local = fibonacci_sphere(count);
            let v1 = *volumes
                .entry(count)
                .or_insert_with(|| crate::laguerre::tangent_polyhedron_volume(&local));
            let frame = sampling_frame(particles, sites, &s.centre, offset);
            let normals = local
                .iter()
                .map(|n| frame[0] * n.x + frame[1] * n.y + frame[2] * n.z)
                .collect();
            (normals, s.radius * (4.0 / 3.0 * std::f64::consts::PI / v1).cbrt())
        })
        .collect()
}

/// The orthonormal frame a sphere's samples are laid in, taken from the packing around its
/// centre: the pole towards the nearest site, the first axis towards the next site not on the
/// pole's line, the second on the side of the third (ties by index). The sampling then moves
/// with the microstructure: a rotated, reflected, translated or permuted packing gets the
/// same seeds rotated, reflected, translated or permuted, so its answer is the same exactly.
/// Falls back to x, y, z when the packing has fewer than three sites.
fn sampling_frame(
    particles: &ParticleSet,
    sites: &SiteIndex,
    centre: &Vec3,
    offset: &dyn Fn(&Vec3, &Vec3) -> Vec3,
) -> [Vec3; 3] {
    let fallback = [Vec3::x(), Vec3::y(), Vec3::z()];
    // The eight nearest sites, by distance then index.
    let candidates = sites.nearest(centre, 8);
    let all = || 0..particles.len();
    let mut near: Vec<(f64, usize, Vec3)> = Vec::with_capacity(9);
    let ids: &mut dyn Iterator<Item = usize> = match &candidates {
        Some(ids) => &mut ids.iter().copied(),
        None => &mut all(),
    };
    for i in ids {
        let d = offset(centre, &particles.centres[i]);
        let r = d.norm();
        if r == 0.0 {
            continue;
        }
        if near.len() < 8 || (r, i) < (near[near.len() - 1].0, near[near.len() - 1].1) {
            let at = near.partition_point(|e| (e.0, e.1) <= (r, i));
            near.insert(at, (r, i, d / r));
            near.truncate(8);
        }
    }
    let Some(&(_, _, pole)) = near.first() else {
        return fallback;
    };
    let mut axes = near[1..].iter().filter_map(|&(_, _, d)| {
        let t = d - pole * d.dot(&pole);
        (t.norm() > 1e-3).then(|| t.normalize())
    });
    let Some(e1) = axes.next() else {
        return fallback;
    };
    let mut e2 = pole.cross(&e1);
    let side = near[1..]
        .iter()
        .map(|&(_, _, d)| d.dot(&e2))
        .find(|v| v.abs() > 1e-3)
        .unwrap_or(1.0);
    if side < 0.0 {
        e2 = -e2;
    }
    [e1, e2, pole]
}

/// The periodic images of a box's content that come within `margin` of the box (m): the
/// shifts (multiples of the periods) other than zero, and zero first.
fn image_shifts(container: &Container) -> Vec<Vec3> {
    let Some(l) = container.period() else {
        return vec![Vec3::zeros()];
    };
    let mut shifts = vec![Vec3::zeros()];
    for k in 0..27 {
        if k != 13 {
            let m = Vec3::new(
                (k % 3) as f64 - 1.0,
                ((k / 3) % 3) as f64 - 1.0,
                (k / 9) as f64 - 1.0,
            );
            shifts.push(m.component_mul(&Vec3::new(l[0], l[1], l[2])));
        }
    }
    shifts
}

/// The seeded spheres (radius r') and their periodic images, indexed by their boxes inflated
/// by a reach (rstar): [`SphereIndex::near`] yields every sphere whose surface may come
/// within the reach of a point of the box.
pub(crate) struct SphereIndex {
    tree: RTree<GeomWithData<Rectangle<[f64; 3]>, usize>>,
}

impl SphereIndex {
    pub(crate) fn new(spheres: impl Iterator<Item = (Vec3, f64)>, container: &Container, reach: f64) -> Self {
        let b = container.bounds();
        let shifts = image_shifts(container);
        let mut boxes = Vec::new();
        for (k, (c, r)) in spheres.enumerate() {
            for shift in &shifts {
                let lo = c + shift - Vec3::repeat(r + reach);
                let hi = c + shift + Vec3::repeat(r + reach);
                if (0..3).all(|a| lo[a] <= b.max[a] && hi[a] >= b.min[a]) {
                    boxes.push(GeomWithData::new(
                        Rectangle::from_corners(lo.into(), hi.into()),
                        k,
                    ));
                }
            }
        }
        Self {
            tree: RTree::bulk_load(boxes),
        }
    }

    /// The spheres near `x` (a point of the box), in no particular order, a sphere once per
    /// image near `x` (the callers take a minimum or an `any`, which neither changes).
    pub(crate) fn near(&self, x: &Vec3) -> impl Iterator<Item = usize> + '_ {
        self.tree
            .locate_in_envelope_intersecting(AABB::from_point([x.x, x.y, x.z]))
            .map(|g| g.data)
    }
}

/// The packing's sites and their periodic images within `margin` of the box, as points
/// (rstar), for nearest-site queries.
struct SiteIndex {
    tree: RTree<GeomWithData<[f64; 3], usize>>,
    margin: f64,
}

impl SiteIndex {
    fn new(particles: &ParticleSet, container: &Container, margin: f64) -> Self {
        let b = container.bounds();
        let shifts = image_shifts(container);
        let mut points = Vec::with_capacity(particles.len());
        for (i, c) in particles.centres.iter().enumerate() {
            for shift in &shifts {
                let x = c + shift;
                if (0..3).all(|a| x[a] >= b.min[a] - margin && x[a] <= b.max[a] + margin) {
                    points.push(GeomWithData::new([x.x, x.y, x.z], i));
                }
            }
        }
        Self {
            tree: RTree::bulk_load(points),
            margin,
        }
    }

    /// Every site at least as near `x` (a point of the box; minimum image) as its `k`-th
    /// nearest other than itself, ties included; `None` when they reach beyond the margin
    /// (the images indexed may then miss one: scan every site).
    fn nearest(&self, x: &Vec3, k: usize) -> Option<Vec<usize>> {
        let at = [x.x, x.y, x.z];
        let mut ids: Vec<usize> = Vec::new();
        let mut kth = f64::INFINITY;
        for (g, d2) in self.tree.nearest_neighbor_iter_with_distance_2(at) {
            if d2 > kth {
                break;
            }
            if d2 > 0.0 && !ids.contains(&g.data) {
                ids.push(g.data);
                if ids.len() == k {
                    kth = d2;
                }
            }
        }
        (ids.len() >= k && kth.sqrt() <= self.margin).then_some(ids)
    }
}

/// `n` points spread evenly on the unit sphere (the Fibonacci lattice).
pub fn fibonacci_sphere(n: usize) -> Vec<Vec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|k| {
            let z = 1.0 - (2.0 * k as f64 + 1.0) / n as f64;
            let rho = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * k as f64;
            Vec3::new(rho * phi.cos(), rho * phi.sin(), z)
        })
        .collect()
}

/// A hash grid of the seeds placed, cells at least `min` wide (the largest distance at which
/// two seeds can overlap), to refuse a seed that would overlap another (minimum image in a
/// periodic box: the grid's cells then tile each period and wrap).
struct SeedGrid {
    /// Cell size and, for a periodic box, the cells per period along each axis.
    cell: [f64; 3],
    cells: Option<[i64; 3]>,
    map: std::collections::HashMap<[i64; 3], Vec<usize>>,
}

impl SeedGrid {
    fn new(min: f64, period: Option<[f64; 3]>) -> Self {
        let (cell, cells) = match period {
            Some(l) => {
                let n = l.map(|lk| ((lk / min).floor() as i64).max(1));
                (
                    [l[0] / n[0] as f64, l[1] / n[1] as f64, l[2] / n[2] as f64],
                    Some(n),
                )
            }
            None => ([min; 3], None),
        };
        Self {
            cell,
            cells,
            map: std::collections::HashMap::new(),
        }
    }

    fn key(&self, x: &Vec3) -> [i64; 3] {
        [0, 1, 2].map(|k| (x[k] / self.cell[k]).floor() as i64)
    }

    fn wrapped(&self, mut key: [i64; 3]) -> [i64; 3] {
        if let Some(n) = self.cells {
            for k in 0..3 {
                key[k] = key[k].rem_euclid(n[k]);
            }
        }
        key
    }

    fn insert(&mut self, x: &Vec3, id: usize) {
        let k = self.wrapped(self.key(x));
        self.map.entry(k).or_default().push(id);
    }

    /// Whether a seed already placed would overlap a seed of radius `r` at `x` (their
    /// distance below the sum of their radii).
    fn too_close(
        &self,
        x: &Vec3,
        r: f64,
        seeds: &[Vec3],
        radii: &[f64],
        offset: &dyn Fn(&Vec3, &Vec3) -> Vec3,
    ) -> bool {
        let [i, j, k] = self.key(x);
        // A periodic axis of fewer than three cells wraps onto a cell already visited.
        let mut seen: Vec<[i64; 3]> = Vec::with_capacity(27);
        for di in -1..=1 {
            for dj in -1..=1 {
                for dk in -1..=1 {
                    let key = self.wrapped([i + di, j + dj, k + dk]);
                    if seen.contains(&key) {
                        continue;
                    }
                    seen.push(key);
                    if let Some(ids) = self.map.get(&key)
                        && ids.iter().any(|&s| offset(&seeds[s], x).norm() < r + radii[s])
                    {
                        return true;
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use demcon_core::Ends;

    #[test]
    fn the_tangent_polyhedron_closes_on_the_sphere_from_above() {
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        let mut last = f64::INFINITY;
        for n in [12, 50, 200, 800] {
            let v = crate::laguerre::tangent_polyhedron_volume(&fibonacci_sphere(n));
            assert!(v > ball && v < last, "{n}: {v}");
            last = v;
        }
        // The cube's six faces: volume 8.
        let axes = [
            Vec3::x(),
            -Vec3::x(),
            Vec3::y(),
            -Vec3::y(),
            Vec3::z(),
            -Vec3::z(),
        ];
        assert!((crate::laguerre::tangent_polyhedron_volume(&axes) - 8.0).abs() < 1e-12);
        assert!((last / ball - 1.0) < 5e-3, "{last}");
    }

    /// The whole container as the body.
    fn walled(container: &Container) -> Body<'_> {
        Body {
            container,
            carve: None,
        }
    }

    /// 20³ sites of radius 0.01 at the cell centres of a unit walled box.
    fn walled_lattice() -> (usize, ParticleSet, Container) {
        let n = 20;
        let centres = lattice(n, |i, j, k| {
            Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5) * (1.0 / n as f64)
        });
        let p = ParticleSet::new(centres, vec![0.01; n * n * n]).unwrap();
        (n, p, Container::Box { size: [1.0; 3] })
    }

    /// The points `at(i, j, k)` of an n³ lattice.
    fn lattice(n: usize, at: impl Fn(usize, usize, usize) -> Vec3) -> Vec<Vec3> {
        (0..n * n * n)
            .map(|m| at(m / (n * n), (m / n) % n, m % n))
            .collect()
    }

    #[test]
    fn shapes_get_pairs_across_their_surfaces_that_overlap_no_site() {
        // Sites of radius 0.03 on a 20³ lattice of the unit periodic cell; a prolate spheroid
        // across a periodic face, an oblate one and a round and a flat cylinder.
        let n = 20;
        let centres = lattice(n, |i, j, k| {
            let jitter = ((i * 7 + j * 13 + k * 29) % 10) as f64 * 1e-3;
            Vec3::new(i as f64, j as f64, k as f64) * (1.0 / n as f64) + Vec3::repeat(jitter)
        });
        let p = ParticleSet::new(centres, vec![0.03; n * n * n]).unwrap();
        let cell = Container::Periodic { size: [1.0; 3] };
        let z = Vec3::z();
        let shapes = [
            demcon_core::Inclusion::spheroid(Vec3::new(0.95, 0.3, 0.3), Vec3::x(), 0.25, 0.08, "s").unwrap(),
            demcon_core::Inclusion::spheroid(Vec3::new(0.5, 0.7, 0.3), z, 0.05, 0.15, "s").unwrap(),
            demcon_core::Inclusion::cylinder(Vec3::new(0.3, 0.3, 0.75), z, 0.08, 0.3, Ends::Round, "s")
                .unwrap(),
            demcon_core::Inclusion::cylinder(Vec3::new(0.7, 0.7, 0.75), z, 0.08, 0.3, Ends::Flat, "s")
                .unwrap(),
        ];
        let h = 1.0 / n as f64;
        let surfaces = Followed {
            shapes: &shapes,
            ..Followed::default()
        };
        let c = conforming_sites(&p, walled(&cell), surfaces, h, &ConformParams::default()).unwrap();
        assert_eq!(c.report.shapes, 4);
        let image = |d: Vec3| d.map(|v| v - v.round());
        let (kept, seeds) = c.particles.centres.split_at(c.kept.len());
        let seed_radii = &c.particles.radii[c.kept.len()..];
        assert!(seeds.len() > 500, "{:?}", c.report);
        for (x, r) in seeds.iter().zip(seed_radii) {
            // Within the shapes' δ = 0.1 h (+ the small inward move) of a surface, not the
            // spheres' 0.25 h, and clear of every kept site.
            let depth = shapes
                .iter()
                .map(|s| s.signed_distance(&(s.centre() + image(x - s.centre()))).abs())
                .fold(f64::INFINITY, f64::min);
            assert!(depth < (SHAPE_OFFSET + 0.05) * h, "{depth}");
            for (y, ry) in kept.iter().zip(&c.particles.radii) {
                assert!(image(x - y).norm() >= r + ry - 1e-12);
            }
        }
        // The pairs: each seed's partner is its mirror across the (moved) tangent plane.
        assert_eq!(seeds.len() % 2, 0);
    }

    #[test]
    fn seeds_pair_across_the_surface_and_clear_the_packing_next_to_it() {
        // A jittered cubic lattice of 20³ sites of radius 0.01 in the unit periodic cell, a
        // sphere of radius 0.3 centred near a corner (its images cross three faces).
        let n = 20;
        let centres = lattice(n, |i, j, k| {
            let jitter = ((i * 7 + j * 13 + k * 29) % 10) as f64 * 1e-3;
            Vec3::new(i as f64, j as f64, k as f64) * (1.0 / n as f64) + Vec3::repeat(jitter)
        });
        let p = ParticleSet::new(centres, vec![0.01; n * n * n]).unwrap();
        let cell = Container::Periodic { size: [1.0; 3] };
        let sphere = SphereSurface {
            centre: Vec3::new(0.1, 0.05, 0.95),
            radius: 0.3,
        };
        let h = 1.0 / n as f64;
        let c = conforming_sites(
            &p,
            walled(&cell),
            Followed {
                spheres: &[sphere],
                ..Followed::default()
            },
            h,
            &ConformParams::default(),
        )
        .unwrap();
        let delta = 0.25 * h;
        let image = |x: &Vec3| {
            let mut d = x - sphere.centre;
            d.iter_mut().for_each(|v| *v -= v.round());
            d
        };
        assert_eq!(c.particles.len(), c.kept.len() + c.n_seeds);
        assert_eq!(c.report.dropped_seeds, 0);
        assert_eq!(c.n_seeds % 2, 0);
        // Every kept site lies wholly beyond 2δ of the seeded sphere (radius r'), every seed at
        // δ from it.
        let r_t = 0.3 * (1.0 - c.report.max_radius_correction);
        for (k, &i) in c.kept.iter().enumerate() {
            let s = image(&p.centres[i as usize]).norm() - r_t;
            assert!(s.abs() >= c.particles.radii[k] + 2.0 * delta, "site {i}: {s}");
        }
        for x in &c.particles.centres[c.kept.len()..] {
            let s = image(x).norm() - r_t;
            assert!((s.abs() - delta).abs() < 1e-12, "{s}");
            assert!((0..3).all(|k| (0.0..1.0).contains(&x[k])), "{x}");
        }
        assert_eq!(c.report.removed_sites, n * n * n - c.kept.len());
    }

    #[test]
    fn nearly_touching_spheres_both_keep_their_pairs_in_the_gap() {
        // Two spheres of radius 0.2 with a gap of 0.02 (0.4 h, h = 0.05) in a
        // walled box, sites on a coarse lattice: both surfaces are sampled up to the gap and
        // no pair is dropped; the pairs facing each other do not overlap.
        let (n, p, cell) = walled_lattice();
        let spheres = [
            SphereSurface {
                centre: Vec3::new(0.29, 0.5, 0.5),
                radius: 0.2,
            },
            SphereSurface {
                centre: Vec3::new(0.71, 0.5, 0.5),
                radius: 0.2,
            },
        ];
        let h = 1.0 / n as f64;
        let c = conforming_sites(
            &p,
            walled(&cell),
            Followed {
                spheres: &spheres,
                ..Followed::default()
            },
            h,
            &ConformParams::default(),
        )
        .unwrap();
        assert_eq!(c.report.dropped_seeds, 0, "{:?}", c.report);
        assert!(c.report.narrowed_pairs > 0, "{:?}", c.report);
        let seeds = &c.particles.centres[c.kept.len()..];
        let radii = &c.particles.radii[c.kept.len()..];
        for a in 0..seeds.len() {
            for b in a + 1..seeds.len() {
                // (a pair's two seeds touch: 2d apart, radius d each)
                assert!(
                    (seeds[a] - seeds[b]).norm() >= (radii[a] + radii[b]) * (1.0 - 1e-12),
                    "{a} {b}"
                );
            }
        }
        // Seeds lie between the spheres, on both sides of the gap's mid-plane.
        let radial = |x: &Vec3| ((x.y - 0.5).powi(2) + (x.z - 0.5).powi(2)).sqrt();
        let in_gap = |x: &Vec3| (x - spheres[0].centre).norm() > 0.2 && (x - spheres[1].centre).norm() > 0.2;
        let left = seeds
            .iter()
            .filter(|x| in_gap(x) && x.x < 0.5 && radial(x) < 0.05)
            .count();
        let right = seeds
            .iter()
            .filter(|x| in_gap(x) && x.x > 0.5 && radial(x) < 0.05)
            .count();
        assert!(left > 0 && right > 0, "{left} {right}");
    }

    #[test]
    fn the_pieces_of_one_plane_do_not_squeeze_each_other() {
        // A crack made of two squares sharing an edge, in a walled box: one surface, so no pair
        // is narrowed along the shared edge, and the seeds cover both pieces.
        let (n, p, cell) = walled_lattice();
        let square = |x0: f64| {
            PlanePatch::Crack(CrackShape::Polygon {
                points: vec![
                    Vec3::new(x0, 0.52, 0.2),
                    Vec3::new(x0 + 0.3, 0.52, 0.2),
                    Vec3::new(x0 + 0.3, 0.52, 0.8),
                    Vec3::new(x0, 0.52, 0.8),
                ],
            })
        };
        let h = 1.0 / n as f64;
        let c = conforming_sites(
            &p,
            walled(&cell),
            Followed {
                planes: &[square(0.2), square(0.5)],
                ..Followed::default()
            },
            h,
            &ConformParams::default(),
        )
        .unwrap();
        assert_eq!(c.report.narrowed_pairs, 0, "{:?}", c.report);
        let seeds = &c.particles.centres[c.kept.len()..];
        assert!(seeds.iter().any(|x| x.x < 0.5) && seeds.iter().any(|x| x.x > 0.5));
        assert!(
            seeds
                .iter()
                .all(|x| ((x.y - 0.52).abs() - 0.25 * h).abs() < 1e-12)
        );
    }
}
