//! Shared helpers of the criterion benchmarks (the benchmarks themselves are `[[bench]]` targets).
