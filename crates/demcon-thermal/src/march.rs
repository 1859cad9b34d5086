//! The one time march of the transient solvers. [`march`] owns what every scheme shares: the
//! segments between output times and the steps of each, the energy ledger, the
//! maximum-principle envelope, sources that change during the run, progress, checkpoints and
//! resuming. A [`Stepper`] (forward Euler, backward Euler, Crank–Nicolson) only advances the
//! temperatures by one step.

use std::time::Instant;

use demcon_network::NodeKind;

use crate::capacity::DtBound;
use crate::checkpoint::{Checkpoints, Schedule, TransientStart, TransientState, check_state};
use crate::error::ThermalError;
use crate::system::{SourceUpdate, ThermalSystem};
use crate::transient::{
    ProgressFn, Ticker, Transient, TransientReport, Turnover, boundary_edges, boundary_gross, boundary_power,
    close_ledger, source_gross, source_power,
};

/// When in a step the boundary heat flow is read for the energy ledger: the scheme's own
/// quadrature, so that the ledger closes to round-off.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Ledger {
    /// At the start of the step (forward Euler).
    Start,
    /// At the end of the step (backward Euler).
    End,
    /// The mean of both ends (Crank–Nicolson).
    Trapezoid,
}

/// The steps of one segment (the span between two stops): `n_full` steps of `h`, and, when
/// `n_steps > n_full`, the rest of length `last`. The last step of a segment always ends on
/// its stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Segment {
    /// Steps in the segment.
    pub(crate) n_steps: u64,
    /// Steps of length `h`, before the last step's time is the stop itself.
    pub(crate) n_full: u64,
    /// Step length (s).
    pub(crate) h: f64,
    /// Length of the steps after the first `n_full` (s).
    pub(crate) last: f64,
}

/// One time-stepping scheme, as [`march`] drives it.
pub(crate) trait Stepper {
    /// Where the ledger reads the boundary flow.
    fn ledger(&self) -> Ledger;

    /// Prepares the first step of segment `seg` (e.g. a linear system for its step).
    fn begin_segment(&mut self, seg: usize) -> Result<(), ThermalError> {
        let _ = seg;
        Ok(())
    }

    /// `next` = the temperatures one step of `h` (s) after `cur`, with the sources in force;
    /// `shortened`: a segment's last step, after its `n_full` steps. Returns the range of
    /// `next` and whether a value of it is not finite, when the scheme asks the march to check
    /// the maximum principle; solver counts go to `report`.
    fn step(
        &mut self,
        cur: &[f64],
        next: &mut Vec<f64>,
        h: f64,
        shortened: bool,
        report: &mut TransientReport,
    ) -> Result<Option<(f64, f64, bool)>, ThermalError>;

    /// New sources from the next step on (W per node, checked).
    fn set_sources(&mut self, sources: &[f64]) -> Result<(), ThermalError>;

    /// Relative rounding of one step's arithmetic: the floor of the energy balance.
    fn unit_roundoff(&self) -> f64 {
        f64::EPSILON / 2.0
    }

    /// A copy of a node vector in the layout the stepper works on best.
    fn copy(&self, v: &[f64]) -> Vec<f64> {
        v.to_vec()
    }

    /// Fills what only this scheme reports, at the end.
    fn finish(&self, report: &mut TransientReport) {
        let _ = report;
    }
}

/// What a march needs besides its stepper, from the scheme's checked parameters.
#[derive(Debug)]
pub(crate) struct MarchParams<'p> {
    /// Scheme name (reports; checked against a resumed state before the stepper is made).
    pub(crate) scheme: &'static str,
    /// Nominal step (s).
    pub(crate) dt: f64,
    /// End time (s).
    pub(crate) t_end: f64,
    /// The stops: output times in (0, t_end], then t_end ([`crate::transient::stops`]).
    pub(crate) stops: Vec<f64>,
    /// The steps of each segment between stops.
    pub(crate) segments: Vec<Segment>,
    /// Output times as the caller gave them (t = 0 and t_end are seen only when listed).
    pub(crate) output_times: &'p [f64],
    /// The explicit bound and its node.
    pub(crate) bound: DtBound,
    /// The paper's step estimate, reported (s).
    pub(crate) paper_dt: Option<f64>,
    /// Maximum-principle envelope: `None` unchecked; `Some(widen)` checked after every step,
    /// widened by its own width when the step is above the bound.
    pub(crate) envelope: Option<bool>,
    /// Progress callback.
    pub(crate) progress: Option<&'p ProgressFn>,
}

/// The range the maximum principle allows the temperatures: the initial range, grown by
/// the fastest heating and cooling rate of the sources in force.
#[derive(Debug, Clone)]
struct Envelope {
    /// Initial range (K).
    lo0: f64,
    hi0: f64,
    /// Growth up to the last source change, heating then cooling (K), and its time (s).
    heat_base: f64,
    cool_base: f64,
    t_change: f64,
    /// Fastest heating and cooling of the sources in force (K/s).
    heat_rate: f64,
    cool_rate: f64,
    /// Widen by the width (a step above the bound).
    widen: bool,
}

impl Envelope {
    /// The growth at time `t` (s): heating, cooling (K).
    fn growth(&self, t: f64) -> (f64, f64) {
        (
            self.heat_base + (t - self.t_change) * self.heat_rate,
            self.cool_base + (t - self.t_change) * self.cool_rate,
        )
    }

    /// Fastest heating and cooling rates of `sources` over the free nodes (K/s).
    fn rates(kinds: &[NodeKind], capacities: &[f64], sources: &[f64]) -> (f64, f64) {
        let (mut heat_rate, mut cool_rate) = (0.0f64, 0.0f64);
        for p in 0..kinds.len() {
            if kinds[p] == NodeKind::Free {
                heat_rate = heat_rate.max(sources[p].max(0.0) / capacities[p]);
                cool_rate = cool_rate.max((-sources[p]).max(0.0) / capacities[p]);
            }
        }
        (heat_rate, cool_rate)
    }

    /// The allowed range at `t` (s).
    fn bounds(&self, t: f64) -> (f64, f64) {
        let (heat, cool) = self.growth(t);
        let width = (self.hi0 - self.lo0) + heat + cool;
        // Round-off of the values the envelope now spans (not only of the initial ones:
        // a body heated from 0 K by a source has an initial range of zero width).
        let rounding = 1e-9 * ((self.lo0 - cool).abs() + (self.hi0 + heat).abs() + width) + f64::MIN_POSITIVE;
        let margin = rounding + if self.widen { width } else { 0.0 };
        (self.lo0 - cool - margin, self.hi0 + heat + margin)
    }

    /// New sources at `t` (s): the growth so far becomes the base.
    fn rebase(&mut self, t: f64, rates: (f64, f64)) {
        let (heat, cool) = self.growth(t);
        (self.heat_base, self.cool_base, self.t_change) = (heat, cool, t);
        (self.heat_rate, self.cool_rate) = rates;
    }
}

/// Runs `make(sources)`'s stepper from `start` through the segments of `m`: the observer sees
/// the temperatures at each stop, `update` may replace the sources after every step, and
/// `checkpoints` receive the state on their schedule. A resumed run continues bit for bit as
/// the uninterrupted one.
///
/// # Errors
/// A resumed state that does not belong to this run; a bad checkpoint schedule; the stepper's
/// errors; [`ThermalError::Diverged`] when the envelope is checked and left; what `update` or
/// `checkpoints.save` return.
pub(crate) fn march<S: Stepper, U: SourceUpdate>(
    system: &ThermalSystem<'_>,
    start: TransientStart<'_>,
    m: MarchParams<'_>,
    make: impl FnOnce(&[f64]) -> Result<S, ThermalError>,
    mut observer: impl FnMut(f64, &[f64]),
    mut update: U,
    checkpoints: Option<Checkpoints<'_, U::Error>>,
) -> Result<Transient, U::Error> {
    let clock = Instant::now();
    let (net, capacities, constraints) = (system.network(), system.capacities(), system.constraints());
    let kinds = constraints.kinds();
    let seg_steps: Vec<u64> = m.segments.iter().map(|s| s.n_steps).collect();
    let total = seg_steps.iter().fold(0u64, |a, &b| a.saturating_add(b));
    let mut report = TransientReport::new(m.scheme, m.dt, m.bound, m.paper_dt);
    let mut turnover = Turnover::default();
    // The state to start from: t = 0, or a checkpoint.
    let (cur, t0, mut sources, first_segment, first_step, prior_wall_s, envelope_base);
    match start {
        TransientStart::Initial(input) => {
            let mut t = input.temperatures.to_vec();
            constraints.impose(&mut t);
            (cur, t0) = (t.clone(), t);
            sources = input.sources.to_vec();
            (first_segment, first_step, prior_wall_s) = (0, 0, 0.0);
            envelope_base = [0.0; 3];
        }
        TransientStart::Resume(s) => {
            check_state(s, system, m.scheme, m.dt, m.t_end, &seg_steps)?;
            cur = s.temperatures.clone();
            t0 = s.initial_temperatures.clone();
            sources = s.sources.clone();
            (first_segment, first_step, prior_wall_s) = (s.segment as usize, s.segment_steps, s.wall_s);
            report.steps = s.steps;
            report.energy_sources_j = s.energy_sources_j;
            report.energy_boundary_j = s.energy_boundary_j;
            report.solver_iterations = s.solver_iterations;
            report.max_relative_residual = s.max_relative_residual;
            turnover = Turnover {
                boundary_j: s.turnover_boundary_j,
                sources_j: s.turnover_sources_j,
            };
            envelope_base = s.envelope;
        }
    }
    let mut ticker = Ticker::new(m.progress, total);
    ticker.skip_to(report.steps);
    let mut schedule = Schedule::new(checkpoints, report.steps)?;
    let mut stepper = make(&sources)?;
    let ledger = stepper.ledger();
    let mut cur = stepper.copy(&cur);
    let mut next = stepper.copy(&cur);
    let mut envelope = m.envelope.map(|widen| {
        let (lo0, hi0) = t0.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
        let [heat_base, cool_base, t_change] = envelope_base;
        let (heat_rate, cool_rate) = Envelope::rates(kinds, capacities, &sources);
        Envelope {
            lo0,
            hi0,
            heat_base,
            cool_base,
            t_change,
            heat_rate,
            cool_rate,
            widen,
        }
    });
    let edges_b = boundary_edges(net, system.conductances(), constraints);
    let mut p_src = source_power(constraints, &sources);
    let mut p_src_gross = source_gross(constraints, &sources);
    if first_segment == 0 && first_step == 0 && m.output_times.first() == Some(&0.0) {
        observer(0.0, &cur);
    }
    // The state between two steps, as a checkpoint hands it out.
    let state = |segment: usize,
                 segment_steps: u64,
                 t: f64,
                 cur: &[f64],
                 sources: &[f64],
                 report: &TransientReport,
                 turnover: &Turnover,
                 envelope: Option<&Envelope>| TransientState {
        scheme: m.scheme.into(),
        dt: m.dt,
        t_end: m.t_end,
        segment: segment as u64,
        segment_steps,
        steps: report.steps,
        t,
        temperatures: cur.to_vec(),
        initial_temperatures: t0.clone(),
        sources: sources.to_vec(),
        energy_sources_j: report.energy_sources_j,
        energy_boundary_j: report.energy_boundary_j,
        turnover_boundary_j: turnover.boundary_j,
        turnover_sources_j: turnover.sources_j,
        solver_iterations: report.solver_iterations,
        max_relative_residual: report.max_relative_residual,
        envelope: envelope.map_or([0.0; 3], |e| [e.heat_base, e.cool_base, e.t_change]),
        wall_s: prior_wall_s + clock.elapsed().as_secs_f64(),
    };
    for (seg, (&stop, segment)) in m.stops.iter().zip(&m.segments).enumerate().skip(first_segment) {
        let t_start = if seg == 0 { 0.0 } else { m.stops[seg - 1] };
        let span = stop - t_start;
        stepper.begin_segment(seg)?;
        let k0 = if seg == first_segment { first_step } else { 0 };
        for k in k0..segment.n_steps {
            let shortened = k >= segment.n_full;
            let h = if shortened { segment.last } else { segment.h };
            let p_b_old = boundary_power(&edges_b, &cur);
            if ledger == Ledger::Start {
                report.energy_boundary_j += h * p_b_old;
                turnover.boundary_j += h * boundary_gross(&edges_b, &cur);
            }
            report.energy_sources_j += h * p_src;
            turnover.sources_j += h * p_src_gross;
            let range = stepper.step(&cur, &mut next, h, shortened, &mut report)?;
            match ledger {
                Ledger::Start => {}
                Ledger::End => {
                    report.energy_boundary_j += h * boundary_power(&edges_b, &next);
                    turnover.boundary_j += h * boundary_gross(&edges_b, &next);
                }
                Ledger::Trapezoid => {
                    report.energy_boundary_j += 0.5 * h * (p_b_old + boundary_power(&edges_b, &next));
                    turnover.boundary_j +=
                        0.5 * h * (boundary_gross(&edges_b, &cur) + boundary_gross(&edges_b, &next));
                }
            }
            report.steps += 1;
            ticker.tick(report.steps);
            let t_now = t_start
                + if shortened {
                    span
                } else {
                    (k + 1) as f64 * segment.h
                };
            if let (Some(env), Some((lo, hi, bad))) = (&envelope, range) {
                let (env_lo, env_hi) = env.bounds(t_now);
                if bad || lo < env_lo || hi > env_hi {
                    let node = next
                        .iter()
                        .position(|&v| !v.is_finite() || v < env_lo || v > env_hi)
                        .unwrap_or(0);
                    return Err(ThermalError::Diverged {
                        step: report.steps,
                        t: t_now,
                        node: node as u32,
                        value: next[node],
                        lo: env_lo,
                        hi: env_hi,
                        dt: m.dt,
                        dt_max: m.bound.dt_max,
                    }
                    .into());
                }
            }
            std::mem::swap(&mut cur, &mut next);
            if let Some(new) = update.update(t_now, &cur)? {
                stepper.set_sources(&new)?;
                p_src = source_power(constraints, &new);
                p_src_gross = source_gross(constraints, &new);
                if let Some(env) = &mut envelope {
                    env.rebase(t_now, Envelope::rates(kinds, capacities, &new));
                }
                sources = new;
            }
            if k + 1 < segment.n_steps {
                schedule.after_step(report.steps, || {
                    state(
                        seg,
                        k + 1,
                        t_now,
                        &cur,
                        &sources,
                        &report,
                        &turnover,
                        envelope.as_ref(),
                    )
                })?;
            }
        }
        if stop < m.t_end || m.output_times.last() == Some(&stop) {
            observer(stop, &cur);
        }
        if seg + 1 < m.stops.len() {
            schedule.after_step(report.steps, || {
                state(
                    seg + 1,
                    0,
                    stop,
                    &cur,
                    &sources,
                    &report,
                    &turnover,
                    envelope.as_ref(),
                )
            })?;
        }
    }
    report.t_end = m.t_end;
    report.wall_s = prior_wall_s + clock.elapsed().as_secs_f64();
    stepper.finish(&mut report);
    close_ledger(
        &mut report,
        constraints,
        capacities,
        (&t0, &cur),
        turnover,
        stepper.unit_roundoff(),
    );
    Ok(Transient {
        temperatures: cur,
        report,
    })
}
