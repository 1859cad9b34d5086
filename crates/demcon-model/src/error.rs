//! Model errors: a bad value names the scene field it came from; numerical failures keep the
//! lower crate's error (with its values) as the source.

use demcon_core::CoreError;

/// Why a model could not be built or solved.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A value is not allowed.
    #[error("scene field `{field}` = {value}: {allowed}")]
    Invalid {
        /// Field path, e.g. `thermal.bcs[0].value`.
        field: String,
        /// The value.
        value: String,
        /// What would be accepted.
        allowed: String,
    },
    /// A lower-level input error, with the field it came from.
    #[error("scene field `{field}`: {source}")]
    Core {
        /// Field path.
        field: String,
        /// The error.
        source: CoreError,
    },
    /// Packing failed (inclusion placement).
    #[error("packing: {0}")]
    Packing(String),
    /// Contact detection or surfaces failed.
    #[error("contacts: {0}")]
    Graph(#[from] demcon_graph::GraphError),
    /// A linear solve or boundary-condition resolution failed.
    #[error("network: {0}")]
    Solve(#[from] demcon_network::SolveError),
    /// The thermal solver failed (instability, divergence…).
    #[error("thermal: {0}")]
    Thermal(#[from] demcon_thermal::ThermalError),
    /// The electric solver failed.
    #[error("electric: {0}")]
    Electric(#[from] demcon_electric::ElectricError),
}

impl ModelError {
    /// An invalid value at `field`.
    /// A number that would print with many digits (`1e-300` as 0.000…) is written in `{:e}` form.
    pub fn invalid(field: &str, value: impl std::fmt::Display, allowed: impl Into<String>) -> Self {
        Self::Invalid {
            field: field.into(),
            value: demcon_core::short_number(value.to_string()),
            allowed: allowed.into(),
        }
    }

    /// A core error at `field`.
    pub fn at(field: &str, source: CoreError) -> Self {
        Self::Core {
            field: field.into(),
            source,
        }
    }
}
