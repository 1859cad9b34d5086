//! Uniform cell grids for finding the particles whose points lie near a given point:
//! a linked-list grid (insert only), an insert-only grid of placed spheres and a grid of
//! spheres stored contiguously per cell. Periodic grids wrap; walled grids clamp to their box.

use demcon_core::{Aabb, Vec3};

use demcon_core::mem::{huge_filled, prefetch};

const NONE: u32 = u32::MAX;

/// A uniform grid of cells over a box; each particle sits in exactly one cell.
#[derive(Debug, Clone)]
pub struct CellGrid {
    min: Vec3,
    /// Cells per axis.
    n: [usize; 3],
    /// Inverse cell edge per axis (1/m).
    inv_h: [f64; 3],
    periodic: bool,
    head: Vec<u32>,
    next: Vec<u32>,
}

impl CellGrid {
    /// A grid over `bounds` whose cells are at least `min_cell` (m) wide along every axis,
    /// for `n_particles` particles (none inserted yet). `max_cells` caps the total count.
    ///
    /// Never loops for ever and never allocates more than `max_cells` cells, whatever the
    /// sizes: at most 2²⁰ cells per axis, at most 200 widenings by 1.25, and a single cell
    /// when the sizes are degenerate (zero, subnormal, not finite), which is slow but correct.
    pub fn new(bounds: &Aabb, min_cell: f64, periodic: bool, n_particles: usize, max_cells: usize) -> Self {
        const PER_AXIS: f64 = (1u64 << 20) as f64;
        let ext = bounds.extent();
        let max_cells = max_cells.max(1);
        let dims = |cell: f64| {
            [0, 1, 2].map(|k| {
                let q = (ext[k] / cell).floor();
                if q.is_nan() {
                    1
                } else {
                    q.clamp(1.0, PER_AXIS) as usize
                }
            })
        };
        let e_max = ext.max();
        let mut cell = if min_cell.is_finite() && min_cell > 0.0 {
            min_cell
        } else {
            e_max
        };
        // Below e_max / 2²⁰ the per-axis cap decides anyway; starting there bounds the loop.
        cell = cell.max(e_max / PER_AXIS);
        let mut n = dims(cell);
        let mut rounds = 0;
        while n[0] * n[1] * n[2] > max_cells && rounds < 200 {
            cell *= 1.25;
            n = dims(cell);
            rounds += 1;
        }
        if n[0] * n[1] * n[2] > max_cells {
            n = [1, 1, 1];
        }
        Self {
            min: bounds.min,
            n,
            inv_h: [0, 1, 2].map(|k| n[k] as f64 / ext[k]),
            periodic,
            head: vec![NONE; n[0] * n[1] * n[2]],
            next: vec![NONE; n_particles],
        }
    }

    #[inline]
    fn coord(&self, p: &Vec3, k: usize) -> usize {
        let c = ((p[k] - self.min[k]) * self.inv_h[k]).floor();
        let n = self.n[k] as isize;
        let c = c as isize;
        if self.periodic {
            c.rem_euclid(n) as usize
        } else {
            c.clamp(0, n - 1) as usize
        }
    }

    #[inline]
    fn cell_index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.n[1] + c[1]) * self.n[0] + c[0]
    }

    /// Puts particle `i` (not in the grid) into the cell of point `p`.
    pub fn insert(&mut self, i: usize, p: &Vec3) {
        let c = self.cell_index([0, 1, 2].map(|k| self.coord(p, k)));
        self.next[i] = self.head[c];
        self.head[c] = i as u32;
    }

    /// Calls `f(j)` for every particle in the cell of `p` and in the cells next to it
    /// (each particle once, also on periodic grids with fewer than three cells per axis).
    #[inline]
    pub fn for_each_near(&self, p: &Vec3, mut f: impl FnMut(usize)) {
        self.for_each_cell_near(p, |c| {
            let mut j = self.head[c];
            while j != NONE {
                f(j as usize);
                j = self.next[j as usize];
            }
        });
    }

    /// Calls `f(cell)` for the cell of `p` and each distinct cell next to it.
    #[inline]
    fn for_each_cell_near(&self, p: &Vec3, mut f: impl FnMut(usize)) {
        let mut axes = [[0usize; 3]; 3];
        let mut counts = [0usize; 3];
        for k in 0..3 {
            let c = self.coord(p, k) as isize;
            let n = self.n[k] as isize;
            for d in -1..=1 {
                let mut q = c + d;
                if self.periodic {
                    q = q.rem_euclid(n);
                } else if q < 0 || q >= n {
                    continue;
                }
                let q = q as usize;
                if !axes[k][..counts[k]].contains(&q) {
                    axes[k][counts[k]] = q;
                    counts[k] += 1;
                }
            }
        }
        for &z in &axes[2][..counts[2]] {
            for &y in &axes[1][..counts[1]] {
                for &x in &axes[0][..counts[0]] {
                    f(self.cell_index([x, y, z]));
                }
            }
        }
    }
}

/// Insert-only grid of placed spheres for the random sequential addition that starts a
/// packing: each cell owns `cap` consecutive slots holding the exact centre and radius
/// (32 bytes; the extra spheres of a full cell go to its spill vector). A placement
/// test reads its cells' slots, one or two cache lines each, and stops at the first overlap,
/// instead of following linked lists into the particle arrays (at 10⁶ particles, ids placed
/// largest first lie at random in space and in memory: the placement took most of the 10 s
/// start, now 5 s of 7). Exact values, so the same placements as any exact test.
#[derive(Debug, Clone)]
pub struct PlacedGrid {
    index: CellGrid,
    cap: usize,
    /// Centre (m) and radius (m) of each slot.
    slots: Vec<[f64; 4]>,
    len: Vec<u32>,
    spill: Vec<Vec<[f64; 4]>>,
}

impl PlacedGrid {
    /// See [`CellGrid::new`].
    pub fn new(bounds: &Aabb, min_cell: f64, periodic: bool, n_particles: usize, max_cells: usize) -> Self {
        let index = CellGrid::new(bounds, min_cell, periodic, 0, max_cells);
        let n_cells = index.head.len();
        // The mean occupancy plus a margin, 2 to 16 slots (64–512 bytes).
        let cap = (n_particles / n_cells + 2).next_power_of_two().clamp(2, 16);
        Self {
            index,
            cap,
            slots: huge_filled(n_cells * cap, [0.0; 4]),
            len: vec![0; n_cells],
            spill: vec![Vec::new(); n_cells],
        }
    }

    /// Stores a sphere of centre `c` (m) and radius `rad` (m).
    pub fn insert(&mut self, c: &Vec3, rad: f64) {
        let k = self.index.cell_index([0, 1, 2].map(|a| self.index.coord(c, a)));
        let slot = [c.x, c.y, c.z, rad];
        let len = self.len[k] as usize;
        if len < self.cap {
            self.slots[k * self.cap + len] = slot;
        } else {
            self.spill[k].push(slot);
        }
        self.len[k] += 1;
    }

    /// Whether some stored sphere (centre c, radius ρ) in the cell of `p` or the cells next
    /// to it is closer than touching a sphere of radius `r` at `p`:
    /// |sep(c − p)|² < (r + ρ)², `sep` mapping a difference to its periodic image.
    #[inline]
    pub fn overlaps(&self, p: &Vec3, r: f64, sep: impl Fn(Vec3) -> Vec3) -> bool {
        let mut cells = [0usize; 27];
        let mut m = 0;
        self.index.for_each_cell_near(p, |k| {
            cells[m] = k;
            m += 1;
            prefetch(&self.len[k]);
            // (Two slots per cache line.)
            for q in (0..self.cap).step_by(2) {
                prefetch(&self.slots[k * self.cap + q]);
            }
        });
        let hit = |s: &[f64; 4]| {
            let d = sep(Vec3::new(s[0], s[1], s[2]) - p);
            let t = r + s[3];
            d.norm_squared() < t * t
        };
        cells[..m].iter().any(|&k| {
            let len = self.len[k] as usize;
            let base = k * self.cap;
            self.slots[base..base + len.min(self.cap)].iter().any(hit)
                || (len > self.cap && self.spill[k].iter().any(hit))
        })
    }
}

/// One sphere stored in a [`SphereGrid`] slot: centre relative to the grid's corner and
/// radius, in single precision (16 bytes; [`SphereGrid::slack`] covers the rounding).
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(16))]
struct Slot {
    c: [f32; 3],
    rad: f32,
}

/// Cell grid of spheres (bounding spheres of the neighbour lists). Each cell owns `cap`
/// consecutive slots (a row of cells along x is one stretch of memory), the ids in a parallel
/// array; the rare extra spheres of a full cell go to its spill vector. Positions and radii
/// are stored in `f32` (a query reads 16 bytes per candidate): callers widen their test by
/// [`slack`](Self::slack), so no overlapping pair is missed (a pair a hair apart may be
/// reported too).
#[derive(Debug, Clone)]
pub struct SphereGrid {
    index: CellGrid,
    cap: usize,
    slots: Vec<Slot>,
    ids: Vec<u32>,
    len: Vec<u32>,
    spill: Vec<Vec<(Slot, u32)>>,
    cell_of: Vec<u32>,
    slack: f64,
}

impl SphereGrid {
    /// See [`CellGrid::new`].
    pub fn new(bounds: &Aabb, min_cell: f64, periodic: bool, n_particles: usize, max_cells: usize) -> Self {
        let index = CellGrid::new(bounds, min_cell, periodic, 0, max_cells);
        let n_cells = index.head.len();
        // Twice the mean occupancy plus a margin, 4 to 16 slots (64–256 bytes).
        let cap = (2 * n_particles / n_cells + 4).next_power_of_two().clamp(4, 16);
        let ext = bounds.extent().max();
        Self {
            index,
            cap,
            slots: huge_filled(n_cells * cap, Slot::default()),
            ids: huge_filled(n_cells * cap, NONE),
            len: vec![0; n_cells],
            spill: vec![Vec::new(); n_cells],
            cell_of: vec![NONE; n_particles],
            // f32 rounding of coordinates below `ext` and radii: < 2·10⁻⁷ ext per distance.
            slack: if ext.is_finite() { 2e-6 * ext } else { 0.0 },
        }
    }

    /// Widening (m) a query must add to the sum of radii to cover the `f32` storage.
    #[inline]
    pub fn slack(&self) -> f64 {
        self.slack
    }

    /// Stores sphere `id` (not in the grid) with centre `c` and radius `rad`.
    pub fn insert(&mut self, id: usize, c: Vec3, rad: f64) {
        let k = self.index.cell_index([0, 1, 2].map(|a| self.index.coord(&c, a)));
        let r = c - self.index.min;
        let slot = Slot {
            c: [r.x as f32, r.y as f32, r.z as f32],
            rad: rad as f32,
        };
        let len = self.len[k] as usize;
        if len < self.cap {
            self.slots[k * self.cap + len] = slot;
            self.ids[k * self.cap + len] = id as u32;
        } else {
            self.spill[k].push((slot, id as u32));
        }
        self.len[k] += 1;
        self.cell_of[id] = k as u32;
    }

    /// Removes sphere `id` (the last sphere of its cell takes its place).
    pub fn remove(&mut self, id: usize) {
        let k = self.cell_of[id] as usize;
        self.cell_of[id] = NONE;
        let (cap, len) = (self.cap, self.len[k] as usize);
        let base = k * cap;
        let found = (0..len.min(cap))
            .find(|&q| self.ids[base + q] == id as u32)
            .or_else(|| {
                self.spill[k]
                    .iter()
                    .position(|e| e.1 == id as u32)
                    .map(|q| q + cap)
            });
        let Some(q) = found else {
            return;
        };
        let last = if len > cap {
            self.spill[k].pop().expect("spill holds the entries beyond cap")
        } else {
            (self.slots[base + len - 1], self.ids[base + len - 1])
        };
        if q < len - 1 {
            if q < cap {
                self.slots[base + q] = last.0;
                self.ids[base + q] = last.1;
            } else {
                self.spill[k][q - cap] = last;
            }
        }
        self.len[k] -= 1;
    }

    /// Calls `f(centre, radius, id)` for every sphere stored in the cell of `p` and the
    /// cells next to it (centre and radius as stored, in `f32` precision).
    #[inline]
    pub fn for_each_near(&self, p: &Vec3, mut f: impl FnMut(Vec3, f64, u32)) {
        // First start loading every cell's count, slots and ids, then read them: the
        // cells are in up to nine places in memory, each load otherwise waited for in turn.
        self.index.for_each_cell_near(p, |k| {
            let base = k * self.cap;
            prefetch(&self.len[k]);
            prefetch(&self.slots[base]);
            prefetch(&self.slots[base + self.cap - 1]);
            prefetch(&self.ids[base]);
        });
        let min = self.index.min;
        let mut visit = |s: &Slot, id: u32| {
            f(
                Vec3::new(s.c[0] as f64, s.c[1] as f64, s.c[2] as f64) + min,
                s.rad as f64,
                id,
            )
        };
        self.index.for_each_cell_near(p, |k| {
            let len = self.len[k] as usize;
            let base = k * self.cap;
            let m = len.min(self.cap);
            for (s, &id) in self.slots[base..base + m].iter().zip(&self.ids[base..base + m]) {
                visit(s, id);
            }
            if len > self.cap {
                for (s, id) in &self.spill[k] {
                    visit(s, *id);
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The box [0, len]³.
    fn cube(len: f64) -> Aabb {
        Aabb {
            min: Vec3::zeros(),
            max: Vec3::repeat(len),
        }
    }

    fn brute(points: &[Vec3], p: &Vec3, r: f64, period: Option<f64>) -> Vec<usize> {
        let mut v: Vec<usize> = (0..points.len())
            .filter(|&j| {
                let mut d = points[j] - p;
                if let Some(l) = period {
                    d = d.map(|x| x - l * (x / l).round());
                }
                d.norm() < r
            })
            .collect();
        v.sort();
        v
    }

    /// Fuzz finding: φ = 4.9e-324, a 1e-308 m sphere or 1e-300 m boxes made the cell
    /// size underflow and `new` widen it for ever.
    #[test]
    fn cell_grid_terminates_on_underflowing_sizes() {
        let cases = [
            (1.0, 0.0),
            (1.0, 4.9e-324),
            (1.0, f64::NAN),
            (1e-300, 1e-310),
            (1e-308, 1e-308),
            (0.0, 0.0),
            (1e300, 1e-300),
            (f64::INFINITY, 1.0),
        ];
        for (len, cell) in cases {
            let b = cube(len);
            for periodic in [false, true] {
                let mut g = CellGrid::new(&b, cell, periodic, 3, 64);
                assert!(g.head.len() <= 64, "{len} {cell}");
                for (i, p) in [Vec3::zeros(), Vec3::repeat(len * 0.5), Vec3::repeat(len)]
                    .iter()
                    .enumerate()
                {
                    g.insert(i, p);
                }
                let mut found = 0;
                g.for_each_near(&Vec3::zeros(), |_| found += 1);
                assert!(found >= 1);
            }
        }
    }

    /// Insert, remove (also from full cells, through the spill) and query against brute force.
    #[test]
    fn sphere_grid_finds_every_overlapping_sphere() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for periodic in [false, true] {
            let len = 6.0;
            let b = Aabb {
                min: Vec3::repeat(-1.0),
                max: Vec3::repeat(len - 1.0),
            };
            let n = 400;
            let mut g = SphereGrid::new(&b, 1.0, periodic, n, 1 << 20);
            let mut c: Vec<Vec3> = Vec::new();
            let mut r: Vec<f64> = Vec::new();
            for i in 0..n {
                // Clustered points overfill some cells.
                let p = if i % 3 == 0 {
                    Vec3::repeat(0.2) + Vec3::new(rng.random(), rng.random(), rng.random()) * 0.5
                } else {
                    b.min + Vec3::new(rng.random(), rng.random(), rng.random()) * len
                };
                c.push(p);
                r.push(0.5 * rng.random::<f64>());
                g.insert(i, p, r[i]);
            }
            let mut alive = vec![true; n];
            for step in 0..600 {
                let i = rng.random_range(0..n);
                if alive[i] {
                    g.remove(i);
                } else {
                    g.insert(i, c[i], r[i]);
                }
                alive[i] = !alive[i];
                let q = rng.random_range(0..n);
                let mut found = Vec::new();
                g.for_each_near(&c[q], |_, _, id| found.push(id as usize));
                found.sort();
                let n_found = found.len();
                found.dedup();
                assert_eq!(found.len(), n_found, "duplicates");
                for j in 0..n {
                    let mut d = c[j] - c[q];
                    if periodic {
                        d = d.map(|x| x - len * (x / len).round());
                    }
                    if alive[j] && d.norm() < r[j] + r[q] {
                        assert!(found.binary_search(&j).is_ok(), "step {step}: {j} missed");
                    }
                    if !alive[j] {
                        assert!(found.binary_search(&j).is_err(), "step {step}: {j} removed");
                    }
                }
            }
        }
    }

    #[test]
    fn finds_all_points_within_one_cell() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        for (periodic, len) in [(false, 10.0), (true, 10.0), (true, 2.5)] {
            let b = cube(len);
            let pts: Vec<Vec3> = (0..300)
                .map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * len)
                .collect();
            let mut g = CellGrid::new(&b, 1.0, periodic, pts.len(), 1 << 20);
            for (i, p) in pts.iter().enumerate() {
                g.insert(i, p);
            }
            for p in pts.iter().take(40) {
                let mut found = vec![];
                g.for_each_near(p, |j| found.push(j));
                let n = found.len();
                found.sort();
                found.dedup();
                assert_eq!(found.len(), n, "duplicates");
                let want = brute(&pts, p, 1.0, periodic.then_some(len));
                assert!(want.iter().all(|j| found.binary_search(j).is_ok()));
            }
        }
    }

    /// The placement test against brute force: spheres of radius ≤ 0.5 in cells of 1,
    /// clustered so that some cells spill, in a walled and a periodic box (also with fewer
    /// than three cells per axis).
    #[test]
    fn placed_grid_reports_exactly_the_overlaps() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for (periodic, len) in [(false, 6.0), (true, 6.0), (true, 2.5)] {
            let b = cube(len);
            let n = 300;
            let mut g = PlacedGrid::new(&b, 1.0, periodic, n, 1 << 20);
            let sep = |d: Vec3| {
                if periodic {
                    d.map(|x| x - len * (x / len).round())
                } else {
                    d
                }
            };
            let mut placed: Vec<(Vec3, f64)> = Vec::new();
            for i in 0..n {
                let p = if i % 3 == 0 {
                    Vec3::repeat(0.2) + Vec3::new(rng.random(), rng.random(), rng.random()) * 0.5
                } else {
                    Vec3::new(rng.random(), rng.random(), rng.random()) * len
                };
                let r = 0.5 * rng.random::<f64>();
                let want = placed.iter().any(|(c, rc)| sep(c - p).norm() < r + rc);
                assert_eq!(g.overlaps(&p, r, sep), want, "sphere {i}");
                // Insert every sphere, overlapping or not, so that cells overfill.
                g.insert(&p, r);
                placed.push((p, r));
            }
        }
    }
}
