//! Explicit (forward Euler) transient solver, Haddad et al. 2021 eq. 6:
//! C_p (T_p' − T_p)/Δt = Σ_q H_pq (T_q − T_p) + Q_p, with its stability bound enforced and
//! divergence detected.

use std::time::Instant;

use demcon_network::{CHUNK, Constraints, MIN_TASK_CHUNKS, Network, NodeKind};
use rayon::prelude::*;

use crate::capacity::{DtBound, stable_dt_bound};
use crate::error::ThermalError;
use crate::transient::{
    Transient, TransientReport, boundary_edges, boundary_power, check_inputs, close_ledger, source_power,
    stops,
};

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
    /// Refuse runs needing more steps than this.
    pub max_steps: u64,
}

impl Default for ExplicitParams {
    fn default() -> Self {
        Self {
            t_end: 1.0,
            dt: TimeStep::default(),
            output_times: Vec::new(),
            paper_dt: None,
            max_steps: 100_000_000,
        }
    }
}

/// The explicit update with its per-row coefficients precomputed:
/// T'_p = c_p T_p + Σ_q w_pq T_q + s_p, with w_pq = Δt H_pq/C_p, c_p = 1 − Σ_q w_pq,
/// s_p = Δt Q_p/C_p on free rows and T'_p = T_p on the others. Rows are swept in parallel,
/// each summed in a fixed order: results do not depend on the thread count.
#[derive(Debug, Clone)]
pub struct ExplicitStepper<'a> {
    net: &'a Network,
    weights: Vec<f64>,
    centre: Vec<f64>,
    source: Vec<f64>,
    dt: f64,
}

impl<'a> ExplicitStepper<'a> {
    /// Precomputes the coefficients for step `dt` (s). Inputs are as in [`run_explicit`];
    /// `dt` is not checked against the bound here.
    ///
    /// # Errors
    /// Bad input (lengths, non-finite or non-positive values).
    pub fn new(
        net: &'a Network,
        conductances: &[f64],
        capacities: &[f64],
        constraints: &Constraints,
        sources: &[f64],
        dt: f64,
    ) -> Result<Self, ThermalError> {
        let zeros = vec![0.0; net.n_nodes()];
        check_inputs(net, conductances, capacities, constraints, sources, &zeros)?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(ThermalError::invalid("dt", dt, "must be a finite time > 0 (s)"));
        }
        let kinds = constraints.kinds();
        let row_ptr = net.row_ptr();
        let entry_edges = net.entry_edges();
        let n = net.n_nodes();
        let mut weights = vec![0.0; entry_edges.len()];
        let mut centre = vec![1.0; n];
        let mut source = vec![0.0; n];
        // Split the entry array by rows so rows can be filled in parallel.
        let mut rows: Vec<&mut [f64]> = Vec::with_capacity(n);
        let mut rest: &mut [f64] = &mut weights;
        for p in 0..n {
            let (head, tail) = rest.split_at_mut(row_ptr[p + 1] - row_ptr[p]);
            rows.push(head);
            rest = tail;
        }
        rows.into_par_iter()
            .zip(centre.par_iter_mut())
            .zip(source.par_iter_mut())
            .enumerate()
            .with_min_len(CHUNK)
            .for_each(|(p, ((w, c), s))| {
                if kinds[p] != NodeKind::Free {
                    return;
                }
                let a = dt / capacities[p];
                let mut sum = 0.0;
                for (wk, &e) in w.iter_mut().zip(&entry_edges[row_ptr[p]..row_ptr[p + 1]]) {
                    *wk = a * conductances[e as usize];
                    sum += *wk;
                }
                *c = 1.0 - sum;
                *s = a * sources[p];
            });
        Ok(Self {
            net,
            weights,
            centre,
            source,
            dt,
        })
    }

    /// The step (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// One step from `t_old` into `t_new` (K); returns the (min, max) of `t_new` and
    /// whether a non-finite value appeared.
    pub fn step(&self, t_old: &[f64], t_new: &mut [f64]) -> (f64, f64, bool) {
        let row_ptr = self.net.row_ptr();
        let cols = self.net.cols();
        let partials: Vec<(f64, f64, bool)> = t_new
            .par_chunks_mut(CHUNK)
            .enumerate()
            .with_min_len(MIN_TASK_CHUNKS)
            .map(|(c, out)| {
                let base = c * CHUNK;
                let (mut lo, mut hi, mut bad) = (f64::INFINITY, f64::NEG_INFINITY, false);
                for (k, o) in out.iter_mut().enumerate() {
                    let p = base + k;
                    let (a, b) = (row_ptr[p], row_ptr[p + 1]);
                    let mut s = self.centre[p] * t_old[p] + self.source[p];
                    for (&q, &w) in cols[a..b].iter().zip(&self.weights[a..b]) {
                        s += w * t_old[q as usize];
                    }
                    *o = s;
                    lo = lo.min(s);
                    hi = hi.max(s);
                    bad |= !s.is_finite();
                }
                (lo, hi, bad)
            })
            .collect();
        partials.iter().fold(
            (f64::INFINITY, f64::NEG_INFINITY, false),
            |(a, b, c), &(x, y, z)| (a.min(x), b.max(y), c | z),
        )
    }
}

/// Explicit (forward Euler) transient from `t_init` to `params.t_end`.
///
/// `conductances`: H_pq per edge (W/K); `capacities`: C_p (J/K, [`crate::capacities`]);
/// `constraints`: fixed temperatures (K) and floating-cluster handling (use
/// [`demcon_network::FloatingPolicy::Keep`] to let isolated clusters evolve on their own);
/// `sources`: Q_p (W); `t_init`: initial temperatures (K; fixed nodes are overwritten by
/// their value). `observer(t, T)` is called at each output time.
///
/// The step is checked against the exact positivity bound min_p C_p/Σ_q H_pq; the report
/// carries it beside the paper's estimate, the energy balance and the cost.
///
/// # Errors
/// Bad input; [`ThermalError::Unstable`] for a fixed step above the bound (unless
/// `allow_unstable`); [`ThermalError::Diverged`] when the solution leaves the range allowed
/// by the maximum principle (widened by its own width when the step is above the bound) or
/// becomes non-finite.
#[allow(clippy::too_many_arguments)]
pub fn run_explicit(
    net: &Network,
    conductances: &[f64],
    capacities: &[f64],
    constraints: &Constraints,
    sources: &[f64],
    t_init: &[f64],
    params: &ExplicitParams,
    mut observer: impl FnMut(f64, &[f64]),
) -> Result<Transient, ThermalError> {
    let start = Instant::now();
    check_inputs(net, conductances, capacities, constraints, sources, t_init)?;
    let stops = stops(params.t_end, &params.output_times)?;
    let bound: DtBound = stable_dt_bound(net, conductances, capacities, constraints)?;
    let dt = match params.dt {
        TimeStep::Auto { safety } => {
            if !(safety > 0.0 && safety <= 1.0) {
                return Err(ThermalError::invalid("dt.safety", safety, "must be in (0, 1]"));
            }
            (safety * bound.dt_max).min(params.t_end)
        }
        TimeStep::Fixed { dt, allow_unstable } => {
            if !(dt.is_finite() && dt > 0.0) {
                return Err(ThermalError::invalid("dt", dt, "must be a finite time > 0 (s)"));
            }
            if dt > bound.dt_max && !allow_unstable {
                return Err(ThermalError::Unstable {
                    dt,
                    dt_max: bound.dt_max,
                    node: bound.node,
                });
            }
            dt
        }
    };
    let needed = (params.t_end / dt).ceil() + stops.len() as f64;
    if needed > params.max_steps as f64 {
        return Err(ThermalError::invalid(
            "dt",
            dt,
            format!(
                "needs about {needed:.3e} steps to reach t_end = {} s, more than max_steps = {} (use the implicit or steady solver)",
                params.t_end, params.max_steps
            ),
        ));
    }
    let stepper = ExplicitStepper::new(net, conductances, capacities, constraints, sources, dt)?;
    let kinds = constraints.kinds();
    let mut cur = t_init.to_vec();
    constraints.impose(&mut cur);
    let t0 = cur.clone();
    let mut next = cur.clone();

    // Range allowed by the maximum principle, growing with the sources.
    let (lo0, hi0) = cur.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
        (a.min(v), b.max(v))
    });
    let (mut heat_rate, mut cool_rate) = (0.0f64, 0.0f64);
    for p in 0..net.n_nodes() {
        if kinds[p] == NodeKind::Free {
            heat_rate = heat_rate.max(sources[p].max(0.0) / capacities[p]);
            cool_rate = cool_rate.max((-sources[p]).max(0.0) / capacities[p]);
        }
    }
    let rounding = 1e-9 * (lo0.abs() + hi0.abs() + (hi0 - lo0)) + f64::MIN_POSITIVE;
    let unstable = dt > bound.dt_max;

    let edges_b = boundary_edges(net, conductances, constraints);
    let p_src = source_power(constraints, sources);
    let mut report = TransientReport::new("forward-euler", dt, bound, params.paper_dt);
    if params.output_times.first() == Some(&0.0) {
        observer(0.0, &cur);
    }
    let mut t_start = 0.0;
    let mut steps: u64 = 0;
    for &stop in &stops {
        let span = stop - t_start;
        let mut n_full = (span / dt * (1.0 + 1e-12)).floor() as u64;
        let mut rem = span - n_full as f64 * dt;
        if rem < 0.0 {
            n_full = n_full.saturating_sub(1);
            rem = span - n_full as f64 * dt;
        }
        let has_partial = rem > 1e-12 * dt;
        let n_steps = n_full + u64::from(has_partial);
        for k in 0..n_steps {
            let h = if k < n_full { dt } else { rem };
            report.energy_boundary_j += h * boundary_power(&edges_b, &cur);
            report.energy_sources_j += h * p_src;
            let (mut lo, mut hi, bad) = stepper.step(&cur, &mut next);
            if k >= n_full {
                // Shortened step: T + θ (T_full − T) is forward Euler with step θ Δt.
                let theta = h / dt;
                let r = next
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
                (lo, hi) = r;
            }
            steps += 1;
            let t_now = t_start + if k < n_full { (k + 1) as f64 * dt } else { span };
            let width = (hi0 - lo0) + t_now * (heat_rate + cool_rate);
            let margin = rounding + if unstable { width } else { 0.0 };
            let (env_lo, env_hi) = (lo0 - t_now * cool_rate - margin, hi0 + t_now * heat_rate + margin);
            if bad || lo < env_lo || hi > env_hi {
                let node = next
                    .iter()
                    .position(|&v| !v.is_finite() || v < env_lo || v > env_hi)
                    .unwrap_or(0);
                return Err(ThermalError::Diverged {
                    step: steps,
                    t: t_now,
                    node: node as u32,
                    value: next[node],
                    lo: env_lo,
                    hi: env_hi,
                    dt,
                    dt_max: bound.dt_max,
                });
            }
            std::mem::swap(&mut cur, &mut next);
        }
        t_start = stop;
        if stop < params.t_end || params.output_times.last() == Some(&stop) {
            observer(stop, &cur);
        }
    }
    report.steps = steps;
    report.t_end = params.t_end;
    report.wall_s = start.elapsed().as_secs_f64();
    report.contacts_per_s = if report.wall_s > 0.0 {
        steps as f64 * net.n_edges() as f64 / report.wall_s
    } else {
        0.0
    };
    close_ledger(&mut report, constraints, capacities, &t0, &cur);
    Ok(Transient {
        temperatures: cur,
        report,
    })
}
