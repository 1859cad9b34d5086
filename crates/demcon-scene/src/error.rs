//! Scene errors: bad input names the file, line or field; numerical failures keep the lower
//! crate's error (with its values) as the source.

use std::path::PathBuf;

use demcon_core::CoreError;

/// Why a scene could not be loaded or run.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The RON text does not parse or has an unknown/missing field.
    #[error("{path}:{line}:{col}: {message}")]
    Parse {
        /// The scene file.
        path: PathBuf,
        /// Line (1-based).
        line: usize,
        /// Column (1-based).
        col: usize,
        /// What is wrong (from the RON parser: unknown field, expected type…).
        message: String,
    },
    /// A value is not allowed.
    #[error("scene field `{field}` = {value}: {allowed}")]
    Invalid {
        /// Field path, e.g. `materials[1].conductivity`.
        field: String,
        /// The value.
        value: String,
        /// What would be accepted.
        allowed: String,
    },
    /// A scene given as a tree of values (a Python dict) has an unknown key, a missing one or
    /// a value of the wrong type.
    #[error("scene field `{field}`: {message}")]
    Schema {
        /// Field path, e.g. `thermal.bcs[0].value` (`.` for the scene itself).
        field: String,
        /// What is wrong, in the scene's words.
        message: String,
    },
    /// Several refusals of one scene, reported together (each as it would be alone).
    #[error("{} problems in the scene:{}", .0.len(), numbered(.0))]
    Several(Vec<SceneError>),
    /// A lower-level input error, with the scene field it came from.
    #[error("scene field `{field}`: {source}")]
    Core {
        /// Field path.
        field: String,
        /// The error.
        source: CoreError,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// A checkpoint cannot be used: none to resume from, or one that is damaged, of another
    /// format, or written for another scene or packing.
    #[error("checkpoint {path}: {problem}")]
    Checkpoint {
        /// The checkpoint file.
        path: PathBuf,
        /// What is wrong, and what to do.
        problem: String,
    },
    /// The run was stopped on purpose right after writing a checkpoint
    /// ([`crate::CheckpointOptions::after_write`]); `--resume` continues it.
    #[error(
        "stopped after the checkpoint at step {steps} (t = {t} s) in {path}: continue the run with --resume"
    )]
    Stopped {
        /// Steps done.
        steps: u64,
        /// Time reached (s).
        t: f64,
        /// The checkpoint file.
        path: PathBuf,
    },
    /// A run's output folder (or one of its files) lacks what a plot needs, or holds a file
    /// that cannot be read.
    #[error("{}: {problem}", path.display())]
    PlotInput {
        /// The folder or file.
        path: PathBuf,
        /// What is missing or wrong, and what would provide it.
        problem: String,
    },
    /// Drawing a chart failed.
    #[error("plot: {0}")]
    Plot(demcon_plot::PlotError),
    /// Packing failed (or stopped short without `allow_short`).
    #[error("packing: {0}")]
    Packing(String),
    /// Contact detection or surfaces failed.
    #[error("contacts: {}", scene_terms(.0))]
    Graph(demcon_graph::GraphError),
    /// A linear solve or boundary-condition resolution failed.
    #[error("network: {}", scene_terms(.0))]
    Solve(demcon_network::SolveError),
    /// The thermal solver failed (instability, divergence…).
    #[error("thermal: {}", scene_terms(.0))]
    Thermal(demcon_thermal::ThermalError),
    /// The electric solver failed.
    #[error("electric: {}", scene_terms(.0))]
    Electric(demcon_electric::ElectricError),
    /// Post-processing failed (probe outside, bad Halo ratio…).
    #[error("post-processing: {}", scene_terms(.0))]
    Post(demcon_post::PostError),
}

/// A lower crate's message in the scene's terms: the library names of what a scene sets are
/// replaced by the scene fields that set them. (The lower crate's error is kept as the
/// variant's value, not as a `source`, so the message is printed once.)
fn scene_terms(e: &impl std::fmt::Display) -> String {
    const TERMS: &[(&str, &str)] = &[
        ("(FloatingPolicy::Exclude)", "(`floating: Exclude`)"),
        ("FloatingPolicy::Exclude", "`floating: Exclude`"),
        ("FloatingPolicy::Fail", "`floating: Fail`"),
        ("use TimeStep::Auto", "use `dt: Auto(safety: ..)`"),
        ("TimeStep::Auto", "`dt: Auto(safety: ..)`"),
        (
            "a looser tolerance or Method::Cholesky",
            "a looser `linear_solver.rel_tol` or `method: Cholesky`",
        ),
        ("Method::Cholesky", "`linear_solver: (method: Cholesky)`"),
        (
            "or allow_unstable to insist",
            "or `dt: Fixed(dt: .., allow_unstable: true)` to insist",
        ),
        ("raise max_epsilon, or", "give `contacts.tolerance` instead, or"),
        ("tolerance.target_coordination", "contacts.coordination"),
        ("tolerance.relative", "contacts.tolerance"),
    ];
    let mut text = e.to_string();
    for (from, to) in TERMS {
        if text.contains(from) {
            text = text.replace(from, to);
        }
    }
    text
}

/// Each error on its own line, numbered.
fn numbered(errors: &[SceneError]) -> String {
    errors
        .iter()
        .enumerate()
        .map(|(i, e)| format!("\n  {}. {e}", i + 1))
        .collect()
}

macro_rules! from_lower {
    ($($variant:ident($t:ty)),*) => {$(
        impl From<$t> for SceneError {
            fn from(e: $t) -> Self {
                SceneError::$variant(e)
            }
        }
    )*};
}

from_lower!(
    Graph(demcon_graph::GraphError),
    Solve(demcon_network::SolveError),
    Thermal(demcon_thermal::ThermalError),
    Electric(demcon_electric::ElectricError),
    Post(demcon_post::PostError),
    Plot(demcon_plot::PlotError)
);

impl SceneError {
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

    /// The errors one by one: those of [`SceneError::Several`], or this one.
    pub fn each(&self) -> Vec<&SceneError> {
        match self {
            Self::Several(v) => v.iter().collect(),
            e => vec![e],
        }
    }

    /// `Ok` without errors, the error alone, or [`SceneError::Several`].
    pub fn all(mut errors: Vec<SceneError>) -> Result<(), SceneError> {
        match errors.len() {
            0 => Ok(()),
            1 => Err(errors.remove(0)),
            _ => Err(Self::Several(errors)),
        }
    }
}

/// An invalid parameter keeps its field, value and allowed range (the field is already the
/// scene's path where this conversion is used).
impl From<CoreError> for SceneError {
    fn from(e: CoreError) -> Self {
        match e {
            CoreError::InvalidParameter {
                field,
                value,
                allowed,
            } => Self::Invalid {
                field,
                value,
                allowed,
            },
            other => Self::Core {
                field: String::new(),
                source: other,
            },
        }
    }
}

impl From<demcon_model::ModelError> for SceneError {
    /// The model's errors keep their kind (and so their message): a bad value stays
    /// [`SceneError::Invalid`], a solver failure stays the solver's.
    fn from(e: demcon_model::ModelError) -> Self {
        use demcon_model::ModelError as M;
        match e {
            M::Invalid {
                field,
                value,
                allowed,
            } => SceneError::Invalid {
                field,
                value,
                allowed,
            },
            M::Core { field, source } => SceneError::Core { field, source },
            M::Packing(s) => SceneError::Packing(s),
            M::Graph(e) => SceneError::Graph(e),
            M::Solve(e) => SceneError::Solve(e),
            M::Thermal(e) => SceneError::Thermal(e),
            M::Electric(e) => SceneError::Electric(e),
        }
    }
}
