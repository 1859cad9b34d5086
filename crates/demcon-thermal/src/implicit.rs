//! Implicit transients (backward Euler, Crank–Nicolson): unconditionally stable, one
//! linear solve per step through the network (CG warm-started, or a reused Cholesky
//! factor), and the steady state solved directly.

use demcon_core::check::{check_finite, check_len};
use demcon_network::{Constraints, LinearSystem, Network, NodeKind, Solution, SolveParams, solve_steady};

use crate::checkpoint::{Checkpoints, TransientStart};
use crate::error::ThermalError;
use crate::march::{Ledger, MarchParams, Segment, Stepper, march};
use crate::system::{SourceUpdate, ThermalSystem, TransientInput};
use crate::transient::{
    DEFAULT_MAX_STEPS, ProgressFn, Transient, TransientReport, boundary_edges, boundary_gross,
    boundary_power, check_max_steps, source_gross, stops,
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
pub fn run_implicit<U: SourceUpdate>(
    system: &ThermalSystem<'_>,
    input: TransientInput<'_>,
    params: &ImplicitParams,
    observer: impl FnMut(f64, &[f64]),
    update: U,
) -> Result<Transient, U::Error> {
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
pub fn run_implicit_from<U: SourceUpdate>(
    system: &ThermalSystem<'_>,
    start: TransientStart<'_>,
    params: &ImplicitParams,
    observer: impl FnMut(f64, &[f64]),
    update: U,
    checkpoints: Option<Checkpoints<'_, U::Error>>,
) -> Result<Transient, U::Error> {
    if let TransientStart::Initial(input) = &start {
        system.check_input(input)?;
    }
    let (stops, seg_steps) = implicit_segments(params.t_end, params.dt, &params.output_times)?;
    let total = seg_steps.iter().fold(0u64, |a, &b| a.saturating_add(b));
    check_max_steps(
        params.dt,
        total as f64,
        params.t_end,
        params.max_steps,
        "use a larger dt or the steady solver",
    )?;
    // Each segment's uniform step, and the step its linear system is built for: a segment
    // whose step is within 1e-12 of the system in force reuses it.
    let (mut segments, mut sys_h) = (
        Vec::with_capacity(stops.len()),
        Vec::<f64>::with_capacity(stops.len()),
    );
    let mut t_prev = 0.0;
    for (&stop, &n_steps) in stops.iter().zip(&seg_steps) {
        let h = (stop - t_prev) / n_steps as f64;
        segments.push(Segment {
            n_steps,
            n_full: n_steps - 1,
            h,
            last: h,
        });
        let reuse = matches!(sys_h.last(), Some(&d) if (d - h).abs() <= 1e-12 * h);
        sys_h.push(if reuse { sys_h[sys_h.len() - 1] } else { h });
        t_prev = stop;
    }
    let m = MarchParams {
        scheme: params.scheme.name(),
        dt: params.dt,
        t_end: params.t_end,
        stops,
        segments,
        output_times: &params.output_times,
        bound: system.stable_dt_bound(),
        paper_dt: None,
        envelope: None,
        progress: params.progress.as_ref(),
    };
    let make = |sources: &[f64]| {
        let n = system.n_nodes();
        Ok(Implicit {
            system,
            scheme: params.scheme,
            solve: params.solve,
            sys_h,
            shift: vec![0.0; n],
            rhs: vec![0.0; n],
            sources: sources.to_vec(),
            prepared: None,
        })
    };
    march(system, start, m, make, observer, update, checkpoints)
}

/// The stops of an implicit run (output times in (0, t_end], then t_end, s) and the number
/// of equal steps in each segment before it: ⌈span/dt⌉ (less 10⁻¹² for rounding), at least 1.
fn implicit_segments(
    t_end: f64,
    dt: f64,
    output_times: &[f64],
) -> Result<(Vec<f64>, Vec<u64>), ThermalError> {
    let stops = stops(t_end, output_times)?;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(ThermalError::invalid("dt", dt, "must be a finite time > 0 (s)"));
    }
    let mut seg_steps = Vec::with_capacity(stops.len());
    let mut t_prev = 0.0;
    for &stop in &stops {
        // `as` saturates: an absurd count stays huge and is refused by the caller.
        seg_steps.push(((stop - t_prev) / dt * (1.0 - 1e-12)).ceil().max(1.0) as u64);
        t_prev = stop;
    }
    Ok((stops, seg_steps))
}

/// The length (s) of the implicit step that starts at `t` (s; 0 or a time a step ended at)
/// in a run of `t_end`, `dt` and `output_times` ([`ImplicitParams`]); `dt` past `t_end`.
///
/// # Errors
/// The parameters' own ([`run_implicit`]).
pub fn implicit_step_after(t_end: f64, dt: f64, output_times: &[f64], t: f64) -> Result<f64, ThermalError> {
    let (stops, seg_steps) = implicit_segments(t_end, dt, output_times)?;
    let mut t_prev = 0.0;
    for (&stop, &n) in stops.iter().zip(&seg_steps) {
        let h = (stop - t_prev) / n as f64;
        // The step ending within rounding of the stop belongs to the next segment.
        if t < stop - 0.5 * h {
            return Ok(h);
        }
        t_prev = stop;
    }
    Ok(dt)
}

/// Backward Euler or Crank–Nicolson: one solve of (f C/Δt + K) T' = b per step (f = 1 or 2),
/// the system built once per step length.
struct Implicit<'a> {
    system: &'a ThermalSystem<'a>,
    scheme: Scheme,
    solve: SolveParams,
    /// The step each segment's system is built for (s).
    sys_h: Vec<f64>,
    /// f C/Δt (W/K) and the right-hand side (W), per node.
    shift: Vec<f64>,
    rhs: Vec<f64>,
    /// Sources in force (W).
    sources: Vec<f64>,
    /// The system in force and its step (s).
    prepared: Option<(f64, LinearSystem<'a>)>,
}

impl Stepper for Implicit<'_> {
    fn ledger(&self) -> Ledger {
        match self.scheme {
            Scheme::BackwardEuler => Ledger::End,
            Scheme::CrankNicolson => Ledger::Trapezoid,
        }
    }

    fn begin_segment(&mut self, seg: usize) -> Result<(), ThermalError> {
        let h_sys = self.sys_h[seg];
        if matches!(&self.prepared, Some((d, _)) if d.to_bits() == h_sys.to_bits()) {
            return Ok(());
        }
        let factor = if self.scheme == Scheme::CrankNicolson {
            2.0
        } else {
            1.0
        };
        let s = self.system;
        for (d, c) in self.shift.iter_mut().zip(s.capacities()) {
            *d = factor * c / h_sys;
        }
        let sys = LinearSystem::new(
            s.network(),
            s.conductances(),
            Some(&self.shift),
            s.constraints(),
            &self.solve,
        )?;
        self.prepared = Some((h_sys, sys));
        Ok(())
    }

    fn step(
        &mut self,
        cur: &[f64],
        next: &mut Vec<f64>,
        _h: f64,
        _shortened: bool,
        report: &mut TransientReport,
    ) -> Result<Option<(f64, f64, bool)>, ThermalError> {
        let Some((_, sys)) = &self.prepared else {
            unreachable!("the march begins every segment")
        };
        let (shift, sources) = (&self.shift, &self.sources);
        if self.scheme == Scheme::CrankNicolson {
            let k_t = self
                .system
                .network()
                .apply_laplacian(self.system.conductances(), cur)?;
            for (p, b) in self.rhs.iter_mut().enumerate() {
                *b = shift[p] * cur[p] - k_t[p] + 2.0 * sources[p];
            }
        } else {
            for (p, b) in self.rhs.iter_mut().enumerate() {
                *b = shift[p] * cur[p] + sources[p];
            }
        }
        let Solution {
            values, report: r, ..
        } = sys.solve(&self.rhs, Some(cur))?;
        *next = values;
        // Excluded nodes keep their value (they are not part of the solve).
        for &p in self.system.constraints().excluded() {
            next[p as usize] = cur[p as usize];
        }
        report.solver_iterations += r.iterations as u64;
        report.max_relative_residual = report.max_relative_residual.max(r.relative_residual);
        Ok(None)
    }

    fn set_sources(&mut self, sources: &[f64]) -> Result<(), ThermalError> {
        check_len("sources", sources.len(), self.sources.len())?;
        check_finite("sources", sources)?;
        self.sources.copy_from_slice(sources);
        Ok(())
    }
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
