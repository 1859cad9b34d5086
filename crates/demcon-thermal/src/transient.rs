//! Pieces shared by the transient solvers: output times, the energy ledger.

use std::sync::Arc;

use demcon_network::{Constraints, Network, NodeKind};

use crate::error::ThermalError;

/// Result of a transient run.
#[derive(Debug, Clone, PartialEq)]
pub struct Transient {
    /// Temperatures at `t_end` (K). Fixed nodes hold their value; excluded nodes keep their
    /// initial value.
    pub temperatures: Vec<f64>,
    /// What happened and what it cost.
    pub report: TransientReport,
}

/// Cost, step and energy balance of a transient run.
#[derive(Debug, Clone, PartialEq)]
pub struct TransientReport {
    /// Scheme name (`forward-euler`, `backward-euler`, `crank-nicolson`).
    pub scheme: &'static str,
    /// Number of time steps taken.
    pub steps: u64,
    /// Nominal time step (s).
    pub dt: f64,
    /// Forward-Euler positivity bound min_p C_p/Σ_q H_pq (s).
    pub dt_bound: f64,
    /// Node that sets `dt_bound`.
    pub dt_bound_node: u32,
    /// The paper's eq. 16 estimate, when the caller supplied it (s).
    pub paper_dt: Option<f64>,
    /// Final time (s).
    pub t_end: f64,
    /// Wall time (s).
    pub wall_s: f64,
    /// Total linear-solver iterations (implicit schemes; 0 for explicit).
    pub solver_iterations: u64,
    /// Largest relative residual of the linear solves (implicit schemes; 0 for explicit).
    pub max_relative_residual: f64,
    /// Contact updates per second of wall time (explicit scheme; 0 otherwise).
    pub contacts_per_s: f64,
    /// Heat stored in the free nodes, Σ C_p (T_end − T_0) (J).
    pub energy_stored_j: f64,
    /// Heat injected by the sources into free nodes, ∫ Σ Q_p dt (J).
    pub energy_sources_j: f64,
    /// Heat received from fixed-temperature nodes, ∫ Σ H_pq (T_fixed − T_p) dt (J).
    pub energy_boundary_j: f64,
    /// |stored − sources − boundary| / scale, the scale being the gross energy turnover:
    /// Σ_p C_p |T_end − T_0| + ∫ Σ_p |Q_p| dt + ∫ Σ_boundary edges |H_pq (T_q − T_p)| dt
    /// (0 if the scale is 0). Not the net flow, which is ≈ 0 on a correct run between two
    /// fixed sets or with no boundary at all: a correct run gives round-off (~1e-12).
    pub energy_balance_error: f64,
    /// Smallest and largest temperature at the end (K).
    pub t_range: [f64; 2],
}

impl TransientReport {
    /// A report with the step data filled and everything measured set to zero.
    pub(crate) fn new(scheme: &'static str, dt: f64, bound: crate::DtBound, paper_dt: Option<f64>) -> Self {
        Self {
            scheme,
            steps: 0,
            dt,
            dt_bound: bound.dt_max,
            dt_bound_node: bound.node,
            paper_dt,
            t_end: 0.0,
            wall_s: 0.0,
            solver_iterations: 0,
            max_relative_residual: 0.0,
            contacts_per_s: 0.0,
            energy_stored_j: 0.0,
            energy_sources_j: 0.0,
            energy_boundary_j: 0.0,
            energy_balance_error: 0.0,
            t_range: [0.0, 0.0],
        }
    }
}

/// Default step cap of both transient solvers ([`crate::ExplicitParams::max_steps`],
/// [`crate::ImplicitParams::max_steps`]): 10⁸ steps.
pub const DEFAULT_MAX_STEPS: u64 = 100_000_000;

/// Most calls of a [`ProgressFn`] per run (plus one at the end).
pub const PROGRESS_CALLS: u64 = 100;

/// Progress callback of a transient run: `f(steps_done, steps_total)`, called after a step
/// at most [`PROGRESS_CALLS`] times per run (every ⌈total/100⌉ steps) and once after the
/// last step (`steps_done == steps_total`). `steps_total` is known before the first step.
/// Meant for a progress bar on long runs; it must be cheap and must not panic.
///
/// ```
/// use demcon_thermal::ProgressFn;
/// let p = ProgressFn::new(|done, total| eprintln!("{done}/{total}"));
/// # let _ = p;
/// ```
#[derive(Clone)]
pub struct ProgressFn(pub Arc<dyn Fn(u64, u64) + Send + Sync>);

impl ProgressFn {
    /// Wraps a closure `f(steps_done, steps_total)`.
    pub fn new(f: impl Fn(u64, u64) + Send + Sync + 'static) -> Self {
        Self(Arc::new(f))
    }
}

impl std::fmt::Debug for ProgressFn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ProgressFn(..)")
    }
}

/// Two callbacks are equal when they are the same closure (pointer equality).
impl PartialEq for ProgressFn {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Calls a [`ProgressFn`] at most [`PROGRESS_CALLS`] times over `total` steps.
pub(crate) struct Ticker<'p> {
    f: Option<&'p ProgressFn>,
    total: u64,
    every: u64,
    next: u64,
}

impl<'p> Ticker<'p> {
    pub(crate) fn new(f: Option<&'p ProgressFn>, total: u64) -> Self {
        let every = total.div_ceil(PROGRESS_CALLS).max(1);
        Self {
            f,
            total,
            every,
            next: every,
        }
    }

    /// A resumed run: `done` steps were taken before it; the next call comes at the first
    /// multiple of the period after them.
    pub(crate) fn skip_to(&mut self, done: u64) {
        if done > 0 {
            self.next = (done / self.every + 1).saturating_mul(self.every);
        }
    }

    /// After step `done` (1-based).
    #[inline]
    pub(crate) fn tick(&mut self, done: u64) {
        if let Some(f) = self.f
            && (done >= self.next || done == self.total)
        {
            (f.0)(done, self.total);
            self.next = done.saturating_add(self.every);
        }
    }
}

/// Refuses a run of `needed` steps above `max_steps` (the same rule and message for both
/// transient solvers), before the first step.
pub(crate) fn check_max_steps(
    dt: f64,
    needed: f64,
    t_end: f64,
    max_steps: u64,
    hint: &str,
) -> Result<(), ThermalError> {
    if max_steps == 0 {
        return Err(ThermalError::invalid("max_steps", 0, "must be ≥ 1"));
    }
    if needed > max_steps as f64 {
        return Err(ThermalError::invalid(
            "dt",
            format!("{dt:e}"),
            format!(
                "needs about {needed:.3e} steps to reach t_end = {t_end:e} s, more than max_steps = {max_steps} ({hint})"
            ),
        ));
    }
    Ok(())
}

/// Checks `t_end` and the output times; returns the stops: the sorted output times in
/// (0, t_end] followed by t_end, deduplicated.
pub(crate) fn stops(t_end: f64, output_times: &[f64]) -> Result<Vec<f64>, ThermalError> {
    if !(t_end.is_finite() && t_end > 0.0) {
        return Err(ThermalError::invalid(
            "t_end",
            t_end,
            "must be a finite time > 0 (s)",
        ));
    }
    let mut out = Vec::with_capacity(output_times.len() + 1);
    let mut last = 0.0;
    for (k, &t) in output_times.iter().enumerate() {
        // A time past t_end by rounding only (e.g. t_end·k/n at k = n) is t_end.
        let t = if t > t_end && t <= t_end * (1.0 + 1e-12) {
            t_end
        } else {
            t
        };
        if !(t.is_finite() && t >= last && t <= t_end) {
            return Err(ThermalError::invalid(
                format!("output_times[{k}]"),
                t,
                format!("must be ascending times in [0, t_end = {t_end}] (s)"),
            ));
        }
        last = t;
        if t > 0.0 && out.last() != Some(&t) {
            out.push(t);
        }
    }
    if out.last() != Some(&t_end) {
        out.push(t_end);
    }
    Ok(out)
}

/// Edges between a free node and a fixed node, as (free, fixed, H): the boundary of the
/// energy ledger.
pub(crate) fn boundary_edges(
    net: &Network,
    conductances: &[f64],
    constraints: &Constraints,
) -> Vec<(u32, u32, f64)> {
    let k = constraints.kinds();
    net.edges()
        .iter()
        .zip(conductances)
        .filter_map(|(&[p, q], &g)| match (k[p as usize], k[q as usize]) {
            (NodeKind::Free, NodeKind::Fixed) => Some((p, q, g)),
            (NodeKind::Fixed, NodeKind::Free) => Some((q, p, g)),
            _ => None,
        })
        .collect()
}

/// Heat flow into the free nodes from the fixed ones (W).
pub(crate) fn boundary_power(edges: &[(u32, u32, f64)], t: &[f64]) -> f64 {
    edges
        .iter()
        .map(|&(free, fixed, g)| g * (t[fixed as usize] - t[free as usize]))
        .sum()
}

/// Gross heat flow through the boundary, Σ over boundary edges of |H (T_fixed − T_free)|
/// (W): the scale of the energy balance.
pub(crate) fn boundary_gross(edges: &[(u32, u32, f64)], t: &[f64]) -> f64 {
    edges
        .iter()
        .map(|&(free, fixed, g)| (g * (t[fixed as usize] - t[free as usize])).abs())
        .sum()
}

/// Σ over free nodes of |Q_p| (W).
pub(crate) fn source_gross(constraints: &Constraints, sources: &[f64]) -> f64 {
    constraints
        .kinds()
        .iter()
        .zip(sources)
        .filter(|(k, _)| **k == NodeKind::Free)
        .map(|(_, q)| q.abs())
        .sum()
}

/// Gross energy turnover of a run (J), accumulated beside the ledger: the denominator of
/// [`TransientReport::energy_balance_error`].
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Turnover {
    /// ∫ Σ |H ΔT| over boundary edges dt (J).
    pub(crate) boundary_j: f64,
    /// ∫ Σ |Q_p| dt (J).
    pub(crate) sources_j: f64,
}

/// Σ over free nodes of Q_p (W).
pub(crate) fn source_power(constraints: &Constraints, sources: &[f64]) -> f64 {
    constraints
        .kinds()
        .iter()
        .zip(sources)
        .filter(|(k, _)| **k == NodeKind::Free)
        .map(|(_, q)| q)
        .sum()
}

/// Fills the energy fields and the range of a report from the start and end states.
///
/// `unit_roundoff`: the relative rounding of one step's arithmetic (2⁻⁵³ in f64, 2⁻²⁴ with
/// f32 conductances). A run whose whole turnover (gross stored, source and boundary energy)
/// stays below the rounding the steps can produce on the energy content,
/// `steps × unit_roundoff × Σ C_p max(|T₀|, |T₁|)`, moved nothing measurable: its balance
/// error is 0 (a ratio of round-off to round-off would read as a plausible few per cent).
pub(crate) fn close_ledger(
    report: &mut TransientReport,
    constraints: &Constraints,
    capacities: &[f64],
    (t0, t1): (&[f64], &[f64]),
    turnover: Turnover,
    unit_roundoff: f64,
) {
    let (stored, stored_gross, content) = constraints
        .kinds()
        .iter()
        .enumerate()
        .filter(|(_, k)| **k == NodeKind::Free)
        .map(|(p, _)| {
            (
                capacities[p] * (t1[p] - t0[p]),
                capacities[p] * t0[p].abs().max(t1[p].abs()),
            )
        })
        .fold((0.0, 0.0, 0.0), |(s, g, c), (v, e)| (s + v, g + v.abs(), c + e));
    report.energy_stored_j = stored;
    let scale = stored_gross + turnover.sources_j + turnover.boundary_j;
    let floor = report.steps.max(1) as f64 * unit_roundoff * content;
    report.energy_balance_error = if scale > floor {
        (stored - report.energy_sources_j - report.energy_boundary_j).abs() / scale
    } else {
        0.0
    };
    let (lo, hi) = t1.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
        (a.min(v), b.max(v))
    });
    report.t_range = [lo, hi];
}

#[cfg(test)]
mod tests {
    use super::stops;

    #[test]
    fn output_times_past_t_end_by_rounding_are_t_end() {
        let t_end = 254.49193782192313;
        let times: Vec<f64> = (1..=20).map(|k| t_end * k as f64 / 20.0).collect();
        let s = stops(t_end, &times).unwrap();
        assert_eq!(s.len(), 20);
        assert_eq!(*s.last().unwrap(), t_end);
        // Beyond rounding it is still an error naming the entry.
        assert!(stops(1.0, &[0.5, 1.001]).is_err());
        assert!(stops(1.0, &[0.5, 0.4]).is_err());
    }
}
