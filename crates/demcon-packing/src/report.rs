//! What a packing is (N, volume fractions overall and in the bulk, radii, overlaps) and
//! what its run cost (events, time, stop reason).

use demcon_core::{Container, ParticleSet, Vec3};
use serde::Serialize;

use crate::lsa::grid::CellGrid;
use crate::params::StopReason;

/// Radius statistics (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RadiusSummary {
    /// Mean radius (m).
    pub mean: f64,
    /// Standard deviation (m).
    pub std: f64,
    /// Smallest radius (m).
    pub min: f64,
    /// Largest radius (m).
    pub max: f64,
}

/// Geometry of a packing in its container.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PackingSummary {
    /// Container kind (`box`, `cylinder`, `sphere`, `periodic`).
    pub container: String,
    /// Number of particles.
    pub n: usize,
    /// Volume fraction: sphere volumes over the container volume (dimensionless).
    pub phi: f64,
    /// Volume fraction in the bulk, `bulk_margin` (m) away from every wall (dimensionless);
    /// equal to `phi` in a periodic box; `None` when no bulk is left.
    pub phi_bulk: Option<f64>,
    /// Thickness of the excluded wall layer (m).
    pub bulk_margin: f64,
    /// Radii (m).
    pub radius: RadiusSummary,
    /// Largest overlap between two spheres or a sphere and a wall, divided by the smaller
    /// radius (dimensionless, 0 if none).
    pub max_overlap: f64,
}

/// Summary of a packing: volume fractions (bulk layer `bulk_margin_diameters` mean
/// diameters thick), radii and the largest overlap.
pub fn summarize(
    particles: &ParticleSet,
    container: &Container,
    bulk_margin_diameters: f64,
) -> PackingSummary {
    let s = particles.radius_stats();
    let margin = 2.0 * s.mean * bulk_margin_diameters;
    PackingSummary {
        container: container.kind().to_string(),
        n: particles.len(),
        phi: particles.solid_volume() / container.volume(),
        phi_bulk: bulk_phi(particles, container, margin),
        bulk_margin: margin,
        radius: RadiusSummary {
            mean: s.mean,
            std: s.std,
            min: s.min,
            max: s.max,
        },
        max_overlap: max_overlap(particles, Some(container)),
    }
}

/// Volume fraction of the region at least `margin` (m) from every wall (dimensionless).
///
/// Spheres wholly inside or outside that region count exactly; the part of a sphere
/// crossing its boundary is the fraction of a 12×12×12 point lattice over the sphere
/// (shifted off the cell centres by a golden-ratio fraction, so that it does not line up
/// with round-number cuts). Each cut sphere is off by at most a few % of its volume, with
/// errors of both signs for random positions: on packings the bulk value is good to ~1e-3;
/// a regular lattice cut identically everywhere is the worst case (test: within 0.01).
/// `None` if the region is empty. Periodic box: the plain volume fraction.
pub fn bulk_phi(particles: &ParticleSet, container: &Container, margin: f64) -> Option<f64> {
    use std::f64::consts::PI;
    let inner = match *container {
        Container::Periodic { .. } => {
            return Some(particles.solid_volume() / container.volume());
        }
        Container::Box { size } => size.iter().map(|l| (l - 2.0 * margin).max(0.0)).product(),
        Container::Cylinder { radius, length } => {
            PI * (radius - margin).max(0.0).powi(2) * (length - 2.0 * margin).max(0.0)
        }
        Container::Sphere { radius } => 4.0 / 3.0 * PI * (radius - margin).max(0.0).powi(3),
    };
    if inner <= 0.0 {
        return None;
    }
    const M: usize = 12;
    const SHIFT: f64 = 0.381_966_011_250_105; // 2 − golden ratio
    let mut solid = 0.0;
    for (i, c) in particles.centres.iter().enumerate() {
        let r = particles.radii[i];
        let d = container.wall_distance(c) - margin;
        if d >= r {
            solid += particles.volume(i);
        } else if d > -r {
            let (mut in_sphere, mut in_both) = (0usize, 0usize);
            for a in 0..M {
                for b in 0..M {
                    for k in 0..M {
                        let off = Vec3::new(a as f64, b as f64, k as f64)
                            .map(|u| (2.0 * (u + SHIFT) / M as f64 - 1.0) * r);
                        if off.norm_squared() <= r * r {
                            in_sphere += 1;
                            if container.wall_distance(&(c + off)) >= margin {
                                in_both += 1;
                            }
                        }
                    }
                }
            }
            solid += particles.volume(i) * in_both as f64 / in_sphere as f64;
        }
    }
    Some(solid / inner)
}

/// Largest overlap (dimensionless, relative to the smaller radius) between two spheres
/// (nearest periodic image in a periodic box) or between a sphere and a wall of
/// `container`; 0 when nothing overlaps. Linear time (cell grid).
pub fn max_overlap(particles: &ParticleSet, container: Option<&Container>) -> f64 {
    let n = particles.len();
    if n == 0 {
        return 0.0;
    }
    let rmax = particles.radii.iter().copied().fold(0.0, f64::max);
    let period = container.and_then(Container::period);
    let bounds = match container {
        Some(c @ Container::Periodic { .. }) => c.bounds(),
        _ => particles.bounds(),
    };
    let mut grid = CellGrid::new(&bounds, 2.0 * rmax, period.is_some(), n, 4 * n + 64);
    for (i, c) in particles.centres.iter().enumerate() {
        grid.insert(i, c);
    }
    let mut worst: f64 = 0.0;
    for (i, ci) in particles.centres.iter().enumerate() {
        let ri = particles.radii[i];
        grid.for_each_near(ci, |j| {
            if j <= i {
                return;
            }
            let mut d = particles.centres[j] - ci;
            if let Some(l) = period {
                for k in 0..3 {
                    d[k] -= l[k] * (d[k] / l[k]).round();
                }
            }
            let rj = particles.radii[j];
            let ov = (ri + rj - d.norm()) / ri.min(rj);
            worst = worst.max(ov);
        });
        if let Some(c) = container {
            worst = worst.max((ri - c.wall_distance(ci)) / ri);
        }
    }
    worst.max(0.0)
}

/// What a packing run produced and what it cost.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PackingReport {
    /// The packing itself: N, φ, bulk φ, radii, overlap.
    #[serde(flatten)]
    pub packing: PackingSummary,
    /// The volume fraction asked for (dimensionless).
    pub target_phi: f64,
    /// Random-close-packing estimate for the radius distribution (dimensionless).
    pub jamming_estimate: f64,
    /// Why the run stopped.
    pub stop: StopReason,
    /// Events processed: collisions between spheres, wall hits and neighbour-list rebuilds.
    pub events: u64,
    /// Sphere–sphere collisions among `events`.
    pub collisions: u64,
    /// Sphere–wall collisions among `events`.
    pub wall_collisions: u64,
    /// Stale events discarded (their partner had collided since); not in `events`.
    pub stale_events: u64,
    /// Thermostat rescales (each recomputes every scheduled event).
    pub thermostat_rescales: u64,
    /// Last reduced pressure `PV/(NkT)` measured from the collision virial (dimensionless).
    pub reduced_pressure: f64,
    /// `events` per second of wall-clock time in the event loop.
    pub events_per_s: f64,
    /// Wall-clock time of the whole `pack` call (s).
    pub wall_s: f64,
    /// Growth rate used (dimensionless, see [`crate::PackingParams::growth_rate`]).
    pub growth_rate: f64,
    /// Seed of the random generator.
    pub seed: u64,
}

impl PackingReport {
    /// Whether the target volume fraction was reached.
    pub fn reached_target(&self) -> bool {
        self.stop == StopReason::TargetReached
    }
}

impl std::fmt::Display for PackingSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "particles          {} in a {}", self.n, self.container)?;
        writeln!(f, "volume fraction    {:.5}", self.phi)?;
        match self.phi_bulk {
            Some(p) => writeln!(
                f,
                "  in the bulk      {p:.5} (farther than {:.4e} m from the walls)",
                self.bulk_margin
            )?,
            None => writeln!(
                f,
                "  in the bulk      n/a (no region {:.4e} m from the walls)",
                self.bulk_margin
            )?,
        }
        let r = &self.radius;
        writeln!(
            f,
            "radius (m)         mean {:.5e}  std {:.5e} (std/mean {:.4})  min {:.5e}  max {:.5e}",
            r.mean,
            r.std,
            r.std / r.mean,
            r.min,
            r.max
        )?;
        write!(
            f,
            "largest overlap    {:.2e} of the smaller radius",
            self.max_overlap
        )
    }
}

impl std::fmt::Display for PackingReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{}", self.packing)?;
        writeln!(
            f,
            "target             {:.5} (jamming estimate {:.3})",
            self.target_phi, self.jamming_estimate
        )?;
        writeln!(f, "stop               {}", self.stop)?;
        writeln!(
            f,
            "events             {} ({} collisions, {} wall hits, {} list rebuilds; {} stale skipped; {} thermostat rescales)",
            self.events,
            self.collisions,
            self.wall_collisions,
            self.events - self.collisions - self.wall_collisions,
            self.stale_events,
            self.thermostat_rescales
        )?;
        writeln!(f, "reduced pressure   {:.3e}", self.reduced_pressure)?;
        writeln!(f, "speed              {:.3e} events/s", self.events_per_s)?;
        write!(
            f,
            "wall time          {:.3} s (growth rate {}, seed {})",
            self.wall_s, self.growth_rate, self.seed
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bulk_phi_of_a_lattice_and_overlaps() {
        // Simple cubic lattice of touching unit-diameter spheres: φ = π/6.
        let n = 6;
        let mut c = vec![];
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    c.push(Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5));
                }
            }
        }
        let p = ParticleSet::new(c, vec![0.5; n * n * n]).unwrap();
        let cont = Container::Box { size: [n as f64; 3] };
        // Margin 1.25 diameters: the bulk box [1.25, 4.75]³ cuts through spheres. Reference:
        // midpoint rule on 140³ points, each tested against its nearest lattice site.
        let s = summarize(&p, &cont, 1.25);
        let (lo, w, m) = (1.25, 3.5, 140);
        let mut hits = 0usize;
        for a in 0..m {
            for b in 0..m {
                for k in 0..m {
                    let q = Vec3::new(a as f64, b as f64, k as f64).map(|u| lo + (u + 0.5) * w / m as f64);
                    let site = q.map(|u| u.floor() + 0.5);
                    hits += usize::from((q - site).norm_squared() <= 0.25);
                }
            }
        }
        let reference = hits as f64 / (m * m * m) as f64;
        assert!((s.phi - std::f64::consts::PI / 6.0).abs() < 1e-12);
        assert!(
            (s.phi_bulk.unwrap() - reference).abs() < 0.01,
            "{:?} vs {reference}",
            s.phi_bulk
        );
        assert!(s.max_overlap < 1e-12);
        let mut q = p.clone();
        q.centres[1].z -= 0.1; // overlap 0.1 with its neighbour: 0.2 of the radius
        assert!((max_overlap(&q, Some(&cont)) - 0.2).abs() < 1e-12);
        // Periodic images are seen.
        let per = Container::Periodic {
            size: [2.0, 2.0, 2.0],
        };
        let pair = ParticleSet::new(
            vec![Vec3::new(0.1, 1.0, 1.0), Vec3::new(1.8, 1.0, 1.0)],
            vec![0.2, 0.2],
        )
        .unwrap();
        assert!((max_overlap(&pair, Some(&per)) - 0.5).abs() < 1e-12);
    }
}
