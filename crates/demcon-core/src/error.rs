//! Bad-input errors shared by all crates: they name the field, the value and what is allowed.

/// An input value that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CoreError {
    /// A parameter is outside its allowed range.
    #[error("invalid {field} = {value}: {allowed}")]
    InvalidParameter {
        /// The parameter's name, as the user wrote it (e.g. `radius`, `materials[1].conductivity`).
        field: String,
        /// The offending value, formatted.
        value: String,
        /// What would have been accepted.
        allowed: String,
    },
    /// A selector chose no particle, so the boundary condition it carries would do nothing.
    #[error("{what} selects no particle")]
    EmptySelection {
        /// Which selection (e.g. `fixed temperature on face YMin`).
        what: String,
    },
}

impl CoreError {
    /// Shorthand for [`CoreError::InvalidParameter`].
    pub fn invalid(field: impl Into<String>, value: impl ToString, allowed: impl Into<String>) -> Self {
        Self::InvalidParameter {
            field: field.into(),
            value: short_number(value.to_string()),
            allowed: allowed.into(),
        }
    }
}

/// A value as messages show it: a decimal number longer than 16 characters in `{:e}` form
/// (`1e-300`, not 0.000…0001); integers (shown exactly) and anything else unchanged.
pub fn short_number(text: String) -> String {
    let integer = text.trim_start_matches('-').bytes().all(|b| b.is_ascii_digit());
    match text.parse::<f64>() {
        Ok(x) if text.len() > 16 && !integer => format!("{x:e}"),
        _ => text,
    }
}

/// Checks that a number is finite and strictly positive.
pub(crate) fn positive(field: &str, value: f64) -> Result<f64, CoreError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(CoreError::invalid(field, value, "must be a finite number > 0"))
    }
}
