//! Explicit (forward Euler) transient solver, Haddad et al. 2021 eq. 6:
//! C_p (T_p' − T_p)/Δt = Σ_q H_pq (T_q − T_p) + Q_p, with its stability bound enforced and
//! divergence detected.

use demcon_core::mem::huge_copy;
use demcon_network::CHUNK;
use rayon::prelude::*;

use crate::capacity::DtBound;
use crate::checkpoint::{Checkpoints, TransientStart};
use crate::error::ThermalError;
pub use crate::kernel::{ExplicitStepper, WeightPrecision};
use crate::march::{Ledger, MarchParams, Segment, Stepper, march};
use crate::system::{SourceUpdate, ThermalSystem, TransientInput};
use crate::transient::{DEFAULT_MAX_STEPS, ProgressFn, Transient, TransientReport, check_max_steps, stops};

/// How the explicit step is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeStep {
    /// Δt = safety × min_p C_p/Σ_q H_pq, safety in (0, 1].
    Auto {
        /// Safety factor in (0, 1] (YADE's default is 0.8).
        safety: f64,
    },
    /// A given step (s). Above the bound it is refused unless `allow_unstable`; then
    /// divergence is detected and reported as [`ThermalError::Diverged`].
    Fixed {
        /// Time step (s).
        dt: f64,
        /// Accept a step above the positivity bound.
        allow_unstable: bool,
    },
}

impl Default for TimeStep {
    fn default() -> Self {
        Self::Auto { safety: 0.8 }
    }
}

/// Parameters of [`run_explicit`].
#[derive(Debug, Clone, PartialEq)]
pub struct ExplicitParams {
    /// Simulated duration (s), > 0.
    pub t_end: f64,
    /// Step choice.
    pub dt: TimeStep,
    /// Times (s, ascending, in [0, t_end]) at which the observer sees the temperatures; the
    /// last step before each is shortened to land on it exactly.
    pub output_times: Vec<f64>,
    /// The paper's eq. 16 estimate ([`crate::paper_dt_estimate`]), only reported (s).
    pub paper_dt: Option<f64>,
    /// Refuse runs needing more steps than this (checked before the first step; default
    /// [`crate::DEFAULT_MAX_STEPS`] = 10⁸).
    pub max_steps: u64,
    /// Optional progress callback ([`ProgressFn`]: steps done, steps total), called at most
    /// ~100 times per run.
    pub progress: Option<ProgressFn>,
    /// How the step stores the contact conductances (default [`WeightPrecision::F64`]).
    pub weights: WeightPrecision,
}

impl Default for ExplicitParams {
    fn default() -> Self {
        Self {
            t_end: 1.0,
            dt: TimeStep::default(),
            output_times: Vec::new(),
            paper_dt: None,
            max_steps: DEFAULT_MAX_STEPS,
            progress: None,
            weights: WeightPrecision::default(),
        }
    }
}

/// Full steps of `dt` in a segment of length `span` (s), and whether a shortened last step
/// is needed.
fn segment_steps(span: f64, dt: f64) -> (u64, bool) {
    let mut n_full = (span / dt * (1.0 + 1e-12)).floor() as u64;
    let mut rem = span - n_full as f64 * dt;
    if rem < 0.0 {
        n_full = n_full.saturating_sub(1);
        rem = span - n_full as f64 * dt;
    }
    (n_full, rem > 1e-12 * dt)
}

/// Explicit (forward Euler) transient from `input.temperatures` to `params.t_end`.
///
/// `system`: the checked network, conductances H_pq (W/K), capacities C_p (J/K) and
/// constraints (fixed temperatures, K; floating clusters kept with
/// [`demcon_network::FloatingPolicy::Keep`] evolve on their own); `input`: initial
/// temperatures (K; fixed nodes are overwritten by their value) and sources Q_p (W).
/// `observer(t, T)` is called at each output time. `update` may replace the sources after
/// every step ([`SourceUpdate`]; pass `()` to keep them): the energy ledger integrates the
/// sources in force over each step, and the maximum-principle envelope grows with each new
/// heating rate.
///
/// The step is checked against the exact positivity bound min_p C_p/Σ_q H_pq; the report
/// carries it beside the paper's estimate, the energy balance and the cost.
/// [`run_explicit_from`] adds checkpoints and resuming.
///
/// # Errors
/// Bad input; [`ThermalError::Unstable`] for a fixed step above the bound (unless
/// `allow_unstable`); [`ThermalError::Diverged`] when the solution leaves the range allowed
/// by the maximum principle (widened by its own width when the step is above the bound) or
/// becomes non-finite; an invalid source vector from `update`; an error returned by
/// `update` stops the run and is passed on.
pub fn run_explicit<U: SourceUpdate>(
    system: &ThermalSystem<'_>,
    input: TransientInput<'_>,
    params: &ExplicitParams,
    observer: impl FnMut(f64, &[f64]),
    update: U,
) -> Result<Transient, U::Error> {
    run_explicit_from(
        system,
        TransientStart::Initial(input),
        params,
        observer,
        update,
        None,
    )
}

/// [`run_explicit`] from `start` (initial temperatures, or a [`TransientState`] of an earlier
/// run of the same system and parameters), handing its state to `checkpoints` on their
/// schedule. A resumed run continues bit for bit as the uninterrupted one: same
/// temperatures, later snapshots and report (wall time and throughput aside; the wall time
/// adds the state's). Its observer sees only the stops after the state (and not t = 0).
///
/// # Errors
/// Those of [`run_explicit`]; a state that does not belong to this run (scheme, step, end
/// time, node count, position); a bad schedule; an error returned by `checkpoints.save`
/// stops the run and is passed on.
pub fn run_explicit_from<U: SourceUpdate>(
    system: &ThermalSystem<'_>,
    start: TransientStart<'_>,
    params: &ExplicitParams,
    observer: impl FnMut(f64, &[f64]),
    update: U,
    checkpoints: Option<Checkpoints<'_, U::Error>>,
) -> Result<Transient, U::Error> {
    if let TransientStart::Initial(input) = &start {
        system.check_input(input)?;
    }
    let stops = stops(params.t_end, &params.output_times)?;
    let bound: DtBound = system.stable_dt_bound();
    let dt = match params.dt {
        TimeStep::Auto { safety } => {
            if !(safety > 0.0 && safety <= 1.0) {
                return Err(ThermalError::invalid("dt.safety", safety, "must be in (0, 1]").into());
            }
            (safety * bound.dt_max).min(params.t_end)
        }
        TimeStep::Fixed { dt, allow_unstable } => {
            if !(dt.is_finite() && dt > 0.0) {
                return Err(ThermalError::invalid("dt", dt, "must be a finite time > 0 (s)").into());
            }
            if dt > bound.dt_max && !allow_unstable {
                return Err(ThermalError::Unstable {
                    dt,
                    dt_max: bound.dt_max,
                    node: bound.node,
                }
                .into());
            }
            dt
        }
    };
    let needed = (params.t_end / dt).ceil() + stops.len() as f64;
    check_max_steps(
        dt,
        needed,
        params.t_end,
        params.max_steps,
        "use the implicit or steady solver",
    )?;
    // Full steps of dt in each segment between stops, then a shortened one to land on it.
    let mut t_start = 0.0;
    let segments = stops
        .iter()
        .map(|&stop| {
            let span = stop - t_start;
            let (n_full, has_partial) = segment_steps(span, dt);
            t_start = stop;
            Segment {
                n_steps: n_full + u64::from(has_partial),
                n_full,
                h: dt,
                last: span - n_full as f64 * dt,
            }
        })
        .collect();
    let m = MarchParams {
        scheme: SCHEME,
        dt,
        t_end: params.t_end,
        stops,
        segments,
        output_times: &params.output_times,
        bound,
        paper_dt: params.paper_dt,
        envelope: Some(dt > bound.dt_max),
        progress: params.progress.as_ref(),
    };
    let make = |sources: &[f64]| {
        Ok(ForwardEuler {
            kernel: ExplicitStepper::with_precision(system, sources, dt, params.weights)?,
            dt,
            n_edges: system.network().n_edges(),
        })
    };
    march(system, start, m, make, observer, update, checkpoints)
}

/// Scheme name of the explicit solver.
const SCHEME: &str = "forward-euler";

/// Forward Euler: T' = T + Δt C⁻¹ (−K T + Q), made by [`ExplicitStepper`]; a shortened step θ Δt
/// is T + θ (T_full − T).
struct ForwardEuler<'a> {
    kernel: ExplicitStepper<'a>,
    /// The step the kernel was built for (s).
    dt: f64,
    /// Contacts, for the throughput.
    n_edges: usize,
}

impl Stepper for ForwardEuler<'_> {
    fn ledger(&self) -> Ledger {
        Ledger::Start
    }

    fn step(
        &mut self,
        cur: &[f64],
        next: &mut Vec<f64>,
        h: f64,
        shortened: bool,
        _report: &mut TransientReport,
    ) -> Result<Option<(f64, f64, bool)>, ThermalError> {
        let (mut lo, mut hi, bad) = self.kernel.step(cur, next);
        if shortened {
            // Shortened step: T + θ (T_full − T) is forward Euler with step θ Δt.
            let theta = h / self.dt;
            (lo, hi) = next
                .par_iter_mut()
                .zip(cur.par_iter())
                .with_min_len(CHUNK)
                .map(|(nx, &c)| {
                    *nx = c + theta * (*nx - c);
                    (*nx, *nx)
                })
                .reduce(
                    || (f64::INFINITY, f64::NEG_INFINITY),
                    |a, b| (a.0.min(b.0), a.1.max(b.1)),
                );
        }
        Ok(Some((lo, hi, bad)))
    }

    fn set_sources(&mut self, sources: &[f64]) -> Result<(), ThermalError> {
        self.kernel.set_sources(sources)
    }

    fn unit_roundoff(&self) -> f64 {
        match self.kernel.precision() {
            WeightPrecision::F64 => f64::EPSILON / 2.0,
            WeightPrecision::F32 => f64::from(f32::EPSILON) / 2.0,
        }
    }

    /// Temperatures in huge pages: at 10⁶ particles the step's gathers miss the TLB less.
    fn copy(&self, v: &[f64]) -> Vec<f64> {
        huge_copy(v)
    }

    fn finish(&self, report: &mut TransientReport) {
        report.contacts_per_s = if report.wall_s > 0.0 {
            report.steps as f64 * self.n_edges as f64 / report.wall_s
        } else {
            0.0
        };
    }
}
