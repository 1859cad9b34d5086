//! Indexed 4-ary min-heap holding exactly one scheduled event time per particle.
//!
//! Keys are `(time, particle id)`, so ties are broken by id and the event order is
//! deterministic. Only `update` is needed: a particle's entry is re-keyed in place. The
//! entries carry their time next to the id (16 bytes), so the four children of a node
//! share one cache line and a sift reads no other array; half the levels of a binary heap.

/// Children per node.
const D: usize = 4;

/// One heap entry: scheduled time (time units) and particle id.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(16))]
struct Entry {
    t: f64,
    id: u32,
}

impl Entry {
    #[inline]
    fn less(&self, o: &Entry) -> bool {
        self.t < o.t || (self.t == o.t && self.id < o.id)
    }
}

/// One entry per particle, ordered by `(time, id)`.
#[derive(Debug, Clone)]
pub struct EventHeap {
    /// Heap array.
    heap: Vec<Entry>,
    /// Position of each particle in `heap`.
    pos: Vec<u32>,
}

impl EventHeap {
    /// A heap over particles `0..times.len()` with the given times.
    pub fn new(times: Vec<f64>) -> Self {
        let n = times.len();
        let mut h = Self {
            heap: times
                .iter()
                .enumerate()
                .map(|(i, &t)| Entry { t, id: i as u32 })
                .collect(),
            pos: (0..n as u32).collect(),
        };
        if n > 1 {
            for i in (0..=(n - 2) / D).rev() {
                h.sift_down(i);
            }
        }
        h
    }

    /// The particle with the earliest event and its time.
    #[inline]
    pub fn top(&self) -> (usize, f64) {
        let e = self.heap[0];
        (e.id as usize, e.t)
    }

    /// Re-keys particle `i` to `time`.
    #[inline]
    pub fn update(&mut self, i: usize, time: f64) {
        let p = self.pos[i] as usize;
        let old = self.heap[p].t;
        self.heap[p].t = time;
        if time < old {
            self.sift_up(p);
        } else {
            self.sift_down(p);
        }
    }

    fn sift_up(&mut self, mut p: usize) {
        let item = self.heap[p];
        while p > 0 {
            let parent = (p - 1) / D;
            let q = self.heap[parent];
            if !item.less(&q) {
                break;
            }
            self.heap[p] = q;
            self.pos[q.id as usize] = p as u32;
            p = parent;
        }
        self.heap[p] = item;
        self.pos[item.id as usize] = p as u32;
    }

    fn sift_down(&mut self, mut p: usize) {
        let n = self.heap.len();
        let item = self.heap[p];
        loop {
            let first = D * p + 1;
            if first >= n {
                break;
            }
            let last = (first + D).min(n);
            let mut c = first;
            for k in first + 1..last {
                if self.heap[k].less(&self.heap[c]) {
                    c = k;
                }
            }
            if !self.heap[c].less(&item) {
                break;
            }
            self.heap[p] = self.heap[c];
            self.pos[self.heap[p].id as usize] = p as u32;
            p = c;
        }
        self.heap[p] = item;
        self.pos[item.id as usize] = p as u32;
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
