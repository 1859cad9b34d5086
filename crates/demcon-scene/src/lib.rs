//! Scenes: the RON file format users describe their problem in (`config`), every value check
//! before any heavy work with clear errors (file, line, field: `validate`), the conversion to
//! plain types (`convert` → [`convert::Problem`]), and the run as named stages (`run`: build →
//! thermal setup → solve → post) that builds only what the scene asks for and writes
//! `summary.json`, CSV and VTK outputs (`output`); a transient writes checkpoints beside its
//! output folder and continues from one bit for bit (`checkpoint`).
//!
//! This is the only crate that reads RON. It builds no physics: surfaces, walls, capacities,
//! calibration, ρ_e(T), Joule power and the electro-thermal coupling live in `demcon-model`.
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

pub mod blocks;
pub mod build;
pub mod checkpoint;
pub mod config;
pub mod convert;
mod error;
pub mod image;
pub mod output;
pub mod plots;
pub mod run;
mod scene;
pub mod shapes;
pub mod validate;

pub use build::build_model;
pub use config::SceneConfig;
pub use convert::Problem;
pub use demcon_model::Model;
/// The distributed solve's session and totals (`demcon run --distributed`).
pub use demcon_network::distributed;
pub use demcon_thermal::ProgressFn;
pub use error::SceneError;
pub use output::{summary_json, write_outputs};
pub use run::{CheckpointOptions, Homogenization, Resumed, RunOptions, RunResult, run, run_on_model};
pub use scene::Scene;
