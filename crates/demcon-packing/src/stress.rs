//! Stress runs of the packer: many small packings over seeds × containers × growth rates,
//! each checked for overlaps and sound stop reasons. A few dozen run in `cargo test`; the
//! full sweep ([`stress_packings`] with ≥ 1000 cases) is for validation runs.

use demcon_core::Container;

use crate::error::PackingError;
use crate::lsa::{MAX_OVERLAP, pack};
use crate::params::{PackingParams, StopReason};
use crate::radius::RadiusDistribution;
use crate::report::max_overlap;

/// Growth rates swept by [`stress_packings`] (dimensionless): from slow to the largest allowed.
pub const STRESS_GROWTH_RATES: [f64; 5] = [0.005, 0.02, 0.1, 0.5, 1.0];

/// One failed stress case: its parameters and what went wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct StressFailure {
    /// Case number (0-based) in the sweep.
    pub case: usize,
    /// Container kind (`box`, `cylinder`, `sphere`, `periodic`).
    pub container: &'static str,
    /// Number of particles.
    pub count: usize,
    /// Growth rate (dimensionless).
    pub growth_rate: f64,
    /// Seed.
    pub seed: u64,
    /// The error or the overlap found.
    pub message: String,
}

/// What a stress sweep found.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StressReport {
    /// Cases run.
    pub cases: usize,
    /// Cases that reached their target volume fraction.
    pub reached: usize,
    /// Cases that jammed first.
    pub jammed: usize,
    /// Largest overlap over all packings, relative to the smaller radius (dimensionless;
    /// recomputed by [`max_overlap`], independent of the packer's own check).
    pub worst_overlap: f64,
    /// The cases that failed (an error, or an overlap above [`MAX_OVERLAP`]).
    pub failures: Vec<StressFailure>,
}

/// Runs `cases` small packings (20–120 particles, φ 0.45–0.62, Gaussian or monodisperse
/// radii) cycling through the four container kinds and [`STRESS_GROWTH_RATES`], seed =
/// case number. Every packing must finish without error (target reached or jammed) and
/// with overlaps ≤ [`MAX_OVERLAP`]. Deterministic; about 15 ms per case in release builds.
pub fn stress_packings(cases: usize) -> StressReport {
    let mut rep = StressReport {
        cases,
        ..Default::default()
    };
    for case in 0..cases {
        let k = case as u64;
        let container = match case % 4 {
            0 => Container::Box {
                size: [1.0, 1.2, 0.8],
            },
            1 => Container::Cylinder {
                radius: 0.6,
                length: 1.0,
            },
            2 => Container::Sphere { radius: 0.6 },
            _ => Container::Periodic { size: [1.0; 3] },
        };
        let growth_rate = STRESS_GROWTH_RATES[(case / 4) % STRESS_GROWTH_RATES.len()];
        let count = 20 + (k.wrapping_mul(37) % 101) as usize;
        let phi = 0.45 + 0.17 * ((k.wrapping_mul(13) % 11) as f64 / 10.0);
        let radii = if case % 3 == 0 {
            RadiusDistribution::Monodisperse
        } else {
            RadiusDistribution::gaussian(0.3)
        };
        let mut params = PackingParams::new(container, count, phi, radii);
        params.growth_rate = growth_rate;
        params.max_events = 2_000_000;
        let fail = |message: String| StressFailure {
            case,
            container: container.kind(),
            count,
            growth_rate,
            seed: k,
            message,
        };
        match pack(&params, k, None) {
            Ok((p, r)) => {
                let ov = max_overlap(&p, Some(&container));
                rep.worst_overlap = rep.worst_overlap.max(ov);
                match r.stop {
                    StopReason::TargetReached => rep.reached += 1,
                    StopReason::Jammed => rep.jammed += 1,
                    other => rep.failures.push(fail(format!("stopped: {other}"))),
                }
                if ov > MAX_OVERLAP {
                    rep.failures
                        .push(fail(format!("overlap {ov:e} of the smaller radius")));
                }
            }
            // A container too small for a few large particles is a refusal, not a failure.
            Err(PackingError::ContainerTooSmall { .. }) => {}
            Err(e) => rep.failures.push(fail(e.to_string())),
        }
    }
    rep
}
