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

/// Where a march starts: t = 0, or a checkpoint's state, checked against the run.
struct Start {
    cur: Vec<f64>,
    t0: Vec<f64>,
    sources: Vec<f64>,
    segment: usize,
    segment_steps: u64,
    prior_wall_s: f64,
    envelope_base: [f64; 3],
    report: TransientReport,
    turnover: Turnover,
}

impl Start {
    fn read(
        system: &ThermalSystem<'_>,
        start: TransientStart<'_>,
        m: &MarchParams<'_>,
        seg_steps: &[u64],
    ) -> Result<Self, ThermalError> {
        let mut report = TransientReport::new(m.scheme, m.dt, m.bound, m.paper_dt);
        Ok(match start {
            TransientStart::Initial(input) => {
                let mut t = input.temperatures.to_vec();
                system.constraints().impose(&mut t);
                Start {
                    cur: t.clone(),
                    t0: t,
                    sources: input.sources.to_vec(),
                    segment: 0,
                    segment_steps: 0,
                    prior_wall_s: 0.0,
                    envelope_base: [0.0; 3],
                    report,
                    turnover: Turnover::default(),
                }
            }
            TransientStart::Resume(s) => {
                check_state(s, system, m.scheme, m.dt, m.t_end, seg_steps)?;
                report.steps = s.steps;
                report.energy_sources_j = s.energy_sources_j;
                report.energy_boundary_j = s.energy_boundary_j;
                report.solver_iterations = s.solver_iterations;
                report.max_relative_residual = s.max_relative_residual;
                Start {
                    cur: s.temperatures.clone(),
                    t0: s.initial_temperatures.clone(),
                    sources: s.sources.clone(),
                    segment: s.segment as usize,
                    segment_steps: s.segment_steps,
                    prior_wall_s: s.wall_s,
                    envelope_base: s.envelope,
                    report,
                    turnover: Turnover {
                        boundary_j: s.turnover_boundary_j,
                        sources_j: s.turnover_sources_j,
                    },
                }
            }
        })
    }
}

/// A march under way: the stepper, the temperatures, the sources in force, the ledger and the
/// envelope.
struct Marching<'a, 'p, S> {
    system: &'a ThermalSystem<'a>,
    m: &'a MarchParams<'p>,
    stepper: S,
    ledger: Ledger,
    /// Free–fixed edges: the boundary of the ledger.
    edges_b: Vec<(u32, u32, f64)>,
    cur: Vec<f64>,
    next: Vec<f64>,
    t0: Vec<f64>,
    sources: Vec<f64>,
    /// Net and gross source power over the free nodes (W).
    p_src: f64,
    p_src_gross: f64,
    report: TransientReport,
    turnover: Turnover,
    envelope: Option<Envelope>,
    ticker: Ticker<'p>,
    clock: Instant,
    prior_wall_s: f64,
}

impl<'a, 'p, S: Stepper> Marching<'a, 'p, S> {
    fn new(
        system: &'a ThermalSystem<'a>,
        m: &'a MarchParams<'p>,
        from: Start,
        stepper: S,
        ticker: Ticker<'p>,
        clock: Instant,
    ) -> Self {
        let (capacities, constraints) = (system.capacities(), system.constraints());
        let envelope = m.envelope.map(|widen| {
            let (lo0, hi0) = from
                .t0
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
            let [heat_base, cool_base, t_change] = from.envelope_base;
            let (heat_rate, cool_rate) = Envelope::rates(constraints.kinds(), capacities, &from.sources);
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
        let cur = stepper.copy(&from.cur);
        Self {
            system,
            m,
            ledger: stepper.ledger(),
            edges_b: boundary_edges(system.network(), system.conductances(), constraints),
            next: stepper.copy(&cur),
            cur,
            t0: from.t0,
            p_src: source_power(constraints, &from.sources),
            p_src_gross: source_gross(constraints, &from.sources),
            sources: from.sources,
            report: from.report,
            turnover: from.turnover,
            envelope,
            ticker,
            clock,
            prior_wall_s: from.prior_wall_s,
            stepper,
        }
    }

    /// Step `k` of `segment` (which starts at `t_start` and spans `span`, s): the ledger, the
    /// step, the envelope. Returns the time reached (s).
    fn step(&mut self, segment: &Segment, k: u64, t_start: f64, span: f64) -> Result<f64, ThermalError> {
        let edges_b = &self.edges_b;
        let shortened = k >= segment.n_full;
        let h = if shortened { segment.last } else { segment.h };
        // The boundary flow at the start of the step, for the schemes whose ledger reads it.
        let p_b_old = match self.ledger {
            Ledger::End => 0.0,
            Ledger::Start | Ledger::Trapezoid => boundary_power(edges_b, &self.cur),
        };
        if self.ledger == Ledger::Start {
            self.report.energy_boundary_j += h * p_b_old;
            self.turnover.boundary_j += h * boundary_gross(edges_b, &self.cur);
        }
        self.report.energy_sources_j += h * self.p_src;
        self.turnover.sources_j += h * self.p_src_gross;
        let range = self
            .stepper
            .step(&self.cur, &mut self.next, h, shortened, &mut self.report)?;
        match self.ledger {
            Ledger::Start => {}
            Ledger::End => {
                self.report.energy_boundary_j += h * boundary_power(edges_b, &self.next);
                self.turnover.boundary_j += h * boundary_gross(edges_b, &self.next);
            }
            Ledger::Trapezoid => {
                self.report.energy_boundary_j += 0.5 * h * (p_b_old + boundary_power(edges_b, &self.next));
                self.turnover.boundary_j +=
                    0.5 * h * (boundary_gross(edges_b, &self.cur) + boundary_gross(edges_b, &self.next));
            }
        }
        self.report.steps += 1;
        self.ticker.tick(self.report.steps);
        let t_now = t_start
            + if shortened {
                span
            } else {
                (k + 1) as f64 * segment.h
            };
        if let (Some(env), Some((lo, hi, bad))) = (&self.envelope, range) {
            let (env_lo, env_hi) = env.bounds(t_now);
            if bad || lo < env_lo || hi > env_hi {
                let node = self
                    .next
                    .iter()
                    .position(|&v| !v.is_finite() || v < env_lo || v > env_hi)
                    .unwrap_or(0);
                return Err(ThermalError::Diverged {
                    step: self.report.steps,
                    t: t_now,
                    node: node as u32,
                    value: self.next[node],
                    lo: env_lo,
                    hi: env_hi,
                    dt: self.m.dt,
                    dt_max: self.m.bound.dt_max,
                });
            }
        }
        std::mem::swap(&mut self.cur, &mut self.next);
        Ok(t_now)
    }

    /// New sources from the next step on, at time `t` (s).
    fn set_sources(&mut self, t: f64, new: Vec<f64>) -> Result<(), ThermalError> {
        let (capacities, constraints) = (self.system.capacities(), self.system.constraints());
        self.stepper.set_sources(&new)?;
        self.p_src = source_power(constraints, &new);
        self.p_src_gross = source_gross(constraints, &new);
        if let Some(env) = &mut self.envelope {
            env.rebase(t, Envelope::rates(constraints.kinds(), capacities, &new));
        }
        self.sources = new;
        Ok(())
    }

    /// The state between two steps, as a checkpoint hands it out: the next step is step
    /// `segment_steps` of `segment`, at time `t` (s).
    fn state(&self, segment: usize, segment_steps: u64, t: f64) -> TransientState {
        let (report, turnover) = (&self.report, &self.turnover);
        TransientState {
            scheme: self.m.scheme.into(),
            dt: self.m.dt,
            t_end: self.m.t_end,
            segment: segment as u64,
            segment_steps,
            steps: report.steps,
            t,
            temperatures: self.cur.to_vec(),
            initial_temperatures: self.t0.clone(),
            sources: self.sources.to_vec(),
            energy_sources_j: report.energy_sources_j,
            energy_boundary_j: report.energy_boundary_j,
            turnover_boundary_j: turnover.boundary_j,
            turnover_sources_j: turnover.sources_j,
            solver_iterations: report.solver_iterations,
            max_relative_residual: report.max_relative_residual,
            envelope: self
                .envelope
                .as_ref()
                .map_or([0.0; 3], |e| [e.heat_base, e.cool_base, e.t_change]),
            wall_s: self.prior_wall_s + self.clock.elapsed().as_secs_f64(),
        }
    }

    /// The result: the report completed and the ledger closed.
    fn finish(mut self) -> Transient {
        self.report.t_end = self.m.t_end;
        self.report.wall_s = self.prior_wall_s + self.clock.elapsed().as_secs_f64();
        self.stepper.finish(&mut self.report);
        close_ledger(
            &mut self.report,
            self.system.constraints(),
            self.system.capacities(),
            (&self.t0, &self.cur),
            self.turnover,
            self.stepper.unit_roundoff(),
        );
        Transient {
            temperatures: self.cur,
            report: self.report,
        }
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
    let seg_steps: Vec<u64> = m.segments.iter().map(|s| s.n_steps).collect();
    let total = seg_steps.iter().fold(0u64, |a, &b| a.saturating_add(b));
    let from = Start::read(system, start, &m, &seg_steps)?;
    let (first_segment, first_step) = (from.segment, from.segment_steps);
    let mut ticker = Ticker::new(m.progress, total);
    ticker.skip_to(from.report.steps);
    let mut schedule = Schedule::new(checkpoints, from.report.steps)?;
    let stepper = make(&from.sources)?;
    let mut run = Marching::new(system, &m, from, stepper, ticker, clock);
    if first_segment == 0 && first_step == 0 && m.output_times.first() == Some(&0.0) {
        observer(0.0, &run.cur);
    }
    for (seg, (&stop, segment)) in m.stops.iter().zip(&m.segments).enumerate().skip(first_segment) {
        let t_start = if seg == 0 { 0.0 } else { m.stops[seg - 1] };
        run.stepper.begin_segment(seg)?;
        let k0 = if seg == first_segment { first_step } else { 0 };
        for k in k0..segment.n_steps {
            let t_now = run.step(segment, k, t_start, stop - t_start)?;
            update.exchange(&mut run.cur)?;
            if let Some(new) = update.update(t_now, &run.cur)? {
                run.set_sources(t_now, new)?;
            }
            if k + 1 < segment.n_steps {
                schedule.after_step(run.report.steps, || run.state(seg, k + 1, t_now))?;
            }
        }
        if stop < m.t_end || m.output_times.last() == Some(&stop) {
            observer(stop, &run.cur);
        }
        if seg + 1 < m.stops.len() {
            schedule.after_step(run.report.steps, || run.state(seg + 1, 0, stop))?;
        }
    }
    Ok(run.finish())
}
