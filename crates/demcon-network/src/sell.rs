//! Sliced-ELLPACK storage (SELL-4-256) of the multigrid hierarchy's matrices, for the sweeps
//! that read every entry of a level once per cycle: the residual, the damped-Jacobi sweep,
//! CG's own product on the finest level, the restriction and the prolongation.
//!
//! Rows of a packing's operator hold ~8 entries, those of the prolongator ~7. In compressed
//! rows, each row's loop (bounds, remainder, four partial sums combined at the end) cost
//! more than its loads: the three fine sweeps ran at ~9 GB/s, a third of the machine's triad
//! (issue 12, perf at 10⁶). Here rows are taken four at a time (a *slice*), sorted by length
//! within windows of 256 rows so a slice's rows have nearly the same length; their entries
//! are interleaved and padded to the slice's longest row with zero values pointing at the
//! row's first column (already read). One fixed-length loop per slice sums the four rows
//! side by side (four independent chains of additions, no per-row exit), as the explicit
//! step does (`demcon-thermal`'s `ExplicitStepper`).
//!
//! Results do not depend on the thread count: each row is summed in its column order, rows
//! stay inside their [`CHUNK`] (a window divides a chunk), and per-chunk partial sums are
//! combined in chunk order.

use rayon::prelude::*;

use crate::csr::{Csr, Value};
use crate::par::{CHUNK, MIN_TASK_CHUNKS, chunks_map};

/// Rows summed side by side (one slice) in the sliced layouts ([`Sell`], and the explicit
/// heat step's in `demcon-thermal`).
pub const SELL_LANES: usize = 4;
/// Rows are sorted by length within windows of this many rows (divides [`CHUNK`], so a
/// chunk's rows stay in the chunk).
pub const SELL_WINDOW: usize = 256;
const LANES: usize = SELL_LANES;
const WINDOW: usize = SELL_WINDOW;
const _: () = assert!(CHUNK.is_multiple_of(WINDOW) && WINDOW.is_multiple_of(LANES));

/// How far ahead (stored entries, about 30 rows) a sliced sweep over a large vector
/// prefetches the x_j it will gather: at 10⁶ unknowns x (8 MB) is out of cache, and the
/// gathers of the columns far away in the index space wait on memory. The 10⁶ electric
/// solve, 36 solves each (`docs/performance.md` §8, "Levers tried"): solve median 0.75 s
/// at 64 or 128 entries ahead, 0.68–0.70 s at 256 or 512, 0.82 s without. The explicit heat
/// step does the same (`demcon-thermal`).
pub(crate) const PREFETCH_AHEAD: usize = 256;

/// Fewest columns (x's length) from which a sweep prefetches its gathers (1 MB of x); below,
/// x stays in cache and the hints only cost instructions (from 16 384 columns, so on level
/// 1 too: no faster).
pub(crate) const PREFETCH_MIN_COLS: usize = 1 << 17;

/// Starts loading `x[idx[at..at + SELL_LANES]]` where those indices exist (a hint only): the
/// prefetch of the sliced sweeps here and of the explicit heat step (`demcon-thermal`).
#[inline(always)]
pub fn prefetch_gathers<T>(idx: &[u32], at: usize, x: &[T]) {
    if let Some(ahead) = idx.get(at..at + LANES) {
        for &q in ahead {
            if let Some(v) = x.get(q as usize) {
                demcon_core::mem::prefetch(v);
            }
        }
    }
}

/// The sliced layout of `n` rows of `len(p)` entries: the row at each sorted position
/// (longest first within windows of [`SELL_WINDOW`] rows, ties by index) and the start of
/// each slice's entries ([`SELL_LANES`] rows per slice, padded to the slice's longest row;
/// one more start than slices, the last being the total).
pub fn sliced_layout(n: usize, len: impl Fn(usize) -> usize + Sync) -> (Vec<u32>, Vec<usize>) {
    let mut perm: Vec<u32> = (0..n as u32).collect();
    perm.par_chunks_mut(WINDOW)
        .for_each(|w| w.sort_by_key(|&p| (std::cmp::Reverse(len(p as usize)), p)));
    let n_slices = n.div_ceil(LANES);
    let mut slice_ptr = Vec::with_capacity(n_slices + 1);
    slice_ptr.push(0usize);
    for s in 0..n_slices {
        let width = perm[s * LANES..((s + 1) * LANES).min(n)]
            .iter()
            .map(|&p| len(p as usize))
            .max()
            .unwrap_or(0);
        slice_ptr.push(slice_ptr[s] + LANES * width);
    }
    (perm, slice_ptr)
}

/// The sorted position of each row of a sliced layout's `perm` (its inverse; a row's position
/// stays in its window).
fn positions(perm: &[u32]) -> Vec<u32> {
    let mut pos = vec![0u32; perm.len()];
    pos.par_chunks_mut(WINDOW).enumerate().for_each(|(w, pw)| {
        let base = w * WINDOW;
        for (k, &p) in perm[base..base + pw.len()].iter().enumerate() {
            pw[p as usize - base] = (base + k) as u32;
        }
    });
    pos
}

/// Per-row terms summed alongside a product ([`Sell::map_rows_with`]): one number, or several
/// summed componentwise, so that dot products share one pass over the matrix.
pub(crate) trait Sums: Copy + Default + Send {
    /// self += other.
    fn add(&mut self, other: Self);
}

impl Sums for f64 {
    #[inline(always)]
    fn add(&mut self, other: Self) {
        *self += other;
    }
}

impl<const K: usize> Sums for [f64; K]
where
    [f64; K]: Default,
{
    #[inline(always)]
    fn add(&mut self, other: Self) {
        for (a, b) in self.iter_mut().zip(other) {
            *a += b;
        }
    }
}

/// A sparse matrix in SELL-4-256 form, values in f32: slice s holds sorted positions
/// 4s..4s+4, whose rows are `perm[4s..4s+4]`; entry j of lane l sits at
/// `slice_ptr[s] + 4j + l`.
#[derive(Debug, Clone)]
pub(crate) struct Sell {
    nrows: usize,
    ncols: usize,
    /// Stored entries of the matrix itself (without padding).
    nnz: usize,
    /// Row at each sorted position.
    perm: Vec<u32>,
    /// Start of each slice's entries; one more than the slices (usize: padding may take the
    /// count past the compressed rows' u32 bound, and it costs 2 bytes per row).
    slice_ptr: Vec<usize>,
    cols: Vec<u32>,
    /// The values rounded to f32 (f64 values laid out alike are kept by the caller:
    /// [`Sell::from_csr_with_f64`]).
    vals: Vec<f32>,
}

impl Sell {
    /// Rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Entries of the matrix (padding not counted).
    pub fn nnz(&self) -> usize {
        self.nnz
    }

    /// `out[i] = f(i, out[i], Σ_j a_ij x_j)` for every row i with this layout's values
    /// `vals` (`self.vals`, or other values laid out alike: [`Sell::from_csr_with_f64`]);
    /// returns, per [`CHUNK`] of rows in chunk order, the sum of `g(i, out[i])` (new value)
    /// over the chunk's rows in their sorted order (a number, or several: [`Sums`]).
    /// Where `x` is larger than the caches ([`PREFETCH_MIN_COLS`] columns or more), the
    /// sweep prefetches the x_j it will gather [`PREFETCH_AHEAD`] entries ahead.
    #[inline(always)]
    pub fn map_rows_with<V: Value, S: Sums>(
        &self,
        vals: &[V],
        x: &[f64],
        out: &mut [f64],
        f: impl Fn(usize, f64, f64) -> f64 + Sync + Send,
        g: impl Fn(usize, f64) -> S + Sync + Send,
    ) -> Vec<S> {
        if self.ncols >= PREFETCH_MIN_COLS {
            self.sweep::<true, V, S>(vals, x, out, f, g)
        } else {
            self.sweep::<false, V, S>(vals, x, out, f, g)
        }
    }

    /// [`Self::map_rows_with`], prefetching or not.
    #[inline(always)]
    fn sweep<const PREFETCH: bool, V: Value, S: Sums>(
        &self,
        vals: &[V],
        x: &[f64],
        out: &mut [f64],
        f: impl Fn(usize, f64, f64) -> f64 + Sync + Send,
        g: impl Fn(usize, f64) -> S + Sync + Send,
    ) -> Vec<S> {
        debug_assert!(vals.len() == self.cols.len() && out.len() == self.nrows && x.len() == self.ncols);
        chunks_map(out, |c, oc| {
            let base = c * CHUNK;
            let end = base + oc.len();
            let mut partial = S::default();
            for s in base / LANES..end.div_ceil(LANES) {
                let (lo, hi) = (self.slice_ptr[s], self.slice_ptr[s + 1]);
                let mut acc = [0.0f64; LANES];
                for (k, (cj, vj)) in self.cols[lo..hi]
                    .chunks_exact(LANES)
                    .zip(vals[lo..hi].chunks_exact(LANES))
                    .enumerate()
                {
                    if PREFETCH {
                        prefetch_gathers(&self.cols, lo + LANES * k + PREFETCH_AHEAD, x);
                    }
                    for ((a, &v), &q) in acc.iter_mut().zip(vj).zip(cj) {
                        *a += v.into() * x[q as usize];
                    }
                }
                let i0 = s * LANES;
                for (l, &a) in acc.iter().enumerate().take(LANES.min(end - i0)) {
                    let i = self.perm[i0 + l] as usize;
                    let o = &mut oc[i - base];
                    *o = f(i, *o, a);
                    partial.add(g(i, *o));
                }
            }
            partial
        })
    }

    /// A P for the P with P[j, group[j]] = 1 (no entry where `group[j]` is [`NO_GROUP`]),
    /// `ngroups` columns, from this layout's values `vals` (f32 or f64, laid out alike): each
    /// row's entries summed by their column's group, in f64 and in the row's order; a row's
    /// groups in the order first met. Returned in this form with the sums rounded to f32
    /// (rows sorted by their own length within the same windows as this layout's), and in
    /// compressed rows with the f64 sums (columns in the order first met, not sorted): the
    /// Galerkin sum Pᵀ (A P) reads those rows one by one. Two passes over the entries in
    /// storage order, a chunk of rows per task: one counts each row's groups, one sums them.
    /// The same matrices for any thread count.
    pub fn group_columns<V: Value>(&self, vals: &[V], group: &[u32], ngroups: usize) -> (Sell, Csr) {
        debug_assert_eq!(vals.len(), self.cols.len());
        let n = self.nrows;
        let grouper = || Grouper {
            mark: vec![[0; LANES]; ngroups],
            at: vec![[0; LANES]; ngroups],
            tag: 0,
            ks: Vec::new(),
            vs: Vec::new(),
        };
        // Pass 1: each row's count of groups, this layout's slices in storage order.
        let mut lens = vec![0u32; n];
        let nnz: usize = lens
            .par_chunks_mut(CHUNK)
            .enumerate()
            .with_min_len(MIN_TASK_CHUNKS)
            .map_init(grouper, |g, (c, lc)| {
                let base = c * CHUNK;
                let mut nnz = 0;
                for q in (base..base + lc.len()).step_by(LANES) {
                    let count = g.sum_slice::<false, V>(self, vals, q / LANES, group);
                    for (l, &m) in count.iter().enumerate().take(LANES.min(n - q)) {
                        lc[self.perm[q + l] as usize - base] = m as u32;
                        nnz += m;
                    }
                }
                nnz
            })
            .sum();
        let (perm, slice_ptr) = sliced_layout(n, |i| lens[i] as usize);
        let pos = positions(&perm);
        // nnz ≤ A's entries, whose count fits u32 (the compressed rows' bound).
        let ptr = row_starts(&lens);
        drop(lens);
        let n_slices = slice_ptr.len() - 1;
        let total = slice_ptr[n_slices];
        let (mut cols, mut vals32) = (vec![0u32; total], vec![0.0f32; total]);
        let (mut row_cols, mut row_sums) = (vec![0u32; nnz], vec![0.0f64; nnz]);
        // Pass 2, a chunk's slices per task (the fresh pages touched by the thread filling
        // them). A chunk's rows keep their windows, so they are this layout's chunk too, and
        // a contiguous range of the compressed rows.
        let per_chunk = CHUNK / LANES;
        let mut parts = Vec::with_capacity(n_slices.div_ceil(per_chunk));
        let (mut rest_c, mut rest_w) = (&mut cols[..], &mut vals32[..]);
        let (mut rest_rc, mut rest_rs) = (&mut row_cols[..], &mut row_sums[..]);
        for (c, s0) in (0..n_slices).step_by(per_chunk).enumerate() {
            let w = slice_ptr[(s0 + per_chunk).min(n_slices)] - slice_ptr[s0];
            let (hc, tc) = rest_c.split_at_mut(w);
            let (hw, tw) = rest_w.split_at_mut(w);
            let m = (ptr[((c + 1) * CHUNK).min(n)] - ptr[c * CHUNK]) as usize;
            let (hrc, trc) = rest_rc.split_at_mut(m);
            let (hrs, trs) = rest_rs.split_at_mut(m);
            parts.push((hc, hw, hrc, hrs));
            (rest_c, rest_w, rest_rc, rest_rs) = (tc, tw, trc, trs);
        }
        let (pos_ref, ptr_ref, slice_ptr_ref) = (&pos, &ptr, &slice_ptr);
        parts
            .into_par_iter()
            .enumerate()
            .with_min_len(MIN_TASK_CHUNKS)
            .for_each_init(grouper, |g, (c, (pc, pw, rc, rs))| {
                let base = c * CHUNK;
                let end = (base + CHUNK).min(n);
                let (first, first_row) = (slice_ptr_ref[c * per_chunk], ptr_ref[base]);
                // This layout's slices in storage order (contiguous reads), each lane
                // written to its row's new place and to its compressed row.
                for q in (base..end).step_by(LANES) {
                    let count = g.sum_slice::<true, V>(self, vals, q / LANES, group);
                    for (l, &cl) in count.iter().enumerate().take(LANES.min(n - q)) {
                        let i = self.perm[q + l] as usize;
                        let to = pos_ref[i] as usize;
                        let s = to / LANES;
                        let (lo, hi) = (slice_ptr_ref[s] - first, slice_ptr_ref[s + 1] - first);
                        // The p-th group at slot LANES p; padding: value 0 at the row's
                        // first column (already read).
                        let pad = if cl > 0 { g.ks[l] } else { 0 };
                        // (A slice of empty rows has no slots at all.)
                        let lane = pc[lo..hi]
                            .iter_mut()
                            .zip(pw[lo..hi].iter_mut())
                            .skip(to % LANES)
                            .step_by(LANES);
                        for (p, (cj, wj)) in lane.enumerate() {
                            let slot = LANES * p + l;
                            (*cj, *wj) = if p < cl {
                                (g.ks[slot], g.vs[slot] as f32)
                            } else {
                                (pad, 0.0)
                            };
                        }
                        let at = (ptr_ref[i] - first_row) as usize;
                        for (p, (kc, vc)) in rc[at..at + cl].iter_mut().zip(&mut rs[at..at + cl]).enumerate()
                        {
                            let slot = LANES * p + l;
                            (*kc, *vc) = (g.ks[slot], g.vs[slot]);
                        }
                    }
                }
            });
        (
            Sell {
                nrows: n,
                ncols: ngroups,
                nnz,
                perm,
                slice_ptr,
                cols,
                vals: vals32,
            },
            Csr {
                nrows: n,
                ncols: ngroups,
                ptr,
                cols: row_cols,
                vals: row_sums,
            },
        )
    }

    /// `out[i] = f(i, out[i], Σ_j a_ij x_j)` with the stored values; returns the per-chunk
    /// sums of `g(i, out[i])` ([`Self::map_rows_with`]).
    #[inline(always)]
    pub fn map_rows<S: Sums>(
        &self,
        x: &[f64],
        out: &mut [f64],
        f: impl Fn(usize, f64, f64) -> f64 + Sync + Send,
        g: impl Fn(usize, f64) -> S + Sync + Send,
    ) -> Vec<S> {
        self.map_rows_with(&self.vals, x, out, f, g)
    }

    /// The layout of `a`, consumed, with its values rounded to f32. Rows keep their column
    /// order. Memory: the values are laid out and `a`'s freed, then the columns: at most
    /// `a`'s 12 bytes per entry plus 4.
    pub fn from_csr(a: Csr) -> Self {
        let (s, _) = Self::convert(a, false);
        s
    }

    /// As [`Self::from_csr`], also returning the f64 values laid out alike (CG's product on
    /// the finest level reads them, the smoother the f32 ones: one structure for both). The
    /// f64 values are laid out first and `a`'s freed, then the columns: at most 20 bytes per
    /// entry during the conversion (`a`'s 12 and the new values' 8), against 16 for `a`
    /// beside an f32 copy.
    pub fn from_csr_with_f64(a: Csr) -> (Self, Vec<f64>) {
        Self::convert(a, true)
    }

    fn convert(a: Csr, keep_f64: bool) -> (Self, Vec<f64>) {
        let (n, ncols, nnz) = (a.nrows, a.ncols, a.nnz());
        let Csr {
            ptr,
            cols: a_cols,
            vals: a_vals,
            ..
        } = a;
        let len = |p: usize| (ptr[p + 1] - ptr[p]) as usize;
        let (perm, slice_ptr) = sliced_layout(n, len);
        let layout = Layout {
            perm: &perm,
            slice_ptr: &slice_ptr,
            ptr: &ptr,
        };
        let (vals, vals64) = if keep_f64 {
            let vals64 = layout.fill(|k| a_vals[k], |_| 0.0);
            drop(a_vals);
            let vals = vals64.par_iter().with_min_len(CHUNK).map(|&v| v as f32).collect();
            (vals, vals64)
        } else {
            let vals = layout.fill(|k| a_vals[k] as f32, |_| 0.0);
            drop(a_vals);
            (vals, Vec::new())
        };
        // Padding reads the row's first column (0 for an empty row): a value already loaded.
        let cols = layout.fill(
            |k| a_cols[k],
            |p| {
                let k = ptr[p as usize] as usize;
                if len(p as usize) > 0 { a_cols[k] } else { 0 }
            },
        );
        drop((a_cols, ptr));
        (
            Self {
                nrows: n,
                ncols,
                nnz,
                perm,
                slice_ptr,
                cols,
                vals,
            },
            vals64,
        )
    }
}

/// A column in no group ([`Sell::group_columns`]).
pub(crate) const NO_GROUP: u32 = u32::MAX;

/// Scratch of [`Sell::group_columns`]: per group and lane, the tag of the last call that
/// met it there and its place in that lane's sums; the lanes' groups and sums, lane l's p-th
/// at LANES p + l.
struct Grouper {
    mark: Vec<[u32; LANES]>,
    at: Vec<[u32; LANES]>,
    tag: u32,
    ks: Vec<u32>,
    vs: Vec<f64>,
}

impl Grouper {
    /// The rows of slice s of `a` summed by group (only counted without `SUMS`), the lanes
    /// side by side (independent chains); returns each lane's count of groups. Branch-free
    /// but for padding and dropped columns: a group is new to lane l when its mark there is
    /// not this call's tag.
    fn sum_slice<const SUMS: bool, V: Value>(
        &mut self,
        a: &Sell,
        vals: &[V],
        s: usize,
        group: &[u32],
    ) -> [usize; LANES] {
        self.tag += 1;
        let tag = self.tag;
        let (lo, hi) = (a.slice_ptr[s], a.slice_ptr[s + 1]);
        if SUMS && self.ks.len() < hi - lo {
            self.ks.resize(hi - lo, 0);
            self.vs.resize(hi - lo, 0.0);
        }
        let lanes = LANES.min(a.nrows - s * LANES);
        let mut count = [0usize; LANES];
        let ahead = group.len() >= PREFETCH_MIN_COLS;
        for (k, (cj, vj)) in a.cols[lo..hi]
            .chunks_exact(LANES)
            .zip(vals[lo..hi].chunks_exact(LANES))
            .enumerate()
        {
            if ahead {
                prefetch_gathers(&a.cols, lo + LANES * k + PREFETCH_AHEAD, group);
            }
            for l in 0..lanes {
                let (k, v) = (group[cj[l] as usize], vj[l].into());
                if v == 0.0 || k == NO_GROUP {
                    continue;
                }
                let ku = k as usize;
                let new = self.mark[ku][l] != tag;
                self.mark[ku][l] = tag;
                if SUMS {
                    let p = if new { count[l] } else { self.at[ku][l] as usize };
                    self.at[ku][l] = p as u32;
                    let slot = LANES * p + l;
                    self.ks[slot] = k;
                    self.vs[slot] = if new { v } else { self.vs[slot] + v };
                }
                count[l] += usize::from(new);
            }
        }
        count
    }
}

/// A square matrix built straight into SELL form from its rows, with its f64 values and
/// access to each row: the finest level of a plain-aggregation hierarchy, assembled from the
/// network without an intermediate compressed-row copy (at 10⁶ unknowns the copy and its
/// conversion took 0.12–0.19 s, this assembly 0.10–0.14 s, and the setup makes 11 000 page
/// faults fewer; `docs/performance.md` § 4).
#[derive(Debug)]
pub(crate) struct RowSell {
    /// The layout, values in f32.
    pub a: Sell,
    /// The f64 values laid out alike.
    pub vals: Vec<f64>,
    /// Sorted position of each row.
    pos: Vec<u32>,
    /// Entries of each row.
    len: Vec<u32>,
}

impl RowSell {
    /// The n × n matrix whose row i has `len(state, i)` entries, written in column order by
    /// `fill(state, i, cols, vals)` (slices of that length); `init` makes one state per
    /// parallel task, as [`Csr::from_row_lengths`]. The same rows give the same matrix for
    /// any thread count.
    pub fn from_rows<S, I, L, F>(n: usize, init: I, len: L, fill: F) -> Self
    where
        I: Fn() -> S + Sync + Send,
        L: Fn(&mut S, usize) -> usize + Sync + Send,
        F: Fn(&mut S, usize, &mut [u32], &mut [f64]) + Sync + Send,
    {
        let mut lens = vec![0u32; n];
        lens.par_chunks_mut(CHUNK)
            .enumerate()
            .with_min_len(MIN_TASK_CHUNKS)
            .for_each_init(&init, |s, (c, lc)| {
                for (k, l) in lc.iter_mut().enumerate() {
                    *l = len(s, c * CHUNK + k) as u32;
                }
            });
        let nnz = lens.iter().map(|&l| l as usize).sum();
        let (perm, slice_ptr) = sliced_layout(n, |p| lens[p] as usize);
        let pos = positions(&perm);
        let n_slices = slice_ptr.len() - 1;
        let total = slice_ptr[n_slices];
        // Columns, f64 and f32 values written in one pass (each fresh page is touched by the
        // thread that fills it, once).
        let mut cols = vec![0u32; total];
        let mut vals = vec![0.0f64; total];
        let mut vals32 = vec![0.0f32; total];
        let mut parts: Vec<(&mut [u32], &mut [f64], &mut [f32])> = Vec::with_capacity(n_slices);
        let (mut rest_c, mut rest_v, mut rest_w) = (&mut cols[..], &mut vals[..], &mut vals32[..]);
        for s in 0..n_slices {
            let w = slice_ptr[s + 1] - slice_ptr[s];
            let (hc, tc) = rest_c.split_at_mut(w);
            let (hv, tv) = rest_v.split_at_mut(w);
            let (hw, tw) = rest_w.split_at_mut(w);
            parts.push((hc, hv, hw));
            (rest_c, rest_v, rest_w) = (tc, tv, tw);
        }
        parts
            .into_par_iter()
            .enumerate()
            .with_min_len(CHUNK / LANES)
            .for_each_init(
                || (init(), Vec::new(), Vec::new()),
                |(st, rc, rv), (s, (pc, pv, pw))| {
                    for l in 0..LANES.min(n - s * LANES) {
                        let p = perm[s * LANES + l] as usize;
                        let m = lens[p] as usize;
                        rc.resize(m, 0);
                        rv.resize(m, 0.0);
                        fill(st, p, rc, rv);
                        // Padding: value 0 at the row's first column (already read).
                        let pad = rc.first().copied().unwrap_or(0);
                        let lane = pc[l..]
                            .iter_mut()
                            .step_by(LANES)
                            .zip(pv[l..].iter_mut().step_by(LANES))
                            .zip(pw[l..].iter_mut().step_by(LANES));
                        for (j, ((c, v), w)) in lane.enumerate() {
                            (*c, *v) = if j < m { (rc[j], rv[j]) } else { (pad, 0.0) };
                            *w = *v as f32;
                        }
                    }
                },
            );
        Self {
            a: Sell {
                nrows: n,
                ncols: n,
                nnz,
                perm,
                slice_ptr,
                cols,
                vals: vals32,
            },
            vals,
            pos,
            len: lens,
        }
    }

    /// Rows.
    pub fn nrows(&self) -> usize {
        self.a.nrows
    }

    /// Row i's entries (column, f64 value) in column order.
    #[inline]
    pub fn row(&self, i: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let at = self.pos[i] as usize;
        let base = self.a.slice_ptr[at / LANES] + at % LANES;
        (0..self.len[i] as usize).map(move |j| {
            let k = base + LANES * j;
            (self.a.cols[k], self.vals[k])
        })
    }

    /// max_i s_i Σ_j |a_ij| (the Gershgorin bound of ρ(SA) for S = diag(s)), read slice by
    /// slice in storage order.
    pub fn max_scaled_abs_row_sum(&self, s: &[f64]) -> f64 {
        let a = &self.a;
        (0..a.slice_ptr.len() - 1)
            .into_par_iter()
            .with_min_len(CHUNK / LANES)
            .map(|sl| {
                let (lo, hi) = (a.slice_ptr[sl], a.slice_ptr[sl + 1]);
                let mut acc = [0.0f64; LANES];
                for vj in self.vals[lo..hi].chunks_exact(LANES) {
                    for (t, v) in acc.iter_mut().zip(vj) {
                        *t += v.abs();
                    }
                }
                let i0 = sl * LANES;
                (0..LANES.min(a.nrows - i0))
                    .map(|l| acc[l] * s[a.perm[i0 + l] as usize])
                    .fold(0.0, f64::max)
            })
            .reduce(|| 0.0, f64::max)
    }

    /// The layout and its f64 values; the row access is dropped.
    pub fn into_parts(self) -> (Sell, Vec<f64>) {
        (self.a, self.vals)
    }

    /// The same matrix in compressed rows.
    pub fn to_csr(&self) -> Csr {
        Csr::from_row_lengths(
            self.nrows(),
            self.nrows(),
            || (),
            |_, i| self.len[i] as usize,
            |_, i, c, v| {
                for ((cj, vj), (col, val)) in c.iter_mut().zip(v.iter_mut()).zip(self.row(i)) {
                    (*cj, *vj) = (col, val);
                }
            },
        )
    }
}

/// Row starts of compressed rows of lengths `lens`: 0, then the running sums.
fn row_starts(lens: &[u32]) -> Vec<u32> {
    let mut ptr = Vec::with_capacity(lens.len() + 1);
    ptr.push(0u32);
    for (i, &m) in lens.iter().enumerate() {
        ptr.push(ptr[i] + m);
    }
    ptr
}

#[cfg(test)]
impl RowSell {
    /// The rows of `a` assembled straight into the sliced layout (tests).
    pub fn from_csr_rows(a: &Csr) -> Self {
        Self::from_rows(
            a.nrows,
            || (),
            |_, i| a.row(i).0.len(),
            |_, i, c, v| {
                let (ac, av) = a.row(i);
                c.copy_from_slice(ac);
                v.copy_from_slice(av);
            },
        )
    }
}

/// Where each compressed-row entry goes in the sliced layout.
struct Layout<'a> {
    perm: &'a [u32],
    slice_ptr: &'a [usize],
    /// The compressed rows' starts.
    ptr: &'a [u32],
}

impl Layout<'_> {
    /// The compressed rows' entries (`src(k)` for entry k) in the sliced layout; the padding
    /// of row p is `pad(p)`. Slices own disjoint ranges: filled in parallel.
    fn fill<U: Copy + Default + Send + Sync>(
        &self,
        src: impl Fn(usize) -> U + Sync,
        pad: impl Fn(u32) -> U + Sync,
    ) -> Vec<U> {
        let n = self.perm.len();
        let n_slices = self.slice_ptr.len() - 1;
        let mut out = vec![U::default(); self.slice_ptr[n_slices]];
        let mut parts: Vec<&mut [U]> = Vec::with_capacity(n_slices);
        let mut rest = &mut out[..];
        for s in 0..n_slices {
            let (head, tail) = rest.split_at_mut(self.slice_ptr[s + 1] - self.slice_ptr[s]);
            parts.push(head);
            rest = tail;
        }
        parts
            .into_par_iter()
            .enumerate()
            .with_min_len(CHUNK / LANES)
            .for_each(|(s, part)| {
                for l in 0..LANES.min(n - s * LANES) {
                    let p = self.perm[s * LANES + l];
                    let fill = pad(p);
                    for j in (l..part.len()).step_by(LANES) {
                        part[j] = fill;
                    }
                    let (lo, hi) = (self.ptr[p as usize] as usize, self.ptr[p as usize + 1] as usize);
                    for (j, k) in (lo..hi).enumerate() {
                        part[LANES * j + l] = src(k);
                    }
                }
            });
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::par::ordered_sum;

    /// A xorshift64 sequence from `state` (≠ 0): test patterns without a dependency.
    fn xorshift(mut state: u64) -> impl FnMut() -> u64 {
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        }
    }

    /// A random symmetric pattern with rows of ~1 to 20 entries, 40 000 rows (ten chunks: the
    /// parallel path).
    fn matrix() -> Csr {
        let n = 40_000usize;
        let mut next = xorshift(0x9e37_79b9_7f4a_7c15);
        let mut rows: Vec<Vec<(u32, f64)>> = (0..n).map(|i| vec![(i as u32, 10.0)]).collect();
        for i in 0..n {
            for _ in 0..(next() % 6) {
                let j = (i + 1 + (next() % 50) as usize) % n;
                let v = -((next() % 1000) as f64 + 1.0) / 997.0;
                rows[i].push((j as u32, v));
                rows[j].push((i as u32, v));
            }
        }
        let mut ptr = vec![0u32];
        let (mut cols, mut vals) = (Vec::new(), Vec::new());
        for r in &mut rows {
            r.sort_by_key(|e| e.0);
            r.dedup_by_key(|e| e.0);
            for &(c, v) in r.iter() {
                cols.push(c);
                vals.push(v);
            }
            ptr.push(cols.len() as u32);
        }
        Csr {
            nrows: n,
            ncols: n,
            ptr,
            cols,
            vals,
        }
    }

    #[test]
    fn rows_match_compressed_rows_and_partials_are_thread_count_free() {
        let a = matrix();
        let (s, v64) = Sell::from_csr_with_f64(a.clone());
        assert_eq!(s.nnz(), a.nnz());
        assert!(s.cols.len() >= a.nnz() && s.cols.len() == s.vals.len() && v64.len() == s.vals.len());
        let x: Vec<f64> = (0..a.nrows).map(|i| (i as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..a.nrows).map(|i| (i as f64 * 0.11).cos()).collect();
        let run = || {
            let mut r = vec![0.0; a.nrows];
            let partials = s.map_rows_with(&v64, &x, &mut r, |i, _, ax| b[i] - ax, |i, ri| ri * x[i]);
            (r, ordered_sum(&partials))
        };
        let (r, rx) = run();
        let mut want = vec![0.0; a.nrows];
        a.residual(&b, &x, &mut want);
        for (i, (u, v)) in r.iter().zip(&want).enumerate() {
            assert!((u - v).abs() <= 1e-13 * (1.0 + v.abs()), "row {i}: {u} vs {v}");
        }
        let rx_want: f64 = want.iter().zip(&x).map(|(u, v)| u * v).sum();
        assert!((rx - rx_want).abs() <= 1e-10 * rx_want.abs().max(1.0));
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (r2, rx2) = pool.install(run);
            assert_eq!(r2, r, "{threads} threads");
            assert_eq!(rx2.to_bits(), rx.to_bits(), "{threads} threads");
        }
        // The f32 values: the same products to f32 rounding.
        let mut y32 = vec![0.0; a.nrows];
        s.map_rows(&x, &mut y32, |i, _, ax| b[i] - ax, |_, _| 0.0);
        for (u, v) in y32.iter().zip(&r) {
            assert!((u - v).abs() <= 1e-6 * (1.0 + v.abs()), "{u} vs {v}");
        }
    }

    #[test]
    fn rows_assembled_in_place_match_the_converted_layout() {
        let a = matrix();
        let direct = RowSell::from_csr_rows(&a);
        let (conv, v64) = Sell::from_csr_with_f64(a.clone());
        assert_eq!(direct.a.nnz(), a.nnz());
        assert_eq!(
            (&direct.a.perm, &direct.a.slice_ptr),
            (&conv.perm, &conv.slice_ptr)
        );
        assert_eq!((&direct.a.cols, &direct.a.vals), (&conv.cols, &conv.vals));
        assert_eq!(direct.vals, v64);
        // Row access and the compressed rows back.
        for i in [0, 1, 4095, 4096, 17_777, a.nrows - 1] {
            let (c, v) = a.row(i);
            let got: Vec<(u32, f64)> = direct.row(i).collect();
            let want: Vec<(u32, f64)> = c.iter().copied().zip(v.iter().copied()).collect();
            assert_eq!(got, want, "row {i}");
        }
        let back = direct.to_csr();
        assert_eq!((&back.ptr, &back.cols, &back.vals), (&a.ptr, &a.cols, &a.vals));
        // The scaled Gershgorin bound, against the compressed rows.
        let s: Vec<f64> = (0..a.nrows).map(|i| 1.0 + (i % 7) as f64).collect();
        let want = (0..a.nrows)
            .map(|i| a.row(i).1.iter().map(|v| v.abs()).sum::<f64>() * s[i])
            .fold(0.0, f64::max);
        assert_eq!(direct.max_scaled_abs_row_sum(&s), want);
        // The same layout on one thread.
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let one = pool.install(|| RowSell::from_csr_rows(&a));
        assert_eq!(
            (&one.a.cols, &one.vals, &one.pos),
            (&direct.a.cols, &direct.vals, &direct.pos)
        );
    }

    #[test]
    fn rectangular_products_match_compressed_rows() {
        // A prolongator-like 40 000 × 5 000 matrix (0 to 9 entries a row) and its transpose.
        let (n, m) = (40_000usize, 5_000usize);
        let mut next = xorshift(0x2545_f491_4f6c_dd1d);
        let mut ptr = vec![0u32];
        let (mut cols, mut vals) = (Vec::new(), Vec::new());
        for _ in 0..n {
            let mut row: Vec<u32> = (0..next() % 10).map(|_| (next() % m as u64) as u32).collect();
            row.sort_unstable();
            row.dedup();
            for c in row {
                cols.push(c);
                vals.push(((next() % 1000) as f64 + 1.0) / 1000.0);
            }
            ptr.push(cols.len() as u32);
        }
        let p = Csr {
            nrows: n,
            ncols: m,
            ptr,
            cols,
            vals,
        };
        let r = p.transpose();
        let xc: Vec<f64> = (0..m).map(|i| (i as f64 * 0.7).sin()).collect();
        let xf: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
        // y += P x, and R x, against the compressed rows with the same f32 values.
        let mut y = xf.clone();
        Sell::from_csr(p.clone()).map_rows(&xc, &mut y, |_, y, s| y + s, |_, _| 0.0);
        let mut want = xf.clone();
        p.clone().into_f32().spmv_add(&xc, &mut want);
        for (u, v) in y.iter().zip(&want) {
            assert!((u - v).abs() <= 1e-12 * (1.0 + v.abs()), "{u} vs {v}");
        }
        let mut z = vec![0.0; m];
        Sell::from_csr(r.clone()).map_rows(&xf, &mut z, |_, _, s| s, |_, _| 0.0);
        let mut want = vec![0.0; m];
        r.into_f32().spmv(&xf, &mut want);
        for (u, v) in z.iter().zip(&want) {
            assert!((u - v).abs() <= 1e-12 * (1.0 + v.abs()), "{u} vs {v}");
        }
    }

    #[test]
    fn grouped_columns_are_a_times_p_whatever_the_thread_count() {
        let a = matrix();
        let n = a.nrows;
        // Groups of ~7 consecutive columns, every 13th column in none, nor any column of
        // 20 000–20 599 (the rows of 20 050–20 549 reach no other: whole slices of empty
        // rows).
        let group: Vec<u32> = (0..n)
            .map(|j| {
                if j % 13 == 5 || (20_000..20_600).contains(&j) {
                    NO_GROUP
                } else {
                    (j / 7) as u32
                }
            })
            .collect();
        let ngroups = n.div_ceil(7);
        let s = Sell::from_csr(a.clone());
        let ap = s.group_columns(&s.vals, &group, ngroups).0;
        assert_eq!((ap.nrows(), ap.ncols()), (n, ngroups));
        // The same product from the f32 values through P as a vector: A (P e).
        let e: Vec<f64> = (0..ngroups).map(|k| ((k * 31 % 17) as f64) - 8.0).collect();
        let pe: Vec<f64> = group
            .iter()
            .map(|&k| if k == NO_GROUP { 0.0 } else { e[k as usize] })
            .collect();
        let (mut want, mut got) = (vec![0.0; n], vec![0.0; n]);
        s.map_rows(&pe, &mut want, |_, _, v| v, |_, _| 0.0);
        ap.map_rows(&e, &mut got, |_, _, v| v, |_, _| 0.0);
        let (mut distinct, mut empty) = (0, 0);
        for i in 0..n {
            let (cols, vals) = a.row(i);
            let scale: f64 = vals.iter().map(|v| v.abs()).sum::<f64>() * 8.0;
            // Sums of f32 entries rounded once more: within 2 ε₃₂ Σ |a_ij| max |e|.
            assert!(
                (got[i] - want[i]).abs() <= 1.2e-7 * scale,
                "row {i}: {} vs {}",
                got[i],
                want[i]
            );
            let mut ks: Vec<u32> = cols
                .iter()
                .map(|&j| group[j as usize])
                .filter(|&k| k != NO_GROUP)
                .collect();
            ks.sort_unstable();
            ks.dedup();
            distinct += ks.len();
            empty += usize::from(ks.is_empty());
        }
        // One entry per group met in a row, and no more.
        assert_eq!(ap.nnz(), distinct);
        assert!(empty >= 500, "{empty} empty rows");
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let again = pool.install(|| s.group_columns(&s.vals, &group, ngroups).0);
            assert_eq!(
                (&again.perm, &again.slice_ptr, &again.cols),
                (&ap.perm, &ap.slice_ptr, &ap.cols),
                "{threads} threads"
            );
            assert!(
                again
                    .vals
                    .iter()
                    .zip(&ap.vals)
                    .all(|(x, y)| x.to_bits() == y.to_bits())
            );
        }
        // From the f64 values: each compressed row holds its group sums exactly as summed in
        // the row's order.
        let (s64, v64) = Sell::from_csr_with_f64(a.clone());
        let (_, rows) = s64.group_columns(&v64, &group, ngroups);
        for i in (0..n).step_by(7) {
            let (cols, vals) = a.row(i);
            let mut want: Vec<(u32, f64)> = Vec::new();
            for (&j, &v) in cols.iter().zip(vals) {
                let k = group[j as usize];
                match want.iter_mut().find(|(g, _)| *g == k) {
                    _ if k == NO_GROUP => {}
                    Some((_, sum)) => *sum += v,
                    None => want.push((k, v)),
                }
            }
            let (rc, rv) = rows.row(i);
            let got: Vec<(u32, f64)> = rc.iter().copied().zip(rv.iter().copied()).collect();
            assert_eq!(got, want, "row {i}");
        }
    }
}
