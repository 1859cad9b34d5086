//! Heat conduction on a DEM conductance network (layer 2): the explicit solver of Haddad et
//! al. 2021 with its exact stability bound, implicit transients, the steady state, and heat
//! sources.
//!
//! Each particle p has a heat capacity C_p (J/K, [`capacities`]) and exchanges
//! H_pq (T_q − T_p) (W) with each contact q: C_p dT_p/dt = Σ_q H_pq (T_q − T_p) + Q_p.
//! Boundary conditions come resolved from [`demcon_network::resolve_fixed`] (fixed
//! temperatures; adiabatic is no condition); imposed fluxes and Joule heating enter as
//! per-particle sources Q_p (W, [`face_flux_sources`]). Long transients hand out their state
//! every K steps or T seconds ([`Checkpoints`]) and continue from it bit for bit
//! ([`run_explicit_from`], [`run_implicit_from`] with [`TransientStart::Resume`]).
//!
//! ```
//! use demcon_network::{FloatingPolicy, Network, SolveParams, resolve_fixed};
//! use demcon_thermal::{
//!     ExplicitParams, ThermalSystem, TimeStep, TransientInput, run_explicit,
//!     solve_steady_temperature, stable_dt_bound,
//! };
//!
//! // A bar of 5 particles, 1 W/K contacts, 2 J/K each; 0 K at node 0, 10 K at node 4.
//! let net = Network::new(5, &[[0, 1], [1, 2], [2, 3], [3, 4]]).unwrap();
//! let h = [1.0; 4];
//! let caps = [2.0; 5];
//! let bcs = resolve_fixed(&net, &[(vec![0], 0.0), (vec![4], 10.0)], FloatingPolicy::Fail).unwrap();
//! // The exact explicit bound: min C_p / Σ_q H_pq = 2 / 2 = 1 s.
//! assert_eq!(stable_dt_bound(&net, &h, &caps, &bcs).unwrap().dt_max, 1.0);
//! let params = ExplicitParams { t_end: 200.0, dt: TimeStep::Auto { safety: 0.8 }, ..Default::default() };
//! let system = ThermalSystem::new(&net, &h, &caps, &bcs).unwrap();
//! let input = TransientInput { temperatures: &[0.0; 5], sources: &[0.0; 5] };
//! let run = run_explicit(&system, input, &params, |_, _| {}, ()).unwrap();
//! // Late enough, the transient reaches the linear steady profile 0, 2.5, 5, 7.5, 10 K.
//! let steady = solve_steady_temperature(&net, &h, &bcs, &[0.0; 5], &SolveParams::default()).unwrap();
//! assert!((steady.solution.values[2] - 5.0).abs() < 1e-9);
//! assert!((run.temperatures[2] - 5.0).abs() < 1e-6);
//! assert!(run.report.energy_balance_error < 1e-10);
//! ```
#![warn(missing_docs)]

mod capacity;
mod checkpoint;
mod error;
mod explicit;
mod implicit;
mod kernel;
mod march;
mod sources;
mod system;
mod transient;

pub use capacity::{DtBound, RepresentativeVolume, capacities, paper_dt_estimate, stable_dt_bound};
pub use checkpoint::{CheckpointEvery, Checkpoints, TransientStart, TransientState};
pub use error::ThermalError;
pub use explicit::{
    ExplicitParams, ExplicitStepper, TimeStep, WeightPrecision, run_explicit, run_explicit_from,
};
pub use implicit::{
    ImplicitParams, Scheme, SteadyTemperature, implicit_step_after, run_implicit, run_implicit_from,
    solve_steady_temperature,
};
pub use sources::{add_sources, face_flux_sources};
pub use system::{NoUpdate, SourceUpdate, SourceUpdateFn, ThermalSystem, TransientInput, source_update_fn};
pub use transient::{DEFAULT_MAX_STEPS, PROGRESS_CALLS, ProgressFn, Transient, TransientReport};
