//! Samples of a shaped inclusion's surface for the conforming seeds: rings along its meridian
//! (spheroids, round and flat cylinders are surfaces of revolution) at equal arc length, closer
//! where the meridian turns fast (a platelet's rim), each ring with points at equal arc length
//! round the axis, so every point stands for about one `spacing`² of surface — but never fewer
//! than six round a ring (one on a cap), so that a thin shape's tangent planes close round its
//! axis. A run of rings with as many points shares their azimuths: a fibre's side becomes flat
//! strips along it. Each point carries its outward normal, the local mean curvature, from
//! which the conforming code moves its tangent plane inwards so that the polyhedron of tangent
//! planes keeps the shape's volume (as r' does for a sphere), and the room its pair has before
//! it meets its neighbours'.

use demcon_core::{Ends, Inclusion, Vec3};

/// Dense points per piece of a meridian, from which the rings are read.
const DENSE: usize = 2048;

/// The fewest points round a ring off the poles: the tangent planes of a hexagon close round
/// the axis within 10 % of the ring's area before the planes are moved in.
const MIN_RING: usize = 6;

/// The closest rings along a sharp meridian (fraction of the spacing): a pair closer to its
/// surface than a few % of the spacing is dropped (`conform::MIN_OFFSET`), so rings finer than
/// that would hold no pairs.
const MIN_STEP: f64 = 0.1;

/// One sample of a surface.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sample {
    /// The point on the surface (m).
    pub at: Vec3,
    /// The outward unit normal.
    pub normal: Vec3,
    /// The surface it stands for (m²).
    pub area: f64,
    /// The mean curvature there (1/m; (κ₁ + κ₂)/2, positive where convex).
    pub curvature: f64,
    /// The room a pair has (m): the shortest of its ring's step along the meridian, the two
    /// next to it, and the chord to the next point round the ring, each shrunk by the surface's
    /// curvature across it (the inner seeds close in as 1 − d κ). A pair's seeds must stay
    /// within half of it of the surface not to meet the neighbouring pairs'.
    pub room: f64,
}

/// A point of a meridian: radius ρ and height z along the axis (m), the outward normal's
/// (ρ, z) components, and the mean curvature (1/m).
type MeridianPoint = (f64, f64, f64, f64, f64);

/// The meridian of `shape` from its top pole (or top face centre) to its bottom one, densely.
fn meridian(shape: &Inclusion) -> Vec<MeridianPoint> {
    let mut out = Vec::new();
    let mut piece = |f: &dyn Fn(f64) -> MeridianPoint| {
        for i in 0..=DENSE {
            out.push(f(i as f64 / DENSE as f64));
        }
    };
    match *shape {
        Inclusion::Spheroid { a, b, .. } => piece(&|u| {
            let t = u * std::f64::consts::PI;
            let (rho, z) = (b * t.sin(), a * t.cos());
            let (nr, nz) = (rho / (b * b), z / (a * a));
            let len = (nr * nr + nz * nz).sqrt();
            let k1 = a * b / (a * a * t.sin().powi(2) + b * b * t.cos().powi(2)).powf(1.5);
            let k2 = if rho > 1e-12 * b { nr / len / rho } else { k1 };
            (rho, z, nr / len, nz / len, 0.5 * (k1 + k2))
        }),
        Inclusion::Cylinder {
            radius: r,
            length,
            ends: Ends::Round,
            ..
        } => {
            let hs = 0.5 * length - r;
            let cap = |from: f64, z0: f64| {
                move |u: f64| {
                    let th = (from + 0.5 * u) * std::f64::consts::PI;
                    (r * th.sin(), z0 + r * th.cos(), th.sin(), th.cos(), 1.0 / r)
                }
            };
            piece(&cap(0.0, hs));
            piece(&|u| (r, hs - 2.0 * hs * u, 1.0, 0.0, 0.5 / r));
            piece(&cap(0.5, -hs));
        }
        Inclusion::Cylinder {
            radius: r, length, ..
        } => {
            let h = 0.5 * length;
            piece(&|u| (r * u, h, 0.0, 1.0, 0.0));
            piece(&|u| (r, h - length * u, 1.0, 0.0, 0.5 / r));
            piece(&|u| (r * (1.0 - u), -h, 0.0, -1.0, 0.0));
        }
    }
    out
}

/// The samples of `shape`'s surface, about `spacing` (m) apart (see the module doc); along the
/// meridian closer where it turns faster, at most half its radius of curvature apart, so that a
/// rim much sharper than `spacing` (a thin platelet's) still gets rings round it.
pub(crate) fn surface_samples(shape: &Inclusion, spacing: f64) -> Vec<Sample> {
    let dense = meridian(shape);
    // The warped arc length w: ds / min(spacing, max(ρ_c / 2, MIN_STEP spacing)), ρ_c the
    // meridian's radius of curvature from the normal's turn between dense points (a corner,
    // where two pieces meet at one point, adds nothing).
    let mut s = vec![0.0; dense.len()];
    let mut w = vec![0.0; dense.len()];
    for i in 1..dense.len() {
        let (a, b) = (dense[i - 1], dense[i]);
        let ds = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let turn = (a.2 * b.2 + a.3 * b.3).clamp(-1.0, 1.0).acos();
        s[i] = s[i - 1] + ds;
        w[i] = w[i - 1]
            + if ds > 0.0 {
                (ds / spacing).max((2.0 * turn).min(ds / (MIN_STEP * spacing)))
            } else {
                0.0
            };
    }
    let total = w[w.len() - 1];
    let rings = (total.round() as usize).max(1);
    let dw = total / rings as f64;
    let u = shape.axis();
    let helper = if u.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
    let e1 = u.cross(&helper).normalize();
    let e2 = u.cross(&e1);
    let centre = shape.centre();
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    // Each ring's dense point, the arc length it stands for along the meridian (m) and the
    // meridian's curvature there (1/m).
    let ring: Vec<(usize, f64, f64)> = (0..rings)
        .map(|k| {
            let target = (k as f64 + 0.5) * dw;
            let i = w.partition_point(|&v| v < target).clamp(1, dense.len() - 1);
            let step = dw * (s[i] - s[i - 1]) / (w[i] - w[i - 1]).max(1e-300);
            let step = if step.is_finite() && step > 0.0 {
                step.min(dw * spacing)
            } else {
                dw * spacing
            };
            // The meridian's curvature there (1/m), from the normal's turn between dense points.
            let (a, b) = (dense[i - 1], dense[i]);
            let ds = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
            let turn = (a.2 * b.2 + a.3 * b.3).clamp(-1.0, 1.0).acos();
            let meridian_curvature = if ds > 0.0 { turn / ds } else { 0.0 };
            (i, step, meridian_curvature)
        })
        .collect();
    let mut out = Vec::new();
    // Each ring turned by the golden angle from the last, unless it has as many points: a run
    // of equal rings (a fibre's side) then makes flat strips along the axis, and the flux
    // along the shape crosses no step of its surface.
    let (mut turn, mut last_count) = (0.0, 0);
    for (k, &(i, step, meridian_curvature)) in ring.iter().enumerate() {
        let (rho, z, nr, nz, curvature) = dense[i];
        let shortest = ring[k.saturating_sub(1)..(k + 2).min(rings)]
            .iter()
            .map(|r| r.1)
            .fold(step, f64::min);
        // At least MIN_RING points round a ring (one on a cap: a ring narrower than its step
        // whose normal is within 45° of the axis): fewer tangent planes would not close round
        // the axis, and a thin shape's inner cells would reach out sideways (a needle's tip).
        let circumference = 2.0 * std::f64::consts::PI * rho;
        let count = if rho < 0.4 * step && nz.abs() > 0.7 {
            1
        } else {
            ((circumference / spacing).round() as usize).max(MIN_RING)
        };
        // Along the meridian, the inner seeds of two rings close in as 1 − d κ₁; round the
        // ring, as 1 − d n_ρ / ρ.
        let along = shortest / (1.0 + shortest * meridian_curvature);
        let round = if count > 1 {
            let chord = 2.0 * rho * (std::f64::consts::PI / count as f64).sin();
            chord / (1.0 + chord * nr.max(0.0) / rho)
        } else {
            f64::INFINITY
        };
        let room = along.min(round);
        if count != last_count {
            turn += golden;
            last_count = count;
        }
        let area = step * 2.0 * std::f64::consts::PI * rho.max(0.25 * step) / count as f64;
        for j in 0..count {
            let phi = turn + 2.0 * std::f64::consts::PI * j as f64 / count as f64;
            let radial = e1 * phi.cos() + e2 * phi.sin();
            out.push(Sample {
                at: centre + u * z + radial * rho,
                normal: (radial * nr + u * nz).normalize(),
                area,
                curvature,
                room,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn total_area(shape: &Inclusion, spacing: f64) -> f64 {
        surface_samples(shape, spacing).iter().map(|s| s.area).sum()
    }

    #[test]
    fn samples_lie_on_the_surface_with_outward_normals_and_cover_its_area() {
        let c = Vec3::new(0.3, -0.2, 0.5);
        let axis = Vec3::new(1.0, 1.0, 0.0);
        let shapes = [
            Inclusion::spheroid(c, axis, 0.3, 0.1, "s").unwrap(),
            Inclusion::spheroid(c, axis, 0.05, 0.2, "s").unwrap(),
            Inclusion::cylinder(c, axis, 0.1, 0.5, Ends::Round, "s").unwrap(),
            Inclusion::cylinder(c, axis, 0.1, 0.5, Ends::Flat, "s").unwrap(),
        ];
        use std::f64::consts::PI;
        // Exact areas: prolate 2πb²(1 + a/(b e) asin e); oblate 2πb² + π a²/e ln((1+e)/(1−e)).
        let e: f64 = (1.0 - (0.1f64 / 0.3).powi(2)).sqrt();
        let prolate = 2.0 * PI * 0.01 * (1.0 + 0.3 / (0.1 * e) * e.asin());
        let eo: f64 = (1.0 - (0.05f64 / 0.2).powi(2)).sqrt();
        let oblate = 2.0 * PI * 0.04 + PI * 0.0025 / eo * ((1.0 + eo) / (1.0 - eo)).ln();
        let round = 4.0 * PI * 0.01 + 2.0 * PI * 0.1 * 0.3;
        let flat = 2.0 * PI * 0.01 + 2.0 * PI * 0.1 * 0.5;
        for (shape, area) in shapes.iter().zip([prolate, oblate, round, flat]) {
            assert!((shape.area() / area - 1.0).abs() < 1e-12, "{shape:?}");
            let spacing = 0.01;
            for smp in surface_samples(shape, spacing) {
                assert!(shape.signed_distance(&smp.at).abs() < 1e-9, "{shape:?}");
                // Outward: a step along the normal leaves the shape.
                assert!(shape.signed_distance(&(smp.at + smp.normal * 1e-4)) > 0.0);
                assert!((smp.normal.norm() - 1.0).abs() < 1e-12);
            }
            let got = total_area(shape, spacing);
            assert!((got / area - 1.0).abs() < 0.02, "{shape:?}: {got} vs {area}");
            // About one sample per spacing² of surface.
            let n = surface_samples(shape, spacing).len() as f64;
            assert!(
                (n * spacing * spacing / area - 1.0).abs() < 0.1,
                "{shape:?}: {n} samples"
            );
        }
    }

    #[test]
    fn a_needle_gets_closed_rings_and_straight_strips_along_its_side() {
        // A 20:1 prolate spheroid 1.1 spacings across: each ring has at least six points (or
        // one, on a cap), equal rings share their azimuths, and a pair's room is at most the
        // chord to its neighbour round the ring.
        let spacing = 0.0137;
        let s = Inclusion::spheroid(Vec3::zeros(), Vec3::z(), 0.3, 0.0075, "s").unwrap();
        let samples = surface_samples(&s, spacing);
        let mut rings: Vec<Vec<Sample>> = Vec::new();
        for smp in samples {
            match rings.last_mut() {
                Some(r) if r[0].at.z == smp.at.z => r.push(smp),
                _ => rings.push(vec![smp]),
            }
        }
        assert!(rings.len() > 40, "{} rings", rings.len());
        let azimuths = |r: &[Sample]| r.iter().map(|p| p.at.y.atan2(p.at.x)).collect::<Vec<_>>();
        let mut aligned = 0;
        for (k, r) in rings.iter().enumerate() {
            assert!(
                r.len() == 1 || r.len() >= MIN_RING,
                "ring {k}: {} points",
                r.len()
            );
            if r.len() > 1 {
                let rho = r[0].at.xy().norm();
                let chord = 2.0 * rho * (std::f64::consts::PI / r.len() as f64).sin();
                assert!(
                    r[0].room > 0.0 && r[0].room <= chord,
                    "ring {k}: room {}",
                    r[0].room
                );
            }
            if k > 0 && rings[k - 1].len() == r.len() {
                for (a, b) in azimuths(&rings[k - 1]).iter().zip(azimuths(r)) {
                    assert!((a - b).abs() < 1e-9, "ring {k}: {a} vs {b}");
                }
                aligned += 1;
            }
        }
        assert!(aligned > 30, "{aligned} aligned rings");
    }

    #[test]
    fn a_sphere_has_its_curvature_everywhere() {
        let s = Inclusion::spheroid(Vec3::zeros(), Vec3::z(), 0.2, 0.2, "s").unwrap();
        for smp in surface_samples(&s, 0.02) {
            assert!((smp.curvature - 5.0).abs() < 1e-6, "{}", smp.curvature);
        }
    }
}
