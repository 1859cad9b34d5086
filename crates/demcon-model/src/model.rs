//! The model every physics runs on: particles (carved, with phases), contacts with their
//! geometry, and the network structure — built from plain inputs, with a report of what each
//! stage did and cost.

use std::sync::OnceLock;
use std::time::Instant;

use demcon_core::{Container, Face, Inclusion, MaterialTable, ParticleSet, Region, Stages, Vec3};
use demcon_graph::{
    ConformParams, ConformReport, ContactGraph, ContactParams, ContactReport, HalfBond, LaguerreParams,
    Laminates, Mix, PlanePatch, SphereSurface, TessellationReport, WallContacts, assign_phase,
    assign_phase_laminate, conforming_sites, detect_contacts, tessellate, tessellate_part,
};
use demcon_network::Network;
use demcon_packing::{
    PackingParams, PackingReport, RadiusDistribution, ShapeParams, ShapeReport, StopReason, carve, pack,
};
use serde::Serialize;

use crate::defects::{
    CutContact, DefectReport, DefectSpec, DefectView, Defects, Numbering, PhaseBridge, apply_defects,
    cut_wall_links, update_interface_marks,
};
use crate::error::{FieldNames, ModelError};
use crate::shapes::{ShapesReport, check_placement, orientation_tensor, random_shapes, shapes_region};

/// Everything the solvers need that does not depend on the physics.
#[derive(Debug, Clone)]
pub struct Model {
    /// The particles (Morton-ordered when generated), carved and with phases set.
    pub particles: ParticleSet,
    /// The container the packing was made in (faces for boundary conditions).
    pub container: Container,
    /// Volume of the solid the particles represent (m³): the container's, or the part of the
    /// carving region inside it.
    pub domain_volume: f64,
    /// The carving region the body was cut from, if any.
    pub carve: Option<Region>,
    /// Conforming seeds at the end of `particles` (`PhaseRule::Conforming`; 0 otherwise): the
    /// sites that put the followed surfaces (spheres, box faces, cracks) on facets, not
    /// particles of the packing.
    pub seeds: usize,
    /// Solid fraction Σ V_p / domain volume of the packing's particles (the conforming seeds
    /// are sites, not grains), used for the representative volume V_p/φ.
    pub phi: f64,
    /// The materials, indexed by phase.
    pub materials: MaterialTable,
    /// Particles cut by a phase interface under the laminate or segment rule, sorted by
    /// particle (empty under the centre rule).
    pub mixes: Vec<Mix>,
    /// Contacts with their geometry. Replace it by [`Model::set_graph`], which rebuilds the
    /// network.
    pub graph: ContactGraph,
    /// Laplacian structure over the contacts ([`Model::network`]): built with the model,
    /// freed by [`Model::release_network`] and then rebuilt on its next use.
    network: OnceLock<Network>,
    /// Interfaces, cracks, damage and broken bonds applied to the graph (cut contacts are
    /// not in `graph`; see [`crate::defects`]).
    pub defects: Defects,
    /// The branches between the cells (or particles) of two spheres that nearly touch, by
    /// particle pair, ascending (conforming cells; by centre when the scene lists an interface;
    /// empty otherwise): an interface law is read at both crossings ([`PhaseBridge`]). Pairs,
    /// not contact indices: they survive cut contacts.
    pub bridges: Vec<PhaseBridge>,
    /// What the build did.
    pub report: ModelReport,
    /// The caller's names for its input ([`ModelParams::fields`]), which this model's refusals
    /// use.
    pub fields: FieldNames,
    /// Particles whose cells this model holds, when it is one MPI rank's block (the first
    /// ones; [`build_block_model`]); `None` for a whole model.
    pub owned: Option<usize>,
}

impl Model {
    /// What the conductances read of the model's defects ([`crate::defects`]).
    pub(crate) fn defect_view(&self) -> DefectView<'_> {
        DefectView {
            defects: &self.defects,
            graph: &self.graph,
            particles: &self.particles,
            container: &self.container,
            mixes: &self.mixes,
            n_phases: self.materials.materials.len(),
            bridges: &self.bridges,
        }
    }

    /// Laplacian structure over the contacts (rebuilt here, identical, after
    /// [`Self::release_network`]).
    pub fn network(&self) -> &Network {
        self.network.get_or_init(|| {
            Network::new(self.particles.len(), &self.graph.pairs)
                .expect("the network was built from these pairs with the model")
        })
    }

    /// Frees the network structure (24 B per contact: 0.17 kB per particle for a Laguerre
    /// graph) while no solve reads it — a thermal run with walls solves on its own network
    /// with the wall nodes. [`Self::network`] rebuilds it if it is read after all.
    pub fn release_network(&mut self) {
        self.network = OnceLock::new();
    }

    /// Replaces the contact graph and the network built from it.
    ///
    /// # Errors
    /// The graph's pairs are not valid network edges (an index beyond the particles).
    pub fn set_graph(&mut self, graph: ContactGraph) -> Result<(), ModelError> {
        let network = Network::new(self.particles.len(), &graph.pairs)?;
        self.graph = graph;
        self.network = OnceLock::from(network);
        Ok(())
    }

    /// The volume of solid particle `p` stands for (m³): its Laguerre cell, or V_p/φ.
    pub fn solid_volume_of(&self, p: usize) -> f64 {
        match self.graph.cells.as_deref() {
            Some(c) => c.volume[p],
            None => self.particles.volume(p) / self.phi,
        }
    }

    /// The wall links of `faces` on this model's graph (the cells' wall facets, or the
    /// particles touching each face); errors are named `context` (e.g. `thermal.bcs`).
    /// The links an open crack crosses (centre to face) are dropped.
    pub fn wall_contacts(&self, faces: &[Face], context: &str) -> Result<WallContacts, ModelError> {
        // A block may hold no cell on a face another rank's cells reach.
        let mut walls = WallContacts::for_graph_part(
            &self.graph,
            &self.particles,
            &self.container,
            faces,
            context,
            self.owned.is_some(),
        )
        .map_err(|e| ModelError::at(context, e))?;
        cut_wall_links(&self.defects, &mut walls, &self.particles, &self.container);
        Ok(walls)
    }

    /// Per contact of [`Model::graph`], its marks for the output writers: a bit set of
    /// [`crate::defects::MARK_INTERFACE`] (crosses a listed phase interface: the series
    /// resistance applies), [`crate::defects::MARK_DAMAGED`] (in a damage region),
    /// [`crate::defects::MARK_FILLED_CRACK`] (crossed by a filled crack) and
    /// [`crate::defects::MARK_PARTLY_CUT`] (a Laguerre facet an open crack covers in part);
    /// 0 for a plain contact. Cut contacts are not in the graph: see [`Model::cut_contacts`].
    pub fn contact_marks(&self) -> &[u8] {
        &self.defects.marks
    }

    /// The contacts removed from the graph by open cracks and broken bonds (pairs of particle
    /// ids, and why), for the output writers.
    pub fn cut_contacts(&self) -> &[CutContact] {
        &self.defects.cut
    }

    /// The particles on a crack face (an end of a contact a crack crosses, open or filled),
    /// ascending.
    pub fn crack_face_particles(&self) -> &[u32] {
        &self.defects.crack_face
    }

    /// How far the two-point flux of each anisotropic material is from its tensor on this
    /// model's bonds: for material m, the tensor its network conducts as in a uniform gradient,
    /// K_net = 3 Σ S d (eᵀ K e) e eᵀ / Σ S d over the contacts between two particles of m (S
    /// the transmission surface, d the branch length, e its direction) — K itself where the
    /// bonds are K-orthogonal (a lattice along K's axes), about (tr K I + 2 K)/5 on random
    /// cells — and max |K_net,ij − K_ij| / |K| (Frobenius). `areas` are the contacts'
    /// surfaces (m²). Materials without a tensor or without such contacts are left out. A
    /// tensor read in each shape's frame is compared there (each bond turned into the frame of
    /// its first particle's shape).
    pub fn anisotropy_consistency(&self, areas: &[f64]) -> Vec<(String, f64)> {
        let axes = self.shape_axes();
        let mut out = Vec::new();
        for (phase, m) in self.materials.materials.iter().enumerate() {
            let Some(k) = &m.conductivity_tensor else {
                continue;
            };
            let (mut net, mut weight) = ([[0.0f64; 3]; 3], 0.0);
            for (c, &[p, q]) in self.graph.pairs.iter().enumerate() {
                let (p, q) = (p as usize, q as usize);
                let ph = &self.particles.phases;
                if ph[p] as usize != phase || ph[q] as usize != phase {
                    continue;
                }
                let geo = &self.graph.geometry[c];
                let w = areas[c] * geo.distance;
                let e = match axes.get(p).copied().flatten() {
                    Some(a) if m.tensor_in_shape_frame => demcon_core::to_shape_frame(&a, &geo.normal),
                    _ => geo.normal,
                };
                let ke = m.conductivity_along(&e);
                for (i, row) in net.iter_mut().enumerate() {
                    for (j, v) in row.iter_mut().enumerate() {
                        *v += w * ke * e[i] * e[j];
                    }
                }
                weight += w;
            }
            if weight == 0.0 {
                continue;
            }
            let norm = k.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
            let err = (0..3)
                .flat_map(|i| (0..3).map(move |j| (i, j)))
                .map(|(i, j)| (3.0 * net[i][j] / weight - k[i][j]).abs() / norm)
                .fold(0.0, f64::max);
            out.push((m.name.clone(), err));
        }
        out
    }

    /// Per particle, the axis of the shape whose frame its material's tensor is read in
    /// ([`crate::shapes::shape_axes`]; empty when no material reads its tensor so).
    pub fn shape_axes(&self) -> Vec<Option<Vec3>> {
        crate::shapes::shape_axes(
            &self.particles,
            &self.container,
            &self.materials.materials,
            &self.mixes,
            &self.report.shapes,
        )
    }

    /// Whether some material conducts anisotropically (a conductivity tensor).
    pub fn anisotropic(&self) -> bool {
        self.materials
            .materials
            .iter()
            .any(|m| m.conductivity_tensor.is_some())
    }

    /// Whether some material's conductivity depends on temperature (λ(T)).
    pub fn conductivity_varies(&self) -> bool {
        self.materials.materials.iter().any(|m| m.conductivity_varies())
    }

    /// The laminate mixes indexed by particle.
    pub fn laminates(&self) -> Laminates<'_> {
        Laminates::new(self.particles.len(), &self.mixes)
    }
}

/// What building the model did and cost.
#[derive(Debug, Clone, Serialize)]
pub struct ModelReport {
    /// Packing report, when the packing was generated here.
    pub packing: Option<PackingReport>,
    /// Particles read from a file, when imported.
    pub imported_from: Option<String>,
    /// Particles removed by carving.
    pub carved_away: usize,
    /// How the phases treat the particles their surfaces cut.
    pub phase_rule: PhaseRule,
    /// Particles per phase (by centre).
    pub phase_counts: Vec<usize>,
    /// Volume fraction of the body each phase carries: Σ v_p W_p / Σ W_p over the particles'
    /// own phases and the laminate fractions of the cut ones, W_p the volume each particle
    /// stands for (its Laguerre cell; V_p/φ, so the sphere share, under the contact models).
    pub phase_fractions: Vec<f64>,
    /// The same share in the spheres' own volume V_p (a walled packing is looser at the walls,
    /// so this differs from the body's fraction under the Laguerre cells).
    pub sphere_phase_fractions: Vec<f64>,
    /// Particles cut by an interface (laminate rule).
    pub mixed_particles: usize,
    /// The conforming seeds placed (`PhaseRule::Conforming`).
    pub conform: Option<ConformSummary>,
    /// Inclusions placed (centres and radius), when asked for.
    pub inclusions: Option<InclusionReport>,
    /// The shaped-inclusion phase entries: count, fraction, orientation tensor, placement.
    pub shapes: Vec<ShapesReport>,
    /// Contact detection summary (the facet graph's, for a tessellation).
    pub contacts: ContactSummary,
    /// The Laguerre tessellation, when the graph is one.
    pub tessellation: Option<TessellationSummary>,
    /// Interfaces, cracks, damage and broken bonds, when the model has any.
    pub defects: Option<DefectReport>,
    /// Wall time of each stage (s): packing, contacts, network.
    pub pack_s: f64,
    /// Contact detection (s).
    pub contacts_s: f64,
    /// Network structure (s).
    pub network_s: f64,
}

/// What the conforming seeds did (`PhaseRule::Conforming`), for `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct ConformSummary {
    /// Spheres whose surfaces the cells follow.
    pub spheres: usize,
    /// Plane patches the cells follow: faces of box regions inside the body, an image's voxel
    /// faces (merged into rectangles), and cracks.
    pub planes: usize,
    /// Shaped inclusions (spheroids, cylinders) whose surfaces the cells follow.
    pub shapes: usize,
    /// The mean site spacing h the sampling was scaled by (m).
    pub spacing_m: f64,
    /// Seeds placed (pairs across the surfaces, less those dropped).
    pub seeds: usize,
    /// Seeds dropped: near another sphere's surface, overlapping a seed, outside the box.
    pub dropped_seeds: usize,
    /// Packing particles removed next to a surface.
    pub removed_particles: usize,
    /// Seed pairs closed in on their surface where another sphere came near.
    pub narrowed_pairs: usize,
    /// Largest 1 − r'/r of the tangent-plane radius correction (a shape: its largest inward
    /// move over its circumradius).
    pub max_radius_correction: f64,
    /// Facets between the cells of two spheres that nearly touch (their branch leaves one
    /// sphere and enters the other across a gap the seed pairs could not follow): a surface
    /// law is read twice on them ([`crate::PhaseBridge`]).
    pub bridged_facets: usize,
}

impl From<&ConformReport> for ConformSummary {
    fn from(r: &ConformReport) -> Self {
        Self {
            spheres: r.spheres,
            spacing_m: r.spacing_m,
            seeds: r.seeds,
            dropped_seeds: r.dropped_seeds,
            planes: r.planes,
            shapes: r.shapes,
            removed_particles: r.removed_sites,
            narrowed_pairs: r.narrowed_pairs,
            max_radius_correction: r.max_radius_correction,
            bridged_facets: 0, // set once the cells are built
        }
    }
}

/// The inclusions of a multi-inclusion composite.
#[derive(Debug, Clone, Serialize)]
pub struct InclusionReport {
    /// Number of inclusions.
    pub count: usize,
    /// Inclusion radius (m).
    pub radius: f64,
    /// Volume fraction of the inclusion spheres in the box.
    pub fraction: f64,
    /// Fraction of the body the model carries in the inclusion phase: its Laguerre cells'
    /// share of the volume, or under the contact models the spheres' share of the solid (by
    /// centre, or with the laminate fractions under the laminate rule).
    pub particle_fraction: f64,
    /// The inclusions' phase (index into the material table).
    pub phase: u16,
    /// Centres (m).
    pub centres: Vec<[f64; 3]>,
}

/// A serialisable summary of the contact report.
#[derive(Debug, Clone, Serialize)]
pub struct ContactSummary {
    /// Relative gap tolerance ε used.
    pub epsilon: f64,
    /// Mean coordination reached.
    pub coordination: f64,
    /// Contacts.
    pub n_contacts: usize,
    /// Particles with no contact.
    pub rattlers: usize,
    /// Particles with fewer than 2 contacts.
    pub under_two_contacts: usize,
    /// Connected components.
    pub n_components: usize,
    /// Size of the largest component.
    pub largest_component: usize,
    /// Diagnostics as text.
    pub diagnostics: Vec<String>,
}

impl ContactSummary {
    fn from(r: &ContactReport) -> Self {
        Self {
            epsilon: r.epsilon,
            coordination: r.coordination,
            n_contacts: r.n_contacts,
            rattlers: r.rattlers.len(),
            under_two_contacts: r.under_two_contacts,
            n_components: r.n_components,
            largest_component: r.largest_component,
            diagnostics: r.diagnostics.iter().map(|d| d.to_string()).collect(),
        }
    }
}

/// A serialisable summary of the Laguerre tessellation.
#[derive(Debug, Clone, Serialize)]
pub struct TessellationSummary {
    /// Facets dropped as negligible.
    pub dropped_facets: usize,
    /// The area below which a facet is dropped (m²).
    pub negligible_area_m2: f64,
    /// Facets found by one cell only.
    pub one_sided_facets: usize,
    /// Largest relative difference of a facet's area seen from its two cells.
    pub max_area_mismatch: f64,
    /// Σ cell volumes / domain volume − 1 (curved walls; carving regions on a 256³ estimate).
    pub volume_error: f64,
    /// Cells clipped by curved surfaces.
    pub curved_cells: usize,
    /// Tangent planes added for curved surfaces.
    pub curved_planes: usize,
    /// Wall time (s).
    pub wall_s: f64,
}

impl TessellationSummary {
    fn from(r: &TessellationReport) -> Self {
        Self {
            dropped_facets: r.dropped_facets,
            negligible_area_m2: r.negligible_area_m2,
            one_sided_facets: r.one_sided_facets,
            max_area_mismatch: r.max_area_mismatch,
            volume_error: r.volume_error,
            curved_cells: r.curved_cells,
            curved_planes: r.curved_planes,
            wall_s: r.wall_s,
        }
    }
}

/// How a particle cut by a phase interface is treated.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub enum PhaseRule {
    /// The phase of its centre.
    #[default]
    Centre,
    /// A laminate of the two phases (volume fractions and interface normal).
    Laminate,
    /// Each half-bond mixes what lies along its own segment, in series.
    Segment,
    /// The Laguerre cells follow the surfaces: seeds mirrored across each sphere phase's
    /// surface, each box region's faces and each crack put facets on them, the packing's sites
    /// next to them are removed ([`demcon_graph::conforming_sites`]), and every cell is of one
    /// phase (its centre's). Needs the Laguerre cells; other regions are assigned by centre.
    Conforming,
}

/// Which particles carving keeps.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum CarveRule {
    /// Particles wholly inside the region.
    #[default]
    WholeSphere,
    /// Particles whose centre is inside.
    Centre,
}

/// A phase assignment, applied in order over phase 0 (the first material).
#[derive(Debug, Clone, PartialEq)]
pub enum PhaseSpec {
    /// The particles in a region take `phase`.
    Region {
        /// Phase id (index into the material table).
        phase: u16,
        /// The region (m).
        region: Region,
    },
    /// Monodisperse spheres placed by the LS algorithm; the particles inside take `phase`.
    Inclusions {
        /// Phase id.
        phase: u16,
        /// Volume fraction of the inclusions in the container's bounding box, in (0, 0.6).
        fraction: f64,
        /// Box edge over inclusion diameter, ≥ 1.
        size_ratio: f64,
    },
    /// Spheres at given centres (m) of one radius (m); in a periodic container their
    /// periodic images count.
    Spheres {
        /// Phase id.
        phase: u16,
        /// Radius (m).
        radius: f64,
        /// Centres (m), inside the container's bounding box.
        centres: Vec<Vec3>,
    },
    /// Spheroids and cylinders at given places (centres inside the container's bounding box;
    /// in a walled container each shape wholly inside it); in a periodic container their
    /// periodic images count. Cut by their exact level set: the centre, laminate and segment
    /// rules (not `Conforming`).
    Shapes {
        /// Phase id.
        phase: u16,
        /// The shapes (m).
        shapes: Vec<Inclusion>,
    },
    /// Shapes placed at random to a volume fraction ([`demcon_packing::place_shapes`]) in the
    /// container (a `Box` or `Periodic`: `placement.container` is replaced by it), seeded by
    /// [`ModelParams::seed`]; cut as [`PhaseSpec::Shapes`].
    RandomShapes {
        /// Phase id.
        phase: u16,
        /// What to place.
        placement: ShapeParams,
        /// The shapes already placed by the caller for a container (e.g. while checking the
        /// input, before packing); used when the model's container is that one, placed again
        /// otherwise.
        placed: Option<Box<(Container, Vec<Inclusion>, ShapeReport)>>,
    },
    /// The labels of a voxel image, each its phase's voxels (in order; a later label wins
    /// where they meet), cut by their smoothed level set as [`PhaseSpec::Shapes`].
    Image {
        /// (phase id, its voxels) per label.
        labels: Vec<(u16, demcon_core::Voxels)>,
    },
}

/// The particles a model starts from, and where they came from.
#[derive(Debug, Clone)]
pub struct Packed {
    /// The particles.
    pub particles: ParticleSet,
    /// Their container.
    pub container: Container,
    /// Packing report, when generated.
    pub report: Option<PackingReport>,
    /// The file they were read from, when imported.
    pub imported_from: Option<String>,
    /// Wall time of the packing or reading (s).
    pub pack_s: f64,
}

/// What to build on the packed particles.
#[derive(Debug, Clone)]
pub struct ModelParams {
    /// Material table (phase = index).
    pub materials: MaterialTable,
    /// Carving region and rule (the domain becomes the region).
    pub carve: Option<(Region, CarveRule)>,
    /// Phase assignments, in order.
    pub phases: Vec<PhaseSpec>,
    /// Treatment of particles cut by an interface.
    pub phase_rule: PhaseRule,
    /// Contact detection (unused when `laguerre` is set).
    pub contacts: ContactParams,
    /// When set, the graph is the Laguerre tessellation's facet graph (the Laguerre surface
    /// model needs it) instead of contacts found by a gap tolerance.
    pub laguerre: Option<LaguerreParams>,
    /// Interface resistances, cracks, damage regions and broken bonds (none by default).
    pub defects: DefectSpec,
    /// Seed (inclusion placement).
    pub seed: u64,
    /// The caller's names for its input, used by every refusal of the model and its problems
    /// ([`FieldNames::MODEL`] by default).
    pub fields: FieldNames,
}

/// Builds the model: carving, phases, contacts, network structure.
pub fn build_model(packed: Packed, params: &ModelParams) -> Result<Model, ModelError> {
    build_model_staged(packed, params, &mut Stages::default())
}

/// The volume (m³) of the part of carving region `region` inside `container`: exact when
/// the region is a box or lies inside the container's box, else a 256³ midpoint grid over
/// the intersection (relative error ~1/256).
fn body_volume(container: &Container, region: &Region) -> f64 {
    let b = container.bounds();
    let r = region.bounds();
    let inside = (0..3).all(|k| r.min[k] >= b.min[k] && r.max[k] <= b.max[k]);
    match (region, container) {
        _ if inside && !matches!(container, Container::Cylinder { .. } | Container::Sphere { .. }) => {
            region.volume(256)
        }
        (Region::Box { min, max }, Container::Box { .. } | Container::Periodic { .. }) => (0..3)
            .map(|k| (max[k].min(b.max[k]) - min[k].max(b.min[k])).max(0.0))
            .product(),
        _ => Region::Intersection(vec![region.clone(), container.region()]).volume(256),
    }
}

/// The conforming seeds of `params`' sphere phases on `particles` (the Laguerre cells only):
/// every `Spheres` and `Inclusions` phase and every `Region(Sphere)`; the site spacing h is
/// (domain volume / particles)^{1/3}.
fn conform(
    params: &ModelParams,
    particles: &ParticleSet,
    container: &Container,
    domain_volume: f64,
    shapes: &[Inclusion],
) -> Result<(demcon_graph::Conformed, Vec<SphereSurface>), ModelError> {
    if params.laguerre.is_none() {
        return Err(ModelError::invalid(
            params.fields.phase_rule,
            "Conforming",
            "conforming seeds shape the Laguerre cells: set `surface: Laguerre`",
        ));
    }
    let spheres = sphere_surfaces(params, container)?;
    let mut planes = Vec::new();
    for ph in &params.phases {
        match ph {
            PhaseSpec::Region {
                region: Region::Box { min, max },
                ..
            } => planes.extend(box_faces(min, max, container)),
            PhaseSpec::Image { labels } => planes.extend(crate::image::voxel_faces(labels, container)),
            _ => {}
        }
    }
    let h = (domain_volume / particles.len().max(1) as f64).cbrt();
    for (i, ph) in params.phases.iter().enumerate() {
        if let PhaseSpec::Image { labels } = ph {
            let entry = format!("{}[{i}]", params.fields.phases);
            crate::image::check_conformable(labels, container, h, (params.fields.phase_rule, &entry))?;
        }
    }
    // The cracks' surfaces: their law (open, filled) sits on the facets that lie on them.
    planes.extend(
        params
            .defects
            .cracks
            .iter()
            .map(|c| PlanePatch::Crack(c.shape.clone())),
    );
    let body = demcon_graph::Body {
        container,
        carve: params.carve.as_ref().map(|(r, _)| r),
    };
    let surfaces = demcon_graph::Followed {
        spheres: &spheres,
        planes: &planes,
        shapes,
    };
    let conformed = conforming_sites(particles, body, surfaces, h, &ConformParams::default())?;
    Ok((conformed, spheres))
}

/// The sphere surfaces of the phases: every `Spheres` and `Inclusions` phase and every
/// `Region(Sphere)`, in the order of the phase entries.
fn sphere_surfaces(params: &ModelParams, container: &Container) -> Result<Vec<SphereSurface>, ModelError> {
    let mut spheres = Vec::new();
    for ph in &params.phases {
        match ph {
            PhaseSpec::Spheres { radius, centres, .. } => {
                spheres.extend(centres.iter().map(|c| SphereSurface {
                    centre: *c,
                    radius: *radius,
                }))
            }
            PhaseSpec::Inclusions {
                fraction, size_ratio, ..
            } => {
                let (centres, radius) = place_inclusions(
                    container,
                    *fraction,
                    *size_ratio,
                    params.seed,
                    params.fields.inclusions,
                )?;
                spheres.extend(centres.into_iter().map(|centre| SphereSurface { centre, radius }));
            }
            PhaseSpec::Region {
                region: Region::Sphere { centre, radius },
                ..
            } => spheres.push(SphereSurface {
                centre: *centre,
                radius: *radius,
            }),
            PhaseSpec::Region { .. }
            | PhaseSpec::Shapes { .. }
            | PhaseSpec::RandomShapes { .. }
            | PhaseSpec::Image { .. } => {}
        }
    }
    Ok(spheres)
}

/// The phase entries of `params` that are not spheres (the regions a gap between two spheres
/// may lie in), in order; in a periodic box repeated round it ([`Region::periodic`]).
fn other_regions(params: &ModelParams, container: &Container) -> Vec<(Region, u16)> {
    params
        .phases
        .iter()
        .filter_map(|ph| match ph {
            PhaseSpec::Region { phase, region } if !matches!(region, Region::Sphere { .. }) => {
                let region = match container.period() {
                    Some(l) => region.periodic(l, 0.0),
                    None => region.clone(),
                };
                Some((region, *phase))
            }
            _ => None,
        })
        .collect()
}

/// The bridges of a model ([`PhaseBridge`]): the branches between the cells or particles of
/// two spheres (`spheres`) that leave the first before entering the second. The phase of the
/// gap at their middle is that of the last of `regions` (the non-sphere phase entries, in
/// order) holding it, else phase 0.
fn phase_bridges(
    regions: &[(Region, u16)],
    graph: &ContactGraph,
    particles: &ParticleSet,
    container: &Container,
    spheres: &[SphereSurface],
) -> Vec<PhaseBridge> {
    let membership = demcon_graph::sphere_membership(&particles.centres, spheres, container);
    let gap_phase = |x: &Vec3| {
        regions
            .iter()
            .rev()
            .find(|(r, _)| r.contains_point(x))
            .map_or(0, |&(_, p)| p)
    };
    demcon_graph::bridges(graph, &particles.centres, spheres, &membership, container)
        .into_iter()
        .map(|b| PhaseBridge {
            pair: graph.pairs[b.contact as usize],
            gap_phase: gap_phase(&b.gap_middle),
            cos_exit: b.cos_exit,
            cos_entry: b.cos_entry,
        })
        .collect()
}

/// The faces of the box `[min, max]` (m) that separate it from the rest of the body, clipped
/// to the container: in a walled container a face on or beyond a wall separates nothing; in a
/// periodic one a face is taken at its position in the cell, and a box spanning a period along
/// an axis has no face across it.
fn box_faces(min: &Vec3, max: &Vec3, container: &Container) -> Vec<PlanePatch> {
    let b = container.bounds();
    let period = container.period();
    let mut faces = Vec::new();
    for axis in 0..3 {
        let [u, v] = [(axis + 1) % 3, (axis + 2) % 3];
        let lo = [min[u].max(b.min[u]), min[v].max(b.min[v])];
        let hi = [max[u].min(b.max[u]), max[v].min(b.max[v])];
        if !(hi[0] > lo[0] && hi[1] > lo[1]) {
            continue;
        }
        for at in [min[axis], max[axis]] {
            let at = match period {
                Some(l) if max[axis] - min[axis] >= l[axis] => continue,
                Some(l) => at.rem_euclid(l[axis]),
                None if at <= b.min[axis] || at >= b.max[axis] => continue,
                None => at,
            };
            faces.push(PlanePatch::Rect { axis, at, lo, hi });
        }
    }
    faces
}

/// The body's phase fractions from the Laguerre cells' volumes; `None` without cells.
fn body_phase_fractions(
    particles: &ParticleSet,
    mixes: &[Mix],
    graph: &ContactGraph,
    n_phases: usize,
) -> Option<Vec<f64>> {
    let cells = graph.cells.as_deref()?;
    Some(Laminates::new(particles.len(), mixes).phase_fractions_by(particles, &cells.volume, n_phases))
}

/// [`build_model`], timing its stages into `stages`: `phases` (carving and phase
/// assignment), `tessellation` or `contacts`, and `network`.
pub fn build_model_staged(
    packed: Packed,
    params: &ModelParams,
    stages: &mut Stages,
) -> Result<Model, ModelError> {
    build(packed, params, None, stages)
}

/// Builds the model of one MPI rank's block (`docs/distributed.md`): the first `owned`
/// particles are the rank's, the others its ghosts, read-only. Only the owned particles'
/// Laguerre cells are built (their facets towards ghosts included); the ghosts' cells are empty
/// and their facets among themselves absent, so only the owned particles' rows of the network
/// are the whole model's. Returns the model and each owned cell's reach
/// ([`demcon_graph::tessellate_part`]), with which the caller checks that its ghosts were
/// enough.
///
/// Errors: those of [`build_model`]; a model that is not the Laguerre cells', or that carves
/// or places conforming seeds (steps over the whole body, not one block).
pub fn build_block_model(
    packed: Packed,
    params: &ModelParams,
    owned: usize,
    stages: &mut Stages,
) -> Result<(Model, Vec<f64>), ModelError> {
    let why = if params.laguerre.is_none() {
        Some("the Laguerre cells (`surface: Laguerre`)")
    } else if params.carve.is_some() {
        Some("no carving")
    } else if params.phase_rule == PhaseRule::Conforming {
        Some(
            "the `Centre`, `Laminate` or `Segment` phase rule (conforming seeds are placed over the whole body)",
        )
    } else {
        None
    };
    if let Some(allowed) = why {
        return Err(ModelError::invalid(
            "block model",
            "this scene",
            format!("a model built per MPI block needs {allowed}"),
        ));
    }
    let mut reach = Vec::new();
    let model = build(packed, params, Some((owned, &mut reach)), stages)?;
    Ok((model, reach))
}

fn build(
    packed: Packed,
    params: &ModelParams,
    mut owned: Option<(usize, &mut Vec<f64>)>,
    stages: &mut Stages,
) -> Result<Model, ModelError> {
    let Packed {
        particles,
        container,
        report: packing,
        imported_from,
        pack_s,
    } = packed;
    let materials = params.materials.clone();
    let n_phases = materials.materials.len();
    params.defects.validate(n_phases, &params.fields)?;
    let n_before = particles.len();
    let Phased {
        particles,
        kept_ids,
        packing_solid,
        domain_volume,
        carved_away,
        mixes,
        inclusions,
        shapes,
        phase_fractions,
        conformed,
    } = stages.time("phases", || phases(params, particles, &container, &materials))?;
    let t1 = Instant::now();
    let graph = match &params.laguerre {
        Some(lp) => match owned.as_mut() {
            Some((n, reach)) => stages.time("tessellation", || {
                tessellate_part(&particles, &container, None, lp, *n).map(|(g, r)| {
                    **reach = r;
                    g
                })
            })?,
            None => stages.time("tessellation", || {
                tessellate(&particles, &container, params.carve.as_ref().map(|c| &c.0), lp)
            })?,
        },
        None => stages.time("contacts", || {
            detect_contacts(&particles, &container, &params.contacts)
        })?,
    };
    let contacts_s = t1.elapsed().as_secs_f64();
    check_connected(&graph, particles.len(), &params.fields)?;
    let numbering = Numbering {
        kept_ids: kept_ids.as_deref(),
        n_before,
        fields: &params.fields,
    };
    let (graph, mut defects) = defects(graph, &particles, &container, &mixes, params, numbering, stages)?;
    let bridges = bridges(
        params,
        conformed.as_ref().map(|c| &c.2),
        &graph,
        &particles,
        &container,
        stages,
    )?;
    if !bridges.is_empty() {
        update_interface_marks(
            &mut defects,
            &graph,
            &particles.phases,
            &mixes,
            &bridges,
            n_phases,
        );
        defects.report.bridged_contacts = bridges.len();
    }
    let t2 = Instant::now();
    let network = stages.time("network", || Network::new(particles.len(), &graph.pairs))?;
    let network_s = t2.elapsed().as_secs_f64();
    let phase_counts = particles.phases.iter().fold(vec![0; n_phases], |mut c, &p| {
        c[p as usize] += 1;
        c
    });
    // The packing's own solid fraction (the conforming seeds are sites, not grains).
    let phi = packing_solid / domain_volume;
    let body_fractions = body_phase_fractions(&particles, &mixes, &graph, n_phases);
    let mut inclusions = inclusions;
    if let (Some(inc), Some(f)) = (inclusions.as_mut(), body_fractions.as_ref()) {
        inc.particle_fraction = f.get(inc.phase as usize).copied().unwrap_or(0.0);
    }
    Ok(Model {
        report: ModelReport {
            packing,
            imported_from,
            carved_away,
            phase_rule: params.phase_rule,
            phase_counts,
            phase_fractions: body_fractions.unwrap_or_else(|| phase_fractions.clone()),
            sphere_phase_fractions: phase_fractions,
            mixed_particles: mixes.len(),
            conform: conformed.as_ref().map(|c| ConformSummary {
                bridged_facets: bridges.len(),
                ..ConformSummary::from(&c.1)
            }),
            inclusions,
            shapes,
            contacts: ContactSummary::from(&graph.report),
            tessellation: graph
                .cells
                .as_deref()
                .map(|c| TessellationSummary::from(&c.report)),
            defects: (!params.defects.is_empty()).then(|| defects.report.clone()),
            pack_s,
            contacts_s,
            network_s,
        },
        particles,
        container,
        domain_volume,
        carve: params.carve.as_ref().map(|(r, _)| r.clone()),
        seeds: conformed.map_or(0, |c| c.0),
        phi,
        materials,
        mixes,
        graph,
        network: OnceLock::from(network),
        defects,
        bridges,
        fields: params.fields,
        owned: owned.map(|(n, _)| n),
    })
}

/// The particles after carving, conforming seeds and phase assignment, and what those steps
/// measured.
struct Phased {
    particles: ParticleSet,
    /// The packing's index of each kept particle (carving or conforming seeds removed some).
    kept_ids: Option<Vec<u32>>,
    /// Solid volume of the packing's own particles (m³).
    packing_solid: f64,
    domain_volume: f64,
    carved_away: usize,
    mixes: Vec<Mix>,
    inclusions: Option<InclusionReport>,
    shapes: Vec<ShapesReport>,
    phase_fractions: Vec<f64>,
    /// Seeds, report and sphere surfaces of the conforming cells.
    conformed: Option<(usize, ConformReport, Vec<SphereSurface>)>,
}

/// The "phases" stage: carving, conforming seeds, phase assignment.
fn phases(
    params: &ModelParams,
    mut particles: ParticleSet,
    container: &Container,
    materials: &MaterialTable,
) -> Result<Phased, ModelError> {
    let mut kept_ids = None;
    let mut domain_volume = container.volume();
    let mut carved_away = 0;
    if let Some((region, rule)) = &params.carve {
        let (kept, ids) = match rule {
            CarveRule::WholeSphere => carve(&particles, region),
            CarveRule::Centre => particles.retain(|i| region.contains_point(&particles.centres[i])),
        };
        carved_away = particles.len() - kept.len();
        if kept.is_empty() {
            return Err(ModelError::invalid(
                params.fields.carve,
                "region",
                "no particle lies inside the carving region",
            ));
        }
        particles = kept;
        kept_ids = Some(ids);
        domain_volume = body_volume(container, region);
    }
    let mut conformed = None;
    let packing_solid = particles.solid_volume();
    let placed = place_shapes(params, container)?;
    if params.phase_rule == PhaseRule::Conforming {
        let all: Vec<Inclusion> = placed
            .iter()
            .flatten()
            .flat_map(|(s, _)| s.iter().cloned())
            .collect();
        let (c, spheres) = conform(params, &particles, container, domain_volume, &all)?;
        kept_ids = Some(match kept_ids.take() {
            Some(ids) => c.kept.iter().map(|&k| ids[k as usize]).collect(),
            None => c.kept.clone(),
        });
        particles = c.particles;
        conformed = Some((c.n_seeds, c.report, spheres));
    }
    let mut mixes = Vec::new();
    let (inclusions, shapes) =
        apply_phases(params, &mut particles, container, materials, &mut mixes, placed)?;
    let phase_fractions =
        Laminates::new(particles.len(), &mixes).phase_fractions(&particles, materials.materials.len());
    Ok(Phased {
        particles,
        kept_ids,
        packing_solid,
        domain_volume,
        carved_away,
        mixes,
        inclusions,
        shapes,
        phase_fractions,
        conformed,
    })
}

/// The "defects" stage: interfaces, cracks, damage and broken bonds on the graph (none: the
/// graph as it is, no marks).
fn defects(
    graph: ContactGraph,
    particles: &ParticleSet,
    container: &Container,
    mixes: &[Mix],
    params: &ModelParams,
    numbering: Numbering<'_>,
    stages: &mut Stages,
) -> Result<(ContactGraph, Defects), ModelError> {
    if params.defects.is_empty() {
        let marks = vec![0; graph.len()];
        return Ok((
            graph,
            Defects {
                marks,
                ..Defects::default()
            },
        ));
    }
    let n_phases = params.materials.materials.len();
    stages.time("defects", || {
        apply_defects(
            graph,
            particles,
            container,
            mixes,
            &params.defects,
            numbering,
            n_phases,
        )
    })
}

/// Where two spheres nearly touch, cells (or particles) inside them meet across the gap: under
/// the conforming cells (the seeds cannot follow such a gap, `spheres` are theirs) and by
/// centre (the "bridges" stage); none under the other rules.
fn bridges(
    params: &ModelParams,
    spheres: Option<&Vec<SphereSurface>>,
    graph: &ContactGraph,
    particles: &ParticleSet,
    container: &Container,
    stages: &mut Stages,
) -> Result<Vec<PhaseBridge>, ModelError> {
    let regions = other_regions(params, container);
    Ok(match (spheres, params.phase_rule) {
        (Some(spheres), _) => stages.time("bridges", || {
            phase_bridges(&regions, graph, particles, container, spheres)
        }),
        (None, PhaseRule::Centre) => {
            let spheres = sphere_surfaces(params, container)?;
            stages.time("bridges", || {
                phase_bridges(&regions, graph, particles, container, &spheres)
            })
        }
        _ => Vec::new(),
    })
}

/// Smallest share of the particles the largest connected cluster must hold: below it the
/// contacts describe a dust of clusters, not a solid, and every result would be meaningless.
pub const MIN_CONNECTED_FRACTION: f64 = 0.5;

/// Fails when the largest connected cluster holds less than [`MIN_CONNECTED_FRACTION`] of the
/// particles.
fn check_connected(graph: &ContactGraph, n: usize, fields: &FieldNames) -> Result<(), ModelError> {
    let largest = graph.report.largest_component;
    if n > 1 && (largest as f64) < MIN_CONNECTED_FRACTION * n as f64 {
        return Err(ModelError::invalid(
            fields.contacts,
            format!(
                "Z = {:.3e}, ε = {:.3e}",
                graph.report.coordination, graph.report.epsilon
            ),
            format!(
                "the largest connected cluster holds {largest} of {n} particles (less than {:.0} %): the \
                 contacts do not make a solid; raise `coordination` or `tolerance`",
                100.0 * MIN_CONNECTED_FRACTION
            ),
        ));
    }
    Ok(())
}

/// Places monodisperse, non-overlapping inclusion spheres in the container's bounding box
/// with the LS algorithm and returns them (centres (m), radius (m)). `fraction` is their
/// volume fraction, `size_ratio` the box edge over the inclusion diameter; refusals name
/// `{field}.fraction` and `{field}.size_ratio`.
pub fn place_inclusions(
    container: &Container,
    fraction: f64,
    size_ratio: f64,
    seed: u64,
    field: &str,
) -> Result<(Vec<Vec3>, f64), ModelError> {
    if !(fraction > 0.0 && fraction < 0.6) {
        return Err(ModelError::invalid(
            &format!("{field}.fraction"),
            fraction,
            "must be in (0, 0.6)",
        ));
    }
    if !(size_ratio.is_finite() && size_ratio >= 1.0) {
        return Err(ModelError::invalid(
            &format!("{field}.size_ratio"),
            size_ratio,
            "must be ≥ 1 (box edge / diameter)",
        ));
    }
    let b = container.bounds();
    let e = b.extent();
    let edge = e.x.min(e.y).min(e.z);
    let d = edge / size_ratio;
    let sphere_v = std::f64::consts::PI / 6.0 * d * d * d;
    let count = ((fraction * b.volume() / sphere_v).round() as usize).max(1);
    let boxc = Container::Box {
        size: [e.x, e.y, e.z],
    };
    let mut params = PackingParams::new(boxc, count, fraction, RadiusDistribution::Monodisperse);
    params.max_wall_s = 120.0;
    let (spheres, report) = pack(&params, seed ^ 0x9e37_79b9_7f4a_7c15, None)
        .map_err(|e| ModelError::Packing(format!("placing inclusions: {e}")))?;
    if report.stop != StopReason::TargetReached {
        return Err(ModelError::invalid(
            &format!("{field}.fraction"),
            fraction,
            format!(
                "the inclusions could not be placed: reached φ = {:.4} ({:?}) with {count} spheres",
                report.packing.phi, report.stop
            ),
        ));
    }
    let centres = spheres.centres.iter().map(|c| c + b.min).collect();
    Ok((centres, spheres.radii[0]))
}

/// The region of the spheres of one radius at `centres` (m) in `container`, with the periodic
/// images that come within `reach` (m) of the cell in a periodic container: pass the largest
/// particle radius, since a particle whose centre lies in the cell reaches out that far and
/// an image can cut it (the laminate and segment rules; translating a periodic
/// microstructure must not change its answer). `field` names the phase in errors.
///
/// Errors: a radius that is not finite and > 0, a centre outside the container's bounding box
/// (named by its index).
pub fn spheres_region(
    container: &Container,
    radius: f64,
    centres: &[Vec3],
    reach: f64,
    field: &str,
) -> Result<Region, ModelError> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(ModelError::invalid(
            &format!("{field}.radius"),
            radius,
            "must be a finite number > 0 (m)",
        ));
    }
    let b = container.bounds();
    if let Some(k) = centres.iter().position(|c| !b.contains(c)) {
        let c = centres[k];
        return Err(ModelError::invalid(
            &format!("{field}.centres[{k}]"),
            format!("({:e}, {:e}, {:e}) m", c.x, c.y, c.z),
            format!(
                "must lie inside the container's bounding box [{:e}, {:e}] × [{:e}, {:e}] × [{:e}, {:e}] m",
                b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z
            ),
        ));
    }
    let mut spheres = Vec::with_capacity(centres.len());
    for c in centres {
        match container.period() {
            None => spheres.push(Region::Sphere { centre: *c, radius }),
            Some(l) => {
                for shift in image_shifts(l) {
                    let image = c + shift;
                    // An image counts when it comes within `reach` of the cell.
                    let gap = (0..3)
                        .map(|k| (b.min[k] - image[k]).max(image[k] - b.max[k]).max(0.0))
                        .map(|g| g * g)
                        .sum::<f64>()
                        .sqrt();
                    if gap < radius + reach.max(0.0) {
                        spheres.push(Region::Sphere {
                            centre: image,
                            radius,
                        });
                    }
                }
            }
        }
    }
    Ok(Region::Union(spheres))
}

/// The 27 shifts (m) of a periodic cell and its neighbours, the cell itself first.
fn image_shifts(l: [f64; 3]) -> impl Iterator<Item = Vec3> {
    let steps = [0.0, -1.0, 1.0];
    steps.into_iter().flat_map(move |i| {
        steps.into_iter().flat_map(move |j| {
            steps
                .into_iter()
                .map(move |k| Vec3::new(i * l[0], j * l[1], k * l[2]))
        })
    })
}

/// Sets the particles in `region` to `phase` under `rule` (cut particles get a [`Mix`]).
/// Returns how many particles the region claims: centres inside, plus particles it cuts under
/// the laminate and segment rules.
fn assign(
    particles: &mut ParticleSet,
    region: &Region,
    phase: u16,
    rule: PhaseRule,
    mixes: &mut Vec<Mix>,
) -> usize {
    let mixed = mixes.len();
    let inside = match rule {
        PhaseRule::Centre | PhaseRule::Conforming => assign_phase(particles, region, phase),
        PhaseRule::Laminate => assign_phase_laminate(particles, region, phase, mixes, HalfBond::Laminate),
        PhaseRule::Segment => assign_phase_laminate(particles, region, phase, mixes, HalfBond::Segment),
    };
    inside + mixes.len().saturating_sub(mixed)
}

/// A phase entry that claims no particle: its region lies outside the body or falls between
/// the particles' centres (smaller than they are).
fn claims_nobody(fields: &FieldNames, i: usize, what: &str) -> ModelError {
    ModelError::invalid(
        &format!("{}[{i}]", fields.phases),
        what,
        "claims no particle: no particle centre lies inside it (and it cuts none): it lies outside the body, \
         or is smaller than the particles; move or enlarge it, or use more particles",
    )
}

/// Gives the particles inside phase entry `entry`'s `shapes` its phase (under the model's rule)
/// and reports them.
fn apply_shapes(
    params: &ModelParams,
    particles: &mut ParticleSet,
    container: &Container,
    mixes: &mut Vec<Mix>,
    (entry, phase): (usize, u16),
    shapes: &[Inclusion],
    placement: Option<ShapeReport>,
) -> Result<ShapesReport, ModelError> {
    let field = format!("{}[{entry}]", params.fields.phases);
    check_placement(container, shapes, &field)?;
    let region = shapes_region(container, shapes);
    if assign(particles, &region, phase, params.phase_rule, mixes) == 0 {
        return Err(claims_nobody(&params.fields, entry, "Shapes"));
    }
    Ok(ShapesReport {
        entry,
        phase,
        count: shapes.len(),
        fraction: shapes.iter().map(Inclusion::volume).sum::<f64>() / container.bounds().volume(),
        orientation_tensor: orientation_tensor(shapes),
        placement,
        shapes: shapes.to_vec(),
    })
}

/// The shapes of a shape entry and, for a random one, how their placement went.
type PlacedShapes = (Vec<Inclusion>, Option<ShapeReport>);

/// Each phase entry's shapes (`None` for the other entries): listed ones as given, random ones
/// placed in the container (seeded by the model's seed). Placed once, before the conforming
/// seeds that follow them and the phases they give.
fn place_shapes(
    params: &ModelParams,
    container: &Container,
) -> Result<Vec<Option<PlacedShapes>>, ModelError> {
    params
        .phases
        .iter()
        .enumerate()
        .map(|(i, ph)| match ph {
            PhaseSpec::Shapes { shapes, .. } => Ok(Some((shapes.clone(), None))),
            PhaseSpec::RandomShapes { placed: Some(p), .. } if p.0 == *container => {
                Ok(Some((p.1.clone(), Some(p.2.clone()))))
            }
            PhaseSpec::RandomShapes { placement, .. } => {
                let field = format!("{}[{i}]", params.fields.phases);
                let (s, r) = random_shapes(container, placement, params.seed, &field)?;
                Ok(Some((s, Some(r))))
            }
            _ => Ok(None),
        })
        .collect()
}

/// Applies the phase assignments in order.
fn apply_phases(
    params: &ModelParams,
    particles: &mut ParticleSet,
    container: &Container,
    materials: &MaterialTable,
    mixes: &mut Vec<Mix>,
    mut placed: Vec<Option<PlacedShapes>>,
) -> Result<(Option<InclusionReport>, Vec<ShapesReport>), ModelError> {
    let mut inclusions = None;
    let mut shape_reports = Vec::new();
    let mut inclusion_phase = None;
    let reach = particles.radii.iter().copied().fold(0.0, f64::max);
    for (i, ph) in params.phases.iter().enumerate() {
        match ph {
            PhaseSpec::Spheres {
                phase,
                radius,
                centres,
            } => {
                let union = spheres_region(
                    container,
                    *radius,
                    centres,
                    reach,
                    &format!("{}[{i}]", params.fields.phases),
                )?;
                if assign(particles, &union, *phase, params.phase_rule, mixes) == 0 {
                    return Err(claims_nobody(&params.fields, i, "Spheres"));
                }
                inclusion_phase = Some(*phase);
                inclusions = Some(InclusionReport {
                    count: centres.len(),
                    radius: *radius,
                    fraction: centres.len() as f64 * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3)
                        / container.bounds().volume(),
                    particle_fraction: 0.0, // set once all phases are applied
                    phase: *phase,
                    centres: centres.iter().map(|c| [c.x, c.y, c.z]).collect(),
                });
            }
            PhaseSpec::Region { phase, region } => {
                // A region in a periodic box is periodic: its images across the faces count.
                let region = match container.period() {
                    Some(l) => std::borrow::Cow::Owned(region.periodic(l, reach)),
                    None => std::borrow::Cow::Borrowed(region),
                };
                if assign(particles, &region, *phase, params.phase_rule, mixes) == 0 {
                    return Err(claims_nobody(&params.fields, i, "Region"));
                }
            }
            PhaseSpec::Image { labels } if params.phase_rule == PhaseRule::Conforming => {
                crate::image::assign_voxels(particles, labels);
            }
            PhaseSpec::Image { labels } => {
                for (phase, voxels) in labels {
                    assign(
                        particles,
                        &Region::Voxels(voxels.clone()),
                        *phase,
                        params.phase_rule,
                        mixes,
                    );
                }
            }
            PhaseSpec::Shapes { phase, .. } | PhaseSpec::RandomShapes { phase, .. } => {
                let (shapes, placement) = placed[i].take().unwrap_or_default();
                let entry = (i, *phase);
                shape_reports.push(apply_shapes(
                    params, particles, container, mixes, entry, &shapes, placement,
                )?);
            }
            PhaseSpec::Inclusions {
                phase,
                fraction,
                size_ratio,
            } => {
                let (centres, radius) = place_inclusions(
                    container,
                    *fraction,
                    *size_ratio,
                    params.seed,
                    params.fields.inclusions,
                )?;
                let union = spheres_region(
                    container,
                    radius,
                    &centres,
                    reach,
                    &format!("{}[{i}]", params.fields.phases),
                )?;
                if assign(particles, &union, *phase, params.phase_rule, mixes) == 0 {
                    return Err(claims_nobody(&params.fields, i, "Inclusions"));
                }
                let b = container.bounds();
                inclusion_phase = Some(*phase);
                inclusions = Some(InclusionReport {
                    count: centres.len(),
                    radius,
                    fraction: centres.len() as f64 * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3)
                        / b.volume(),
                    particle_fraction: 0.0, // set once all phases are applied
                    phase: *phase,
                    centres: centres.iter().map(|c| [c.x, c.y, c.z]).collect(),
                });
            }
        }
    }
    materials
        .check_phases(&particles.phases)
        .map_err(|e| ModelError::at(params.fields.phases, e))?;
    if let Some(inc) = inclusions.as_mut() {
        let phase = inclusion_phase.unwrap_or(0);
        let f = Laminates::new(particles.len(), mixes).phase_fractions(particles, materials.materials.len());
        inc.particle_fraction = f.get(phase as usize).copied().unwrap_or(0.0);
    }
    Ok((inclusions, shape_reports))
}

/// Re-assigns the phases of a built model (same packing and contacts): every particle back
/// to phase 0 with no mix, then each `(region, phase)` in order under `rule`; updates the
/// report's phase counts, carried fractions and cut-particle count. For studies that compare
/// phase layouts or rules on one packing.
///
/// # Errors
/// `rule` is `Conforming`, or the model was built with conforming cells: those cells are made
/// for their surfaces (rebuild the model with the new phases instead).
pub fn set_region_phases(
    model: &mut Model,
    regions: &[(Region, u16)],
    rule: PhaseRule,
) -> Result<(), ModelError> {
    if rule == PhaseRule::Conforming || model.report.phase_rule == PhaseRule::Conforming {
        return Err(ModelError::invalid(
            model.fields.phase_rule,
            "Conforming",
            "conforming cells are built for their surfaces: build a new model with the new phases",
        ));
    }
    model.particles.phases.iter_mut().for_each(|p| *p = 0);
    model.mixes.clear();
    // The bridges follow the new layout's spheres (by centre; the cut rules read the
    // crossings on the half-bonds).
    model.bridges = match rule {
        PhaseRule::Centre => {
            let mut spheres = Vec::new();
            let mut others = Vec::new();
            for (region, phase) in regions {
                match region {
                    Region::Sphere { centre, radius } => spheres.push(SphereSurface {
                        centre: *centre,
                        radius: *radius,
                    }),
                    Region::Union(parts) if parts.iter().all(|r| matches!(r, Region::Sphere { .. })) => {
                        spheres.extend(parts.iter().filter_map(|r| match r {
                            Region::Sphere { centre, radius } => Some(SphereSurface {
                                centre: *centre,
                                radius: *radius,
                            }),
                            _ => None,
                        }))
                    }
                    _ => others.push((region.clone(), *phase)),
                }
            }
            phase_bridges(
                &others,
                &model.graph,
                &model.particles,
                &model.container,
                &spheres,
            )
        }
        _ => Vec::new(),
    };
    for (region, phase) in regions {
        assign(&mut model.particles, region, *phase, rule, &mut model.mixes);
    }
    let n_phases = model.materials.materials.len();
    let mut counts = vec![0; n_phases];
    for &p in &model.particles.phases {
        if (p as usize) < n_phases {
            counts[p as usize] += 1;
        }
    }
    model.report.phase_counts = counts;
    let spheres = model.laminates().phase_fractions(&model.particles, n_phases);
    model.report.phase_fractions =
        body_phase_fractions(&model.particles, &model.mixes, &model.graph, n_phases)
            .unwrap_or_else(|| spheres.clone());
    model.report.sphere_phase_fractions = spheres;
    model.report.mixed_particles = model.mixes.len();
    update_interface_marks(
        &mut model.defects,
        &model.graph,
        &model.particles.phases,
        &model.mixes,
        &model.bridges,
        n_phases,
    );
    if let Some(r) = model.report.defects.as_mut() {
        r.interface_contacts = model.defects.report.interface_contacts;
    }
    model.report.phase_rule = rule;
    Ok(())
}

/// The model with the defects of `spec` (interfaces, cracks, damage, broken bonds by current
/// particle ids) applied to its graph, without packing or tessellating again: for studies of
/// cracks or interfaces on one packing and network. The network structure is rebuilt without
/// the cut contacts; the report's contact summary and `defects` are updated.
///
/// Errors: a value `spec` refuses, or a model that already has defects (build it without).
pub fn with_defects(model: &Model, spec: &DefectSpec) -> Result<Model, ModelError> {
    let n_phases = model.materials.materials.len();
    spec.validate(n_phases, &model.fields)?;
    if !model.defects.spec.is_empty() {
        return Err(ModelError::invalid(
            model.fields.defects,
            "a model with defects",
            "apply defects to a model built without any",
        ));
    }
    let n = model.particles.len();
    let (graph, defects) = apply_defects(
        model.graph.clone(),
        &model.particles,
        &model.container,
        &model.mixes,
        spec,
        Numbering {
            kept_ids: None,
            n_before: n,
            fields: &model.fields,
        },
        n_phases,
    )?;
    let mut defects = defects;
    if !model.bridges.is_empty() {
        update_interface_marks(
            &mut defects,
            &graph,
            &model.particles.phases,
            &model.mixes,
            &model.bridges,
            n_phases,
        );
    }
    let network = Network::new(n, &graph.pairs)?;
    let mut report = model.report.clone();
    report.contacts = ContactSummary::from(&graph.report);
    report.defects = (!spec.is_empty()).then(|| defects.report.clone());
    Ok(Model {
        particles: model.particles.clone(),
        container: model.container,
        domain_volume: model.domain_volume,
        carve: model.carve.clone(),
        seeds: model.seeds,
        phi: model.phi,
        materials: model.materials.clone(),
        mixes: model.mixes.clone(),
        graph,
        network: OnceLock::from(network),
        defects,
        bridges: model.bridges.clone(),
        report,
        fields: model.fields,
        owned: model.owned,
    })
}
