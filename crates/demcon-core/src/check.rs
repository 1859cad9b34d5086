//! Input checks shared by the library crates: one value per node/edge/particle, finite
//! values, finite values > 0. Each returns a [`CheckError`] that names the input (and the
//! first bad index); each crate's error type converts it into its own variant, so the
//! messages a user reads keep each crate's wording.
//!
//! ```
//! use demcon_core::check::{CheckError, Rule, check_len, check_positive};
//!
//! assert!(check_len("capacities", 3, 3).is_ok());
//! assert_eq!(
//!     check_positive("capacities", &[1.0, 0.0]),
//!     Err(CheckError::Value { what: "capacities".into(), index: 1, value: 0.0, rule: Rule::Positive })
//! );
//! ```

/// What a checked value must be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rule {
    /// A finite number (no NaN, no ±∞).
    Finite,
    /// A finite number > 0.
    Positive,
}

impl Rule {
    /// The rule as the end of a sentence: `a finite number`, `a finite number > 0`.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Finite => "a finite number",
            Self::Positive => "a finite number > 0",
        }
    }
}

/// An input array that failed a check.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CheckError {
    /// The array does not have the expected number of entries.
    #[error("{what} has {got} entries, expected {expected}")]
    Length {
        /// The input's name (e.g. `sources`).
        what: String,
        /// Its length.
        got: usize,
        /// The length it must have (one entry per node, edge or particle).
        expected: usize,
    },
    /// An entry breaks its rule; the first such entry is named.
    #[error("invalid {what}[{index}] = {value}: must be {}", rule.describe())]
    Value {
        /// The input's name (e.g. `capacities`).
        what: String,
        /// Index of the first bad entry.
        index: usize,
        /// Its value (in the input's unit).
        value: f64,
        /// The rule it breaks.
        rule: Rule,
    },
}

/// Checks that an array has `expected` entries (`got` is its length).
///
/// # Errors
/// [`CheckError::Length`] naming `what`.
pub fn check_len(what: &str, got: usize, expected: usize) -> Result<(), CheckError> {
    if got == expected {
        Ok(())
    } else {
        Err(CheckError::Length {
            what: what.to_string(),
            got,
            expected,
        })
    }
}

/// Checks that every value is finite.
///
/// # Errors
/// [`CheckError::Value`] with [`Rule::Finite`], naming the first bad index.
pub fn check_finite(what: &str, values: &[f64]) -> Result<(), CheckError> {
    check_rule(what, values, Rule::Finite, |v| v.is_finite())
}

/// Checks that every value is finite and strictly positive.
///
/// # Errors
/// [`CheckError::Value`] with [`Rule::Positive`], naming the first bad index.
pub fn check_positive(what: &str, values: &[f64]) -> Result<(), CheckError> {
    check_rule(what, values, Rule::Positive, |v| v.is_finite() && v > 0.0)
}

fn check_rule(what: &str, values: &[f64], rule: Rule, ok: impl Fn(f64) -> bool) -> Result<(), CheckError> {
    match values.iter().position(|&v| !ok(v)) {
        None => Ok(()),
        Some(index) => Err(CheckError::Value {
            what: what.to_string(),
            index,
            value: values[index],
            rule,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_bad_entry_is_named() {
        assert_eq!(check_len("x", 2, 2), Ok(()));
        assert_eq!(
            check_len("x", 1, 2).unwrap_err().to_string(),
            "x has 1 entries, expected 2"
        );
        assert_eq!(check_finite("x", &[0.0, -1.0]), Ok(()));
        let e = check_finite("x", &[0.0, f64::NAN, f64::INFINITY]).unwrap_err();
        assert!(matches!(
            e,
            CheckError::Value {
                index: 1,
                rule: Rule::Finite,
                ..
            }
        ));
        assert_eq!(e.to_string(), "invalid x[1] = NaN: must be a finite number");
        let e = check_positive("y", &[1.0, 2.0, 0.0, -1.0]).unwrap_err();
        assert_eq!(e.to_string(), "invalid y[2] = 0: must be a finite number > 0");
        assert!(check_positive("y", &[f64::INFINITY]).is_err());
        assert_eq!(check_positive("y", &[]), Ok(()));
    }
}
