//! Checkpoints of a transient: the [`TransientState`] a run hands out between two steps
//! (every K steps and/or every T seconds of wall time, [`CheckpointEvery`]) and from which
//! [`crate::run_explicit_from`] and [`crate::run_implicit_from`] continue exactly as if the run
//! had never stopped: same temperatures, snapshots and report, bit for bit (wall times
//! aside).
//!
//! The wall clock only decides *when* a state is handed out; taking one reads the solver's
//! variables and changes none of them, so results never depend on when checkpoints happen.

use std::time::Instant;

use crate::error::ThermalError;
use crate::system::ThermalSystem;

/// The state of a transient between two steps: everything needed to continue it
/// bit-identically. Plain data (every field public) so a caller can store it; the solvers
/// check it against their system and parameters before continuing.
///
/// The observer of the run that wrote it has seen every stop (output time) before
/// `segment`, and t = 0 when asked: a resumed run calls it only for the later stops, so a
/// caller keeps what its observer saw beside the state.
#[derive(Debug, Clone, PartialEq)]
pub struct TransientState {
    /// Scheme of the run (`forward-euler`, `backward-euler`, `crank-nicolson`).
    pub scheme: String,
    /// Nominal time step of the run (s); a resumed run must compute the same.
    pub dt: f64,
    /// End time of the run (s).
    pub t_end: f64,
    /// The segment (the span up to the next stop: output times, then `t_end`) the next step
    /// belongs to, from 0.
    pub segment: u64,
    /// Steps already taken in that segment.
    pub segment_steps: u64,
    /// Steps taken since t = 0.
    pub steps: u64,
    /// Time reached (s).
    pub t: f64,
    /// Temperature of every node (K).
    pub temperatures: Vec<f64>,
    /// Temperature of every node at t = 0, fixed values imposed (K): the reference of the
    /// stored energy.
    pub initial_temperatures: Vec<f64>,
    /// Heat sources in force, one per node (W).
    pub sources: Vec<f64>,
    /// Heat injected by the sources so far, ∫ Σ Q_p dt (J).
    pub energy_sources_j: f64,
    /// Heat received from fixed-temperature nodes so far (J).
    pub energy_boundary_j: f64,
    /// Gross boundary turnover so far, ∫ Σ |H ΔT| dt (J).
    pub turnover_boundary_j: f64,
    /// Gross source turnover so far, ∫ Σ |Q_p| dt (J).
    pub turnover_sources_j: f64,
    /// Linear-solver iterations so far (implicit schemes; 0 for explicit).
    pub solver_iterations: u64,
    /// Largest relative residual so far (implicit schemes; 0 for explicit).
    pub max_relative_residual: f64,
    /// Explicit scheme: growth of the maximum-principle envelope up to the last source
    /// change, heating then cooling (K), and that change's time (s); zeros for implicit.
    pub envelope: [f64; 3],
    /// Wall time spent so far (s); only reported (the resumed report adds its own).
    pub wall_s: f64,
}

/// Where a transient starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TransientStart<'a> {
    /// At t = 0 from initial temperatures and sources.
    Initial(crate::TransientInput<'a>),
    /// From a state handed out by an earlier run of the same system and parameters.
    Resume(&'a TransientState),
}

/// When a transient hands out its state: after every `steps` steps and/or once `seconds` of
/// wall time have passed since the last checkpoint (or the start), whichever comes first;
/// never when both are `None`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CheckpointEvery {
    /// Steps between two checkpoints (≥ 1).
    pub steps: Option<u64>,
    /// Wall time between two checkpoints (s, finite and > 0).
    pub seconds: Option<f64>,
}

impl CheckpointEvery {
    /// Checks the schedule.
    ///
    /// # Errors
    /// `checkpoint.steps` = 0, or `checkpoint.seconds` not finite and > 0.
    pub fn check(&self) -> Result<(), ThermalError> {
        if self.steps == Some(0) {
            return Err(ThermalError::invalid("checkpoint.steps", 0, "must be ≥ 1"));
        }
        if let Some(s) = self.seconds
            && !(s.is_finite() && s > 0.0)
        {
            return Err(ThermalError::invalid(
                "checkpoint.seconds",
                s,
                "must be a finite time > 0 (s)",
            ));
        }
        Ok(())
    }
}

/// The checkpoints of a run: when, and what receives each state. An error returned by
/// `save` stops the run and is returned by it as it is (the state it was given is complete: a
/// caller may keep it and stop on purpose). `E` is the caller's error type, the one its
/// [`crate::SourceUpdate`] returns; the solver's own errors convert into it.
pub struct Checkpoints<'a, E = ThermalError> {
    /// When.
    pub every: CheckpointEvery,
    /// Receives each state.
    pub save: &'a mut dyn FnMut(TransientState) -> Result<(), E>,
}

impl<E> std::fmt::Debug for Checkpoints<'_, E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Checkpoints")
            .field("every", &self.every)
            .finish_non_exhaustive()
    }
}

/// Decides when a checkpoint is due; kept apart from the arithmetic.
pub(crate) struct Schedule<'a, E> {
    checkpoints: Option<Checkpoints<'a, E>>,
    last_steps: u64,
    last_time: Instant,
}

impl<'a, E> Schedule<'a, E> {
    /// A schedule starting at `steps` steps done.
    pub(crate) fn new(checkpoints: Option<Checkpoints<'a, E>>, steps: u64) -> Result<Self, ThermalError> {
        if let Some(c) = &checkpoints {
            c.every.check()?;
        }
        Ok(Self {
            checkpoints,
            last_steps: steps,
            last_time: Instant::now(),
        })
    }

    /// After `steps` steps: hands out the state `make` builds when a checkpoint is due.
    #[inline]
    pub(crate) fn after_step(&mut self, steps: u64, make: impl FnOnce() -> TransientState) -> Result<(), E> {
        let Some(c) = self.checkpoints.as_mut() else {
            return Ok(());
        };
        let by_steps = c
            .every
            .steps
            .is_some_and(|k| steps >= self.last_steps.saturating_add(k));
        let by_time = c
            .every
            .seconds
            .is_some_and(|s| self.last_time.elapsed().as_secs_f64() >= s);
        if by_steps || by_time {
            (c.save)(make())?;
            self.last_steps = steps;
            self.last_time = Instant::now();
        }
        Ok(())
    }
}

/// Checks a state against the run about to continue it: scheme, step, end time, the node
/// count, finite values, and a position (`segment`, `segment_steps`, `steps`) that lies on
/// the run's own step sequence (`seg_steps`: the steps of each segment).
pub(crate) fn check_state(
    state: &TransientState,
    system: &ThermalSystem<'_>,
    scheme: &str,
    dt: f64,
    t_end: f64,
    seg_steps: &[u64],
) -> Result<(), ThermalError> {
    let bad = |field: &str, value: String, allowed: String| {
        Err(ThermalError::invalid(
            format!("resume state: {field}"),
            value,
            allowed,
        ))
    };
    if state.scheme != scheme {
        return bad("scheme", state.scheme.clone(), format!("this run is {scheme}"));
    }
    if state.dt.to_bits() != dt.to_bits() {
        return bad(
            "dt",
            format!("{:e}", state.dt),
            format!("this run steps {dt:e} s (another system or step choice?)"),
        );
    }
    if state.t_end.to_bits() != t_end.to_bits() {
        return bad(
            "t_end",
            format!("{:e}", state.t_end),
            format!("this run ends at {t_end:e} s"),
        );
    }
    let n = system.n_nodes();
    for (what, v) in [
        ("temperatures", &state.temperatures),
        ("initial_temperatures", &state.initial_temperatures),
        ("sources", &state.sources),
    ] {
        demcon_core::check::check_len(what, v.len(), n)?;
        demcon_core::check::check_finite(what, v)?;
    }
    let seg = state.segment as usize;
    let in_seg = seg_steps.get(seg).copied();
    let placed = match in_seg {
        Some(k) => state.segment_steps == 0 || state.segment_steps < k,
        None => false,
    };
    let before: u64 = seg_steps.iter().take(seg).sum();
    if !placed || before + state.segment_steps != state.steps {
        return bad(
            "position",
            format!(
                "segment {}, step {} of it, {} steps",
                state.segment, state.segment_steps, state.steps
            ),
            format!(
                "must lie before the end of this run ({} segments, {} steps)",
                seg_steps.len(),
                seg_steps.iter().sum::<u64>()
            ),
        );
    }
    Ok(())
}
