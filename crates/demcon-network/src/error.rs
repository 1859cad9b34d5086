//! Errors of the network crate: bad input apart from numerical failure.

use demcon_core::check::CheckError;

/// Why a network could not be built or solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// A parameter or input value is outside its allowed range.
    #[error("invalid {field} = {value}: {allowed}")]
    InvalidParameter {
        /// The input's name (e.g. `conductances[17]`).
        field: String,
        /// The offending value, formatted.
        value: String,
        /// What would have been accepted.
        allowed: String,
    },
    /// An input vector does not have one entry per node (or per edge).
    #[error("{what} has {got} entries, expected {expected}")]
    LengthMismatch {
        /// Which input.
        what: String,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A node index is not below the number of nodes.
    #[error("{what} refers to node {node}, but the network has {n_nodes} nodes")]
    NodeOutOfRange {
        /// Where the index was found (e.g. `edges[12]`, `fixed set 1`).
        what: String,
        /// The offending node index.
        node: u64,
        /// Number of nodes of the network.
        n_nodes: usize,
    },
    /// An edge joins a node to itself.
    #[error("edges[{edge}] joins node {node} to itself")]
    SelfLoop {
        /// Edge index.
        edge: usize,
        /// The node.
        node: u32,
    },
    /// A set of fixed values selects no node.
    #[error("fixed set {set} selects no node")]
    EmptyFixedSet {
        /// Index of the set in the caller's list.
        set: usize,
    },
    /// One node receives two different fixed values.
    #[error("node {node} is fixed to {first} by set {first_set} and to {second} by set {second_set}")]
    ConflictingFixed {
        /// The node.
        node: u32,
        /// First value (K or V).
        first: f64,
        /// Set that gave the first value.
        first_set: usize,
        /// Second value (K or V).
        second: f64,
        /// Set that gave the second value.
        second_set: usize,
    },
    /// No node has a fixed value: a steady problem would be singular.
    #[error(
        "no node has a fixed value: a steady solve needs at least one fixed value (temperature or potential)"
    )]
    NoFixedValue,
    /// Some connected clusters reach no fixed value (their steady state is undetermined).
    #[error(
        "{nodes} node(s) in {clusters} cluster(s) reach no fixed value (largest cluster: {largest} nodes, e.g. node {example}); exclude them (FloatingPolicy::Exclude) or add a fixed value"
    )]
    FloatingCluster {
        /// Number of floating clusters.
        clusters: usize,
        /// Total number of nodes in them.
        nodes: usize,
        /// Size of the largest one.
        largest: usize,
        /// One node of the largest floating cluster.
        example: u32,
    },
    /// An iterative solve stopped before reaching its tolerance.
    #[error(
        "{method} did not converge: relative residual {relative_residual:.3e} > tolerance {tolerance:.1e} after {iterations} iterations"
    )]
    NotConverged {
        /// Method name.
        method: &'static str,
        /// Iterations done.
        iterations: usize,
        /// Relative residual reached, ‖b − Ax‖/‖b‖.
        relative_residual: f64,
        /// Requested tolerance.
        tolerance: f64,
    },
    /// A non-finite number (NaN or ±∞) appeared during an iterative solve, or the residual
    /// norm overflowed: the inputs are too large (or too small) for f64 arithmetic.
    #[error(
        "{method} produced a non-finite {what} = {value:e} at iteration {iteration} (inputs too large for f64 arithmetic? keep |b_i| ≤ {max_rhs:e})",
        max_rhs = crate::solve::MAX_RHS_ENTRY
    )]
    NonFinite {
        /// Method name.
        method: &'static str,
        /// Iteration at which it was seen (0: before the first).
        iteration: usize,
        /// Which quantity (e.g. `relative residual`, `p·Ap`).
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// The residual stopped decreasing above the tolerance and above what the arithmetic
    /// can reach (a stagnating solve is stopped instead of running to `max_iter`).
    #[error(
        "{method} stagnated: relative residual {residual:.3e} > tolerance {tolerance:.1e} after {iterations} iterations, with no decrease over the last {window} restarts (attainable in f64 ≈ {attainable:.1e}; a looser tolerance or Method::Cholesky may help)"
    )]
    Stagnated {
        /// Method name.
        method: &'static str,
        /// Iterations done.
        iterations: usize,
        /// Best true relative residual reached, ‖b − Ax‖/‖b‖.
        residual: f64,
        /// Requested tolerance.
        tolerance: f64,
        /// Estimate of the smallest relative residual f64 arithmetic can resolve for this
        /// system and solution, ε·‖|b| + |A||x|‖/‖b‖ (see [`crate::SolveReport::attainable`]).
        attainable: f64,
        /// Restarts without decrease that triggered the stop.
        window: usize,
    },
    /// The operator was found not positive definite (a numerical breakdown).
    #[error("{method} broke down at iteration {iteration}: the system is not positive definite ({detail})")]
    Breakdown {
        /// Method name.
        method: &'static str,
        /// Iteration at which it happened.
        iteration: usize,
        /// What was seen.
        detail: String,
    },
    /// The direct factorisation failed.
    #[error("sparse Cholesky failed: {0}")]
    Factorization(String),
    /// A distributed solve ([`crate::Method::Distributed`]) cannot run in this build or
    /// process (built without the `petsc` feature, PETSc not started).
    #[error("distributed solve unavailable: {why}")]
    DistributedUnavailable {
        /// What is missing and how to get it.
        why: String,
    },
    /// A PETSc call failed (its `PetscErrorCode` and PETSc's text for it).
    #[error("PETSc's {call} failed with error code {code}: {message}")]
    Petsc {
        /// The PETSc function.
        call: &'static str,
        /// Its `PetscErrorCode`.
        code: i32,
        /// PETSc's description of the code.
        message: String,
    },
}

impl SolveError {
    /// Shorthand for [`SolveError::InvalidParameter`].
    pub fn invalid(field: impl Into<String>, value: impl ToString, allowed: impl Into<String>) -> Self {
        Self::InvalidParameter {
            field: field.into(),
            value: value.to_string(),
            allowed: allowed.into(),
        }
    }
}

/// A failed shared input check ([`demcon_core::check`]): a wrong length is a
/// [`SolveError::LengthMismatch`], a bad value a [`SolveError::InvalidParameter`] naming
/// its index.
impl From<CheckError> for SolveError {
    fn from(e: CheckError) -> Self {
        match e {
            CheckError::Length { what, got, expected } => Self::LengthMismatch { what, expected, got },
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
