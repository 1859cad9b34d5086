//! Post-processing of demcon particle fields: per-particle flux (Haddad 2021 eq. 20 with the
//! physical sign), Halo smoothing (eqs. 22–23), coefficient of variation, effective
//! conductivity, probes, profiles, slices, and VTK (`.vtu`) and CSV writers (and their readers,
//! for tools that open a run's files: `read_vtu`, `read_csv`).
//!
//! Everything takes plain data, so this crate depends on no solver: contact pairs
//! `&[[u32; 2]]`, branch vectors `ℓ_pq = x_q − x_p` (m, minimum image if periodic),
//! conductances `g_pq = λ S_pq / d_pq` (W/K), representative volumes `V_rep,p` (m³, `V_p/φ`
//! or `V_p/f_v,p`) and node values (K).
//!
//! ```
//! use demcon_core::{Container, ParticleSet, Vec3};
//! use demcon_post::{Domain, HaloParams, ProbeMethod, halo_flux, particle_dipoles, particle_flux, probe};
//!
//! // A row of three touching spheres (r = 1 mm) along x, with T = 1000·x K (x in m).
//! let r = 1e-3;
//! let p = ParticleSet::new(
//!     (0..3).map(|i| Vec3::new((2 * i + 1) as f64 * r, r, r)).collect(),
//!     vec![r; 3],
//! ).unwrap();
//! let pairs = [[0u32, 1], [1, 2]];
//! let branches = [Vec3::new(2.0 * r, 0.0, 0.0); 2];
//! let lambda = 50.0; // W/(m·K)
//! let g = [lambda * 4.0 * r * r / (2.0 * r); 2]; // λ S / d with S = 4r², W/K
//! let t: Vec<f64> = p.centres.iter().map(|c| 1000.0 * c.x).collect();
//! let vrep = vec![(2.0 * r).powi(3); 3]; // simple cubic cell, m³
//!
//! // The middle particle sees the whole gradient: q = −λ ∇T (W/m²), sign included.
//! let q = particle_flux(&pairs, &branches, &g, &vrep, &t).unwrap();
//! assert!((q[1].x + lambda * 1000.0).abs() < 1e-9);
//!
//! // Halo smoothing over 2 radii: the ends average with the middle.
//! let domain = Domain::of_container(&Container::Box { size: [6.0 * r, 2.0 * r, 2.0 * r] }).unwrap();
//! let d = particle_dipoles(&pairs, &branches, &g, &t).unwrap();
//! let h = halo_flux(&p, &d, &vrep, &domain, &HaloParams::ratio(2.0)).unwrap();
//! assert!((h.flux[0].x + 0.75 * lambda * 1000.0).abs() < 1e-9); // (0.5 + 1) / 2 of λ∇T
//! assert!(h.truncated[0]);
//!
//! // Temperature at a point: nearest particle.
//! let t_mid = probe(&p, &vrep, &t, &Vec3::new(3.2 * r, r, r), &ProbeMethod::Nearest, &domain).unwrap();
//! assert_eq!(t_mid, t[1]);
//! ```
#![warn(missing_docs)]

mod atomic;
mod csv;
mod domain;
mod error;
mod flux;
mod halo;
mod probe;
mod slice;
mod stats;
mod vtk;
mod vtu_read;

pub use csv::{read_csv, write_csv};
pub use domain::{Domain, Plane};
pub use error::PostError;
pub use flux::{PlaneFlow, flow_across_plane, particle_dipoles, particle_dipoles_levers, particle_flux};
pub use halo::{
    HaloBlock, HaloField, HaloParams, HaloPhases, HaloReport, HaloScale, halo_flux, halo_flux_blocked,
};
pub use probe::{Line, MAX_PROFILE_POINTS, ProbeIndex, ProbeMethod, line_points, probe, profile};
pub use slice::{Grid, SliceParams, slice_grid};
pub use stats::{coefficient_of_variation, components, effective_conductivity, magnitudes};
pub use vtk::{
    Field, FieldData, Polyhedra, write_lines_vtp, write_polyhedra_vtu, write_pvd, write_triangles_vtp,
    write_vtu,
};
pub use vtu_read::{VtuArray, VtuData, read_vtu};
