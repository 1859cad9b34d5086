//! One convex cell, clipped plane by plane: vertices relative to the cell's site, faces as
//! vertex loops (counter-clockwise seen from outside) in flat buffers reused between cells.

use demcon_core::Vec3;

/// What bounds a face: a neighbour (its index in the caller's candidate list), a wall of the
/// container, or the initial bounding box (`BOUND`, meaning "not yet clipped").
pub(crate) type Tag = u32;

/// The tag of a face of the initial bounding box that no plane has cut away yet.
pub(crate) const BOUND: Tag = u32::MAX;

/// Tags at or above this value are walls: `WALL_BASE + code`.
pub(crate) const WALL_BASE: Tag = u32::MAX - 64;

/// Why a clip could not be applied.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ClipError {
    /// The plane removes the whole cell.
    Empty,
    /// A face crosses the plane more than once, or the new face does not close: the cell is
    /// numerically degenerate.
    Degenerate,
}

/// A convex polyhedron around the origin (the site).
#[derive(Debug, Clone, Default)]
pub(crate) struct Cell {
    /// Vertex positions relative to the site (m).
    pub verts: Vec<Vec3>,
    /// Vertex ids of every face, face after face.
    pub loops: Vec<u32>,
    /// Face f owns `loops[start[f]..start[f + 1]]`.
    pub start: Vec<u32>,
    /// What bounds each face.
    pub tags: Vec<Tag>,
    // Scratch buffers of `clip`, kept to avoid allocating per plane.
    s: Vec<f64>,
    map: Vec<u32>,
    new_verts: Vec<Vec3>,
    new_loops: Vec<u32>,
    new_start: Vec<u32>,
    new_tags: Vec<Tag>,
    edges: Vec<(u32, u32, u32)>,
    cap: Vec<(u32, u32)>,
}

impl Cell {
    /// The cell as a polyhedron around the site `x` (m): the vertices its faces use, and the
    /// faces as loops of indices into them.
    pub fn polyhedron(&self, x: Vec3) -> super::Polyhedron {
        let mut local = vec![u32::MAX; self.verts.len()];
        let mut verts = Vec::new();
        let faces = (0..self.n_faces())
            .map(|f| {
                self.face(f)
                    .iter()
                    .map(|&v| {
                        if local[v as usize] == u32::MAX {
                            local[v as usize] = verts.len() as u32;
                            verts.push(x + self.verts[v as usize]);
                        }
                        local[v as usize]
                    })
                    .collect()
            })
            .collect();
        (verts, faces)
    }

    /// The axis-aligned box `[lo, hi]` (relative to the site, m) with the given face tags in
    /// the order −x, +x, −y, +y, −z, +z.
    pub fn reset_box(&mut self, lo: Vec3, hi: Vec3, tags: [Tag; 6]) {
        self.verts.clear();
        for k in 0..8 {
            self.verts.push(Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ));
        }
        // Loops counter-clockwise seen from outside.
        const FACES: [[u32; 4]; 6] = [
            [0, 4, 6, 2], // −x
            [1, 3, 7, 5], // +x
            [0, 1, 5, 4], // −y
            [2, 6, 7, 3], // +y
            [0, 2, 3, 1], // −z
            [4, 5, 7, 6], // +z
        ];
        self.loops.clear();
        self.start.clear();
        self.tags.clear();
        self.start.push(0);
        for (f, face) in FACES.iter().enumerate() {
            self.loops.extend_from_slice(face);
            self.start.push(self.loops.len() as u32);
            self.tags.push(tags[f]);
        }
    }

    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.tags.len()
    }

    /// The vertex ids of face `f`.
    pub fn face(&self, f: usize) -> &[u32] {
        &self.loops[self.start[f] as usize..self.start[f + 1] as usize]
    }

    /// Largest squared distance of a vertex from the site (m²).
    pub fn max_radius_sq(&self) -> f64 {
        self.verts.iter().map(|v| v.norm_squared()).fold(0.0, f64::max)
    }

    /// Vector area of face `f` (m²): its area times its outward unit normal.
    pub fn vector_area(&self, f: usize) -> Vec3 {
        let ids = self.face(f);
        let o = self.verts[ids[0] as usize];
        let mut a = Vec3::zeros();
        for w in ids[1..].windows(2) {
            a += (self.verts[w[0] as usize] - o).cross(&(self.verts[w[1] as usize] - o));
        }
        0.5 * a
    }

    /// Centroid of face `f` relative to the site (m): the area-weighted mean of its fan
    /// triangles' centroids (the face's first vertex when it has no area).
    pub fn centroid(&self, f: usize) -> Vec3 {
        let ids = self.face(f);
        let o = self.verts[ids[0] as usize];
        let (mut sum, mut total) = (Vec3::zeros(), 0.0);
        let n = self.vector_area(f);
        for w in ids[1..].windows(2) {
            let (a, b) = (self.verts[w[0] as usize], self.verts[w[1] as usize]);
            let t = 0.5 * (a - o).cross(&(b - o)).dot(&n);
            sum += t * (o + a + b) / 3.0;
            total += t;
        }
        if total > 0.0 { sum / total } else { o }
    }

    /// Volume (m³): Σ_f (A_f · v_f) / 3 over the faces (divergence theorem).
    pub fn volume(&self) -> f64 {
        (0..self.n_faces())
            .map(|f| self.vector_area(f).dot(&self.verts[self.face(f)[0] as usize]))
            .sum::<f64>()
            / 3.0
    }

    /// Keeps the half-space `n·x ≤ c` (n a unit vector, x relative to the site); the new face
    /// gets `tag`. Vertices within `tol` (m) of the plane count as inside. Returns whether the
    /// cell changed.
    pub fn clip(&mut self, n: &Vec3, c: f64, tag: Tag, tol: f64) -> Result<bool, ClipError> {
        self.s.clear();
        let (mut any_out, mut all_out) = (false, true);
        for v in &self.verts {
            let s = n.dot(v) - c;
            any_out |= s > tol;
            all_out &= s > tol;
            self.s.push(s);
        }
        if !any_out {
            return Ok(false);
        }
        if all_out {
            return Err(ClipError::Empty);
        }
        // Kept vertices, renumbered.
        self.map.clear();
        self.new_verts.clear();
        for (i, v) in self.verts.iter().enumerate() {
            if self.s[i] <= tol {
                self.map.push(self.new_verts.len() as u32);
                self.new_verts.push(*v);
            } else {
                self.map.push(u32::MAX);
            }
        }
        self.new_loops.clear();
        self.new_start.clear();
        self.new_tags.clear();
        self.new_start.push(0);
        self.edges.clear();
        self.cap.clear();
        for f in 0..self.tags.len() {
            let (a0, a1) = (self.start[f] as usize, self.start[f + 1] as usize);
            let len = a1 - a0;
            let begin = self.new_loops.len();
            let (mut exit, mut entry, mut crossings) = (u32::MAX, u32::MAX, 0);
            for k in 0..len {
                let a = self.loops[a0 + k];
                let b = self.loops[a0 + (k + 1) % len];
                let (ia, ib) = (self.map[a as usize] != u32::MAX, self.map[b as usize] != u32::MAX);
                if ia {
                    self.new_loops.push(self.map[a as usize]);
                }
                if ia != ib {
                    let x = self.intersection(a, b);
                    self.new_loops.push(x);
                    crossings += 1;
                    if ia {
                        exit = x;
                    } else {
                        entry = x;
                    }
                }
            }
            match crossings {
                0 => {}
                2 => self.cap.push((entry, exit)),
                _ => return Err(ClipError::Degenerate),
            }
            if self.new_loops.len() - begin >= 3 {
                self.new_start.push(self.new_loops.len() as u32);
                self.new_tags.push(self.tags[f]);
            } else {
                self.new_loops.truncate(begin);
            }
        }
        // The new face: follow entry → exit links (each crossing vertex is the exit of one face
        // and the entry of the face across the cut edge).
        if self.cap.len() >= 3 {
            let begin = self.new_loops.len();
            let first = self.cap[0].0;
            let mut at = first;
            for _ in 0..self.cap.len() {
                let Some(&(_, next)) = self.cap.iter().find(|e| e.0 == at) else {
                    return Err(ClipError::Degenerate);
                };
                self.new_loops.push(at);
                at = next;
                if at == first {
                    break;
                }
            }
            if at != first || self.new_loops.len() - begin != self.cap.len() {
                return Err(ClipError::Degenerate);
            }
            self.new_start.push(self.new_loops.len() as u32);
            self.new_tags.push(tag);
        }
        std::mem::swap(&mut self.verts, &mut self.new_verts);
        std::mem::swap(&mut self.loops, &mut self.new_loops);
        std::mem::swap(&mut self.start, &mut self.new_start);
        std::mem::swap(&mut self.tags, &mut self.new_tags);
        self.drop_unused();
        Ok(true)
    }

    /// The vertex where edge (a, b) crosses the plane, created once per edge.
    fn intersection(&mut self, a: u32, b: u32) -> u32 {
        let key = (a.min(b), a.max(b));
        if let Some(&(_, _, x)) = self.edges.iter().find(|e| (e.0, e.1) == key) {
            return x;
        }
        let (sa, sb) = (self.s[key.0 as usize], self.s[key.1 as usize]);
        let t = (sa / (sa - sb)).clamp(0.0, 1.0);
        let (va, vb) = (self.verts[key.0 as usize], self.verts[key.1 as usize]);
        let x = self.new_verts.len() as u32;
        self.new_verts.push(va + t * (vb - va));
        self.edges.push((key.0, key.1, x));
        x
    }

    /// Removes vertices no face uses (a face that vanished may leave some).
    fn drop_unused(&mut self) {
        self.map.clear();
        self.map.resize(self.verts.len(), u32::MAX);
        for &v in &self.loops {
            self.map[v as usize] = 0;
        }
        if self.map.iter().all(|&m| m == 0) {
            return;
        }
        self.new_verts.clear();
        for (i, v) in self.verts.iter().enumerate() {
            if self.map[i] == 0 {
                self.map[i] = self.new_verts.len() as u32;
                self.new_verts.push(*v);
            }
        }
        for v in &mut self.loops {
            *v = self.map[*v as usize];
        }
        std::mem::swap(&mut self.verts, &mut self.new_verts);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_cube() -> Cell {
        let mut c = Cell::default();
        c.reset_box(Vec3::repeat(-0.5), Vec3::repeat(0.5), [BOUND; 6]);
        c
    }

    fn closure(c: &Cell) -> f64 {
        (0..c.n_faces()).map(|f| c.vector_area(f)).sum::<Vec3>().norm()
    }

    #[test]
    fn box_volume_areas_and_closure() {
        let c = unit_cube();
        assert!((c.volume() - 1.0).abs() < 1e-15);
        for f in 0..6 {
            assert!((c.vector_area(f).norm() - 1.0).abs() < 1e-15);
        }
        assert!(closure(&c) < 1e-15);
        // Outward normals: face 1 is +x.
        assert!((c.vector_area(1) - Vec3::x()).norm() < 1e-15);
        assert!((c.centroid(1) - Vec3::new(0.5, 0.0, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn a_plane_through_the_middle_halves_the_cube() {
        let mut c = unit_cube();
        assert_eq!(c.clip(&Vec3::x(), 0.0, 7, 1e-12), Ok(true));
        assert!((c.volume() - 0.5).abs() < 1e-15);
        let f = c.tags.iter().position(|&t| t == 7).unwrap();
        assert!((c.vector_area(f) - Vec3::x()).norm() < 1e-15);
        assert!(closure(&c) < 1e-15);
        // A plane beyond the cell changes nothing.
        assert_eq!(c.clip(&Vec3::y(), 0.6, 8, 1e-12), Ok(false));
        // A plane that removes everything.
        assert_eq!(c.clip(&-Vec3::x(), -0.6, 9, 1e-12), Err(ClipError::Empty));
    }

    #[test]
    fn cutting_a_corner_gives_a_triangle() {
        let mut c = unit_cube();
        let n = Vec3::new(1.0, 1.0, 1.0).normalize();
        let d = n.dot(&Vec3::repeat(0.25));
        assert_eq!(c.clip(&n, d, 3, 1e-12), Ok(true));
        // The corner removed is a tetrahedron with legs 0.75: volume 0.75³/6.
        assert!((c.volume() - (1.0 - 0.75f64.powi(3) / 6.0)).abs() < 1e-14);
        let f = c.tags.iter().position(|&t| t == 3).unwrap();
        assert_eq!(c.face(f).len(), 3);
        assert!(closure(&c) < 1e-14);
    }

    #[test]
    fn many_random_planes_keep_a_closed_convex_cell() {
        // Planes tangent to a sphere of radius 0.3: the cell converges to the sphere.
        let mut c = unit_cube();
        let mut state = 12345u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for k in 0..2000 {
            let n = Vec3::new(rnd(), rnd(), rnd());
            if n.norm() < 1e-3 {
                continue;
            }
            c.clip(&n.normalize(), 0.3, k, 1e-12).unwrap();
        }
        let v = c.volume();
        let sphere = 4.0 / 3.0 * std::f64::consts::PI * 0.027;
        assert!(v > sphere && v < 1.01 * sphere, "{v} vs {sphere}");
        assert!(closure(&c) < 1e-12);
        // Every vertex on or inside the bounding sphere of the faces.
        assert!(c.max_radius_sq().sqrt() < 0.35);
    }
}
