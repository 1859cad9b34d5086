//! Deterministic parallel helpers: fixed-size chunks, partial sums combined in chunk order,
//! so results are bitwise identical for any rayon thread count.

use rayon::prelude::*;

/// Rows (or vector entries) per parallel chunk. Fixed, so the reduction order is fixed.
pub const CHUNK: usize = 4096;

/// Fewest chunks one parallel task handles (32 768 rows): small problems then run on one
/// thread without synchronisation cost. Does not change results (the chunks stay fixed).
pub const MIN_TASK_CHUNKS: usize = 8;

/// Sums per-chunk partial results in chunk order (deterministic).
pub fn ordered_sum(partials: &[f64]) -> f64 {
    partials.iter().sum()
}

/// Sums per-chunk partial results of several quantities, each in chunk order
/// (deterministic, as [`ordered_sum`]).
pub fn ordered_sums<const K: usize>(partials: &[[f64; K]]) -> [f64; K] {
    std::array::from_fn(|k| partials.iter().map(|p| p[k]).sum())
}

/// Whether `len` entries are processed on the calling thread: at most one parallel task's
/// worth of chunks, where handing the work to the pool would cost more than it saves (and,
/// on a loaded machine, wait for a worker to be scheduled). Results are identical either
/// way: the chunks and the order of the partial results are the same.
pub(crate) fn sequential(len: usize) -> bool {
    len <= CHUNK * MIN_TASK_CHUNKS
}

/// `f(chunk index, chunk)` over the [`CHUNK`]-sized chunks of `y`, results in chunk order;
/// in parallel when `y` is larger than one task.
pub(crate) fn chunks_map<T, F>(y: &mut [f64], f: F) -> Vec<T>
where
    T: Send,
    F: Fn(usize, &mut [f64]) -> T + Sync + Send,
{
    if sequential(y.len()) {
        y.chunks_mut(CHUNK).enumerate().map(|(c, yc)| f(c, yc)).collect()
    } else {
        y.par_chunks_mut(CHUNK)
            .enumerate()
            .with_min_len(MIN_TASK_CHUNKS)
            .map(|(c, yc)| f(c, yc))
            .collect()
    }
}

/// As [`chunks_map`] over the matching chunks of two vectors of equal length.
pub(crate) fn chunks_map2<T, F>(x: &mut [f64], y: &mut [f64], f: F) -> Vec<T>
where
    T: Send,
    F: Fn(usize, &mut [f64], &mut [f64]) -> T + Sync + Send,
{
    debug_assert_eq!(x.len(), y.len());
    if sequential(y.len()) {
        x.chunks_mut(CHUNK)
            .zip(y.chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, (xc, yc))| f(c, xc, yc))
            .collect()
    } else {
        x.par_chunks_mut(CHUNK)
            .zip(y.par_chunks_mut(CHUNK))
            .enumerate()
            .with_min_len(MIN_TASK_CHUNKS)
            .map(|(c, (xc, yc))| f(c, xc, yc))
            .collect()
    }
}

/// Dot product a·b with a thread-count-independent summation order.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let chunk = |(x, y): (&[f64], &[f64])| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    let partials: Vec<f64> = if sequential(a.len()) {
        a.chunks(CHUNK).zip(b.chunks(CHUNK)).map(chunk).collect()
    } else {
        a.par_chunks(CHUNK)
            .zip(b.par_chunks(CHUNK))
            .with_min_len(MIN_TASK_CHUNKS)
            .map(chunk)
            .collect()
    };
    ordered_sum(&partials)
}
