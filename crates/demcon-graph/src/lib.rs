//! The contact graph of a sphere packing (layer 0 of demcon): which particles touch, the
//! geometry of each contact, its transmission surface, the material property across
//! phases, the contact conductances, and the graph's connectivity.
//!
//! Flow: [`detect_contacts`] (a relative gap tolerance, or the tolerance that reaches a
//! target mean coordination Z, 7.5 by default) → [`ContactGraph`] with one
//! [`ContactGeometry`] per contact (d_pq, unit normal p→q; gap and R_m from the radii) and a
//! [`ContactReport`] (ε, Z, rattlers, components, cost, diagnostics) →
//! [`contact_surfaces`] under a [`SurfaceModel`] (calibrated C_t·π·R_m², or Terreros α) →
//! [`contact_property`] per contact with an [`InterfaceRule`] → [`conductances`]
//! property·S/d. [`representative_volumes`] gives each particle's volume (V_p/φ or
//! V_p/f_v), [`assign_phase`] sets phases from a region by the particles' centres, and
//! [`assign_phase_laminate`] also resolves the interface inside the particles it cuts
//! ([`Mix`]: a laminate of the two phases, [`contact_property_laminate`]).
//!
//! Neighbour search: a uniform cell grid swept particle by particle in id order, in parallel
//! (default), or
//! an rstar R-tree self-join ([`NeighbourSearch`]); both give identical graphs. The grid is
//! the default because it is ~4× faster on packings. Measured with the `contacts` criterion
//! benchmark (whole [`detect_contacts`] at target Z = 7.5, jittered FCC lattice with
//! Gaussian-ish radii in a walled box, 2-core machine under a load of 7–8):
//!
//! | particles | contacts | cell grid | rstar |
//! |---|---|---|---|
//! | 1.1·10⁴ | 4.1·10⁴ | 9.9 ms | 37.5 ms |
//! | 9.8·10⁴ | 3.7·10⁵ | 108 ms | 465 ms |
//! | 1.0·10⁶ | 3.75·10⁶ | 1.22 s (ids shuffled: 1.65 s) | 5.0 s |
//!
//! Grid cells are one largest contact distance wide, so a cell and its 26 neighbours hold
//! a few dozen spheres stored contiguously (nine runs along x); each particle tests them
//! for partners of higher id, so fixed id ranges run in parallel and emit their pairs
//! already sorted (no global sort), with no tree to build or descend (ids in no spatial order
//! are swept in cell order and sorted once). Since issue 12 the 10⁶ case takes 0.35 s on a
//! quiet machine, 0.8 s under a load of 5 (see `docs/performance.md`; the table above is the
//! earlier sweep, under load). rstar's self-join walks two trees
//! of inflated boxes on one thread. rstar remains the right tool for region, probe and
//! Halo queries. With a target coordination, ε is exact: candidates are found once at a
//! search tolerance and ranked by relative gap (no bisection iterations needed).
//!
//! ```
//! use demcon_core::{Container, ParticleSet, Vec3};
//! use demcon_graph::*;
//!
//! // A row of four touching spheres of radius 0.5 m along x, in a box.
//! let centres = (0..4).map(|i| Vec3::new(0.5 + i as f64, 0.5, 0.5)).collect();
//! let particles = ParticleSet::new(centres, vec![0.5; 4]).unwrap();
//! let container = Container::Box { size: [4.0, 1.0, 1.0] };
//! let graph = detect_contacts(&particles, &container, &ContactParams::relative(0.01)).unwrap();
//! assert_eq!(graph.pairs, vec![[0, 1], [1, 2], [2, 3]]);
//! assert_eq!(graph.report.n_components, 1);
//! assert!((graph.coordination() - 1.5).abs() < 1e-12);
//!
//! // Calibrated surfaces S = C_t π R_m², copper-like λ = 400 W/(m·K): H = λ S / d.
//! let s = contact_surfaces(&graph, &particles, &SurfaceModel::Calibrated { c_t: 0.8 }).unwrap();
//! let lambda = contact_property(&graph, &particles.phases, &[400.0], InterfaceRule::HarmonicMean).unwrap();
//! let h = conductances(&graph, &s.area, &lambda).unwrap();
//! let expected = 400.0 * 0.8 * std::f64::consts::PI * 0.25 / 1.0;
//! assert!(h.iter().all(|&g| (g - expected).abs() < 1e-9 * expected));
//! ```
#![warn(missing_docs)]

mod bridge;
mod calibrated;
mod conform;
mod contact;
mod crack;
mod error;
mod interface;
mod laguerre;
mod laminate;
mod phase;
mod search;
mod shape_samples;
mod surface;
mod terreros;
mod wall;

pub use bridge::{Bridge, NO_SPHERE, bridges, sphere_membership};
pub use calibrated::surface_calibrated;
pub use conform::{
    Body, ConformParams, ConformReport, Conformed, Followed, PlanePatch, SphereSurface, conforming_sites,
    fibonacci_sphere,
};
pub use contact::{
    ContactGeometry, ContactGraph, ContactParams, ContactReport, ContactTolerance, CoordinationPoint,
    Diagnostic, coordination_curve, detect_contacts,
};
pub use crack::{CrackCover, CrackCrossing, CrackShape, blocked_contacts, crossed_contacts, first_crossing};
pub use demcon_core::Components;
pub use error::GraphError;
pub use interface::{InterfaceRule, conductances, contact_property, interface_value, interface_value_split};
pub use laguerre::{
    CellWall, Cells, LaguerreParams, TessellationReport, WallFacet, cell_polyhedra, ghost_width_needed,
    tessellate, tessellate_part,
};
pub use laminate::{
    HalfBond, Laminates, Mix, assign_phase_laminate, contact_property_laminate, inside_fraction,
    interface_normal, laminate_value, plane_cut_fraction, sphere_cut_fraction,
};
pub use phase::assign_phase;
pub use search::{NeighbourSearch, relative_gap};
pub use surface::{SurfaceModel, Surfaces, contact_surfaces, representative_volumes};
pub use terreros::{
    TERREROS_ALPHA, TERREROS_NODES, TERREROS_VOLUME_FRACTION, TerrerosValue, surface_terreros, terreros_alpha,
};
pub use wall::WallContacts;
