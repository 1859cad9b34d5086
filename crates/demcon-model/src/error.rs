//! Model errors: a bad value names the caller's field it came from ([`FieldNames`]); numerical
//! failures keep the lower crate's error (with its values) as the source.

use demcon_core::CoreError;

/// Why a model could not be built or solved.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A value is not allowed.
    #[error("field `{field}` = {value}: {allowed}")]
    Invalid {
        /// Field path in the caller's terms ([`FieldNames`]), e.g. `thermal.bcs[0].face`.
        field: String,
        /// The value.
        value: String,
        /// What would be accepted.
        allowed: String,
    },
    /// A lower-level input error, with the field it came from.
    #[error("field `{field}`: {source}")]
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

/// The names a caller gives the parts of its input, so that a refused value is named where the
/// user wrote it: the scene passes its RON paths (`thermal.bcs`, `outputs.etc_axis`, …); the
/// default is the model's own parameter names. A refusal appends the item and sub-field
/// (`{bcs}[2].face`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldNames {
    /// [`crate::ThermalProblem::bcs`].
    pub bcs: &'static str,
    /// [`crate::ThermalProblem::sources`].
    pub sources: &'static str,
    /// [`crate::ThermalProblem::solver`] (its time step is `{solver}.dt`).
    pub solver: &'static str,
    /// [`crate::ElectricProblem::electrodes`].
    pub electrodes: &'static str,
    /// The choice of a periodic electric homogenisation.
    pub electric_homogenize: &'static str,
    /// The tolerance of the electro-thermal coupling.
    pub recouple_tolerance: &'static str,
    /// A checkpoint a run resumes from ([`crate::RunCheckpoint`]).
    pub checkpoint: &'static str,
    /// The surface model (its C_t is `{surface}.c_t`).
    pub surface: &'static str,
    /// [`crate::ModelParams::phases`].
    pub phases: &'static str,
    /// A [`crate::PhaseSpec::Inclusions`] phase.
    pub inclusions: &'static str,
    /// [`crate::ModelParams::phase_rule`].
    pub phase_rule: &'static str,
    /// [`crate::ModelParams::carve`].
    pub carve: &'static str,
    /// [`crate::ModelParams::contacts`].
    pub contacts: &'static str,
    /// [`crate::ModelParams::defects`] as a whole.
    pub defects: &'static str,
    /// [`crate::DefectSpec::interfaces`].
    pub interfaces: &'static str,
    /// [`crate::DefectSpec::grain_boundaries`].
    pub grain_boundaries: &'static str,
    /// [`crate::DefectSpec::cracks`].
    pub cracks: &'static str,
    /// [`crate::DefectSpec::damage`].
    pub damage: &'static str,
    /// [`crate::DefectSpec::cut_pairs`].
    pub cut_contacts: &'static str,
    /// The axis of an effective conductivity ([`crate::effective_conductivity`]).
    pub etc_axis: &'static str,
}

impl FieldNames {
    /// The model's own parameter names.
    pub const MODEL: Self = Self {
        bcs: "bcs",
        sources: "sources",
        solver: "solver",
        electrodes: "electrodes",
        electric_homogenize: "homogenize",
        recouple_tolerance: "recouple_tolerance",
        checkpoint: "checkpoint",
        surface: "surface",
        phases: "phases",
        inclusions: "phases.Inclusions",
        phase_rule: "phase_rule",
        carve: "carve",
        contacts: "contacts",
        defects: "defects",
        interfaces: "interfaces",
        grain_boundaries: "grain_boundaries",
        cracks: "cracks",
        damage: "damage",
        cut_contacts: "cut_pairs",
        etc_axis: "axis",
    };
}

impl Default for FieldNames {
    fn default() -> Self {
        Self::MODEL
    }
}
