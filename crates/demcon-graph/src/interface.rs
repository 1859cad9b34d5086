//! Per-contact material property (conductivity) with the interface rule across phases, and
//! contact conductances property·S/d.

use demcon_core::CoreError;

use crate::ContactGraph;
use crate::error::{GraphError, same_len};

/// How a contact between two phases combines their properties.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InterfaceRule {
    /// λ_Γ = 2 λ_p λ_q/(λ_p + λ_q): two half-bonds in series, a perfect interface
    /// (Haddad 2021 eq. 24). The default.
    #[default]
    HarmonicMean,
    /// λ_Γ = (λ_p + λ_q)/2, kept for comparison (overestimates the effective conductivity).
    ArithmeticMean,
}

/// The combined property of two phases (same unit as `a` and `b`, both > 0).
pub fn interface_value(a: f64, b: f64, rule: InterfaceRule) -> f64 {
    if a == b {
        return a;
    }
    match rule {
        InterfaceRule::HarmonicMean => 2.0 * a * b / (a + b),
        InterfaceRule::ArithmeticMean => 0.5 * (a + b),
    }
}

/// The combined property of two half-bonds in series when the contact is split at `w` (the
/// share of the branch on `a`'s side, in (0, 1)): 1/(w/a + (1 − w)/b) for the harmonic rule,
/// w a + (1 − w) b for the arithmetic one. `w = 0.5` is [`interface_value`] exactly.
pub fn interface_value_split(a: f64, b: f64, w: f64, rule: InterfaceRule) -> f64 {
    if a == b || w == 0.5 {
        return interface_value(a, b, rule);
    }
    match rule {
        InterfaceRule::HarmonicMean => 1.0 / (w / a + (1.0 - w) / b),
        InterfaceRule::ArithmeticMean => w * a + (1.0 - w) * b,
    }
}

/// A material property per contact (e.g. λ in W/(m·K), or 1/ρ_e in S/m): the phase's value
/// when both particles share a phase, the `rule` across phases — over the two half-bonds of a
/// Laguerre facet (split at h_p/d, [`ContactGraph::split`]) or two equal halves otherwise.
/// `phases` holds one phase per particle, `per_phase` one value (> 0) per phase.
///
/// Errors: lengths that do not match, a phase without a value, a non-positive value.
pub fn contact_property(
    graph: &ContactGraph,
    phases: &[u16],
    per_phase: &[f64],
    rule: InterfaceRule,
) -> Result<Vec<f64>, GraphError> {
    same_len("phases", phases.len(), graph.n_particles, "particle")?;
    if let Some(k) = per_phase.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(CoreError::invalid(
            format!("per_phase[{k}]"),
            per_phase[k],
            "must be a finite number > 0",
        )
        .into());
    }
    if let Some(i) = phases.iter().position(|&m| m as usize >= per_phase.len()) {
        return Err(CoreError::invalid(
            format!("phases[{i}]"),
            phases[i],
            format!("a phase with a value (0..{})", per_phase.len()),
        )
        .into());
    }
    Ok(graph
        .pairs
        .iter()
        .enumerate()
        .map(|(k, &[p, q])| {
            let a = per_phase[phases[p as usize] as usize];
            let b = per_phase[phases[q as usize] as usize];
            interface_value_split(a, b, graph.split(k), rule)
        })
        .collect())
}

/// Contact conductances property·S_pq/d_pq: W/K for a thermal conductivity λ (W/(m·K)),
/// siemens for an electric conductivity 1/ρ_e (S/m); `areas` in m², one per contact.
///
/// Errors: arrays whose length is not the number of contacts, non-finite or negative values.
pub fn conductances(
    graph: &ContactGraph,
    areas: &[f64],
    property_per_contact: &[f64],
) -> Result<Vec<f64>, GraphError> {
    same_len("areas", areas.len(), graph.pairs.len(), "contact")?;
    same_len(
        "property_per_contact",
        property_per_contact.len(),
        graph.pairs.len(),
        "contact",
    )?;
    for (name, v) in [("areas", areas), ("property_per_contact", property_per_contact)] {
        if let Some(k) = v.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(
                CoreError::invalid(format!("{name}[{k}]"), v[k], "must be a finite number ≥ 0").into(),
            );
        }
    }
    Ok(graph
        .geometry
        .iter()
        .zip(areas.iter().zip(property_per_contact))
        .map(|(g, (s, k))| k * s / g.distance)
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harmonic_mean_limits() {
        let h = |a, b| interface_value(a, b, InterfaceRule::HarmonicMean);
        assert_eq!(h(3.0, 3.0), 3.0);
        // One very poor conductor dominates: λ_Γ → 2·λ_small.
        assert!((h(1e-6, 1.0) / 2e-6 - 1.0).abs() < 1e-5);
        // Symmetric, and between min and max, at most the arithmetic mean.
        assert_eq!(h(0.195, 1.5), h(1.5, 0.195));
        let a = interface_value(0.195, 1.5, InterfaceRule::ArithmeticMean);
        assert!(0.195 < h(0.195, 1.5) && h(0.195, 1.5) < a && a < 1.5);
        // Series of two equal half-bonds: 1/λ_Γ = (1/λ_p + 1/λ_q)/2.
        assert!((1.0 / h(2.0, 5.0) - 0.5 * (0.5 + 0.2)).abs() < 1e-15);
    }
}
