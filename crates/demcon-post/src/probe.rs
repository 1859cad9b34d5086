//! Values at probe points and along lines: the nearest particle, or an average over a small
//! ball weighted by representative volume. Neighbour queries use an R*-tree (rstar).

use demcon_core::check::{check_len, check_positive};
use demcon_core::{ParticleSet, Vec3};
use rstar::RTree;
use rstar::primitives::GeomWithData;
use serde::{Deserialize, Serialize};

use crate::domain::Domain;
use crate::error::{PostError, check_particles};

/// How a probe turns particle values into a value at a point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ProbeMethod {
    /// The value of the particle whose centre is nearest to the point (ties: lowest id).
    Nearest,
    /// The average over the particles whose centre lies within `radius` (m) of the point,
    /// weighted by their representative volumes `V_rep` (so that it is a volume average of
    /// the piecewise-constant field). Fails if the ball holds no centre. In a periodic domain
    /// the radius must not exceed half the smallest period.
    BallAverage {
        /// Ball radius (m), > 0.
        radius: f64,
    },
}

/// A straight line sampled at `n_points` equally spaced points, both ends included.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// First point (m).
    pub from: Vec3,
    /// Last point (m).
    pub to: Vec3,
    /// Number of points, in 2..=[`MAX_PROFILE_POINTS`] (10⁶).
    pub n_points: usize,
}

type Entry = GeomWithData<[f64; 3], u32>;

/// A search structure over the particle centres, built once and queried at many points.
#[derive(Debug)]
pub struct ProbeIndex<'a> {
    particles: &'a ParticleSet,
    weights: &'a [f64],
    domain: &'a Domain,
    tree: RTree<Entry>,
}

impl<'a> ProbeIndex<'a> {
    /// Indexes the particles (centres wrapped into the cell when periodic).
    /// `rep_volumes` (m³, > 0) are the weights of [`ProbeMethod::BallAverage`].
    pub fn new(
        particles: &'a ParticleSet,
        rep_volumes: &'a [f64],
        domain: &'a Domain,
    ) -> Result<Self, PostError> {
        domain.validate()?;
        check_particles(particles)?;
        if particles.is_empty() {
            return Err(PostError::invalid(
                "particles",
                "0 particles",
                "at least one particle to probe",
            ));
        }
        check_len("rep_volumes", rep_volumes.len(), particles.len())?;
        check_positive("rep_volumes", rep_volumes)?;
        let entries = particles
            .centres
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let w = domain.wrap(c);
                GeomWithData::new([w.x, w.y, w.z], i as u32)
            })
            .collect();
        Ok(Self {
            particles,
            weights: rep_volumes,
            domain,
            tree: RTree::bulk_load(entries),
        })
    }

    /// Images of the (wrapped) point `q` to search from, each with its distance to the
    /// periodic cell (m), nearest first: `q` itself (distance 0), plus its 26 neighbouring
    /// images when the domain is periodic.
    fn images(&self, q: &Vec3) -> Vec<(f64, Vec3)> {
        let Some(l) = self.domain.period else {
            return vec![(0.0, *q)];
        };
        let mut out = Vec::with_capacity(27);
        for sx in -1..=1 {
            for sy in -1..=1 {
                for sz in -1..=1 {
                    let img = q + Vec3::new(sx as f64 * l[0], sy as f64 * l[1], sz as f64 * l[2]);
                    let d2: f64 = (0..3)
                        .map(|a| {
                            let d = (-img[a]).max(img[a] - l[a]).max(0.0);
                            d * d
                        })
                        .sum();
                    out.push((d2.sqrt(), img));
                }
            }
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        out
    }

    /// The particles and weights (summing to 1) that make the value at `point`.
    /// Errors: a point outside the domain ([`PostError::ProbeOutside`]), a bad ball radius,
    /// or an empty ball ([`PostError::EmptyProbe`]).
    pub fn stencil(&self, point: &Vec3, method: &ProbeMethod) -> Result<Vec<(u32, f64)>, PostError> {
        let q = self.domain.locate(point)?;
        match *method {
            ProbeMethod::Nearest => {
                let mut best: Option<(f64, u32)> = None;
                for (reach, img) in self.images(&q) {
                    if best.is_some_and(|(d2, _)| reach * reach > d2) {
                        break;
                    }
                    let a = [img.x, img.y, img.z];
                    let Some(nn) = self.tree.nearest_neighbor(a) else {
                        continue;
                    };
                    let d2 = dist2(nn.geom(), &a);
                    // All centres at that same distance: keep the lowest id.
                    let id = self
                        .tree
                        .locate_within_distance(a, d2)
                        .map(|e| e.data)
                        .min()
                        .unwrap_or(nn.data);
                    if best.is_none_or(|b| (d2, id) < b) {
                        best = Some((d2, id));
                    }
                }
                let (_, id) = best.expect("the tree is not empty");
                Ok(vec![(id, 1.0)])
            }
            ProbeMethod::BallAverage { radius } => {
                let half_period = self
                    .domain
                    .period
                    .map_or(f64::INFINITY, |l| 0.5 * l[0].min(l[1]).min(l[2]));
                if !(radius.is_finite() && radius > 0.0 && radius <= half_period) {
                    return Err(PostError::invalid(
                        "radius",
                        radius,
                        format!(
                            "the ball radius must be a finite number > 0 (m){}",
                            if half_period.is_finite() {
                                format!(" and at most half the smallest period ({half_period} m)")
                            } else {
                                String::new()
                            }
                        ),
                    ));
                }
                let mut ids: Vec<u32> = Vec::new();
                for (reach, img) in self.images(&q) {
                    if reach > radius {
                        break;
                    }
                    ids.extend(
                        self.tree
                            .locate_within_distance([img.x, img.y, img.z], radius * radius)
                            .map(|e| e.data),
                    );
                }
                if ids.is_empty() {
                    return Err(PostError::EmptyProbe {
                        point: [point.x, point.y, point.z],
                        radius,
                    });
                }
                ids.sort_unstable();
                let total: f64 = ids.iter().map(|&i| self.weights[i as usize]).sum();
                Ok(ids
                    .into_iter()
                    .map(|i| (i, self.weights[i as usize] / total))
                    .collect())
            }
        }
    }

    fn check_values(&self, len: usize) -> Result<(), PostError> {
        Ok(check_len("values", len, self.particles.len())?)
    }

    /// Value of a scalar particle field at `point` (unit of `values`).
    pub fn probe(&self, values: &[f64], point: &Vec3, method: &ProbeMethod) -> Result<f64, PostError> {
        self.check_values(values.len())?;
        let mut v = 0.0;
        for (i, w) in self.stencil(point, method)? {
            let x = values[i as usize];
            if !x.is_finite() {
                return Err(PostError::invalid(format!("values[{i}]"), x, "must be finite"));
            }
            v += w * x;
        }
        Ok(v)
    }

    /// Value of a vector particle field at `point` (unit of `values`).
    pub fn probe_vector(
        &self,
        values: &[Vec3],
        point: &Vec3,
        method: &ProbeMethod,
    ) -> Result<Vec3, PostError> {
        self.check_values(values.len())?;
        let mut v = Vec3::zeros();
        for (i, w) in self.stencil(point, method)? {
            let x = values[i as usize];
            if !x.iter().all(|c| c.is_finite()) {
                return Err(PostError::invalid(
                    format!("values[{i}]"),
                    format!("{:?}", x.as_slice()),
                    "must be finite",
                ));
            }
            v += w * x;
        }
        Ok(v)
    }

    /// Profile of a scalar field along `line`: `(s, value)` pairs where `s` is the distance
    /// from `line.from` (m). Every point must lie in the domain.
    pub fn profile(
        &self,
        values: &[f64],
        line: &Line,
        method: &ProbeMethod,
    ) -> Result<Vec<(f64, f64)>, PostError> {
        line_points(line)?
            .into_iter()
            .map(|(s, p)| Ok((s, self.probe(values, &p, method)?)))
            .collect()
    }
}

fn dist2(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum()
}

/// Most sample points of a profile line ([`Line::n_points`]): 10⁶ (a few tens of MB of
/// output; finer than any particle field needs). More is refused, not allocated.
pub const MAX_PROFILE_POINTS: usize = 1_000_000;

/// The sample points of a line and their distance from its start (m).
pub fn line_points(line: &Line) -> Result<Vec<(f64, Vec3)>, PostError> {
    crate::error::check_point("line.from", &line.from)?;
    crate::error::check_point("line.to", &line.to)?;
    if !(2..=MAX_PROFILE_POINTS).contains(&line.n_points) {
        return Err(PostError::invalid(
            "line.n_points",
            line.n_points,
            format!("from 2 (both ends are sampled) to {MAX_PROFILE_POINTS} points"),
        ));
    }
    let len = (line.to - line.from).norm();
    let m = (line.n_points - 1) as f64;
    Ok((0..line.n_points)
        .map(|i| {
            let t = i as f64 / m;
            (t * len, line.from + t * (line.to - line.from))
        })
        .collect())
}

/// Value of a scalar field at one point (builds an index: for many points, use
/// [`ProbeIndex`] or [`profile`]). `rep_volumes` (m³) weight the ball average.
pub fn probe(
    particles: &ParticleSet,
    rep_volumes: &[f64],
    values: &[f64],
    point: &Vec3,
    method: &ProbeMethod,
    domain: &Domain,
) -> Result<f64, PostError> {
    ProbeIndex::new(particles, rep_volumes, domain)?.probe(values, point, method)
}

/// Profile of a scalar field along a line: `(s, value)` pairs, `s` the distance from
/// `line.from` (m). `rep_volumes` (m³) weight the ball average.
pub fn profile(
    particles: &ParticleSet,
    rep_volumes: &[f64],
    values: &[f64],
    line: &Line,
    method: &ProbeMethod,
    domain: &Domain,
) -> Result<Vec<(f64, f64)>, PostError> {
    ProbeIndex::new(particles, rep_volumes, domain)?.profile(values, line, method)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n_points: usize) -> Line {
        Line {
            from: Vec3::new(0.0, 0.0, 0.0),
            to: Vec3::new(1.0, 0.0, 0.0),
            n_points,
        }
    }

    #[test]
    fn profiles_with_a_huge_points_are_refused_naming_points() {
        for n in [usize::MAX, 1usize << 32, MAX_PROFILE_POINTS + 1, 1] {
            let e = line_points(&line(n)).unwrap_err().to_string();
            assert!(e.contains("n_points") && e.contains(&n.to_string()), "{e}");
            assert!(e.contains("1000000"), "{e}");
        }
        assert_eq!(
            line_points(&line(MAX_PROFILE_POINTS)).unwrap().len(),
            MAX_PROFILE_POINTS
        );
    }
}
