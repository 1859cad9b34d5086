//! Neighbour lists stored flat: one 128-byte block per particle holding its scheduled event,
//! its bounding sphere (centre, radius), the list length and the first [`INLINE`] neighbour
//! ids; the rare longer lists continue in a per-particle spill vector.
//!
//! Processing an event reads the block of its particle (the event), and predicting the next
//! one reads it again (bounding sphere, neighbours): one pair of adjacent cache lines at an
//! address computed from the id, instead of an event array, a `Vec` header, the list and two
//! arrays for the bounding sphere, as `Vec<Vec<u32>>` did.

use std::collections::HashMap;

use demcon_core::Vec3;

use super::Ev;
use demcon_core::mem::{huge_filled, prefetch};

/// Neighbour ids stored in the block itself. Lists at φ ≈ 0.63 hold ~11 ids on average
/// (Gaussian 0.3, skin 0.4); a few % of the particles hold more than 20.
pub const INLINE: usize = 20;

/// Event, bounding sphere and neighbour list of one particle (two cache lines).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct Block {
    /// Bounding-sphere centre (m).
    c: Vec3,
    /// Bounding-sphere radius (m).
    rad: f64,
    /// Scheduled event.
    ev: Ev,
    /// Number of neighbours (inline and spilled).
    len: u32,
    ids: [u32; INLINE],
}

/// Bounding spheres and symmetric neighbour lists of all particles.
#[derive(Debug, Clone)]
pub struct NbLists {
    blocks: Vec<Block>,
    /// Neighbours beyond the first [`INLINE`], for the few particles that have them
    /// (looked up by id only, so the map's order never matters).
    spill: HashMap<u32, Vec<u32>>,
}

impl NbLists {
    /// Empty lists, bounding spheres of radius 0 at the origin, for `n` particles.
    pub fn new(n: usize) -> Self {
        Self {
            blocks: huge_filled(
                n,
                Block {
                    c: Vec3::zeros(),
                    rad: 0.0,
                    ev: Ev::Exit,
                    len: 0,
                    ids: [0; INLINE],
                },
            ),
            spill: HashMap::new(),
        }
    }

    /// Bounding sphere of `i`: centre (m) and radius (m).
    #[inline]
    pub fn sphere(&self, i: usize) -> (Vec3, f64) {
        let b = &self.blocks[i];
        (b.c, b.rad)
    }

    /// Sets the bounding sphere of `i`.
    #[inline]
    pub fn set_sphere(&mut self, i: usize, c: Vec3, rad: f64) {
        let b = &mut self.blocks[i];
        b.c = c;
        b.rad = rad;
    }

    /// Starts loading the block of `i` (both cache lines) into the cache.
    #[inline]
    pub fn prefetch(&self, i: usize) {
        let b = &self.blocks[i];
        prefetch(b);
        prefetch(&b.ids[INLINE - 1]);
    }

    /// Scheduled event of `i`.
    #[inline]
    pub fn event(&self, i: usize) -> Ev {
        self.blocks[i].ev
    }

    /// Sets the scheduled event of `i`.
    #[inline]
    pub fn set_event(&mut self, i: usize, ev: Ev) {
        self.blocks[i].ev = ev;
    }

    /// Number of neighbours of `i`.
    #[inline]
    pub fn len(&self, i: usize) -> usize {
        self.blocks[i].len as usize
    }

    /// Neighbours of `i`: the inline part and the spilled part.
    #[inline]
    pub fn get(&self, i: usize) -> (&[u32], &[u32]) {
        let b = &self.blocks[i];
        let len = b.len as usize;
        if len <= INLINE {
            (&b.ids[..len], &[])
        } else {
            (&b.ids[..], &self.spill[&(i as u32)][..])
        }
    }

    /// The neighbours of `i` held in its block (all of them up to [`INLINE`]).
    #[inline]
    pub fn inline_ids(&self, i: usize) -> &[u32] {
        let b = &self.blocks[i];
        &b.ids[..(b.len as usize).min(INLINE)]
    }

    /// Neighbour number `k` of `i`.
    #[inline]
    fn at(&self, i: usize, k: usize) -> u32 {
        if k < INLINE {
            self.blocks[i].ids[k]
        } else {
            self.spill[&(i as u32)][k - INLINE]
        }
    }

    /// Appends `j` to the list of `i`.
    #[inline]
    pub fn push(&mut self, i: usize, j: u32) {
        let b = &mut self.blocks[i];
        let len = b.len as usize;
        if len < INLINE {
            b.ids[len] = j;
        } else {
            self.spill.entry(i as u32).or_default().push(j);
        }
        b.len += 1;
    }

    /// Removes `j` from the list of `i` (the last entry takes its place); no-op if absent.
    pub fn remove(&mut self, i: usize, j: u32) {
        let len = self.len(i);
        let Some(k) = (0..len).find(|&k| self.at(i, k) == j) else {
            return;
        };
        let last = self.at(i, len - 1);
        if len > INLINE {
            let spill = self.spill.get_mut(&(i as u32)).expect("spilled list");
            spill.pop();
            if spill.is_empty() {
                self.spill.remove(&(i as u32));
            }
        }
        if k < len - 1 {
            if k < INLINE {
                self.blocks[i].ids[k] = last;
            } else {
                self.spill.get_mut(&(i as u32)).expect("spilled list")[k - INLINE] = last;
            }
        }
        self.blocks[i].len -= 1;
    }

    /// Moves the list of `i` into `out` (cleared first) and empties it.
    pub fn take(&mut self, i: usize, out: &mut Vec<u32>) {
        out.clear();
        let (a, b) = self.get(i);
        out.extend_from_slice(a);
        out.extend_from_slice(b);
        self.blocks[i].len = 0;
        self.spill.remove(&(i as u32));
    }

    /// Replaces the list of `i` by `list`.
    pub fn set(&mut self, i: usize, list: &[u32]) {
        self.blocks[i].len = 0;
        self.spill.remove(&(i as u32));
        for &j in list {
            self.push(i, j);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_is_two_cache_lines() {
        assert_eq!(std::mem::size_of::<Block>(), 128);
    }

    #[test]
    fn behaves_like_vectors() {
        let n = 5;
        let mut lists = NbLists::new(n);
        let mut want: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut x: u64 = 7;
        let mut rnd = |m: u64| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 33) % m
        };
        for step in 0..20_000 {
            let i = rnd(n as u64) as usize;
            match rnd(10) {
                0..=5 => {
                    let j = rnd(1000) as u32;
                    if !want[i].contains(&j) {
                        lists.push(i, j);
                        want[i].push(j);
                    }
                }
                6..=8 => {
                    if !want[i].is_empty() {
                        let k = rnd(want[i].len() as u64) as usize;
                        let j = want[i][k];
                        lists.remove(i, j);
                        want[i].swap_remove(k);
                    }
                }
                _ => {
                    let mut out = Vec::new();
                    lists.take(i, &mut out);
                    assert_eq!(out, want[i], "step {step}");
                    out.truncate(rnd(40) as usize);
                    lists.set(i, &out);
                    want[i] = out;
                }
            }
            let (a, b) = lists.get(i);
            let got: Vec<u32> = a.iter().chain(b).copied().collect();
            assert_eq!(got, want[i], "step {step}");
            assert_eq!(lists.len(i), want[i].len());
        }
    }
}
