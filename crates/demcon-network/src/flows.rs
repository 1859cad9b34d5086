//! Flows through the network from a nodal solution: per edge, per node, across a boundary.

use demcon_core::check::{check_finite, check_len};
use rayon::prelude::*;

use crate::error::SolveError;
use crate::network::Network;
use crate::par::CHUNK;

/// Flow through every edge, g_pq (u_p − u_q), positive from p to q for `edges[e] = [p, q]`
/// (W when u is in K and g in W/K; A when u is in V and g in S).
///
/// # Errors
/// Length mismatches, bad conductances, non-finite values.
pub fn edge_flows(net: &Network, conductances: &[f64], values: &[f64]) -> Result<Vec<f64>, SolveError> {
    net.check_conductances(conductances)?;
    check_len("values", values.len(), net.n_nodes())?;
    check_finite("values", values)?;
    Ok(net
        .edges()
        .par_iter()
        .zip(conductances.par_iter())
        .with_min_len(CHUNK)
        .map(|(&[p, q], g)| g * (values[p as usize] - values[q as usize]))
        .collect())
}

/// Net flow leaving a node set into the rest of the network (W or A):
/// Σ over edges with p in the set and q outside of g_pq (u_p − u_q). For the set of nodes
/// at a fixed value this is the flow the boundary injects (current in, heat in).
///
/// # Errors
/// Length mismatches, bad conductances, non-finite values, node index out of range.
pub fn boundary_flow(
    net: &Network,
    conductances: &[f64],
    values: &[f64],
    nodes: &[u32],
) -> Result<f64, SolveError> {
    net.check_conductances(conductances)?;
    check_len("values", values.len(), net.n_nodes())?;
    check_finite("values", values)?;
    let mut inside = vec![false; net.n_nodes()];
    for &p in nodes {
        *inside
            .get_mut(p as usize)
            .ok_or_else(|| SolveError::NodeOutOfRange {
                what: "boundary_flow nodes".into(),
                node: p as u64,
                n_nodes: net.n_nodes(),
            })? = true;
    }
    let mut total = 0.0;
    for (e, &[p, q]) in net.edges().iter().enumerate() {
        let (a, b) = (inside[p as usize], inside[q as usize]);
        if a != b {
            let f = conductances[e] * (values[p as usize] - values[q as usize]);
            total += if a { f } else { -f };
        }
    }
    Ok(total)
}
