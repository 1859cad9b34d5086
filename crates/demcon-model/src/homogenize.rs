//! Periodic homogenisation on a model: the effective thermal conductivity tensor and the
//! electric conductivity tensor of a periodic packing, for any surface model (three load
//! cases G = e_x, e_y, e_z on the fluctuation, `demcon_network::homogenize`).

use std::time::Instant;

use demcon_graph::InterfaceRule;
use demcon_network::{Homogenized, SolveParams, homogenize};
use serde::Serialize;

use crate::assembly::SurfaceSpec;
use crate::calibrate::CtCalibration;
use crate::electric::electric_conductances;
use crate::error::ModelError;
use crate::model::Model;
use crate::thermal::thermal_conductances;

/// An effective tensor and what it cost.
#[derive(Debug, Clone, Serialize)]
pub struct TensorReport {
    /// Λ row-major (W/(m·K) thermal, S/m electric).
    pub tensor: [[f64; 3]; 3],
    /// Λ_xx, Λ_yy, Λ_zz: the scalar effective value along each axis.
    pub axes: [f64; 3],
    /// Eigenvalues of the symmetric part, ascending.
    pub eigenvalues: [f64; 3],
    /// max |Λ − Λᵀ| / max |Λ|.
    pub symmetry_error: f64,
    /// Connected components of the network (each one's fluctuation held at 0 at one node).
    pub components: usize,
    /// Linear-solver iterations of the three load cases.
    pub iterations: [usize; 3],
    /// Their relative residuals.
    pub residuals: [f64; 3],
    /// Solver.
    pub method: String,
    /// Wall time of the three solves and their setup (s).
    pub wall_s: f64,
}

impl TensorReport {
    fn from(h: &Homogenized, wall_s: f64) -> Self {
        Self {
            tensor: h.tensor,
            axes: h.diagonal(),
            eigenvalues: h.eigenvalues,
            symmetry_error: h.symmetry_error,
            components: h.components,
            iterations: std::array::from_fn(|k| h.solves[k].iterations),
            residuals: std::array::from_fn(|k| h.solves[k].relative_residual),
            method: h.solves[0].method.to_string(),
            wall_s,
        }
    }
}

/// A homogenisation and, for an `Auto` C_t, its calibration.
#[derive(Debug, Clone, Serialize)]
pub struct HomogenizeRun {
    /// The tensor.
    pub report: TensorReport,
    /// C_t calibrated on this packing (calibrated surfaces with `Auto`).
    pub calibration: Option<CtCalibration>,
    /// The fluctuation of each load case per particle (m: K per K/m), for the fields.
    #[serde(skip)]
    pub fluctuations: [Vec<f64>; 3],
}

/// The container's volume, or an error naming `field` when it is not periodic.
fn periodic_volume(model: &Model, field: &str, value: &str) -> Result<f64, ModelError> {
    match model.container.period() {
        Some(l) => Ok(l[0] * l[1] * l[2]),
        None => Err(ModelError::invalid(
            field,
            value,
            format!(
                "periodic homogenisation needs a Periodic container; this packing's is a {} (use a steady \
                 solve with two walls for an effective conductivity along one axis)",
                model.container.kind()
            ),
        )),
    }
}

/// The effective conductivity tensor (W/(m·K)) of the periodic model under `surface` and
/// `interface`.
///
/// Errors: a container that is not periodic (named as `thermal.solver`), the setup's and the
/// solver's errors.
pub fn homogenize_thermal(
    model: &Model,
    surface: &SurfaceSpec,
    interface: InterfaceRule,
    solve: &SolveParams,
) -> Result<HomogenizeRun, ModelError> {
    let volume = periodic_volume(model, model.fields.solver, "Homogenize")?;
    let (g, calibration) = thermal_conductances(model, surface, interface)?;
    tensor(model, &g, volume, solve, calibration)
}

/// The effective electric conductivity tensor (S/m) of the periodic model at the reference
/// temperature of ρ_e.
///
/// Errors: a container that is not periodic (named as `electric.homogenize`), the setup's
/// and the solver's errors.
pub fn homogenize_electric(
    model: &Model,
    surface: &SurfaceSpec,
    interface: InterfaceRule,
    solve: &SolveParams,
) -> Result<HomogenizeRun, ModelError> {
    let volume = periodic_volume(model, model.fields.electric_homogenize, "true")?;
    let g = electric_conductances(model, surface, interface, None)?;
    tensor(model, &g, volume, solve, None)
}

fn tensor(
    model: &Model,
    g: &[f64],
    volume: f64,
    solve: &SolveParams,
    calibration: Option<CtCalibration>,
) -> Result<HomogenizeRun, ModelError> {
    let start = Instant::now();
    let branches: Vec<_> = (0..model.graph.len()).map(|k| model.graph.branch(k)).collect();
    let h = homogenize(model.network(), g, &branches, volume, solve)?;
    let report = TensorReport::from(&h, start.elapsed().as_secs_f64());
    Ok(HomogenizeRun {
        report,
        calibration,
        fluctuations: h.fluctuations,
    })
}
