//! Electric conductivities on plain types: σ = 1/ρ_e(T) of every particle (a particle cut by a
//! phase interface mixes its two phases along a half-bond), the contact conductances S σ/d
//! they give, and the Joule power of the links that tie particles to a face electrode.

use demcon_core::{Material, Vec3};
use demcon_graph::{ContactGraph, InterfaceRule, Laminates, Mix, interface_value_split};

use crate::error::ElectricError;

/// Electric conductivities σ = 1/ρ_e(T_p) of every particle (S/m): its own phase's and, for a
/// particle cut by a phase interface, the other phase's with the mix that combines them along a
/// half-bond.
#[derive(Debug, Clone, PartialEq)]
pub struct ParticleConductivities {
    /// σ of the particle's own phase (S/m).
    pub own: Vec<f64>,
    /// The interface mix and σ of the other phase (S/m), for cut particles.
    pub other: Vec<Option<(Mix, f64)>>,
}

impl ParticleConductivities {
    /// Particle p's conductivity along the unit vector `e` over a half-bond of length `half`
    /// (m) (S/m).
    pub fn half_bond(&self, p: usize, e: &Vec3, half: f64) -> f64 {
        match &self.other[p] {
            Some((m, s)) => m.half_bond_value(self.own[p], *s, e, half),
            None => self.own[p],
        }
    }
}

/// σ = 1/ρ_e(T) of `material` at `t` (°C).
///
/// # Errors
/// [`ElectricError::InvalidParameter`] at `materials[<name>].resistivity` when the material has
/// no resistivity, or ρ_e(T) is not finite and > 0.
pub fn conductivity_at(material: &Material, t: f64) -> Result<f64, ElectricError> {
    let field = || format!("materials[{}].resistivity", material.name);
    let rho = material
        .resistivity_at(t)
        .ok_or_else(|| ElectricError::InvalidParameter {
            field: field(),
            value: "none".into(),
            allowed: "an electric scene needs it".into(),
        })?;
    if !(rho.is_finite() && rho > 0.0) {
        return Err(ElectricError::InvalidParameter {
            field: field(),
            value: rho.to_string(),
            allowed: format!("ρ_e(T = {t:.3}) must stay > 0: check resistivity_temp_coeff"),
        });
    }
    Ok(1.0 / rho)
}

/// Conductivities of every particle: `materials[phase]`, the particles' `phases` and the cut
/// particles (`laminates`); `temperatures` (°C, one per particle), when given, evaluate ρ_e(T),
/// else each material's ρ_e at its reference temperature.
///
/// # Errors
/// Those of [`conductivity_at`].
pub fn particle_conductivities(
    materials: &[Material],
    phases: &[u16],
    laminates: &Laminates<'_>,
    temperatures: Option<&[f64]>,
) -> Result<ParticleConductivities, ElectricError> {
    let sigma_of = |phase: u16, p: usize| {
        let m = &materials[phase as usize];
        conductivity_at(m, temperatures.map_or(m.resistivity_ref_temp, |t| t[p]))
    };
    let mut own = Vec::with_capacity(phases.len());
    let mut other = Vec::with_capacity(phases.len());
    for (p, &phase) in phases.iter().enumerate() {
        own.push(sigma_of(phase, p)?);
        other.push(match laminates.get(p) {
            Some(m) => Some((*m, sigma_of(m.other_phase, p)?)),
            None => None,
        });
    }
    Ok(ParticleConductivities { own, other })
}

/// Contact conductances 1/R_pq = S_pq σ_pq / d_pq (S), `area` the transmission surfaces S_pq
/// (m²), σ_pq the two particles' half-bond conductivities combined by `rule` (two half-bonds in
/// series for the harmonic mean).
pub fn contact_conductances(
    graph: &ContactGraph,
    area: &[f64],
    sigma: &ParticleConductivities,
    rule: InterfaceRule,
) -> Vec<f64> {
    graph
        .pairs
        .iter()
        .zip(&graph.geometry)
        .zip(area)
        .enumerate()
        .map(|(k, ((&[p, q], geo), &a))| {
            let (p, q) = (p as usize, q as usize);
            let w = graph.split(k);
            let (sp, sq) = (
                sigma.half_bond(p, &geo.normal, w * geo.distance),
                sigma.half_bond(q, &(-geo.normal), (1.0 - w) * geo.distance),
            );
            interface_value_split(sp, sq, w, rule) * a / geo.distance
        })
        .collect()
}

/// Gives each face-electrode link's Joule power wholly to its particle: `joule` (W per node,
/// from [`crate::joule_power`], which booked half of every branch to each end) receives the
/// half booked to the electrode node, η · G Δu² / 2 per link. `links`: (particle, electrode
/// node, conductance G in S); `potentials` (V) per node.
pub fn give_link_joule_to_particles(
    joule: &mut [f64],
    potentials: &[f64],
    eta: f64,
    links: impl IntoIterator<Item = (u32, u32, f64)>,
) {
    for (p, node, g) in links {
        let du = potentials[p as usize] - potentials[node as usize];
        joule[p as usize] += 0.5 * eta * g * du * du;
    }
}
