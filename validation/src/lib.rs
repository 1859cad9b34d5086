//! Validation cases of the two papers (Haddad 2021, Hubert 2017): each case builds its scene,
//! runs it and returns named comparisons against analytic, FEM or FFT references.
//!
//! `cargo xtask validate [CASE…] [--quick | --full] [--out DIR]` runs them and writes one
//! `<case>.json` per case plus `REPORT.md` and PNG charts (DESIGN.md §3).
//!
//! ```
//! // The analytic references are usable on their own:
//! let t = validation::analytic::sphere_centre_temperature(10.0, 0.05, 20.0, 200.0, 185.0 / (2700.0 * 900.0));
//! assert!((t - 182.178).abs() < 1e-3);
//! ```
#![warn(missing_docs)]

pub mod analytic;
pub mod cases;
pub mod outcome;
pub mod refs;
pub mod report;
pub mod table;

use std::path::PathBuf;

pub use outcome::{CaseOutcome, Comparison, Mode, Table};

/// What every case receives.
#[derive(Debug, Clone)]
pub struct Ctx {
    /// Quick (CI) or full (paper scale).
    pub mode: Mode,
    /// Output folder (JSON, charts, VTK).
    pub out: PathBuf,
    /// Base seed; realisation `k` of a case uses `seed + k`.
    pub seed: u64,
}

impl Ctx {
    /// `quick` or `full` value.
    pub fn pick<T>(&self, quick: T, full: T) -> T {
        match self.mode {
            Mode::Quick => quick,
            Mode::Full => full,
        }
    }
}

/// A registered validation case.
#[derive(Clone, Copy)]
pub struct Case {
    /// Stable id (e.g. `slab-transient`).
    pub id: &'static str,
    /// One line: the paper section and what is compared.
    pub about: &'static str,
    /// Runs the case.
    pub run: fn(&Ctx) -> anyhow::Result<CaseOutcome>,
}
