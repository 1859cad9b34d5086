//! Radius distributions (relative to the mean), their moments, sampling, and the jamming
//! density estimate they imply.

use demcon_core::CoreError;
use rand::Rng;
use rand_distr::{Distribution, Normal};
use serde::Serialize;

/// Shape of the radius distribution, as ratios to the nominal mean radius; the absolute
/// scale (m) follows from the container volume, the count and the target volume fraction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum RadiusDistribution {
    /// All radii equal.
    Monodisperse,
    /// Normal distribution of mean 1 and standard deviation `cov`, truncated to
    /// `[min_ratio, max_ratio]` by rejection (so the truncated std is a little below `cov`:
    /// see [`RadiusDistribution::moments`]). [`RadiusDistribution::gaussian`] gives the
    /// default truncation `1 ± 2.5 cov`, floored at 0.1.
    Gaussian {
        /// Standard deviation over mean of the untruncated normal (dimensionless, ≥ 0).
        cov: f64,
        /// Smallest radius allowed, as a ratio to the mean (> 0, < 1).
        min_ratio: f64,
        /// Largest radius allowed, as a ratio to the mean (> 1).
        max_ratio: f64,
    },
}

/// Number of standard deviations kept on each side by [`RadiusDistribution::gaussian`].
pub const DEFAULT_TRUNCATION_SIGMAS: f64 = 2.5;
/// Floor of the default lower truncation (ratio to the mean radius). Tiny particles shrink
/// the stable explicit time step of the thermal solver (∝ R_min²).
pub const MIN_RATIO_FLOOR: f64 = 0.1;

impl RadiusDistribution {
    /// Gaussian radii with std/mean `cov`, truncated to `[max(1 − 2.5 cov, 0.1), 1 + 2.5 cov]`
    /// (ratios to the mean). `cov = 0` gives [`RadiusDistribution::Monodisperse`].
    pub fn gaussian(cov: f64) -> Self {
        if cov == 0.0 {
            return Self::Monodisperse;
        }
        Self::Gaussian {
            cov,
            min_ratio: (1.0 - DEFAULT_TRUNCATION_SIGMAS * cov).max(MIN_RATIO_FLOOR),
            max_ratio: 1.0 + DEFAULT_TRUNCATION_SIGMAS * cov,
        }
    }

    /// Checks the parameters; the error names the field (`radius-cov`, `radius-min-ratio`,
    /// `radius-max-ratio`).
    pub fn validate(&self) -> Result<(), CoreError> {
        if let Self::Gaussian {
            cov,
            min_ratio,
            max_ratio,
        } = *self
        {
            if !(cov.is_finite() && cov >= 0.0) {
                return Err(CoreError::invalid(
                    "radius-cov",
                    cov,
                    "the std/mean of the radii must be a finite number ≥ 0",
                ));
            }
            if !(min_ratio.is_finite() && min_ratio > 0.0 && min_ratio < 1.0) {
                return Err(CoreError::invalid(
                    "radius-min-ratio",
                    min_ratio,
                    "must be in (0, 1) (ratio of the smallest radius to the mean)",
                ));
            }
            if !(max_ratio.is_finite() && max_ratio > 1.0 && max_ratio <= 10.0) {
                return Err(CoreError::invalid(
                    "radius-max-ratio",
                    max_ratio,
                    "must be in (1, 10] (ratio of the largest radius to the mean)",
                ));
            }
        }
        Ok(())
    }

    /// Mean, standard deviation (both as ratios to the nominal mean) and skewness of the
    /// distribution actually sampled (the truncated one), by numerical integration
    /// (relative error < 1e-9).
    pub fn moments(&self) -> (f64, f64, f64) {
        match *self {
            Self::Monodisperse => (1.0, 0.0, 0.0),
            Self::Gaussian {
                cov,
                min_ratio,
                max_ratio,
            } => {
                if cov == 0.0 {
                    return (1.0, 0.0, 0.0);
                }
                // Composite Simpson on the truncated interval of the N(1, cov) density.
                let n = 20_000;
                let h = (max_ratio - min_ratio) / n as f64;
                let mut m = [0.0; 4];
                for k in 0..=n {
                    let x = min_ratio + h * k as f64;
                    let w = if k == 0 || k == n {
                        1.0
                    } else if k % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    };
                    let f = w * (-0.5 * ((x - 1.0) / cov).powi(2)).exp();
                    for (p, mp) in m.iter_mut().enumerate() {
                        *mp += f * x.powi(p as i32);
                    }
                }
                let mean = m[1] / m[0];
                let var = m[2] / m[0] - mean * mean;
                let third = m[3] / m[0] - 3.0 * mean * var - mean.powi(3);
                let std = var.max(0.0).sqrt();
                let skew = if std > 0.0 { third / std.powi(3) } else { 0.0 };
                (mean, std, skew)
            }
        }
    }

    /// `n` radius ratios drawn from the distribution (mean ≈ 1).
    pub fn sample(&self, n: usize, rng: &mut impl Rng) -> Vec<f64> {
        match *self {
            Self::Monodisperse => vec![1.0; n],
            Self::Gaussian {
                cov,
                min_ratio,
                max_ratio,
            } => {
                let Ok(normal) = Normal::new(1.0, cov) else {
                    return vec![1.0; n];
                };
                (0..n)
                    .map(|_| {
                        loop {
                            let x = normal.sample(rng);
                            if (min_ratio..=max_ratio).contains(&x) {
                                break x;
                            }
                        }
                    })
                    .collect()
            }
        }
    }
}

/// Random-close-packing estimate of the volume fraction at which a Lubachevsky–Stillinger
/// packing of this distribution jams (dimensionless): Desmond & Weeks, Phys. Rev. E 90,
/// 022204 (2014), `φ_RCP = 0.634 + 0.0658 δ + 0.0857 S δ²` with δ = std/mean and S the
/// skewness of the (truncated) distribution; fitted for δ ≤ 0.4. Monodisperse: 0.634;
/// Gaussian 0.3 truncated at ±2.5σ: 0.653. Slow LS growth reaches a little more (0.64–0.645
/// monodisperse).
pub fn jamming_estimate(dist: &RadiusDistribution) -> f64 {
    let (mean, std, skew) = dist.moments();
    let d = std / mean;
    0.634 + 0.0658 * d + 0.0857 * skew * d * d
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn truncated_moments_and_jamming() {
        let g = RadiusDistribution::gaussian(0.3);
        let (m, s, sk) = g.moments();
        assert!((m - 1.0).abs() < 1e-9 && sk.abs() < 1e-9);
        // Truncated at ±2.5σ: std factor sqrt(1 − 2·2.5·φ(2.5)/(2Φ(2.5) − 1)) = 0.95459.
        assert!((s / 0.3 - 0.954_59).abs() < 1e-4, "{s}");
        let phi = jamming_estimate(&g);
        assert!((phi - 0.6528).abs() < 5e-4, "{phi}");
        assert_eq!(jamming_estimate(&RadiusDistribution::Monodisperse), 0.634);
    }

    #[test]
    fn samples_match_the_moments() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let g = RadiusDistribution::Gaussian {
            cov: 0.4,
            min_ratio: 0.3,
            max_ratio: 2.5,
        };
        let (m, s, sk) = g.moments();
        assert!(sk > 0.0); // asymmetric truncation
        let x = g.sample(200_000, &mut rng);
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        let std = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / x.len() as f64).sqrt();
        // Standard errors: s/√n ≈ 8e-4 on the mean; allow 4 of them.
        assert!((mean - m).abs() < 4.0 * s / (x.len() as f64).sqrt(), "{mean} {m}");
        assert!((std - s).abs() < 0.005 * s, "{std} {s}");
        assert!(x.iter().all(|v| (0.3..=2.5).contains(v)));
    }

    #[test]
    fn bad_parameters_are_named() {
        let e = RadiusDistribution::Gaussian {
            cov: -0.1,
            min_ratio: 0.5,
            max_ratio: 1.5,
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("radius-cov"), "{e}");
        let e = RadiusDistribution::Gaussian {
            cov: 0.1,
            min_ratio: 1.2,
            max_ratio: 1.5,
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("radius-min-ratio"), "{e}");
    }
}
