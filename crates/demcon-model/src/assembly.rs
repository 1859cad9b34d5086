//! What the thermal and electric networks share, below both and below the C_t calibration: the
//! transmission-surface choice ([`SurfaceSpec`], [`CtSpec`]), the default linear solver and the
//! model's network extended by the wall nodes.

use demcon_graph::{SurfaceModel, WallContacts};
use demcon_network::{Method, Network, SolveParams};

use crate::error::ModelError;
use crate::model::Model;

/// Default steady/implicit solver: MIC-preconditioned CG below 10⁴ unknowns,
/// smoothed-aggregation AMG-PCG above (`Method::Auto`), to a relative residual of 1e-10.
pub fn default_solve_params() -> SolveParams {
    SolveParams::new(Method::Auto, 1e-10, 200_000)
}

/// The C_t of the calibrated surface model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CtSpec {
    /// Calibrated on the model's own packing before the run.
    Auto,
    /// A given value (dimensionless, > 0).
    Value(f64),
}

/// Which transmission-surface model a network uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceSpec {
    /// S = C_t π R_m² (Haddad 2021).
    Calibrated(CtSpec),
    /// Terreros α (Hubert 2017).
    TerrerosAlpha,
    /// Facets of the Laguerre cells (the model's graph must be a tessellation).
    Laguerre,
}

impl SurfaceSpec {
    /// The surface model with C_t resolved (`c_t` from a calibration when `Auto`; 1 if none).
    pub fn model(&self, c_t: Option<f64>) -> SurfaceModel {
        match *self {
            SurfaceSpec::TerrerosAlpha => SurfaceModel::TerrerosAlpha,
            SurfaceSpec::Laguerre => SurfaceModel::Laguerre,
            SurfaceSpec::Calibrated(CtSpec::Value(v)) => SurfaceModel::Calibrated { c_t: v },
            SurfaceSpec::Calibrated(CtSpec::Auto) => SurfaceModel::Calibrated {
                c_t: c_t.unwrap_or(1.0),
            },
        }
    }
}

/// The model's network extended by one node per wall (`None` without walls), and the
/// conductances of the contacts followed by those of the wall links.
pub(crate) fn network_with_walls(
    model: &Model,
    walls: &WallContacts,
    contact_g: Vec<f64>,
    wall_g: Vec<f64>,
) -> Result<(Option<Network>, Vec<f64>), ModelError> {
    if walls.is_empty() {
        return Ok((None, contact_g));
    }
    let mut edges = model.graph.pairs.clone();
    edges.extend(walls.edges());
    let mut g = contact_g;
    g.extend(wall_g);
    Ok((Some(Network::new(walls.n_nodes(), &edges)?), g))
}
