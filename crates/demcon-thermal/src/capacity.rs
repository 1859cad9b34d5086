//! Heat capacity of each particle's representative element, and the explicit step bounds.

use demcon_core::check::{check_len, check_positive};
use demcon_network::{Constraints, Network, NodeKind};

use crate::error::ThermalError;
use crate::system::ThermalSystem;

/// Volume of the material a particle represents.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RepresentativeVolume<'a> {
    /// V_p / φ with φ the packing's solid fraction (calibrated model, Haddad 2021 eq. 6;
    /// eq. 5's extra 1/φ is a misprint). Σ_p V_p/φ equals the domain volume.
    PackingFraction(f64),
    /// V_p / f_v(n_p) with a per-particle volume fraction (Terreros model), in (0, 1].
    VolumeFraction(&'a [f64]),
    /// The volume each particle stands for, given (m³): its Laguerre cell.
    Given(&'a [f64]),
}

/// Heat capacity of each particle, C_p = c_p ρ_c,p V_rep,p (J/K).
///
/// `volumes`: V_p (m³); `specific_heat`: c (J/(kg·K)); `density`: continuum density ρ_c
/// (kg/m³) of the particle's material; all per particle.
///
/// # Errors
/// [`ThermalError::InvalidParameter`] for a length mismatch or a value that is not finite
/// and > 0 (φ and f_v must be in (0, 1]).
pub fn capacities(
    volumes: &[f64],
    specific_heat: &[f64],
    density: &[f64],
    rep: RepresentativeVolume<'_>,
) -> Result<Vec<f64>, ThermalError> {
    let n = volumes.len();
    check_positive("volumes", volumes)?;
    check_len("specific_heat", specific_heat.len(), n)?;
    check_positive("specific_heat", specific_heat)?;
    check_len("density", density.len(), n)?;
    check_positive("density", density)?;
    if let RepresentativeVolume::Given(v) = rep {
        check_len("representative volumes", v.len(), n)?;
        check_positive("representative volumes", v)?;
        return Ok((0..n).map(|p| specific_heat[p] * density[p] * v[p]).collect());
    }
    let frac = |p: usize| match rep {
        RepresentativeVolume::PackingFraction(phi) => phi,
        RepresentativeVolume::VolumeFraction(f) => f[p],
        RepresentativeVolume::Given(_) => unreachable!("returned above"),
    };
    match rep {
        RepresentativeVolume::Given(_) => {}
        RepresentativeVolume::PackingFraction(phi) => {
            if !(phi > 0.0 && phi <= 1.0) {
                return Err(ThermalError::invalid(
                    "packing fraction φ",
                    phi,
                    "must be in (0, 1]",
                ));
            }
        }
        RepresentativeVolume::VolumeFraction(f) => {
            check_len("volume_fraction", f.len(), n)?;
            if let Some(p) = f.iter().position(|v| !(*v > 0.0 && *v <= 1.0)) {
                return Err(ThermalError::invalid(
                    format!("volume_fraction[{p}]"),
                    f[p],
                    "must be in (0, 1]",
                ));
            }
        }
    }
    Ok((0..n)
        .map(|p| specific_heat[p] * density[p] * volumes[p] / frac(p))
        .collect())
}

/// The exact positivity bound of the forward-Euler step and the node that sets it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DtBound {
    /// min over free nodes of C_p / Σ_q H_pq (s); `f64::INFINITY` when no free node has a
    /// contact. Below it the explicit update is a convex combination (maximum principle,
    /// stability); the true stability limit 2/λ_max(C⁻¹K) is at most 2× larger.
    pub dt_max: f64,
    /// The node that sets it (`u32::MAX` when infinite).
    pub node: u32,
}

/// Forward-Euler positivity bound min_p C_p / Σ_q H_pq over free nodes (s).
///
/// `conductances`: H_pq per edge (W/K); `capacities`: C_p per node (J/K).
///
/// # Errors
/// Bad conductances or capacities.
pub fn stable_dt_bound(
    net: &Network,
    conductances: &[f64],
    capacities: &[f64],
    constraints: &Constraints,
) -> Result<DtBound, ThermalError> {
    Ok(ThermalSystem::new(net, conductances, capacities, constraints)?.stable_dt_bound())
}

/// [`stable_dt_bound`] on inputs already checked ([`ThermalSystem`]).
pub(crate) fn dt_bound_of(
    net: &Network,
    conductances: &[f64],
    capacities: &[f64],
    constraints: &Constraints,
) -> DtBound {
    let sums = net.row_sums(conductances);
    let mut best = DtBound {
        dt_max: f64::INFINITY,
        node: u32::MAX,
    };
    for (p, (&c, &s)) in capacities.iter().zip(&sums).enumerate() {
        if constraints.kinds()[p] == NodeKind::Free && s > 0.0 && c / s < best.dt_max {
            best = DtBound {
                dt_max: c / s,
                node: p as u32,
            };
        }
    }
    best
}

/// The critical step estimate of Haddad et al. 2021, eq. 16 (s), reported beside the exact
/// bound: Δt_cr = 2 d_min² / (3 a n_p C_t).
///
/// `d_min`: smallest contact distance (m); `diffusivity`: particle diffusivity
/// a = λ/(c ρ_d) (m²/s); `n_p`: number of contacts of a particle; `c_t`: calibrated surface
/// coefficient. It assumes a mean-sized particle: on polydisperse packings the exact bound
/// ([`stable_dt_bound`]) can be ~20× smaller, and stepping with this estimate diverges.
/// Returns NaN-free `f64::INFINITY` if an argument is not positive.
pub fn paper_dt_estimate(d_min: f64, diffusivity: f64, n_p: f64, c_t: f64) -> f64 {
    let den = 3.0 * diffusivity * n_p * c_t;
    if d_min > 0.0 && den > 0.0 && den.is_finite() && d_min.is_finite() {
        2.0 * d_min * d_min / den
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use demcon_network::{FloatingPolicy, resolve_fixed};

    #[test]
    fn capacities_use_the_representative_volume() {
        let c = capacities(
            &[1e-6, 2e-6],
            &[900.0, 900.0],
            &[2700.0, 2700.0],
            RepresentativeVolume::PackingFraction(0.64),
        )
        .unwrap();
        assert!((c[0] - 900.0 * 2700.0 * 1e-6 / 0.64).abs() < 1e-12);
        let f = [0.5, 1.0];
        let c = capacities(
            &[1e-6, 2e-6],
            &[1.0, 1.0],
            &[1.0, 1.0],
            RepresentativeVolume::VolumeFraction(&f),
        )
        .unwrap();
        assert_eq!(c, vec![2e-6, 2e-6]);
        assert!(matches!(
            capacities(&[1.0], &[1.0], &[1.0], RepresentativeVolume::PackingFraction(1.5)),
            Err(ThermalError::InvalidParameter { .. })
        ));
        assert!(matches!(
            capacities(&[1.0, -1.0], &[1.0; 2], &[1.0; 2], RepresentativeVolume::PackingFraction(0.6)),
            Err(ThermalError::InvalidParameter { ref field, .. }) if field == "volumes[1]"
        ));
    }

    #[test]
    fn bound_is_the_smallest_free_ratio() {
        let net = Network::new(3, &[[0, 1], [1, 2]]).unwrap();
        let g = [2.0, 3.0];
        let caps = [1.0, 10.0, 0.1];
        let free = resolve_fixed(&net, &[], FloatingPolicy::Keep).unwrap();
        let b = stable_dt_bound(&net, &g, &caps, &free).unwrap();
        assert_eq!((b.dt_max, b.node), (0.1 / 3.0, 2));
        // Fixing node 2 removes it from the minimum.
        let fixed = resolve_fixed(&net, &[(vec![2], 1.0)], FloatingPolicy::Fail).unwrap();
        let b = stable_dt_bound(&net, &g, &caps, &fixed).unwrap();
        assert_eq!((b.dt_max, b.node), (0.5, 0));
        assert!((paper_dt_estimate(1e-3, 1e-5, 7.5, 0.8) - 2e-6 / (3.0 * 1e-5 * 7.5 * 0.8)).abs() < 1e-15);
        assert_eq!(paper_dt_estimate(0.0, 1.0, 1.0, 1.0), f64::INFINITY);
    }
}
