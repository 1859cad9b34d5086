//! Ticks of a linear axis: where they go ([`nice_ticks`]: multiples of 1, 2 or 5 × 10ᵏ) and
//! how they read ([`tick_labels`]: as many digits as it takes for consecutive labels to
//! differ, or an offset from the first label when that would need more than
//! [`MAX_DIGITS`] significant digits). A colour bar over 1.4 mK at 263 °C reads
//! `262.9392`, `262.9394`, …, not `262.9` eight times.

use std::ops::Range;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;

/// The most significant digits a label is written with before the labels switch to offsets
/// from the first one (`262.939177`, `+2e-8`, `+4e-8`, …).
pub const MAX_DIGITS: usize = 8;

/// Ticks inside `[lo, hi]` at a step of 1, 2 or 5 × 10ᵏ, at most `max_ticks` (≥ 2) of them and
/// as many as fit; empty when the range is not finite or `lo > hi`, one tick when `lo == hi`.
pub fn nice_ticks(lo: f64, hi: f64, max_ticks: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return Vec::new();
    }
    let span = hi - lo;
    if span <= f64::EPSILON * lo.abs().max(hi.abs()) || span == 0.0 {
        return vec![lo];
    }
    let max_ticks = max_ticks.max(2);
    // The smallest 1-2-5 step that gives at most `max_ticks` ticks.
    let mut exp = (span / max_ticks as f64).log10().floor() as i32 - 1;
    loop {
        for m in [1.0, 2.0, 5.0] {
            let step = m * 10f64.powi(exp);
            let first = (lo / step).ceil();
            let last = (hi / step).floor();
            if last - first + 1.0 <= max_ticks as f64 {
                return (0..=((last - first).max(0.0) as usize))
                    // k · step rather than a running sum: no drift.
                    .map(|k| (first + k as f64) * step)
                    .filter(|t| *t >= lo - 1e-9 * span && *t <= hi + 1e-9 * span)
                    .map(|t| t.clamp(lo, hi))
                    .collect();
            }
        }
        exp += 1;
    }
}

/// Labels of `ticks` (increasing): the same number of decimals for all, as many as it takes
/// for consecutive labels to differ; past [`MAX_DIGITS`] significant digits the first label
/// is the value and the others its offset (`+2e-8`). Values of magnitude ≥ 10⁵ or < 10⁻³ are
/// written with an exponent (`1.25e6`).
pub fn tick_labels(ticks: &[f64]) -> Vec<String> {
    if ticks.len() < 2 {
        return ticks.iter().map(|&t| crate::fmt_tick(t)).collect();
    }
    let step = ticks
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    let big = ticks.iter().fold(0.0f64, |a, t| a.max(t.abs()));
    if !(step.is_finite() && big.is_finite()) {
        return ticks.iter().map(|&t| crate::fmt_tick(t)).collect();
    }
    // Written as mantissa × 10^e when the values are very large or very small.
    let e = if big != 0.0 && !(1e-3..1e5).contains(&big) {
        big.log10().floor() as i32
    } else {
        0
    };
    let scale = 10f64.powi(e);
    let decimals = decimals_for(ticks, scale, step);
    let int_digits = ((big / scale).log10().floor() as i64 + 1).max(1) as usize;
    if int_digits + decimals > MAX_DIGITS {
        return offset_labels(ticks, step);
    }
    let label = |t: f64| {
        let s = format!("{:.decimals$}", t / scale);
        let s = if s.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') {
            s.trim_start_matches('-').to_string()
        } else {
            s
        };
        if e == 0 { s } else { format!("{s}e{e}") }
    };
    ticks.iter().map(|&t| label(t)).collect()
}

/// The fewest decimals (of the values divided by `scale`) that tell ticks `step` apart and
/// read each back within a thousandth of the step.
fn decimals_for(ticks: &[f64], scale: f64, step: f64) -> usize {
    let first = (-(step / scale).log10() - 1e-9).ceil().max(0.0) as usize;
    (first..=17)
        .find(|&d| {
            let labels: Vec<String> = ticks.iter().map(|t| format!("{:.d$}", t / scale)).collect();
            labels.windows(2).all(|w| w[0] != w[1])
                && ticks.iter().zip(&labels).all(|(t, l)| {
                    l.parse::<f64>()
                        .is_ok_and(|v| (v * scale - t).abs() <= 1e-3 * step)
                })
        })
        .unwrap_or(17)
}

/// The first tick in full, the others as `+offset` from it (the offsets rounded to the step).
fn offset_labels(ticks: &[f64], step: f64) -> Vec<String> {
    let base = ticks[0];
    // The base with the decimals it needs at this step, however many digits that takes.
    let d = (-step.log10() - 1e-9).ceil().max(0.0) as usize;
    let mut out = vec![if d <= 17 {
        trim(&format!("{base:.d$}"))
    } else {
        format!("{base:e}")
    }];
    out.extend(ticks[1..].iter().map(|&t| {
        let k = ((t - base) / step).round();
        format!("+{}", crate::fmt_tick(k * step))
    }));
    out
}

fn trim(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

/// A linear f64 axis whose ticks are given: `bold` labelled, `light` for the light mesh lines.
/// (plotters' own `with_key_points` loses the f64 axis's label formatter.)
pub(crate) struct Ticked {
    inner: RangedCoordf64,
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Ticked {
    /// The axis over `range` with ticks `bold` and light lines `light`.
    pub(crate) fn new(range: Range<f64>, bold: Vec<f64>, light: Vec<f64>) -> Self {
        Self {
            inner: range.into(),
            bold,
            light,
        }
    }
}

impl Ranged for Ticked {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.inner.range()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn distinct(l: &[String]) -> bool {
        l.windows(2).all(|w| w[0] != w[1])
    }

    #[test]
    fn ticks_are_round_steps_inside_the_range() {
        assert_eq!(nice_ticks(0.0, 10.0, 6), [0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!(
            nice_ticks(20.3, 29.7, 10),
            [21.0, 22.0, 23.0, 24.0, 25.0, 26.0, 27.0, 28.0, 29.0]
        );
        assert_eq!(nice_ticks(-1.0, 1.0, 5), [-1.0, -0.5, 0.0, 0.5, 1.0]);
        assert_eq!(nice_ticks(3.0, 3.0, 5), [3.0]);
        assert!(nice_ticks(f64::NAN, 1.0, 5).is_empty());
        for (lo, hi) in [(262.93917794868514, 262.94059723416916), (1e-9, 3e-9), (0.0, 1e6)] {
            let t = nice_ticks(lo, hi, 8);
            assert!((3..=8).contains(&t.len()), "{lo} {hi}: {t:?}");
            assert!(t.iter().all(|&x| x >= lo && x <= hi), "{t:?}");
        }
    }

    #[test]
    fn labels_of_ordinary_ranges_are_short() {
        assert_eq!(
            tick_labels(&nice_ticks(20.0, 30.0, 6)),
            ["20", "22", "24", "26", "28", "30"]
        );
        assert_eq!(
            tick_labels(&nice_ticks(-1.0, 1.0, 5)),
            ["-1.0", "-0.5", "0.0", "0.5", "1.0"]
        );
        assert_eq!(tick_labels(&[0.0, 0.25, 0.5]), ["0.00", "0.25", "0.50"]);
        assert_eq!(tick_labels(&[0.0, 5e5, 1e6]), ["0.0e6", "0.5e6", "1.0e6"]);
        assert_eq!(tick_labels(&[1e-9, 2e-9, 3e-9]), ["1e-9", "2e-9", "3e-9"]);
        assert_eq!(tick_labels(&[35.0]), ["35"]);
    }

    /// The joule-transient colour bar: 1.4 mK at 262.9 °C read "262.9" eight times.
    #[test]
    fn a_tiny_range_gets_the_digits_it_needs() {
        let ticks = nice_ticks(262.93917794868514, 262.94059723416916, 8);
        let l = tick_labels(&ticks);
        assert!(distinct(&l), "{l:?}");
        assert_eq!(l[0], "262.9392");
        assert!(l.iter().all(|s| s.len() == 8), "{l:?}");
        // Each label reads back as its tick.
        for (t, s) in ticks.iter().zip(&l) {
            assert!((s.parse::<f64>().unwrap() - t).abs() < 1e-9, "{s} {t}");
        }
    }

    /// Past eight significant digits: the first value in full, then offsets.
    #[test]
    fn a_range_below_eight_digits_reads_as_offsets() {
        let ticks = nice_ticks(262.939177, 262.9391771, 6);
        let l = tick_labels(&ticks);
        assert!(distinct(&l), "{l:?}");
        assert!(l[0].starts_with("262.93917"), "{l:?}");
        assert!(l[1..].iter().all(|s| s.starts_with('+')), "{l:?}");
        assert_eq!(l[1], "+2e-8", "{l:?}");
        // 10⁷ and half units: offsets too.
        let l = tick_labels(&[1e7, 1e7 + 0.5, 1e7 + 1.0]);
        assert_eq!(l, ["10000000", "+0.5", "+1"]);
    }
}
