//! Crack surfaces and the contacts they cut: a contact (or Laguerre facet) is crossed by a
//! crack when its centre-to-centre segment x_p → x_p + d_pq e_pq (the minimum-image branch in
//! a periodic box) passes through the crack's surface.
//!
//! Shapes: a disc (centre, unit normal, radius) or a plane polygon (its points in order,
//! convex or not, closed implicitly). The crossing test is half-open, so that a centre lying
//! exactly on the crack's plane is on one definite side: with s = n·(x − c) the signed distance
//! of a point to the plane, the segment a → b crosses when (s_a > 0) ≠ (s_b > 0) and the point
//! where it meets the plane lies inside the shape (boundary included). Two particles whose
//! centres both lie on the plane are never separated.
//!
//! In a periodic box the crack is repeated with the cell: the segment is tested against the 27
//! images of the crack that can reach it.

use demcon_core::{Container, CoreError, ParticleSet, Vec3};
use rayon::prelude::*;

use crate::ContactGraph;

/// The surface of a crack (m).
#[derive(Debug, Clone, PartialEq)]
pub enum CrackShape {
    /// A flat disc (a penny crack).
    Disc {
        /// Centre (m).
        centre: Vec3,
        /// Normal (any length > 0; normalised by the tests).
        normal: Vec3,
        /// Radius (m), > 0.
        radius: f64,
    },
    /// A plane polygon, its vertices in order (at least 3, not collinear, in one plane).
    Polygon {
        /// Vertices (m).
        points: Vec<Vec3>,
    },
}

/// Relative tolerance of the planarity of a polygon, on its largest extent.
const PLANARITY_TOLERANCE: f64 = 1e-6;

impl CrackShape {
    /// Checks the shape; errors name `field` (e.g. `cracks[2]`): a radius not finite and > 0,
    /// a zero or non-finite normal, a polygon of fewer than 3 points, with non-finite points,
    /// of zero area (collinear or repeated points) or not plane.
    pub fn validate(&self, field: &str) -> Result<(), CoreError> {
        let finite = |v: &Vec3| v.iter().all(|x| x.is_finite());
        match self {
            CrackShape::Disc {
                centre,
                normal,
                radius,
            } => {
                if !finite(centre) {
                    return Err(CoreError::invalid(
                        format!("{field}.centre"),
                        fmt(centre),
                        "finite coordinates (m)",
                    ));
                }
                if !(finite(normal) && normal.norm() > 0.0) {
                    return Err(CoreError::invalid(
                        format!("{field}.normal"),
                        fmt(normal),
                        "a finite, non-zero vector",
                    ));
                }
                if !(radius.is_finite() && *radius > 0.0) {
                    return Err(CoreError::invalid(
                        format!("{field}.radius"),
                        radius,
                        "a finite number > 0 (m)",
                    ));
                }
            }
            CrackShape::Polygon { points } => {
                if points.len() < 3 {
                    return Err(CoreError::invalid(
                        format!("{field}.points"),
                        format!("{} points", points.len()),
                        "at least 3 points",
                    ));
                }
                if let Some(k) = points.iter().position(|p| !finite(p)) {
                    return Err(CoreError::invalid(
                        format!("{field}.points[{k}]"),
                        fmt(&points[k]),
                        "finite coordinates (m)",
                    ));
                }
                let (n, area, extent) = polygon_frame(points);
                if !(area > 1e-12 * extent * extent && area > 0.0) {
                    return Err(CoreError::invalid(
                        format!("{field}.points"),
                        format!("area {area:e} m²"),
                        "a polygon of non-zero area (its points are collinear or repeated)",
                    ));
                }
                let c = points[0];
                if let Some(k) = points
                    .iter()
                    .position(|p| n.dot(&(p - c)).abs() > PLANARITY_TOLERANCE * extent)
                {
                    return Err(CoreError::invalid(
                        format!("{field}.points[{k}]"),
                        fmt(&points[k]),
                        format!(
                            "in the plane of the other points (it lies {:e} m off it)",
                            n.dot(&(points[k] - c)).abs()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// A point of the crack's plane and its unit normal.
    pub fn plane(&self) -> (Vec3, Vec3) {
        match self {
            CrackShape::Disc { centre, normal, .. } => (*centre, normal.normalize()),
            CrackShape::Polygon { points } => (points[0], polygon_frame(points).0),
        }
    }

    /// A ball holding the crack (centre, radius in m).
    pub fn bounding_ball(&self) -> (Vec3, f64) {
        match self {
            CrackShape::Disc { centre, radius, .. } => (*centre, *radius),
            CrackShape::Polygon { points } => {
                let c = points.iter().sum::<Vec3>() / points.len() as f64;
                let r = points.iter().map(|p| (p - c).norm()).fold(0.0, f64::max);
                (c, r)
            }
        }
    }

    /// Where the segment a → b (m) crosses the crack (the half-open rule of the module doc),
    /// or `None`.
    pub fn crossing(&self, a: &Vec3, b: &Vec3) -> Option<Vec3> {
        let (c, n) = self.plane();
        let (sa, sb) = (n.dot(&(a - c)), n.dot(&(b - c)));
        if (sa > 0.0) == (sb > 0.0) {
            return None;
        }
        let t = sa / (sa - sb);
        let x = a + (b - a) * t;
        let inside = match self {
            CrackShape::Disc { centre, radius, .. } => {
                let r = x - centre;
                // Distance in the plane (x lies on it up to round-off).
                (r - n * n.dot(&r)).norm_squared() <= radius * radius
            }
            CrackShape::Polygon { points } => point_in_polygon(points, &n, &x),
        };
        inside.then_some(x)
    }

    /// Whether the crack, or one of its periodic images when `period` (m) is given, crosses
    /// the segment a → b; the crossing point (in the frame of the segment).
    pub fn crossing_periodic(&self, a: &Vec3, b: &Vec3, period: Option<[f64; 3]>) -> Option<Vec3> {
        let (bc, br) = self.bounding_ball();
        let near = |shift: &Vec3| segment_ball_distance(a, b, &(bc + shift)) <= br;
        match period {
            None => near(&Vec3::zeros()).then(|| self.crossing(a, b)).flatten(),
            Some(l) => {
                for i in [0.0, -1.0, 1.0] {
                    for j in [0.0, -1.0, 1.0] {
                        for k in [0.0, -1.0, 1.0] {
                            let s = Vec3::new(i * l[0], j * l[1], k * l[2]);
                            if near(&s)
                                && let Some(x) = self.crossing(&(a - s), &(b - s))
                            {
                                return Some(x + s);
                            }
                        }
                    }
                }
                None
            }
        }
    }
}

/// Smallest |e·n| (e the branch, n the crack's normal) used to project a facet onto a crack's
/// plane: a branch nearly in the plane would stretch its footprint without bound.
const MIN_OBLIQUITY: f64 = 0.2;
/// Rings and angles of the equal-area sample of a facet's disc ([`CrackShape::blocked_fraction`]).
const FOOTPRINT_RINGS: usize = 6;
const FOOTPRINT_ANGLES: usize = 12;

impl CrackShape {
    /// Whether the point `x` of the crack's plane (unit normal `n`) lies inside the shape.
    pub(crate) fn contains_planar(&self, n: &Vec3, x: &Vec3) -> bool {
        match self {
            CrackShape::Disc { centre, radius, .. } => {
                let r = x - centre;
                (r - n * n.dot(&r)).norm_squared() <= radius * radius
            }
            CrackShape::Polygon { points } => point_in_polygon(points, n, x),
        }
    }

    /// The fraction of a contact's facet that the crack covers, seen along the branch a → b
    /// (m): the facet is read as a disc of radius `rho` (m, the radius of its area) centred at
    /// `centre` (m), normal to the branch, and each point of it conducts along a tube parallel
    /// to the branch; a tube is blocked where it meets the crack's plane inside the shape. So
    /// the fraction is the part of the facet's footprint on the plane (the disc projected along
    /// the branch: an ellipse) that lies inside the crack, sampled at 72 equal-area points.
    /// 0 when the branch does not cross the crack's plane (the half-open rule of the module
    /// doc). With `rho` = 0 it is the segment rule: 1 when [`CrackShape::crossing`] finds a
    /// crossing, else 0.
    ///
    /// With a `domain` (a walled container), only the tubes that lie in it count: a sample
    /// whose point on the facet's disc, or whose point on the crack's plane, is outside the
    /// container is no part of the facet (the disc reaches past the wall that clips the real
    /// facet), so a crack that ends at a wall covers the facets along that wall wholly. When
    /// no sample is inside, the segment rule decides.
    pub fn blocked_fraction(
        &self,
        a: &Vec3,
        b: &Vec3,
        centre: &Vec3,
        rho: f64,
        domain: Option<&Container>,
    ) -> f64 {
        let (c, n) = self.plane();
        let (sa, sb) = (n.dot(&(a - c)), n.dot(&(b - c)));
        if (sa > 0.0) == (sb > 0.0) {
            return 0.0;
        }
        if rho <= 0.0 {
            return if self.crossing(a, b).is_some() { 1.0 } else { 0.0 };
        }
        let e = (b - a).normalize();
        let ne = n.dot(&e);
        let slope = ne.signum() * ne.abs().max(MIN_OBLIQUITY);
        // An orthonormal pair across the branch.
        let helper = if e.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
        let s1 = e.cross(&helper).normalize();
        let s2 = e.cross(&s1);
        let in_domain = |x: &Vec3| domain.is_none_or(|d| d.wall_distance(x) >= 0.0);
        let (mut inside, mut counted) = (0usize, 0usize);
        for i in 0..FOOTPRINT_RINGS {
            let r = rho * ((i as f64 + 0.5) / FOOTPRINT_RINGS as f64).sqrt();
            for j in 0..FOOTPRINT_ANGLES {
                let t = std::f64::consts::TAU * (j as f64 + 0.5 * (i % 2) as f64) / FOOTPRINT_ANGLES as f64;
                let y = centre + (s1 * t.cos() + s2 * t.sin()) * r;
                let x = y - e * (n.dot(&(y - c)) / slope);
                if !(in_domain(&y) && in_domain(&x)) {
                    continue;
                }
                counted += 1;
                if self.contains_planar(&n, &x) {
                    inside += 1;
                }
            }
        }
        if counted == 0 {
            return self.blocked_fraction(a, b, centre, 0.0, None);
        }
        inside as f64 / counted as f64
    }

    /// [`CrackShape::blocked_fraction`] in `container`: over the crack and its periodic images
    /// in a periodic box (the images' fractions add up, at most 1), else over the tubes inside
    /// the container's walls.
    pub fn blocked_fraction_in(
        &self,
        a: &Vec3,
        b: &Vec3,
        centre: &Vec3,
        rho: f64,
        container: &Container,
    ) -> f64 {
        let period = container.period();
        let domain = period.is_none().then_some(container);
        let (bc, br) = self.bounding_ball();
        let reach = br + rho * (1.0 + 1.0 / MIN_OBLIQUITY);
        let at = |s: &Vec3| {
            if segment_ball_distance(a, b, &(bc + s)) > reach {
                0.0
            } else {
                self.blocked_fraction(&(a - s), &(b - s), &(centre - s), rho, domain)
            }
        };
        match period {
            None => at(&Vec3::zeros()),
            Some(l) => {
                let mut sum = 0.0;
                for i in [0.0, -1.0, 1.0] {
                    for j in [0.0, -1.0, 1.0] {
                        for k in [0.0, -1.0, 1.0] {
                            sum += at(&Vec3::new(i * l[0], j * l[1], k * l[2]));
                        }
                    }
                }
                sum.min(1.0)
            }
        }
    }
}

fn fmt(v: &Vec3) -> String {
    format!("({:e}, {:e}, {:e})", v.x, v.y, v.z)
}

/// Unit normal (Newell's method; zero for a degenerate polygon), area (m²) and largest
/// extent (m) of a polygon.
fn polygon_frame(points: &[Vec3]) -> (Vec3, f64, f64) {
    let mut n = Vec3::zeros();
    for (k, p) in points.iter().enumerate() {
        let q = points[(k + 1) % points.len()];
        n += p.cross(&q);
    }
    let area = 0.5 * n.norm();
    let extent = points
        .iter()
        .flat_map(|p| points.iter().map(move |q| (p - q).norm()))
        .fold(0.0, f64::max);
    let unit = if area > 0.0 { n / n.norm() } else { Vec3::zeros() };
    (unit, area, extent)
}

/// Whether `x` (on the polygon's plane, unit normal `n`) lies inside the polygon: the
/// crossing number in the projection that drops the normal's largest component.
fn point_in_polygon(points: &[Vec3], n: &Vec3, x: &Vec3) -> bool {
    let drop = n.iamax();
    let (u, v) = ((drop + 1) % 3, (drop + 2) % 3);
    let (px, py) = (x[u], x[v]);
    let mut inside = false;
    let m = points.len();
    for k in 0..m {
        let (a, b) = (points[k], points[(k + 1) % m]);
        let (ax, ay, bx, by) = (a[u], a[v], b[u], b[v]);
        if (ay > py) != (by > py) {
            let xc = ax + (py - ay) / (by - ay) * (bx - ax);
            if px < xc {
                inside = !inside;
            }
        }
    }
    inside
}

/// Distance (m) from the point `c` to the segment a → b.
fn segment_ball_distance(a: &Vec3, b: &Vec3, c: &Vec3) -> f64 {
    let ab = b - a;
    let l2 = ab.norm_squared();
    let t = if l2 > 0.0 {
        (ab.dot(&(c - a)) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - c).norm()
}

/// A contact crossed by a crack.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrackCrossing {
    /// The first crack (index into the list given) that the contact's segment crosses.
    pub crack: u32,
    /// Where it crosses (m), on the segment from p's centre.
    pub point: Vec3,
}

/// For every contact of `graph`, the first of `cracks` its centre-to-centre segment crosses
/// (the minimum-image branch from p; every periodic image of a crack in a periodic
/// `container`). Runs in parallel; the result does not depend on the thread count.
pub fn crossed_contacts(
    graph: &ContactGraph,
    particles: &ParticleSet,
    container: &Container,
    cracks: &[CrackShape],
) -> Vec<Option<CrackCrossing>> {
    if cracks.is_empty() {
        return vec![None; graph.len()];
    }
    let period = container.period();
    map_branches(graph, particles, |_, a, b| first_crossing(cracks, &a, &b, period))
}

/// `f(k, a, b)` for every contact k of `graph`, with a the centre of its first particle and
/// b = a + its branch vector (m), in parallel; in contact order whatever the thread count.
fn map_branches<T: Send>(
    graph: &ContactGraph,
    particles: &ParticleSet,
    f: impl Fn(usize, Vec3, Vec3) -> T + Sync,
) -> Vec<T> {
    (0..graph.len())
        .into_par_iter()
        .with_min_len(1024)
        .map(|k| {
            let a = particles.centres[graph.pairs[k][0] as usize];
            f(k, a, a + graph.branch(k))
        })
        .collect()
}

/// A contact whose facet a crack covers in part or in whole ([`blocked_contacts`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrackCover {
    /// The first crack (index into the list given) that covers part of the facet.
    pub crack: u32,
    /// The covered fraction of the facet, in (0, 1] (the cracks' fractions add up, at most 1).
    pub fraction: f64,
    /// Where the branch meets that crack's plane (m), on the segment from p's centre.
    pub point: Vec3,
}

/// For every contact of `graph`, how much of its facet `cracks` cover
/// ([`CrackShape::blocked_fraction`]): the facet of a Laguerre graph is the disc of its area
/// around its centroid; a graph without cells has no facet, and the segment rule decides
/// (covered wholly when its segment crosses a crack, [`crossed_contacts`]), as it does for
/// every graph with `whole_facets`. Runs in parallel; the result does not depend on the
/// thread count.
pub fn blocked_contacts(
    graph: &ContactGraph,
    particles: &ParticleSet,
    container: &Container,
    cracks: &[CrackShape],
    whole_facets: bool,
) -> Vec<Option<CrackCover>> {
    let cells = graph.cells.as_deref().filter(|_| !whole_facets);
    let Some(cells) = cells else {
        return crossed_contacts(graph, particles, container, cracks)
            .into_iter()
            .map(|x| {
                x.map(|x| CrackCover {
                    crack: x.crack,
                    fraction: 1.0,
                    point: x.point,
                })
            })
            .collect();
    };
    if cracks.is_empty() {
        return vec![None; graph.len()];
    }
    map_branches(graph, particles, |k, a, b| {
        let centre = a + cells.centroid[k];
        let rho = (cells.facet_area[k] / std::f64::consts::PI).sqrt();
        let mut cover: Option<CrackCover> = None;
        for (i, c) in cracks.iter().enumerate() {
            let f = c.blocked_fraction_in(&a, &b, &centre, rho, container);
            if f <= 0.0 {
                continue;
            }
            match cover.as_mut() {
                Some(x) => x.fraction = (x.fraction + f).min(1.0),
                None => {
                    let (o, n) = c.plane();
                    let (sa, sb) = (n.dot(&(a - o)), n.dot(&(b - o)));
                    let t = if sa != sb { sa / (sa - sb) } else { 0.5 };
                    cover = Some(CrackCover {
                        crack: i as u32,
                        fraction: f,
                        point: a + (b - a) * t.clamp(0.0, 1.0),
                    });
                }
            }
        }
        cover
    })
}

/// The first of `cracks` the segment a → b crosses (periodic images when `period` is given).
pub fn first_crossing(
    cracks: &[CrackShape],
    a: &Vec3,
    b: &Vec3,
    period: Option<[f64; 3]>,
) -> Option<CrackCrossing> {
    cracks.iter().enumerate().find_map(|(i, c)| {
        c.crossing_periodic(a, b, period).map(|point| CrackCrossing {
            crack: i as u32,
            point,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    #[test]
    fn segment_and_disc() {
        let d = CrackShape::Disc {
            centre: v(0.0, 0.0, 0.0),
            normal: v(0.0, 0.0, 2.0),
            radius: 1.0,
        };
        assert!(d.validate("c").is_ok());
        let x = d.crossing(&v(0.5, 0.0, -1.0), &v(0.5, 0.0, 3.0)).unwrap();
        assert!((x - v(0.5, 0.0, 0.0)).norm() < 1e-15);
        // Outside the rim, parallel to the plane, not reaching it.
        assert!(d.crossing(&v(1.1, 0.0, -1.0), &v(1.1, 0.0, 1.0)).is_none());
        assert!(d.crossing(&v(0.0, 0.0, 0.5), &v(0.5, 0.0, 0.5)).is_none());
        assert!(d.crossing(&v(0.0, 0.0, 0.5), &v(0.0, 0.0, 0.1)).is_none());
        // Half-open: a centre on the plane is on the negative side.
        assert!(d.crossing(&v(0.0, 0.0, 0.0), &v(0.0, 0.0, 1.0)).is_some());
        assert!(d.crossing(&v(0.0, 0.0, 0.0), &v(0.0, 0.0, -1.0)).is_none());
        assert!(d.crossing(&v(0.0, 0.0, 0.0), &v(0.3, 0.0, 0.0)).is_none());
        // Oblique segment through the rim region.
        let x = d.crossing(&v(-2.0, 0.0, -1.0), &v(0.0, 0.0, 1.0)).unwrap();
        assert!((x - v(-1.0, 0.0, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn blocked_fraction_of_a_facet() {
        let d = CrackShape::Disc {
            centre: v(0.0, 0.0, 0.0),
            normal: v(0.0, 0.0, 1.0),
            radius: 1.0,
        };
        let f = |x: f64, rho: f64| {
            d.blocked_fraction(&v(x, 0.0, -0.5), &v(x, 0.0, 0.5), &v(x, 0.0, 0.0), rho, None)
        };
        // Inside, far from the rim: covered wholly; far outside: not at all.
        assert_eq!(f(0.0, 0.3), 1.0);
        assert_eq!(f(1.5, 0.3), 0.0);
        // Across the rim: about half, less when the facet's centre is outside.
        let half = f(1.0, 0.3);
        assert!((0.4..0.6).contains(&half), "{half}");
        let less = f(1.15, 0.3);
        assert!(0.0 < less && less < half, "{less}");
        // A branch that does not reach the plane is not blocked.
        assert_eq!(
            d.blocked_fraction(&v(0.0, 0.0, 0.1), &v(0.0, 0.0, 0.5), &v(0.0, 0.0, 0.3), 0.3, None),
            0.0
        );
        // Without a facet it is the segment rule.
        for x in [0.0, 0.99, 1.01, 1.5] {
            let seg = d.crossing(&v(x, 0.0, -0.5), &v(x, 0.0, 0.5)).is_some();
            assert_eq!(f(x, 0.0), if seg { 1.0 } else { 0.0 });
        }
        // An oblique branch through the middle is covered wholly; its footprint is stretched
        // along the branch's direction in the plane, so at the rim it is cut more along x
        // than a normal branch would be at the same distance.
        let oblique = |x: f64| {
            d.blocked_fraction(
                &v(x - 0.5, 0.0, -0.5),
                &v(x + 0.5, 0.0, 0.5),
                &v(x, 0.0, 0.0),
                0.3,
                None,
            )
        };
        assert_eq!(oblique(0.0), 1.0);
        assert!(oblique(1.3) > f(1.3, 0.3), "{} {}", oblique(1.3), f(1.3, 0.3));
        // Periodic images add up: the same disc one period away covers the facet wholly.
        let p = d.blocked_fraction_in(
            &v(4.0, 0.0, -0.5),
            &v(4.0, 0.0, 0.5),
            &v(4.0, 0.0, 0.0),
            0.3,
            &Container::Periodic { size: [4.0; 3] },
        );
        assert_eq!(p, 1.0);
    }

    #[test]
    fn a_crack_that_ends_at_a_wall_covers_the_facets_along_it_wholly() {
        // The plane z = 0 over the box's section x ∈ [0, 2] exactly; a facet (disc of radius
        // 0.3) centred 0.1 from the wall x = 0 reaches 0.2 past it, where the real facet does
        // not exist: only its tubes inside the box count.
        let c = CrackShape::Polygon {
            points: vec![
                v(0.0, 0.0, 0.0),
                v(2.0, 0.0, 0.0),
                v(2.0, 2.0, 0.0),
                v(0.0, 2.0, 0.0),
            ],
        };
        let box_ = Container::Box {
            size: [2.0, 2.0, 2.0],
        };
        let (a, b, centre) = (v(0.1, 1.0, -0.5), v(0.1, 1.0, 0.5), v(0.1, 1.0, 0.0));
        let free = c.blocked_fraction(&a, &b, &centre, 0.3, None);
        assert!(free < 0.9, "{free}");
        assert_eq!(c.blocked_fraction(&a, &b, &centre, 0.3, Some(&box_)), 1.0);
        // The same for an oblique branch whose tubes meet the plane past the wall.
        let (a, b) = (v(0.2, 1.0, -0.5), v(0.0, 1.0, 0.5));
        assert_eq!(c.blocked_fraction_in(&a, &b, &centre, 0.3, &box_), 1.0);
        // A crack that stops short of the wall still leaves the rest of the facet open.
        let short = CrackShape::Polygon {
            points: vec![
                v(0.1, 0.0, 0.0),
                v(2.0, 0.0, 0.0),
                v(2.0, 2.0, 0.0),
                v(0.1, 2.0, 0.0),
            ],
        };
        let half = short.blocked_fraction_in(&v(0.1, 1.0, -0.5), &v(0.1, 1.0, 0.5), &centre, 0.3, &box_);
        assert!((0.5..0.9).contains(&half), "{half}");
    }

    #[test]
    fn segment_and_polygon_convex_and_not() {
        // An L-shaped polygon in the plane x = 0.5.
        let l = CrackShape::Polygon {
            points: vec![
                v(0.5, 0.0, 0.0),
                v(0.5, 2.0, 0.0),
                v(0.5, 2.0, 1.0),
                v(0.5, 1.0, 1.0),
                v(0.5, 1.0, 2.0),
                v(0.5, 0.0, 2.0),
            ],
        };
        assert!(l.validate("c").is_ok());
        let cross = |y: f64, z: f64| l.crossing(&v(0.0, y, z), &v(1.0, y, z)).is_some();
        assert!(cross(0.5, 0.5));
        assert!(cross(1.5, 0.5));
        assert!(cross(0.5, 1.5));
        assert!(!cross(1.5, 1.5)); // the notch of the L
        assert!(!cross(2.5, 0.5));
        // Reverse direction crosses too.
        assert!(l.crossing(&v(1.0, 0.5, 0.5), &v(0.0, 0.5, 0.5)).is_some());
    }

    #[test]
    fn bad_shapes_are_refused() {
        let zero = CrackShape::Disc {
            centre: v(0.0, 0.0, 0.0),
            normal: v(0.0, 0.0, 1.0),
            radius: 0.0,
        };
        assert!(
            zero.validate("cracks[0]")
                .unwrap_err()
                .to_string()
                .contains("cracks[0].radius")
        );
        let flat = CrackShape::Disc {
            centre: v(0.0, 0.0, 0.0),
            normal: v(0.0, 0.0, 0.0),
            radius: 1.0,
        };
        assert!(flat.validate("c").unwrap_err().to_string().contains("c.normal"));
        let line = CrackShape::Polygon {
            points: vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(2.0, 0.0, 0.0)],
        };
        assert!(
            line.validate("c")
                .unwrap_err()
                .to_string()
                .contains("non-zero area")
        );
        let two = CrackShape::Polygon {
            points: vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0)],
        };
        assert!(two.validate("c").is_err());
        let warped = CrackShape::Polygon {
            points: vec![
                v(0.0, 0.0, 0.0),
                v(1.0, 0.0, 0.0),
                v(1.0, 1.0, 0.1),
                v(0.0, 1.0, 0.0),
            ],
        };
        assert!(
            warped
                .validate("c")
                .unwrap_err()
                .to_string()
                .contains("in the plane")
        );
    }

    #[test]
    fn periodic_images_cut_wrapping_segments() {
        // A disc at x = 0.05 in a unit periodic cell; the segment from x = 0.95 to 1.1 (its
        // minimum image across the boundary) crosses the image at x = 1.05.
        let d = CrackShape::Disc {
            centre: v(0.05, 0.5, 0.5),
            normal: v(1.0, 0.0, 0.0),
            radius: 0.2,
        };
        let (a, b) = (v(0.95, 0.5, 0.5), v(1.1, 0.5, 0.5));
        assert!(d.crossing_periodic(&a, &b, None).is_none());
        let x = d.crossing_periodic(&a, &b, Some([1.0; 3])).unwrap();
        assert!((x - v(1.05, 0.5, 0.5)).norm() < 1e-14);
        // A disc whose image would be hit only along y does not cut a segment along x.
        assert!(
            d.crossing_periodic(&v(0.0, 0.95, 0.5), &v(0.0, 1.05, 0.5), Some([1.0; 3]))
                .is_none()
        );
    }
}
