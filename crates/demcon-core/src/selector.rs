//! Selectors turn "the particles touching face YMin" or "the particles in this region"
//! into sorted particle ids.

use crate::{Container, CoreError, ParticleSet, Region};

/// Default largest gap between a particle's surface and a face for the particle to count
/// as touching it, as a fraction of the particle's radius.
pub const DEFAULT_FACE_GAP: f64 = 0.5;

/// A face of a container.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Face {
    /// The plane x = min.
    XMin,
    /// The plane x = max.
    XMax,
    /// The plane y = min.
    YMin,
    /// The plane y = max.
    YMax,
    /// The plane z = min.
    ZMin,
    /// The plane z = max.
    ZMax,
    /// The curved wall of a cylinder or a sphere.
    Outer,
    /// The surface of the carving region a carved body was cut from (Laguerre cells only: the
    /// cells clipped by it are its facets). Not a face of the container.
    Carved,
}

impl Face {
    /// The face's name as written in scene files and messages (`XMin` … `Outer`).
    pub fn name(self) -> &'static str {
        match self {
            Face::XMin => "XMin",
            Face::XMax => "XMax",
            Face::YMin => "YMin",
            Face::YMax => "YMax",
            Face::ZMin => "ZMin",
            Face::ZMax => "ZMax",
            Face::Outer => "Outer",
            Face::Carved => "Carved",
        }
    }

    /// The axis a flat face is normal to; `None` for the curved `Outer` and `Carved` faces.
    pub fn axis(self) -> Option<crate::Axis> {
        use crate::Axis;
        match self {
            Face::XMin | Face::XMax => Some(Axis::X),
            Face::YMin | Face::YMax => Some(Axis::Y),
            Face::ZMin | Face::ZMax => Some(Axis::Z),
            Face::Outer | Face::Carved => None,
        }
    }

    /// The two faces normal to `axis`: (min side, max side).
    pub fn pair(axis: crate::Axis) -> (Face, Face) {
        use crate::Axis;
        match axis {
            Axis::X => (Face::XMin, Face::XMax),
            Axis::Y => (Face::YMin, Face::YMax),
            Axis::Z => (Face::ZMin, Face::ZMax),
        }
    }
}

/// Which particles a boundary condition, probe or phase applies to.
#[derive(Debug, Clone, PartialEq)]
pub enum Selector {
    /// Every particle.
    All,
    /// Particles whose surface comes within [`DEFAULT_FACE_GAP`] × their radius of the face.
    Face(Face),
    /// Particles whose surface comes within `gap` (m) of the face.
    FaceWithin {
        /// The face.
        face: Face,
        /// Largest surface-to-face gap (m).
        gap: f64,
    },
    /// Particles whose centre lies in the region.
    Region(Region),
    /// Particles of one phase.
    Phase(u16),
    /// Explicit particle ids.
    Particles(Vec<u32>),
}

impl Selector {
    /// The ids (sorted, unique) of the selected particles. Fails when a face does not exist
    /// on this container or an explicit id is out of range; an empty result is not an error
    /// here (see [`Selector::select_nonempty`]).
    pub fn select(&self, particles: &ParticleSet, container: &Container) -> Result<Vec<u32>, CoreError> {
        let n = particles.len();
        let ids: Vec<u32> = match self {
            Selector::All => (0..n as u32).collect(),
            Selector::Face(face) => self.face_ids(particles, container, *face, |r| DEFAULT_FACE_GAP * r)?,
            Selector::FaceWithin { face, gap } => {
                if !(gap.is_finite() && *gap >= 0.0) {
                    return Err(CoreError::invalid(
                        "gap",
                        gap,
                        "must be a finite distance ≥ 0 (m)",
                    ));
                }
                self.face_ids(particles, container, *face, |_| *gap)?
            }
            Selector::Region(region) => (0..n)
                .filter(|&i| region.contains_point(&particles.centres[i]))
                .map(|i| i as u32)
                .collect(),
            Selector::Phase(ph) => (0..n)
                .filter(|&i| particles.phases[i] == *ph)
                .map(|i| i as u32)
                .collect(),
            Selector::Particles(list) => {
                if let Some(&bad) = list.iter().find(|&&i| i as usize >= n) {
                    return Err(CoreError::invalid(
                        "particles",
                        bad,
                        format!("ids must be below the particle count {n}"),
                    ));
                }
                let mut v = list.clone();
                v.sort_unstable();
                v.dedup();
                v
            }
        };
        Ok(ids)
    }

    /// Like [`Selector::select`], but an empty selection is an error naming `what`.
    pub fn select_nonempty(
        &self,
        particles: &ParticleSet,
        container: &Container,
        what: &str,
    ) -> Result<Vec<u32>, CoreError> {
        let ids = self.select(particles, container)?;
        if ids.is_empty() {
            return Err(CoreError::EmptySelection {
                what: what.to_string(),
            });
        }
        Ok(ids)
    }

    fn face_ids(
        &self,
        particles: &ParticleSet,
        container: &Container,
        face: Face,
        gap: impl Fn(f64) -> f64,
    ) -> Result<Vec<u32>, CoreError> {
        if !container.faces().contains(&face) {
            let have: Vec<&str> = container.faces().iter().map(|f| f.name()).collect();
            let carved = if face == Face::Carved {
                " (the carved surface is a wall for WallTemperature, HeatFlux, Convection, Radiation and \
                 face electrodes, not a particle selection: select particles near it with a Region)"
            } else {
                ""
            };
            return Err(CoreError::invalid(
                "face",
                face.name(),
                format!(
                    "a {} container has the faces [{}]{carved}",
                    container.kind(),
                    have.join(", ")
                ),
            ));
        }
        Ok((0..particles.len())
            .filter(|&i| {
                let r = particles.radii[i];
                let d = container
                    .face_distance(face, &particles.centres[i])
                    .unwrap_or(f64::INFINITY);
                d - r <= gap(r)
            })
            .map(|i| i as u32)
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec3;

    #[test]
    fn faces_and_errors() {
        let c = Container::Box {
            size: [1.0, 1.0, 1.0],
        };
        let p = ParticleSet::new(
            vec![Vec3::new(0.1, 0.5, 0.5), Vec3::new(0.5, 0.5, 0.5)],
            vec![0.1, 0.1],
        )
        .unwrap();
        assert_eq!(Selector::Face(Face::XMin).select(&p, &c).unwrap(), vec![0]);
        assert!(
            Selector::Face(Face::XMax)
                .select_nonempty(&p, &c, "fixed temperature on XMax")
                .is_err()
        );
        assert!(Selector::Face(Face::Outer).select(&p, &c).is_err());
        assert!(Selector::Particles(vec![5]).select(&p, &c).is_err());
        assert_eq!(
            Selector::FaceWithin {
                face: Face::XMax,
                gap: 0.5
            }
            .select(&p, &c)
            .unwrap(),
            vec![1]
        );
    }
}
