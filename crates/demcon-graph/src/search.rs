//! Candidate-pair search: every pair whose relative gap (d − R_p − R_q)/(R_p + R_q) is at
//! most ε, found by a uniform cell grid (the default) or by an rstar R-tree self-join.
//!
//! Both return the same pairs, sorted by (p, q) with p < q. The cell grid is the default
//! because it is faster on packings (uniform density, bounded radius ratio): see the
//! `contacts` criterion benchmark and the crate documentation for the measured figures.

use demcon_core::{CoreError, Vec3};
use rayon::prelude::*;
use rstar::RTree;
use rstar::primitives::{GeomWithData, Rectangle};

use crate::error::GraphError;

/// How candidate contact pairs are found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NeighbourSearch {
    /// Uniform grid of cubic cells at least one largest contact distance wide, particles
    /// binned by centre and visited in cell order (half shell), in parallel over cell ranges.
    #[default]
    CellGrid,
    /// rstar R-tree of the spheres' bounding boxes (inflated by 1 + ε), joined with itself;
    /// periodic images are inserted as ghost boxes. Single-threaded.
    RTree,
}

/// Relative gap of a pair: (d − R_p − R_q)/(R_p + R_q) (dimensionless). A pair is in contact
/// for a tolerance ε when this is ≤ ε; it is negative for overlapping spheres.
#[inline]
pub fn relative_gap(distance: f64, r_p: f64, r_q: f64) -> f64 {
    let s = r_p + r_q;
    (distance - s) / s
}

/// Vector from `a` to `b` (m); in a periodic box the minimum image, assuming both points
/// are wrapped into `[0, L)`. Exactly antisymmetric in `a` and `b`.
#[inline(always)]
pub(crate) fn separation(a: &Vec3, b: &Vec3, period: Option<&[f64; 3]>) -> Vec3 {
    let mut d = b - a;
    if let Some(l) = period {
        for k in 0..3 {
            let h = 0.5 * l[k];
            if d[k] > h {
                d[k] -= l[k];
            } else if d[k] < -h {
                d[k] += l[k];
            }
        }
    }
    d
}

/// `x` wrapped into `[0, l)` (m).
pub(crate) fn wrap(x: f64, l: f64) -> f64 {
    let r = x.rem_euclid(l);
    if r >= l { r - l } else { r }
}

/// A pair within the search tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Candidate {
    /// `p << 32 | q` with p < q: sorting by key sorts by (p, q).
    pub key: u64,
    /// Relative gap (d − R_p − R_q)/(R_p + R_q).
    pub rel_gap: f64,
}

impl Candidate {
    fn new(a: u32, b: u32, rel_gap: f64) -> Self {
        let (p, q) = if a < b { (a, b) } else { (b, a) };
        Self {
            key: ((p as u64) << 32) | q as u64,
            rel_gap,
        }
    }

    /// The smaller particle id.
    pub fn p(&self) -> u32 {
        (self.key >> 32) as u32
    }

    /// The larger particle id.
    pub fn q(&self) -> u32 {
        self.key as u32
    }
}

/// Margin on the prefilter distance so that rounding never drops a pair with rel ≤ ε.
const MARGIN: f64 = 1.0 + 1e-9;

/// Largest particle span and radius the search accepts (m): beyond, squared distances
/// overflow f64 and cell indices lose meaning.
pub(crate) const MAX_SPAN: f64 = 1e150;

/// Pairs with relative gap ≤ `eps`, sorted by key. `pos` must be wrapped into the period
/// when `period` is given, and every contact distance must stay under half the period.
///
/// Errors: a non-finite position or radius, or particles spanning more than [`MAX_SPAN`]
/// (named, with the value), instead of a panic or a meaningless grid.
pub(crate) fn candidates(
    method: NeighbourSearch,
    pos: &[Vec3],
    radii: &[f64],
    period: Option<[f64; 3]>,
    eps: f64,
) -> Result<Vec<Candidate>, GraphError> {
    check_span(pos, radii)?;
    Ok(match method {
        NeighbourSearch::CellGrid => grid_candidates(pos, radii, period, eps),
        NeighbourSearch::RTree => rtree_candidates(pos, radii, period, eps),
    })
}

/// Refuses non-finite centres or radii and spans above [`MAX_SPAN`].
fn check_span(pos: &[Vec3], radii: &[f64]) -> Result<(), GraphError> {
    for (i, (c, &r)) in pos.iter().zip(radii).enumerate() {
        // Written so that NaN fails too.
        if !(c.iter().all(|x| x.abs() <= MAX_SPAN) && r.abs() <= MAX_SPAN) {
            return Err(CoreError::invalid(
                format!("particles[{i}]"),
                format!("centre ({:e}, {:e}, {:e}) m, radius {r:e} m", c.x, c.y, c.z),
                format!("coordinates and radii must be finite and at most {MAX_SPAN:e} m in magnitude"),
            )
            .into());
        }
    }
    Ok(())
}

/// The cell grid: dimensions, cell widths, origin.
struct Grid {
    dims: [usize; 3],
    inv_width: [f64; 3],
    origin: Vec3,
    periodic: bool,
}

impl Grid {
    fn new(pos: &[Vec3], reach: f64, period: Option<[f64; 3]>) -> Self {
        let (origin, extent) = match period {
            Some(l) => (Vec3::zeros(), Vec3::new(l[0], l[1], l[2])),
            None => {
                let mut min = Vec3::repeat(f64::INFINITY);
                let mut max = Vec3::repeat(f64::NEG_INFINITY);
                for c in pos {
                    min = min.inf(c);
                    max = max.sup(c);
                }
                (min, max - min)
            }
        };
        // Never more than ~2 cells per particle: sparse sets get wider cells. Cell counts are
        // clamped before the cast (a tiny reach or a huge span once overflowed the index), the
        // width starts at span / max_cells and widens at most 200 times; a degenerate span
        // falls back to a single cell (slow, still exact).
        let max_cells = 2.0 * pos.len() as f64 + 64.0;
        let e_max = extent.max();
        let mut h = if reach.is_finite() && reach > 0.0 {
            reach
        } else {
            e_max
        };
        h = h.max(e_max / max_cells);
        let dims_for = |h: f64| -> [usize; 3] {
            std::array::from_fn(|k| {
                let cells = (extent[k] / h).floor();
                let cells = if cells.is_nan() {
                    0.0
                } else {
                    cells.clamp(0.0, max_cells)
                } as usize;
                match period {
                    Some(_) => cells.max(1),
                    None => cells + 1,
                }
            })
        };
        for _ in 0..200 {
            let dims = dims_for(h);
            let total = dims.iter().map(|&d| d as f64).product::<f64>();
            if total <= max_cells {
                let inv_width = std::array::from_fn(|k| match period {
                    Some(l) => dims[k] as f64 / l[k],
                    None => 1.0 / h,
                });
                return Self {
                    dims,
                    inv_width,
                    origin,
                    periodic: period.is_some(),
                };
            }
            h *= 1.25;
        }
        Self {
            dims: [1, 1, 1],
            inv_width: [0.0; 3],
            origin,
            periodic: period.is_some(),
        }
    }

    fn len(&self) -> usize {
        self.dims.iter().product()
    }

    fn cell_of(&self, c: &Vec3) -> usize {
        let i: [usize; 3] = std::array::from_fn(|k| {
            let f = ((c[k] - self.origin[k]) * self.inv_width[k]).floor();
            (f.max(0.0) as usize).min(self.dims[k] - 1)
        });
        i[0] + self.dims[0] * (i[1] + self.dims[1] * i[2])
    }

    /// The distinct neighbour cells of `a` with index > `a`, into `out`; returns their count.
    fn forward_neighbours(&self, a: usize, out: &mut [usize; 27]) -> usize {
        let [nx, ny, nz] = self.dims;
        let ix = a % nx;
        let iy = (a / nx) % ny;
        let iz = a / (nx * ny);
        let step = |i: usize, d: isize, n: usize| -> Option<usize> {
            let j = i as isize + d;
            if (0..n as isize).contains(&j) {
                Some(j as usize)
            } else if self.periodic {
                Some(j.rem_euclid(n as isize) as usize)
            } else {
                None
            }
        };
        let mut m = 0;
        for dz in -1..=1 {
            let Some(jz) = step(iz, dz, nz) else { continue };
            for dy in -1..=1 {
                let Some(jy) = step(iy, dy, ny) else { continue };
                for dx in -1..=1 {
                    let Some(jx) = step(ix, dx, nx) else { continue };
                    let b = jx + nx * (jy + ny * jz);
                    if b > a {
                        out[m] = b;
                        m += 1;
                    }
                }
            }
        }
        out[..m].sort_unstable();
        let mut k = 0;
        for i in 0..m {
            if i == 0 || out[i] != out[k - 1] {
                out[k] = out[i];
                k += 1;
            }
        }
        k
    }
}

/// Cell-grid search. Cells are at least one largest contact distance wide, so every pair
/// within tolerance lies in the same or adjacent cells; each unordered cell pair is visited
/// once (the cell with the smaller index visits), in parallel over fixed cell ranges.
fn grid_candidates(pos: &[Vec3], radii: &[f64], period: Option<[f64; 3]>, eps: f64) -> Vec<Candidate> {
    let n = pos.len();
    let rmax = radii.iter().copied().fold(0.0, f64::max);
    let reach = 2.0 * rmax * (1.0 + eps.max(0.0)) * MARGIN;
    let grid = Grid::new(pos, reach, period);
    let ncell = grid.len();

    // Counting sort of the particles by cell (stable: ids ascending within a cell).
    let cell: Vec<u32> = pos.par_iter().map(|c| grid.cell_of(c) as u32).collect();
    let mut start = vec![0u32; ncell + 1];
    for &c in &cell {
        start[c as usize + 1] += 1;
    }
    for i in 0..ncell {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut order = vec![0u32; n];
    for (i, &c) in cell.iter().enumerate() {
        order[fill[c as usize] as usize] = i as u32;
        fill[c as usize] += 1;
    }
    drop(fill);
    drop(cell);
    let packed: Vec<(Vec3, f64)> = order
        .par_iter()
        .map(|&i| (pos[i as usize], radii[i as usize]))
        .collect();
    let per = period.as_ref();
    let scale = (1.0 + eps) * MARGIN;

    let test = |i: usize, j: usize, out: &mut Vec<Candidate>| {
        let (ci, ri) = &packed[i];
        let (cj, rj) = &packed[j];
        let d = separation(ci, cj, per);
        let d2 = d.norm_squared();
        let s = ri + rj;
        let cut = s * scale;
        if d2 <= cut * cut {
            let rel = relative_gap(d2.sqrt(), *ri, *rj);
            if rel <= eps {
                out.push(Candidate::new(order[i], order[j], rel));
            }
        }
    };

    let chunk = ncell.div_ceil(256).max(1);
    let nchunks = ncell.div_ceil(chunk);
    let parts: Vec<Vec<Candidate>> = (0..nchunks)
        .into_par_iter()
        .map(|ch| {
            let mut out = Vec::new();
            let mut nb = [0usize; 27];
            for a in ch * chunk..((ch + 1) * chunk).min(ncell) {
                let (sa, ea) = (start[a] as usize, start[a + 1] as usize);
                if sa == ea {
                    continue;
                }
                for i in sa..ea {
                    for j in i + 1..ea {
                        test(i, j, &mut out);
                    }
                }
                let m = grid.forward_neighbours(a, &mut nb);
                for &b in &nb[..m] {
                    let (sb, eb) = (start[b] as usize, start[b + 1] as usize);
                    for i in sa..ea {
                        for j in sb..eb {
                            test(i, j, &mut out);
                        }
                    }
                }
            }
            out
        })
        .collect();
    let mut all = Vec::with_capacity(parts.iter().map(Vec::len).sum());
    for p in parts {
        all.extend(p);
    }
    all.par_sort_unstable_by_key(|c| c.key);
    all
}

/// R-tree search: boxes inflated by (1 + ε) around each sphere (plus ghost images near the
/// faces of a periodic box), joined with themselves, then filtered by the exact distance.
fn rtree_candidates(pos: &[Vec3], radii: &[f64], period: Option<[f64; 3]>, eps: f64) -> Vec<Candidate> {
    type Item = GeomWithData<Rectangle<[f64; 3]>, u32>;
    let scale = (1.0 + eps.max(0.0)) * MARGIN;
    let rmax = radii.iter().copied().fold(0.0, f64::max);
    let reach = 2.0 * rmax * scale;
    let item = |c: Vec3, r: f64, id: usize| -> Item {
        let h = r * scale;
        Item::new(
            Rectangle::from_corners([c.x - h, c.y - h, c.z - h], [c.x + h, c.y + h, c.z + h]),
            id as u32,
        )
    };
    let originals: Vec<Item> = (0..pos.len()).map(|i| item(pos[i], radii[i], i)).collect();
    let mut with_ghosts = originals.clone();
    if let Some(l) = period {
        for (i, c) in pos.iter().enumerate() {
            let shifts: [Vec<f64>; 3] = std::array::from_fn(|k| {
                let mut s = vec![0.0];
                if c[k] <= reach {
                    s.push(l[k]);
                }
                if c[k] >= l[k] - reach {
                    s.push(-l[k]);
                }
                s
            });
            for &sx in &shifts[0] {
                for &sy in &shifts[1] {
                    for &sz in &shifts[2] {
                        if sx != 0.0 || sy != 0.0 || sz != 0.0 {
                            with_ghosts.push(item(c + Vec3::new(sx, sy, sz), radii[i], i));
                        }
                    }
                }
            }
        }
    }
    let a = RTree::bulk_load(originals);
    let b = RTree::bulk_load(with_ghosts);
    let per = period.as_ref();
    let mut out: Vec<Candidate> = a
        .intersection_candidates_with_other_tree(&b)
        .filter(|(x, y)| x.data < y.data)
        .filter_map(|(x, y)| {
            let (i, j) = (x.data as usize, y.data as usize);
            let d = separation(&pos[i], &pos[j], per);
            let rel = relative_gap(d.norm_squared().sqrt(), radii[i], radii[j]);
            (rel <= eps).then(|| Candidate::new(x.data, y.data, rel))
        })
        .collect();
    out.sort_unstable_by_key(|c| c.key);
    out.dedup_by_key(|c| c.key);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fuzz findings: φ ≤ ~1e-70 in a scene (tiny radii in a normal box) and coordinates
    /// ≥ ~1e297 overflowed the cell index (index out of bounds).
    #[test]
    fn cell_search_survives_tiny_radii_and_huge_coordinates() {
        let pos = vec![
            Vec3::zeros(),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2e-70, 0.0, 0.0),
        ];
        let radii = vec![1e-70; 3];
        for method in [NeighbourSearch::CellGrid, NeighbourSearch::RTree] {
            let c = candidates(method, &pos, &radii, None, 0.1).unwrap();
            assert_eq!(c.len(), 1);
            assert_eq!((c[0].p(), c[0].q()), (0, 2));
            let c = candidates(method, &pos, &radii, Some([3.0; 3]), 0.1).unwrap();
            assert_eq!(c.len(), 1);
        }
        let far = vec![
            Vec3::zeros(),
            Vec3::new(1e140, 0.0, 0.0),
            Vec3::new(1e140, 1.0, 0.0),
        ];
        let c = candidates(NeighbourSearch::CellGrid, &far, &[0.6; 3], None, 0.1).unwrap();
        assert_eq!(c.len(), 1);
        for bad in [1e297, f64::INFINITY, f64::NAN] {
            let p = vec![Vec3::zeros(), Vec3::new(bad, 0.0, 0.0)];
            let e = candidates(NeighbourSearch::CellGrid, &p, &[0.5; 2], None, 0.1).unwrap_err();
            assert!(e.to_string().contains("particles[1]"), "{e}");
        }
    }
}
