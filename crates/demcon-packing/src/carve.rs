//! Carving: keep the spheres of a packing that lie wholly inside a region, for shapes the
//! packing algorithm cannot fill directly (e.g. a cylinder with a circumferential groove).

use demcon_core::{ParticleSet, Region};

/// The particles whose whole sphere lies inside `region` (surface included), in their
/// original order (so a Morton-ordered packing stays Morton-ordered), and their old ids.
pub fn carve(particles: &ParticleSet, region: &Region) -> (ParticleSet, Vec<u32>) {
    particles.retain(|i| region.contains_sphere(&particles.centres[i], particles.radii[i]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use demcon_core::{Axis, Vec3};

    #[test]
    fn groove_removes_the_spheres_it_touches() {
        let centres: Vec<Vec3> = (0..10).map(|k| Vec3::new(0.0, 0.0, 0.5 + k as f64)).collect();
        let p = ParticleSet::new(centres, vec![0.5; 10]).unwrap();
        let rod = Region::Cylinder {
            base: Vec3::zeros(),
            axis: Axis::Z,
            radius: 1.0,
            length: 10.0,
        };
        // A ring-shaped groove around z ∈ [4.2, 4.8], reaching radius 0.3 from the axis.
        let groove = Region::Difference(
            Box::new(Region::Cylinder {
                base: Vec3::new(0.0, 0.0, 4.2),
                axis: Axis::Z,
                radius: 2.0,
                length: 0.6,
            }),
            Box::new(Region::Cylinder {
                base: Vec3::new(0.0, 0.0, 4.2),
                axis: Axis::Z,
                radius: 0.3,
                length: 0.6,
            }),
        );
        let (kept, ids) = carve(&p, &Region::Difference(Box::new(rod), Box::new(groove)));
        assert_eq!(ids, vec![0, 1, 2, 3, 5, 6, 7, 8, 9]);
        assert_eq!(kept.len(), 9);
    }
}
