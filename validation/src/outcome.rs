//! What a validation case returns: named metrics, the references they are compared with,
//! the tolerance and why, and the cost of the run.

use serde::Serialize;
use serde_json::{Map, Value};

/// `--quick` (CI, a few minutes on 2 cores) or `--full` (the papers' particle counts).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Small sizes, runs in CI.
    Quick,
    /// Paper-scale sizes, run by hand.
    Full,
}

impl Mode {
    /// `"quick"` or `"full"`.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Quick => "quick",
            Mode::Full => "full",
        }
    }
}

/// One measured quantity set against a reference with a tolerance.
#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    /// What is compared (e.g. `T_centre(10 s)`).
    pub name: String,
    /// Our value.
    pub measured: f64,
    /// The reference value.
    pub reference: f64,
    /// Largest accepted |measured − reference| (absolute, in the quantity's unit) — or, when
    /// `relative` is true, largest accepted relative difference (fraction).
    pub tolerance: f64,
    /// Whether `tolerance` is relative.
    pub relative: bool,
    /// Where the reference comes from.
    pub source: String,
    /// Whether the comparison passed.
    pub pass: bool,
}

impl Comparison {
    /// A relative comparison: passes when |m − r| ≤ tol·|r|.
    pub fn relative(name: &str, measured: f64, reference: f64, tol: f64, source: &str) -> Self {
        let pass = measured.is_finite() && (measured - reference).abs() <= tol * reference.abs();
        Self {
            name: name.into(),
            measured,
            reference,
            tolerance: tol,
            relative: true,
            source: source.into(),
            pass,
        }
    }

    /// An absolute comparison: passes when |m − r| ≤ tol.
    pub fn absolute(name: &str, measured: f64, reference: f64, tol: f64, source: &str) -> Self {
        let pass = measured.is_finite() && (measured - reference).abs() <= tol;
        Self {
            name: name.into(),
            measured,
            reference,
            tolerance: tol,
            relative: false,
            source: source.into(),
            pass,
        }
    }

    /// An upper bound: passes when m ≤ bound (e.g. an error metric against the paper's error).
    pub fn at_most(name: &str, measured: f64, bound: f64, source: &str) -> Self {
        let pass = measured.is_finite() && measured <= bound;
        Self {
            name: name.into(),
            measured,
            reference: bound,
            tolerance: 0.0,
            relative: false,
            source: source.into(),
            pass,
        }
    }
}

/// The result of one validation case, written as `<case>.json` (DESIGN.md §3).
#[derive(Debug, Clone, Serialize)]
pub struct CaseOutcome {
    /// Case id (stable; other tools read it).
    pub case: String,
    /// `quick` or `full`.
    pub mode: Mode,
    /// Largest particle count used.
    pub n_particles: usize,
    /// Wall time of the whole case (s).
    pub wall_s: f64,
    /// Named metrics (stable names; fractions, not percent).
    pub metrics: Map<String, Value>,
    /// The paper's (or FEM/FFT/analytic) values for the same metrics, with `source`.
    pub reference: Map<String, Value>,
    /// The comparisons that decide `pass`.
    pub comparisons: Vec<Comparison>,
    /// Whether every comparison passed.
    pub pass: bool,
    /// Free-text remarks for the report (what was measured how, what is doubtful).
    pub notes: Vec<String>,
    /// Charts written next to the JSON (file names).
    pub charts: Vec<String>,
    /// Extra tables for the report: (title, header, rows).
    #[serde(skip)]
    pub tables: Vec<Table>,
}

/// A small table for REPORT.md.
#[derive(Debug, Clone, Default)]
pub struct Table {
    /// Title line.
    pub title: String,
    /// Column names.
    pub header: Vec<String>,
    /// Rows of formatted cells.
    pub rows: Vec<Vec<String>>,
}

impl CaseOutcome {
    /// An empty outcome for `case` in `mode`.
    pub fn new(case: &str, mode: Mode) -> Self {
        Self {
            case: case.into(),
            mode,
            n_particles: 0,
            wall_s: 0.0,
            metrics: Map::new(),
            reference: Map::new(),
            comparisons: Vec::new(),
            pass: true,
            notes: Vec::new(),
            charts: Vec::new(),
            tables: Vec::new(),
        }
    }

    /// Records a metric.
    pub fn metric(&mut self, name: &str, value: impl Into<Value>) {
        self.metrics.insert(name.into(), value.into());
    }

    /// Records a reference value.
    pub fn reference(&mut self, name: &str, value: impl Into<Value>) {
        self.reference.insert(name.into(), value.into());
    }

    /// Adds a comparison; a failing one fails the case.
    pub fn compare(&mut self, c: Comparison) {
        self.pass &= c.pass;
        self.comparisons.push(c);
    }

    /// Adds a note for the report.
    pub fn note(&mut self, text: impl Into<String>) {
        self.notes.push(text.into());
    }
}

/// Formats a float for tables: 4 significant digits, or scientific when tiny/huge.
pub fn fmt_sig(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{v:.3e}")
    } else {
        let digits = if a == 0.0 {
            0
        } else {
            (3 - a.log10().floor() as i32).max(0)
        } as usize;
        format!("{v:.digits$}")
    }
}
