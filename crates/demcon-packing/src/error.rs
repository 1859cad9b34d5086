//! Errors of demcon-packing: bad input (with the field, value and what is allowed), file
//! problems (with the path and line), and numerical failures.

use std::path::PathBuf;

use demcon_core::CoreError;

/// Everything that can go wrong while packing, carving or reading/writing packings.
#[derive(Debug, thiserror::Error)]
pub enum PackingError {
    /// A parameter is out of range (names the field, the value and what is allowed).
    #[error(transparent)]
    Invalid(#[from] CoreError),
    /// The container cannot hold the requested particles.
    #[error("container too small: {reason}")]
    ContainerTooSmall {
        /// What does not fit, with the numbers (m).
        reason: String,
    },
    /// The random initial placement (random sequential addition) did not succeed.
    #[error("could not place {count} particles at random without overlap, even at volume fraction {phi:.3}")]
    Placement {
        /// Number of particles requested.
        count: usize,
        /// Lowest starting volume fraction tried.
        phi: f64,
    },
    /// Random sequential addition of shapes stalled before the target fraction.
    #[error(
        "the shapes could not reach volume fraction {target}: random sequential addition stalled at \
         {reached:.4} ({placed} of {count} shapes placed, the next found no room in {attempts} tries after \
         {relaxations} rattles); the attainable fraction for these shapes and this gap is about {reached:.3}: \
         lower the fraction or the min_gap"
    )]
    ShapesStalled {
        /// The volume fraction asked.
        target: f64,
        /// The volume fraction placed when it stalled.
        reached: f64,
        /// Shapes placed.
        placed: usize,
        /// Shapes drawn for the target.
        count: usize,
        /// Tries between rattles.
        attempts: usize,
        /// Rattles in a row without room.
        relaxations: usize,
    },
    /// The event-driven run left overlapping spheres: an internal numerical failure.
    #[error(
        "numerical failure: spheres overlap by {overlap:.3e} of the smaller radius (allowed {allowed:.0e})"
    )]
    Overlap {
        /// Largest overlap divided by the smaller radius.
        overlap: f64,
        /// The largest overlap accepted.
        allowed: f64,
    },
    /// A sphere lies outside its container (beyond [`crate::INSIDE_TOLERANCE`]).
    #[error(
        "particle {particle} (centre ({x}, {y}, {z}) m, radius {radius} m) lies outside the {container}: \
         it crosses the boundary by {protrusion} m, {relative} of its radius (allowed {allowed})",
        x = crate::xyzr::short(centre[0]),
        y = crate::xyzr::short(centre[1]),
        z = crate::xyzr::short(centre[2]),
        radius = crate::xyzr::short(*radius),
        protrusion = crate::xyzr::short(*protrusion),
        relative = crate::xyzr::short(protrusion / radius),
        allowed = crate::INSIDE_TOLERANCE
    )]
    Outside {
        /// Particle index (from 0).
        particle: usize,
        /// Its centre (m).
        centre: [f64; 3],
        /// Its radius (m).
        radius: f64,
        /// How far it crosses the boundary (m).
        protrusion: f64,
        /// Container kind and size, as in a file header.
        container: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The system error.
        source: std::io::Error,
    },
    /// A file from another code cannot be imported: a file or column is missing, or its
    /// content is not what that format writes (names the file and what is missing).
    #[error("{}: {message}", path.display())]
    Import {
        /// The file or folder.
        path: PathBuf,
        /// What is missing or wrong, and what was expected.
        message: String,
    },
    /// A packing file is malformed.
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Line number, from 1.
        line: usize,
        /// What is wrong and what was expected.
        message: String,
    },
}
