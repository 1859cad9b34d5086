//! Sub-particle interfaces: the "laminate" (composite-voxel) phase rule.
//!
//! A particle cut by a phase interface (|signed distance of its centre| < R_p) carries a
//! [`Mix`]: the other phase, the fraction of its volume in that phase and the interface
//! normal. Its conductivity is the tensor of a laminate of the two phases (Kabel, Merkert &
//! Andrä 2015, composite voxels in FFT homogenisation):
//!
//! Λ = λ_∥ (I − n nᵀ) + λ_⊥ n nᵀ, λ_∥ = (1−w) λ_a + w λ_b (arithmetic, along the layers),
//! λ_⊥ = 1/((1−w)/λ_a + w/λ_b) (harmonic, across them),
//!
//! with λ_a the particle's own phase (the phase of its centre, as the centre rule gives),
//! λ_b the other phase and w the other phase's volume fraction. The half-bond of a contact
//! along the unit branch e uses λ_p(e) = eᵀ Λ e ([`HalfBond::Laminate`]); the two half-bonds
//! then combine by the [`InterfaceRule`] as for unmixed particles. Capacities (ρc) and any
//! scalar property mix arithmetically.
//!
//! [`HalfBond::Segment`] is the network's own reading of the same geometry: a half-bond is
//! the segment from the centre along e over half the branch length ℓ, and its conductivity
//! is the series mix over the part u of that segment beyond the (plane) interface:
//! 1/λ_p(e) = (1−u)/λ_a + u/λ_b, u = clamp(1 − δ/(ℓ e·n), 0, 1) when the segment heads
//! towards the interface (e·n > 0, n pointing to the other phase, δ the centre's distance to
//! the interface), else u = 0: branches along the interface see the centre's phase.

use demcon_core::{CoreError, ParticleSet, Region, Vec3};

use crate::error::{GraphError, same_len};
use crate::phase::RegionQuery;
use crate::{ContactGraph, InterfaceRule, interface_value_split};

/// A particle cut by a phase interface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mix {
    /// The particle.
    pub particle: u32,
    /// The phase on the other side of the interface (the particle's own phase is the phase
    /// of its centre, `ParticleSet::phases`).
    pub other_phase: u16,
    /// Fraction of the particle's volume in `other_phase`, in (0, 1).
    pub other_fraction: f64,
    /// Unit normal of the interface at the particle, pointing from its own phase into
    /// `other_phase`.
    pub normal: Vec3,
    /// Distance (m) from the particle's centre to the interface along `normal` (≥ 0).
    pub offset: f64,
    /// A second interface plane (unit normal towards `other_phase`, offset in m) when the
    /// particle's centre lies outside a union of spheres and two of them cut it (a particle
    /// in the gap between two inclusions); only [`HalfBond::Segment`] uses it.
    pub second: Option<(Vec3, f64)>,
    /// How its half-bonds see the two phases.
    pub half_bond: HalfBond,
}

/// How the half-bond of a particle cut by an interface sees the two phases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HalfBond {
    /// eᵀ Λ e of the laminate tensor (volume fractions; arithmetic along the interface,
    /// harmonic across).
    #[default]
    Laminate,
    /// Series mix along the half-bond segment (the part of the branch beyond the interface).
    Segment,
}

impl Mix {
    /// λ_p(e) = eᵀ Λ e of the laminate for a property `own` (the particle's phase) and
    /// `other` (same unit, both > 0) along the unit vector `e`.
    pub fn along(&self, own: f64, other: f64, e: &Vec3) -> f64 {
        laminate_value(own, other, self.other_fraction, e.dot(&self.normal).powi(2))
    }

    /// Fraction of the segment from the centre along the unit vector `e` over `length` (m)
    /// that lies beyond the (plane) interface — beyond either plane when there are two (the
    /// parts beyond each plane both run to the segment's end, so their union is the longer).
    pub fn segment_fraction(&self, e: &Vec3, length: f64) -> f64 {
        let beyond = |n: &Vec3, offset: f64| {
            let k = e.dot(n);
            if k <= 0.0 || length <= 0.0 {
                0.0
            } else {
                (1.0 - offset / (k * length)).clamp(0.0, 1.0)
            }
        };
        let u = beyond(&self.normal, self.offset);
        match &self.second {
            Some((n, offset)) => u.max(beyond(n, *offset)),
            None => u,
        }
    }

    /// The half-bond value of a property (`own`, `other` > 0) along the unit vector `e` over
    /// a half-bond of `length` (m), by this mix's [`HalfBond`] rule.
    pub fn half_bond_value(&self, own: f64, other: f64, e: &Vec3, length: f64) -> f64 {
        match self.half_bond {
            HalfBond::Laminate => self.along(own, other, e),
            HalfBond::Segment => {
                let u = self.segment_fraction(e, length);
                if u <= 0.0 {
                    own
                } else {
                    1.0 / ((1.0 - u) / own + u / other)
                }
            }
        }
    }

    /// The arithmetic mix (1−w)·own + w·other (heat capacity per volume, density).
    pub fn arithmetic(&self, own: f64, other: f64) -> f64 {
        (1.0 - self.other_fraction) * own + self.other_fraction * other
    }
}

/// eᵀ Λ e for a laminate of `a` (fraction 1−w) and `b` (fraction w) whose normal makes
/// cos²θ = `cos2` with e: λ_∥ + (λ_⊥ − λ_∥) cos²θ.
pub fn laminate_value(a: f64, b: f64, w: f64, cos2: f64) -> f64 {
    if a == b || w <= 0.0 {
        return a;
    }
    let par = (1.0 - w) * a + w * b;
    let perp = 1.0 / ((1.0 - w) / a + w / b);
    par + (perp - par) * cos2.clamp(0.0, 1.0)
}

/// Volume fraction of a ball of radius `r` whose centre lies at signed distance `s` from a
/// plane, on the negative side: the cap h²(3r − h)/(4r³) with h = r − s clamped to [0, 2r].
pub fn plane_cut_fraction(s: f64, r: f64) -> f64 {
    let h = (r - s).clamp(0.0, 2.0 * r);
    h * h * (3.0 * r - h) / (4.0 * r * r * r)
}

/// Volume fraction of a ball of radius `r` whose centre lies at distance `d` from the
/// centre of a sphere of radius `a`, inside that sphere (exact lens volume).
pub fn sphere_cut_fraction(d: f64, r: f64, a: f64) -> f64 {
    if d >= r + a {
        return 0.0;
    }
    if d + r <= a {
        return 1.0;
    }
    if d + a <= r {
        return (a / r).powi(3);
    }
    // Lens of two spheres at distance d.
    let v = std::f64::consts::PI
        * (a + r - d).powi(2)
        * (d * d + 2.0 * d * r - 3.0 * r * r + 2.0 * d * a + 6.0 * a * r - 3.0 * a * a)
        / (12.0 * d);
    (v / (4.0 / 3.0 * std::f64::consts::PI * r.powi(3))).clamp(0.0, 1.0)
}

/// Fraction of the ball (c, r) inside `region`: exact for a sphere and for a union of
/// disjoint spheres (the sum of the lenses, at most 1), a plane cut at the signed distance
/// otherwise (exact for planes, good while the region's curvature radius ≫ r).
pub fn inside_fraction(region: &Region, c: &Vec3, r: f64) -> f64 {
    match region {
        Region::Sphere { centre, radius } => sphere_cut_fraction((c - centre).norm(), r, *radius),
        Region::Union(rs) if rs.iter().all(|x| matches!(x, Region::Sphere { .. })) => {
            rs.iter().map(|x| inside_fraction(x, c, r)).sum::<f64>().min(1.0)
        }
        _ => plane_cut_fraction(region.signed_distance(c), r),
    }
}

/// Unit gradient of the region's signed distance at `c` (central differences of step
/// `h` m); the x axis where the gradient vanishes.
pub fn interface_normal(region: &Region, c: &Vec3, h: f64) -> Vec3 {
    let mut g = Vec3::zeros();
    for k in 0..3 {
        let mut dp = *c;
        let mut dm = *c;
        dp[k] += h;
        dm[k] -= h;
        g[k] = region.signed_distance(&dp) - region.signed_distance(&dm);
    }
    let n = g.norm();
    if n > 0.0 && n.is_finite() {
        g / n
    } else {
        Vec3::x()
    }
}

/// Laminate phase rule: every particle whose sphere lies wholly in `region` takes `phase`
/// (as the centre rule would); every particle cut by the region's boundary keeps the phase
/// of its centre (`phase` if the centre is inside, its previous phase otherwise) and gets a
/// [`Mix`] with the other phase, the volume fraction in it and the interface normal.
/// A particle cut again by a later region loses its earlier mix (one interface per
/// particle). `mixes` stays sorted by particle; `half_bond` says how the new mixes'
/// half-bonds see the phases. Returns the particles whose centre lies in the region (the
/// centre rule's count).
pub fn assign_phase_laminate(
    particles: &mut ParticleSet,
    region: &Region,
    phase: u16,
    mixes: &mut Vec<Mix>,
    half_bond: HalfBond,
) -> usize {
    let mut count = 0;
    let mut new = Vec::new();
    let mut touched = Vec::new();
    // Everything below reads the region within r (and the normal's step, 1e-3 r) of a centre.
    let reach = 1.01 * particles.radii.iter().copied().fold(0.0, f64::max);
    let query = RegionQuery::new(region, reach);
    for p in 0..particles.len() {
        let c = particles.centres[p];
        let r = particles.radii[p];
        let near = query.near(&c);
        let region = near.as_ref();
        let s = region.signed_distance(&c);
        if s >= r {
            continue; // wholly outside: unchanged
        }
        let inside = s <= 0.0;
        let old = particles.phases[p];
        if inside {
            particles.phases[p] = phase;
            count += 1;
            touched.push(p as u32);
        }
        if s <= -r {
            continue; // wholly inside
        }
        let v = inside_fraction(region, &c, r);
        let w = if inside { 1.0 - v } else { v };
        let other = if inside { old } else { phase };
        if other != particles.phases[p] && w > 1e-12 && w < 1.0 - 1e-12 {
            if !inside {
                touched.push(p as u32);
            }
            // The signed distance grows outwards: the other phase lies outside when the
            // centre is inside.
            let grad = interface_normal(region, &c, 1e-3 * r);
            new.push(Mix {
                particle: p as u32,
                other_phase: other,
                other_fraction: w,
                normal: if inside { grad } else { -grad },
                offset: s.abs(),
                second: if inside {
                    None
                } else {
                    second_sphere(region, &c, r)
                },
                half_bond,
            });
        }
    }
    // `touched` is sorted (particles in order): drop their old mixes, add the new ones.
    mixes.retain(|m| touched.binary_search(&m.particle).is_err());
    mixes.extend(new);
    mixes.sort_by_key(|m| m.particle);
    count
}

/// For a centre outside a union of spheres: the plane of the second-nearest sphere that cuts
/// the ball (c, r) — unit normal from c towards its centre and the distance from c to its
/// surface — if two or more cut it.
fn second_sphere(region: &Region, c: &Vec3, r: f64) -> Option<(Vec3, f64)> {
    let Region::Union(rs) = region else {
        return None;
    };
    let mut cuts: Vec<(f64, Vec3)> = rs
        .iter()
        .filter_map(|x| match x {
            Region::Sphere { centre, radius } => {
                let d = centre - c;
                let dist = d.norm();
                let s = dist - radius;
                (s > 0.0 && s < r && dist > 0.0).then(|| (s, d / dist))
            }
            _ => None,
        })
        .collect();
    if cuts.len() < 2 {
        return None;
    }
    cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
    Some((cuts[1].1, cuts[1].0))
}

/// The mixes of a particle set, indexed for lookup by particle.
#[derive(Debug, Clone)]
pub struct Laminates<'a> {
    mixes: &'a [Mix],
    /// Index into `mixes` per particle, `u32::MAX` for none.
    index: Vec<u32>,
}

impl<'a> Laminates<'a> {
    /// Indexes `mixes` (particles < `n`).
    pub fn new(n: usize, mixes: &'a [Mix]) -> Self {
        let mut index = vec![u32::MAX; n];
        for (k, m) in mixes.iter().enumerate() {
            if (m.particle as usize) < n {
                index[m.particle as usize] = k as u32;
            }
        }
        Self { mixes, index }
    }

    /// The mix of particle `p`, if it is cut by an interface.
    pub fn get(&self, p: usize) -> Option<&Mix> {
        match self.index.get(p) {
            Some(&k) if k != u32::MAX => Some(&self.mixes[k as usize]),
            _ => None,
        }
    }

    /// Particle `p`'s half-bond value of a property (one value per phase) along the unit
    /// vector `e` over a half-bond of `length` (m).
    pub fn half_bond(&self, p: usize, phases: &[u16], per_phase: &[f64], e: &Vec3, length: f64) -> f64 {
        let own = per_phase[phases[p] as usize];
        match self.get(p) {
            Some(m) => m.half_bond_value(own, per_phase[m.other_phase as usize], e, length),
            None => own,
        }
    }

    /// Particle `p`'s arithmetic mix of a property (one value per phase).
    pub fn arithmetic(&self, p: usize, phases: &[u16], per_phase: &[f64]) -> f64 {
        let own = per_phase[phases[p] as usize];
        match self.get(p) {
            Some(m) => m.arithmetic(own, per_phase[m.other_phase as usize]),
            None => own,
        }
    }

    /// Share of each of `n_phases` phases in the particles' own (sphere) volume:
    /// Σ_p v_p,phase V_p / Σ V_p.
    pub fn phase_fractions(&self, particles: &ParticleSet, n_phases: usize) -> Vec<f64> {
        let spheres: Vec<f64> = (0..particles.len()).map(|p| particles.volume(p)).collect();
        self.phase_fractions_by(particles, &spheres, n_phases)
    }

    /// Share of each of `n_phases` phases in the volumes `volumes` (m³ per particle, e.g. the
    /// Laguerre cells: the body's volume fractions): Σ_p v_p,phase W_p / Σ W_p, a cut
    /// particle split by its laminate fraction.
    pub fn phase_fractions_by(&self, particles: &ParticleSet, volumes: &[f64], n_phases: usize) -> Vec<f64> {
        debug_assert_eq!(volumes.len(), particles.len());
        let mut v = vec![0.0; n_phases];
        for (p, &vp) in volumes.iter().enumerate() {
            let own = particles.phases[p] as usize;
            match self.get(p) {
                Some(m) => {
                    if own < n_phases {
                        v[own] += (1.0 - m.other_fraction) * vp;
                    }
                    if (m.other_phase as usize) < n_phases {
                        v[m.other_phase as usize] += m.other_fraction * vp;
                    }
                }
                None if own < n_phases => v[own] += vp,
                None => {}
            }
        }
        let total: f64 = volumes.iter().sum();
        v.iter().map(|x| x / total).collect()
    }
}

/// Like [`crate::contact_property`], with particles cut by interfaces: each contact combines
/// the half-bond values λ_p(e) and λ_q(−e) over its two half-bonds (halves, or split at the
/// Laguerre facet) by `rule`.
///
/// Errors: as [`crate::contact_property`], and a mix whose other phase has no value.
pub fn contact_property_laminate(
    graph: &ContactGraph,
    phases: &[u16],
    per_phase: &[f64],
    mixes: &[Mix],
    rule: InterfaceRule,
) -> Result<Vec<f64>, GraphError> {
    let base = crate::contact_property(graph, phases, per_phase, rule)?;
    if mixes.is_empty() {
        return Ok(base);
    }
    same_len("phases", phases.len(), graph.n_particles, "particle")?;
    if let Some(m) = mixes
        .iter()
        .find(|m| m.other_phase as usize >= per_phase.len() || m.particle as usize >= phases.len())
    {
        return Err(CoreError::invalid(
            format!("mix of particle {}", m.particle),
            m.other_phase,
            format!(
                "a particle < {} and a phase with a value (0..{})",
                phases.len(),
                per_phase.len()
            ),
        )
        .into());
    }
    let lam = Laminates::new(phases.len(), mixes);
    Ok(graph
        .pairs
        .iter()
        .zip(&graph.geometry)
        .zip(base)
        .enumerate()
        .map(|(k, ((&[p, q], g), b))| {
            let (p, q) = (p as usize, q as usize);
            if lam.get(p).is_none() && lam.get(q).is_none() {
                return b;
            }
            let w = graph.split(k);
            let a = lam.half_bond(p, phases, per_phase, &g.normal, w * g.distance);
            let c = lam.half_bond(q, phases, per_phase, &(-g.normal), (1.0 - w) * g.distance);
            interface_value_split(a, c, w, rule)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cap_and_lens_fractions() {
        assert_eq!(plane_cut_fraction(1.0, 1.0), 0.0);
        assert_eq!(plane_cut_fraction(-1.0, 1.0), 1.0);
        assert!((plane_cut_fraction(0.0, 1.0) - 0.5).abs() < 1e-15);
        // Cap of height h = 0.5 r: π h²(3r−h)/3 over 4π r³/3.
        assert!((plane_cut_fraction(0.5, 1.0) - 0.25 * 2.5 / 4.0).abs() < 1e-15);
        // A small ball on the surface of a huge sphere: the plane cut.
        let big = 1e4;
        for s in [-0.7, -0.2, 0.0, 0.3, 0.9] {
            let f = sphere_cut_fraction(big + s, 1.0, big);
            assert!((f - plane_cut_fraction(s, 1.0)).abs() < 1e-3, "s = {s}: {f}");
        }
        // Same-size spheres with coincident centres, and a ball holding the sphere.
        assert!((sphere_cut_fraction(1e-9, 1.0, 1.0) - 1.0).abs() < 1e-6);
        assert!((sphere_cut_fraction(0.1, 2.0, 1.0) - 0.125).abs() < 1e-15);
        // Lens volume of two unit spheres at d = 1: 5π/12.
        let lens = 5.0 * std::f64::consts::PI / 12.0 / (4.0 / 3.0 * std::f64::consts::PI);
        assert!((sphere_cut_fraction(1.0, 1.0, 1.0) - lens).abs() < 1e-12);
    }

    #[test]
    fn normals_of_known_regions() {
        let ball = Region::Sphere {
            centre: Vec3::zeros(),
            radius: 1.0,
        };
        let n = interface_normal(&ball, &Vec3::new(0.6, 0.8, 0.0), 1e-4);
        assert!((n - Vec3::new(0.6, 0.8, 0.0)).norm() < 1e-6);
        let half = Region::Box {
            min: Vec3::new(-10.0, -10.0, -10.0),
            max: Vec3::new(10.0, 0.0, 10.0),
        };
        let n = interface_normal(&half, &Vec3::new(0.3, 0.1, -0.2), 1e-4);
        assert!((n - Vec3::y()).norm() < 1e-9);
    }

    #[test]
    fn laminate_limits() {
        // Across the layers: series; along them: parallel.
        let (a, b, w) = (1.0, 9.0, 0.25);
        assert!((laminate_value(a, b, w, 1.0) - 1.0 / (0.75 / a + 0.25 / b)).abs() < 1e-15);
        assert!((laminate_value(a, b, w, 0.0) - (0.75 * a + 0.25 * b)).abs() < 1e-15);
        assert_eq!(laminate_value(2.0, 2.0, 0.4, 0.3), 2.0);
        let m = Mix {
            particle: 0,
            other_phase: 1,
            other_fraction: w,
            normal: Vec3::z(),
            offset: 0.1,
            second: None,
            half_bond: HalfBond::Laminate,
        };
        // Segment: along the normal, beyond the offset; nothing across or away from it.
        assert!((m.segment_fraction(&Vec3::z(), 0.4) - 0.75).abs() < 1e-15);
        assert_eq!(m.segment_fraction(&(-Vec3::z()), 0.4), 0.0);
        assert_eq!(m.segment_fraction(&Vec3::x(), 0.4), 0.0);
        let seg = Mix {
            half_bond: HalfBond::Segment,
            ..m
        };
        assert!((seg.half_bond_value(a, b, &Vec3::z(), 0.4) - 1.0 / (0.25 / a + 0.75 / b)).abs() < 1e-15);
        assert_eq!(seg.half_bond_value(a, b, &Vec3::x(), 0.4), a);
        // A second plane (a particle between two inclusions): the segment sees the nearer
        // crossing of either.
        let two = Mix {
            second: Some((Vec3::x(), 0.2)),
            ..seg
        };
        assert!((two.segment_fraction(&Vec3::x(), 0.4) - 0.5).abs() < 1e-15);
        assert!((two.segment_fraction(&Vec3::z(), 0.4) - 0.75).abs() < 1e-15);
        assert_eq!(two.segment_fraction(&(-Vec3::x()), 0.4), 0.0);
        let e = Vec3::new(1.0, 0.0, 1.0).normalize();
        let mid = m.along(a, b, &e);
        assert!((mid - 0.5 * (laminate_value(a, b, w, 0.0) + laminate_value(a, b, w, 1.0))).abs() < 1e-14);
    }

    #[test]
    fn a_particle_between_two_inclusions_carries_both_planes() {
        // Two unit spheres 2.6 apart along x; a ball of radius 0.5 midway (0.3 from each)
        // is cut by both; one at 1.2 from the first only by it.
        let mut p = ParticleSet::new(
            vec![Vec3::new(1.3, 0.0, 0.0), Vec3::new(0.0, 1.2, 0.0)],
            vec![0.5; 2],
        )
        .unwrap();
        let two = Region::Union(vec![
            Region::Sphere {
                centre: Vec3::zeros(),
                radius: 1.0,
            },
            Region::Sphere {
                centre: Vec3::new(2.6, 0.0, 0.0),
                radius: 1.0,
            },
        ]);
        let mut mixes = Vec::new();
        assign_phase_laminate(&mut p, &two, 1, &mut mixes, HalfBond::Segment);
        assert_eq!(mixes.len(), 2);
        let (n1, s1) = (mixes[0].normal, mixes[0].offset);
        let (n2, s2) = mixes[0].second.expect("cut by both spheres");
        assert!((s1 - 0.3).abs() < 1e-9 && (s2 - 0.3).abs() < 1e-9);
        assert!(
            (n1.x.abs() - 1.0).abs() < 1e-6 && (n1 + n2).norm() < 1e-6,
            "{n1:?} {n2:?}"
        );
        assert!((mixes[0].other_fraction - 2.0 * sphere_cut_fraction(1.3, 0.5, 1.0)).abs() < 1e-12);
        // Segments towards either sphere cross its surface at 0.3 of a 0.4 half-bond.
        for e in [Vec3::x(), -Vec3::x()] {
            assert!((mixes[0].segment_fraction(&e, 0.4) - 0.25).abs() < 1e-6);
        }
        assert_eq!(mixes[1].second, None);
    }

    #[test]
    fn laminate_assignment_keeps_centre_phases() {
        let mut p = ParticleSet::new(
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(0.8, 0.0, 0.0),
                Vec3::new(1.2, 0.0, 0.0),
                Vec3::new(3.0, 0.0, 0.0),
            ],
            vec![0.5; 4],
        )
        .unwrap();
        let ball = Region::Sphere {
            centre: Vec3::zeros(),
            radius: 1.0,
        };
        let mut mixes = Vec::new();
        assert_eq!(
            assign_phase_laminate(&mut p, &ball, 1, &mut mixes, HalfBond::Laminate),
            2
        );
        assert_eq!(p.phases, vec![1, 1, 0, 0]);
        assert_eq!(mixes.len(), 2);
        assert_eq!((mixes[0].particle, mixes[0].other_phase), (1, 0));
        assert_eq!((mixes[1].particle, mixes[1].other_phase), (2, 1));
        assert!((mixes[0].other_fraction - (1.0 - sphere_cut_fraction(0.8, 0.5, 1.0))).abs() < 1e-15);
        assert!((mixes[1].other_fraction - sphere_cut_fraction(1.2, 0.5, 1.0)).abs() < 1e-15);
        // Normals point into the other phase; offsets are the distances to the sphere.
        assert!((mixes[0].normal - Vec3::x()).norm() < 1e-6);
        assert!((mixes[1].normal + Vec3::x()).norm() < 1e-6);
        assert!((mixes[0].offset - 0.2).abs() < 1e-12 && (mixes[1].offset - 0.2).abs() < 1e-12);
        // Carried inclusion volume: particle 0 whole, 1 and 2 in part.
        let lam = Laminates::new(4, &mixes);
        let f = lam.phase_fractions(&p, 2);
        let v_in = 1.0 + (1.0 - mixes[0].other_fraction) + mixes[1].other_fraction;
        assert!((f[1] - v_in / 4.0).abs() < 1e-12);
        assert!((f[0] + f[1] - 1.0).abs() < 1e-12);
        // A later region over particle 1 wholly removes its mix.
        let big = Region::Sphere {
            centre: Vec3::zeros(),
            radius: 2.0,
        };
        assign_phase_laminate(&mut p, &big, 1, &mut mixes, HalfBond::Laminate);
        assert!(mixes.iter().all(|m| m.particle != 1 && m.particle != 2));
    }

    /// A simple cubic lattice of touching unit-diameter spheres, nx × ny × nz, in a box.
    fn lattice(nx: usize, ny: usize, nz: usize) -> (ParticleSet, demcon_core::Container) {
        let mut c = Vec::new();
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    c.push(Vec3::new(0.5 + i as f64, 0.5 + j as f64, 0.5 + k as f64));
                }
            }
        }
        let n = c.len();
        let box_ = demcon_core::Container::Box {
            size: [nx as f64, ny as f64, nz as f64],
        };
        (ParticleSet::new(c, vec![0.5; n]).unwrap(), box_)
    }

    /// Conductivity of the lattice along x between its first and last layers of centres,
    /// with equal surfaces on every contact (the common factor S/d dropped): the chains
    /// along x in parallel, each a series of its contacts. Exact when no heat crosses
    /// between chains (every chain alike, or each chain uniform along x).
    fn lattice_conductivity_x(
        p: &ParticleSet,
        g: &ContactGraph,
        lam: &[f64],
        ny: usize,
        nz: usize,
        nx: usize,
    ) -> f64 {
        let mut chain_r = std::collections::BTreeMap::<(i64, i64), f64>::new();
        for (k, &[a, _]) in g.pairs.iter().enumerate() {
            if g.geometry[k].normal.x.abs() > 0.99 {
                let c = p.centres[a as usize];
                *chain_r
                    .entry(((c.y * 2.0) as i64, (c.z * 2.0) as i64))
                    .or_default() += 1.0 / lam[k];
            }
        }
        assert_eq!(chain_r.len(), ny * nz);
        // Σ chain conductances × length (nx − 1) / section (ny nz).
        chain_r.values().map(|r| 1.0 / r).sum::<f64>() * (nx - 1) as f64 / (ny * nz) as f64
    }

    #[test]
    fn lattice_series_and_parallel() {
        lattice_series_and_parallel_with(HalfBond::Laminate, true);
        lattice_series_and_parallel_with(HalfBond::Segment, false);
    }

    /// The series result for both half-bond rules (the cut layer's centres on the plane);
    /// the parallel result for the laminate (`parallel`), the centre's phase for the
    /// segment rule (its branches run along the plane).
    fn lattice_series_and_parallel_with(hb: HalfBond, parallel_expected: bool) {
        let (nx, ny, nz) = (6, 4, 3);
        let (la, lb) = (1.0, 7.0);
        let per_phase = [la, lb];
        let params = crate::ContactParams::relative(0.01);
        let rule = InterfaceRule::HarmonicMean;
        // Series: the plane x = 2.5 (through the centres of layer 2) normal to the flow;
        // phase 1 beyond it. Between the first (x = 0.5) and last (x = 5.5) centres: 2 of
        // phase 0 then 3 of phase 1.
        let (mut p, container) = lattice(nx, ny, nz);
        let g = crate::detect_contacts(&p, &container, &params).unwrap();
        let beyond = Region::Box {
            min: Vec3::new(2.5, -1.0, -1.0),
            max: Vec3::new(10.0, 10.0, 10.0),
        };
        let mut mixes = Vec::new();
        assign_phase_laminate(&mut p, &beyond, 1, &mut mixes, hb);
        assert_eq!(mixes.len(), ny * nz);
        assert!(mixes.iter().all(|m| (m.other_fraction - 0.5).abs() < 1e-12));
        let lam = contact_property_laminate(&g, &p.phases, &per_phase, &mixes, rule).unwrap();
        let series = 5.0 / (2.0 / la + 3.0 / lb);
        let got = lattice_conductivity_x(&p, &g, &lam, ny, nz, nx);
        assert!((got - series).abs() < 1e-12 * series, "{got} vs series {series}");
        // The centre rule puts the whole cut layer in phase 1: 1.5 + 3.5 instead of 2 + 3.
        let centre = crate::contact_property(&g, &p.phases, &per_phase, rule).unwrap();
        let got_c = lattice_conductivity_x(&p, &g, &centre, ny, nz, nx);
        assert!((got_c - 5.0 / (1.5 / la + 3.5 / lb)).abs() < 1e-12, "{got_c}");

        // Parallel: the plane y = 1.5 (through the centres of row 1) along the flow; phase 1
        // above it. Rows are cells of width 1 in y: 1.5 of phase 0, 2.5 of phase 1.
        let (mut p, container) = lattice(nx, ny, nz);
        let g = crate::detect_contacts(&p, &container, &params).unwrap();
        let above = Region::Box {
            min: Vec3::new(-1.0, 1.5, -1.0),
            max: Vec3::new(10.0, 10.0, 10.0),
        };
        let mut mixes = Vec::new();
        assign_phase_laminate(&mut p, &above, 1, &mut mixes, hb);
        assert_eq!(mixes.len(), nx * nz);
        let lam = contact_property_laminate(&g, &p.phases, &per_phase, &mixes, rule).unwrap();
        let parallel = if parallel_expected {
            (1.5 * la + 2.5 * lb) / 4.0
        } else {
            (la + 3.0 * lb) / 4.0
        };
        let got = lattice_conductivity_x(&p, &g, &lam, ny, nz, nx);
        assert!(
            (got - parallel).abs() < 1e-12 * parallel,
            "{got} vs parallel {parallel}"
        );
    }

    #[test]
    fn segment_rule_gives_the_series_result_at_any_plane_position() {
        // A chain of touching unit spheres along x, the plane x = x0 anywhere inside: the
        // segment rule puts the interface exactly where it is along the chain.
        let (nx, ny, nz) = (6, 1, 1);
        let (la, lb) = (1.0, 7.0);
        for x0 in [2.1, 2.3, 2.5, 2.75, 2.95, 3.2] {
            let (mut p, container) = lattice(nx, ny, nz);
            let g = crate::detect_contacts(&p, &container, &crate::ContactParams::relative(0.01)).unwrap();
            let beyond = Region::Box {
                min: Vec3::new(x0, -1.0, -1.0),
                max: Vec3::new(10.0, 10.0, 10.0),
            };
            let mut mixes = Vec::new();
            assign_phase_laminate(&mut p, &beyond, 1, &mut mixes, HalfBond::Segment);
            let lam =
                contact_property_laminate(&g, &p.phases, &[la, lb], &mixes, InterfaceRule::HarmonicMean)
                    .unwrap();
            let got = lattice_conductivity_x(&p, &g, &lam, ny, nz, nx);
            // Between the first (0.5) and last (5.5) centres.
            let series = 5.0 / ((x0 - 0.5) / la + (5.5 - x0) / lb);
            assert!(
                (got - series).abs() < 1e-12 * series,
                "x0 = {x0}: {got} vs {series}"
            );
        }
    }
}
