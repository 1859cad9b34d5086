//! Checkpoints of a thermal transient on a model, coupled or not: what
//! [`crate::solve_thermal_checkpointed`] and [`crate::couple_checkpointed`] hand out during a
//! run ([`RunCheckpoint`]: the solver's [`TransientState`], the snapshots taken so far, and
//! the state of the ρ_e(T) coupling) and continue from, bit for bit.
//!
//! Steady solves (thermal, or the steady electro-thermal fixed point) have nothing to resume:
//! asked to, they refuse. Storing a checkpoint (a file) is the caller's business.

use demcon_thermal::{CheckpointEvery, TransientState};

use crate::error::{FieldNames, ModelError};

/// Everything a transient on a model needs to continue bit-identically.
#[derive(Debug, Clone, PartialEq)]
pub struct RunCheckpoint {
    /// The thermal solver's state (node temperatures, sources in force, ledger, position).
    pub transient: TransientState,
    /// Snapshots of the particles taken so far (t (s), temperatures (°C)).
    pub snapshots: Vec<(f64, Vec<f64>)>,
    /// The time-accurate ρ_e(T) coupling's state (coupled transients with
    /// `recouple_tolerance` only).
    pub coupling: Option<CouplingState>,
}

/// The state of a transient's ρ_e(T) coupling ([`crate::couple()`]): the electric solve in
/// force is the one at `last_temperatures`, redone on resuming (the solve is deterministic).
#[derive(Debug, Clone, PartialEq)]
pub struct CouplingState {
    /// Particle temperatures of the last potential solve (°C).
    pub last_temperatures: Vec<f64>,
    /// Potential solves so far.
    pub solves: u64,
    /// Their wall time (s); only reported.
    pub solves_wall_s: f64,
}

/// Receives each checkpoint; an error stops the run and is returned by the solve.
pub type CheckpointSink<'a> = dyn FnMut(RunCheckpoint) -> Result<(), ModelError> + 'a;

/// Checkpoints of a transient solve: when to hand them out, where to, and the one to
/// continue from.
pub struct Checkpointing<'a, 'b> {
    /// When (never when both are `None`).
    pub every: CheckpointEvery,
    /// Continue from this checkpoint instead of the initial temperatures.
    pub resume: Option<&'b RunCheckpoint>,
    /// Receives each checkpoint.
    pub sink: &'b mut CheckpointSink<'a>,
}

impl std::fmt::Debug for Checkpointing<'_, '_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Checkpointing")
            .field("every", &self.every)
            .field("resume", &self.resume.map(|r| r.transient.steps))
            .finish_non_exhaustive()
    }
}

/// The refusal of a run that cannot continue from `resume` because of what it is
/// (`what`, e.g. "a steady solve").
pub(crate) fn not_resumable(fields: &FieldNames, what: &str) -> ModelError {
    ModelError::invalid(
        fields.solver,
        what,
        "only a transient (Explicit or Implicit) can be resumed: a steady solve has nothing to resume",
    )
}

/// Checks that a checkpoint carries a coupling state exactly when the run is a coupled
/// transient (`coupled`), and that state's length.
pub(crate) fn check_coupling(
    ck: &RunCheckpoint,
    coupled: bool,
    n: usize,
    fields: &FieldNames,
) -> Result<(), ModelError> {
    let field = format!("{}.coupling", fields.checkpoint);
    match (&ck.coupling, coupled) {
        (None, false) => Ok(()),
        (Some(c), true)
            if c.last_temperatures.len() == n && c.last_temperatures.iter().all(|t| t.is_finite()) =>
        {
            Ok(())
        }
        (Some(c), true) => Err(ModelError::invalid(
            &field,
            format!("{} temperatures", c.last_temperatures.len()),
            format!("must hold one finite temperature per particle ({n})"),
        )),
        (c, _) => Err(ModelError::invalid(
            &field,
            if c.is_some() { "present" } else { "absent" },
            if coupled {
                "this run re-solves the potential during the transient (recouple_tolerance): its checkpoint must carry the coupling"
            } else {
                "this run does not re-solve the potential during the transient: the checkpoint comes from another run"
            },
        )),
    }
}
