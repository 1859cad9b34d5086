//! Inputs of a packing run, its stop reasons and the progress it reports while running.

use demcon_core::{AvailableMemory, Container, CoreError, MemoryBound};
use serde::Serialize;

use crate::radius::{RadiusDistribution, jamming_estimate};
use crate::xyzr::short;

/// How far above [`jamming_estimate`] a target volume fraction may lie before it is
/// rejected as unreachable (dimensionless). Slow growth packs a little beyond random close
/// packing (and monodisperse spheres start to crystallise); more than this is not promised.
pub const MAX_PHI_ABOVE_JAMMING: f64 = 0.04;

/// Allowed container lengths (edges, radii, cylinder length), m: volumes (L³) and the sums
/// of R³ over up to 10⁹ spheres then stay ~10²⁰⁰ away from f64 underflow and overflow.
pub const LENGTH_RANGE: (f64, f64) = (1e-30, 1e30);

/// Smallest target volume fraction (dimensionless): below it the spheres are a dilute gas,
/// not a packing, and their radii head for underflow.
pub const MIN_PHI: f64 = 1e-6;

/// Allowed growth rates (dimensionless). The number of events grows as 1/g (10⁴ spheres
/// need ~2.5·10⁷ events at 0.005), so 10⁻⁴ already costs ~10⁹ events; 1 is the largest
/// rate the stress sweep ([`crate::stress_packings`]) covers.
pub const GROWTH_RATE_RANGE: (f64, f64) = (1e-4, 1.0);

/// Largest volume fraction the fast compression stage may run to (dimensionless): fast
/// growth jams early (growth rate 0.1 jams Gaussian-0.3 spheres at φ ≈ 0.61), and the
/// structure of a dense packing forms above ~0.55.
pub const MAX_COMPRESSION_PHI: f64 = 0.6;

/// Allowed neighbour-list skins (fraction of the mean radius). List rebuilds happen every
/// ~skin radii of travel, so 0.01 costs ~40× the rebuilds of the default 0.4 (and a skin
/// near 0 would rebuild without end); above 2 the lists hold most of the box.
pub const NEIGHBOUR_SKIN_RANGE: (f64, f64) = (0.01, 2.0);

/// Allowed thermostat tolerances (fraction): every rescale costs N predictions, so tiny
/// tolerances rescale after nearly every event.
pub const THERMOSTAT_TOLERANCE_RANGE: (f64, f64) = (1e-3, 10.0);

/// Largest jamming pressure `PV/(NkT)` (dimensionless): p* ≈ 3/(1 − φ/φ_J) near jamming,
/// so 10¹² asks φ to within ~10⁻¹² of φ_J, the resolution of the positions.
pub const MAX_JAM_PRESSURE: f64 = 1e12;

/// Memory used by the packer per particle (bytes): particle state (64), event, bounding
/// sphere and neighbour list in one block (128), bounding-sphere grid (~35), event queue
/// (~50: a record per particle and the bucket lists), placement grid, output and renumbering
/// (~100). Measured 416 B at φ 0.635 (maximum resident set of 10⁶ particles), rounded up.
pub const BYTES_PER_PARTICLE: u64 = 600;

/// Memory limit assumed when the available memory is not known (bytes): 64 GiB.
pub const DEFAULT_MEMORY_LIMIT: u64 = 64 << 30;

/// Largest particle count (ids are `u32`).
pub const MAX_COUNT: usize = u32::MAX as usize - 1;

/// Where a memory limit comes from, for the messages of [`PackingParams::check_memory`] and
/// [`crate::check_tile_memory`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MemoryLimit {
    /// The machine's available memory (`MemAvailable` of `/proc/meminfo`), bytes.
    Available(u64),
    /// What this process may still allocate and what bounds it: the least of `MemAvailable`,
    /// its address-space limit (`ulimit -v`) and its cgroup's memory limit
    /// ([`demcon_core::available_memory_bound`]).
    Bounded(AvailableMemory),
    /// The fixed [`DEFAULT_MEMORY_LIMIT`], when nothing was measured.
    Fixed,
}

impl MemoryLimit {
    /// The memory this process may still allocate ([`demcon_core::available_memory_bound`]:
    /// the machine's, its own address-space limit's or its cgroup's, whichever is least) where
    /// it can be read, else [`Self::Fixed`].
    pub fn current() -> Self {
        demcon_core::available_memory_bound().map_or(Self::Fixed, Self::Bounded)
    }

    /// The limit (bytes) and where it comes from, in words.
    pub fn bytes_and_source(&self) -> (u64, String) {
        match self {
            Self::Available(b) => (*b, MemoryBound::MemAvailable.to_string()),
            Self::Bounded(a) => (a.bytes, a.bound.to_string()),
            Self::Fixed => (
                DEFAULT_MEMORY_LIMIT,
                "fixed limit (the available memory is not known)".into(),
            ),
        }
    }
}

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
    /// Fast compression stage: below this volume fraction the radii grow at
    /// [`compression_growth_rate`](Self::compression_growth_rate) instead of
    /// [`growth_rate`](Self::growth_rate) (dimensionless, in [0, 0.6]; 0 turns the stage off).
    /// The structure of a dense packing forms above it: with the defaults, jamming φ and
    /// the bulk coordination match a run without the stage within their seed-to-seed
    /// scatter (docs/packing.md), while 0.5 or a growth rate of 0.2 already raised the
    /// coordination. Default 0.45.
    pub compression_phi: f64,
    /// Growth rate of the fast compression stage (dimensionless, in the growth-rate range);
    /// no fast stage when it is not above `growth_rate`. Default 0.1.
    pub compression_growth_rate: f64,
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
            compression_phi: 0.45,
            compression_growth_rate: 0.1,
        }
    }

    /// Estimated peak memory of the packer for `count` particles (bytes):
    /// `count` × [`BYTES_PER_PARTICLE`].
    pub fn memory_estimate(&self) -> u64 {
        (self.count as u64).saturating_mul(BYTES_PER_PARTICLE)
    }

    /// Refuses a `count` whose [`memory_estimate`](Self::memory_estimate) exceeds `limit`;
    /// the message gives both and says where the limit comes from.
    pub fn check_memory(&self, limit: &MemoryLimit) -> Result<(), CoreError> {
        let (bytes, source) = limit.bytes_and_source();
        let need = self.memory_estimate();
        if need > bytes {
            return Err(CoreError::invalid(
                "count",
                self.count,
                format!(
                    "the packer needs ~{BYTES_PER_PARTICLE} bytes per particle, {:.3e} bytes for {} \
                     particles, above the {source} of {:.3e} bytes: at most {} particles",
                    need as f64,
                    self.count,
                    bytes as f64,
                    bytes / BYTES_PER_PARTICLE
                ),
            ));
        }
        Ok(())
    }

    /// Checks every field, before any heavy work; the error names the field, the value and
    /// what is allowed. The count is checked against [`DEFAULT_MEMORY_LIMIT`]; callers that
    /// know the available memory also call [`check_memory`](Self::check_memory).
    pub fn validate(&self) -> Result<(), CoreError> {
        check_lengths(&self.container)?;
        self.container.validate()?;
        self.radii.validate()?;
        if self.count == 0 || self.count > MAX_COUNT {
            return Err(CoreError::invalid(
                "count",
                self.count,
                format!("must be between 1 and {MAX_COUNT}"),
            ));
        }
        self.check_memory(&MemoryLimit::Fixed)?;
        let phi_max = jamming_estimate(&self.radii) + MAX_PHI_ABOVE_JAMMING;
        if !(self.target_phi.is_finite() && self.target_phi >= MIN_PHI && self.target_phi <= phi_max) {
            return Err(CoreError::invalid(
                "phi",
                short(self.target_phi),
                format!(
                    "must be in [{MIN_PHI:e}, {phi_max:.3}]: this radius distribution jams near φ ≈ {:.3} \
                     (Desmond & Weeks 2014 estimate) and slow growth gains at most ~{MAX_PHI_ABOVE_JAMMING}",
                    jamming_estimate(&self.radii)
                ),
            ));
        }
        let range = |field: &str, v: f64, (lo, hi): (f64, f64), why: &str| {
            if v >= lo && v <= hi {
                Ok(())
            } else {
                Err(CoreError::invalid(
                    field,
                    short(v),
                    format!("must be in [{lo:e}, {hi:e}] ({why})"),
                ))
            }
        };
        range(
            "growth-rate",
            self.growth_rate,
            GROWTH_RATE_RANGE,
            "events grow as 1/growth rate; 1 is the largest tested",
        )?;
        if self.max_events == 0 {
            return Err(CoreError::invalid("max-events", 0, "must be ≥ 1"));
        }
        if self.max_wall_s.is_nan() || self.max_wall_s <= 0.0 {
            return Err(CoreError::invalid(
                "max-time",
                short(self.max_wall_s),
                "must be > 0 s (or infinite)",
            ));
        }
        range(
            "jam-pressure",
            self.jam_pressure,
            (1.0 + f64::EPSILON, MAX_JAM_PRESSURE),
            "the reduced pressure PV/(NkT) must exceed 1; 1e12 already asks φ to within 1e-12 of jamming",
        )?;
        range(
            "initial-phi",
            self.initial_phi,
            (1e-3, 0.35),
            "random placement gives up below 1e-3 and fails above ~0.35",
        )?;
        range(
            "neighbour-skin",
            self.neighbour_skin,
            NEIGHBOUR_SKIN_RANGE,
            "fraction of the mean radius; rebuilds grow as 1/skin",
        )?;
        range(
            "thermostat-tolerance",
            self.thermostat_tolerance,
            THERMOSTAT_TOLERANCE_RANGE,
            "fraction of kinetic-energy rise; each rescale costs N predictions",
        )?;
        range(
            "compression-phi",
            self.compression_phi,
            (0.0, MAX_COMPRESSION_PHI),
            "volume fraction up to which the fast compression stage runs; 0 turns it off",
        )?;
        range(
            "compression-growth-rate",
            self.compression_growth_rate,
            GROWTH_RATE_RANGE,
            "growth rate of the fast compression stage",
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

/// Refuses container lengths outside [`LENGTH_RANGE`] (the error names the field).
pub(crate) fn check_lengths(c: &Container) -> Result<(), CoreError> {
    let lengths: Vec<(&str, f64)> = match *c {
        Container::Box { size } | Container::Periodic { size } => {
            vec![("size.x", size[0]), ("size.y", size[1]), ("size.z", size[2])]
        }
        Container::Cylinder { radius, length } => vec![("radius", radius), ("length", length)],
        Container::Sphere { radius } => vec![("radius", radius)],
    };
    let (lo, hi) = LENGTH_RANGE;
    for (field, v) in lengths {
        if !(v >= lo && v <= hi) {
            return Err(CoreError::invalid(
                format!("container.{field}"),
                format!("{} m", short(v)),
                format!(
                    "must be in [{lo:e}, {hi:e}] m (volumes must stay far from f64 underflow and overflow)"
                ),
            ));
        }
    }
    Ok(())
}

/// Events per particle that reaching φ took at the least, as (φ, events per particle):
/// measured 2026-11-24 on 2·10³ and 2·10⁴ particles in a box and a periodic box, Gaussian
/// radii of spread 0.3 and monodisperse, the default growth rates, each value the fewest
/// seen at that φ or any higher one (docs/packing.md "Budgets").
const MEASURED_EVENTS_PER_PARTICLE: [(f64, f64); 7] = [
    (0.0, 0.0),
    (0.2, 7.2),
    (0.35, 14.7),
    (0.5, 27.6),
    (0.55, 50.9),
    (0.6, 75.9),
    (0.62, 138.7),
];

/// Events per second that no packing reaches: twice the fastest rate measured (1.3·10⁶ /s at
/// 2·10³ particles, release build): a time budget under [`min_events`] / this cannot reach.
pub const EVENT_RATE_BOUND: f64 = 2.6e6;

/// A lower bound on the events a packing of `count` particles needs to reach `target_phi`:
/// half the fewest events per particle measured for that φ (interpolated linearly; held
/// beyond the last measured φ). A budget below it cannot reach the target, so it can be
/// refused before any work rather than stopped after.
pub fn min_events(count: usize, target_phi: f64) -> u64 {
    let table = &MEASURED_EVENTS_PER_PARTICLE;
    let per_particle = match table.iter().position(|&(phi, _)| phi >= target_phi) {
        None => table[table.len() - 1].1,
        Some(0) => 0.0,
        Some(k) => {
            let ((x0, y0), (x1, y1)) = (table[k - 1], table[k]);
            y0 + (y1 - y0) * (target_phi - x0) / (x1 - x0)
        }
    };
    (0.5 * per_particle * count as f64) as u64
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
