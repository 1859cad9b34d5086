//! Values that follow time: a constant, or a table of (t, value) points interpolated linearly
//! between them, with a jump where two points share a time.

use crate::CoreError;

/// A value constant in time or given by a table ([`TimeValue::table`]).
#[derive(Debug, Clone, PartialEq)]
pub enum TimeValue {
    /// The same value at every time.
    Constant(f64),
    /// Points (t (s), value), times non-decreasing; linear between points, a jump where two
    /// consecutive points share a time (the later one holds from that time on); before the
    /// first point its value, after the last its value.
    Table(Vec<(f64, f64)>),
}

impl From<f64> for TimeValue {
    fn from(v: f64) -> Self {
        TimeValue::Constant(v)
    }
}

impl TimeValue {
    /// A table, checked: at least one point, every time and value finite, times
    /// non-decreasing, at most two points at one time (a jump). `field` names it in errors.
    pub fn table(points: Vec<(f64, f64)>, field: &str) -> Result<Self, CoreError> {
        if points.is_empty() {
            return Err(CoreError::invalid(
                field,
                "[]",
                "a table of at least one (t, value) point",
            ));
        }
        for (i, &(t, v)) in points.iter().enumerate() {
            if !(t.is_finite() && v.is_finite()) {
                return Err(CoreError::invalid(
                    format!("{field}[{i}]"),
                    format!("({}, {})", n(t), n(v)),
                    "a finite time (s) and a finite value",
                ));
            }
            if i > 0 && t < points[i - 1].0 {
                return Err(CoreError::invalid(
                    format!("{field}[{i}]"),
                    format!("t = {}", n(t)),
                    format!(
                        "times in increasing order (the point before is at t = {})",
                        n(points[i - 1].0)
                    ),
                ));
            }
            if i > 1 && t == points[i - 2].0 {
                return Err(CoreError::invalid(
                    format!("{field}[{i}]"),
                    format!("t = {}", n(t)),
                    "at most two points at one time (a jump from the first value to the second)",
                ));
            }
        }
        Ok(TimeValue::Table(points))
    }

    /// The value at time `t` (s).
    pub fn at(&self, t: f64) -> f64 {
        let points = match self {
            TimeValue::Constant(v) => return *v,
            TimeValue::Table(p) => p,
        };
        // The first point later than t: t lies in [points[k − 1], points[k]).
        let k = points.partition_point(|&(ti, _)| ti <= t);
        if k == 0 {
            return points[0].1;
        }
        if k == points.len() {
            return points[k - 1].1;
        }
        let ((t0, v0), (t1, v1)) = (points[k - 1], points[k]);
        v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    }

    /// Whether the value never changes.
    pub fn is_constant(&self) -> bool {
        match self {
            TimeValue::Constant(_) => true,
            TimeValue::Table(p) => p.iter().all(|&(_, v)| v == p[0].1),
        }
    }

    /// The times where the table changes slope or jumps (s); none for a constant.
    pub fn breakpoints(&self) -> Vec<f64> {
        match self {
            TimeValue::Constant(_) => Vec::new(),
            TimeValue::Table(p) => {
                let mut t: Vec<f64> = p.iter().map(|&(t, _)| t).collect();
                t.dedup();
                t
            }
        }
    }

    /// Refuses a table that does not cover `[0, t_end]` (s): its first time after 0 or its
    /// last before `t_end`. `field` names it.
    pub fn check_covers(&self, t_end: f64, field: &str) -> Result<(), CoreError> {
        let TimeValue::Table(p) = self else {
            return Ok(());
        };
        let (first, last) = (p[0].0, p[p.len() - 1].0);
        if first > 0.0 || last < t_end {
            return Err(CoreError::invalid(
                field,
                format!("a table over [{}, {}] s", n(first), n(last)),
                format!("a table covering the run, [0, t_end] = [0, {}] s", n(t_end)),
            ));
        }
        Ok(())
    }

    /// The smallest and largest value the table takes.
    pub fn range(&self) -> (f64, f64) {
        match self {
            TimeValue::Constant(v) => (*v, *v),
            TimeValue::Table(p) => p
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &(_, v)| {
                    (a.min(v), b.max(v))
                }),
        }
    }
}

/// A number as messages show it ([`crate::error::short_number`]: no 300-digit decimals).
fn n(x: f64) -> String {
    crate::error::short_number(x.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_interpolates_jumps_and_holds_its_ends() {
        let v = TimeValue::table(vec![(0.0, 20.0), (0.0, 100.0), (10.0, 100.0), (20.0, 200.0)], "v").unwrap();
        assert_eq!(v.at(-1.0), 20.0);
        assert_eq!(v.at(0.0), 100.0);
        assert_eq!(v.at(5.0), 100.0);
        assert_eq!(v.at(15.0), 150.0);
        assert_eq!(v.at(30.0), 200.0);
        assert_eq!(v.breakpoints(), [0.0, 10.0, 20.0]);
        assert!(!v.is_constant());
        assert_eq!(v.range(), (20.0, 200.0));
        assert!(v.check_covers(20.0, "v").is_ok());
        assert!(
            v.check_covers(21.0, "v")
                .unwrap_err()
                .to_string()
                .contains("[0, 21]")
        );
    }

    #[test]
    fn bad_tables_are_refused_by_point() {
        let e = |p: Vec<(f64, f64)>| TimeValue::table(p, "bcs[0].value").unwrap_err().to_string();
        assert!(e(vec![]).contains("at least one"));
        assert!(e(vec![(0.0, 1.0), (2.0, 1.0), (1.0, 1.0)]).contains("bcs[0].value[2]"));
        assert!(e(vec![(0.0, 1.0), (1.0, 1.0), (1.0, 2.0), (1.0, 3.0)]).contains("at most two"));
        assert!(e(vec![(0.0, f64::NAN)]).contains("finite"));
    }
}
