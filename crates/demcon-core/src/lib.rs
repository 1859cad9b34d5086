//! Shared vocabulary of demcon: particles, containers and regions, face/region selectors,
//! materials, the error type for bad input, and the stages of a run (time and memory).
//!
//! Every other crate builds on these plain types; none of them does file I/O (the stages
//! only read the process's own memory figures from `/proc`, and the available memory its
//! limits from `/proc` and `/sys/fs/cgroup`).
//!
//! ```
//! use demcon_core::{Container, Face, ParticleSet, Selector, Vec3};
//!
//! // Two touching unit-diameter spheres in a 1 × 1 × 2 box.
//! let container = Container::Box { size: [1.0, 1.0, 2.0] };
//! let p = ParticleSet::new(
//!     vec![Vec3::new(0.5, 0.5, 0.5), Vec3::new(0.5, 0.5, 1.5)],
//!     vec![0.5, 0.5],
//! ).unwrap();
//! let bottom = Selector::Face(Face::ZMin).select(&p, &container).unwrap();
//! assert_eq!(bottom, vec![0]);
//! assert!((p.solid_volume() / container.volume() - std::f64::consts::PI / 6.0).abs() < 1e-12);
//! ```
#![warn(missing_docs)]

mod available;
pub mod check;
mod components;
mod diagnostic;
mod error;
mod inclusion;
mod material;
pub mod mem;
mod morton;
mod particles;
mod region;
mod selector;
mod shape;
mod stages;
mod time_value;
mod voxels;

pub use available::{AvailableMemory, MemoryBound, available_memory, available_memory_bound};
pub use components::Components;
pub use diagnostic::Diagnostic;
pub use error::{CoreError, short_number};
pub use inclusion::{Ends, Inclusion, unit_axis};
pub use material::{Material, MaterialTable, to_shape_frame};
pub use morton::{MortonCurve, morton_order};
pub use particles::{ParticleSet, RadiusStats};
pub use region::Region;
pub use selector::{DEFAULT_FACE_GAP, Face, Selector};
pub use shape::{Aabb, Axis, Container};
pub use stages::{
    StageObserver, StageRecord, Stages, release_free_memory, reset_peak_resident, resident_bytes,
};
pub use time_value::TimeValue;
pub use voxels::Voxels;

/// A point or vector in 3-D space (m).
pub type Vec3 = nalgebra::Vector3<f64>;
