//! Physics assembly on plain types (layer 3 of demcon): everything between a built packing
//! and the solvers, with no file format in sight — a function here never names a `…Config`.
//!
//! - [`model`]: the [`Model`] (particles, phases, contacts, network structure) built from a
//!   packing by [`build_model`], phase layouts ([`PhaseSpec`], [`PhaseRule`],
//!   [`set_region_phases`]) and inclusion placement.
//! - [`thermal`]: a [`ThermalProblem`] → [`thermal_setup`] (surfaces, conductances, wall links,
//!   capacities) → [`thermal_bcs`] (resolved boundary conditions and sources) →
//!   [`solve_thermal`] (explicit, implicit or steady).
//! - [`defects`]: imperfect interfaces, cracks, damage and broken bonds ([`DefectSpec`] in
//!   [`ModelParams`], applied by [`build_model`]: cut contacts leave the graph, the others
//!   carry series resistances and factors that both physics' conductances apply).
//! - [`shapes`](mod@shapes): shaped-inclusion phases (spheroids, cylinders, listed or placed at
//!   random) as the region the phase rules cut, and their report.
//! - [`etc`]: the effective conductivity of a steady run from its two held sets
//!   ([`effective_conductivity`]), refused where it is not defined.
//! - `assembly`: what both physics share — the surface choice ([`SurfaceSpec`]), the default
//!   solver ([`default_solve_params`]), the network extended by the wall nodes.
//! - [`calibrate`]: C_t on the model's own packing ([`calibrate_ct_with`]).
//! - [`electric`]: an [`ElectricProblem`] → [`solve_electric`] (conductances with ρ_e(T),
//!   electrodes on particles or faces, Joule power).
//! - [`flux`]: the per-particle flux densities of a solved network, heat or current
//!   ([`flux_dipoles`], [`flux_density`], [`ElectricRun::current_density`]).
//! - [`couple`](mod@couple): the electro-thermal coupling ([`couple()`]: one-way, steady fixed
//!   point, or time-accurate re-solves in a transient).
//! - [`homogenize`](mod@homogenize): the effective conductivity tensors of a periodic packing
//!   ([`homogenize_thermal`], [`homogenize_electric`]: three load cases on the fluctuation).
//! - [`checkpoint`]: what a transient (coupled or not) hands out during a run and continues
//!   from bit for bit ([`RunCheckpoint`], [`solve_thermal_checkpointed`],
//!   [`couple_checkpointed`]).
//!
//! Walls (faces held at a temperature or a potential) are [`demcon_graph::WallContacts`]:
//! one structure that the thermal and electric conductances, the Joule bookkeeping and the
//! flux dipoles all read.
#![warn(missing_docs)]

mod assembly;
pub mod calibrate;
pub mod checkpoint;
pub mod couple;
pub mod defects;
pub mod electric;
mod error;
pub mod etc;
pub mod flux;
pub mod homogenize;
mod image;
pub mod model;
pub mod shapes;
pub mod surroundings;
pub mod thermal;

pub use calibrate::{CalibrationBc, CtCalibration, calibrate_ct, calibrate_ct_with};
pub use checkpoint::{CheckpointSink, Checkpointing, CouplingState, RunCheckpoint};
pub use couple::{Coupled, couple, couple_checkpointed};
pub use defects::{
    Crack, CutCause, CutContact, Damage, DefectReport, DefectSpec, Defects, GrainBoundary,
    InterfaceResistance, MARK_DAMAGED, MARK_FILLED_CRACK, MARK_INTERFACE, MARK_PARTLY_CUT,
};
pub use electric::{
    ElectricNetwork, ElectricProblem, ElectricReport, ElectricRun, Electrode, ElectrodeAt,
    electric_conductances, electric_network, electric_surface_model, particle_conductivities, solve_electric,
};
pub use error::{FieldNames, ModelError};
pub use etc::{EtcValue, FLOW_MISMATCH_WARNING, effective_conductivity};
pub use flux::{flux_density, flux_dipoles};
pub use homogenize::{HomogenizeRun, TensorReport, homogenize_electric, homogenize_thermal};
pub use image::check_conformable as check_image_conformable;
pub use model::{
    CarveRule, ConformSummary, ContactSummary, InclusionReport, Model, ModelParams, ModelReport, Packed,
    PhaseRule, PhaseSpec, TessellationSummary, build_block_model, build_model, build_model_staged,
    place_inclusions, set_region_phases, spheres_region, with_defects,
};
pub use shapes::ShapesReport;
pub use thermal::{
    CtSpec, ExtraSourceUpdate, ExtraSources, FixedSet, FixedTarget, SurfaceSpec, ThermalBc, ThermalBcs,
    ThermalProblem, ThermalRun, ThermalSetup, ThermalSolveReport, ThermalSolver, TimeStepSpec, VolumeSource,
    default_solve_params, initial_node_temperatures, solve_thermal, solve_thermal_checkpointed,
    solve_thermal_with, thermal_bcs, thermal_conductances, thermal_setup,
};
