//! The Laguerre (power, radical Voronoi) tessellation of the spheres, clipped by the
//! container and an optional carving region: the network of the third surface model.
//!
//! The cell of sphere p is {x : |x − x_p|² − R_p² ≤ |x − x_q|² − R_q² for every q}. Two
//! particles are neighbours when their cells share a facet; the facet's area is the
//! transmission surface S_pq and its plane splits the centre distance d into
//! h_p = (d² + R_p² − R_q²)/(2d) and h_q = d − h_p. Facets are perpendicular to the centre
//! line and every closed cell has Σ S n = 0, so a linear field solves the network exactly.
//!
//! Each cell is built on its own: the container's bounding box (walled containers) or a
//! box around the site (periodic), cut by the power planes of the neighbours found in a
//! uniform grid (about one site per grid cell): the 27 adjacent grid cells first, nearest
//! plane first, then the other grid cells in order of distance until no unseen sphere can
//! reach the cell (certified by a lower bound on the plane offset of any sphere farther than
//! the next grid cell). A plane is clipped only when it can reach the cell's farthest
//! vertex; on a jittered FCC lattice every plane clipped ends as a facet.
//!
//! A cylinder's mantle is one global polygon of tangent planes (within `curved_tolerance` ×
//! R̄ of the circle), the same for every cell, so that the cells along it still close and a
//! linear field stays exact. A sphere container and a carving region are followed cell by
//! cell: planes tangent where the segment from the site to the vertex farthest outside leaves
//! the domain, until every vertex lies within `curved_tolerance` × R_p of the surface;
//! neighbouring cells may then be cut differently (their shared facet's two areas differ, see
//! `max_area_mismatch`). The volume left is reported. Cells run in parallel; each depends only
//! on its own inputs, so the result does not depend on the thread count.

mod cell;

use std::time::Instant;

use demcon_core::{Container, CoreError, Face, ParticleSet, Region, Vec3};
use rayon::prelude::*;

use self::cell::{BOUND, Cell, ClipError, Tag, WALL_BASE};
use crate::contact::{ContactGeometry, ContactGraph, ContactReport, prepare, summarise};
use crate::error::{GraphError, positive};

/// Parameters of [`tessellate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaguerreParams {
    /// Facets smaller than this times R̄² (R̄ the mean radius) are dropped as negligible
    /// (dimensionless). Default 1e-12: dropping them changes no conductance sum by more
    /// than that relative amount.
    pub negligible_area: f64,
    /// Curved walls and carving surfaces are followed by tangent planes until every vertex
    /// of the cell lies within this fraction of the particle's radius outside the surface
    /// (dimensionless). Default 1e-3.
    pub curved_tolerance: f64,
    /// Most tangent planes one cell may receive from curved surfaces. Default 64.
    pub max_curved_planes: usize,
    /// Largest overlap of two spheres accepted, as a fraction of the smaller radius
    /// (dimensionless): beyond it a centre can fall outside its own cell. Default 0.1.
    pub max_overlap: f64,
}

impl Default for LaguerreParams {
    fn default() -> Self {
        Self {
            negligible_area: 1e-12,
            curved_tolerance: 1e-3,
            max_curved_planes: 64,
            max_overlap: 0.1,
        }
    }
}

impl LaguerreParams {
    /// Checks every field; the error names it.
    pub fn validate(&self) -> Result<(), GraphError> {
        positive("laguerre.negligible_area", self.negligible_area)?;
        positive("laguerre.curved_tolerance", self.curved_tolerance)?;
        positive("laguerre.max_overlap", self.max_overlap)?;
        if self.max_curved_planes == 0 {
            return Err(CoreError::invalid("laguerre.max_curved_planes", 0, "must be ≥ 1").into());
        }
        Ok(())
    }
}

/// Volume of the polyhedron {x : n_k·x ≤ 1 for every k} cut by the tangent planes at the unit
/// normals `normals` around the unit sphere (dimensionless; ∞ when they do not close it). For
/// the conforming seeds' radius correction ([`crate::conforming_sites`]).
pub(crate) fn tangent_polyhedron_volume(normals: &[Vec3]) -> f64 {
    let mut c = Cell::default();
    // A box the polyhedron of well-spread normals fits in (its vertices lie within ~√3).
    let b = 4.0;
    c.reset_box(Vec3::repeat(-b), Vec3::repeat(b), [BOUND; 6]);
    for (k, n) in normals.iter().enumerate() {
        if c.clip(n, 1.0, k as Tag, 1e-12).is_err() {
            return f64::INFINITY;
        }
    }
    if c.tags.contains(&BOUND) {
        return f64::INFINITY;
    }
    c.volume()
}

/// What bounds a wall facet of a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellWall {
    /// A face of the container.
    Face(Face),
    /// The surface of the carving region.
    Carved,
}

impl CellWall {
    /// The wall a face names: [`Face::Carved`] is the carving region's surface.
    pub fn of(face: Face) -> Self {
        match face {
            Face::Carved => CellWall::Carved,
            f => CellWall::Face(f),
        }
    }
}

/// The part of a particle's cell on one wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallFacet {
    /// The particle.
    pub particle: u32,
    /// The wall.
    pub wall: CellWall,
    /// Area (m²), summed over the planes that approximate a curved wall.
    pub area: f64,
    /// Distance from the centre to the facet, area-weighted over its planes (m).
    pub distance: f64,
    /// Outward unit normal (of the summed vector area).
    pub normal: Vec3,
    /// Centroid of the facet relative to the particle's centre (m), area-weighted over its
    /// planes: the lever arm of its flow in the particle's flux.
    pub centroid: Vec3,
}

/// The cells of a Laguerre tessellation, beside the graph of their shared facets.
#[derive(Debug, Clone, PartialEq)]
pub struct Cells {
    /// Area of the facet of each contact (m²), same order as the graph's pairs: the mean of
    /// the two cells' values (equal to round-off).
    pub facet_area: Vec<f64>,
    /// h_p / d_pq per contact: where the facet plane splits the centre line, from p.
    pub split: Vec<f64>,
    /// Centroid of each contact's facet relative to p's centre (m) (the mean of the two
    /// cells' values, q's shifted by the branch): the lever arm of the contact's flow in p's
    /// flux; q's is this minus the branch.
    pub centroid: Vec<Vec3>,
    /// Volume of each cell (m³).
    pub volume: Vec<f64>,
    /// Wall facets, sorted by particle then wall.
    pub walls: Vec<WallFacet>,
    /// What the tessellation did.
    pub report: TessellationReport,
}

impl Cells {
    /// The cells of the particles `keep` (ascending), renumbered by `new_id` (`u32::MAX` for
    /// removed particles); `pairs` are the full graph's. The removed cells leave holes: the
    /// facets they shared become free surface (adiabatic).
    pub(crate) fn induced(&self, pairs: &[[u32; 2]], keep: &[u32], new_id: &[u32]) -> Cells {
        let kept = |&[p, q]: &[u32; 2]| new_id[p as usize] != u32::MAX && new_id[q as usize] != u32::MAX;
        let mut facet_area = Vec::new();
        let mut split = Vec::new();
        let mut centroid = Vec::new();
        for (k, pq) in pairs.iter().enumerate() {
            if kept(pq) {
                facet_area.push(self.facet_area[k]);
                split.push(self.split[k]);
                centroid.push(self.centroid[k]);
            }
        }
        Cells {
            facet_area,
            split,
            centroid,
            volume: keep.iter().map(|&i| self.volume[i as usize]).collect(),
            walls: self
                .walls
                .iter()
                .filter(|w| new_id[w.particle as usize] != u32::MAX)
                .map(|w| WallFacet {
                    particle: new_id[w.particle as usize],
                    ..*w
                })
                .collect(),
            report: self.report.clone(),
        }
    }

    /// The wall facets of `wall`, in particle order.
    pub fn on_wall(&self, wall: CellWall) -> impl Iterator<Item = &WallFacet> + '_ {
        self.walls.iter().filter(move |w| w.wall == wall)
    }
}

/// What the tessellation did, found and cost.
#[derive(Debug, Clone, PartialEq)]
pub struct TessellationReport {
    /// Facets dropped as negligible (counted once per pair).
    pub dropped_facets: usize,
    /// The area below which a facet is dropped (m²).
    pub negligible_area_m2: f64,
    /// Facets found by one cell only (after dropping negligible ones): should be 0.
    pub one_sided_facets: usize,
    /// Largest |S_p − S_q| / S of a facet seen from its two cells.
    pub max_area_mismatch: f64,
    /// Σ cell volumes (m³).
    pub cells_volume: f64,
    /// The domain's volume (m³): the container's, or the carving region's (estimated on a
    /// 256³ grid).
    pub domain_volume: f64,
    /// Σ cell volumes / domain volume − 1: the volume curved walls leave outside the domain
    /// (tangent planes never cut the inside of a convex wall).
    pub volume_error: f64,
    /// Cells that touch a curved surface, and the tangent planes they received.
    pub curved_cells: usize,
    /// Tangent planes added for curved surfaces.
    pub curved_planes: usize,
    /// Largest grid layer searched for a cell's neighbours.
    pub max_layers: usize,
    /// Power planes tried, and those that cut a cell.
    pub planes_tried: u64,
    /// Power planes that cut a cell.
    pub planes_cut: u64,
    /// Wall time (s).
    pub wall_s: f64,
}

/// Wall tag codes: 0..6 are the container's faces (`Face` order below), 7 the carving region.
const FACES: [Face; 7] = [
    Face::XMin,
    Face::XMax,
    Face::YMin,
    Face::YMax,
    Face::ZMin,
    Face::ZMax,
    Face::Outer,
];
const CARVED: u32 = 7;

fn wall_tag(code: u32) -> Tag {
    WALL_BASE + code
}

fn wall_of(tag: Tag) -> CellWall {
    match tag - WALL_BASE {
        CARVED => CellWall::Carved,
        c => CellWall::Face(FACES[c as usize]),
    }
}

/// Grid layers (Chebyshev) searched around a site in cell order; beyond, a walled grid is
/// searched whole (sparse sets) and a periodic one is refused (its images could repeat).
const MAX_SEARCH_LAYERS: i64 = 10;

/// A uniform grid of the sites.
struct Grid {
    dims: [usize; 3],
    width: f64,
    origin: Vec3,
    period: Option<[f64; 3]>,
    /// Sites of cell c are `items[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    fn new(pos: &[Vec3], lo: Vec3, hi: Vec3, period: Option<[f64; 3]>) -> Self {
        let extent = hi - lo;
        let volume = extent.x.max(f64::MIN_POSITIVE)
            * extent.y.max(f64::MIN_POSITIVE)
            * extent.z.max(f64::MIN_POSITIVE);
        // About one site per grid cell.
        let width = (volume / pos.len() as f64).cbrt();
        let dims: [usize; 3] = std::array::from_fn(|k| {
            let n = (extent[k] / width).floor();
            (if n.is_finite() { n.clamp(1.0, 1e6) } else { 1.0 }) as usize
        });
        let grid_width = match period {
            // Periodic: cells tile the period exactly (widths may differ per axis slightly;
            // use the largest for the distance bound).
            Some(l) => (0..3).map(|k| l[k] / dims[k] as f64).fold(0.0, f64::max),
            None => (0..3)
                .map(|k| extent[k] / dims[k] as f64)
                .fold(0.0, f64::max)
                .max(width),
        };
        let mut g = Grid {
            dims,
            width: grid_width,
            origin: lo,
            period,
            start: Vec::new(),
            items: Vec::new(),
        };
        let ncell = dims[0] * dims[1] * dims[2];
        let cell_of: Vec<usize> = pos.iter().map(|p| g.flat(g.index(p))).collect();
        let mut count = vec![0u32; ncell + 1];
        for &c in &cell_of {
            count[c + 1] += 1;
        }
        for c in 0..ncell {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; pos.len()];
        for (i, &c) in cell_of.iter().enumerate() {
            items[fill[c] as usize] = i as u32;
            fill[c] += 1;
        }
        g.start = count;
        g.items = items;
        g
    }

    fn index(&self, p: &Vec3) -> [i64; 3] {
        std::array::from_fn(|k| {
            let w = match self.period {
                Some(l) => l[k] / self.dims[k] as f64,
                None => self.width,
            };
            let i = ((p[k] - self.origin[k]) / w).floor();
            (if i.is_finite() { i } else { 0.0 }).clamp(0.0, (self.dims[k] - 1) as f64) as i64
        })
    }

    fn flat(&self, i: [i64; 3]) -> usize {
        (i[0] as usize) + self.dims[0] * ((i[1] as usize) + self.dims[1] * (i[2] as usize))
    }

    /// The sites of grid cell `at + offset` with the shift (m) to add to their positions
    /// (periodic images); nothing for a cell outside a walled grid.
    fn block(&self, at: [i64; 3], offset: [i64; 3], mut visit: impl FnMut(u32, Vec3)) {
        let mut idx = [0i64; 3];
        let mut shift = Vec3::zeros();
        for k in 0..3 {
            let i = at[k] + offset[k];
            let n = self.dims[k] as i64;
            match self.period {
                Some(l) => {
                    idx[k] = i.rem_euclid(n);
                    shift[k] = i.div_euclid(n) as f64 * l[k];
                }
                None if (0..n).contains(&i) => idx[k] = i,
                None => return,
            }
        }
        let c = self.flat(idx);
        for &q in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
            visit(q, shift);
        }
    }

    /// The largest Chebyshev offset searched: every grid cell of a walled grid, or as far as
    /// every image stays distinct in a periodic grid (2·layer + 1 ≤ dims).
    fn max_layer(&self) -> i64 {
        match self.period {
            Some(_) => (*self.dims.iter().min().expect("3 dims") as i64 - 1) / 2,
            None => *self.dims.iter().max().expect("3 dims") as i64 - 1,
        }
    }

    /// Offsets of the grid cells up to `layer` (Chebyshev), sorted by the smallest distance
    /// (m) from any point of the centre cell to any point of the offset cell.
    fn offsets(&self, layer: i64) -> Vec<([i64; 3], f64)> {
        let mut v = Vec::with_capacity(((2 * layer + 1) as usize).pow(3));
        for dz in -layer..=layer {
            for dy in -layer..=layer {
                for dx in -layer..=layer {
                    let gap = |d: i64| (d.abs() - 1).max(0) as f64;
                    let m = self.width * (gap(dx).powi(2) + gap(dy).powi(2) + gap(dz).powi(2)).sqrt();
                    v.push(([dx, dy, dz], m));
                }
            }
        }
        v.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        v
    }
}

/// A neighbour whose power plane cut the cell: its id and displacement from the site (m).
#[derive(Debug, Clone, Copy)]
struct Candidate {
    q: u32,
    disp: Vec3,
}

/// One cell's result.
#[derive(Debug, Default)]
struct CellOut {
    volume: f64,
    /// (q, area, displacement, centroid relative to the site) per facet towards a larger id
    /// q, sorted by q: the graph's record of that facet.
    up: Vec<(u32, f64, Vec3, Vec3)>,
    /// (q, area) per facet towards a smaller id q, sorted by q: only to check the facet
    /// against q's record (its area, and that q lists it), so each facet's full record is
    /// kept once, not twice.
    down: Vec<(u32, f64)>,
    /// (wall tag, vector area Σ A n, Σ A h, Σ A, Σ A c) per wall.
    walls: Vec<(Tag, Vec3, f64, f64, Vec3)>,
    curved_planes: usize,
    layers: usize,
    tried: u64,
    cut: u64,
    /// Distance from the site to the cell's farthest vertex (m).
    far: f64,
}

/// The state of one cell's neighbour search.
struct Search {
    /// The site (m).
    x: Vec3,
    /// Its radius (m).
    rp: f64,
    /// Clipping tolerance (m).
    tol: f64,
    /// Squared largest vertex distance of the cell so far (m²).
    rho2: f64,
    /// The first failure.
    failed: Option<CellFail>,
}

/// Why one cell failed.
#[derive(Debug)]
enum CellFail {
    Overlap { q: u32, distance: f64 },
    Coincident { q: u32, distance: f64 },
    Empty,
    Degenerate,
    TooSmallPeriod { layers: i64 },
}

/// Inputs shared by every cell.
struct Setup<'a> {
    pos: &'a [Vec3],
    radii: &'a [f64],
    container: &'a Container,
    carve: Option<&'a Region>,
    grid: Grid,
    /// Grid offsets in order of distance.
    offsets: &'a [([i64; 3], f64)],
    /// Whether the offsets reach every grid cell from every other (walled grids).
    offsets_cover_grid: bool,
    /// A cylinder container's mantle as one polygon: the outward normals of its tangent
    /// planes (empty for other containers).
    mantle: Vec<Vec3>,
    /// The cylinder's radius (m).
    mantle_radius: f64,
    r_max: f64,
    params: LaguerreParams,
}

impl Setup<'_> {
    /// The error of a failed cell, naming the particle.
    fn error(&self, p: usize, e: CellFail) -> GraphError {
        cell_error(
            p,
            e,
            self.pos,
            self.radii,
            self.container,
            self.params.max_overlap,
        )
    }

    /// Builds the cell of site `p` into `cell`.
    fn cell(
        &self,
        p: usize,
        cell: &mut Cell,
        cands: &mut Vec<Candidate>,
        near: &mut Vec<(f64, u32, Vec3)>,
    ) -> Result<CellOut, CellFail> {
        let x = self.pos[p];
        let rp = self.radii[p];
        let tol = 1e-12 * rp.max(self.grid.width);
        let mut out = CellOut::default();
        self.start_box(x, cell);
        // Curved container walls and the carving surface: the tangent plane nearest the site
        // first, so that the neighbour search starts from a small cell.
        self.curve_clip(x, rp, cell, &mut out, true)?;
        // Neighbours, grid cells in order of distance: each power plane that can reach the
        // cell clips it at once (nearest first, roughly). Certified when no sphere at a
        // distance d ≥ D (the next grid cell's) can reach it: its plane offset is at least
        // (D² + R_p² − R_max²)/(2D).
        let at = self.grid.index(&x);
        cands.clear();
        let mut st = Search {
            x,
            rp,
            tol,
            rho2: cell.max_radius_sq(),
            failed: None,
        };
        // The adjacent grid cells first, nearest power plane first: they make the cell nearly
        // final, so that most later planes are rejected without clipping.
        let adjacent = self.offsets.iter().take_while(|o| o.1 == 0.0).count();
        near.clear();
        for &(offset, _) in &self.offsets[..adjacent] {
            self.grid.block(at, offset, |q, shift| {
                if !(q as usize == p && offset == [0, 0, 0]) {
                    let disp = self.pos[q as usize] + shift - x;
                    let rq = self.radii[q as usize];
                    let d2 = disp.norm_squared();
                    let c = (d2 + rp * rp - rq * rq) / d2.sqrt().max(f64::MIN_POSITIVE);
                    near.push((c, q, shift));
                }
            });
        }
        near.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(_, q, shift) in near.iter() {
            self.consider(&mut st, q, shift, cell, cands, &mut out);
        }
        out.layers = 1;
        let mut certified = false;
        for &(offset, dmin) in &self.offsets[adjacent..] {
            let bound = (dmin * dmin + rp * rp - self.r_max * self.r_max) / (2.0 * dmin);
            if bound > 0.0 && bound * bound > st.rho2 && !cell.tags.contains(&BOUND) {
                certified = true;
                break;
            }
            out.layers = out.layers.max(
                offset
                    .iter()
                    .map(|o| o.unsigned_abs() as usize)
                    .max()
                    .unwrap_or(0),
            );
            self.grid.block(at, offset, |q, shift| {
                self.consider(&mut st, q, shift, cell, cands, &mut out)
            });
        }
        if !certified && st.failed.is_none() {
            match self.grid.period {
                // Past the offsets searched, images could repeat.
                Some(_) => {
                    return Err(CellFail::TooSmallPeriod {
                        layers: out.layers as i64 + 1,
                    });
                }
                // A sparse or irregular set: every other site, beyond the grid cells seen.
                None if self.offsets_cover_grid => {}
                None => {
                    let layers = out.layers as i64;
                    for q in 0..self.pos.len() as u32 {
                        let i = self.grid.index(&self.pos[q as usize]);
                        if (0..3).any(|k| (i[k] - at[k]).abs() > layers) {
                            self.consider(&mut st, q, Vec3::zeros(), cell, cands, &mut out);
                        }
                    }
                }
            }
        }
        if let Some(f) = st.failed {
            return Err(f);
        }
        self.curve_clip(x, rp, cell, &mut out, false)?;
        self.faces(p, cell, cands, &mut out)?;
        out.far = cell.max_radius_sq().sqrt();
        out.up.sort_unstable_by_key(|f| f.0);
        out.down.sort_unstable_by_key(|f| f.0);
        if out.up.windows(2).any(|w| w[0].0 == w[1].0) || out.down.windows(2).any(|w| w[0].0 == w[1].0) {
            // Two facets with one neighbour: two of its images (refused in periodic boxes).
            return Err(CellFail::TooSmallPeriod {
                layers: out.layers as i64,
            });
        }
        Ok(out)
    }

    /// The cell of the site at `x` before any neighbour: half a period around it in a
    /// periodic box (BOUND faces), else the container's bounding box with its walls' tags.
    #[inline]
    fn start_box(&self, x: Vec3, cell: &mut Cell) {
        match (self.container, self.container.period()) {
            (_, Some(l)) => {
                // Large enough for any cell the search can certify; BOUND faces that survive
                // mean the cell was not closed by its neighbours.
                let h = Vec3::new(l[0], l[1], l[2]) * 0.5;
                cell.reset_box(-h, h, [BOUND; 6]);
            }
            (c, None) => {
                let b = c.bounds();
                let tags: [Tag; 6] = match c {
                    Container::Box { .. } => std::array::from_fn(|k| wall_tag(k as u32)),
                    Container::Cylinder { .. } => {
                        let o = wall_tag(6);
                        [o, o, o, o, wall_tag(4), wall_tag(5)]
                    }
                    _ => [wall_tag(6); 6],
                };
                cell.reset_box(b.min - x, b.max - x, tags);
            }
        }
    }

    /// The clipped cell's volume, facets (towards larger ids with their geometry, towards
    /// smaller ids with their area) and wall facets into `out`; refused when a face is still
    /// the starting box's (the period is too small).
    #[inline]
    fn faces(&self, p: usize, cell: &Cell, cands: &[Candidate], out: &mut CellOut) -> Result<(), CellFail> {
        out.volume = cell.volume();
        // Faces. The facet list is allocated at its exact length: a million cells' lists
        // grown by doubling would hold a third more memory than their facets.
        let (mut ups, mut downs) = (0, 0);
        for f in 0..cell.n_faces() {
            let tag = cell.tags[f];
            if tag < WALL_BASE {
                if cands[tag as usize].q as usize > p {
                    ups += 1;
                } else {
                    downs += 1;
                }
            }
        }
        out.up.reserve_exact(ups);
        out.down.reserve_exact(downs);
        for f in 0..cell.n_faces() {
            let tag = cell.tags[f];
            let a = cell.vector_area(f);
            let area = a.norm();
            if tag >= WALL_BASE {
                let h = a.dot(&cell.verts[cell.face(f)[0] as usize]);
                let c = area * cell.centroid(f);
                match out.walls.iter_mut().find(|w| w.0 == tag) {
                    Some(w) => {
                        w.1 += a;
                        w.2 += h;
                        w.3 += area;
                        w.4 += c;
                    }
                    None => out.walls.push((tag, a, h, area, c)),
                }
            } else if tag == BOUND {
                return Err(CellFail::TooSmallPeriod {
                    layers: self.grid.max_layer() + 1,
                });
            } else {
                let cd = cands[tag as usize];
                if cd.q as usize > p {
                    out.up.push((cd.q, area, cd.disp, cell.centroid(f)));
                } else {
                    out.down.push((cd.q, area));
                }
            }
        }
        Ok(())
    }

    /// Clips the cell by the power plane of site `q` (displaced by `shift`) when it can reach
    /// the cell; a neighbour that cuts is appended to `cands` (its index is the face tag).
    fn consider(
        &self,
        st: &mut Search,
        q: u32,
        shift: Vec3,
        cell: &mut Cell,
        cands: &mut Vec<Candidate>,
        out: &mut CellOut,
    ) {
        if st.failed.is_some() {
            return;
        }
        let disp = self.pos[q as usize] + shift - st.x;
        let d2 = disp.norm_squared();
        let (rp, rq) = (st.rp, self.radii[q as usize]);
        // The plane offset c = (d² + R_p² − R_q²)/(2d) can cut only if c² < ρ² (or c ≤ 0).
        let num = d2 + rp * rp - rq * rq;
        if num > 0.0 && num * num >= 4.0 * d2 * st.rho2 {
            return;
        }
        let dist = d2.sqrt();
        if dist <= 1e-12 * (rp + rq) {
            st.failed = Some(CellFail::Coincident { q, distance: dist });
            return;
        }
        if rp + rq - dist > self.params.max_overlap * rp.min(rq) {
            st.failed = Some(CellFail::Overlap { q, distance: dist });
            return;
        }
        out.tried += 1;
        match cell.clip(&(disp / dist), num / (2.0 * dist), cands.len() as Tag, st.tol) {
            Ok(true) => {
                out.cut += 1;
                cands.push(Candidate { q, disp });
                st.rho2 = cell.max_radius_sq();
            }
            Ok(false) => {}
            Err(e) => st.failed = Some(fail(e)),
        }
    }

    /// Clips by planes tangent to the curved container walls and the carving surface: only
    /// at the point nearest the site when `first`, else at the vertex farthest outside
    /// until all are within tolerance.
    fn curve_clip(
        &self,
        x: Vec3,
        rp: f64,
        cell: &mut Cell,
        out: &mut CellOut,
        first: bool,
    ) -> Result<(), CellFail> {
        let tol = 1e-12 * rp.max(self.grid.width);
        let limit = self.params.curved_tolerance * rp;
        if !first && !self.mantle.is_empty() {
            // A cylinder's mantle: the one global polygon of tangent planes, so that two
            // neighbouring cells are cut alike and their shared facet is the same polygon.
            let radius = self.mantle_radius;
            for n in &self.mantle {
                let c = radius - n.dot(&x);
                if (c <= 0.0 || c * c < cell.max_radius_sq())
                    && cell.clip(n, c, wall_tag(6), tol).map_err(fail)?
                {
                    out.curved_planes += 1;
                }
            }
        }
        let surfaces: [(Option<Surface>, u32); 2] = [
            (
                match *self.container {
                    Container::Sphere { radius } => Some(Surface::Sphere(radius)),
                    _ => None,
                },
                6,
            ),
            (self.carve.map(Surface::Region), CARVED),
        ];
        for (surface, code) in surfaces {
            let Some(surface) = surface else { continue };
            if first {
                // The site is inside: the plane tangent at its nearest surface point.
                if let Some((n, c)) = surface.tangent(&x, rp)
                    && cell.clip(&n, c - n.dot(&x), wall_tag(code), tol).map_err(fail)?
                {
                    out.curved_planes += 1;
                }
                continue;
            }
            // Only cells that can reach the surface (signed distance is 1-Lipschitz).
            let reach = cell.max_radius_sq().sqrt();
            if surface.distance(&x) + reach <= limit {
                continue;
            }
            for _ in 0..self.params.max_curved_planes {
                let (mut worst, mut at) = (limit, None);
                for v in &cell.verts {
                    let s = surface.distance(&(x + v));
                    if s > worst {
                        worst = s;
                        at = Some(x + v);
                    }
                }
                let Some(y) = at else { break };
                // Where the segment from the site to the vertex leaves the domain: its tangent
                // plane keeps the site even where the surface is concave (a groove's corner),
                // where the plane at the vertex's nearest surface point may not.
                let exit = surface.exit(&x, &y);
                let Some((n, c)) = surface.tangent(&exit, rp) else {
                    break;
                };
                if n.dot(&x) > c - 1e-9 * rp {
                    // The plane would cut the site off its own cell: leave the rest (reported
                    // in the volume error).
                    break;
                }
                if cell.clip(&n, c - n.dot(&x), wall_tag(code), tol).map_err(fail)? {
                    out.curved_planes += 1;
                } else {
                    break;
                }
            }
        }
        Ok(())
    }
}

/// The outward normals of a regular polygon of tangent planes that follows a circle of
/// `radius` (m) within `sagitta` (m): M sides with R (1/cos(π/M) − 1) ≤ sagitta, M a multiple
/// of 4 (so that the bounding box's faces are four of its sides), at least 16.
fn mantle_polygon(radius: f64, sagitta: f64) -> Vec<Vec3> {
    let ratio = (sagitta / radius).max(1e-12);
    let half = (1.0 / (1.0 + ratio)).acos();
    let m = ((std::f64::consts::PI / half).ceil() as usize).clamp(16, 1 << 16);
    let m = m.div_ceil(4) * 4;
    (0..m)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * k as f64 / m as f64;
            Vec3::new(t.cos(), t.sin(), 0.0)
        })
        .collect()
}

fn fail(e: ClipError) -> CellFail {
    match e {
        ClipError::Empty => CellFail::Empty,
        ClipError::Degenerate => CellFail::Degenerate,
    }
}

/// A curved surface bounding the cells.
#[derive(Clone, Copy)]
enum Surface<'a> {
    /// A sphere about the origin (radius, m).
    Sphere(f64),
    /// A region's boundary (cells stay inside).
    Region(&'a Region),
}

impl Surface<'_> {
    /// Signed distance (m), positive outside the domain.
    fn distance(&self, y: &Vec3) -> f64 {
        match *self {
            Surface::Sphere(r) => y.norm() - r,
            Surface::Region(region) => region.signed_distance(y),
        }
    }

    /// The point where the segment from `inside` (distance < 0) to `outside` (distance > 0)
    /// crosses the surface, by bisection to 1e-12 of the segment.
    fn exit(&self, inside: &Vec3, outside: &Vec3) -> Vec3 {
        let (mut a, mut b) = (*inside, *outside);
        for _ in 0..40 {
            let m = 0.5 * (a + b);
            if self.distance(&m) > 0.0 {
                b = m;
            } else {
                a = m;
            }
        }
        0.5 * (a + b)
    }

    /// The plane tangent at the surface point nearest `y`: (unit outward normal n, offset c)
    /// with the domain side n·z ≤ c (absolute coordinates). `None` where the normal is
    /// undefined (on the axis or centre).
    fn tangent(&self, y: &Vec3, scale: f64) -> Option<(Vec3, f64)> {
        match *self {
            Surface::Sphere(r) => {
                let l = y.norm();
                (l > 0.0).then(|| (y / l, r))
            }
            Surface::Region(region) => {
                let h = 1e-6 * scale;
                let g = Vec3::new(
                    region.signed_distance(&(y + Vec3::x() * h))
                        - region.signed_distance(&(y - Vec3::x() * h)),
                    region.signed_distance(&(y + Vec3::y() * h))
                        - region.signed_distance(&(y - Vec3::y() * h)),
                    region.signed_distance(&(y + Vec3::z() * h))
                        - region.signed_distance(&(y - Vec3::z() * h)),
                );
                let l = g.norm();
                if !(l > 0.0 && l.is_finite()) {
                    return None;
                }
                let n = g / l;
                let foot = y - region.signed_distance(y) * n;
                Some((n, n.dot(&foot)))
            }
        }
    }
}

/// The Laguerre tessellation of `particles` in `container`, clipped by `carve` when given:
/// a [`ContactGraph`] of the cells sharing a facet, with [`Cells`] (facet areas, splits,
/// cell volumes, wall facets) and a report.
///
/// Errors (naming the particle and the value): invalid parameters or particles, coincident
/// centres, an overlap above `max_overlap`, a particle outside the container, an empty or
/// degenerate cell, a periodic box too small for the search.
pub fn tessellate(
    particles: &ParticleSet,
    container: &Container,
    carve: Option<&Region>,
    params: &LaguerreParams,
) -> Result<ContactGraph, GraphError> {
    let start = Instant::now();
    with_setup(particles, container, carve, params, |setup| {
        let cells = build_cells(setup, particles.len())?;
        let r_mean = particles.radii.iter().sum::<f64>() / particles.len() as f64;
        assemble(
            particles,
            container,
            carve,
            cells,
            params,
            (r_mean, particles.len()),
            start,
        )
    })
}

/// The Laguerre cells of the first `owned` particles only, the others being read-only
/// neighbours (an MPI rank's ghosts, `docs/distributed.md`): the graph holds every facet of an
/// owned cell (towards owned or other particles), each area as the owned side computes it;
/// the other particles' cells are empty (volume 0, no wall facet) and their facets among
/// themselves absent (all particles owned: the graph of [`tessellate`]). Also returns each
/// owned cell's reach ρ_p, the distance from its site to
/// its farthest vertex (m): a sphere j of radius ≤ R_max can cut cell p only if
/// |x_j − x_p| < ρ_p + √(ρ_p² − R_p² + R_max²), so when every sphere within that distance of
/// an owned site is among `particles`, the owned cells are those of the whole packing.
///
/// Errors: those of [`tessellate`]; `owned` above the particle count.
pub fn tessellate_part(
    particles: &ParticleSet,
    container: &Container,
    carve: Option<&Region>,
    params: &LaguerreParams,
    owned: usize,
) -> Result<(ContactGraph, Vec<f64>), GraphError> {
    if owned > particles.len() {
        return Err(CoreError::invalid(
            "owned",
            owned,
            format!("at most the particle count ({})", particles.len()),
        )
        .into());
    }
    let start = Instant::now();
    with_setup(particles, container, carve, params, |setup| {
        let mut cells = build_cells(setup, owned)?;
        let reach: Vec<f64> = cells.iter().map(|c| c.far).collect();
        cells.resize_with(particles.len(), CellOut::default);
        let r_mean = particles.radii.iter().sum::<f64>() / particles.len() as f64;
        let graph = assemble(particles, container, carve, cells, params, (r_mean, owned), start)?;
        Ok((graph, reach))
    })
}

/// The cells of the first `owned` sites, in parallel (each depends only on its own inputs).
fn build_cells(setup: &Setup<'_>, owned: usize) -> Result<Vec<CellOut>, GraphError> {
    let results: Vec<Result<CellOut, CellFail>> = (0..owned)
        .into_par_iter()
        .map_init(
            || (Cell::default(), Vec::new(), Vec::new()),
            |(cell, cands, near), p| setup.cell(p, cell, cands, near),
        )
        .collect();
    let mut cells = Vec::with_capacity(setup.pos.len());
    for (p, r) in results.into_iter().enumerate() {
        cells.push(r.map_err(|e| setup.error(p, e))?);
    }
    Ok(cells)
}

/// The ghost width (m) that certifies cells built by [`tessellate_part`]: the largest
/// ρ_p + √(ρ_p² − R_p² + R_max²) over the owned cells (`radii` and `reach` theirs, `r_max` the
/// largest radius of the whole packing). When every sphere within this distance of an owned
/// centre was among the particles, no missing sphere could have cut an owned cell.
pub fn ghost_width_needed(radii: &[f64], reach: &[f64], r_max: f64) -> f64 {
    radii
        .iter()
        .zip(reach)
        .map(|(&r, &rho)| rho + (rho * rho - r * r + r_max * r_max).max(0.0).sqrt())
        .fold(0.0, f64::max)
}

/// A convex polyhedron: its vertices (m) and its faces as loops of indices into them.
pub type Polyhedron = (Vec<Vec3>, Vec<Vec<u32>>);

/// The Laguerre cells of the particles `which`, built as [`tessellate`] builds them, as
/// polyhedra for drawing (`cells.vtu`): each cell's vertices (m; a periodic cell may reach
/// past the box) and faces (vertex loops, counter-clockwise seen from outside).
///
/// Errors: those of [`tessellate`]; an index of `which` out of range.
pub fn cell_polyhedra(
    particles: &ParticleSet,
    container: &Container,
    carve: Option<&Region>,
    params: &LaguerreParams,
    which: &[u32],
) -> Result<Vec<Polyhedron>, GraphError> {
    if let Some(&p) = which.iter().find(|&&p| p as usize >= particles.len()) {
        return Err(CoreError::invalid(
            "which",
            p,
            format!("a particle index (fewer than {})", particles.len()),
        )
        .into());
    }
    with_setup(particles, container, carve, params, |setup| {
        which
            .par_iter()
            .map_init(
                || (Cell::default(), Vec::new(), Vec::new()),
                |(cell, cands, near), &p| {
                    let p = p as usize;
                    setup.cell(p, cell, cands, near).map_err(|e| setup.error(p, e))?;
                    Ok(cell.polyhedron(setup.pos[p]))
                },
            )
            .collect()
    })
}

/// Checks the particles, prepares the search grid and hands the cell builder to `f`.
fn with_setup<R>(
    particles: &ParticleSet,
    container: &Container,
    carve: Option<&Region>,
    params: &LaguerreParams,
    f: impl FnOnce(&Setup) -> Result<R, GraphError>,
) -> Result<R, GraphError> {
    params.validate()?;
    let prepared = prepare(particles, container)?;
    let pos: &[Vec3] = &prepared.pos;
    let n = particles.len();
    let radii = &particles.radii;
    if container.period().is_none() {
        let b = container.bounds();
        if let Some(i) = (0..n).find(|&i| {
            let c = pos[i];
            container.wall_distance(&c) < 0.0 || !(b.contains(&c))
        }) {
            return Err(CoreError::invalid(
                format!("particles[{i}]"),
                format!("centre ({:e}, {:e}, {:e}) m", pos[i].x, pos[i].y, pos[i].z),
                format!("centres must lie inside the {} container", container.kind()),
            )
            .into());
        }
    }
    if let Some(region) = carve
        && let Some(i) = (0..n).find(|&i| region.signed_distance(&pos[i]) > 0.0)
    {
        return Err(CoreError::invalid(
            format!("particles[{i}]"),
            format!("centre ({:e}, {:e}, {:e}) m", pos[i].x, pos[i].y, pos[i].z),
            "centres must lie inside the carving region",
        )
        .into());
    }
    let (lo, hi) = match container.period() {
        Some(l) => (Vec3::zeros(), Vec3::new(l[0], l[1], l[2])),
        None => {
            let b = container.bounds();
            (b.min, b.max)
        }
    };
    let r_max = radii.iter().copied().fold(0.0, f64::max);
    let r_mean = radii.iter().sum::<f64>() / n as f64;
    let grid = Grid::new(pos, lo, hi, container.period());
    let layers = grid.max_layer().min(MAX_SEARCH_LAYERS);
    let offsets = grid.offsets(layers);
    let offsets_cover_grid = layers == grid.max_layer();
    let (mantle, mantle_radius) = match *container {
        Container::Cylinder { radius, .. } => {
            (mantle_polygon(radius, params.curved_tolerance * r_mean), radius)
        }
        _ => (Vec::new(), 0.0),
    };
    let setup = Setup {
        pos,
        radii,
        container,
        carve,
        grid,
        offsets: &offsets,
        offsets_cover_grid,
        mantle,
        mantle_radius,
        r_max,
        params: *params,
    };
    f(&setup)
}

/// The error of a failed cell, naming the particle.
fn cell_error(
    p: usize,
    e: CellFail,
    pos: &[Vec3],
    radii: &[f64],
    container: &Container,
    max_overlap: f64,
) -> GraphError {
    let at = |i: usize| {
        format!(
            "centre ({:e}, {:e}, {:e}) m, radius {:e} m",
            pos[i].x, pos[i].y, pos[i].z, radii[i]
        )
    };
    match e {
        CellFail::Coincident { q, distance } => GraphError::CoincidentCentres {
            p: (p as u32).min(q),
            q: (p as u32).max(q),
            distance,
        },
        CellFail::Overlap { q, distance } => {
            let (rp, rq) = (radii[p], radii[q as usize]);
            CoreError::invalid(
                format!("particles[{p}] and particles[{q}]"),
                format!(
                    "distance {distance:e} m, radii {rp:e} m and {rq:e} m: an overlap of {:.3} × the smaller radius",
                    (rp + rq - distance) / rp.min(rq)
                ),
                format!(
                    "the Laguerre cells need spheres that overlap by at most {} × the smaller radius (a packing \
                     file whose positions and radii are in different units, or a soft-sphere DEM state compressed \
                     past that: check the file with `demcon info`)",
                    max_overlap
                ),
            )
            .into()
        }
        CellFail::Empty => CoreError::invalid(
            format!("particles[{p}]"),
            at(p),
            "its Laguerre cell is empty (the sphere lies inside the power planes of its neighbours)",
        )
        .into(),
        CellFail::Degenerate => CoreError::invalid(
            format!("particles[{p}]"),
            at(p),
            "its Laguerre cell is numerically degenerate (planes meeting within round-off)",
        )
        .into(),
        CellFail::TooSmallPeriod { layers } => CoreError::invalid(
            "container.size",
            format!("{:?} m", container.period().unwrap_or([0.0; 3])),
            format!(
                "the periodic box is too small for the tessellation: the cell of particles[{p}] needs neighbours \
                 {layers} grid layers away, which would meet their own images"
            ),
        )
        .into(),
    }
}

/// Particles per block of the graph's fill (each block writes its own slices).
const FILL_BLOCK: usize = 4096;

/// The blocks `lo..hi` of [`FILL_BLOCK`] particles that cover `0..n`.
fn fill_blocks(n: usize) -> Vec<(usize, usize)> {
    (0..n)
        .step_by(FILL_BLOCK)
        .map(|b| (b, (b + FILL_BLOCK).min(n)))
        .collect()
}

/// How many facets each cell records (those towards larger ids that `facet` keeps), as the
/// start of each cell's range in the graph's arrays (n + 1 offsets): the arrays are then
/// allocated once at their final size and filled in place.
fn facet_offsets<F>(cells: &[CellOut], facet: &F) -> Vec<usize>
where
    F: Fn(usize, u32, f64, Vec3) -> Option<(f64, Vec3, f64, bool)> + Sync,
{
    let counts: Vec<u32> = cells
        .par_iter()
        .enumerate()
        .map(|(p, c)| {
            c.up.iter()
                .filter(|&&(q, a1, _, c1)| facet(p, q, a1, c1).is_some())
                .count() as u32
        })
        .collect();
    let mut offsets = Vec::with_capacity(cells.len() + 1);
    offsets.push(0usize);
    for &c in &counts {
        offsets.push(offsets[offsets.len() - 1] + c as usize);
    }
    offsets
}

/// One block's share of the graph's arrays.
struct BlockOut<'a> {
    pairs: &'a mut [[u32; 2]],
    geometry: &'a mut [ContactGeometry],
    area: &'a mut [f64],
    split: &'a mut [f64],
    centroid: &'a mut [Vec3],
}

impl<'a> BlockOut<'a> {
    /// The first `len` facets, and the rest.
    fn split_at(self, len: usize) -> (BlockOut<'a>, BlockOut<'a>) {
        let (a0, a1) = self.pairs.split_at_mut(len);
        let (b0, b1) = self.geometry.split_at_mut(len);
        let (c0, c1) = self.area.split_at_mut(len);
        let (d0, d1) = self.split.split_at_mut(len);
        let (e0, e1) = self.centroid.split_at_mut(len);
        (
            BlockOut {
                pairs: a0,
                geometry: b0,
                area: c0,
                split: d0,
                centroid: e0,
            },
            BlockOut {
                pairs: a1,
                geometry: b1,
                area: c1,
                split: d1,
                centroid: e1,
            },
        )
    }
}

/// Fills the facets the cells `lo..hi` record (towards larger ids, kept by `facet`) into
/// `out`, in the particles' order; returns the block's counts. `threshold`: the area below
/// which a facet drops (m²); `radii` (m) place each facet's split point.
fn fill_block<F>(
    cells: &[CellOut],
    (lo, hi): (usize, usize),
    out: BlockOut<'_>,
    facet: &F,
    (threshold, radii): (f64, &[f64]),
    period: Option<[f64; 3]>,
) -> BlockStats
where
    F: Fn(usize, u32, f64, Vec3) -> Option<(f64, Vec3, f64, bool)> + Sync,
{
    let (mut dropped, mut one_sided, mut mismatch, mut too_small) = (0, 0, 0.0f64, None);
    let mut k = 0;
    for p in lo..hi {
        // Facets towards smaller ids are counted from q's side, unless q does not list
        // p at all (then it is lost: reported as one-sided).
        for &(q, a1) in &cells[p].down {
            let listed = cells[q as usize]
                .up
                .binary_search_by_key(&(p as u32), |e| e.0)
                .is_ok();
            if a1 >= threshold && !listed {
                one_sided += 1;
            }
        }
        for &(q, a1, disp, c1) in &cells[p].up {
            let Some((area, c, mis, one)) = facet(p, q, a1, c1) else {
                dropped += 1;
                continue;
            };
            if one {
                one_sided += 1;
            } else {
                mismatch = mismatch.max(mis);
            }
            if let Some(l) = period
                && too_small.is_none()
                && (0..3).any(|i| disp[i].abs() > 0.5 * l[i])
            {
                too_small = Some((p as u32, q));
            }
            let d = disp.norm();
            let (rp, rq) = (radii[p], radii[q as usize]);
            out.pairs[k] = [p as u32, q];
            out.geometry[k] = ContactGeometry {
                distance: d,
                normal: disp / d,
            };
            out.area[k] = area;
            out.centroid[k] = c;
            out.split[k] = (d * d + rp * rp - rq * rq) / (2.0 * d * d);
            k += 1;
        }
    }
    debug_assert_eq!(k, out.pairs.len());
    (dropped, one_sided, mismatch, too_small)
}

/// Per block of cells: dropped facets, one-sided facets, largest area mismatch, first pair
/// across more than half a period.
type BlockStats = (usize, usize, f64, Option<(u32, u32)>);

/// The blocks' totals: dropped facets, one-sided facets, largest area mismatch; refused when a
/// facet spans more than half the period of the box `period`.
fn block_totals(stats: &[BlockStats], period: Option<[f64; 3]>) -> Result<(usize, usize, f64), GraphError> {
    let (mut one_sided, mut mismatch, mut dropped_facets) = (0usize, 0.0f64, 0usize);
    for &(d, o, m, too_small) in stats {
        dropped_facets += d;
        one_sided += o;
        mismatch = mismatch.max(m);
        if let (Some((p, q)), Some(l)) = (too_small, period) {
            return Err(CoreError::invalid(
                "container.size",
                format!("{l:?} m"),
                format!(
                    "the periodic box is too small for the tessellation: particles {p} and {q} share a facet \
                     across more than half a period"
                ),
            )
            .into());
        }
    }
    Ok((dropped_facets, one_sided, mismatch))
}

/// How the cells met the container's curved walls and the planes they tried.
#[derive(Debug, Clone, Copy, Default)]
struct PlaneCounts {
    curved_cells: usize,
    curved_planes: usize,
    max_layers: usize,
    tried: u64,
    cut: u64,
}

/// The cells' wall facets at or above the area `threshold` (m²), per particle in face order,
/// and the plane counts.
fn wall_facets(cells: &[CellOut], threshold: f64) -> (Vec<WallFacet>, PlaneCounts) {
    let mut k = PlaneCounts::default();
    let mut walls = Vec::new();
    for (p, c) in cells.iter().enumerate() {
        if c.curved_planes > 0 {
            k.curved_cells += 1;
        }
        k.curved_planes += c.curved_planes;
        k.max_layers = k.max_layers.max(c.layers);
        k.tried += c.tried;
        k.cut += c.cut;
        let mut w: Vec<WallFacet> = c
            .walls
            .iter()
            .filter(|w| w.3 >= threshold)
            .map(|&(tag, a, h, area, c)| WallFacet {
                particle: p as u32,
                wall: wall_of(tag),
                area,
                distance: h / area,
                normal: a.normalize(),
                centroid: c / area,
            })
            .collect();
        w.sort_by_key(|f| match f.wall {
            CellWall::Face(face) => FACES.iter().position(|&x| x == face).unwrap_or(0),
            CellWall::Carved => 7,
        });
        walls.extend(w);
    }
    (walls, k)
}

/// Pairs the two sides of every facet into the graph, and reports.
fn assemble(
    particles: &ParticleSet,
    container: &Container,
    carve: Option<&Region>,
    cells: Vec<CellOut>,
    params: &LaguerreParams,
    (r_mean, owned): (f64, usize),
    start: Instant,
) -> Result<ContactGraph, GraphError> {
    let n = particles.len();
    let radii = &particles.radii;
    let threshold = params.negligible_area * r_mean * r_mean;
    // Each facet recorded by its smaller id p, checked against q's side (its area; cells'
    // lists are sorted by neighbour, so a binary search finds it). Facets below the threshold
    // drop. The centroid is p's (both sides compute the same polygon, to round-off).
    let side = |p: usize, q: u32| -> Option<f64> {
        let f = &cells[q as usize].down;
        f.binary_search_by_key(&(p as u32), |e| e.0)
            .ok()
            .map(|i| f[i].1)
            .filter(|&a| a >= threshold)
    };
    // One facet as p records it: (area, centroid relative to p, area mismatch, one-sided),
    // or None if dropped.
    // Facets towards particles whose cells are not built (`owned` and above) have one side.
    let facet = |p: usize, q: u32, a1: f64, c1: Vec3| match ((a1 >= threshold).then_some(a1), side(p, q)) {
        (a, _) if q as usize >= owned => a.map(|a| (a, c1, 0.0, false)),
        (None, None) => None,
        (Some(a), Some(b)) => Some((0.5 * (a + b), c1, (a - b).abs() / a.max(b), false)),
        (Some(a), None) | (None, Some(a)) => Some((a, c1, 1.0, true)),
    };
    // Pass 1: how many facets each cell records (those towards larger ids that are kept), so
    // that the graph's arrays are allocated once at their final size and filled in place (a
    // list per cell, or arrays grown by doubling, cost up to three times the graph's memory).
    let offsets = facet_offsets(&cells, &facet);
    let total = offsets[n];
    let mut pairs = vec![[0u32; 2]; total];
    let mut geometry = vec![ContactGeometry::default(); total];
    let mut facet_area = vec![0.0; total];
    let mut split = vec![0.0; total];
    let mut centroid = vec![Vec3::zeros(); total];
    // Pass 2: fill, in blocks of particles writing to disjoint slices (the order is the
    // particles', so the result is the same for any thread count).
    let period = container.period();
    let blocks = fill_blocks(n);
    let mut slices = Vec::with_capacity(blocks.len());
    let mut rest = BlockOut {
        pairs: &mut pairs,
        geometry: &mut geometry,
        area: &mut facet_area,
        split: &mut split,
        centroid: &mut centroid,
    };
    for &(lo, hi) in &blocks {
        let (head, tail) = rest.split_at(offsets[hi] - offsets[lo]);
        slices.push(((lo, hi), head));
        rest = tail;
    }
    let stats: Vec<BlockStats> = slices
        .into_par_iter()
        .map(|(range, out)| fill_block(&cells, range, out, &facet, (threshold, radii), period))
        .collect();
    let (dropped_facets, one_sided, mismatch) = block_totals(&stats, period)?;
    let (walls, planes) = wall_facets(&cells, threshold);
    let volume: Vec<f64> = cells.iter().map(|c| c.volume).collect();
    let cells_volume: f64 = volume.iter().sum();
    let domain_volume = match carve {
        Some(r) => r.volume(256),
        None => container.volume(),
    };
    let mut graph = ContactGraph {
        n_particles: n,
        pairs,
        geometry,
        report: ContactReport {
            epsilon: 0.0,
            target_coordination: None,
            coordination: 0.0,
            n_contacts: 0,
            rattlers: Vec::new(),
            under_two_contacts: 0,
            overlaps: 0,
            n_components: 0,
            largest_component: 0,
            search: crate::NeighbourSearch::CellGrid,
            search_rounds: 1,
            candidates: planes.tried as usize,
            wall_time_s: 0.0,
            diagnostics: Vec::new(),
        },
        cells: Some(Box::new(Cells {
            facet_area,
            split,
            centroid,
            volume,
            walls,
            report: TessellationReport {
                dropped_facets,
                negligible_area_m2: threshold,
                one_sided_facets: one_sided,
                max_area_mismatch: mismatch,
                cells_volume,
                domain_volume,
                volume_error: cells_volume / domain_volume - 1.0,
                curved_cells: planes.curved_cells,
                curved_planes: planes.curved_planes,
                max_layers: planes.max_layers,
                planes_tried: planes.tried,
                planes_cut: planes.cut,
                wall_s: 0.0,
            },
        })),
        cut_degrees: Vec::new(),
    };
    summarise(&mut graph, radii);
    let wall_s = start.elapsed().as_secs_f64();
    graph.report.wall_time_s = wall_s;
    if let Some(c) = graph.cells.as_mut() {
        c.report.wall_s = wall_s;
    }
    Ok(graph)
}
