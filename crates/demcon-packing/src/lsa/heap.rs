//! Indexed 8-ary min-heap holding exactly one scheduled event time per particle.
//!
//! Keys are `(time, particle id)`, so ties are broken by id and the event order is
//! deterministic. Only `update` is needed: a particle's entry is re-keyed in place. The
//! entries carry their time next to the id (16 bytes) and the eight children of a node fill
//! one 128-byte aligned group (two adjacent cache lines), so a level of a sift reads one
//! group and no other array; a third of the levels of a binary heap.

use super::huge::{huge_filled, huge_vec};

/// Children per node.
const D: usize = 8;

/// One heap entry: scheduled time (time units) and particle id.
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

/// The `D` children of one node, aligned to two cache lines.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(128))]
struct Group([Entry; D]);

/// One entry per particle, ordered by `(time, id)`.
///
/// Node `k` (root 0) is stored at slot `k + D − 1`, so the children of `k`, nodes
/// `Dk + 1 … Dk + D`, are exactly group `k + 1`; the first `D − 1` slots are unused.
#[derive(Debug, Clone)]
pub struct EventHeap {
    groups: Vec<Group>,
    /// Number of entries.
    n: usize,
    /// Node of each particle.
    pos: Vec<u32>,
}

impl EventHeap {
    /// A heap over particles `0..times.len()` with the given times.
    pub fn new(times: Vec<f64>) -> Self {
        let n = times.len();
        let empty = Entry {
            t: f64::INFINITY,
            id: u32::MAX,
        };
        let mut h = Self {
            groups: huge_filled((n + D - 1).div_ceil(D).max(1), Group([empty; D])),
            n,
            pos: huge_vec(0..n as u32),
        };
        for (i, &t) in times.iter().enumerate() {
            h.put(i, Entry { t, id: i as u32 });
        }
        if n > 1 {
            for k in (0..=(n - 2) / D).rev() {
                h.sift_down(k);
            }
        }
        h
    }

    #[inline]
    fn at(&self, k: usize) -> Entry {
        let s = k + D - 1;
        self.groups[s / D].0[s % D]
    }

    #[inline]
    fn put(&mut self, k: usize, e: Entry) {
        let s = k + D - 1;
        self.groups[s / D].0[s % D] = e;
        self.pos[e.id as usize] = k as u32;
    }

    /// The particle with the earliest event and its time.
    #[inline]
    pub fn top(&self) -> (usize, f64) {
        let e = self.at(0);
        (e.id as usize, e.t)
    }

    /// The particle with the second-earliest event (the earliest among the root's children),
    /// usually the next to be processed; `None` below two entries.
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

    /// Re-keys particle `i` to `time`.
    #[inline]
    pub fn update(&mut self, i: usize, time: f64) {
        debug_assert!(time >= 0.0, "event times are non-negative");
        let k = self.pos[i] as usize;
        let old = self.at(k).t;
        let e = Entry {
            t: time,
            id: i as u32,
        };
        if time < old {
            self.sift_up(k, e);
        } else {
            let s = k + D - 1;
            self.groups[s / D].0[s % D] = e;
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn behaves_like_a_sorted_list() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let n = 200;
        let mut keys: Vec<f64> = (0..n).map(|_| rng.random::<f64>()).collect();
        let mut h = EventHeap::new(keys.clone());
        for step in 0..5000 {
            let (i, t) = h.top();
            let (j, tj) = keys
                .iter()
                .enumerate()
                .map(|(j, &k)| (j, k))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                .unwrap();
            assert_eq!((i, t), (j, tj), "step {step}");
            // The runner-up is the second-earliest entry.
            let second = (0..n)
                .filter(|&q| q != j)
                .min_by(|&a, &b| keys[a].total_cmp(&keys[b]).then(a.cmp(&b)));
            assert_eq!(h.runner_up(), second, "step {step}");
            let k = rng.random_range(0..n);
            // Mix of increases, decreases and ties.
            let nt = if step % 7 == 0 {
                0.5
            } else {
                rng.random::<f64>() * 2.0
            };
            keys[k] = nt;
            h.update(k, nt);
        }
    }
}
