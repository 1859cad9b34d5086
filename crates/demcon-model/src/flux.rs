//! Per-particle flux densities of a solved network on a model — the heat flux (W/m²) of the
//! temperatures, the current density (A/m²) of the potentials — by one construction: the
//! dipole D_p = Σ g (u_q − u_p) ℓ of the particle's contacts (each flow acting at its Laguerre
//! facet's centroid with cells, [`demcon_graph::ContactGraph::add_dipoles`]) and wall links
//! ([`demcon_graph::WallContacts::add_dipoles`]), divided by twice the representative volume:
//! q_p = −D_p / (2 V_p), the physical sign (Haddad 2021 eq. 20 corrected: heat and current flow
//! from high to low values). With Laguerre cells this is exact for a linear field in every
//! cell, wall cells included (docs/laguerre.md).

use demcon_core::Vec3;
use demcon_graph::WallContacts;

use crate::model::Model;

/// The flux dipoles D_p (W·m for heat, A·m for current) of every particle of `model`: its
/// contacts' and its wall links'. `conductances` are the network's (W/K or S): the contacts of
/// `model.graph`, then the links of `walls`; `nodes` its values (°C or V): the particles, then
/// one per wall. The heat flux's dipoles are those of a `ThermalSetup` (`walls`,
/// `conductances`) and `ThermalRun::node_temperatures`; the current's those of an
/// [`crate::ElectricRun`] ([`crate::ElectricRun::current_density`]).
///
/// Panics if the lengths do not match (`conductances`: contacts + links; `nodes`: particles +
/// walls): the arrays come from one setup or run.
pub fn flux_dipoles(model: &Model, walls: &WallContacts, conductances: &[f64], nodes: &[f64]) -> Vec<Vec3> {
    let m = model.graph.len();
    let n = model.particles.len();
    assert_eq!(
        conductances.len(),
        m + walls.len(),
        "conductances: contacts, then wall links"
    );
    assert_eq!(nodes.len(), n + walls.n_walls(), "nodes: particles, then walls");
    let (contacts, links) = conductances.split_at(m);
    let mut d = vec![Vec3::zeros(); n];
    model.graph.add_dipoles(contacts, nodes, &mut d);
    walls.add_dipoles(links, nodes, &mut d);
    d
}

/// The flux density q_p = −D_p / (2 V_p) of the dipoles `dipoles` (W·m or A·m) over the
/// representative volumes `volumes` (m³: the Laguerre cells', or V_p/φ, V_p/f_v of the contact
/// models): W/m² for heat, A/m² for current, in the direction the flow goes.
pub fn flux_density(dipoles: &[Vec3], volumes: &[f64]) -> Vec<Vec3> {
    assert_eq!(dipoles.len(), volumes.len(), "one volume per particle");
    dipoles.iter().zip(volumes).map(|(d, v)| -d / (2.0 * v)).collect()
}
