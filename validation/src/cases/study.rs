//! A study: a case's measurement repeated over sizes × packings (seeds), its rows kept with the
//! size and the packing they came from, and the spread over the packings at each size — the
//! loop every multi-packing case used to write by hand.

use super::common::Spread;
use crate::Table;
use crate::table::Columns;

/// One packing's measurement in a [`Study`].
#[derive(Debug, Clone)]
pub struct Measured<R> {
    /// The particle count asked for (the ladder's rung).
    pub n_target: usize,
    /// Index of the packing at this size, from 0.
    pub k: u64,
    /// What the case measured on it.
    pub rows: R,
}

/// Rows of one measurement per (size, packing), in ladder order then packing order.
#[derive(Debug, Clone)]
pub struct Study<R> {
    sizes: Vec<usize>,
    packings: Vec<Measured<R>>,
}

impl<R> Study<R> {
    /// Runs `measure(n, seed, k)` on `packings(n)` packings (seeds `seed`, `seed + 1`, …) at
    /// each size of `sizes`, in the order given.
    ///
    /// # Errors
    /// The first error of `measure`.
    pub fn run(
        sizes: &[usize],
        packings: impl Fn(usize) -> u64,
        seed: u64,
        mut measure: impl FnMut(usize, u64, u64) -> anyhow::Result<R>,
    ) -> anyhow::Result<Self> {
        let mut out = Vec::new();
        for &n in sizes {
            for k in 0..packings(n) {
                out.push(Measured {
                    n_target: n,
                    k,
                    rows: measure(n, seed + k, k)?,
                });
            }
        }
        Ok(Self {
            sizes: sizes.to_vec(),
            packings: out,
        })
    }

    /// The sizes, as given.
    pub fn sizes(&self) -> &[usize] {
        &self.sizes
    }

    /// The largest size.
    pub fn largest(&self) -> usize {
        self.sizes.iter().copied().max().unwrap_or(0)
    }

    /// Every packing, in ladder order then packing order.
    pub fn packings(&self) -> &[Measured<R>] {
        &self.packings
    }

    /// Every packing's rows, in ladder order then packing order.
    pub fn rows(&self) -> impl Iterator<Item = &R> {
        self.packings.iter().map(|p| &p.rows)
    }

    /// The rows of the packings of size `n`.
    pub fn at(&self, n: usize) -> impl Iterator<Item = &R> {
        self.packings
            .iter()
            .filter(move |p| p.n_target == n)
            .map(|p| &p.rows)
    }

    /// Mean and max of `value` over the packings of size `n` (NaN when one is NaN).
    pub fn spread(&self, n: usize, value: impl Fn(&R) -> f64) -> Spread {
        Spread::of(self.at(n).map(value))
    }

    /// The largest `value` over every packing of every size.
    pub fn worst(&self, value: impl Fn(&R) -> f64) -> f64 {
        self.rows().map(value).fold(0.0, f64::max)
    }

    /// Every packing's rows with its index at its size (for a table of packings).
    pub fn indexed(&self) -> Vec<(u64, &R)> {
        self.packings.iter().map(|p| (p.k, &p.rows)).collect()
    }

    /// A table with a line per packing: its particles (`particles`), its index at its size,
    /// then the `columns` a case adds.
    pub fn packings_table<'a>(
        &'a self,
        title: impl Into<String>,
        particles: impl Fn(&R) -> usize + 'a,
        columns: impl FnOnce(Columns<'a, (u64, &'a R)>) -> Columns<'a, (u64, &'a R)>,
    ) -> Table {
        let cols = Columns::new()
            .column("N", move |(_, r): &(u64, &R)| particles(r).to_string())
            .column("packing", |(k, _)| k.to_string());
        columns(cols).table(title, &self.indexed())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_keep_their_size_and_packing_and_spread_per_size() {
        let s = Study::run(&[10, 20], |_| 3, 7, |n, seed, k| Ok((n, seed, k))).unwrap();
        assert_eq!(s.packings().len(), 6);
        assert_eq!(s.largest(), 20);
        let at20: Vec<_> = s.at(20).copied().collect();
        assert_eq!(at20, vec![(20, 7, 0), (20, 8, 1), (20, 9, 2)]);
        let seeds: Vec<u64> = s.rows().map(|r| r.1).collect();
        assert_eq!(seeds, vec![7, 8, 9, 7, 8, 9]);
        let sp = s.spread(10, |r| r.1 as f64);
        assert_eq!((sp.mean, sp.max, sp.count), (8.0, 9.0, 3));
        let nan = s.spread(10, |r| if r.2 == 1 { f64::NAN } else { 0.0 });
        assert!(nan.mean.is_nan() && nan.max.is_nan());
        assert!(
            Study::run(
                &[5],
                |_| 2,
                0,
                |_, _, k| if k == 1 { anyhow::bail!("no") } else { Ok(k) }
            )
            .is_err()
        );
    }
}
