//! The domain that probes, slices and the Halo refer to: a region of space, periodic or not,
//! and an axis-aligned plane.

use demcon_core::{Axis, Container, ParticleSet, Region, Vec3};

use crate::error::PostError;

/// Where the particles live: probes must lie inside, Halos that reach past the boundary are
/// flagged as truncated, and a periodic domain wraps points and neighbourhoods.
#[derive(Debug, Clone, PartialEq)]
pub struct Domain {
    /// The region (m). In a periodic domain this is the fundamental cell `[0, period]`.
    pub region: Region,
    /// Periods along x, y, z (m) of a periodic box spanning `[0, period]`; `None` for walls.
    pub period: Option<[f64; 3]>,
}

impl Domain {
    /// The domain of a container (validated): its region, and its period if it is periodic.
    pub fn of_container(container: &Container) -> Result<Domain, PostError> {
        container.validate()?;
        Ok(Domain {
            region: container.region(),
            period: container.period(),
        })
    }

    /// A walled domain given by a region (e.g. a carved, notched specimen).
    pub fn of_region(region: Region) -> Domain {
        Domain { region, period: None }
    }

    /// The box around all the spheres of a set (walled), for data that comes without its
    /// container. Fails on an empty set.
    pub fn around(particles: &ParticleSet) -> Result<Domain, PostError> {
        if particles.is_empty() {
            return Err(PostError::invalid(
                "particles",
                "0 particles",
                "at least one particle",
            ));
        }
        let b = particles.bounds();
        Ok(Domain::of_region(Region::Box {
            min: b.min,
            max: b.max,
        }))
    }

    /// Checks the period (finite, > 0).
    pub(crate) fn validate(&self) -> Result<(), PostError> {
        if let Some(p) = self.period {
            for (k, name) in ["period.x", "period.y", "period.z"].iter().enumerate() {
                if !(p[k].is_finite() && p[k] > 0.0) {
                    return Err(PostError::invalid(*name, p[k], "must be a finite number > 0 (m)"));
                }
            }
        }
        Ok(())
    }

    /// Distance (m) from `p` to the domain boundary, positive inside; `+∞` when periodic.
    pub fn depth(&self, p: &Vec3) -> f64 {
        match self.period {
            Some(_) => f64::INFINITY,
            None => -self.region.signed_distance(p),
        }
    }

    /// The point wrapped into the periodic cell `[0, period)`; unchanged when walled.
    pub fn wrap(&self, p: &Vec3) -> Vec3 {
        match self.period {
            Some(l) => Vec3::new(wrap1(p.x, l[0]), wrap1(p.y, l[1]), wrap1(p.z, l[2])),
            None => *p,
        }
    }

    /// Checks that a probe point lies in the domain (walled: within a round-off tolerance of
    /// 1e-9 × the domain size outside the boundary) and returns it, wrapped if periodic.
    pub(crate) fn locate(&self, p: &Vec3) -> Result<Vec3, PostError> {
        crate::error::check_point("point", p)?;
        if self.period.is_some() {
            return Ok(self.wrap(p));
        }
        let depth = self.depth(p);
        let tol = 1e-9 * self.region.bounds().extent().max();
        if depth < -tol {
            return Err(PostError::ProbeOutside {
                point: [p.x, p.y, p.z],
                distance: -depth,
            });
        }
        Ok(*p)
    }
}

/// `x` wrapped into `[0, l)`.
pub(crate) fn wrap1(x: f64, l: f64) -> f64 {
    let w = x.rem_euclid(l);
    // rem_euclid can round up to exactly l for tiny negative x.
    if w >= l { 0.0 } else { w }
}

/// The plane `x[axis] = position` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// Normal axis.
    pub axis: Axis,
    /// Coordinate of the plane along the axis (m).
    pub position: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_rejects_outside_and_wraps_periodic() {
        let d = Domain::of_container(&Container::Box { size: [1.0; 3] }).unwrap();
        assert!(d.locate(&Vec3::new(0.5, 0.5, 1.0)).is_ok());
        let e = d.locate(&Vec3::new(0.5, 1.5, 0.5)).unwrap_err();
        assert!(matches!(e, PostError::ProbeOutside { distance, .. } if (distance - 0.5).abs() < 1e-12));
        assert!(e.to_string().contains("1.5"), "{e}");
        assert!(d.locate(&Vec3::new(f64::NAN, 0.0, 0.0)).is_err());
        let p = Domain::of_container(&Container::Periodic { size: [2.0; 3] }).unwrap();
        assert_eq!(
            p.locate(&Vec3::new(-0.5, 2.5, 1.0)).unwrap(),
            Vec3::new(1.5, 0.5, 1.0)
        );
        assert!(Domain::of_container(&Container::Sphere { radius: -1.0 }).is_err());
    }
}
