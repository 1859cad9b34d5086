//! The explicit step's kernel: forward Euler's update with its per-row coefficients
//! precomputed, in the layout the memory-bound sweep wants (rows in slices of four, sorted
//! by degree within windows, SELL-4-256), optional f32 weights, huge pages and software
//! prefetch. [`crate::run_explicit`] reads as forward Euler; this is how one step is made fast.

use demcon_core::check::{check_finite, check_len};
use demcon_core::mem::huge_filled;
use demcon_network::{
    CHUNK, MIN_TASK_CHUNKS, Network, NodeKind, SELL_LANES, prefetch_gathers, sliced_layout,
};
use rayon::prelude::*;

use crate::error::ThermalError;
use crate::system::ThermalSystem;

/// Storage of the contact conductances in the explicit step.
///
/// The step is memory-bound: at 10⁶ particles it streams its arrays at the machine's
/// bandwidth, so its speed is the bytes per contact (see `docs/performance.md`, issue 12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum WeightPrecision {
    /// w_pq = Δt H_pq/C_p in f64 (12 bytes per stored entry):
    /// T'_p = c_p T_p + Σ_q w_pq T_q + s_p, c_p = 1 − Σ_q w_pq.
    #[default]
    F64,
    /// H_pq rounded once to f32, the same value for (p, q) and (q, p) (8 bytes per stored
    /// entry, −25 % bytes per contact): T'_p = T_p + (Δt/C_p) Σ_q H̃_pq (T_q − T_p) + s_p.
    /// Because H̃ is symmetric, the energy Σ C_p T_p is conserved to f64 round-off exactly as
    /// with [`Self::F64`]; the conductances differ by ≤ 6·10⁻⁸ relative (f32 rounding), which
    /// moves the temperatures by the same relative order (measured: see
    /// `docs/performance.md`). Conductances outside f32's normal range are refused.
    F32,
}

/// Rows swept together by the explicit kernel (one slice). Rows are sorted by degree within
/// windows of [`demcon_network::SELL_WINDOW`] rows (a divisor of [`CHUNK`]), so the rows of a
/// slice have nearly the same number of entries and little padding is needed: the layout
/// of [`sliced_layout`], which the multigrid hierarchy shares.
const LANES: usize = SELL_LANES;

/// The explicit update with its per-row coefficients precomputed:
/// T'_p = c_p T_p + Σ_q w_pq T_q + s_p, with w_pq = Δt H_pq/C_p, c_p = 1 − Σ_q w_pq,
/// s_p = Δt Q_p/C_p on free rows and T'_p = T_p on the others. Rows are swept in parallel,
/// each summed in a fixed order (c_p T_p + s_p, then its neighbours in index order): results
/// do not depend on the thread count.
///
/// The sweep is memory-bound, so the layout is chosen for the bytes it moves and for the
/// work per row: rows are grouped in slices of four (sorted by degree within windows of 256
/// rows) whose entries are interleaved and padded to the slice's longest row with zero
/// weights (SELL-4-256 format). The four rows are summed side by side with one fixed-length
/// loop per slice: no per-row loop exit, four independent additions in flight. Per entry it
/// reads a u32 column and an f64 weight (12 bytes) and gathers T_q (from cache when the
/// particles are in a space-filling order); per row a u32 permutation index, c_p, T_p and
/// T'_p (and s_p only when some source is non-zero). Fixed and excluded rows carry no entry.
/// The entry streams live in huge pages, and from 2¹⁷ rows on the sweep prefetches the T_q
/// it will gather 128 entries ahead (results unchanged: both are hints to the machine).
#[derive(Debug, Clone)]
pub struct ExplicitStepper<'a> {
    net: std::marker::PhantomData<&'a Network>,
    n: usize,
    /// Row (node) at each sorted position; sorting stays within a window.
    perm: Vec<u32>,
    /// Start of each slice's entries (slice s holds sorted positions 4s..4s+4).
    slice_ptr: Vec<u32>,
    /// Neighbour of each slice entry (entry j of lane l at slice_ptr[s] + 4j + l).
    cols: Vec<u32>,
    /// The coefficients of each slice entry, 0 on padding.
    weights: Weights,
    /// s_p in sorted order, absent when every source is zero.
    source: Option<Vec<f64>>,
    /// Δt/C_p in sorted order on free rows, 0 on the others (s/(J/K)): turns a new source
    /// vector into s_p ([`Self::set_sources`]).
    scale: Vec<f64>,
    dt: f64,
}

/// The per-entry coefficients of the step, by [`WeightPrecision`].
#[derive(Debug, Clone)]
enum Weights {
    /// w_pq in f64, with c_p in sorted order.
    F64 { w: Vec<f64>, centre: Vec<f64> },
    /// H̃_pq in f32 (the row's factor Δt/C_p is `scale`).
    F32 { h: Vec<f32> },
}

impl<'a> ExplicitStepper<'a> {
    /// Precomputes the coefficients for step `dt` (s) on a checked `system`, with the
    /// sources Q_p (W per node; ignored at fixed and excluded nodes), weights in f64. `dt`
    /// is not checked against the bound here.
    ///
    /// # Errors
    /// Bad sources (length, non-finite values) or step, or a network whose padded entries
    /// exceed u32::MAX.
    pub fn new(system: &ThermalSystem<'a>, sources: &[f64], dt: f64) -> Result<Self, ThermalError> {
        Self::with_precision(system, sources, dt, WeightPrecision::F64)
    }

    /// As [`Self::new`], storing the conductances as `precision` says.
    ///
    /// # Errors
    /// Those of [`Self::new`]; with [`WeightPrecision::F32`], a conductance of a free row
    /// outside f32's normal range (named).
    pub fn with_precision(
        system: &ThermalSystem<'a>,
        sources: &[f64],
        dt: f64,
        precision: WeightPrecision,
    ) -> Result<Self, ThermalError> {
        let (net, conductances, capacities, constraints) = (
            system.network(),
            system.conductances(),
            system.capacities(),
            system.constraints(),
        );
        check_len("sources", sources.len(), net.n_nodes())?;
        check_finite("sources", sources)?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(ThermalError::invalid("dt", dt, "must be a finite time > 0 (s)"));
        }
        let kinds = constraints.kinds();
        let row_ptr = net.row_ptr();
        let entry_edges = net.entry_edges();
        let net_cols = net.cols();
        let n = net.n_nodes();
        let free = |p: usize| kinds[p] == NodeKind::Free;
        let degree = |p: usize| if free(p) { row_ptr[p + 1] - row_ptr[p] } else { 0 };
        // Sorted by degree (descending, ties by index) within each window, in slices.
        let (perm, slice_ptr) = sliced_layout(n, degree);
        let n_slices = slice_ptr.len() - 1;
        let total = slice_ptr[n_slices];
        if total > u32::MAX as usize {
            return Err(ThermalError::invalid(
                "network entries",
                total,
                "must fit in u32 (≤ 4 294 967 295, about 2·10⁹ contacts)",
            ));
        }
        // The entry streams and the temperatures in huge pages (`demcon_core::mem`): the
        // gathers of T_q then rarely miss the TLB.
        let mut cols = huge_filled(total, 0u32);
        let mut weights = huge_filled(total, 0.0f64);
        let mut centre = vec![1.0; n];
        let mut source = vec![0.0; n];
        let mut scale = vec![0.0; n];
        // Fill slice by slice (in parallel over slices: each owns its entry range).
        let mut slices_c: Vec<&mut [u32]> = Vec::with_capacity(n_slices);
        let mut slices_w: Vec<&mut [f64]> = Vec::with_capacity(n_slices);
        let (mut rest_c, mut rest_w) = (&mut cols[..], &mut weights[..]);
        for s in 0..n_slices {
            let len = slice_ptr[s + 1] - slice_ptr[s];
            let (hc, tc) = rest_c.split_at_mut(len);
            let (hw, tw) = rest_w.split_at_mut(len);
            slices_c.push(hc);
            slices_w.push(hw);
            rest_c = tc;
            rest_w = tw;
        }
        slices_c
            .into_par_iter()
            .zip(slices_w.into_par_iter())
            .zip(centre.par_chunks_mut(LANES))
            .zip(source.par_chunks_mut(LANES))
            .zip(scale.par_chunks_mut(LANES))
            .enumerate()
            .with_min_len(CHUNK / LANES)
            .for_each(|(s, ((((sc, sw), cc), ss), sa))| {
                for (l, ((c, src), sca)) in cc.iter_mut().zip(ss.iter_mut()).zip(sa.iter_mut()).enumerate() {
                    let p = perm[s * LANES + l] as usize;
                    // Padding points at the row itself with weight 0.
                    for j in (l..sc.len()).step_by(LANES) {
                        sc[j] = p as u32;
                    }
                    if !free(p) {
                        continue;
                    }
                    let a = dt / capacities[p];
                    let mut sum = 0.0;
                    let (lo, hi) = (row_ptr[p], row_ptr[p + 1]);
                    for (j, (&q, &e)) in net_cols[lo..hi].iter().zip(&entry_edges[lo..hi]).enumerate() {
                        let h = conductances[e as usize];
                        let w = a * h;
                        sc[LANES * j + l] = q;
                        // F32 keeps H itself (rounded below), the same for (p, q) and (q, p).
                        sw[LANES * j + l] = if precision == WeightPrecision::F32 { h } else { w };
                        sum += w;
                    }
                    *c = 1.0 - sum;
                    *src = a * sources[p];
                    *sca = a;
                }
            });
        let source = source.iter().any(|&v| v != 0.0).then_some(source);
        let weights = match precision {
            WeightPrecision::F64 => Weights::F64 { w: weights, centre },
            WeightPrecision::F32 => Weights::F32 {
                h: f32_weights(&weights)?,
            },
        };
        Ok(Self {
            net: std::marker::PhantomData,
            n,
            perm,
            slice_ptr: slice_ptr.iter().map(|&v| v as u32).collect(),
            cols,
            weights,
            source,
            scale,
            dt,
        })
    }

    /// Replaces the source term by `sources` (Q_p, W per node; values on fixed and excluded
    /// nodes are ignored), e.g. Joule heat re-evaluated during a run. O(n).
    ///
    /// # Errors
    /// A length other than one value per node, or a non-finite value.
    pub fn set_sources(&mut self, sources: &[f64]) -> Result<(), ThermalError> {
        check_len("sources", sources.len(), self.n)?;
        check_finite("sources", sources)?;
        let s: Vec<f64> = self
            .perm
            .par_iter()
            .zip(self.scale.par_iter())
            .with_min_len(CHUNK)
            .map(|(&p, &a)| a * sources[p as usize])
            .collect();
        self.source = s.iter().any(|&v| v != 0.0).then_some(s);
        Ok(())
    }

    /// The step (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Bytes one step moves at least (B): per stored entry (padding included) a u32 column
    /// and the weight, 8 bytes in f64 or 4 in f32; per row 4 (permutation) + 8 (c_p, or
    /// Δt/C_p with f32 weights) + 8 (read T_p) + 8 (write T'_p) + 8 (s_p, when present);
    /// plus 4 per slice. The gathers T_q are counted as cache hits. Divide by the step time
    /// for the achieved bandwidth.
    pub fn bytes_per_step(&self) -> f64 {
        let per_row = if self.source.is_some() { 36.0 } else { 28.0 };
        let per_entry = match self.weights {
            Weights::F64 { .. } => 12.0,
            Weights::F32 { .. } => 8.0,
        };
        per_entry * self.cols.len() as f64 + per_row * self.n as f64 + 4.0 * self.slice_ptr.len() as f64
    }

    /// Stored entries (contact weights and padding): twice the free-row contacts, plus the
    /// padding of each four-row slice to its longest row.
    pub fn stored_entries(&self) -> usize {
        self.cols.len()
    }

    /// How the conductances are stored.
    pub fn precision(&self) -> WeightPrecision {
        match self.weights {
            Weights::F64 { .. } => WeightPrecision::F64,
            Weights::F32 { .. } => WeightPrecision::F32,
        }
    }

    /// One step from `t_old` into `t_new` (K); returns the (min, max) of `t_new` and
    /// whether a non-finite value appeared. At scale, keep both in huge pages
    /// ([`demcon_core::mem::huge_copy`], as [`run_explicit`] does): at 10⁶ particles the
    /// gathers of T_q otherwise miss the TLB.
    ///
    /// # Panics
    /// If `t_old` or `t_new` does not have one value per node (an internal invariant of
    /// [`run_explicit`]).
    pub fn step(&self, t_old: &[f64], t_new: &mut [f64]) -> (f64, f64, bool) {
        if self.n >= PREFETCH_MIN_ROWS {
            self.sweep::<true>(t_old, t_new)
        } else {
            self.sweep::<false>(t_old, t_new)
        }
    }

    /// [`Self::step`], prefetching the gathers or not.
    fn sweep<const PREFETCH: bool>(&self, t_old: &[f64], t_new: &mut [f64]) -> (f64, f64, bool) {
        let n = self.n;
        assert!(t_old.len() == n && t_new.len() == n, "one temperature per node");
        let partials: Vec<(f64, f64, bool)> = t_new
            .par_chunks_mut(CHUNK)
            .enumerate()
            .with_min_len(MIN_TASK_CHUNKS)
            .map(|(c, out)| {
                let base = c * CHUNK;
                let end = base + out.len();
                let (mut lo, mut hi, mut bad) = (f64::INFINITY, f64::NEG_INFINITY, false);
                for s in base / LANES..end.div_ceil(LANES) {
                    let (a, b) = (self.slice_ptr[s] as usize, self.slice_ptr[s + 1] as usize);
                    let i0 = s * LANES;
                    let lanes = LANES.min(end - i0);
                    let mut acc = [0.0f64; LANES];
                    match &self.weights {
                        Weights::F64 { w, centre } => {
                            for (l, v) in acc.iter_mut().enumerate().take(lanes) {
                                let i = i0 + l;
                                let src = self.source.as_ref().map_or(0.0, |src| src[i]);
                                *v = centre[i] * t_old[self.perm[i] as usize] + src;
                            }
                            for (k, (cj, wj)) in self.cols[a..b]
                                .chunks_exact(LANES)
                                .zip(w[a..b].chunks_exact(LANES))
                                .enumerate()
                            {
                                if PREFETCH {
                                    prefetch_gathers(&self.cols, a + LANES * k + PREFETCH_AHEAD, t_old);
                                }
                                for ((v, &w), &q) in acc.iter_mut().zip(wj).zip(cj) {
                                    *v += w * t_old[q as usize];
                                }
                            }
                        }
                        Weights::F32 { h } => {
                            let mut tp = [0.0f64; LANES];
                            for (l, t) in tp.iter_mut().enumerate().take(lanes) {
                                *t = t_old[self.perm[i0 + l] as usize];
                            }
                            for (k, (cj, hj)) in self.cols[a..b]
                                .chunks_exact(LANES)
                                .zip(h[a..b].chunks_exact(LANES))
                                .enumerate()
                            {
                                if PREFETCH {
                                    prefetch_gathers(&self.cols, a + LANES * k + PREFETCH_AHEAD, t_old);
                                }
                                for (((v, &h), &q), &t) in acc.iter_mut().zip(hj).zip(cj).zip(&tp) {
                                    *v += f64::from(h) * (t_old[q as usize] - t);
                                }
                            }
                            for (l, v) in acc.iter_mut().enumerate().take(lanes) {
                                let i = i0 + l;
                                let src = self.source.as_ref().map_or(0.0, |src| src[i]);
                                *v = tp[l] + self.scale[i] * *v + src;
                            }
                        }
                    }
                    for (l, &v) in acc.iter().enumerate().take(lanes) {
                        out[self.perm[i0 + l] as usize - base] = v;
                        lo = lo.min(v);
                        hi = hi.max(v);
                        bad |= !v.is_finite();
                    }
                }
                (lo, hi, bad)
            })
            .collect();
        partials.iter().fold(
            (f64::INFINITY, f64::NEG_INFINITY, false),
            |(a, b, c), &(x, y, z)| (a.min(x), b.max(y), c | z),
        )
    }
}

/// How far ahead (stored entries, about 16 rows) the explicit sweep prefetches the
/// temperatures it will gather. At 10⁶ particles the 8 MB of temperatures are out of cache,
/// and the gathers of the neighbours that lie far in the index space wait on memory: the
/// out-of-order window alone does not reach them in time. In a standalone benchmark of the
/// kernel (10⁶ rows, 7.9·10⁶ entries, medians of 7 rounds, two threads) huge pages took the
/// step from 7.8 to 9.4·10⁸ contacts/s and this prefetch, 128 entries ahead, to
/// 10.5–11.1·10⁸; 32, 64 or 256 ahead gained less or the same. In the solver benchmark at
/// 10⁶: 5.5–5.7 → 8.1–8.3·10⁸ contacts/s (`docs/performance.md` §8, "Levers tried").
const PREFETCH_AHEAD: usize = 128;

/// Fewest rows from which the sweep prefetches (1 MB of temperatures). Below, the
/// temperatures stay in cache and the hints only cost instructions: at 10⁵ particles the
/// step was 13–17 % slower with them (`docs/performance.md` §8, "Levers tried").
const PREFETCH_MIN_ROWS: usize = 1 << 17;

/// The conductances H (W/K) rounded once to f32, in huge pages; refused outside f32's normal
/// range (0, padding, stays 0).
fn f32_weights(h: &[f64]) -> Result<Vec<f32>, ThermalError> {
    if let Some(k) = h
        .iter()
        .position(|&v| v != 0.0 && !(v.abs() >= f32::MIN_POSITIVE as f64 && v.abs() <= f32::MAX as f64))
    {
        return Err(ThermalError::invalid(
            "conductances",
            h[k],
            "must lie in f32's normal range (1.2e-38 to 3.4e38 W/K) for f32 weights; use WeightPrecision::F64",
        ));
    }
    let mut out = huge_filled(h.len(), 0.0f32);
    out.par_iter_mut()
        .zip(h.par_iter())
        .with_min_len(CHUNK)
        .for_each(|(o, &w)| *o = w as f32);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use demcon_network::{Constraints, FloatingPolicy, resolve_fixed};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Random network of `n` nodes with local and a few far links, degrees 0 to ~14.
    fn network(n: usize, seed: u64) -> (Network, Vec<f64>, Vec<f64>, Vec<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut edges = Vec::new();
        for p in 0..n {
            for _ in 0..rng.random_range(0..8usize) {
                let q = if rng.random::<f64>() < 0.9 {
                    (p + rng.random_range(1..40usize)).min(n - 1)
                } else {
                    rng.random_range(0..n)
                };
                if q != p {
                    edges.push([p as u32, q as u32]);
                }
            }
        }
        let g = (0..edges.len()).map(|_| rng.random_range(0.1..3.0)).collect();
        let caps = (0..n).map(|_| rng.random_range(5.0..50.0)).collect();
        let q = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        (Network::new(n, &edges).unwrap(), g, caps, q)
    }

    /// The update written row by row from the network's compressed rows, in the order the
    /// stepper promises (c_p T_p + s_p, then neighbours in index order).
    fn reference(
        net: &Network,
        g: &[f64],
        caps: &[f64],
        c: &Constraints,
        q: &[f64],
        dt: f64,
        t: &[f64],
    ) -> Vec<f64> {
        (0..net.n_nodes())
            .map(|p| {
                if c.kinds()[p] != NodeKind::Free {
                    return t[p];
                }
                let a = dt / caps[p];
                let range = net.row_ptr()[p]..net.row_ptr()[p + 1];
                let w: Vec<f64> = net.entry_edges()[range.clone()]
                    .iter()
                    .map(|&e| a * g[e as usize])
                    .collect();
                let mut sum = 0.0;
                w.iter().for_each(|v| sum += v);
                let mut s = (1.0 - sum) * t[p] + a * q[p];
                for (&col, wk) in net.cols()[range].iter().zip(&w) {
                    s += wk * t[col as usize];
                }
                s
            })
            .collect()
    }

    #[test]
    fn sliced_kernel_matches_the_row_formula_bit_for_bit_for_any_thread_count() {
        // 40 003 nodes: not a multiple of the slice width, more than one parallel task.
        let n = 40_003;
        let (net, g, caps, q) = network(n, 3);
        let fixed: Vec<u32> = (0..n as u32).step_by(97).collect();
        let c = resolve_fixed(&net, &[(fixed, 2.0)], FloatingPolicy::Keep).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let t: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..4.0)).collect();
        let dt = 0.5;
        for sources in [q.clone(), vec![0.0; n]] {
            let system = ThermalSystem::new(&net, &g, &caps, &c).unwrap();
            let st = ExplicitStepper::new(&system, &sources, dt).unwrap();
            let want = reference(&net, &g, &caps, &c, &sources, dt, &t);
            for threads in [1, 3] {
                let mut out = vec![0.0; n];
                let (lo, hi, bad) = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| st.step(&t, &mut out));
                assert_eq!(out, want, "{threads} threads");
                assert!(!bad);
                assert_eq!(lo, want.iter().cloned().fold(f64::INFINITY, f64::min));
                assert_eq!(hi, want.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
            }
            // Padding stays small: fewer than 10 % extra entries over the free rows'.
            let useful: usize = (0..n)
                .filter(|&p| c.kinds()[p] == NodeKind::Free)
                .map(|p| net.degree(p))
                .sum();
            assert!(st.stored_entries() >= useful);
            assert!(
                (st.stored_entries() as f64) < 1.1 * useful as f64,
                "{} vs {useful}",
                st.stored_entries()
            );
        }
        // A non-finite temperature is flagged.
        let system = ThermalSystem::new(&net, &g, &caps, &c).unwrap();
        let st = ExplicitStepper::new(&system, &q, dt).unwrap();
        let mut t_bad = t.clone();
        t_bad[n - 1] = f64::NAN;
        let mut out = vec![0.0; n];
        assert!(st.step(&t_bad, &mut out).2);
    }

    /// The f32 update written row by row: T_p + (Δt/C_p) Σ_q f32(H_pq) (T_q − T_p) + Δt Q_p/C_p,
    /// neighbours in index order.
    fn reference_f32(
        net: &Network,
        g: &[f64],
        caps: &[f64],
        c: &Constraints,
        q: &[f64],
        dt: f64,
        t: &[f64],
    ) -> Vec<f64> {
        (0..net.n_nodes())
            .map(|p| {
                if c.kinds()[p] != NodeKind::Free {
                    return t[p];
                }
                let a = dt / caps[p];
                let range = net.row_ptr()[p]..net.row_ptr()[p + 1];
                let mut acc = 0.0;
                for (&col, &e) in net.cols()[range.clone()].iter().zip(&net.entry_edges()[range]) {
                    acc += f64::from(g[e as usize] as f32) * (t[col as usize] - t[p]);
                }
                t[p] + a * acc + a * q[p]
            })
            .collect()
    }

    #[test]
    fn f32_kernel_matches_its_row_formula_bit_for_bit_for_any_thread_count() {
        let n = 40_003;
        let (net, g, caps, q) = network(n, 5);
        let fixed: Vec<u32> = (0..n as u32).step_by(89).collect();
        let c = resolve_fixed(&net, &[(fixed, 2.0)], FloatingPolicy::Keep).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let t: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..4.0)).collect();
        let dt = 0.5;
        for sources in [q.clone(), vec![0.0; n]] {
            let system = ThermalSystem::new(&net, &g, &caps, &c).unwrap();
            let st = ExplicitStepper::with_precision(&system, &sources, dt, WeightPrecision::F32).unwrap();
            assert_eq!(st.precision(), WeightPrecision::F32);
            let want = reference_f32(&net, &g, &caps, &c, &sources, dt, &t);
            for threads in [1, 3] {
                let mut out = vec![0.0; n];
                let (lo, hi, bad) = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| st.step(&t, &mut out));
                assert_eq!(out, want, "{threads} threads");
                assert!(!bad);
                assert_eq!(lo, want.iter().cloned().fold(f64::INFINITY, f64::min));
                assert_eq!(hi, want.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
            }
        }
        // Conductances f32 cannot hold are refused, not flushed to zero.
        let tiny = vec![1e-300; g.len()];
        let system = ThermalSystem::new(&net, &tiny, &caps, &c).unwrap();
        let e = ExplicitStepper::with_precision(&system, &q, dt, WeightPrecision::F32).unwrap_err();
        assert!(e.to_string().contains("f32"), "{e}");
    }

    /// Adiabatic walls, no source: Σ C_p T_p is conserved to round-off with either
    /// precision (f32 conductances are symmetric), and the f32 run stays within the f32
    /// rounding of the conductances of the f64 run.
    #[test]
    fn both_precisions_conserve_energy_and_agree() {
        let n = 20_000;
        let (net, g, caps, _) = network(n, 7);
        let c = resolve_fixed(&net, &[], FloatingPolicy::Keep).unwrap();
        let system = ThermalSystem::new(&net, &g, &caps, &c).unwrap();
        let dt = 0.8 * system.stable_dt_bound().dt_max;
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let t0: Vec<f64> = (0..n).map(|_| rng.random_range(250.0..350.0)).collect();
        let energy = |t: &[f64]| t.iter().zip(&caps).map(|(t, c)| t * c).sum::<f64>();
        let e0 = energy(&t0);
        let mut runs = Vec::new();
        for precision in [WeightPrecision::F64, WeightPrecision::F32] {
            let st = ExplicitStepper::with_precision(&system, &vec![0.0; n], dt, precision).unwrap();
            let (mut a, mut b) = (t0.clone(), vec![0.0; n]);
            for _ in 0..500 {
                st.step(&a, &mut b);
                std::mem::swap(&mut a, &mut b);
            }
            let drift = (energy(&a) - e0).abs() / e0;
            assert!(drift < 1e-13, "{precision:?}: relative energy drift {drift:e}");
            runs.push(a);
        }
        let diff = runs[0]
            .iter()
            .zip(&runs[1])
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        // 100 K of initial spread, conductances perturbed by ≤ 6e-8 relative.
        assert!(diff < 100.0 * 1e-7, "max |T_f32 − T_f64| = {diff:e} K");
        assert!(diff > 0.0);
    }
}
