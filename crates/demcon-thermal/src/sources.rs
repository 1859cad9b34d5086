//! Heat sources per particle: an imposed flux on a face shared by projected area, and sums.

use demcon_core::ParticleSet;

use crate::error::ThermalError;

/// Per-particle sources (W) that inject `total_power` (W; negative extracts heat) through
/// the particles `ids` (e.g. those touching a face), shared in proportion to their
/// projected area π r_p² (the same for any face direction of a sphere).
///
/// For an imposed flux density q (W/m²) on a face of area A, pass q·A. Listing a particle
/// twice counts it once.
///
/// # Errors
/// An empty `ids`, an index out of range, or a non-finite power.
pub fn face_flux_sources(
    particles: &ParticleSet,
    ids: &[u32],
    total_power: f64,
) -> Result<Vec<f64>, ThermalError> {
    if !total_power.is_finite() {
        return Err(ThermalError::invalid(
            "total_power",
            total_power,
            "must be a finite number (W)",
        ));
    }
    if ids.is_empty() {
        return Err(ThermalError::invalid(
            "face particles",
            "none",
            "the heat-flux boundary must select at least one particle",
        ));
    }
    let n = particles.len();
    let mut chosen = vec![false; n];
    for &p in ids {
        *chosen.get_mut(p as usize).ok_or_else(|| {
            ThermalError::invalid(
                "face particle id",
                p,
                format!("must be < number of particles ({n})"),
            )
        })? = true;
    }
    let area = |p: usize| std::f64::consts::PI * particles.radii[p] * particles.radii[p];
    let total_area: f64 = (0..n).filter(|&p| chosen[p]).map(area).sum();
    Ok((0..n)
        .map(|p| {
            if chosen[p] {
                total_power * area(p) / total_area
            } else {
                0.0
            }
        })
        .collect())
}

/// Element-wise sum of source vectors (W), e.g. a face flux plus Joule heating.
///
/// # Errors
/// Vectors of different lengths.
pub fn add_sources(a: &[f64], b: &[f64]) -> Result<Vec<f64>, ThermalError> {
    if a.len() != b.len() {
        return Err(ThermalError::invalid(
            "sources (length)",
            b.len(),
            format!("must match the first source vector ({})", a.len()),
        ));
    }
    Ok(a.iter().zip(b).map(|(x, y)| x + y).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use demcon_core::Vec3;

    #[test]
    fn flux_is_shared_by_projected_area() {
        let p = ParticleSet::new(
            vec![Vec3::zeros(), Vec3::new(1.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0)],
            vec![0.1, 0.2, 0.3],
        )
        .unwrap();
        let s = face_flux_sources(&p, &[0, 1, 1], 5.0).unwrap();
        assert_eq!(s[2], 0.0);
        assert!((s[0] + s[1] - 5.0).abs() < 1e-12);
        assert!((s[1] / s[0] - 4.0).abs() < 1e-12);
        assert!(face_flux_sources(&p, &[], 1.0).is_err());
        assert!(face_flux_sources(&p, &[7], 1.0).is_err());
        assert!(face_flux_sources(&p, &[0], f64::NAN).is_err());
        assert_eq!(add_sources(&[1.0, 2.0], &[0.5, 0.5]).unwrap(), vec![1.5, 2.5]);
        assert!(add_sources(&[1.0], &[1.0, 2.0]).is_err());
    }
}
