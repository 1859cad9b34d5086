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

/// Squared distance (m²) from `c` to the packed sphere `x` = (centre, radius), nearest image
/// when `PERIODIC` (half periods `h`, periods `l`). The same operations as
/// [`separation`]`(c, x)`, so the same bits, and exactly antisymmetric: the same gap from
/// either end of a pair.
#[inline(always)]
fn packed_distance2<const PERIODIC: bool>(x: &[f64; 4], c: [f64; 3], h: [f64; 3], l: [f64; 3]) -> f64 {
    let mut d = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
    if PERIODIC {
        for k in 0..3 {
            if d[k] > h[k] {
                d[k] -= l[k];
            } else if d[k] < -h[k] {
                d[k] += l[k];
            }
        }
    }
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
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

/// Candidate pairs in parts (one per parallel task); the parts, concatenated, are sorted by
/// key.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Candidates {
    pub parts: Vec<Vec<Candidate>>,
}

impl Candidates {
    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.parts.iter().map(Vec::len).sum()
    }

    /// The pairs in key order.
    pub fn iter(&self) -> impl Iterator<Item = &Candidate> {
        self.parts.iter().flatten()
    }
}

/// Margin on the prefilter distance so that rounding never drops a pair with rel ≤ ε.
const MARGIN: f64 = 1.0 + 1e-9;

/// Largest particle span and radius the search accepts (m): beyond, squared distances
/// overflow f64 and cell indices lose meaning.
pub(crate) const MAX_SPAN: f64 = 1e150;

/// Pairs with relative gap ≤ `eps`, sorted by key (across the parts). `pos` must be wrapped into the period
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
) -> Result<Candidates, GraphError> {
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
        // Never more than ~3 cells per particle: sparse sets get wider cells. Cell counts are
        // clamped before the cast (a tiny reach or a huge span once overflowed the index), the
        // width starts at the larger of span / max_cells and (volume / max_cells)^(1/3), and
        // widens at most 200 times (by 2 % for the first 100, so that the grid is as fine as
        // allowed: each particle tests the particles of 27 cells); a degenerate span falls
        // back to a single cell (slow, still exact).
        let max_cells = 3.0 * pos.len() as f64 + 64.0;
        let e_max = extent.max();
        let mut h = if reach.is_finite() && reach > 0.0 {
            reach
        } else {
            e_max
        };
        h = h.max(e_max / max_cells);
        let volume = extent.x * extent.y * extent.z;
        if volume.is_finite() && volume > 0.0 {
            h = h.max((volume / max_cells).cbrt());
        }
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
        for i in 0..200 {
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
            h *= if i < 100 { 1.02 } else { 1.25 };
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

    /// The particles of cell `a` and of its neighbours, as ranges of the cell-sorted arrays
    /// (`start[c]..start[c + 1]` holds cell `c`), into `out`; returns their count. Every
    /// distinct cell lies in exactly one range (a periodic axis of one or two cells wraps onto
    /// itself), and cells adjacent along x share a range.
    fn neighbour_ranges(&self, a: usize, start: &[u32], out: &mut [(u32, u32); 27]) -> usize {
        let [nx, ny, nz] = self.dims;
        let ix = a % nx;
        let iy = (a / nx) % ny;
        let iz = a / (nx * ny);
        let interior = |i: usize, n: usize| i >= 1 && i + 1 < n;
        if !self.periodic || (interior(ix, nx) && interior(iy, ny) && interior(iz, nz)) {
            // Runs clamped to the grid: distinct cells, each x-run contiguous.
            let (x0, x1) = (ix.saturating_sub(1), (ix + 1).min(nx - 1));
            let mut m = 0;
            for jz in iz.saturating_sub(1)..=(iz + 1).min(nz - 1) {
                for jy in iy.saturating_sub(1)..=(iy + 1).min(ny - 1) {
                    let row = nx * (jy + ny * jz);
                    out[m] = (start[row + x0], start[row + x1 + 1]);
                    m += 1;
                }
            }
            return m;
        }
        // A periodic boundary cell: the wrapped cells, sorted, deduplicated and coalesced.
        let wrapped = |i: usize, d: isize, n: usize| (i as isize + d).rem_euclid(n as isize) as usize;
        let mut cells = [0usize; 27];
        let mut k = 0;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    cells[k] = wrapped(ix, dx, nx) + nx * (wrapped(iy, dy, ny) + ny * wrapped(iz, dz, nz));
                    k += 1;
                }
            }
        }
        cells.sort_unstable();
        let mut m = 0;
        let mut prev = usize::MAX;
        for &c in &cells {
            if c == prev {
                continue;
            }
            if m > 0 && c == prev + 1 {
                out[m - 1].1 = start[c + 1];
            } else {
                out[m] = (start[c], start[c + 1]);
                m += 1;
            }
            prev = c;
        }
        m
    }
}

/// Particles per parallel task of the cell-grid sweep (fixed, so the parts, and the work
/// each does, do not depend on the thread count).
const SWEEP_CHUNK: usize = 4096;

/// Cell-grid search. Cells are at least one largest contact distance wide, so every pair
/// within tolerance lies in the same or adjacent cells. Particles are binned by a counting
/// sort (ids ascending within a cell, centre and radius copied side by side in cell order);
/// then each particle p, in id order, tests the particles q > p of its cell and of the
/// neighbouring ones, and its pairs are sorted by q. Fixed id ranges run in parallel, so the
/// parts, concatenated, are sorted by (p, q) with no global sort and do not depend on the
/// thread count. Each pair is tested from both ends (twice the distance tests of a half-shell
/// sweep), which costs less than sorting the candidates afterwards. When the ids do not
/// follow space ([`ids_follow_space`]), particles are visited in cell order instead and the
/// pairs sorted once (the same pairs, the same values).
fn grid_candidates(pos: &[Vec3], radii: &[f64], period: Option<[f64; 3]>, eps: f64) -> Candidates {
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
    let packed: Vec<[f64; 4]> = order
        .par_iter()
        .map(|&i| {
            let c = &pos[i as usize];
            [c.x, c.y, c.z, radii[i as usize]]
        })
        .collect();
    let scale = (1.0 + eps) * MARGIN;

    let sweep = Sweep {
        grid: &grid,
        start: &start,
        cell: &cell,
        order: &order,
        packed: &packed,
        pos,
        radii,
        scale,
        eps,
    };
    let run = |ids: &mut dyn ExactSizeIterator<Item = usize>| match period {
        Some(l) => sweep.run::<true>(ids, &l),
        None => sweep.run::<false>(ids, &[0.0; 3]),
    };
    let chunks = 0..n.div_ceil(SWEEP_CHUNK);
    let range = |ch: usize| ch * SWEEP_CHUNK..((ch + 1) * SWEEP_CHUNK).min(n);
    if ids_follow_space(&grid, &cell) {
        // Id order: each part sorted, the parts in order.
        let parts = chunks.into_par_iter().map(|ch| run(&mut range(ch))).collect();
        Candidates { parts }
    } else {
        // Ids in no spatial order (e.g. shuffled): visiting them in id order would read
        // scattered cells, so particles are visited in cell order, each pair once (half
        // shell), and the pairs sorted once.
        let parts: Vec<Vec<Candidate>> = chunks
            .into_par_iter()
            .map(|ch| match period {
                Some(l) => sweep.run_cells::<true>(range(ch), &l),
                None => sweep.run_cells::<false>(range(ch), &[0.0; 3]),
            })
            .collect();
        let mut all = Vec::with_capacity(parts.iter().map(Vec::len).sum());
        for part in parts {
            all.extend(part);
        }
        all.par_sort_unstable_by_key(|c| c.key);
        Candidates { parts: vec![all] }
    }
}

/// Whether particle ids follow space: at least half of the consecutive ids lie in the same
/// or adjacent cells (a Morton or lattice numbering: nearly all; random ids: almost none).
fn ids_follow_space(grid: &Grid, cell: &[u32]) -> bool {
    let [nx, ny, _] = grid.dims;
    let coords = |a: u32| {
        let a = a as usize;
        [a % nx, (a / nx) % ny, a / (nx * ny)]
    };
    let near = cell
        .par_windows(2)
        .with_min_len(SWEEP_CHUNK)
        .filter(|w| {
            let (x, y) = (coords(w[0]), coords(w[1]));
            (0..3).all(|k| x[k].abs_diff(y[k]) <= 1)
        })
        .count();
    2 * near >= cell.len().saturating_sub(1)
}

/// The binned particles and what the sweep of one id range needs.
struct Sweep<'a> {
    grid: &'a Grid,
    start: &'a [u32],
    /// Cell of each particle, by id.
    cell: &'a [u32],
    /// Particle ids in cell order.
    order: &'a [u32],
    /// Centre and radius in cell order.
    packed: &'a [[f64; 4]],
    pos: &'a [Vec3],
    radii: &'a [f64],
    /// (1 + ε) with the rounding margin.
    scale: f64,
    eps: f64,
}

impl Sweep<'_> {
    /// The candidates (p, q > p) of the particles p in `ids`, sorted by key; `PERIODIC` with
    /// the period `l` (the minimum image, as [`separation`]).
    fn run<const PERIODIC: bool>(
        &self,
        ids: impl ExactSizeIterator<Item = usize>,
        l: &[f64; 3],
    ) -> Vec<Candidate> {
        let mut out: Vec<Candidate> = Vec::with_capacity(8 * ids.len());
        let mut ranges = [(0u32, 0u32); 27];
        let (mut last, mut m) = (usize::MAX, 0);
        let h = l.map(|x| 0.5 * x);
        for p in ids {
            let a = self.cell[p] as usize;
            if a != last {
                m = self.grid.neighbour_ranges(a, self.start, &mut ranges);
                last = a;
            }
            let (cp, rp) = (&self.pos[p], self.radii[p]);
            let p = p as u32;
            let from = out.len();
            for &(lo, hi) in &ranges[..m] {
                let (lo, hi) = (lo as usize, hi as usize);
                for (x, &q) in self.packed[lo..hi].iter().zip(&self.order[lo..hi]) {
                    let d2 = packed_distance2::<PERIODIC>(x, [cp.x, cp.y, cp.z], h, *l);
                    let cut = (rp + x[3]) * self.scale;
                    // `&`, not `&&`: one rarely taken branch.
                    if (d2 <= cut * cut) & (q > p) {
                        let rel = relative_gap(d2.sqrt(), rp, x[3]);
                        if rel <= self.eps {
                            out.push(Candidate {
                                key: ((p as u64) << 32) | q as u64,
                                rel_gap: rel,
                            });
                        }
                    }
                }
            }
            out[from..].sort_unstable_by_key(|c| c.key);
        }
        out
    }

    /// The candidates of the particles at cell-sorted positions `slots`, each pair once: a
    /// particle tests the neighbours after it in cell order. Unsorted.
    fn run_cells<const PERIODIC: bool>(&self, slots: std::ops::Range<usize>, l: &[f64; 3]) -> Vec<Candidate> {
        let mut out: Vec<Candidate> = Vec::with_capacity(8 * slots.len());
        let mut ranges = [(0u32, 0u32); 27];
        let (mut last, mut m) = (usize::MAX, 0);
        let h = l.map(|x| 0.5 * x);
        for i in slots {
            let p = self.order[i];
            let a = self.cell[p as usize] as usize;
            if a != last {
                m = self.grid.neighbour_ranges(a, self.start, &mut ranges);
                last = a;
            }
            let [cx, cy, cz, rp] = self.packed[i];
            for &(lo, hi) in &ranges[..m] {
                let (lo, hi) = ((lo as usize).max(i + 1), hi as usize);
                if lo >= hi {
                    continue;
                }
                for (x, &q) in self.packed[lo..hi].iter().zip(&self.order[lo..hi]) {
                    let d2 = packed_distance2::<PERIODIC>(x, [cx, cy, cz], h, *l);
                    let cut = (rp + x[3]) * self.scale;
                    if d2 <= cut * cut {
                        let rel = relative_gap(d2.sqrt(), rp, x[3]);
                        if rel <= self.eps {
                            out.push(Candidate::new(p, q, rel));
                        }
                    }
                }
            }
        }
        out
    }
}

/// R-tree search: boxes inflated by (1 + ε) around each sphere (plus ghost images near the
/// faces of a periodic box), joined with themselves, then filtered by the exact distance.
fn rtree_candidates(pos: &[Vec3], radii: &[f64], period: Option<[f64; 3]>, eps: f64) -> Candidates {
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
    Candidates { parts: vec![out] }
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
            let c0 = c.iter().next().unwrap();
            assert_eq!((c0.p(), c0.q()), (0, 2));
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
