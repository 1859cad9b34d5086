//! The error type of demcon-post: bad input (naming the field, the value and what is allowed),
//! probes outside the domain, undefined statistics and file-system failures.

use std::path::PathBuf;

use demcon_core::CoreError;
use demcon_core::check::{CheckError, Rule, check_positive};

/// What can go wrong in post-processing.
#[derive(Debug, thiserror::Error)]
pub enum PostError {
    /// An input value or array cannot be used (wrong length, out-of-range index, non-finite
    /// number, non-positive volume, negative Halo ratio…).
    #[error(transparent)]
    Input(#[from] CoreError),
    /// A probe point lies outside the domain.
    #[error(
        "probe point ({:.6e}, {:.6e}, {:.6e}) m lies outside the domain ({distance:.3e} m beyond its boundary)",
        point[0], point[1], point[2]
    )]
    ProbeOutside {
        /// The point (m).
        point: [f64; 3],
        /// Its distance outside the domain boundary (m, > 0).
        distance: f64,
    },
    /// A ball-average probe found no particle centre inside its ball.
    #[error(
        "no particle centre within {radius:.3e} m of probe point ({:.6e}, {:.6e}, {:.6e}) m: use a larger ball or the nearest-particle probe",
        point[0], point[1], point[2]
    )]
    EmptyProbe {
        /// The point (m).
        point: [f64; 3],
        /// Ball radius (m).
        radius: f64,
    },
    /// A statistic is undefined for these values (e.g. the coefficient of variation of a
    /// zero-mean field).
    #[error("{what} is undefined: {why}")]
    Undefined {
        /// The statistic.
        what: &'static str,
        /// Why, with the value that makes it undefined.
        why: String,
    },
    /// Writing or reading a file failed.
    #[error("{action} {}: {source}", path.display())]
    Io {
        /// `writing` or `reading`.
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// A file read back is not in the expected format.
    #[error("{}: line {line}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// Line number (1-based).
        line: usize,
        /// What is wrong.
        message: String,
    },
}

impl PostError {
    /// Shorthand for an [`PostError::Input`] error made with [`CoreError::invalid`].
    pub fn invalid(field: impl Into<String>, value: impl ToString, allowed: impl Into<String>) -> Self {
        Self::Input(CoreError::invalid(field, value, allowed))
    }
}

/// A failed shared input check ([`demcon_core::check`]) as an input error naming the
/// array (wrong length) or its first bad entry.
impl From<CheckError> for PostError {
    fn from(e: CheckError) -> Self {
        match e {
            CheckError::Length { what, got, expected } => Self::invalid(
                what,
                format!("{got} entries"),
                format!("exactly {expected} entries"),
            ),
            CheckError::Value {
                what,
                index,
                value,
                rule,
            } => Self::invalid(
                format!("{what}[{index}]"),
                value,
                match rule {
                    Rule::Finite => "must be finite",
                    Rule::Positive => "must be a finite number > 0",
                },
            ),
        }
    }
}

/// Checks that every vector is finite; the error names the first bad entry.
pub(crate) fn check_finite_vec(field: &str, values: &[demcon_core::Vec3]) -> Result<(), PostError> {
    match values.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
        None => Ok(()),
        Some(i) => Err(PostError::invalid(
            format!("{field}[{i}]"),
            format!("{:?}", values[i].as_slice()),
            "must be finite",
        )),
    }
}

/// Checks that a point is finite.
pub(crate) fn check_point(field: &str, p: &demcon_core::Vec3) -> Result<(), PostError> {
    if p.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(PostError::invalid(
            field,
            format!("{:?}", p.as_slice()),
            "must be finite (m)",
        ))
    }
}

/// Checks a particle set whose fields may have been filled by hand: arrays of equal length,
/// finite centres, finite radii > 0.
pub(crate) fn check_particles(p: &demcon_core::ParticleSet) -> Result<(), PostError> {
    let n = p.radii.len();
    if p.centres.len() != n || p.phases.len() != n {
        return Err(PostError::invalid(
            "particles",
            format!(
                "{} centres, {} radii, {} phases",
                p.centres.len(),
                n,
                p.phases.len()
            ),
            "arrays of equal length",
        ));
    }
    check_finite_vec("particles.centres", &p.centres)?;
    Ok(check_positive("particles.radii", &p.radii)?)
}
