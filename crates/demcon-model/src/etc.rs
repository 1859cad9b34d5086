//! The effective conductivity of a steady run, from what the run imposes.
//!
//! λ_e = (Q/A) L / ΔT (W/(m·K)) is defined for a body between two sets held at different
//! temperatures, facing each other along one axis, with no heat entering anywhere else. Each
//! figure comes from the run, never from the container alone:
//!
//! - **the two held sets** ([`FixedSet`]): a held face (`WallTemperature`) sits at the face's
//!   plane; held particles (`FixedTemperature`) at the mean of their centres along the axis.
//!   Their spans along the axis must not overlap (else they do not face each other along it),
//!   and a held face must be normal to the axis;
//! - **L**: the distance between the two sets' positions along the axis (m);
//! - **A**: the body's mean section, its volume (the Laguerre cells' sum, or the domain's)
//!   over its extent along the axis (m²); with held faces on Laguerre cells, each face's
//!   own area (its cells' wall facets) is compared with it and a section that varies between
//!   the faces (a notch, a taper) is reported as a warning;
//! - **Q**: the mean of the heat leaving the hot set and entering the cold set (W); both are
//!   reported, and a mismatch (a run that has not reached its steady state) is a warning;
//! - **ΔT**: the two held values (K).
//!
//! Refused ([`ModelError::Invalid`] at `outputs.etc_axis`): a periodic container (heat then
//! also flows round the period: use the homogenisation), a number of held sets other than
//! two, equal held values, any source inside (an imposed flux, a volumetric source, Joule
//! heat: the flow through the two sets then differs and no single λ_e describes it), held
//! sets that do not face each other along the axis.

use demcon_core::{Axis, Container};
use demcon_graph::CellWall;
use serde::Serialize;

use crate::error::ModelError;
use crate::model::Model;
use crate::thermal::{FixedSet, FixedTarget, ThermalBcs, ThermalSetup};

/// Relative mismatch of the heat through the two held sets above which it is reported (the
/// steady solves stop at a relative residual of 1e-10 and keep the two within ~1e-8).
pub const FLOW_MISMATCH_WARNING: f64 = 1e-6;

/// Relative difference between a held face's area and the mean section above which the
/// section is reported as varying (a Laguerre prism matches to round-off; a cylinder's
/// mantle polygon costs ~1e-4 on the cells' volume but not on the face).
const SECTION_WARNING: f64 = 1e-3;

/// Effective conductivity of a steady run, with every figure it was computed from.
#[derive(Debug, Clone, Serialize)]
pub struct EtcValue {
    /// The axis the held sets face each other along (`X`, `Y` or `Z`).
    pub axis: String,
    /// Heat flow through the body (W): the mean of `hot_flow_w` and `cold_flow_w`.
    pub heat_flow_w: f64,
    /// Heat leaving the hot held set (W).
    pub hot_flow_w: f64,
    /// Heat entering the cold held set (W).
    pub cold_flow_w: f64,
    /// The body's mean section normal to the axis (m²): its volume over its extent.
    pub area_m2: f64,
    /// Distance between the two held sets along the axis (m).
    pub length_m: f64,
    /// Where the hot and the cold set sit along the axis (m).
    pub positions_m: [f64; 2],
    /// T_hot − T_cold (K).
    pub delta_t: f64,
    /// λ_e = (Q/A) L / ΔT (W/(m·K)).
    pub lambda_e: f64,
    /// Findings that qualify the figure (a varying section, unequal flows); empty when none.
    pub warnings: Vec<String>,
}

/// Where a held set lies along an axis.
struct Span {
    /// Its position: the face's plane, or the mean of the held centres (m).
    at: f64,
    /// Its extent along the axis: [min, max] of the held centres, or the plane twice (m).
    range: [f64; 2],
    /// For a held face, its own area (m²) where the Laguerre cells give it.
    face_area: Option<f64>,
    /// How the scene holds it, for messages.
    what: String,
}

/// λ_e along `axis` of a steady thermal run: `node_temperatures` are every node's (particles,
/// then walls; °C) and `extra_heat` says whether heat is added inside by another physics
/// (Joule heating), which [`ThermalBcs::sources`] does not show.
///
/// # Errors
/// [`ModelError::Invalid`] at `outputs.etc_axis` for every case the module doc lists, and
/// the network's errors of the flow sums.
pub fn effective_conductivity(
    model: &Model,
    axis: Axis,
    setup: &ThermalSetup,
    bcs: &ThermalBcs,
    node_temperatures: &[f64],
    extra_heat: bool,
) -> Result<EtcValue, ModelError> {
    let ax = format!("{axis:?}");
    let refuse = |why: String| ModelError::invalid(model.fields.etc_axis, &ax, why);
    let (hot, cold) = held_pair(model, setup, bcs, extra_heat, &refuse)?;
    let [h, c] = [hot, cold].map(|s| span(model, setup, s, axis));
    let (h, c) = (h?, c?);
    let apart = h.range[1] < c.range[0] || c.range[1] < h.range[0];
    if !apart {
        return Err(refuse(format!(
            "the held sets do not face each other along {ax}: the hot set ({}) spans [{:.6e}, {:.6e}] m and \
             the cold set ({}) [{:.6e}, {:.6e}] m along it; set `etc_axis` to the axis the two sets are \
             apart along",
            h.what, h.range[0], h.range[1], c.what, c.range[0], c.range[1]
        )));
    }
    let length = (h.at - c.at).abs();
    let net = setup.network(model);
    let hot_flow = demcon_network::boundary_flow(
        net,
        &setup.conductances,
        node_temperatures,
        &hot.nodes(&setup.walls),
    )?;
    let cold_flow = -demcon_network::boundary_flow(
        net,
        &setup.conductances,
        node_temperatures,
        &cold.nodes(&setup.walls),
    )?;
    let q = 0.5 * (hot_flow + cold_flow);
    let area = mean_section(model, axis)?;
    let mut warnings = Vec::new();
    let mismatch = (hot_flow - cold_flow).abs() / hot_flow.abs().max(cold_flow.abs()).max(f64::MIN_POSITIVE);
    if mismatch > FLOW_MISMATCH_WARNING {
        warnings.push(format!(
            "ETC: the heat leaving the hot set ({hot_flow:.6e} W) and entering the cold set ({cold_flow:.6e} W) \
             differ by {mismatch:.2e} (relative): λ_e uses their mean"
        ));
    }
    for s in [&h, &c] {
        if let Some(a) = s.face_area
            && (a / area - 1.0).abs() > SECTION_WARNING
        {
            warnings.push(format!(
                "ETC: the held face {} has an area of {a:.6e} m² against the body's mean section {area:.6e} m² \
                 (volume over length): the section varies between the held sets, so λ_e is the conductivity \
                 of a uniform bar of that mean section with the same conductance",
                s.what
            ));
        }
    }
    let delta_t = hot.value - cold.value;
    let lambda_e = q / area * length / delta_t;
    if !lambda_e.is_finite() {
        return Err(refuse(format!(
            "λ_e = Q L / (A ΔT) is not finite (Q = {q:e} W, L = {length:e} m, A = {area:e} m², ΔT = {delta_t} K)"
        )));
    }
    Ok(EtcValue {
        axis: ax.clone(),
        heat_flow_w: q,
        hot_flow_w: hot_flow,
        cold_flow_w: cold_flow,
        area_m2: area,
        length_m: length,
        positions_m: [h.at, c.at],
        delta_t,
        lambda_e,
        warnings,
    })
}

/// The hot and the cold held set of a run a single λ_e describes: a box that is not periodic,
/// no face exchanging heat, exactly two held sets at two temperatures, and no heat added
/// inside (`extra_heat`: by another physics); otherwise the reason, through `refuse`.
fn held_pair<'a>(
    model: &Model,
    setup: &ThermalSetup,
    bcs: &'a ThermalBcs,
    extra_heat: bool,
    refuse: &dyn Fn(String) -> ModelError,
) -> Result<(&'a FixedSet, &'a FixedSet), ModelError> {
    if model.container.period().is_some() {
        return Err(refuse(
            "a periodic box conducts round its period as well as between held sets, so no λ_e along one \
             axis follows from them: use `thermal.solver: Homogenize` (with `bcs: []`) for the effective \
             tensor"
                .into(),
        ));
    }
    if let Some(x) = setup.surroundings.faces.first() {
        return Err(refuse(format!(
            "face {} exchanges heat with its surroundings (Convection or Radiation): heat leaves elsewhere than \
             through the two held sets and no single λ_e describes the body; an ETC run holds two faces and \
             nothing else",
            x.face.name()
        )));
    }
    let [first, second] = bcs.fixed_sets.as_slice() else {
        return Err(refuse(format!(
            "the effective conductivity needs exactly two held sets (FixedTemperature or WallTemperature); \
             this run holds {}",
            bcs.fixed_sets.len()
        )));
    };
    if first.value == second.value {
        return Err(refuse(format!(
            "the two held sets are both at {} °C: λ_e needs a temperature difference",
            first.value
        )));
    }
    let sourced = bcs.sources.iter().filter(|&&s| s != 0.0).count();
    if sourced > 0 || extra_heat {
        let what = if sourced > 0 {
            format!("{sourced} particle(s) receive heat from an imposed flux or a source")
        } else {
            "Joule heating adds heat inside the body".to_string()
        };
        return Err(refuse(format!(
            "{what}: the heat through the two held sets then differs and no single λ_e describes it; \
             remove the sources (or HeatFlux, or the electric physics' heating: `eta: 0.0`) for an ETC run"
        )));
    }
    Ok(if first.value > second.value {
        (first, second)
    } else {
        (second, first)
    })
}

/// Where held set `s` lies along `axis`.
fn span(model: &Model, setup: &ThermalSetup, s: &FixedSet, axis: Axis) -> Result<Span, ModelError> {
    let k = axis.index();
    match &s.target {
        FixedTarget::Wall(w) => {
            let face = setup.walls.faces[*w];
            if face.axis() != Some(axis) {
                return Err(ModelError::invalid(
                    model.fields.etc_axis,
                    format!("{axis:?}"),
                    format!(
                        "the held face {} is not normal to {axis:?}, so the held sets do not face each other \
                         along it; set `etc_axis` to the axis of the two held faces",
                        face.name()
                    ),
                ));
            }
            let b = model.container.bounds();
            let at = if face == demcon_core::Face::pair(axis).0 {
                b.min[k]
            } else {
                b.max[k]
            };
            let face_area = model
                .graph
                .cells
                .as_deref()
                .map(|cells| cells.on_wall(CellWall::Face(face)).map(|f| f.area).sum());
            Ok(Span {
                at,
                range: [at, at],
                face_area,
                what: format!("WallTemperature on {}", face.name()),
            })
        }
        FixedTarget::Particles(ids) => {
            let xs = ids.iter().map(|&p| model.particles.centres[p as usize][k]);
            let (lo, hi, sum) = xs.fold((f64::INFINITY, f64::NEG_INFINITY, 0.0), |(lo, hi, s), x| {
                (lo.min(x), hi.max(x), s + x)
            });
            Ok(Span {
                at: sum / ids.len().max(1) as f64,
                range: [lo, hi],
                face_area: None,
                what: format!("{} held particles", ids.len()),
            })
        }
    }
}

/// The body's mean section normal to `axis` (m²): its volume (the Laguerre cells' sum, or
/// the domain's) over its extent along the axis (the container's, narrowed by a carving
/// region's bounds when the model has one).
fn mean_section(model: &Model, axis: Axis) -> Result<f64, ModelError> {
    let k = axis.index();
    let volume = match model.graph.cells.as_deref() {
        Some(cells) => cells.volume.iter().sum(),
        None => model.domain_volume,
    };
    let extent = body_extent(&model.container, model.carve.as_ref(), k);
    if !(extent > 0.0 && volume > 0.0) {
        return Err(ModelError::invalid(
            model.fields.etc_axis,
            format!("{axis:?}"),
            format!("the body has no extent along this axis (volume {volume:e} m³, extent {extent:e} m)"),
        ));
    }
    Ok(volume / extent)
}

/// The body's extent along axis `k` (m): the container's bounds, narrowed by the carving
/// region's.
fn body_extent(container: &Container, carve: Option<&demcon_core::Region>, k: usize) -> f64 {
    let b = container.bounds();
    let (mut lo, mut hi) = (b.min[k], b.max[k]);
    if let Some(r) = carve {
        let rb = r.bounds();
        lo = lo.max(rb.min[k]);
        hi = hi.min(rb.max[k]);
    }
    hi - lo
}
