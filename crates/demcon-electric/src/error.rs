//! Errors of the electric solver: bad electrodes and parameters apart from network failures.

use demcon_network::SolveError;

/// Why an electric computation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElectricError {
    /// A parameter is outside its allowed range.
    #[error("invalid {field} = {value}: {allowed}")]
    InvalidParameter {
        /// The input's name (e.g. `eta`).
        field: String,
        /// The offending value, formatted.
        value: String,
        /// What would have been accepted.
        allowed: String,
    },
    /// No electrode was given: potentials are undetermined.
    #[error("no electrode: at least one fixed potential is needed (two for a current)")]
    NoElectrode,
    /// An electrode selects no particle.
    #[error("electrode {index} selects no particle")]
    EmptyElectrode {
        /// Index of the electrode in the caller's list.
        index: usize,
    },
    /// Two electrodes share a particle.
    #[error("electrodes {first} and {second} both select particle {node}; electrodes must be disjoint")]
    ElectrodesOverlap {
        /// First electrode index.
        first: usize,
        /// Second electrode index.
        second: usize,
        /// A shared particle.
        node: u32,
    },
    /// The network solve failed (bad input, floating cluster, non-convergence).
    #[error(transparent)]
    Network(#[from] SolveError),
}
