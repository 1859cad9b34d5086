//! One rank's block of a tiled packing (issue 37, `docs/distributed.md`): the particles of
//! [`tile`](crate::tile)`(particles, container, repeat)` whose global index — their place
//! along the tiled box's Morton curve, exactly as `tile` numbers them — falls in the rank's
//! share, and the ghost particles of the other blocks within a given distance of them. Made by
//! sweeps over the copies without ever holding the tiled packing: the memory is the block's and
//! its ghosts', whatever the tiling's size.
//!
//! The shares are equal ranges of global indices (rank r of K owns [N r / K, N (r + 1) / K)):
//! contiguous along the Morton curve, so a compact set of octree cells. The boundaries are
//! found by a histogram of the keys' top bits and one sort of the boundary bucket.

use std::collections::HashMap;

use demcon_core::{Container, CoreError, MortonCurve, ParticleSet, Vec3};

use crate::error::PackingError;
use crate::tile::{Repeat, tiled_count};

/// Top bits of the Morton key (of 63) that bucket the copies when the shares' boundaries are
/// sought: 2¹⁶ buckets (0.5 MB of counts).
const BUCKET_BITS: u32 = 16;

/// One rank's part of a tiled packing: the particles it owns and its ghosts.
#[derive(Debug, Clone)]
pub struct Block {
    /// The owned particles in global order: `owned[i]` is particle `first + i` of the tiling.
    pub owned: ParticleSet,
    /// Global index of the first owned particle.
    pub first: usize,
    /// The particles of other blocks whose centre is within the ghost width of an owned one
    /// (minimum image across the tiled period), in global order, centres inside the tiled box.
    pub ghosts: ParticleSet,
    /// Global index of each ghost.
    pub ghost_ids: Vec<usize>,
    /// The tiled periodic container.
    pub container: Container,
    /// Particles in the whole tiling.
    pub total: usize,
}

/// A copy of a particle along the tiling's curve: its Morton key and its index in the tiles'
/// concatenation (x fastest, then y, then z; `tile`'s tie-break), so that the order of these
/// pairs is `tile`'s global order.
type Place = (u64, u64);

/// The copies of a periodic packing, swept without being stored.
struct Copies<'a> {
    particles: &'a ParticleSet,
    size: [f64; 3],
    repeat: Repeat,
    curve: MortonCurve,
}

impl Copies<'_> {
    /// Calls `f(place, centre, base)` for every copy, `base` the particle copied.
    fn sweep(&self, mut f: impl FnMut(Place, Vec3, usize)) {
        let n = self.particles.len() as u64;
        let mut tile = 0u64;
        for iz in 0..self.repeat[2] {
            for iy in 0..self.repeat[1] {
                for ix in 0..self.repeat[0] {
                    let shift = Vec3::new(
                        ix as f64 * self.size[0],
                        iy as f64 * self.size[1],
                        iz as f64 * self.size[2],
                    );
                    for (p, c) in self.particles.centres.iter().enumerate() {
                        let x = c + shift;
                        f((self.curve.key(&x), tile * n + p as u64), x, p);
                    }
                    tile += 1;
                }
            }
        }
    }

    /// The copy at `place`: its centre (computed as [`Copies::sweep`] does, so bit for bit the
    /// same) and the particle copied.
    fn copy(&self, place: Place) -> (Vec3, usize) {
        let n = self.particles.len() as u64;
        let (tile, p) = ((place.1 / n) as usize, (place.1 % n) as usize);
        let (ix, iy, iz) = (
            tile % self.repeat[0],
            (tile / self.repeat[0]) % self.repeat[1],
            tile / (self.repeat[0] * self.repeat[1]),
        );
        let shift = Vec3::new(
            ix as f64 * self.size[0],
            iy as f64 * self.size[1],
            iz as f64 * self.size[2],
        );
        (self.particles.centres[p] + shift, p)
    }

    /// The copies at `places`, in that order, with their radii and phases.
    fn set(&self, places: &[Place]) -> Result<ParticleSet, PackingError> {
        let copies: Vec<(Vec3, usize)> = places.iter().map(|&pl| self.copy(pl)).collect();
        let mut s = ParticleSet::new(
            copies.iter().map(|c| c.0).collect(),
            copies.iter().map(|c| self.particles.radii[c.1]).collect(),
        )?;
        s.phases = copies.iter().map(|c| self.particles.phases[c.1]).collect();
        Ok(s)
    }

    /// The places at global positions `positions` (each < the total), by a histogram of the
    /// keys' top bits and a sort of each wanted bucket.
    fn select(&self, positions: &[usize]) -> Vec<Place> {
        let shift = 63 - BUCKET_BITS;
        let mut counts = vec![0usize; 1 << BUCKET_BITS];
        self.sweep(|(key, _), _, _| counts[(key >> shift) as usize] += 1);
        // Each position's bucket and its rank inside it.
        let mut below = 0;
        let mut starts = Vec::with_capacity(counts.len());
        for c in &counts {
            starts.push(below);
            below += c;
        }
        let wanted: Vec<(usize, usize)> = positions
            .iter()
            .map(|&pos| {
                let b = starts.partition_point(|&s| s <= pos) - 1;
                (b, pos - starts[b])
            })
            .collect();
        let mut buckets: HashMap<usize, Vec<Place>> = wanted.iter().map(|&(b, _)| (b, Vec::new())).collect();
        self.sweep(|place, _, _| {
            if let Some(v) = buckets.get_mut(&((place.0 >> shift) as usize)) {
                v.push(place);
            }
        });
        for v in buckets.values_mut() {
            v.sort_unstable();
        }
        wanted.iter().map(|&(b, k)| buckets[&b][k]).collect()
    }
}

/// Rank `rank`'s block of `particles` (a periodic packing in `container`) tiled `repeat` times
/// among `ranks` ranks, with ghosts within `ghost_width` (m) of its particles' centres. With
/// `walls` the tiled box is walled (`Container::Box`, as the scene's `Tile(walls: true)`): the
/// same particles, ghosts found without periodic images.
///
/// # Errors
/// A walled container, a zero repeat, `rank ≥ ranks`, more ranks than particles, and a ghost
/// width that is not a positive length or is thicker than half a block (the edge of a cube
/// holding a share of the box's volume): the error names the field, the value and what is
/// allowed.
pub fn tile_block(
    particles: &ParticleSet,
    container: &Container,
    repeat: Repeat,
    walls: bool,
    rank: usize,
    ranks: usize,
    ghost_width: f64,
) -> Result<Block, PackingError> {
    let Container::Periodic { size } = *container else {
        return Err(CoreError::invalid(
            "container",
            container.kind(),
            "only a periodic packing can be tiled into blocks",
        )
        .into());
    };
    let total = tiled_count(particles.len(), repeat, "repeat")?;
    if ranks == 0 || ranks > total {
        return Err(CoreError::invalid(
            "ranks",
            ranks,
            format!("must be between 1 and the tiling's {total} particles (every block needs a particle)"),
        )
        .into());
    }
    if rank >= ranks {
        return Err(CoreError::invalid("rank", rank, format!("must be below the {ranks} ranks")).into());
    }
    let tiled_size = [0, 1, 2].map(|k| size[k] * repeat[k] as f64);
    let tiled = if walls {
        Container::Box { size: tiled_size }
    } else {
        Container::Periodic { size: tiled_size }
    };
    let block_edge = (tiled.volume() / ranks as f64).cbrt();
    if !(ghost_width.is_finite() && ghost_width > 0.0 && ghost_width <= 0.5 * block_edge) {
        return Err(CoreError::invalid(
            "ghost_width",
            ghost_width,
            format!(
                "must be a length > 0 and at most half a block's edge, {:.4e} m (the edge of a cube holding \
                 1/{ranks} of the box): a thicker ghost layer would hold more than the block",
                0.5 * block_edge
            ),
        )
        .into());
    }
    let copies = Copies {
        particles,
        size,
        repeat,
        curve: MortonCurve::new(&tiled.bounds()),
    };
    let first = total * rank / ranks;
    let end = total * (rank + 1) / ranks;
    let bounds = copies.select(&[first, end.min(total - 1)]);
    let (lo, hi) = (
        bounds[0],
        if end == total {
            (u64::MAX, u64::MAX)
        } else {
            bounds[1]
        },
    );
    let owns = |p: &Place| *p >= lo && *p < hi;

    // The owned copies, in global order.
    let mut owned: Vec<Place> = Vec::with_capacity(end - first);
    copies.sweep(|place, _, _| {
        if owns(&place) {
            owned.push(place);
        }
    });
    owned.sort_unstable();
    debug_assert_eq!(owned.len(), end - first);
    let owned = copies.set(&owned)?;

    // The ghosts: every other copy within the width of an owned centre (minimum image unless
    // walled); none for a single block.
    let mut ghosts: Vec<Place> = Vec::new();
    if ranks > 1 {
        let grid = Grid::new(tiled_size, !walls, ghost_width, &owned.centres);
        copies.sweep(|place, x, _| {
            if !owns(&place) && grid.near(&x, &owned.centres, ghost_width) {
                ghosts.push(place);
            }
        });
        ghosts.sort_unstable();
    }
    // Each ghost's global index: the copies before it along the curve.
    let mut before = vec![0usize; ghosts.len() + 1];
    if !ghosts.is_empty() {
        copies.sweep(|place, _, _| before[ghosts.partition_point(|g| *g < place)] += 1);
    }
    let mut ghost_ids = Vec::with_capacity(ghosts.len());
    let mut running = 0;
    for b in &before[..ghosts.len()] {
        running += b;
        ghost_ids.push(running - 1);
    }
    Ok(Block {
        owned,
        first,
        ghosts: copies.set(&ghosts)?,
        ghost_ids,
        container: tiled,
        total,
    })
}

/// The owned centres on a grid of cells at least the ghost width wide (and no more cells than
/// owned centres) over the tiled box, stored as compressed rows: cell k holds
/// `members[start[k]..start[k + 1]]`. Distances are minimum-image when `wrap`.
struct Grid {
    period: [f64; 3],
    wrap: bool,
    cells: [usize; 3],
    start: Vec<u32>,
    members: Vec<u32>,
}

impl Grid {
    fn new(period: [f64; 3], wrap: bool, width: f64, centres: &[Vec3]) -> Self {
        let volume: f64 = period.iter().product();
        let side = width.max((volume / centres.len().max(1) as f64).cbrt());
        let cells = period.map(|l| ((l / side).floor() as usize).max(1));
        let mut grid = Self {
            period,
            wrap,
            cells,
            start: vec![0; cells.iter().product::<usize>() + 1],
            members: vec![0; centres.len()],
        };
        let keys: Vec<usize> = centres.iter().map(|c| grid.index(grid.cell(c))).collect();
        for &k in &keys {
            grid.start[k + 1] += 1;
        }
        for k in 1..grid.start.len() {
            grid.start[k] += grid.start[k - 1];
        }
        let mut fill = grid.start.clone();
        for (i, &k) in keys.iter().enumerate() {
            grid.members[fill[k] as usize] = i as u32;
            fill[k] += 1;
        }
        grid
    }

    fn cell(&self, x: &Vec3) -> [usize; 3] {
        [0, 1, 2].map(|k| {
            let n = self.cells[k] as i64;
            ((x[k] / self.period[k] * n as f64).floor() as i64).rem_euclid(n) as usize
        })
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.cells[1] + c[1]) * self.cells[0] + c[0]
    }

    /// Whether a centre of `centres` (those the grid was built on) lies within `width` of `x`
    /// (minimum image).
    fn near(&self, x: &Vec3, centres: &[Vec3], width: f64) -> bool {
        let c = self.cell(x);
        let mut seen = [usize::MAX; 27];
        for d in 0..27 {
            let off = [d % 3, (d / 3) % 3, d / 9];
            let at = [0, 1, 2].map(|k| (c[k] + self.cells[k] + off[k] - 1) % self.cells[k]);
            let k = self.index(at);
            // Fewer than three cells along an axis: the same cell twice.
            if seen[..d].contains(&k) {
                continue;
            }
            seen[d] = k;
            for &i in &self.members[self.start[k] as usize..self.start[k + 1] as usize] {
                let mut d = centres[i as usize] - x;
                for a in (0..3).filter(|_| self.wrap) {
                    d[a] -= self.period[a] * (d[a] / self.period[a]).round();
                }
                if d.norm() < width {
                    return true;
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tile;

    /// `tile`'s test packing with three phases.
    fn small() -> (ParticleSet, Container) {
        let (mut p, c) = crate::tile::tests::small();
        p.phases = (0..p.len()).map(|i| (i % 3) as u16).collect();
        (p, c)
    }

    #[test]
    fn the_blocks_are_the_serial_tiling_cut_in_order() {
        let (p, c) = small();
        let repeat = [2, 3, 2];
        let (whole, wc) = tile(&p, &c, repeat).unwrap();
        for ranks in 1..=4 {
            let mut next = 0;
            for rank in 0..ranks {
                let b = tile_block(&p, &c, repeat, false, rank, ranks, 1e-4).unwrap();
                assert_eq!(b.first, next);
                assert_eq!(b.total, whole.len());
                assert_eq!(b.container.period(), wc.period());
                for (i, x) in b.owned.centres.iter().enumerate() {
                    let g = b.first + i;
                    assert_eq!(*x, whole.centres[g], "rank {rank} of {ranks}, particle {g}");
                    assert_eq!(b.owned.radii[i], whole.radii[g]);
                    assert_eq!(b.owned.phases[i], whole.phases[g]);
                }
                next += b.owned.len();
            }
            assert_eq!(next, whole.len());
        }
    }

    #[test]
    fn ghosts_are_every_other_particle_within_the_width_with_its_global_index() {
        let (p, c) = small();
        let repeat = [2, 2, 2];
        let (whole, wc) = tile(&p, &c, repeat).unwrap();
        let l = wc.period().unwrap();
        let width = 1.5e-4;
        for walls in [false, true] {
            // Minimum image in the periodic tiling, plain distance in the walled box.
            let dist = |a: &Vec3, b: &Vec3| {
                let mut d = a - b;
                for k in (0..3).filter(|_| !walls) {
                    d[k] -= l[k] * (d[k] / l[k]).round();
                }
                d.norm()
            };
            for rank in 0..3 {
                let b = tile_block(&p, &c, repeat, walls, rank, 3, width).unwrap();
                assert_eq!(matches!(b.container, Container::Box { .. }), walls);
                let owned = b.first..b.first + b.owned.len();
                let want: Vec<usize> = (0..whole.len())
                    .filter(|g| !owned.contains(g))
                    .filter(|&g| {
                        owned
                            .clone()
                            .any(|o| dist(&whole.centres[g], &whole.centres[o]) < width)
                    })
                    .collect();
                assert!(!want.is_empty());
                assert_eq!(b.ghost_ids, want, "rank {rank}, walls {walls}");
                for (i, &g) in b.ghost_ids.iter().enumerate() {
                    assert_eq!(b.ghosts.centres[i], whole.centres[g]);
                    assert_eq!(b.ghosts.radii[i], whole.radii[g]);
                    assert_eq!(b.ghosts.phases[i], whole.phases[g]);
                }
            }
        }
    }

    #[test]
    fn bad_ranks_widths_and_containers_are_refused_by_name() {
        let (p, c) = small();
        let e = |r: Result<Block, PackingError>| r.unwrap_err().to_string();
        let s = e(tile_block(&p, &c, [2, 2, 2], false, 2, 2, 1e-4));
        assert!(s.contains("rank = 2") && s.contains("below the 2 ranks"), "{s}");
        let s = e(tile_block(&p, &c, [1, 1, 1], false, 0, 301, 1e-4));
        assert!(s.contains("ranks = 301") && s.contains("300 particles"), "{s}");
        let s = e(tile_block(&p, &c, [2, 2, 2], false, 0, 4, 1e-3));
        assert!(s.contains("ghost_width") && s.contains("half a block"), "{s}");
        let s = e(tile_block(&p, &c, [2, 2, 2], false, 0, 4, f64::NAN));
        assert!(s.contains("ghost_width"), "{s}");
        let s = e(tile_block(
            &p,
            &Container::Box { size: [1e-3; 3] },
            [2, 2, 2],
            false,
            0,
            2,
            1e-4,
        ));
        assert!(s.contains("container") && s.contains("periodic"), "{s}");
        let s = e(tile_block(&p, &c, [2, 0, 2], false, 0, 2, 1e-4));
        assert!(s.contains("repeat[1]"), "{s}");
    }
}
