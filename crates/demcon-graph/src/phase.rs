//! Phase assignment: the particles whose centre lies in a region take a phase.

use std::borrow::Cow;

use demcon_core::{ParticleSet, Region, Vec3};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree};

/// Unions with fewer members are queried whole.
const INDEXED_MEMBERS: usize = 16;

/// A region prepared for many point queries. A union of many members (a composite's spheres
/// and their periodic images) is indexed by its members' boxes (an rstar R-tree), so that
/// a query at a point sees only the members whose box comes within `reach` of it: the
/// [`RegionQuery::near`] union has the same signed distance as the whole wherever that is
/// below `reach` (the members left out are farther), and +∞ where no member is near.
/// Members keep their order, so sums and minima over them give the same bits as the whole.
pub(crate) struct RegionQuery<'a> {
    region: &'a Region,
    tree: Option<RTree<GeomWithData<Rectangle<[f64; 3]>, usize>>>,
}

impl<'a> RegionQuery<'a> {
    /// Indexes `region` for queries whose answer matters within `reach` (m) of its boundary.
    pub(crate) fn new(region: &'a Region, reach: f64) -> Self {
        let tree = match region {
            Region::Union(members) if members.len() >= INDEXED_MEMBERS => {
                let boxes = members
                    .iter()
                    .enumerate()
                    .map(|(k, m)| {
                        let b = m.bounds();
                        let lo = b.min - Vec3::repeat(reach);
                        let hi = b.max + Vec3::repeat(reach);
                        GeomWithData::new(Rectangle::from_corners(lo.into(), hi.into()), k)
                    })
                    .collect();
                Some(RTree::bulk_load(boxes))
            }
            _ => None,
        };
        Self { region, tree }
    }

    /// The part of the region that matters within `reach` of `p`: the whole region, or the
    /// union of the members near `p` (in their order).
    pub(crate) fn near(&self, p: &Vec3) -> Cow<'a, Region> {
        match (&self.tree, self.region) {
            (Some(tree), Region::Union(members)) => {
                let at = [p.x, p.y, p.z];
                let mut ids: Vec<usize> = tree
                    .locate_in_envelope_intersecting(AABB::from_point(at))
                    .map(|g| g.data)
                    .collect();
                ids.sort_unstable();
                Cow::Owned(Region::Union(
                    ids.into_iter().map(|k| members[k].clone()).collect(),
                ))
            }
            _ => Cow::Borrowed(self.region),
        }
    }
}

/// Sets `phase` on every particle whose centre lies in `region` (boundary included) and
/// returns how many particles it set. Other particles keep their phase.
pub fn assign_phase(particles: &mut ParticleSet, region: &Region, phase: u16) -> usize {
    let query = RegionQuery::new(region, 0.0);
    let mut count = 0;
    for (c, m) in particles.centres.iter().zip(particles.phases.iter_mut()) {
        if query.near(c).contains_point(c) {
            *m = phase;
            count += 1;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use demcon_core::Vec3;

    #[test]
    fn centre_in_region_rule() {
        let mut p = ParticleSet::new(
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(0.9, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
            ],
            vec![0.5, 0.5, 0.5],
        )
        .unwrap();
        let ball = Region::Sphere {
            centre: Vec3::zeros(),
            radius: 1.0,
        };
        // Particle 1 sticks out of the ball but its centre is inside: it is assigned.
        assert_eq!(assign_phase(&mut p, &ball, 2), 2);
        assert_eq!(p.phases, vec![2, 2, 0]);
    }

    #[test]
    fn an_indexed_union_answers_as_the_whole_within_its_reach() {
        // 60 balls on a jittered line and points around them: the indexed union's signed
        // distance is the whole union's to the bit wherever it is below the reach.
        let members: Vec<Region> = (0..60)
            .map(|k| Region::Sphere {
                centre: Vec3::new(0.1 * k as f64, 0.01 * (k % 7) as f64, 0.0),
                radius: 0.04 + 0.001 * (k % 5) as f64,
            })
            .collect();
        let whole = Region::Union(members);
        let reach = 0.03;
        let query = RegionQuery::new(&whole, reach);
        for i in 0..2000 {
            let p = Vec3::new(
                -0.2 + 6.4 * (i as f64 * 0.618_033_988_7).fract(),
                -0.1 + 0.3 * (i as f64 * 0.414_213_562_3).fract(),
                -0.1 + 0.2 * (i as f64 * 0.732_050_807_6).fract(),
            );
            let exact = whole.signed_distance(&p);
            let near = query.near(&p).signed_distance(&p);
            if exact < reach {
                assert_eq!(near.to_bits(), exact.to_bits(), "{p}");
            } else {
                assert!(near >= reach, "{p}: {near}");
            }
            assert_eq!(query.near(&p).contains_point(&p), whole.contains_point(&p));
        }
    }
}
