//! The particle set: centres, radii and phases, stored as parallel arrays.

use crate::{Aabb, CoreError, Vec3};

/// Spheres of a packing. Index `i` in every array is particle `i`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParticleSet {
    /// Centres (m).
    pub centres: Vec<Vec3>,
    /// Radii (m).
    pub radii: Vec<f64>,
    /// Phase (material index) of each particle; 0 by default.
    pub phases: Vec<u16>,
}

impl ParticleSet {
    /// A set of particles, all of phase 0. Fails on mismatched lengths, non-finite centres or
    /// non-positive radii, naming the particle.
    pub fn new(centres: Vec<Vec3>, radii: Vec<f64>) -> Result<Self, CoreError> {
        if centres.len() != radii.len() {
            return Err(CoreError::invalid(
                "radii",
                format!("{} values", radii.len()),
                format!("one radius per centre ({} centres)", centres.len()),
            ));
        }
        if let Some(i) = centres.iter().position(|c| !c.iter().all(|v| v.is_finite())) {
            return Err(CoreError::invalid(
                format!("centres[{i}]"),
                format!("{:?}", centres[i].as_slice()),
                "must be finite",
            ));
        }
        if let Some(i) = radii.iter().position(|r| !(r.is_finite() && *r > 0.0)) {
            return Err(CoreError::invalid(
                format!("radii[{i}]"),
                radii[i],
                "must be a finite number > 0 (m)",
            ));
        }
        let phases = vec![0; centres.len()];
        Ok(Self {
            centres,
            radii,
            phases,
        })
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.radii.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.radii.is_empty()
    }

    /// Volume of particle `i` (m³).
    pub fn volume(&self, i: usize) -> f64 {
        4.0 / 3.0 * std::f64::consts::PI * self.radii[i].powi(3)
    }

    /// Total volume of the spheres (m³).
    pub fn solid_volume(&self) -> f64 {
        (0..self.len()).map(|i| self.volume(i)).sum()
    }

    /// Mean, standard deviation, minimum and maximum radius (m). Zeros when empty.
    pub fn radius_stats(&self) -> RadiusStats {
        let n = self.len();
        if n == 0 {
            return RadiusStats::default();
        }
        let mean = self.radii.iter().sum::<f64>() / n as f64;
        let var = self.radii.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / n as f64;
        RadiusStats {
            mean,
            std: var.sqrt(),
            min: self.radii.iter().copied().fold(f64::INFINITY, f64::min),
            max: self.radii.iter().copied().fold(0.0, f64::max),
        }
    }

    /// Box around all spheres (m).
    pub fn bounds(&self) -> Aabb {
        let mut min = Vec3::repeat(f64::INFINITY);
        let mut max = Vec3::repeat(f64::NEG_INFINITY);
        for (c, &r) in self.centres.iter().zip(&self.radii) {
            min = min.inf(&(c - Vec3::repeat(r)));
            max = max.sup(&(c + Vec3::repeat(r)));
        }
        Aabb { min, max }
    }

    /// The particles `order[0], order[1], …` in that order: a permutation reorders the set,
    /// a subset extracts part of it. Ids must be below `len()`.
    pub fn permuted(&self, order: &[u32]) -> ParticleSet {
        ParticleSet {
            centres: order.iter().map(|&i| self.centres[i as usize]).collect(),
            radii: order.iter().map(|&i| self.radii[i as usize]).collect(),
            phases: order.iter().map(|&i| self.phases[i as usize]).collect(),
        }
    }

    /// The particles for which `keep` is true, and their old ids (in the same order).
    pub fn retain(&self, mut keep: impl FnMut(usize) -> bool) -> (ParticleSet, Vec<u32>) {
        let ids: Vec<u32> = (0..self.len()).filter(|&i| keep(i)).map(|i| i as u32).collect();
        (self.permuted(&ids), ids)
    }
}

/// Summary of a radius distribution (m).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RadiusStats {
    /// Mean radius (m).
    pub mean: f64,
    /// Standard deviation (m), population form.
    pub std: f64,
    /// Smallest radius (m).
    pub min: f64,
    /// Largest radius (m).
    pub max: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_particles() {
        assert!(ParticleSet::new(vec![Vec3::zeros()], vec![]).is_err());
        let e = ParticleSet::new(vec![Vec3::zeros(), Vec3::zeros()], vec![1.0, 0.0]).unwrap_err();
        assert!(e.to_string().contains("radii[1]"), "{e}");
    }

    #[test]
    fn permute_and_retain() {
        let p = ParticleSet::new(
            vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)],
            vec![0.1, 0.2],
        )
        .unwrap();
        let q = p.permuted(&[1, 0]);
        assert_eq!(q.radii, vec![0.2, 0.1]);
        let (r, ids) = p.retain(|i| p.radii[i] > 0.15);
        assert_eq!((r.len(), ids), (1, vec![1]));
        let s = p.radius_stats();
        assert!((s.mean - 0.15).abs() < 1e-15 && (s.std - 0.05).abs() < 1e-15);
    }
}
