//! Wall contacts: container faces held at a value (a temperature, a potential) are extra
//! nodes of the network, each linked to the particles touching its face by a half-contact.
//!
//! A wall link of particle p to face f has the half-length h_p = max(d_p, R_p/2) (d_p the
//! centre-to-face distance, clamped so a particle pressed into the wall keeps a finite
//! conductance), the outward face normal n_p at the particle, and the transmission surface
//! S_p of the particle under the surface model ([`WallContacts::surfaces`]). Its conductance
//! is g = k_p(n_p, h_p) S_p / h_p, with k_p the particle's conductivity along n_p
//! ([`WallContacts::conductances`]).
//!
//! With the Laguerre model the links are the cells' facets on the face instead
//! ([`WallContacts::for_graph`]): h_p is the distance from the centre to the facet, n_p its
//! normal and S_p its area.
//!
//! Wall nodes come after the particles: wall w is node `n_particles + w`. Only this module
//! knows that numbering; everyone else asks [`WallContacts::node`], [`WallContacts::edges`],
//! [`WallContacts::split`], or splits and joins node values with
//! [`WallContacts::particle_part`], [`WallContacts::split_nodes`] and
//! [`WallContacts::join_nodes`].

use std::ops::Range;

use demcon_core::{Container, CoreError, Face, ParticleSet, Selector, Vec3};

use crate::{CellWall, ContactGraph, SurfaceModel, surface_calibrated, terreros_alpha};

/// The links between particles and the container faces held at a value.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WallContacts {
    /// Number of particles (wall nodes are numbered after them).
    n_particles: usize,
    /// The faces, one network node each, in the order given to [`WallContacts::build`].
    pub faces: Vec<Face>,
    /// The links of wall w are `starts[w]..starts[w + 1]`.
    starts: Vec<usize>,
    /// Per link: the particle.
    pub particle: Vec<u32>,
    /// Per link: half-length h_p = max(centre-to-face distance, R_p/2) (m).
    pub half_length: Vec<f64>,
    /// Per link: outward unit normal of the face at the particle.
    pub normal: Vec<Vec3>,
    /// Per link: the area of the cell's facet on the face (m²), when built from Laguerre cells
    /// (empty otherwise).
    pub facet_area: Vec<f64>,
    /// Per link: the facet's centroid relative to the particle's centre (m), when built from
    /// Laguerre cells (empty otherwise: the link acts at h_p n_p).
    pub lever: Vec<Vec3>,
}

impl WallContacts {
    /// Links every particle touching each of `faces` (the [`Selector::Face`] rule) to that
    /// face. `context` names the request in errors (e.g. `thermal.bcs`).
    ///
    /// Errors: a face the container does not have, or one no particle touches.
    pub fn build(
        particles: &ParticleSet,
        container: &Container,
        faces: &[Face],
        context: &str,
    ) -> Result<Self, CoreError> {
        let mut w = WallContacts {
            n_particles: particles.len(),
            faces: faces.to_vec(),
            starts: vec![0],
            ..Default::default()
        };
        for &face in faces {
            if face == Face::Carved {
                return Err(CoreError::invalid(
                    format!("wall {} ({context})", face.name()),
                    face.name(),
                    "a face of the container: the carved surface is a wall only under Laguerre cells \
                     (`surface: Laguerre`), whose facets on it it is made of",
                ));
            }
            let ids = Selector::Face(face).select_nonempty(
                particles,
                container,
                &format!("wall {} ({context})", face.name()),
            )?;
            for p in ids {
                let pu = p as usize;
                let (c, r) = (particles.centres[pu], particles.radii[pu]);
                let h = container.face_distance(face, &c).unwrap_or(r).max(0.5 * r);
                let n = container.face_normal(face, &c).unwrap_or_else(Vec3::x);
                w.particle.push(p);
                w.half_length.push(h);
                w.normal.push(n);
            }
            w.starts.push(w.particle.len());
        }
        Ok(w)
    }

    /// The links of `faces` for a graph: the cells' wall facets when the graph is a Laguerre
    /// tessellation, else the particles touching each face ([`WallContacts::build`]).
    ///
    /// Errors: a face the container does not have, or one no particle (cell) touches.
    pub fn for_graph(
        graph: &ContactGraph,
        particles: &ParticleSet,
        container: &Container,
        faces: &[Face],
        context: &str,
    ) -> Result<Self, CoreError> {
        Self::for_graph_part(graph, particles, container, faces, context, false)
    }

    /// [`WallContacts::for_graph`] on a part of the body (an MPI rank's block) when
    /// `part`: a face none of its cells reaches then gets no link instead of an error.
    pub fn for_graph_part(
        graph: &ContactGraph,
        particles: &ParticleSet,
        container: &Container,
        faces: &[Face],
        context: &str,
        part: bool,
    ) -> Result<Self, CoreError> {
        let Some(cells) = graph.cells.as_deref() else {
            return Self::build(particles, container, faces, context);
        };
        let mut w = WallContacts {
            n_particles: particles.len(),
            faces: faces.to_vec(),
            starts: vec![0],
            ..Default::default()
        };
        for &face in faces {
            if face != Face::Carved && !container.faces().contains(&face) {
                return Err(CoreError::invalid(
                    format!("wall {} ({context})", face.name()),
                    face.name(),
                    format!(
                        "a face of the {} container: {:?}",
                        container.kind(),
                        container.faces()
                    ),
                ));
            }
            let before = w.particle.len();
            for f in cells.on_wall(CellWall::of(face)) {
                w.particle.push(f.particle);
                w.half_length.push(f.distance);
                w.normal.push(f.normal);
                w.facet_area.push(f.area);
                w.lever.push(f.centroid);
            }
            if w.particle.len() == before && !part {
                return Err(CoreError::invalid(
                    format!("wall {} ({context})", face.name()),
                    face.name(),
                    if face == Face::Carved {
                        "the surface of a carving region (`carve`) some Laguerre cell reaches"
                    } else {
                        "a face some Laguerre cell reaches (none does: carved away?)"
                    },
                ));
            }
            w.starts.push(w.particle.len());
        }
        Ok(w)
    }

    /// Keeps only the links `k` for which `keep(k)` holds (e.g. drops the links a crack cuts);
    /// the walls stay, in their order, possibly with no link left.
    pub fn retain_links(&mut self, keep: impl Fn(usize) -> bool) {
        let kept: Vec<usize> = (0..self.len()).filter(|&k| keep(k)).collect();
        if kept.len() == self.len() {
            return;
        }
        let mut starts = vec![0];
        for w in 0..self.n_walls() {
            let r = self.links(w);
            starts.push(starts[w] + kept.iter().filter(|k| r.contains(k)).count());
        }
        let pick = |v: &[Vec3]| -> Vec<Vec3> {
            if v.is_empty() {
                Vec::new()
            } else {
                kept.iter().map(|&k| v[k]).collect()
            }
        };
        self.particle = kept.iter().map(|&k| self.particle[k]).collect();
        self.half_length = kept.iter().map(|&k| self.half_length[k]).collect();
        self.normal = pick(&self.normal);
        self.lever = pick(&self.lever);
        if !self.facet_area.is_empty() {
            self.facet_area = kept.iter().map(|&k| self.facet_area[k]).collect();
        }
        self.starts = starts;
    }

    /// No wall at all.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// Number of walls (faces).
    pub fn n_walls(&self) -> usize {
        self.faces.len()
    }

    /// Number of links.
    pub fn len(&self) -> usize {
        self.particle.len()
    }

    /// Number of particles the walls were built for.
    pub fn n_particles(&self) -> usize {
        self.n_particles
    }

    /// Nodes of the extended network: the particles, then one per wall.
    pub fn n_nodes(&self) -> usize {
        self.n_particles + self.faces.len()
    }

    /// The network node of wall `w`.
    pub fn node(&self, w: usize) -> u32 {
        (self.n_particles + w) as u32
    }

    /// The particles' part of values over the extended network's nodes (`n_particles` of
    /// them first, then the walls).
    pub fn particle_part(nodes: &[f64], n_particles: usize) -> &[f64] {
        &nodes[..n_particles]
    }

    /// Values over the extended network's nodes split into the particles' and the walls'.
    pub fn split_nodes(mut nodes: Vec<f64>, n_particles: usize) -> (Vec<f64>, Vec<f64>) {
        let walls = nodes.split_off(n_particles);
        (nodes, walls)
    }

    /// Values over the extended network's nodes from the particles' and the walls'.
    pub fn join_nodes(particles: &[f64], walls: &[f64]) -> Vec<f64> {
        [particles, walls].concat()
    }

    /// The links of wall `w` (indices into the per-link arrays).
    pub fn links(&self, w: usize) -> Range<usize> {
        self.starts[w]..self.starts[w + 1]
    }

    /// The wall each link belongs to.
    pub fn wall_of_links(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.n_walls()).flat_map(|w| self.links(w).map(move |_| w))
    }

    /// The links as network edges `[particle, wall node]`, in link order.
    pub fn edges(&self) -> impl Iterator<Item = [u32; 2]> + '_ {
        self.wall_of_links()
            .zip(&self.particle)
            .map(|(w, &p)| [p, self.node(w)])
    }

    /// Is network node `node` a particle (not a wall)?
    pub fn is_particle(&self, node: u32) -> bool {
        (node as usize) < self.n_particles
    }

    /// Splits values over the extended network's nodes into (particles, walls).
    pub fn split<'a>(&self, nodes: &'a [f64]) -> (&'a [f64], &'a [f64]) {
        nodes.split_at(self.n_particles)
    }

    /// The transmission surface of each link (m²) under `model`: C_t π R_p² (calibrated),
    /// α(n_p + 1) R_p² (Terreros: the wall counts as one more neighbour) or the facet's area
    /// (Laguerre; links built by [`WallContacts::for_graph`] on a tessellation). `degrees` are
    /// the particles' contact counts.
    pub fn surfaces(&self, particles: &ParticleSet, degrees: &[u32], model: &SurfaceModel) -> Vec<f64> {
        self.particle
            .iter()
            .enumerate()
            .map(|(k, &p)| {
                let pu = p as usize;
                let r = particles.radii[pu];
                match *model {
                    SurfaceModel::Calibrated { c_t } => surface_calibrated(c_t, r),
                    SurfaceModel::TerrerosAlpha => terreros_alpha(degrees[pu] + 1).alpha * r * r,
                    // A link without a facet (contacts, not cells) has none.
                    SurfaceModel::Laguerre => self.facet_area.get(k).copied().unwrap_or(0.0),
                }
            })
            .collect()
    }

    /// Link conductances g = k_p(n_p, h_p) S_p / h_p (W/K for heat, S for current), with
    /// `surfaces` from [`WallContacts::surfaces`] (m²) and `half_bond(p, n, h)` particle p's
    /// conductivity along the unit vector n over a half-bond of length h (W/(m·K) or S/m).
    pub fn conductances(&self, surfaces: &[f64], half_bond: impl Fn(usize, &Vec3, f64) -> f64) -> Vec<f64> {
        (0..self.len())
            .map(|k| {
                let h = self.half_length[k];
                half_bond(self.particle[k] as usize, &self.normal[k], h) * surfaces[k] / h
            })
            .collect()
    }

    /// Adds each link's share to the particle dipoles D_p = Σ g (u_q − u_p) ℓ_pq: a link of
    /// conductance g over the half-length h is the bond to the mirror image at 2h, of
    /// conductance g/2 and difference 2 (u_w − u_p), so it adds 2 g (u_w − u_p) h n — or, for a
    /// Laguerre wall facet, 2 g (u_w − u_p) a with a the facet's centroid from the centre.
    /// `g` are the link conductances, `nodes` the values of every node (particles, then walls).
    pub fn add_dipoles(&self, g: &[f64], nodes: &[f64], dipoles: &mut [Vec3]) {
        for (k, w) in self.wall_of_links().enumerate() {
            let p = self.particle[k] as usize;
            let uw = nodes[self.node(w) as usize];
            dipoles[p] += 2.0 * g[k] * (uw - nodes[p]) * self.lever(k);
        }
    }

    /// Where link `k` acts, from its particle's centre (m): the Laguerre facet's centroid, or
    /// h_p n_p without cells.
    pub fn lever(&self, k: usize) -> Vec3 {
        self.lever
            .get(k)
            .copied()
            .unwrap_or_else(|| self.half_length[k] * self.normal[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_touching_particles_and_numbers_walls_after_them() {
        // Three spheres in a row along z in a 1 × 1 × 3 box; only the end ones touch ZMin/ZMax.
        let centres = (0..3).map(|i| Vec3::new(0.5, 0.5, 0.5 + i as f64)).collect();
        let p = ParticleSet::new(centres, vec![0.5; 3]).unwrap();
        let c = Container::Box {
            size: [1.0, 1.0, 3.0],
        };
        let w = WallContacts::build(&p, &c, &[Face::ZMin, Face::ZMax], "test").unwrap();
        assert_eq!(w.n_nodes(), 5);
        assert_eq!(w.edges().collect::<Vec<_>>(), vec![[0, 3], [2, 4]]);
        assert_eq!(w.half_length, vec![0.5, 0.5]);
        assert_eq!(w.normal[0], -Vec3::z());
        let s = w.surfaces(&p, &[1, 2, 1], &SurfaceModel::Calibrated { c_t: 1.0 });
        let g = w.conductances(&s, |_, _, _| 2.0);
        let expected = 2.0 * std::f64::consts::PI * 0.25 / 0.5;
        assert!(g.iter().all(|&x| (x - expected).abs() < 1e-12));
        // A linear field u = z: the wall dipoles of the end particles point along +z.
        let nodes = [0.5, 1.5, 2.5, 0.0, 3.0];
        let mut d = vec![Vec3::zeros(); 3];
        w.add_dipoles(&g, &nodes, &mut d);
        assert!(d[0].z > 0.0 && d[2].z > 0.0 && d[1] == Vec3::zeros());
        let (parts, walls) = w.split(&nodes);
        assert_eq!((parts.len(), walls), (3, &[0.0, 3.0][..]));
    }

    #[test]
    fn a_face_the_container_lacks_is_an_error() {
        let p = ParticleSet::new(vec![Vec3::zeros()], vec![0.5]).unwrap();
        let c = Container::Sphere { radius: 1.0 };
        assert!(WallContacts::build(&p, &c, &[Face::XMin], "test").is_err());
    }
}
