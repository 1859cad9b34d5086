//! Per-particle flux from contact data (Haddad 2021 eq. 20, with the physical sign) and the
//! net flow through a plane, from plain arrays: contact pairs, branch vectors, conductances.

use demcon_core::check::{check_finite, check_len, check_positive};
use demcon_core::{ParticleSet, Vec3};
use serde::{Deserialize, Serialize};

use crate::Plane;
use crate::error::{PostError, check_finite_vec, check_particles};

/// Checks the contact arrays against each other and against `n` particles.
fn check_contacts(
    n: usize,
    pairs: &[[u32; 2]],
    branches: Option<&[Vec3]>,
    conductances: &[f64],
) -> Result<(), PostError> {
    if let Some(b) = branches {
        check_len("branches", b.len(), pairs.len())?;
        check_finite_vec("branches", b)?;
    }
    check_len("conductances", conductances.len(), pairs.len())?;
    if let Some(i) = conductances.iter().position(|g| !(g.is_finite() && *g >= 0.0)) {
        return Err(PostError::invalid(
            format!("conductances[{i}]"),
            conductances[i],
            "must be a finite number >= 0 (W/K or S)",
        ));
    }
    if let Some(c) = pairs
        .iter()
        .position(|&[p, q]| p as usize >= n || q as usize >= n || p == q)
    {
        return Err(PostError::invalid(
            format!("pairs[{c}]"),
            format!("{:?}", pairs[c]),
            format!("two different particle ids below {n}"),
        ));
    }
    Ok(())
}

/// Flux dipole of every particle, `D_p = Σ_q g_pq (u_q − u_p) ℓ_pq` (W·m for heat, A·m for
/// current). Each contact feeds both of its ends (the term is the same for p and q, since
/// swapping them flips both the difference and the branch).
///
/// - `pairs`: contacts `[p, q]` (particle ids, p ≠ q);
/// - `branches`: `ℓ_pq = x_q − x_p` per contact (m), the minimum image in a periodic box;
/// - `conductances`: `g_pq = λ S_pq / d_pq` per contact (W/K, or S for electric conduction);
/// - `values`: node values `u` per particle (K or °C; V). Its length is the particle count.
///
/// The accumulation is sequential in contact order, so the result is deterministic.
pub fn particle_dipoles(
    pairs: &[[u32; 2]],
    branches: &[Vec3],
    conductances: &[f64],
    values: &[f64],
) -> Result<Vec<Vec3>, PostError> {
    check_contacts(values.len(), pairs, Some(branches), conductances)?;
    check_finite("values", values)?;
    let mut dipoles = vec![Vec3::zeros(); values.len()];
    for ((&[p, q], l), &g) in pairs.iter().zip(branches).zip(conductances) {
        let (p, q) = (p as usize, q as usize);
        let term = (g * (values[q] - values[p])) * l;
        dipoles[p] += term;
        dipoles[q] += term;
    }
    Ok(dipoles)
}

/// [`particle_dipoles`] with each contact's flow acting at its Laguerre facet's centroid:
/// p receives `2 g (u_q − u_p) a_pq` and q `2 g (u_q − u_p) (ℓ_pq − a_pq)`, `a_pq` the facet
/// centroid relative to p (`levers`, m; `ℓ/2` gives [`particle_dipoles`]). With Laguerre cells
/// the flux `−D_p / (2 V_cell,p)` is then exact for a linear field in every cell, because
/// Σ_facets S (c_f − x_p) ⊗ n = V_cell I (the divergence theorem; wall links included with
/// their own facets' centroids, `WallContacts::add_dipoles`).
pub fn particle_dipoles_levers(
    pairs: &[[u32; 2]],
    branches: &[Vec3],
    conductances: &[f64],
    values: &[f64],
    levers: &[Vec3],
) -> Result<Vec<Vec3>, PostError> {
    check_contacts(values.len(), pairs, Some(branches), conductances)?;
    check_finite("values", values)?;
    check_len("levers", levers.len(), pairs.len())?;
    if let Some(k) = levers.iter().position(|a| !a.iter().all(|x| x.is_finite())) {
        return Err(PostError::invalid(
            format!("levers[{k}]"),
            format!("{:?}", levers[k].as_slice()),
            "must be finite (m)",
        ));
    }
    let mut dipoles = vec![Vec3::zeros(); values.len()];
    for (((&[p, q], l), &g), a) in pairs.iter().zip(branches).zip(conductances).zip(levers) {
        let (p, q) = (p as usize, q as usize);
        let flow = 2.0 * g * (values[q] - values[p]);
        dipoles[p] += flow * a;
        dipoles[q] += flow * (l - a);
    }
    Ok(dipoles)
}

/// Physical per-particle flux `q_p = −D_p / (2 V_rep,p)` (W/m² for heat, A/m² for current),
/// i.e. Haddad 2021 eq. 20 with the sign corrected: eq. 20 as printed, with `e_pq` from p to
/// q, gives `+λ∇T`; the physical flux is `−λ∇T` (see `refs/analytic.md` §3).
///
/// `rep_volumes` are the representative volumes `V_rep,p` (m³): `V_p/φ` in the calibrated
/// model, `V_p/f_v,p` in the Terreros model. The factor 1/2 comes from each contact being
/// shared by its two particles. Other arguments as in [`particle_dipoles`].
///
/// On a simple cubic lattice with `S = 4r²`, `d = 2r`, `V_rep = d³` and a linear field the
/// result is exactly `−λ∇T` (a unit test).
pub fn particle_flux(
    pairs: &[[u32; 2]],
    branches: &[Vec3],
    conductances: &[f64],
    rep_volumes: &[f64],
    values: &[f64],
) -> Result<Vec<Vec3>, PostError> {
    check_len("rep_volumes", rep_volumes.len(), values.len())?;
    check_positive("rep_volumes", rep_volumes)?;
    let mut d = particle_dipoles(pairs, branches, conductances, values)?;
    for (v, &w) in d.iter_mut().zip(rep_volumes) {
        *v *= -0.5 / w;
    }
    Ok(d)
}

/// Net flow through a plane, summed over the contacts whose branch crosses it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlaneFlow {
    /// Net flow in the `+axis` direction (W for heat, A for current).
    pub flow: f64,
    /// Number of contacts crossing the plane.
    pub contacts: usize,
}

/// Net flow through the plane `x[plane.axis] = plane.position` (m): the sum over crossing contacts of the
/// physical branch flow `g_pq (u_p − u_q)` from p to q, counted positive when it goes in the
/// `+axis` direction (W for heat, A for current).
///
/// In steady state with no sources between two planes, conservation makes the result the same
/// for every plane position and equal to the heat flow through a face: divide by the section
/// and the gradient for an effective conductivity (see
/// [`effective_conductivity`](crate::effective_conductivity)).
///
/// A contact crosses when `x_p` and `x_p + ℓ_pq` lie on different sides (a centre exactly on
/// the plane counts as on the `+` side). `period` is the box period along `axis` (m) in a
/// periodic box: then the planes `position + m·period` all count, so branches that wrap
/// around are handled; `None` for a walled container.
pub fn flow_across_plane(
    particles: &ParticleSet,
    pairs: &[[u32; 2]],
    branches: &[Vec3],
    conductances: &[f64],
    values: &[f64],
    plane: Plane,
    period: Option<f64>,
) -> Result<PlaneFlow, PostError> {
    let Plane { axis, position } = plane;
    check_particles(particles)?;
    let n = particles.len();
    check_len("values", values.len(), n)?;
    check_finite("values", values)?;
    check_contacts(n, pairs, Some(branches), conductances)?;
    if !position.is_finite() {
        return Err(PostError::invalid("position", position, "must be finite (m)"));
    }
    if let Some(l) = period
        && !(l.is_finite() && l > 0.0)
    {
        return Err(PostError::invalid("period", l, "must be a finite number > 0 (m)"));
    }
    let k = axis.index();
    let side = |x: f64| -> i64 {
        match period {
            Some(l) => ((x - position) / l).floor() as i64,
            None => i64::from(x >= position),
        }
    };
    let mut flow = 0.0;
    let mut contacts = 0;
    for ((&[p, q], l), &g) in pairs.iter().zip(branches).zip(conductances) {
        let a = particles.centres[p as usize][k];
        let crossings = side(a + l[k]) - side(a);
        if crossings != 0 {
            contacts += 1;
            flow += crossings as f64 * g * (values[p as usize] - values[q as usize]);
        }
    }
    Ok(PlaneFlow { flow, contacts })
}

#[cfg(test)]
mod tests {

    #[test]
    fn levers_at_mid_branch_are_the_plain_dipoles() {
        let pairs = [[0, 1], [1, 2]];
        let branches = [Vec3::new(1.0, 0.5, 0.0), Vec3::new(0.0, 2.0, -1.0)];
        let g = [2.0, 3.0];
        let t = [1.0, 4.0, -2.0];
        let half: Vec<Vec3> = branches.iter().map(|l| 0.5 * l).collect();
        let a = particle_dipoles(&pairs, &branches, &g, &t).unwrap();
        let b = particle_dipoles_levers(&pairs, &branches, &g, &t, &half).unwrap();
        assert_eq!(a, b);
        assert!(particle_dipoles_levers(&pairs, &branches, &g, &t, &half[..1]).is_err());
    }

    use super::*;
    use demcon_core::Axis;

    /// Simple cubic lattice of `n³` particles of radius r, spacing d = 2r, with its nearest-
    /// neighbour contacts.
    fn cubic(n: usize, r: f64) -> (ParticleSet, Vec<[u32; 2]>, Vec<Vec3>) {
        let d = 2.0 * r;
        let id = |i: usize, j: usize, k: usize| (i * n * n + j * n + k) as u32;
        let mut centres = Vec::new();
        let mut pairs = Vec::new();
        let mut branches = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    centres.push(Vec3::new(i as f64, j as f64, k as f64) * d + Vec3::repeat(r));
                    for (di, dj, dk, e) in [(1, 0, 0, Vec3::x()), (0, 1, 0, Vec3::y()), (0, 0, 1, Vec3::z())]
                    {
                        if i + di < n && j + dj < n && k + dk < n {
                            pairs.push([id(i, j, k), id(i + di, j + dj, k + dk)]);
                            branches.push(e * d);
                        }
                    }
                }
            }
        }
        let p = ParticleSet::new(centres, vec![r; n * n * n]).unwrap();
        (p, pairs, branches)
    }

    #[test]
    fn cubic_lattice_flux_is_exactly_minus_lambda_grad_t() {
        let (r, lambda, n) = (0.5e-3, 237.0, 6);
        let (p, pairs, branches) = cubic(n, r);
        let d = 2.0 * r;
        let s = 4.0 * r * r;
        let g = vec![lambda * s / d; pairs.len()];
        let grad = Vec3::new(300.0, -120.0, 45.0); // K/m
        let t: Vec<f64> = p.centres.iter().map(|c| 20.0 + grad.dot(c)).collect();
        let vrep = vec![d * d * d; p.len()];
        let q = particle_flux(&pairs, &branches, &g, &vrep, &t).unwrap();
        let expected = -lambda * grad;
        let id = |i: usize, j: usize, k: usize| i * n * n + j * n + k;
        // Interior particles have all six neighbours: the flux is exact, sign included.
        for i in 1..n - 1 {
            for j in 1..n - 1 {
                for k in 1..n - 1 {
                    let err = (q[id(i, j, k)] - expected).norm() / expected.norm();
                    assert!(err < 1e-12, "particle ({i},{j},{k}): {:?}", q[id(i, j, k)]);
                }
            }
        }
        // A boundary particle misses the half of the dipole across the wall.
        let corner = q[id(0, 2, 2)];
        assert!((corner.x - 0.5 * expected.x).abs() < 1e-9 * expected.norm());
    }

    #[test]
    fn dipoles_feed_both_ends() {
        let pairs = [[0u32, 1]];
        let l = [Vec3::new(2.0, 0.0, 0.0)];
        let d = particle_dipoles(&pairs, &l, &[3.0], &[1.0, 4.0]).unwrap();
        assert_eq!(d, vec![Vec3::new(18.0, 0.0, 0.0); 2]);
    }

    #[test]
    fn bad_contacts_are_named() {
        let l = [Vec3::x()];
        let e = particle_dipoles(&[[0, 5]], &l, &[1.0], &[0.0, 1.0]).unwrap_err();
        assert!(e.to_string().contains("pairs[0]"), "{e}");
        let e = particle_dipoles(&[[0, 1]], &l, &[-1.0], &[0.0, 1.0]).unwrap_err();
        assert!(e.to_string().contains("conductances[0]"), "{e}");
        let e = particle_dipoles(&[[0, 1]], &[], &[1.0], &[0.0, 1.0]).unwrap_err();
        assert!(e.to_string().contains("branches"), "{e}");
        let e = particle_flux(&[[0, 1]], &l, &[1.0], &[1.0, 0.0], &[0.0, 1.0]).unwrap_err();
        assert!(e.to_string().contains("rep_volumes[1]"), "{e}");
        let e = particle_dipoles(&[[0, 1]], &l, &[1.0], &[0.0, f64::NAN]).unwrap_err();
        assert!(e.to_string().contains("values[1]"), "{e}");
    }

    #[test]
    fn plane_flow_on_a_lattice_is_lambda_grad_times_area_at_every_plane() {
        let (r, lambda, n) = (1.0, 2.0, 5);
        let (p, pairs, branches) = cubic(n, r);
        let g = vec![lambda * 4.0 * r * r / (2.0 * r); pairs.len()];
        let t: Vec<f64> = p.centres.iter().map(|c| 10.0 - 3.0 * c.y).collect();
        let area = (n as f64 * 2.0 * r).powi(2);
        for pos in [1.5, 3.0, 7.2] {
            let f = flow_across_plane(
                &p,
                &pairs,
                &branches,
                &g,
                &t,
                Plane {
                    axis: Axis::Y,
                    position: pos,
                },
                None,
            )
            .unwrap();
            assert_eq!(f.contacts, n * n);
            assert!((f.flow - lambda * 3.0 * area).abs() < 1e-9, "{f:?}");
        }
        // Periodic wrap: a branch from x = 9 to x = 11 crosses the plane 0 + 10 m.
        let two = ParticleSet::new(
            vec![Vec3::new(9.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)],
            vec![1.0; 2],
        )
        .unwrap();
        let f = flow_across_plane(
            &two,
            &[[0, 1]],
            &[Vec3::new(2.0, 0.0, 0.0)],
            &[1.0],
            &[5.0, 3.0],
            Plane {
                axis: Axis::X,
                position: 0.0,
            },
            Some(10.0),
        )
        .unwrap();
        assert_eq!((f.flow, f.contacts), (2.0, 1));
    }
}
