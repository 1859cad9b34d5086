//! The error type of demcon-graph: bad input apart from numerical failure.

use demcon_core::CoreError;

/// Why a contact graph or one of its derived quantities could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GraphError {
    /// A parameter or an input array is invalid (names the field, the value and what is allowed).
    #[error(transparent)]
    Invalid(#[from] CoreError),
    /// The particle set has no particle.
    #[error("the particle set is empty: contact detection needs at least 2 particles")]
    EmptyParticleSet,
    /// Two particles have the same centre, so their contact normal is undefined.
    #[error(
        "particles {p} and {q} have the same centre (distance {distance} m): the contact normal is undefined"
    )]
    CoincidentCentres {
        /// First particle id.
        p: u32,
        /// Second particle id.
        q: u32,
        /// Their centre distance (m), zero or below 1e-12 of their radii sum.
        distance: f64,
    },
    /// The target mean coordination number cannot be reached with a tolerance up to the limit.
    #[error(
        "target coordination Z = {target} is unreachable: the largest tolerance tried, \
         epsilon = {max_epsilon} (relative gap), gives Z = {max_coordination}; \
         lower the target, raise max_epsilon, or (periodic box) enlarge the box"
    )]
    UnreachableCoordination {
        /// Requested mean coordination number.
        target: f64,
        /// Mean coordination number reached at `max_epsilon`.
        max_coordination: f64,
        /// Largest relative gap tolerance tried (bounded by `max_epsilon` and, in a periodic
        /// box, by the minimum-image limit).
        max_epsilon: f64,
    },
}

/// Checks that a number is finite and strictly positive.
pub(crate) fn positive(field: &str, value: f64) -> Result<f64, GraphError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(CoreError::invalid(field, value, "must be a finite number > 0").into())
    }
}

/// Checks that an array has the expected length.
pub(crate) fn same_len(field: &str, len: usize, expected: usize, what: &str) -> Result<(), GraphError> {
    if len == expected {
        Ok(())
    } else {
        Err(CoreError::invalid(
            field,
            format!("{len} values"),
            format!("one per {what} ({expected})"),
        )
        .into())
    }
}
