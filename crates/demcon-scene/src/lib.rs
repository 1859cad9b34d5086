//! Scenes: the RON file format users describe their problem in, its validation with clear
//! errors (file, line, field), and the run pipeline that builds only what the scene asks
//! for — packing, contacts, thermal and/or electric networks, solvers, post-processing — and
//! writes `summary.json`, CSV and VTK outputs.
//!
//! This is the only crate that reads RON, and the one place where the electric and thermal
//! solvers meet (the Joule power vector, ρ_e(T)).
//!
//! ```
//! use std::path::{Path, PathBuf};
//! use demcon_scene::{RunOptions, Scene, run};
//!
//! let text = r#"(
//!     packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 300, phi: 0.55, radius_cov: 0.0),
//!     contacts: (coordination: 6.0),
//!     surface: TerrerosAlpha,
//!     materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0)],
//!     thermal: (
//!         bcs: [
//!             FixedTemperature(select: Face(YMin), value: 0.0),
//!             FixedTemperature(select: Face(YMax), value: 1.0),
//!         ],
//!         solver: Steady,
//!     ),
//!     outputs: (etc_axis: Y, vtk: false),
//! )"#;
//! let scene = Scene::parse(text, Path::new("doc.ron"), PathBuf::new()).unwrap();
//! let result = run(&scene, &RunOptions::default()).unwrap();
//! let etc = result.etc.unwrap().lambda_e;
//! assert!(etc > 10.0 && etc < 60.0, "{etc}");
//! ```
#![warn(missing_docs)]

pub mod config;
pub mod convert;
pub mod electric;
mod error;
pub mod model;
pub mod output;
pub mod run;
pub mod thermal;

pub use config::SceneConfig;
pub use error::SceneError;
pub use model::{Model, build_model};
pub use output::{summary_json, write_outputs};
pub use run::{RunOptions, RunResult, Scene, run, run_on_model};
