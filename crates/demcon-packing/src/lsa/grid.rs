//! Uniform cell grid with doubly linked cell lists, for finding the particles whose
//! points lie near a given point. Periodic grids wrap; walled grids clamp to their box.

use demcon_core::{Aabb, Vec3};

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
    prev: Vec<u32>,
    cell_of: Vec<u32>,
}

impl CellGrid {
    /// A grid over `bounds` whose cells are at least `min_cell` (m) wide along every axis,
    /// for `n_particles` particles (none inserted yet). `max_cells` caps the total count.
    pub fn new(bounds: &Aabb, min_cell: f64, periodic: bool, n_particles: usize, max_cells: usize) -> Self {
        let ext = bounds.extent();
        let mut cell = min_cell;
        let dims = |cell: f64| [0, 1, 2].map(|k| ((ext[k] / cell).floor() as usize).clamp(1, 1 << 20));
        let mut n = dims(cell);
        while n[0] * n[1] * n[2] > max_cells.max(1) {
            cell *= 1.25;
            n = dims(cell);
        }
        Self {
            min: bounds.min,
            n,
            inv_h: [0, 1, 2].map(|k| n[k] as f64 / ext[k]),
            periodic,
            head: vec![NONE; n[0] * n[1] * n[2]],
            next: vec![NONE; n_particles],
            prev: vec![NONE; n_particles],
            cell_of: vec![NONE; n_particles],
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
        let h = self.head[c];
        self.next[i] = h;
        self.prev[i] = NONE;
        if h != NONE {
            self.prev[h as usize] = i as u32;
        }
        self.head[c] = i as u32;
        self.cell_of[i] = c as u32;
    }

    /// Takes particle `i` out of its cell.
    pub fn remove(&mut self, i: usize) {
        let c = self.cell_of[i] as usize;
        let (p, n) = (self.prev[i], self.next[i]);
        if p == NONE {
            self.head[c] = n;
        } else {
            self.next[p as usize] = n;
        }
        if n != NONE {
            self.prev[n as usize] = p;
        }
        self.cell_of[i] = NONE;
    }

    /// Calls `f(j)` for every particle in the cell of `p` and in the cells next to it
    /// (each particle once, also on periodic grids with fewer than three cells per axis).
    #[inline]
    pub fn for_each_near(&self, p: &Vec3, mut f: impl FnMut(usize)) {
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
                    let mut j = self.head[self.cell_index([x, y, z])];
                    while j != NONE {
                        f(j as usize);
                        j = self.next[j as usize];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

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

    #[test]
    fn finds_all_points_within_one_cell() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        for (periodic, len) in [(false, 10.0), (true, 10.0), (true, 2.5)] {
            let b = Aabb {
                min: Vec3::zeros(),
                max: Vec3::repeat(len),
            };
            let pts: Vec<Vec3> = (0..300)
                .map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * len)
                .collect();
            let mut g = CellGrid::new(&b, 1.0, periodic, pts.len(), 1 << 20);
            for (i, p) in pts.iter().enumerate() {
                g.insert(i, p);
            }
            // Move a few around.
            for (i, p) in pts.iter().enumerate().take(50) {
                g.remove(i);
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
}
