//! Electric conduction on a DEM conductance network (layer 2), after Hubert et al. 2017:
//! Kirchhoff's current law with Ohm's law on every contact, K u = 0 with fixed potentials
//! on electrodes (K = Aᵀ C A, the conductance-weighted Laplacian), solved through
//! `demcon-network`. Branch currents, electrode currents with their balance, the equivalent
//! resistance ΔV/I, and the Joule power per particle that the thermal solvers accept as a
//! source.
//!
//! Contact conductances 1/R_pq = S_pq/(ρ_e d_pq) (S) come from the particles' conductivities
//! σ = 1/ρ_e(T) ([`particle_conductivities`], [`contact_conductances`]); the surfaces S_pq
//! from `demcon-graph`.
//!
//! ```
//! use demcon_electric::{ElectricParams, joule_power, solve_potential};
//! use demcon_network::Network;
//!
//! // Two 2 S contacts in series between a 1 V and a 0 V electrode: R = 1 Ω, I = 1 A.
//! let net = Network::new(3, &[[0, 1], [1, 2]]).unwrap();
//! let g = [2.0, 2.0];
//! let sol = solve_potential(&net, &g, &[(vec![0], 1.0), (vec![2], 0.0)], &ElectricParams::default())
//!     .unwrap();
//! assert!((sol.resistance_ohm.unwrap() - 1.0).abs() < 1e-9);
//! assert!(sol.current_mismatch < 1e-9);
//! // Joule power: V·I = 1 W, half of each branch to each of its particles.
//! let p = joule_power(&net, &g, &sol.potentials, 1.0).unwrap();
//! assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-9);
//! assert!((p[1] - 0.5).abs() < 1e-9);
//! ```
#![warn(missing_docs)]

mod conductivity;
mod error;
mod solve;

pub use conductivity::{
    ParticleConductivities, conductivity_at, contact_conductances, give_link_joule_to_particles,
    particle_conductivities,
};
pub use error::ElectricError;
pub use solve::{ElectricParams, ElectricSolution, joule_power, solve_potential};
