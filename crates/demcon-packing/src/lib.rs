//! Dense random sphere packings for demcon: the Lubachevsky–Stillinger algorithm (LSA)
//! with radii growing in proportion, in a box, cylinder, sphere or periodic box; radius
//! distributions; carving of packings by regions; tiling of periodic packings; plain-text
//! `x y z r` files; imports from PackingGeneration, LIGGGHTS/LAMMPS dumps and YADE.
//!
//! ```
//! use demcon_core::Container;
//! use demcon_packing::{PackingParams, RadiusDistribution, StopReason, pack};
//!
//! // 300 spheres, Gaussian radii (std/mean 0.3), in a 1 mm periodic box at φ = 0.55.
//! let params = PackingParams::new(
//!     Container::Periodic { size: [1e-3; 3] },
//!     300,
//!     0.55,
//!     RadiusDistribution::gaussian(0.3),
//! );
//! let (spheres, report) = pack(&params, 42, None).unwrap();
//! assert_eq!(report.stop, StopReason::TargetReached);
//! assert_eq!(spheres.len(), 300);
//! assert!((report.packing.phi - 0.55).abs() < 1e-9);
//! assert!(report.packing.max_overlap < 1e-9);
//! println!("{report}");
//! ```
#![warn(missing_docs)]

mod block;
mod carve;
mod error;
mod import;
mod lsa;
mod params;
mod radius;
mod report;
mod shapes;
mod stress;
mod tile;
mod xyzr;

pub use block::{Block, tile_block};
pub use carve::carve;
pub use error::PackingError;
pub use import::{
    ImportFormat, ImportedPacking, PACKING_GENERATION_RECORD_BYTES, check_imported, import_packing,
    read_liggghts_dump, read_packing_generation, read_yade_text,
};
pub use lsa::{MAX_OVERLAP, pack, predict};
pub use params::{
    BYTES_PER_PARTICLE, DEFAULT_MEMORY_LIMIT, EVENT_RATE_BOUND, GROWTH_RATE_RANGE, LENGTH_RANGE,
    MAX_COMPRESSION_PHI, MAX_COUNT, MAX_JAM_PRESSURE, MAX_PHI_ABOVE_JAMMING, MIN_PHI, MemoryLimit,
    NEIGHBOUR_SKIN_RANGE, PackProgress, PackingParams, StopReason, THERMOSTAT_TOLERANCE_RANGE, min_events,
};
pub use radius::{DEFAULT_TRUNCATION_SIGMAS, MIN_RATIO_FLOOR, RadiusDistribution, jamming_estimate};
pub use report::{PackingReport, PackingSummary, RadiusSummary, bulk_phi, max_overlap, summarize};
pub use shapes::{
    Orientation, ShapeKind, ShapeParams, ShapeReport, ShapeStop, first_overlap, periodic_images, place_shapes,
};
pub use stress::{STRESS_GROWTH_RATES, StressFailure, StressReport, stress_packings};
pub use tile::{Repeat, TILE_BYTES_PER_PARTICLE, check_tile_memory, tile, tiled_count};
pub use xyzr::{
    INSIDE_TOLERANCE, MAX_FILE_PHI, XyzrFile, check_inside, check_writable, format_xyzr, parse_xyzr,
    read_xyzr, read_xyzr_container, read_xyzr_file, write_atomic, write_atomic_all, write_xyzr,
    write_xyzr_with_notes,
};
