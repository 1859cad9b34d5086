//! Errors of the thermal solvers: bad input, refused unstable steps, detected divergence.

use demcon_core::check::CheckError;
use demcon_network::SolveError;

/// Why a thermal computation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ThermalError {
    /// A parameter or input value is outside its allowed range.
    #[error("invalid {field} = {value}: {allowed}")]
    InvalidParameter {
        /// The input's name (e.g. `capacities[3]`, `params.t_end`).
        field: String,
        /// The offending value, formatted.
        value: String,
        /// What would have been accepted.
        allowed: String,
    },
    /// The requested explicit step exceeds the stability bound min_p C_p/Σ_q H_pq.
    #[error(
        "explicit time step {dt:.4e} s exceeds the stability bound {dt_max:.4e} s (set by node {node}); use TimeStep::Auto, a smaller step, the implicit solver, or allow_unstable to insist"
    )]
    Unstable {
        /// Requested step (s).
        dt: f64,
        /// Bound min_p C_p/Σ_q H_pq (s).
        dt_max: f64,
        /// Node that sets the bound.
        node: u32,
    },
    /// The explicit solution left the range allowed by the maximum principle (or became
    /// non-finite): the step was too large.
    #[error(
        "explicit solution diverged at step {step} (t = {t:.4e} s): node {node} reached {value:e} K, outside [{lo:.4e}, {hi:.4e}] K (dt = {dt:.4e} s, stability bound {dt_max:.4e} s)"
    )]
    Diverged {
        /// Step number (1-based).
        step: u64,
        /// Time reached (s).
        t: f64,
        /// A node outside the range.
        node: u32,
        /// Its value (K), possibly non-finite.
        value: f64,
        /// Lower end of the allowed range (K).
        lo: f64,
        /// Upper end of the allowed range (K).
        hi: f64,
        /// Step used (s).
        dt: f64,
        /// Stability bound (s).
        dt_max: f64,
    },
    /// A network solve failed (bad input, floating cluster, non-convergence).
    #[error(transparent)]
    Network(#[from] SolveError),
}

impl ThermalError {
    /// Shorthand for [`ThermalError::InvalidParameter`].
    pub fn invalid(field: impl Into<String>, value: impl ToString, allowed: impl Into<String>) -> Self {
        Self::InvalidParameter {
            field: field.into(),
            value: value.to_string(),
            allowed: allowed.into(),
        }
    }
}

/// A failed shared input check ([`demcon_core::check`]) as an
/// [`ThermalError::InvalidParameter`]: `what (length)` for a wrong length, `what[i]` for the
/// first bad value.
impl From<CheckError> for ThermalError {
    fn from(e: CheckError) -> Self {
        match e {
            CheckError::Length { what, got, expected } => Self::invalid(
                format!("{what} (length)"),
                got,
                format!("must have one entry per particle ({expected})"),
            ),
            CheckError::Value {
                what,
                index,
                value,
                rule,
            } => Self::invalid(
                format!("{what}[{index}]"),
                value,
                format!("must be {}", rule.describe()),
            ),
        }
    }
}
