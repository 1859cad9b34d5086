//! Implicit transients (backward Euler, Crank–Nicolson): unconditionally stable, one
//! linear solve per step through the network (CG warm-started, or a reused Cholesky
//! factor), and the steady state solved directly.

use std::time::Instant;

use demcon_core::check::{check_finite, check_len};
use demcon_network::{Constraints, LinearSystem, Network, NodeKind, Solution, SolveParams, solve_steady};

use crate::checkpoint::{Checkpoints, Schedule, TransientStart, TransientState, check_state};
use crate::error::ThermalError;
use crate::system::{SourceUpdate, ThermalSystem, TransientInput};
use crate::transient::{
    DEFAULT_MAX_STEPS, ProgressFn, Ticker, Transient, TransientReport, Turnover, boundary_edges,
    boundary_gross, boundary_power, check_max_steps, close_ledger, source_gross, source_power, stops,
};

/// Implicit time discretisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scheme {
    /// First order, L-stable (no oscillation): (C/Δt + K) T' = C/Δt T + Q.
    #[default]
    BackwardEuler,
    /// Second order, A-stable (may oscillate for Δt far above the explicit bound):
    /// (2C/Δt + K) T' = (2C/Δt − K) T + 2Q.
    CrankNicolson,
}

impl Scheme {
    fn name(self) -> &'static str {
        match self {
            Self::BackwardEuler => "backward-euler",
            Self::CrankNicolson => "crank-nicolson",
        }
    }
}

/// Parameters of [`run_implicit`].
#[derive(Debug, Clone, PartialEq)]
pub struct ImplicitParams {
    /// Simulated duration (s), > 0.
    pub t_end: f64,
    /// Time step (s), > 0; shortened uniformly within a segment to land on output times.
    pub dt: f64,
    /// Scheme.
    pub scheme: Scheme,
    /// Times (s, ascending, in [0, t_end]) at which the observer sees the temperatures.
    pub output_times: Vec<f64>,
    /// Linear solver of each step.
    pub solve: SolveParams,
    /// Refuse runs needing more steps than this (checked before the first step, with the
    /// same rule and message as [`crate::ExplicitParams::max_steps`]; default
    /// [`crate::DEFAULT_MAX_STEPS`] = 10⁸).
    pub max_steps: u64,
    /// Optional progress callback ([`ProgressFn`]: steps done, steps total), called at most
    /// ~100 times per run.
    pub progress: Option<ProgressFn>,
}

impl Default for ImplicitParams {
    fn default() -> Self {
        Self {
            t_end: 1.0,
            dt: 0.01,
            scheme: Scheme::default(),
            output_times: Vec::new(),
            solve: SolveParams::default(),
            max_steps: DEFAULT_MAX_STEPS,
            progress: None,
        }
    }
}

/// Implicit transient from `input.temperatures` to `params.t_end`; `system`, `input`,
/// `observer` and `update` as in [`crate::run_explicit`]. Floating clusters may be kept
/// ([`demcon_network::FloatingPolicy::Keep`]): their heat capacity makes each step well
/// posed. Each step uses the sources in force at its start (for Crank–Nicolson, at both
/// ends of the step); the energy ledger integrates them. [`run_implicit_from`] adds
/// checkpoints and resuming.
///
/// # Errors
/// Bad input; linear-solver failures ([`ThermalError::Network`]); an invalid source vector
/// from `update`; an error returned by `update` stops the run and is passed on.
pub fn run_implicit(
    system: &ThermalSystem<'_>,
    input: TransientInput<'_>,
    params: &ImplicitParams,
    observer: impl FnMut(f64, &[f64]),
    update: impl SourceUpdate,
) -> Result<Transient, ThermalError> {
    run_implicit_from(
        system,
        TransientStart::Initial(input),
        params,
        observer,
        update,
        None,
    )
}

/// [`run_implicit`] from `start` (initial temperatures, or a [`TransientState`] of an earlier
/// run of the same system and parameters), handing its state to `checkpoints` on their
/// schedule; as [`crate::run_explicit_from`], a resumed run continues bit for bit as the
/// uninterrupted one (each step's solve is warm-started from the temperatures, which the
/// state holds; the linear system is rebuilt for the step in force).
///
/// # Errors
/// Those of [`run_implicit`]; a state that does not belong to this run; a bad schedule; an
/// error returned by `checkpoints.save` stops the run and is passed on.
pub fn run_implicit_from(
    system: &ThermalSystem<'_>,
    start: TransientStart<'_>,
    params: &ImplicitParams,
    mut observer: impl FnMut(f64, &[f64]),
    mut update: impl SourceUpdate,
    checkpoints: Option<Checkpoints<'_>>,
) -> Result<Transient, ThermalError> {
    let clock = Instant::now();
    if let TransientStart::Initial(input) = &start {
        system.check_input(input)?;
    }
    let (net, conductances, capacities, constraints) = (
        system.network(),
        system.conductances(),
        system.capacities(),
        system.constraints(),
    );
    let stops = stops(params.t_end, &params.output_times)?;
    if !(params.dt.is_finite() && params.dt > 0.0) {
        return Err(ThermalError::invalid(
            "dt",
            params.dt,
            "must be a finite time > 0 (s)",
        ));
    }
    // Steps of each segment between stops (output times), counted before the first step.
    let mut seg_steps = Vec::with_capacity(stops.len());
    let mut t_prev = 0.0;
    for &stop in &stops {
        // `as` saturates: an absurd count stays huge and is refused below.
        seg_steps.push(((stop - t_prev) / params.dt * (1.0 - 1e-12)).ceil().max(1.0) as u64);
        t_prev = stop;
    }
    let total = seg_steps.iter().fold(0u64, |a, &b| a.saturating_add(b));
    check_max_steps(
        params.dt,
        total as f64,
        params.t_end,
        params.max_steps,
        "use a larger dt or the steady solver",
    )?;
    // The step each segment's linear system is built for: a segment whose step is within
    // 1e-12 of the system in force reuses it.
    let mut sys_h: Vec<f64> = Vec::with_capacity(stops.len());
    let mut t_prev = 0.0;
    for (&stop, &n_steps) in stops.iter().zip(&seg_steps) {
        let h = (stop - t_prev) / n_steps as f64;
        let reuse = matches!(sys_h.last(), Some(&d) if (d - h).abs() <= 1e-12 * h);
        sys_h.push(if reuse { sys_h[sys_h.len() - 1] } else { h });
        t_prev = stop;
    }
    let bound = system.stable_dt_bound();
    let n = net.n_nodes();
    let cn = params.scheme == Scheme::CrankNicolson;
    let factor = if cn { 2.0 } else { 1.0 };
    let scheme = params.scheme.name();
    let mut report = TransientReport::new(scheme, params.dt, bound, None);
    let mut turnover = Turnover::default();
    // The state to start from: t = 0, or a checkpoint.
    let (mut cur, t0, mut sources, first_segment, first_step, prior_wall_s);
    match start {
        TransientStart::Initial(input) => {
            cur = input.temperatures.to_vec();
            constraints.impose(&mut cur);
            t0 = cur.clone();
            sources = input.sources.to_vec();
            (first_segment, first_step, prior_wall_s) = (0, 0, 0.0);
        }
        TransientStart::Resume(s) => {
            check_state(s, system, scheme, params.dt, params.t_end, &seg_steps)?;
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
        }
    }
    let mut ticker = Ticker::new(params.progress.as_ref(), total);
    ticker.skip_to(report.steps);
    let mut schedule = Schedule::new(checkpoints, report.steps)?;
    let edges_b = boundary_edges(net, conductances, constraints);
    let mut p_src = source_power(constraints, &sources);
    let mut p_src_gross = source_gross(constraints, &sources);
    let kinds = constraints.kinds();

    if first_segment == 0 && first_step == 0 && params.output_times.first() == Some(&0.0) {
        observer(0.0, &cur);
    }
    // The state between two steps, as a checkpoint hands it out.
    let state = |segment: usize,
                 segment_steps: u64,
                 t: f64,
                 cur: &[f64],
                 sources: &[f64],
                 report: &TransientReport,
                 turnover: &Turnover| TransientState {
        scheme: scheme.into(),
        dt: params.dt,
        t_end: params.t_end,
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
        envelope: [0.0; 3],
        wall_s: prior_wall_s + clock.elapsed().as_secs_f64(),
    };
    let mut shift = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    let mut system: Option<(f64, LinearSystem<'_>)> = None;
    for (seg, (&stop, &n_steps)) in stops.iter().zip(&seg_steps).enumerate().skip(first_segment) {
        let t_start = if seg == 0 { 0.0 } else { stops[seg - 1] };
        let span = stop - t_start;
        let h = span / n_steps as f64;
        let h_sys = sys_h[seg];
        if !matches!(&system, Some((d, _)) if d.to_bits() == h_sys.to_bits()) {
            for p in 0..n {
                shift[p] = factor * capacities[p] / h_sys;
            }
            system = Some((
                h_sys,
                LinearSystem::new(net, conductances, Some(&shift), constraints, &params.solve)?,
            ));
        }
        let sys = match &system {
            Some((_, s)) => s,
            None => unreachable!("system built above"),
        };
        let k0 = if seg == first_segment { first_step } else { 0 };
        for k in k0..n_steps {
            let p_b_old = boundary_power(&edges_b, &cur);
            if cn {
                let k_t = net.apply_laplacian(conductances, &cur)?;
                for p in 0..n {
                    rhs[p] = shift[p] * cur[p] - k_t[p] + 2.0 * sources[p];
                }
            } else {
                for p in 0..n {
                    rhs[p] = shift[p] * cur[p] + sources[p];
                }
            }
            let Solution {
                values, report: r, ..
            } = sys.solve(&rhs, Some(&cur))?;
            let mut next = values;
            // Excluded nodes keep their value (they are not part of the solve).
            for p in constraints.excluded() {
                next[*p as usize] = cur[*p as usize];
            }
            let p_b_new = boundary_power(&edges_b, &next);
            let prev = &cur;
            report.energy_boundary_j += if cn {
                0.5 * h * (p_b_old + p_b_new)
            } else {
                h * p_b_new
            };
            report.energy_sources_j += h * p_src;
            turnover.boundary_j += if cn {
                0.5 * h * (boundary_gross(&edges_b, prev) + boundary_gross(&edges_b, &next))
            } else {
                h * boundary_gross(&edges_b, &next)
            };
            turnover.sources_j += h * p_src_gross;
            report.solver_iterations += r.iterations as u64;
            report.max_relative_residual = report.max_relative_residual.max(r.relative_residual);
            report.steps += 1;
            ticker.tick(report.steps);
            cur = next;
            let t_now = t_start
                + if k + 1 == n_steps {
                    span
                } else {
                    (k + 1) as f64 * h
                };
            if let Some(new) = update.update(t_now, &cur)? {
                check_len("sources", new.len(), n)?;
                check_finite("sources", &new)?;
                p_src = source_power(constraints, &new);
                p_src_gross = source_gross(constraints, &new);
                sources = new;
            }
            if k + 1 < n_steps {
                schedule.after_step(report.steps, || {
                    state(seg, k + 1, t_now, &cur, &sources, &report, &turnover)
                })?;
            }
        }
        if stop < params.t_end || params.output_times.last() == Some(&stop) {
            observer(stop, &cur);
        }
        if seg + 1 < stops.len() {
            schedule.after_step(report.steps, || {
                state(seg + 1, 0, stop, &cur, &sources, &report, &turnover)
            })?;
        }
    }
    debug_assert!(kinds.len() == n);
    report.t_end = params.t_end;
    report.wall_s = prior_wall_s + clock.elapsed().as_secs_f64();
    close_ledger(
        &mut report,
        constraints,
        capacities,
        (&t0, &cur),
        turnover,
        f64::EPSILON / 2.0,
    );
    Ok(Transient {
        temperatures: cur,
        report,
    })
}

/// Steady temperatures and the heat balance that checks them.
#[derive(Debug, Clone, PartialEq)]
pub struct SteadyTemperature {
    /// Temperatures (K), with excluded nodes listed (value 0, not a result) and the solve
    /// report.
    pub solution: Solution,
    /// Heat leaving the free nodes into the fixed-temperature nodes (W); equals the total
    /// source power at steady state.
    pub heat_to_fixed_w: f64,
    /// Σ Q over free nodes (W).
    pub source_power_w: f64,
    /// |heat_to_fixed − source_power| / (gross boundary flow + Σ|Q|), the gross boundary flow
    /// being Σ over fixed-to-free edges of |H (T_fixed − T_free)| (W) and Σ|Q| over free nodes
    /// (0 if the scale is 0). The net flows nearly cancel on a run between two fixed sets, so
    /// they cannot be the scale; a correct solve gives ~ its residual (≤ 1e-9 at rel_tol 1e-8).
    pub balance_error: f64,
}

/// Steady state K T = Q with the fixed temperatures of `constraints` (K), solved directly
/// through the network (CG or Cholesky per `params`).
///
/// # Errors
/// Bad input, floating clusters that were not excluded, solver failures.
pub fn solve_steady_temperature(
    net: &Network,
    conductances: &[f64],
    constraints: &Constraints,
    sources: &[f64],
    params: &SolveParams,
) -> Result<SteadyTemperature, ThermalError> {
    check_len("sources", sources.len(), net.n_nodes())?;
    check_finite("sources", sources)?;
    let solution = solve_steady(net, conductances, constraints, sources, params)?;
    let edges_b = boundary_edges(net, conductances, constraints);
    let heat_to_fixed_w = -boundary_power(&edges_b, &solution.values);
    let source_power_w: f64 = constraints
        .kinds()
        .iter()
        .zip(sources)
        .filter(|(k, _)| **k == NodeKind::Free)
        .map(|(_, q)| q)
        .sum();
    let scale = boundary_gross(&edges_b, &solution.values) + source_gross(constraints, sources);
    let balance_error = if scale > 0.0 {
        (heat_to_fixed_w - source_power_w).abs() / scale
    } else {
        0.0
    };
    Ok(SteadyTemperature {
        solution,
        heat_to_fixed_w,
        source_power_w,
        balance_error,
    })
}
