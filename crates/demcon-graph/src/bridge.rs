//! Facets between the cells of two different spheres ("bridges").
//!
//! The conforming seeds (`conform.rs`) put facets on every sphere surface, but where two
//! spheres come closer than the seed pairs can follow (a pair squeezed below
//! `MIN_OFFSET` × δ, i.e. a gap under ~0.2 δ, is dropped), the cells inside the two spheres
//! meet across the gap: their facet's branch leaves one sphere and enters the other. A
//! surface law (an interface conductance) must then be read on that branch twice, at the exit
//! and at the entry, each with the |e·n| of its crossing — which the phases alone cannot tell,
//! both cells being of one phase. [`sphere_membership`] says which sphere holds each cell's
//! centre and [`bridges`] finds those branches and their two crossings.

use demcon_core::{Container, Vec3};
use rayon::prelude::*;

use crate::ContactGraph;
use crate::conform::{SphereIndex, SphereSurface};

/// No sphere holds the point (see [`sphere_membership`]).
pub const NO_SPHERE: u32 = u32::MAX;

/// A contact whose branch leaves one sphere and enters another.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bridge {
    /// Index of the contact in the graph.
    pub contact: u32,
    /// |e·n| where the branch leaves p's sphere (e the branch, n the sphere's normal).
    pub cos_exit: f64,
    /// |e·n| where it enters q's sphere.
    pub cos_entry: f64,
    /// The middle of the gap between the two crossings (m; wrapped into a periodic cell).
    pub gap_middle: Vec3,
    /// Length of the branch between the two spheres (m).
    pub gap_length: f64,
}

/// The minimum-image offset from `a` to `b` in `container`.
fn offset(container: &Container, a: &Vec3, b: &Vec3) -> Vec3 {
    let mut d = b - a;
    if let Some(l) = container.period() {
        for k in 0..3 {
            d[k] -= l[k] * (d[k] / l[k]).round();
        }
    }
    d
}

/// For each point, the index of the sphere of `spheres` that holds it (distance to the
/// centre below the radius, minimum image in a periodic box), [`NO_SPHERE`] for none; the
/// lowest index when spheres overlap. Points must lie in the container (a periodic cell's
/// points wrapped into it).
pub fn sphere_membership(points: &[Vec3], spheres: &[SphereSurface], container: &Container) -> Vec<u32> {
    if spheres.is_empty() {
        return vec![NO_SPHERE; points.len()];
    }
    let index = SphereIndex::new(spheres.iter().map(|s| (s.centre, s.radius)), container, 0.0);
    points
        .par_iter()
        .with_min_len(1024)
        .map(|x| {
            index
                .near(x)
                .filter(|&k| offset(container, &spheres[k].centre, x).norm() < spheres[k].radius)
                .min()
                .map_or(NO_SPHERE, |k| k as u32)
        })
        .collect()
}

/// The contacts of `graph` between particles held by two spheres (`membership` from
/// [`sphere_membership`]; in a periodic box two images of one sphere count as two) whose
/// branch leaves the first before it enters the second (a gap between them along the branch),
/// with the two crossings. A branch between two points of one sphere (image) never leaves it.
pub fn bridges(
    graph: &ContactGraph,
    centres: &[Vec3],
    spheres: &[SphereSurface],
    membership: &[u32],
    container: &Container,
) -> Vec<Bridge> {
    let wrap = |x: Vec3| match container.period() {
        Some(l) => Vec3::new(x.x.rem_euclid(l[0]), x.y.rem_euclid(l[1]), x.z.rem_euclid(l[2])),
        None => x,
    };
    graph
        .pairs
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .filter_map(|(k, &[p, q])| {
            let (a, b) = (membership[p as usize], membership[q as usize]);
            if a == NO_SPHERE || b == NO_SPHERE {
                return None;
            }
            let (sa, sb) = (&spheres[a as usize], &spheres[b as usize]);
            let g = &graph.geometry[k];
            let (xp, e) = (centres[p as usize], g.normal);
            let xq = xp + g.distance * e;
            // Offsets from the branch's start to each sphere's image nearest its own end.
            let wa = -offset(container, &xp, &sa.centre);
            let wb = xp - (xq + offset(container, &xq, &sb.centre));
            // |w + t e| = r: the exit from a (larger root), the entry into b (smaller root).
            let root = |w: &Vec3, r: f64, sign: f64| {
                let h = e.dot(w);
                let disc = h * h - w.norm_squared() + r * r;
                (disc >= 0.0).then(|| -h + sign * disc.sqrt())
            };
            let t_exit = root(&wa, sa.radius, 1.0)?;
            let t_entry = root(&wb, sb.radius, -1.0)?;
            if t_entry <= t_exit {
                // One sphere (image) holds the whole branch, or two overlap along it: no gap.
                return None;
            }
            let cos = |w: &Vec3, t: f64, r: f64| (e.dot(&(w + t * e)) / r).abs();
            Some(Bridge {
                contact: k as u32,
                cos_exit: cos(&wa, t_exit, sa.radius),
                cos_entry: cos(&wb, t_entry, sb.radius),
                gap_middle: wrap(xp + 0.5 * (t_exit + t_entry) * e),
                gap_length: t_entry - t_exit,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn membership_sees_periodic_images_and_takes_the_lowest_index() {
        let container = Container::Periodic { size: [1.0; 3] };
        let spheres = [
            SphereSurface {
                centre: Vec3::new(0.05, 0.5, 0.5),
                radius: 0.1,
            },
            SphereSurface {
                centre: Vec3::new(0.5, 0.5, 0.5),
                radius: 0.2,
            },
            SphereSurface {
                centre: Vec3::new(0.6, 0.5, 0.5),
                radius: 0.2,
            },
        ];
        let points = [
            Vec3::new(0.98, 0.5, 0.5),
            Vec3::new(0.55, 0.5, 0.5),
            Vec3::new(0.75, 0.5, 0.5),
            Vec3::new(0.5, 0.1, 0.5),
        ];
        assert_eq!(
            sphere_membership(&points, &spheres, &container),
            vec![0, 1, 2, NO_SPHERE]
        );
        assert_eq!(sphere_membership(&points, &[], &container), vec![NO_SPHERE; 4]);
    }
}
