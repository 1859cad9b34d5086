//! The event queue: exactly one scheduled event time per particle, popped in `(time, id)`
//! order. The near future sits in a small indexed 8-ary heap, the rest in a two-level calendar
//! of time buckets (after Paul 2007, as Smallenburg 2022 uses it for event-driven hard spheres).
//!
//! Time is cut into buckets of width `w` (time units), and runs of [`FINE`] buckets into laps.
//! The heap holds every event whose bucket is at most the current one, `cur`; a later event of
//! the current lap waits, unsorted, in its bucket's list, an event of the next [`COARSE`] − 1
//! laps in its lap's list, and anything further in an overflow list. When the heap runs empty,
//! `cur` moves on and that bucket's list is poured into the heap; at the start of each lap its
//! list is sorted out into the buckets, and every [`COARSE`] laps the overflow list into the
//! laps. The bucket of a time is monotone in the time, so every event in the heap precedes
//! every event outside it, and the pops come in exactly the order a heap over all particles
//! gives (ties broken by id).
//!
//! Why: in a heap over all `N` particles a sift is a chain of dependent loads through
//! `log₈ N` levels spread over 16 N bytes (1.6 MB at 10⁵, 16 MB at 10⁶), each a likely cache
//! miss. Here the heap holds a few hundred events (a few kB), an event scheduled ahead is
//! appended to one of 2 × 512 lists whose ends stay in cache, and sorting a list out reads the
//! particles' records independently of each other, so those loads overlap.
//!
//! Entries are not removed from the lists when a particle is rescheduled: each particle's
//! record says where its live entry is and carries its time, and entries that no longer match
//! are dropped when their list is sorted out. The width is chosen at every rebuild (the packer
//! rebuilds at each thermostat rescale) so that about [`NEAR`] events fall in a bucket.

use demcon_core::mem::{huge_filled, prefetch};

/// Children per heap node.
const D: usize = 8;

/// Events per bucket the width aims at: enough that pours are rare, few enough that the heap
/// stays in L1 (three levels of 8).
const NEAR: usize = 256;

/// Buckets per lap (a power of two).
const FINE: u64 = 512;

/// Laps held in lists ahead of the overflow list (a power of two).
const COARSE: u64 = 512;

/// Where a particle's live entry is: in the heap (at `Rec::pos`), in a bucket's list, in a
/// lap's list, or in the overflow list.
const IN_HEAP: u32 = 0;
const IN_BUCKET: u32 = 1;
const IN_LAP: u32 = 2;
const IN_OVERFLOW: u32 = 3;

/// One entry: scheduled time (time units) and particle id.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(16))]
struct Entry {
    t: f64,
    id: u32,
}

impl Entry {
    /// `(time, id)` as one integer: the bits of a non-negative `f64` (infinity included)
    /// order like the numbers, so comparing keys needs no branch.
    #[inline]
    fn key(&self) -> u128 {
        ((self.t.to_bits() as u128) << 32) | self.id as u128
    }

    #[inline]
    fn less(&self, o: &Entry) -> bool {
        self.key() < o.key()
    }
}

/// The `D` children of one heap node, aligned to two cache lines.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(128))]
struct Group([Entry; D]);

const EMPTY: Entry = Entry {
    t: f64::INFINITY,
    id: u32::MAX,
};

/// Per particle: its scheduled time, where the live entry is, and its heap node when there.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(16))]
struct Rec {
    t: f64,
    pos: u32,
    loc: u32,
}

/// One scheduled event per particle, ordered by `(time, id)`.
///
/// Heap node `k` (root 0) is stored at slot `k + D − 1`, so the children of `k`, nodes
/// `Dk + 1 … Dk + D`, are exactly group `k + 1`; the first `D − 1` slots are unused.
#[derive(Debug, Clone)]
pub struct EventQueue {
    groups: Vec<Group>,
    /// Number of heap entries.
    n: usize,
    rec: Vec<Rec>,
    /// Lists of the buckets of the current lap: bucket `b` is `buckets[b % FINE]`.
    buckets: Vec<Vec<Entry>>,
    /// Lists of the next `COARSE − 1` laps: lap `l` is `laps[l % COARSE]`.
    laps: Vec<Vec<Entry>>,
    overflow: Vec<Entry>,
    /// Time at which bucket 0 starts (time units).
    origin: f64,
    /// 1 / bucket width (per time unit); 0 puts every finite time in bucket 0.
    inv_w: f64,
    /// The current bucket: the heap holds every event of buckets `≤ cur`.
    cur: u64,
    /// Lap at which the overflow list is next sorted out (all its entries lie at or after it).
    next_sort: u64,
    /// Live entries outside the heap: in bucket lists, in lap lists, in the overflow list.
    in_buckets: usize,
    in_laps: usize,
    in_overflow: usize,
}

impl EventQueue {
    /// A queue over particles `0..times.len()` with the given times (time units, ≥ 0); the
    /// bucket width is set from them.
    pub fn new(times: Vec<f64>) -> Self {
        let n = times.len();
        let (origin, w) = calendar_shape(&times);
        let mut q = Self {
            groups: vec![Group([EMPTY; D]); 1],
            n: 0,
            rec: huge_filled(
                n,
                Rec {
                    t: f64::INFINITY,
                    pos: u32::MAX,
                    loc: IN_OVERFLOW,
                },
            ),
            buckets: vec![Vec::new(); FINE as usize],
            laps: vec![Vec::new(); COARSE as usize],
            overflow: Vec::new(),
            origin,
            inv_w: if w > 0.0 { 1.0 / w } else { 0.0 },
            cur: 0,
            next_sort: COARSE,
            in_buckets: 0,
            in_laps: 0,
            in_overflow: 0,
        };
        for (i, &t) in times.iter().enumerate() {
            q.rec[i].t = t;
            let b = q.bucket(t);
            if b == 0 {
                q.push_unordered(i, t);
            } else {
                q.place_far(i, t, b);
            }
        }
        q.heapify();
        if q.n == 0 {
            q.refill();
        }
        q
    }

    /// The particle with the earliest event and its time.
    #[inline]
    pub fn top(&self) -> (usize, f64) {
        let e = self.at(0);
        (e.id as usize, e.t)
    }

    /// A particle with one of the next events: the earliest among the root's children, usually
    /// the second-earliest overall; `None` when the heap holds one entry. A hint only.
    #[inline]
    pub fn runner_up(&self) -> Option<usize> {
        if self.n < 2 {
            return None;
        }
        let g = &self.groups[1].0;
        let count = (self.n - 1).min(D);
        let best = g[..count].iter().min_by_key(|e| e.key())?;
        Some(best.id as usize)
    }

    /// Re-keys particle `i` to `time` (time units, not before the current top's time).
    #[inline]
    pub fn update(&mut self, i: usize, time: f64) {
        debug_assert!(time >= 0.0, "event times are non-negative");
        let Rec { pos, loc, .. } = self.rec[i];
        self.rec[i].t = time;
        let b = self.bucket(time);
        if loc == IN_HEAP {
            let k = pos as usize;
            if b <= self.cur {
                let e = Entry {
                    t: time,
                    id: i as u32,
                };
                if e.less(&self.at(k)) {
                    self.sift_up(k, e);
                } else {
                    self.set(k, e);
                    self.sift_down(k);
                }
                return;
            }
            self.remove(k);
            self.place_far(i, time, b);
            if self.n == 0 {
                self.refill();
            }
        } else {
            self.forget(loc);
            if b <= self.cur {
                self.insert(i, time);
            } else {
                self.place_far(i, time, b);
            }
        }
    }

    /// Bucket of time `t`: monotone in `t`; infinity (and anything past 2⁶⁴ widths) lands in
    /// the last bucket, `u64::MAX`.
    #[inline]
    fn bucket(&self, t: f64) -> u64 {
        // `as` saturates: negative → 0, too large or infinite → u64::MAX.
        ((t - self.origin) * self.inv_w) as u64
    }

    /// Lap of bucket `b`.
    #[inline]
    fn lap(b: u64) -> u64 {
        b / FINE
    }

    /// Counts a live entry outside the heap out of its place's tally.
    #[inline]
    fn forget(&mut self, loc: u32) {
        match loc {
            IN_BUCKET => self.in_buckets -= 1,
            IN_LAP => self.in_laps -= 1,
            _ => self.in_overflow -= 1,
        }
    }

    /// Files particle `i` (out of the heap, bucket `b > cur`) in its bucket's list,
    /// its lap's list or the overflow list.
    #[inline]
    fn place_far(&mut self, i: usize, t: f64, b: u64) {
        let e = Entry { t, id: i as u32 };
        let (lap, now) = (Self::lap(b), Self::lap(self.cur));
        let loc = if lap == now {
            self.in_buckets += 1;
            self.buckets[(b % FINE) as usize].push(e);
            IN_BUCKET
        } else if lap - now < COARSE {
            self.in_laps += 1;
            self.laps[(lap % COARSE) as usize].push(e);
            IN_LAP
        } else {
            self.in_overflow += 1;
            self.overflow.push(e);
            IN_OVERFLOW
        };
        self.rec[i].loc = loc;
    }

    /// Moves on to the next bucket with live entries and pours it into the (empty) heap.
    fn refill(&mut self) {
        while self.n == 0 && self.in_buckets + self.in_laps + self.in_overflow > 0 {
            if self.in_buckets > 0 {
                // A live entry lies ahead in this lap.
                self.cur += 1;
                let list = std::mem::take(&mut self.buckets[(self.cur % FINE) as usize]);
                self.sort_out(list, IN_BUCKET);
                continue;
            }
            // Nothing live in this lap's buckets (what is left there is dead): start the next
            // lap with live entries.
            self.buckets.iter_mut().for_each(Vec::clear);
            let lap = if self.in_laps > 0 {
                Self::lap(self.cur) + 1
            } else {
                self.overflow
                    .iter()
                    .filter(|e| self.live(e, IN_OVERFLOW))
                    .map(|e| Self::lap(self.bucket(e.t)))
                    .min()
                    .expect("live overflow entries")
            };
            self.cur = lap.saturating_mul(FINE);
            if lap >= self.next_sort {
                self.next_sort = lap.saturating_add(COARSE);
                let list = std::mem::take(&mut self.overflow);
                self.sort_out(list, IN_OVERFLOW);
            }
            let list = std::mem::take(&mut self.laps[(lap % COARSE) as usize]);
            self.sort_out(list, IN_LAP);
        }
    }

    /// Whether `e` is the live entry of its particle in the place `loc`.
    #[inline]
    fn live(&self, e: &Entry, loc: u32) -> bool {
        let r = &self.rec[e.id as usize];
        r.loc == loc && r.t.to_bits() == e.t.to_bits()
    }

    /// Sorts out a list taken from the place `loc`: its live entries of buckets `≤ cur` go to
    /// the heap (then heapified, when it was empty), the others to their bucket's, lap's or
    /// the overflow list; dead entries are dropped.
    fn sort_out(&mut self, list: Vec<Entry>, loc: u32) {
        // Records are read at random places: request each a few entries ahead.
        const AHEAD: usize = 8;
        let mut to_heap = false;
        for (q, e) in list.iter().enumerate() {
            if let Some(f) = list.get(q + AHEAD) {
                prefetch(&self.rec[f.id as usize]);
            }
            if !self.live(e, loc) {
                continue;
            }
            self.forget(loc);
            let b = self.bucket(e.t);
            if b <= self.cur {
                self.push_unordered(e.id as usize, e.t);
                to_heap = true;
            } else {
                self.place_far(e.id as usize, e.t, b);
            }
        }
        if to_heap {
            self.heapify();
        }
    }

    #[inline]
    fn at(&self, k: usize) -> Entry {
        let s = k + D - 1;
        self.groups[s / D].0[s % D]
    }

    /// Writes `e` at node `k` without touching its particle's record.
    #[inline]
    fn set(&mut self, k: usize, e: Entry) {
        let s = k + D - 1;
        self.groups[s / D].0[s % D] = e;
    }

    #[inline]
    fn put(&mut self, k: usize, e: Entry) {
        self.set(k, e);
        let r = &mut self.rec[e.id as usize];
        r.pos = k as u32;
        r.loc = IN_HEAP;
    }

    /// Appends particle `i` at the heap's end without ordering it (then [`Self::heapify`]).
    #[inline]
    fn push_unordered(&mut self, i: usize, t: f64) {
        let k = self.n;
        // Node k sits at slot k + D − 1, in group ⌈k / D⌉.
        if k.div_ceil(D) >= self.groups.len() {
            self.groups.push(Group([EMPTY; D]));
        }
        self.n += 1;
        self.put(k, Entry { t, id: i as u32 });
    }

    fn heapify(&mut self) {
        if self.n > 1 {
            for k in (0..=(self.n - 2) / D).rev() {
                self.sift_down(k);
            }
        }
    }

    #[inline]
    fn insert(&mut self, i: usize, t: f64) {
        self.push_unordered(i, t);
        let k = self.n - 1;
        self.sift_up(k, Entry { t, id: i as u32 });
    }

    /// Takes node `k` out of the heap (its particle's record is left to the caller).
    #[inline]
    fn remove(&mut self, k: usize) {
        self.n -= 1;
        if k == self.n {
            return;
        }
        let last = self.at(self.n);
        if last.less(&self.at(k)) {
            self.sift_up(k, last);
        } else {
            self.set(k, last);
            self.sift_down(k);
        }
    }

    fn sift_up(&mut self, mut k: usize, item: Entry) {
        while k > 0 {
            let parent = (k - 1) / D;
            let q = self.at(parent);
            if !item.less(&q) {
                break;
            }
            self.put(k, q);
            k = parent;
        }
        self.put(k, item);
    }

    fn sift_down(&mut self, mut k: usize) {
        let item = self.at(k);
        loop {
            let first = D * k + 1;
            if first >= self.n {
                break;
            }
            let g = &self.groups[k + 1].0;
            let count = (self.n - first).min(D);
            let (mut c, mut best) = (0, g[0].key());
            for (q, e) in g.iter().enumerate().take(count).skip(1) {
                let k = e.key();
                c = if k < best { q } else { c };
                best = best.min(k);
            }
            let child = g[c];
            if !child.less(&item) {
                break;
            }
            self.put(k, child);
            k = first + c;
        }
        self.put(k, item);
    }
}

/// Origin and bucket width (time units; width 0 for one bucket) for these event times: the
/// width holds about [`NEAR`] of the finite times past the earliest.
fn calendar_shape(times: &[f64]) -> (f64, f64) {
    let origin = times
        .iter()
        .copied()
        .filter(|t| t.is_finite())
        .fold(f64::INFINITY, f64::min);
    if !origin.is_finite() {
        return (0.0, 0.0);
    }
    let mut d: Vec<f64> = times
        .iter()
        .filter(|t| t.is_finite())
        .map(|t| t - origin)
        .collect();
    if d.len() <= 2 * NEAR {
        return (origin, 0.0);
    }
    let (_, &mut w, _) = d.select_nth_unstable_by(NEAR, f64::total_cmp);
    (origin, w.max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Drives the queue like the packer (pop the top, re-key it and a random partner to later
    /// times, `delay(rng, step)` ahead) and checks every top against a sorted list.
    fn check(n: usize, steps: usize, seed: u64, delay: impl Fn(&mut rand_chacha::ChaCha8Rng, usize) -> f64) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut keys: Vec<f64> = (0..n).map(|_| delay(&mut rng, 0)).collect();
        let mut q = EventQueue::new(keys.clone());
        for step in 0..steps {
            let (i, t) = q.top();
            let (j, tj) = keys
                .iter()
                .enumerate()
                .map(|(j, &k)| (j, k))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                .unwrap();
            assert_eq!((i, t), (j, tj), "step {step}");
            if let Some(r) = q.runner_up() {
                assert_ne!(r, i);
            }
            let now = t;
            // Mix of increases, ties, events at `now`, far ones and never.
            for k in [i, rng.random_range(0..n)] {
                let nt = match step % 11 {
                    0 => now,
                    5 => f64::INFINITY,
                    7 => now + 1e3 * delay(&mut rng, step),
                    9 => now + 1e7 * delay(&mut rng, step),
                    _ if k % 5 == 0 => (now * 8.0).round() / 8.0 + 0.125,
                    _ => now + delay(&mut rng, step),
                };
                keys[k] = nt;
                q.update(k, nt);
            }
        }
    }

    #[test]
    fn pops_in_the_order_of_a_sorted_list() {
        check(2000, 30_000, 3, |r, _| r.random::<f64>());
        check(3000, 30_000, 4, |r, _| -r.random::<f64>().ln());
        // Delays growing 10⁹-fold: the heap keeps running dry, later laps and the overflow
        // list are sorted out, and empty stretches are jumped.
        check(1500, 30_000, 8, |r, step| {
            r.random::<f64>() * 10f64.powf(step as f64 / 3000.0)
        });
    }

    #[test]
    fn small_and_degenerate_queues() {
        check(1, 100, 5, |r, _| r.random::<f64>());
        check(40, 2000, 6, |r, _| r.random::<f64>());
        // Everything never: the top is the lowest id at infinity.
        let q = EventQueue::new(vec![f64::INFINITY; 600]);
        assert_eq!(q.top(), (0, f64::INFINITY));
        // All at one time: one bucket.
        check(700, 3000, 7, |_, _| 1.0);
    }
}
