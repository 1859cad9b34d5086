//! Transmission-surface models (one enum, one `match`) and the representative volume of
//! each particle that goes with them.

use demcon_core::{CoreError, ParticleSet};

use crate::error::{GraphError, positive, same_len};
use crate::{Cells, ContactGraph, surface_calibrated, terreros_alpha};

/// How the transmission surface S_pq of a contact is computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceModel {
    /// S_pq = C_t·π·R_m² (Haddad 2021); C_t (dimensionless, > 0) from a calibration run.
    Calibrated {
        /// Calibration constant C_t (dimensionless).
        c_t: f64,
    },
    /// S_pq = √(α(n_p) R_p² · α(n_q) R_q²) (Terreros 2013, Hubert 2017), n = neighbour count.
    TerrerosAlpha,
    /// S_pq = the area of the facet the Laguerre cells of p and q share; the graph must come
    /// from [`crate::tessellate`]. Representative volume: the cell's.
    Laguerre,
}

impl SurfaceModel {
    /// Checks the model's parameters; the error names the field.
    pub fn validate(&self) -> Result<(), GraphError> {
        if let SurfaceModel::Calibrated { c_t } = *self {
            positive("surface.c_t", c_t)?;
        }
        Ok(())
    }
}

/// Transmission surfaces of every contact.
#[derive(Debug, Clone, PartialEq)]
pub struct Surfaces {
    /// S_pq per contact, same order as the graph's pairs (m²).
    pub area: Vec<f64>,
    /// With the Terreros model: particles whose neighbour count lies outside [4, 20] and
    /// took the end value of α (rattlers included). Always 0 for the calibrated model.
    pub clamped: usize,
}

fn check_graph(graph: &ContactGraph, particles: &ParticleSet) -> Result<(), GraphError> {
    same_len(
        "particles.radii",
        particles.radii.len(),
        graph.n_particles,
        "graph particle",
    )
}

/// The cells of a tessellated graph, or an error saying the Laguerre model needs them.
pub(crate) fn cells_of(graph: &ContactGraph) -> Result<&Cells, GraphError> {
    graph.cells.as_deref().ok_or_else(|| {
        CoreError::invalid(
            "surface",
            "Laguerre",
            "the Laguerre surface model needs the graph of a Laguerre tessellation (tessellate), not contacts found by a gap tolerance",
        )
        .into()
    })
}

/// The transmission surface of every contact (m²) under `model`.
///
/// Errors: invalid model parameters, or a particle set that does not match the graph.
pub fn contact_surfaces(
    graph: &ContactGraph,
    particles: &ParticleSet,
    model: &SurfaceModel,
) -> Result<Surfaces, GraphError> {
    model.validate()?;
    check_graph(graph, particles)?;
    let r = &particles.radii;
    Ok(match *model {
        SurfaceModel::Calibrated { c_t } => Surfaces {
            area: (0..graph.len())
                .map(|k| surface_calibrated(c_t, graph.mean_radius(k, r)))
                .collect(),
            clamped: 0,
        },
        SurfaceModel::TerrerosAlpha => {
            let degrees = graph.surface_degrees();
            let alpha: Vec<f64> = degrees.iter().map(|&n| terreros_alpha(n).alpha).collect();
            let clamped = degrees.iter().filter(|&&n| terreros_alpha(n).clamped).count();
            let area = graph
                .pairs
                .iter()
                .map(|&[p, q]| {
                    let (p, q) = (p as usize, q as usize);
                    (alpha[p] * alpha[q]).sqrt() * (r[p] * r[q])
                })
                .collect();
            Surfaces { area, clamped }
        }
        SurfaceModel::Laguerre => Surfaces {
            area: cells_of(graph)?.facet_area.clone(),
            clamped: 0,
        },
    })
}

/// The volume each particle stands for (m³): V_p/φ with the calibrated model (φ the packing's
/// solid fraction, in (0, 1]), V_p/f_v(n_p) with the Terreros model, the cell's volume with the
/// Laguerre model (φ is then not used).
/// Heat capacity is ρ_c·c times this volume.
///
/// Errors: φ outside (0, 1] (calibrated model), a particle set that does not match the graph.
pub fn representative_volumes(
    graph: &ContactGraph,
    particles: &ParticleSet,
    model: &SurfaceModel,
    phi: f64,
) -> Result<Vec<f64>, GraphError> {
    model.validate()?;
    check_graph(graph, particles)?;
    let n = graph.n_particles;
    Ok(match model {
        SurfaceModel::Calibrated { .. } => {
            if !(phi.is_finite() && phi > 0.0 && phi <= 1.0) {
                return Err(demcon_core::CoreError::invalid(
                    "phi",
                    phi,
                    "the solid volume fraction must lie in (0, 1]",
                )
                .into());
            }
            (0..n).map(|i| particles.volume(i) / phi).collect()
        }
        SurfaceModel::TerrerosAlpha => graph
            .surface_degrees()
            .iter()
            .enumerate()
            .map(|(i, &d)| particles.volume(i) / terreros_alpha(d).volume_fraction)
            .collect(),
        SurfaceModel::Laguerre => cells_of(graph)?.volume.clone(),
    })
}
