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

/// Dot product a·b with a thread-count-independent summation order.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let partials: Vec<f64> = a
        .par_chunks(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .with_min_len(MIN_TASK_CHUNKS)
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>())
        .collect();
    ordered_sum(&partials)
}
