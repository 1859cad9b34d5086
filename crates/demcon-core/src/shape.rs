//! Containers a packing is made in, axis-aligned boxes, and the axis enum.

use crate::error::{CoreError, positive};
use crate::{Face, Region, Vec3};

/// A coordinate axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    /// The x axis.
    X,
    /// The y axis.
    Y,
    /// The z axis.
    Z,
}

impl Axis {
    /// Index of the axis in a vector: 0, 1 or 2.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }

    /// Unit vector along the axis.
    pub fn unit(self) -> Vec3 {
        let mut v = Vec3::zeros();
        v[self.index()] = 1.0;
        v
    }
}

/// An axis-aligned box `[min, max]` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner (m).
    pub min: Vec3,
    /// Upper corner (m).
    pub max: Vec3,
}

impl Aabb {
    /// Edge lengths (m).
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Volume (m³).
    pub fn volume(&self) -> f64 {
        let e = self.extent();
        e.x * e.y * e.z
    }

    /// Whether the point lies in the closed box.
    pub fn contains(&self, p: &Vec3) -> bool {
        (0..3).all(|k| p[k] >= self.min[k] && p[k] <= self.max[k])
    }
}

/// The vessel a packing is grown in. All walls are hard except in `Periodic`.
///
/// Conventions (SI, m): a box spans `[0, LX] × [0, LY] × [0, LZ]`; a cylinder has its axis
/// along z, `x² + y² ≤ R²`, `0 ≤ z ≤ L`; a sphere is centred at the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Container {
    /// Box with hard walls spanning `[0, size]` (m).
    Box {
        /// Edge lengths LX, LY, LZ (m).
        size: [f64; 3],
    },
    /// Cylinder along z with hard walls.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length along z (m).
        length: f64,
    },
    /// Sphere centred at the origin with a hard wall.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// Periodic box spanning `[0, size]` (m); particles see the images across every face.
    Periodic {
        /// Periods LX, LY, LZ (m).
        size: [f64; 3],
    },
}

impl Container {
    /// Checks that every dimension is finite and positive; the error names the field.
    pub fn validate(&self) -> Result<(), CoreError> {
        match *self {
            Container::Box { size } | Container::Periodic { size } => {
                for (k, name) in ["size.x", "size.y", "size.z"].iter().enumerate() {
                    positive(name, size[k])?;
                }
            }
            Container::Cylinder { radius, length } => {
                positive("radius", radius)?;
                positive("length", length)?;
            }
            Container::Sphere { radius } => {
                positive("radius", radius)?;
            }
        }
        Ok(())
    }

    /// A short name: `box`, `cylinder`, `sphere` or `periodic`.
    pub fn kind(&self) -> &'static str {
        match self {
            Container::Box { .. } => "box",
            Container::Cylinder { .. } => "cylinder",
            Container::Sphere { .. } => "sphere",
            Container::Periodic { .. } => "periodic",
        }
    }

    /// Inner volume (m³).
    pub fn volume(&self) -> f64 {
        match *self {
            Container::Box { size } | Container::Periodic { size } => size[0] * size[1] * size[2],
            Container::Cylinder { radius, length } => std::f64::consts::PI * radius * radius * length,
            Container::Sphere { radius } => 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3),
        }
    }

    /// Bounding box (m).
    pub fn bounds(&self) -> Aabb {
        match *self {
            Container::Box { size } | Container::Periodic { size } => Aabb {
                min: Vec3::zeros(),
                max: Vec3::new(size[0], size[1], size[2]),
            },
            Container::Cylinder { radius, length } => Aabb {
                min: Vec3::new(-radius, -radius, 0.0),
                max: Vec3::new(radius, radius, length),
            },
            Container::Sphere { radius } => Aabb {
                min: Vec3::repeat(-radius),
                max: Vec3::repeat(radius),
            },
        }
    }

    /// The periods along x, y, z (m) of a periodic box, `None` for walled containers.
    pub fn period(&self) -> Option<[f64; 3]> {
        match *self {
            Container::Periodic { size } => Some(size),
            _ => None,
        }
    }

    /// The largest sphere radius that fits (m): half the smallest inner dimension.
    pub fn inradius(&self) -> f64 {
        match *self {
            Container::Box { size } | Container::Periodic { size } => {
                0.5 * size.iter().copied().fold(f64::INFINITY, f64::min)
            }
            Container::Cylinder { radius, length } => radius.min(0.5 * length),
            Container::Sphere { radius } => radius,
        }
    }

    /// The faces this container has, in a fixed order.
    pub fn faces(&self) -> &'static [Face] {
        match self {
            Container::Box { .. } => &[
                Face::XMin,
                Face::XMax,
                Face::YMin,
                Face::YMax,
                Face::ZMin,
                Face::ZMax,
            ],
            Container::Cylinder { .. } => &[Face::ZMin, Face::ZMax, Face::Outer],
            Container::Sphere { .. } => &[Face::Outer],
            Container::Periodic { .. } => &[],
        }
    }

    /// Distance (m) from point `p` to `face`, positive inside the container; `None` when the
    /// container has no such face.
    pub fn face_distance(&self, face: Face, p: &Vec3) -> Option<f64> {
        if !self.faces().contains(&face) {
            return None;
        }
        let b = self.bounds();
        Some(match face {
            Face::XMin => p.x - b.min.x,
            Face::XMax => b.max.x - p.x,
            Face::YMin => p.y - b.min.y,
            Face::YMax => b.max.y - p.y,
            Face::ZMin => p.z - b.min.z,
            Face::ZMax => b.max.z - p.z,
            Face::Outer => match *self {
                Container::Cylinder { radius, .. } => radius - (p.x * p.x + p.y * p.y).sqrt(),
                Container::Sphere { radius } => radius - p.norm(),
                _ => unreachable!("only cylinders and spheres have an outer face"),
            },
            Face::Carved => return None,
        })
    }

    /// Outward unit normal of `face` at (the projection of) point `p`; `None` when the
    /// container has no such face. On the curved face of a cylinder (sphere) it is the radial
    /// direction of `p` from the axis (centre); `+x` when `p` lies on the axis (centre).
    pub fn face_normal(&self, face: Face, p: &Vec3) -> Option<Vec3> {
        if !self.faces().contains(&face) {
            return None;
        }
        Some(match face {
            Face::XMin => -Vec3::x(),
            Face::XMax => Vec3::x(),
            Face::YMin => -Vec3::y(),
            Face::YMax => Vec3::y(),
            Face::ZMin => -Vec3::z(),
            Face::ZMax => Vec3::z(),
            Face::Outer => {
                let r = match self {
                    Container::Cylinder { .. } => Vec3::new(p.x, p.y, 0.0),
                    _ => *p,
                };
                let l = r.norm();
                if l > 0.0 { r / l } else { Vec3::x() }
            }
            Face::Carved => return None,
        })
    }

    /// Area (m²) of `face`; `None` when the container has no such face.
    pub fn face_area(&self, face: Face) -> Option<f64> {
        use std::f64::consts::PI;
        if !self.faces().contains(&face) {
            return None;
        }
        Some(match (*self, face) {
            (Container::Box { size }, f) => {
                size[0] * size[1] * size[2] / size[f.axis().expect("flat face").index()]
            }
            (Container::Cylinder { radius, .. }, Face::ZMin | Face::ZMax) => PI * radius * radius,
            (Container::Cylinder { radius, length }, _) => 2.0 * PI * radius * length,
            (Container::Sphere { radius }, _) => 4.0 * PI * radius * radius,
            (Container::Periodic { .. }, _) => unreachable!("a periodic box has no faces"),
        })
    }

    /// Cross-section (m²) normal to `axis` and length along it (m), for containers that are
    /// prisms along `axis` (box and periodic box: any axis; cylinder: z); `None` otherwise.
    pub fn section_and_length(&self, axis: Axis) -> Option<(f64, f64)> {
        let e = self.bounds().extent();
        let k = axis.index();
        match *self {
            Container::Box { .. } | Container::Periodic { .. } => Some((e.x * e.y * e.z / e[k], e[k])),
            Container::Cylinder { radius, length } if axis == Axis::Z => {
                Some((std::f64::consts::PI * radius * radius, length))
            }
            _ => None,
        }
    }

    /// Distance (m) from point `p` to the nearest wall, positive inside; `+∞` for a periodic box.
    pub fn wall_distance(&self, p: &Vec3) -> f64 {
        self.faces()
            .iter()
            .filter_map(|&f| self.face_distance(f, p))
            .fold(f64::INFINITY, f64::min)
    }

    /// The container as a region (a periodic box is its fundamental cell).
    pub fn region(&self) -> Region {
        match *self {
            Container::Box { size } | Container::Periodic { size } => Region::Box {
                min: Vec3::zeros(),
                max: Vec3::new(size[0], size[1], size[2]),
            },
            Container::Cylinder { radius, length } => Region::Cylinder {
                base: Vec3::zeros(),
                axis: Axis::Z,
                radius,
                length,
            },
            Container::Sphere { radius } => Region::Sphere {
                centre: Vec3::zeros(),
                radius,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volumes_and_distances() {
        let c = Container::Cylinder {
            radius: 1.0,
            length: 5.0,
        };
        assert!((c.volume() - 5.0 * std::f64::consts::PI).abs() < 1e-12);
        let p = Vec3::new(0.5, 0.0, 1.0);
        assert_eq!(c.face_distance(Face::ZMin, &p), Some(1.0));
        assert_eq!(c.face_distance(Face::Outer, &p), Some(0.5));
        assert_eq!(c.face_distance(Face::XMin, &p), None);
        assert!((c.wall_distance(&p) - 0.5).abs() < 1e-15);
        assert!(
            Container::Periodic { size: [1.0; 3] }
                .wall_distance(&p)
                .is_infinite()
        );
    }

    #[test]
    fn face_geometry() {
        let b = Container::Box {
            size: [1.0, 2.0, 4.0],
        };
        assert_eq!(b.face_area(Face::YMax), Some(4.0));
        assert_eq!(b.face_area(Face::Outer), None);
        assert_eq!(b.section_and_length(Axis::Z), Some((2.0, 4.0)));
        assert_eq!(b.face_normal(Face::XMin, &Vec3::zeros()), Some(-Vec3::x()));
        let c = Container::Cylinder {
            radius: 1.0,
            length: 3.0,
        };
        let n = c.face_normal(Face::Outer, &Vec3::new(0.0, 0.5, 2.0)).unwrap();
        assert!((n - Vec3::y()).norm() < 1e-15);
        assert!((c.face_area(Face::Outer).unwrap() - 6.0 * std::f64::consts::PI).abs() < 1e-12);
        assert_eq!(c.section_and_length(Axis::X), None);
        let s = Container::Sphere { radius: 2.0 };
        assert!((s.face_area(Face::Outer).unwrap() - 16.0 * std::f64::consts::PI).abs() < 1e-12);
        assert_eq!(
            Container::Periodic { size: [1.0; 3] }.face_normal(Face::XMin, &Vec3::zeros()),
            None
        );
        for f in b.faces() {
            let ax = f.axis().unwrap();
            let (lo, hi) = Face::pair(ax);
            assert!(*f == lo || *f == hi);
        }
    }

    #[test]
    fn validation_names_the_field() {
        let e = Container::Box {
            size: [1.0, -2.0, 1.0],
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("size.y"), "{e}");
        assert!(Container::Sphere { radius: f64::NAN }.validate().is_err());
    }
}
