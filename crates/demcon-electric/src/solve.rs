//! The Kirchhoff/Ohm solve, its currents and resistance, and Joule heating.

use demcon_network::{
    Diagnostic, FloatingPolicy, Network, SolveParams, SolveReport, boundary_flow, edge_flows, resolve_fixed,
    solve_steady,
};

use crate::error::ElectricError;

/// Parameters of [`solve_potential`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ElectricParams {
    /// Particles in clusters that reach no electrode: fail (default) or exclude (their
    /// potential is then not computed and they carry no current).
    /// [`FloatingPolicy::Keep`] is refused by the steady solve.
    pub floating: FloatingPolicy,
    /// Linear solver.
    pub solve: SolveParams,
}

/// Potentials, currents and resistance of a network.
#[derive(Debug, Clone, PartialEq)]
pub struct ElectricSolution {
    /// Potential of every particle (V); 0 at excluded particles (see [`Self::excluded`]).
    pub potentials: Vec<f64>,
    /// Particles excluded as floating (sorted).
    pub excluded: Vec<u32>,
    /// Current of every branch (A), positive from p to q for `edges[e] = [p, q]`.
    pub branch_currents: Vec<f64>,
    /// Current leaving each electrode into the domain (A), in the caller's order.
    pub electrode_currents: Vec<f64>,
    /// Total current entering the domain, Σ of the positive electrode currents (A).
    pub current_in: f64,
    /// Total current leaving the domain, −Σ of the negative electrode currents (A).
    pub current_out: f64,
    /// |current_in − current_out| / current_in (Kirchhoff check; 0 when no current flows).
    pub current_mismatch: f64,
    /// Equivalent resistance (Ω) ΔV/I between the two electrodes when there are exactly
    /// two, at different potentials, with a non-zero current; `None` otherwise.
    pub resistance_ohm: Option<f64>,
    /// Findings such as excluded floating clusters.
    pub diagnostics: Vec<Diagnostic>,
    /// Solver cost and residual.
    pub report: SolveReport,
}

impl ElectricSolution {
    /// The solution with the potential differences from `ground` (V) scaled by `factor`:
    /// Kirchhoff's laws are linear, so this is the solution with every electrode's potential
    /// moved that way (a current-controlled pair: solve at a unit difference, then scale to
    /// the current asked). Currents scale by `factor`; the resistance is unchanged; excluded
    /// particles keep 0.
    pub fn rescaled(mut self, ground: f64, factor: f64) -> Self {
        for (p, u) in self.potentials.iter_mut().enumerate() {
            if self.excluded.binary_search(&(p as u32)).is_err() {
                *u = ground + factor * (*u - ground);
            }
        }
        self.branch_currents.iter_mut().for_each(|i| *i *= factor);
        self.electrode_currents.iter_mut().for_each(|i| *i *= factor);
        self.current_in = self.electrode_currents.iter().filter(|&&i| i > 0.0).sum();
        self.current_out = -self.electrode_currents.iter().filter(|&&i| i < 0.0).sum::<f64>();
        self
    }
}

/// Solves Kirchhoff's laws with fixed potentials on the electrodes.
///
/// `conductances`: 1/R_pq per edge (S), finite and > 0; `electrodes[k] = (particles,
/// potential in V)`, disjoint and non-empty.
///
/// # Errors
/// [`ElectricError::NoElectrode`], [`ElectricError::EmptyElectrode`],
/// [`ElectricError::ElectrodesOverlap`], and network errors (bad conductances, floating
/// clusters under [`FloatingPolicy::Fail`], non-convergence).
pub fn solve_potential(
    net: &Network,
    conductances: &[f64],
    electrodes: &[(Vec<u32>, f64)],
    params: &ElectricParams,
) -> Result<ElectricSolution, ElectricError> {
    if electrodes.is_empty() {
        return Err(ElectricError::NoElectrode);
    }
    let mut owner = vec![usize::MAX; net.n_nodes()];
    for (k, (nodes, _)) in electrodes.iter().enumerate() {
        if nodes.is_empty() {
            return Err(ElectricError::EmptyElectrode { index: k });
        }
        for &p in nodes {
            // Out-of-range indices are reported by resolve_fixed below.
            if let Some(o) = owner.get_mut(p as usize) {
                if *o != usize::MAX && *o != k {
                    return Err(ElectricError::ElectrodesOverlap {
                        first: *o,
                        second: k,
                        node: p,
                    });
                }
                *o = k;
            }
        }
    }
    let constraints = resolve_fixed(net, electrodes, params.floating)?;
    let zero = vec![0.0; net.n_nodes()];
    let sol = solve_steady(net, conductances, &constraints, &zero, &params.solve)?;
    let branch_currents = edge_flows(net, conductances, &sol.values)?;
    let electrode_currents = electrodes
        .iter()
        .map(|(nodes, _)| boundary_flow(net, conductances, &sol.values, nodes))
        .collect::<Result<Vec<f64>, _>>()?;
    let current_in: f64 = electrode_currents.iter().filter(|i| **i > 0.0).sum();
    let current_out: f64 = -electrode_currents.iter().filter(|i| **i < 0.0).sum::<f64>();
    let current_mismatch = if current_in > 0.0 {
        (current_in - current_out).abs() / current_in
    } else {
        0.0
    };
    let resistance_ohm = match electrodes {
        [(_, va), (_, vb)] if va != vb && electrode_currents[0] != 0.0 => {
            Some((va - vb) / electrode_currents[0])
        }
        _ => None,
    };
    Ok(ElectricSolution {
        potentials: sol.values,
        excluded: sol.excluded,
        branch_currents,
        electrode_currents,
        current_in,
        current_out,
        current_mismatch,
        resistance_ohm,
        diagnostics: constraints.diagnostics().to_vec(),
        report: sol.report,
    })
}

/// Joule power per particle (W): each branch dissipates P = η Δu w = η g Δu² (Hubert et
/// al. 2017, eqs. 8–11), shared half and half between its two particles. The sum over
/// particles equals η V I between two electrodes.
///
/// `conductances`: S per edge; `potentials`: V per particle; `eta`: fraction of the
/// dissipated power converted to heat in the particles, in [0, 1].
///
/// # Errors
/// η outside [0, 1] or not finite; network input errors (lengths, non-finite potentials,
/// bad conductances).
pub fn joule_power(
    net: &Network,
    conductances: &[f64],
    potentials: &[f64],
    eta: f64,
) -> Result<Vec<f64>, ElectricError> {
    if !(0.0..=1.0).contains(&eta) {
        return Err(ElectricError::InvalidParameter {
            field: "eta".into(),
            value: eta.to_string(),
            allowed: "must be in [0, 1]".into(),
        });
    }
    let currents = edge_flows(net, conductances, potentials)?;
    let mut power = vec![0.0; net.n_nodes()];
    for (&[p, q], w) in net.edges().iter().zip(&currents) {
        let du = potentials[p as usize] - potentials[q as usize];
        let half = 0.5 * eta * du * w;
        power[p as usize] += half;
        power[q as usize] += half;
    }
    Ok(power)
}
