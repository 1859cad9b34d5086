//! Phase assignment: the particles whose centre lies in a region take a phase.

use demcon_core::{ParticleSet, Region};

/// Sets `phase` on every particle whose centre lies in `region` (boundary included) and
/// returns how many particles it set. Other particles keep their phase.
pub fn assign_phase(particles: &mut ParticleSet, region: &Region, phase: u16) -> usize {
    let mut count = 0;
    for (c, m) in particles.centres.iter().zip(particles.phases.iter_mut()) {
        if region.contains_point(c) {
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
}
