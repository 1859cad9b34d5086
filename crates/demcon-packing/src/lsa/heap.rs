//! Indexed binary min-heap holding exactly one scheduled event time per particle.
//!
//! Keys are `(time, particle id)`, so ties are broken by id and the event order is
//! deterministic. Only `update` is needed: a particle's entry is re-keyed in place.

/// One entry per particle, ordered by `(time, id)`.
#[derive(Debug, Clone)]
pub struct EventHeap {
    /// Heap array of particle ids.
    heap: Vec<u32>,
    /// Position of each particle in `heap`.
    pos: Vec<u32>,
    /// Scheduled time of each particle (time units).
    key: Vec<f64>,
}

impl EventHeap {
    /// A heap over particles `0..times.len()` with the given times.
    pub fn new(times: Vec<f64>) -> Self {
        let n = times.len();
        let mut h = Self {
            heap: (0..n as u32).collect(),
            pos: (0..n as u32).collect(),
            key: times,
        };
        for i in (0..n / 2).rev() {
            h.sift_down(i);
        }
        h
    }

    #[inline]
    fn less(&self, a: u32, b: u32) -> bool {
        let (ka, kb) = (self.key[a as usize], self.key[b as usize]);
        ka < kb || (ka == kb && a < b)
    }

    /// The particle with the earliest event and its time.
    #[inline]
    pub fn top(&self) -> (usize, f64) {
        let i = self.heap[0] as usize;
        (i, self.key[i])
    }

    /// Re-keys particle `i` to `time`.
    #[inline]
    pub fn update(&mut self, i: usize, time: f64) {
        let old = self.key[i];
        self.key[i] = time;
        let p = self.pos[i] as usize;
        if time < old {
            self.sift_up(p);
        } else {
            self.sift_down(p);
        }
    }

    fn sift_up(&mut self, mut p: usize) {
        let item = self.heap[p];
        while p > 0 {
            let parent = (p - 1) / 2;
            let q = self.heap[parent];
            if !self.less(item, q) {
                break;
            }
            self.heap[p] = q;
            self.pos[q as usize] = p as u32;
            p = parent;
        }
        self.heap[p] = item;
        self.pos[item as usize] = p as u32;
    }

    fn sift_down(&mut self, mut p: usize) {
        let n = self.heap.len();
        let item = self.heap[p];
        loop {
            let l = 2 * p + 1;
            if l >= n {
                break;
            }
            let r = l + 1;
            let c = if r < n && self.less(self.heap[r], self.heap[l]) {
                r
            } else {
                l
            };
            if !self.less(self.heap[c], item) {
                break;
            }
            self.heap[p] = self.heap[c];
            self.pos[self.heap[p] as usize] = p as u32;
            p = c;
        }
        self.heap[p] = item;
        self.pos[item as usize] = p as u32;
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
