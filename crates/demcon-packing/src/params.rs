//! Inputs of a packing run, its stop reasons and the progress it reports while running.

use demcon_core::{Container, CoreError};
use serde::Serialize;

use crate::radius::{RadiusDistribution, jamming_estimate};

/// How far above [`jamming_estimate`] a target volume fraction may lie before it is
/// rejected as unreachable (dimensionless). Slow growth packs a little beyond random close
/// packing (and monodisperse spheres start to crystallise); more than this is not promised.
pub const MAX_PHI_ABOVE_JAMMING: f64 = 0.04;

/// Parameters of a Lubachevsky–Stillinger packing. Build with [`PackingParams::new`] and
/// change the fields you need.
///
/// Internal units: lengths in m; time in units where the rms velocity per component
/// equals the mean final radius per time unit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PackingParams {
    /// The vessel (hard walls, or periodic box).
    #[serde(skip)]
    pub container: Container,
    /// Number of particles (≥ 1).
    pub count: usize,
    /// Volume fraction to reach (dimensionless, in (0, jamming estimate + 0.04]); it fixes the
    /// final radii: Σ 4/3 π R³ = φ · container volume.
    pub target_phi: f64,
    /// Shape of the radius distribution.
    pub radii: RadiusDistribution,
    /// Growth speed of the mean radius over the rms velocity per component
    /// (dimensionless, > 0). Slower growth jams denser and costs more events. Default 0.02.
    pub growth_rate: f64,
    /// Stop after this many events (collisions, wall hits, neighbour-list rebuilds).
    pub max_events: u64,
    /// Stop after this wall-clock time (s); `f64::INFINITY` for none.
    pub max_wall_s: f64,
    /// Reduced pressure `PV/(NkT)` above which the packing counts as jammed
    /// (dimensionless, > 1). Default 1e6, i.e. φ within ~2·10⁻⁶ of its jamming point.
    pub jam_pressure: f64,
    /// Volume fraction of the random sequential placement the growth starts from
    /// (dimensionless, in (0, 0.35]); capped at 0.9 × target. Default 0.3.
    pub initial_phi: f64,
    /// Neighbour-list skin: the bounding sphere of each particle is its radius plus this
    /// fraction of the mean radius (dimensionless, in (0, 2]). Default 0.4.
    pub neighbour_skin: f64,
    /// Kinetic-energy rise (fraction, > 0) that triggers a thermostat rescale back to the
    /// initial temperature. Each rescale recomputes every event (cost ≈ N predictions), so
    /// a small value is slow; the growth rate relative to the thermal speed then drifts by
    /// at most `√(1 + tol)`. Default 0.5.
    pub thermostat_tolerance: f64,
    /// Width of the wall layer excluded from the bulk volume fraction, in mean diameters
    /// (≥ 0). Default 2.
    pub bulk_margin_diameters: f64,
}

impl PackingParams {
    /// `count` particles of the given radius distribution in `container`, grown to
    /// `target_phi`, with the default growth rate, budgets and numerical settings.
    pub fn new(container: Container, count: usize, target_phi: f64, radii: RadiusDistribution) -> Self {
        Self {
            container,
            count,
            target_phi,
            radii,
            growth_rate: 0.02,
            max_events: u64::MAX,
            max_wall_s: f64::INFINITY,
            jam_pressure: 1e6,
            initial_phi: 0.3,
            neighbour_skin: 0.4,
            thermostat_tolerance: 0.5,
            bulk_margin_diameters: 2.0,
        }
    }

    /// Checks every field; the error names the field, the value and what is allowed.
    pub fn validate(&self) -> Result<(), CoreError> {
        self.container.validate()?;
        self.radii.validate()?;
        if self.count == 0 || self.count >= u32::MAX as usize {
            return Err(CoreError::invalid(
                "count",
                self.count,
                "must be between 1 and 4 294 967 294",
            ));
        }
        let phi_max = jamming_estimate(&self.radii) + MAX_PHI_ABOVE_JAMMING;
        if !(self.target_phi.is_finite() && self.target_phi > 0.0 && self.target_phi <= phi_max) {
            return Err(CoreError::invalid(
                "phi",
                self.target_phi,
                format!(
                    "must be in (0, {phi_max:.3}]: this radius distribution jams near φ ≈ {:.3} \
                     (Desmond & Weeks 2014 estimate) and slow growth gains at most ~{MAX_PHI_ABOVE_JAMMING}",
                    jamming_estimate(&self.radii)
                ),
            ));
        }
        let pos = |field: &str, v: f64, allowed: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(CoreError::invalid(field, v, allowed))
            }
        };
        pos("growth-rate", self.growth_rate, "must be a finite number > 0")?;
        if self.max_events == 0 {
            return Err(CoreError::invalid("max-events", 0, "must be ≥ 1"));
        }
        if self.max_wall_s.is_nan() || self.max_wall_s <= 0.0 {
            return Err(CoreError::invalid(
                "max-time",
                self.max_wall_s,
                "must be > 0 s (or infinite)",
            ));
        }
        if !(self.jam_pressure.is_finite() && self.jam_pressure > 1.0) {
            return Err(CoreError::invalid(
                "jam-pressure",
                self.jam_pressure,
                "the reduced pressure PV/(NkT) must be a finite number > 1",
            ));
        }
        if !(self.initial_phi > 0.0 && self.initial_phi <= 0.35) {
            return Err(CoreError::invalid(
                "initial-phi",
                self.initial_phi,
                "must be in (0, 0.35]",
            ));
        }
        if !(self.neighbour_skin > 0.0 && self.neighbour_skin <= 2.0) {
            return Err(CoreError::invalid(
                "neighbour-skin",
                self.neighbour_skin,
                "must be in (0, 2] (fraction of the mean radius)",
            ));
        }
        pos(
            "thermostat-tolerance",
            self.thermostat_tolerance,
            "must be a finite number > 0",
        )?;
        if !(self.bulk_margin_diameters.is_finite() && self.bulk_margin_diameters >= 0.0) {
            return Err(CoreError::invalid(
                "bulk-margin",
                self.bulk_margin_diameters,
                "must be a finite number ≥ 0 (mean diameters)",
            ));
        }
        Ok(())
    }
}

/// Why a packing run stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum StopReason {
    /// The target volume fraction was reached exactly.
    TargetReached,
    /// The reduced pressure passed the jamming threshold before the target.
    Jammed,
    /// The event budget ran out before the target.
    EventBudget,
    /// The wall-clock budget ran out before the target.
    TimeBudget,
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            StopReason::TargetReached => "target volume fraction reached",
            StopReason::Jammed => "jammed before the target (reduced pressure above threshold)",
            StopReason::EventBudget => "event budget exhausted before the target",
            StopReason::TimeBudget => "time budget exhausted before the target",
        })
    }
}

/// State of a running packing, passed to the progress callback about 5 times a second.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackProgress {
    /// Current volume fraction (dimensionless).
    pub phi: f64,
    /// Target volume fraction (dimensionless).
    pub target_phi: f64,
    /// Events so far.
    pub events: u64,
    /// Wall-clock time so far (s).
    pub wall_s: f64,
    /// Latest reduced pressure `PV/(NkT)` (dimensionless; 0 before the first estimate).
    pub reduced_pressure: f64,
}
