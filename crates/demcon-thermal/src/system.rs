//! The inputs of a transient, each checked once: the validated [`ThermalSystem`] (network,
//! conductances, capacities, resolved boundary conditions), the [`TransientInput`] (initial
//! temperatures and sources), and the [`SourceUpdate`] hook that may replace the sources
//! during a run.

use demcon_core::check::{check_finite, check_len, check_positive};
use demcon_network::{Constraints, Network};

use crate::capacity::{DtBound, dt_bound_of};
use crate::error::ThermalError;

/// A thermal network whose values were checked once: the structure, H_pq per edge (W/K),
/// C_p per node (J/K) and the resolved boundary conditions (fixed temperatures, K).
///
/// Built by [`ThermalSystem::new`], so "one finite conductance > 0 per edge, one finite
/// capacity > 0 per node, constraints of this network" is a property of the type, and the
/// solvers ([`crate::run_explicit`], [`crate::run_implicit`], [`crate::ExplicitStepper`])
/// cannot receive capacities in place of conductances.
#[derive(Debug, Clone, Copy)]
pub struct ThermalSystem<'a> {
    network: &'a Network,
    conductances: &'a [f64],
    capacities: &'a [f64],
    constraints: &'a Constraints,
}

impl<'a> ThermalSystem<'a> {
    /// Checks and bundles the parts of a thermal network.
    ///
    /// `conductances`: H_pq per edge of `network` (W/K); `capacities`: C_p per node (J/K,
    /// [`crate::capacities`]); `constraints`: fixed temperatures (K) and floating-cluster
    /// handling from [`demcon_network::resolve_fixed`] on the same network (use
    /// [`demcon_network::FloatingPolicy::Keep`] to let isolated clusters evolve on their own).
    ///
    /// # Errors
    /// [`ThermalError::Network`] for conductances of the wrong length or not finite and > 0;
    /// [`ThermalError::InvalidParameter`] naming `capacities` (length, or the first entry that
    /// is not finite and > 0) or `constraints` (length).
    pub fn new(
        network: &'a Network,
        conductances: &'a [f64],
        capacities: &'a [f64],
        constraints: &'a Constraints,
    ) -> Result<Self, ThermalError> {
        let n = network.n_nodes();
        network.check_conductances(conductances)?;
        check_len("capacities", capacities.len(), n)?;
        check_positive("capacities", capacities)?;
        check_len("constraints", constraints.kinds().len(), n)?;
        Ok(Self {
            network,
            conductances,
            capacities,
            constraints,
        })
    }

    /// The network (structure).
    pub fn network(&self) -> &'a Network {
        self.network
    }

    /// H_pq per edge (W/K).
    pub fn conductances(&self) -> &'a [f64] {
        self.conductances
    }

    /// C_p per node (J/K).
    pub fn capacities(&self) -> &'a [f64] {
        self.capacities
    }

    /// Resolved boundary conditions (fixed temperatures in K).
    pub fn constraints(&self) -> &'a Constraints {
        self.constraints
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.network.n_nodes()
    }

    /// Forward-Euler positivity bound min_p C_p / Σ_q H_pq over free nodes (s); as
    /// [`crate::stable_dt_bound`], without checking again.
    pub fn stable_dt_bound(&self) -> DtBound {
        dt_bound_of(self.network, self.conductances, self.capacities, self.constraints)
    }

    /// Checks the per-node vectors of a transient against this system.
    pub(crate) fn check_input(&self, input: &TransientInput<'_>) -> Result<(), ThermalError> {
        let n = self.n_nodes();
        check_len("sources", input.sources.len(), n)?;
        check_finite("sources", input.sources)?;
        check_len("initial temperatures", input.temperatures.len(), n)?;
        check_finite("initial temperatures", input.temperatures)?;
        Ok(())
    }
}

/// Where a transient starts: one initial temperature and one heat source per node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransientInput<'a> {
    /// Initial temperature of each node (K); fixed nodes are overwritten by their value.
    pub temperatures: &'a [f64],
    /// Heat source Q_p of each node (W, positive heats); ignored at fixed and excluded
    /// nodes. A [`SourceUpdate`] may replace it during the run.
    pub sources: &'a [f64],
}

/// Sources that may change during a transient (e.g. Joule heat re-evaluated from the
/// temperatures). `()` and [`NoUpdate`] keep the sources; closures are wrapped by
/// [`source_update_fn`].
pub trait SourceUpdate {
    /// The error an update may stop the run with: the caller's own type, into which the
    /// solver's errors convert (the run returns it as it is).
    type Error: From<ThermalError>;

    /// Called once after every step with the time reached `t` (s) and the temperatures
    /// `temps` (K, one per node). Returns new sources (W per node) to use from the next step
    /// on, or `None` to keep the current ones.
    ///
    /// # Errors
    /// Any error stops the run and is returned by the solver.
    fn update(&mut self, t: f64, temps: &[f64]) -> Result<Option<Vec<f64>>, Self::Error>;

    /// Called after every step, before [`SourceUpdate::update`], with the temperatures
    /// reached: may overwrite the nodes this process does not own with their owners' values
    /// (an MPI rank's ghosts, `demcon run --distributed` by blocks). The march's maximum-principle
    /// envelope stays this process's own (its initial and fixed values): give every process
    /// the whole range. Does nothing by default.
    ///
    /// # Errors
    /// Any error stops the run and is returned by the solver.
    fn exchange(&mut self, temps: &mut [f64]) -> Result<(), Self::Error> {
        let _ = temps;
        Ok(())
    }
}

/// Sources that never change.
impl SourceUpdate for () {
    type Error = ThermalError;

    fn update(&mut self, _t: f64, _temps: &[f64]) -> Result<Option<Vec<f64>>, ThermalError> {
        Ok(None)
    }
}

/// Sources that never change (a named form of `()`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoUpdate;

impl SourceUpdate for NoUpdate {
    type Error = ThermalError;

    fn update(&mut self, _t: f64, _temps: &[f64]) -> Result<Option<Vec<f64>>, ThermalError> {
        Ok(None)
    }
}

/// A closure used as a [`SourceUpdate`]; made by [`source_update_fn`].
#[derive(Debug, Clone, Copy)]
pub struct SourceUpdateFn<F>(F);

/// Wraps `f(t, T)` (t in s, T in K per node; returns new sources in W per node, or `None`)
/// as a [`SourceUpdate`] whose error is the closure's. A `&mut` closure works too.
pub fn source_update_fn<F, E>(f: F) -> SourceUpdateFn<F>
where
    F: FnMut(f64, &[f64]) -> Result<Option<Vec<f64>>, E>,
    E: From<ThermalError>,
{
    SourceUpdateFn(f)
}

impl<F, E> SourceUpdate for SourceUpdateFn<F>
where
    F: FnMut(f64, &[f64]) -> Result<Option<Vec<f64>>, E>,
    E: From<ThermalError>,
{
    type Error = E;

    fn update(&mut self, t: f64, temps: &[f64]) -> Result<Option<Vec<f64>>, E> {
        (self.0)(t, temps)
    }
}

impl<U: SourceUpdate + ?Sized> SourceUpdate for &mut U {
    type Error = U::Error;

    fn update(&mut self, t: f64, temps: &[f64]) -> Result<Option<Vec<f64>>, U::Error> {
        (**self).update(t, temps)
    }

    fn exchange(&mut self, temps: &mut [f64]) -> Result<(), U::Error> {
        (**self).exchange(temps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use demcon_network::{FloatingPolicy, resolve_fixed};

    #[test]
    fn bad_parts_are_named_once() {
        let net = Network::new(3, &[[0, 1], [1, 2]]).unwrap();
        let free = resolve_fixed(&net, &[], FloatingPolicy::Keep).unwrap();
        let g = [1.0, 2.0];
        let caps = [1.0, 1.0, 1.0];
        assert!(ThermalSystem::new(&net, &g, &caps, &free).is_ok());
        // Capacities in place of conductances: wrong length, caught.
        assert!(matches!(
            ThermalSystem::new(&net, &caps, &g, &free),
            Err(ThermalError::Network(_))
        ));
        assert!(matches!(
            ThermalSystem::new(&net, &g, &[1.0, 0.0, 1.0], &free),
            Err(ThermalError::InvalidParameter { ref field, .. }) if field == "capacities[1]"
        ));
        let other = Network::new(2, &[[0, 1]]).unwrap();
        let c2 = resolve_fixed(&other, &[], FloatingPolicy::Keep).unwrap();
        assert!(matches!(
            ThermalSystem::new(&net, &g, &caps, &c2),
            Err(ThermalError::InvalidParameter { ref field, .. }) if field == "constraints (length)"
        ));
    }

    #[test]
    fn the_default_update_keeps_the_sources() {
        assert_eq!(().update(1.0, &[0.0]), Ok(None));
        assert_eq!(NoUpdate.update(1.0, &[0.0]), Ok(None));
        fn call(
            mut u: impl SourceUpdate<Error = ThermalError>,
            t: f64,
        ) -> Result<Option<Vec<f64>>, ThermalError> {
            u.update(t, &[0.0])
        }
        let mut calls = 0;
        let mut hook = |t, _: &[f64]| {
            calls += 1;
            Ok::<_, ThermalError>(Some(vec![t]))
        };
        assert_eq!(call(source_update_fn(&mut hook), 2.0), Ok(Some(vec![2.0])));
        let mut wrapped = source_update_fn(&mut hook);
        assert_eq!(call(&mut wrapped, 3.0), Ok(Some(vec![3.0])));
        assert_eq!(call(&mut NoUpdate, 3.0), Ok(None));
        assert_eq!(calls, 2);
    }
}
