//! Event-time predictions and collision rules for growing hard spheres (pure functions).
//!
//! Radii grow linearly in time; a sphere of radius `r` grows at `ṙ` (m per time unit).
//! All times returned are delays from "now" (time units), `f64::INFINITY` for "never".
//! Roots are taken in the cancellation-free form `c / (−b + √(b² − ac))` (Bannerman et al.
//! 2012, arXiv 1211.6718), which stays accurate when two spheres have just touched.

use demcon_core::Vec3;

/// Delay until two growing spheres touch.
///
/// `r = x_j − x_i` (m), `v = v_j − v_i` (m per time unit), `sigma = R_i + R_j` now (m),
/// `gamma = Ṙ_i + Ṙ_j` (m per time unit). Solves `|r + v τ| = σ + γ τ`, i.e.
/// `(v² − γ²) τ² + 2 (r·v − σγ) τ + (r² − σ²) = 0`. When growth outruns the relative motion
/// (`v² < γ²`) a collision always happens, whatever the direction of motion.
/// Touching or (round-off) overlapping pairs that are closing collide at once (delay 0).
#[inline]
pub fn pair_delay(r: &Vec3, v: &Vec3, sigma: f64, gamma: f64) -> f64 {
    let rv = r.dot(v);
    let r2 = r.norm_squared();
    pair_delay_coef(
        v.norm_squared() - gamma * gamma,
        rv - sigma * gamma,
        r2 - sigma * sigma,
        rv,
        r2,
        gamma,
    )
}

/// [`pair_delay`] from the coefficients of `aτ² + 2bτ + c = 0`: `a = v² − γ²`,
/// `b = r·v − σγ`, `c = r² − σ²`, with `rv = r·v`, `r2 = r²` and `gamma` for the closing
/// test of touching pairs.
#[inline]
pub fn pair_delay_coef(a: f64, b: f64, c: f64, rv: f64, r2: f64, gamma: f64) -> f64 {
    if c <= 0.0 {
        // Same closing test as `collide_pair` (n·v < γ), so a collision at once always
        // changes the velocities and cannot be rescheduled at the same instant.
        return if rv < r2.sqrt() * gamma {
            0.0
        } else {
            f64::INFINITY
        };
    }
    if b >= 0.0 && a >= 0.0 {
        return f64::INFINITY;
    }
    let disc = b * b - a * c;
    if disc < 0.0 {
        return f64::INFINITY;
    }
    let den = -b + disc.sqrt();
    if den > 0.0 { c / den } else { f64::INFINITY }
}

/// Delay until a growing sphere touches a plane it is moving in front of.
///
/// `gap` = distance from the centre to the plane minus the radius (m), `w` = velocity
/// component along the inward normal (m per time unit), `rdot` = growth rate of the radius.
/// The gap closes at `ṙ − w`.
#[inline]
pub fn plane_delay(gap: f64, w: f64, rdot: f64) -> f64 {
    let closing = rdot - w;
    if closing <= 0.0 {
        f64::INFINITY
    } else if gap <= 0.0 {
        0.0
    } else {
        gap / closing
    }
}

/// Delay until a growing sphere, inside a ball, touches the ball's surface.
///
/// `p` = centre of the sphere minus centre of the ball (m), `v` its velocity, `room` =
/// ball radius minus sphere radius now (m), `rdot` the sphere's growth rate. Solves
/// `|p + v τ| = room − ṙ τ`. Used for spherical walls, the radial wall of a cylinder (with
/// `p`, `v` projected on the plane normal to the axis) and the neighbour-list bounding
/// spheres.
#[inline]
pub fn inside_ball_delay(p: &Vec3, v: &Vec3, room: f64, rdot: f64) -> f64 {
    let b = p.dot(v) + room * rdot;
    let c = p.norm_squared() - room * room;
    if c >= 0.0 || room <= 0.0 {
        // Same closing test as `collide_wall` (inward speed below ṙ).
        return if p.dot(v) + p.norm() * rdot > 0.0 {
            0.0
        } else {
            f64::INFINITY
        };
    }
    let a = v.norm_squared() - rdot * rdot;
    let disc = (b * b - a * c).max(0.0);
    let den = b + disc.sqrt();
    if den > 0.0 { -c / den } else { f64::INFINITY }
}

/// Collision of two equal-mass growing spheres: the normal relative speed is reflected about
/// the growth speed, `s' = 2γ − s` where `s = n·(v_j − v_i)` is the separation rate.
///
/// `n` = unit vector from i to j, `gamma` = `Ṙ_i + Ṙ_j`. Returns the impulse per unit mass
/// `|b|` (m per time unit) given to each sphere, 0 if the pair is not closing (then nothing
/// changes). The kinetic energy grows by `|b| γ` (unit masses): growth injects energy.
#[inline]
pub fn collide_pair(vi: &mut Vec3, vj: &mut Vec3, n: &Vec3, gamma: f64) -> f64 {
    let b = n.dot(&(*vj - *vi)) - gamma;
    if b >= 0.0 {
        return 0.0;
    }
    *vi += b * n;
    *vj -= b * n;
    -b
}

/// Reflection of a growing sphere off a fixed wall with inward unit normal `n_in`:
/// `w' = 2ṙ − w` for the inward component `w`. Returns the change of `w` (≥ 0), or 0 if the
/// sphere was not closing on the wall.
#[inline]
pub fn collide_wall(v: &mut Vec3, n_in: &Vec3, rdot: f64) -> f64 {
    let w = v.dot(n_in);
    if w >= rdot {
        return 0.0;
    }
    let dw = 2.0 * (rdot - w);
    *v += dw * n_in;
    dw
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Gap after `tau` for the pair problem, directly from the definition.
    fn pair_gap(r: &Vec3, v: &Vec3, sigma: f64, gamma: f64, tau: f64) -> f64 {
        (r + v * tau).norm() - (sigma + gamma * tau)
    }

    #[test]
    fn head_on_without_growth() {
        let r = Vec3::new(3.0, 0.0, 0.0);
        let v = Vec3::new(-1.0, 0.0, 0.0);
        assert_relative_eq!(pair_delay(&r, &v, 1.0, 0.0), 2.0, epsilon = 1e-14);
        // Moving apart: never.
        assert!(pair_delay(&r, &(-v), 1.0, 0.0).is_infinite());
    }

    #[test]
    fn growth_outruns_separation() {
        // Separating at speed 0.5 while the radii sum grows at 1: they must meet.
        let r = Vec3::new(2.0, 0.0, 0.0);
        let v = Vec3::new(0.5, 0.0, 0.0);
        let tau = pair_delay(&r, &v, 1.0, 1.0);
        assert_relative_eq!(tau, 2.0, epsilon = 1e-14);
        assert!(pair_gap(&r, &v, 1.0, 1.0, tau).abs() < 1e-13);
    }

    #[test]
    fn oblique_roots_are_contacts_and_first() {
        // Sweep random-ish configurations: the root is a contact, the gap is positive before.
        let mut k = 0.0_f64;
        for i in 0..200 {
            k += 0.7;
            let r = Vec3::new(2.0 + (k).sin(), (1.3 * k).cos(), 0.5 * (0.7 * k).sin());
            let v = Vec3::new(-(0.3 * k).cos().abs() - 0.1, (2.1 * k).sin(), (1.7 * k).cos());
            let gamma = 0.05 * (i % 5) as f64;
            let tau = pair_delay(&r, &v, 1.0, gamma);
            if tau.is_finite() {
                assert!(pair_gap(&r, &v, 1.0, gamma, tau).abs() < 1e-12, "i={i}");
                for f in [0.1, 0.5, 0.9] {
                    assert!(pair_gap(&r, &v, 1.0, gamma, f * tau) > 0.0);
                }
            } else {
                for t in [0.1, 1.0, 10.0, 100.0] {
                    assert!(pair_gap(&r, &v, 1.0, gamma, t) > 0.0, "i={i} t={t}");
                }
            }
        }
    }

    #[test]
    fn touching_pair_after_collision_meets_again_only_by_growth() {
        // Just after a collision the pair is touching and separating at 2γ − s.
        let n = Vec3::new(1.0, 0.0, 0.0);
        let mut vi = Vec3::new(1.0, 0.2, 0.0);
        let mut vj = Vec3::new(-1.0, 0.0, 0.3);
        let gamma = 0.1;
        let imp = collide_pair(&mut vi, &mut vj, &n, gamma);
        assert_relative_eq!(imp, 2.1, epsilon = 1e-14);
        let s_after = n.dot(&(vj - vi));
        assert_relative_eq!(s_after, 2.0 * gamma + 2.0, epsilon = 1e-14);
        // Tangential components untouched.
        assert_eq!((vi.y, vj.z), (0.2, 0.3));
        let r = n * 1.0;
        assert!(pair_delay(&r, &(vj - vi), 1.0, gamma).is_infinite());
    }

    #[test]
    fn collision_conserves_momentum_and_injects_energy() {
        let n = Vec3::new(0.6, 0.8, 0.0);
        let (mut vi, mut vj) = (Vec3::new(0.5, 0.9, -0.2), Vec3::new(-0.4, -0.3, 0.1));
        let (p0, e0) = (vi + vj, vi.norm_squared() + vj.norm_squared());
        let gamma = 0.05;
        let imp = collide_pair(&mut vi, &mut vj, &n, gamma);
        assert_relative_eq!((vi + vj - p0).norm(), 0.0, epsilon = 1e-15);
        let de = 0.5 * (vi.norm_squared() + vj.norm_squared() - e0);
        assert_relative_eq!(de, imp * gamma, epsilon = 1e-14);
    }

    #[test]
    fn overlapping_pair_collides_at_once_only_if_the_rule_acts() {
        // Overlap by round-off; separating slightly faster than growth along n, but
        // r·v − σγ < 0: must not be scheduled at delay 0 (the rule would do nothing).
        let r = Vec3::new(0.999_999, 0.0, 0.0);
        let gamma = 0.1;
        let v = Vec3::new(0.100_000_05, 0.0, 0.0);
        assert!(pair_delay(&r, &v, 1.0, gamma).is_infinite());
        let (mut vi, mut vj) = (Vec3::zeros(), v);
        assert_eq!(collide_pair(&mut vi, &mut vj, &Vec3::x(), gamma), 0.0);
        // Closing: delay 0, and the rule acts.
        let v = Vec3::new(0.05, 0.0, 0.0);
        assert_eq!(pair_delay(&r, &v, 1.0, gamma), 0.0);
        let (mut vi, mut vj) = (Vec3::zeros(), v);
        assert!(collide_pair(&mut vi, &mut vj, &Vec3::x(), gamma) > 0.0);
    }

    #[test]
    fn planes_and_balls() {
        assert_relative_eq!(plane_delay(1.0, -1.0, 0.0), 1.0);
        assert_relative_eq!(plane_delay(1.0, 0.5, 1.0), 2.0); // growth catches up
        assert!(plane_delay(1.0, 1.0, 0.5).is_infinite());
        // Still sphere at the centre, 2 m of room shrinking at 1 m per time unit: 2 time units.
        let tau = inside_ball_delay(&Vec3::zeros(), &Vec3::zeros(), 2.0, 1.0);
        assert_relative_eq!(tau, 2.0, epsilon = 1e-14);
        // Moving at 1 towards the wall without growth.
        let tau = inside_ball_delay(&Vec3::zeros(), &Vec3::new(0.0, 1.0, 0.0), 2.0, 0.0);
        assert_relative_eq!(tau, 2.0, epsilon = 1e-14);
        // Off-centre, oblique.
        let p = Vec3::new(0.5, -0.3, 0.2);
        let v = Vec3::new(-0.7, 0.4, 0.9);
        let (room, rdot) = (1.5, 0.2);
        let tau = inside_ball_delay(&p, &v, room, rdot);
        assert!(((p + v * tau).norm() - (room - rdot * tau)).abs() < 1e-13);
        let mut w = Vec3::new(0.0, 0.0, -2.0);
        let dw = collide_wall(&mut w, &Vec3::new(0.0, 0.0, 1.0), 0.5);
        assert_relative_eq!(dw, 5.0);
        assert_relative_eq!(w.z, 3.0);
    }
}
