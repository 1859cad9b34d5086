//! Compact compressed-row matrices of the multigrid hierarchy, with parallel products whose
//! results do not depend on the thread count (rows in fixed chunks, each row summed in a
//! fixed order, partial dot products combined in chunk order).

use rayon::prelude::*;

use crate::par::{CHUNK, MIN_TASK_CHUNKS, chunks_map, ordered_sum};

/// A sparse matrix in compressed rows: the entries of row i are
/// `cols[ptr[i]..ptr[i + 1]]` (sorted, unique) with values `vals[..]`. Values are f64, or f32
/// for the operators only the multigrid preconditioner reads ([`Csr::into_f32`]); products
/// always compute in f64.
#[derive(Debug, Clone, Default)]
pub(crate) struct Csr<T = f64> {
    pub nrows: usize,
    pub ncols: usize,
    /// Row starts (u32: half the bytes of usize on every pass; `from_row_lengths` checks
    /// the count).
    pub ptr: Vec<u32>,
    pub cols: Vec<u32>,
    pub vals: Vec<T>,
}

/// A stored matrix value: f64, or f32 widened to f64 exactly on every use.
pub(crate) trait Value: Copy + Send + Sync + Into<f64> {}
impl Value for f64 {}
impl Value for f32 {}

impl<T: Value> Csr<T> {
    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.cols.len()
    }

    /// Row i as (columns, values).
    #[inline(always)]
    pub fn row(&self, i: usize) -> (&[u32], &[T]) {
        let (lo, hi) = (self.ptr[i] as usize, self.ptr[i + 1] as usize);
        (&self.cols[lo..hi], &self.vals[lo..hi])
    }

    /// y = self · x. (tests: the cycle reads the [`crate::sell::Sell`] form).
    #[cfg(test)]
    pub fn spmv(&self, x: &[f64], y: &mut [f64]) {
        chunks_map(y, |c, yc| {
            let base = c * CHUNK;
            for (k, yi) in yc.iter_mut().enumerate() {
                *yi = self.row_dot(base + k, x);
            }
        });
    }

    /// q = self · p; returns p·q.
    pub fn spmv_dot(&self, p: &[f64], q: &mut [f64]) -> f64 {
        self.spmv_dot_with(&self.vals, p, q)
    }

    /// y += self · x. (tests: the cycle reads the [`crate::sell::Sell`] form).
    #[cfg(test)]
    pub fn spmv_add(&self, x: &[f64], y: &mut [f64]) {
        chunks_map(y, |c, yc| {
            let base = c * CHUNK;
            for (k, yi) in yc.iter_mut().enumerate() {
                *yi += self.row_dot(base + k, x);
            }
        });
    }

    /// r = b − self · x (tests; the cycle's residual reads the [`crate::sell::Sell`] form).
    #[cfg(test)]
    pub fn residual(&self, b: &[f64], x: &[f64], r: &mut [f64]) {
        chunks_map(r, |c, rc| {
            let base = c * CHUNK;
            for (k, ri) in rc.iter_mut().enumerate() {
                *ri = b[base + k] - self.row_dot(base + k, x);
            }
        });
    }

    /// Σ_j a_ij x_j for row i, in f64. Four independent partial sums (entry k goes to sum
    /// k mod 4, combined as (s0 + s1) + (s2 + s3)): a row has ~8 entries, and one accumulator
    /// would serialise them on the floating-point add latency. Fixed order: deterministic.
    #[inline(always)]
    pub fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
        self.row_dot_with(&self.vals, i, x)
    }

    /// As [`Self::row_dot`] with other values on the same structure (`vals` as long as
    /// `cols`): the fine operator's f64 values beside the f32 ones the smoother reads.
    #[inline(always)]
    pub fn row_dot_with<V: Value>(&self, vals: &[V], i: usize, x: &[f64]) -> f64 {
        let (lo, hi) = (self.ptr[i] as usize, self.ptr[i + 1] as usize);
        let (rc, rv) = (&self.cols[lo..hi], &vals[lo..hi]);
        let mut acc = [0.0f64; 4];
        let (c4, v4) = (rc.chunks_exact(4), rv.chunks_exact(4));
        let (cr, vr) = (c4.remainder(), v4.remainder());
        for (c, v) in c4.zip(v4) {
            for l in 0..4 {
                acc[l] += v[l].into() * x[c[l] as usize];
            }
        }
        for (l, (&j, &v)) in cr.iter().zip(vr).enumerate() {
            acc[l] += v.into() * x[j as usize];
        }
        (acc[0] + acc[1]) + (acc[2] + acc[3])
    }

    /// q = A · p with A's values `vals` on this structure; returns p·q.
    pub fn spmv_dot_with<V: Value>(&self, vals: &[V], p: &[f64], q: &mut [f64]) -> f64 {
        debug_assert_eq!(vals.len(), self.cols.len());
        let partials = chunks_map(q, |c, qc| {
            let base = c * CHUNK;
            let mut acc = 0.0;
            for (k, qi) in qc.iter_mut().enumerate() {
                let v = self.row_dot_with(vals, base + k, p);
                acc += v * p[base + k];
                *qi = v;
            }
            acc
        });
        ordered_sum(&partials)
    }
}

impl Csr {
    /// The same matrix with f32 values (each value rounded to nearest), reusing the
    /// structure: half the value bytes for operators that only the preconditioner reads.
    #[cfg(test)]
    pub fn into_f32(self) -> Csr<f32> {
        Csr {
            nrows: self.nrows,
            ncols: self.ncols,
            vals: self.vals.par_iter().map(|&v| v as f32).collect(),
            ptr: self.ptr,
            cols: self.cols,
        }
    }

    /// Builds a matrix row by row in one pass: `row(scratch, i, cols, vals)` appends the
    /// entries of row i (sorted unique columns) to its chunk's buffers, which are then
    /// joined in chunk order; `init` makes a scratch state per parallel task (it must not
    /// influence the values). The join costs a copy of the result, where
    /// [`Self::from_row_lengths`] builds each row twice: for results much smaller than what
    /// their rows read (the plain-aggregation Galerkin operator, a tenth of its fine level).
    pub fn from_rows<S, I, F>(nrows: usize, ncols: usize, init: I, row: F) -> Self
    where
        I: Fn() -> S + Sync + Send,
        F: Fn(&mut S, usize, &mut Vec<u32>, &mut Vec<f64>) + Sync + Send,
    {
        let build = |s: &mut S, c: usize| {
            let (mut lens, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
            for i in c * CHUNK..((c + 1) * CHUNK).min(nrows) {
                let before = cols.len();
                row(s, i, &mut cols, &mut vals);
                lens.push(cols.len() - before);
            }
            (lens, cols, vals)
        };
        let chunks = nrows.div_ceil(CHUNK);
        let pieces: Vec<(Vec<usize>, Vec<u32>, Vec<f64>)> = if chunks <= MIN_TASK_CHUNKS {
            let mut s = init();
            (0..chunks).map(|c| build(&mut s, c)).collect()
        } else {
            (0..chunks)
                .into_par_iter()
                .with_min_len(MIN_TASK_CHUNKS)
                .map_init(&init, build)
                .collect()
        };
        let nnz: usize = pieces.iter().map(|p| p.1.len()).sum();
        assert!(
            u32::try_from(nnz).is_ok(),
            "{nnz} entries: more than a u32 row pointer holds"
        );
        let mut ptr = Vec::with_capacity(nrows + 1);
        ptr.push(0u32);
        let (mut cols, mut vals) = (Vec::with_capacity(nnz), Vec::with_capacity(nnz));
        for (lens, c, v) in pieces {
            for l in lens {
                ptr.push(ptr[ptr.len() - 1] + l as u32);
            }
            cols.extend_from_slice(&c);
            vals.extend_from_slice(&v);
        }
        Self {
            nrows,
            ncols,
            ptr,
            cols,
            vals,
        }
    }

    /// Builds a matrix in place from its row lengths: `len(scratch, i)` is the number of
    /// entries of row i, then `fill(scratch, i, cols, vals)` writes row i into slices of
    /// exactly that length (sorted unique columns); `init` makes a scratch state per
    /// parallel task (it must not influence the values). Rows are counted and filled in
    /// parallel chunks of [`CHUNK`]. No per-chunk copy exists beside the result, so the
    /// peak is the matrix itself, for the price of a counting pass.
    pub fn from_row_lengths<S, I, L, F>(nrows: usize, ncols: usize, init: I, len: L, fill: F) -> Self
    where
        I: Fn() -> S + Sync + Send,
        L: Fn(&mut S, usize) -> usize + Sync + Send,
        F: Fn(&mut S, usize, &mut [u32], &mut [f64]) + Sync + Send,
    {
        Self::from_row_lengths_in(nrows, ncols, CHUNK, MIN_TASK_CHUNKS, init, len, fill)
    }

    /// As [`Self::from_row_lengths`], in chunks of `chunk` rows and parallel tasks of at
    /// least `task_chunks` chunks (few costly rows, as a block of the Galerkin product, are
    /// worth two threads in smaller chunks). Rows are built independently: the result is
    /// the same for any chunking.
    fn from_row_lengths_in<S, I, L, F>(
        nrows: usize,
        ncols: usize,
        chunk: usize,
        task_chunks: usize,
        init: I,
        len: L,
        fill: F,
    ) -> Self
    where
        I: Fn() -> S + Sync + Send,
        L: Fn(&mut S, usize) -> usize + Sync + Send,
        F: Fn(&mut S, usize, &mut [u32], &mut [f64]) + Sync + Send,
    {
        let sequential = |n: usize| n <= chunk * task_chunks;
        let mut lens = vec![0u32; nrows];
        let count = |s: &mut S, (c, lc): (usize, &mut [u32])| {
            for (k, l) in lc.iter_mut().enumerate() {
                *l = len(s, c * chunk + k) as u32;
            }
        };
        if sequential(nrows) {
            let mut s = init();
            lens.chunks_mut(chunk).enumerate().for_each(|t| count(&mut s, t));
        } else {
            lens.par_chunks_mut(chunk)
                .enumerate()
                .with_min_len(task_chunks)
                .for_each_init(&init, count);
        }
        let mut ptr = Vec::with_capacity(nrows + 1);
        ptr.push(0u32);
        let mut total = 0u64;
        for &l in &lens {
            total += u64::from(l);
            assert!(
                u32::try_from(total).is_ok(),
                "{total} entries: more than a u32 row pointer holds"
            );
            ptr.push(total as u32);
        }
        drop(lens);
        let nnz = total as usize;
        let mut cols = vec![0u32; nnz];
        let mut vals = vec![0.0f64; nnz];
        // Each chunk's rows and its slices of the result.
        let mut targets = Vec::with_capacity(nrows.div_ceil(chunk));
        let (mut rest_c, mut rest_v) = (cols.as_mut_slice(), vals.as_mut_slice());
        for lo in (0..nrows).step_by(chunk) {
            let hi = (lo + chunk).min(nrows);
            let n = (ptr[hi] - ptr[lo]) as usize;
            let (hc, tc) = rest_c.split_at_mut(n);
            let (hv, tv) = rest_v.split_at_mut(n);
            targets.push((lo..hi, hc, hv));
            rest_c = tc;
            rest_v = tv;
        }
        let ptr_ref = &ptr;
        let fill_chunk = |s: &mut S, (rows, tc, tv): (std::ops::Range<usize>, &mut [u32], &mut [f64])| {
            let base = ptr_ref[rows.start] as usize;
            for i in rows {
                let (lo, hi) = (ptr_ref[i] as usize - base, ptr_ref[i + 1] as usize - base);
                fill(s, i, &mut tc[lo..hi], &mut tv[lo..hi]);
            }
        };
        if sequential(nrows) {
            let mut s = init();
            targets.into_iter().for_each(|t| fill_chunk(&mut s, t));
        } else {
            targets
                .into_par_iter()
                .with_min_len(task_chunks)
                .for_each_init(&init, fill_chunk);
        }
        Self {
            nrows,
            ncols,
            ptr,
            cols,
            vals,
        }
    }

    /// The transpose (rows of the result list their columns in increasing order).
    pub fn transpose(&self) -> Self {
        let mut count = vec![0usize; self.ncols + 1];
        for &c in &self.cols {
            count[c as usize + 1] += 1;
        }
        for j in 0..self.ncols {
            count[j + 1] += count[j];
        }
        let ptr = count.iter().map(|&c| c as u32).collect();
        let mut fill = count;
        let mut cols = vec![0u32; self.nnz()];
        let mut vals = vec![0.0; self.nnz()];
        for i in 0..self.nrows {
            let (rc, rv) = self.row(i);
            for (&c, &v) in rc.iter().zip(rv) {
                let k = fill[c as usize];
                cols[k] = i as u32;
                vals[k] = v;
                fill[c as usize] += 1;
            }
        }
        Self {
            nrows: self.ncols,
            ncols: self.nrows,
            ptr,
            cols,
            vals,
        }
    }

    /// The product self · b. Each entry is summed in the order of the row's entries, then of
    /// b's rows (deterministic). The multigrid setup forms its products by
    /// [`Self::galerkin`]; this is the reference it is tested against.
    #[cfg(test)]
    pub fn matmul(&self, b: &Csr) -> Self {
        self.matmul_rows(b, self.nrows, |i| i)
    }

    /// Rows `row_of(0..nrows)` of the product self · b, summed as [`Self::matmul`] sums
    /// them (row i of the result is row `row_of(i)` of the full product, bit for bit).
    fn matmul_rows(&self, b: &Csr, nrows: usize, row_of: impl Fn(usize) -> usize + Sync + Send) -> Self {
        debug_assert_eq!(self.ncols, b.nrows);
        let m = b.ncols;
        // Built in place: a symbolic pass counts each row's columns, then the numeric pass
        // writes the rows into the result (no chunk copies beside a large product). Chunks
        // of 1024 rows, a few parallel tasks per thread: a block of the Galerkin product on
        // a coarse level has ~2·10⁴ costly rows, which chunks of [`CHUNK`] rows left on one
        // thread (the result does not depend on the chunking).
        const MATMUL_CHUNK: usize = 1024;
        let tasks = 2 * rayon::current_num_threads().max(1);
        Self::from_row_lengths_in(
            nrows,
            m,
            MATMUL_CHUNK,
            nrows.div_ceil(MATMUL_CHUNK).div_ceil(tasks).max(1),
            || Accumulator::new(m),
            |acc, i| {
                let (ac, _) = self.row(row_of(i));
                ac.iter()
                    .map(|&k| b.row(k as usize).0.iter().filter(|&&j| acc.mark(i, j)).count())
                    .sum()
            },
            |acc, i, cols, vals| {
                let (ac, av) = self.row(row_of(i));
                for (&k, &a) in ac.iter().zip(av) {
                    let (bc, bv) = b.row(k as usize);
                    for (&j, &v) in bc.iter().zip(bv) {
                        acc.add(i, j, a * v);
                    }
                }
                acc.drain_sorted_into(cols, vals);
            },
        )
    }

    /// The Galerkin product R (A P) of `self` = R, without storing A P whole: R's rows are
    /// formed in blocks, each from the rows of A P that the block reads (computed for the
    /// block, then dropped). Every entry is summed exactly as `self.matmul(&a.matmul(p))`
    /// sums it — the same products, in increasing order of A P's row — so the result is the
    /// same bit for bit; a row of A P read by several blocks is computed once per block (a
    /// few per cent more work at 10⁶ nodes). Peak: the result plus one block's rows of A P
    /// (an eighth) instead of the whole A P.
    pub fn galerkin(&self, a: &Csr, p: &Csr) -> Self {
        /// Blocks of R's rows (fewer when a block would drop below [`GALERKIN_MIN_ROWS`]).
        const GALERKIN_BLOCKS: usize = 16;
        /// Fewest rows of R per block.
        const GALERKIN_MIN_ROWS: usize = 1024;
        self.galerkin_in_blocks(a, p, self.nrows.div_ceil(GALERKIN_BLOCKS).max(GALERKIN_MIN_ROWS))
    }

    /// [`Self::galerkin`] in blocks of `block` rows of R.
    fn galerkin_in_blocks(&self, a: &Csr, p: &Csr, block: usize) -> Self {
        /// Rows of R per parallel chunk (a row of R reads ~20 rows of A P at 10⁶ nodes).
        const GALERKIN_CHUNK: usize = 256;
        debug_assert_eq!(self.ncols, a.nrows);
        let (nc, m) = (self.nrows, p.ncols);
        // Row of A P within the current block, by row of A P (written before it is read),
        // and the last block (counted from 1) that read each row of A P.
        let mut local = vec![u32::MAX; a.nrows];
        let mut seen = vec![0u32; a.nrows];
        let mut ptr = Vec::with_capacity(nc + 1);
        ptr.push(0u32);
        // Grown block by block (amortised doubling; the result is a fraction of A P).
        let (mut cols, mut vals) = (Vec::new(), Vec::new());
        // Parallel tasks per block: a few per thread (each makes its own accumulator).
        let tasks = 2 * rayon::current_num_threads().max(1);
        for (b, c0) in (0..nc).step_by(block).enumerate() {
            let c1 = (c0 + block).min(nc);
            let stamp = b as u32 + 1;
            let mut rows = Vec::new();
            for &k in &self.cols[self.ptr[c0] as usize..self.ptr[c1] as usize] {
                if std::mem::replace(&mut seen[k as usize], stamp) != stamp {
                    rows.push(k);
                }
            }
            rows.sort_unstable();
            for (x, &k) in rows.iter().enumerate() {
                local[k as usize] = x as u32;
            }
            let ap = a.matmul_rows(p, rows.len(), |x| rows[x] as usize);
            drop(rows);
            let local = &local;
            let piece = Self::from_row_lengths_in(
                c1 - c0,
                m,
                GALERKIN_CHUNK,
                (c1 - c0).div_ceil(GALERKIN_CHUNK).div_ceil(tasks),
                || Accumulator::new(m),
                |acc, i| {
                    let (rc, _) = self.row(c0 + i);
                    rc.iter()
                        .map(|&k| {
                            let (bc, _) = ap.row(local[k as usize] as usize);
                            bc.iter().filter(|&&j| acc.mark(i, j)).count()
                        })
                        .sum()
                },
                |acc, i, cols, vals| {
                    let (rc, rv) = self.row(c0 + i);
                    for (&k, &r) in rc.iter().zip(rv) {
                        let (bc, bv) = ap.row(local[k as usize] as usize);
                        for (&j, &v) in bc.iter().zip(bv) {
                            acc.add(i, j, r * v);
                        }
                    }
                    acc.drain_sorted_into(cols, vals);
                },
            );
            drop(ap);
            let base = u64::from(*ptr.last().unwrap_or(&0));
            for &q in &piece.ptr[1..] {
                let total = base + u64::from(q);
                assert!(
                    u32::try_from(total).is_ok(),
                    "{total} entries: more than a u32 row pointer holds"
                );
                ptr.push(total as u32);
            }
            cols.extend_from_slice(&piece.cols);
            vals.extend_from_slice(&piece.vals);
        }
        cols.shrink_to_fit();
        vals.shrink_to_fit();
        Self {
            nrows: nc,
            ncols: m,
            ptr,
            cols,
            vals,
        }
    }
}

/// Dense scatter accumulator for one sparse row.
pub(crate) struct Accumulator {
    values: Vec<f64>,
    mark: Vec<usize>,
    touched: Vec<u32>,
}

impl Accumulator {
    /// For rows of `ncols` columns.
    pub fn new(ncols: usize) -> Self {
        Self {
            values: vec![0.0; ncols],
            mark: vec![usize::MAX; ncols],
            touched: Vec::new(),
        }
    }

    /// Adds v at column j of row `row` (rows must be distinct between drains).
    #[inline]
    pub fn add(&mut self, row: usize, j: u32, v: f64) {
        let ju = j as usize;
        if self.mark[ju] == row {
            self.values[ju] += v;
        } else {
            self.mark[ju] = row;
            self.values[ju] = v;
            self.touched.push(j);
        }
    }

    /// Marks column j as met in row `row` of a symbolic pass (each row marked once);
    /// true the first time.
    #[inline]
    pub fn mark(&mut self, row: usize, j: u32) -> bool {
        // The symbolic pass marks with a tag no row index nor the cleared mark takes, so
        // that the numeric pass of the same row starts afresh.
        let tag = usize::MAX - 1 - row;
        let m = &mut self.mark[j as usize];
        if *m == tag {
            false
        } else {
            *m = tag;
            true
        }
    }

    /// Appends the row's entries (sorted columns), and resets.
    pub fn drain_sorted_append(&mut self, cols: &mut Vec<u32>, vals: &mut Vec<f64>) {
        self.touched.sort_unstable();
        for &j in &self.touched {
            cols.push(j);
            vals.push(self.values[j as usize]);
            self.mark[j as usize] = usize::MAX;
        }
        self.touched.clear();
    }

    /// Writes the row's entries (sorted columns) into slices of exactly their count, and
    /// resets.
    pub fn drain_sorted_into(&mut self, cols: &mut [u32], vals: &mut [f64]) {
        debug_assert_eq!(self.touched.len(), cols.len());
        self.touched.sort_unstable();
        for ((&j, c), v) in self.touched.iter().zip(cols.iter_mut()).zip(vals.iter_mut()) {
            *c = j;
            *v = self.values[j as usize];
            self.mark[j as usize] = usize::MAX;
        }
        self.touched.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dense(a: &Csr) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; a.ncols]; a.nrows];
        for (i, row) in d.iter_mut().enumerate() {
            let (c, v) = a.row(i);
            for (&j, &x) in c.iter().zip(v) {
                row[j as usize] += x;
            }
        }
        d
    }

    fn small(nrows: usize, ncols: usize, seed: u64) -> Csr {
        let mut s = seed;
        let mut next = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 33) as usize
        };
        let rows: Vec<Vec<(u32, f64)>> = (0..nrows)
            .map(|_| {
                let mut r: Vec<(u32, f64)> = (0..3)
                    .map(|_| ((next() % ncols) as u32, (next() % 7) as f64 - 3.0))
                    .collect();
                r.sort_by_key(|e| e.0);
                r.dedup_by_key(|e| e.0);
                r
            })
            .collect();
        Csr::from_rows(
            nrows,
            ncols,
            || (),
            |_, i, c, v| {
                for &(j, x) in &rows[i] {
                    c.push(j);
                    v.push(x);
                }
            },
        )
    }

    #[test]
    fn products_and_transpose_match_dense_arithmetic() {
        let a = small(9, 7, 1);
        let b = small(7, 5, 2);
        let (da, db) = (dense(&a), dense(&b));
        let c = dense(&a.matmul(&b));
        for i in 0..9 {
            for j in 0..5 {
                let want: f64 = (0..7).map(|k| da[i][k] * db[k][j]).sum();
                assert_eq!(c[i][j], want);
            }
        }
        // R (A P) in blocks of rows, bit for bit the product of the stored A P.
        let p = small(7, 4, 3);
        let r = small(5, 9, 4);
        let want = r.matmul(&a.matmul(&p));
        for block in [1, 2, 3, 5, 8] {
            let got = r.galerkin_in_blocks(&a, &p, block);
            assert_eq!((&got.ptr, &got.cols), (&want.ptr, &want.cols), "block {block}");
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got.vals), bits(&want.vals), "block {block}");
        }
        assert_eq!(r.galerkin(&a, &p).vals, want.vals);
        let t = dense(&a.transpose());
        for i in 0..9 {
            for j in 0..7 {
                assert_eq!(t[j][i], da[i][j]);
            }
        }
        let x: Vec<f64> = (0..7).map(|k| k as f64 - 2.5).collect();
        let mut y = vec![0.0; 9];
        a.spmv(&x, &mut y);
        for i in 0..9 {
            assert_eq!(y[i], (0..7).map(|k| da[i][k] * x[k]).sum::<f64>());
        }
    }
}
