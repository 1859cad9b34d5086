//! Checkpoints and resuming: a transient stopped at any checkpoint and continued from its
//! state ends bit for bit as the uninterrupted run (temperatures, later snapshots, every
//! report number but wall time and throughput), for the explicit and both implicit schemes,
//! with output times that shorten steps and sources replaced during the run; taking
//! checkpoints (by steps or by wall time) changes nothing; a state from another run is
//! refused.

mod common;

use common::{face, lattice};
use demcon_network::{Constraints, FloatingPolicy, Network, resolve_fixed};
use demcon_thermal::{
    CheckpointEvery, Checkpoints, ExplicitParams, ImplicitParams, Scheme, ThermalError, ThermalSystem,
    TimeStep, Transient, TransientInput, TransientStart, TransientState, run_explicit_from,
    run_implicit_from, source_update_fn,
};

/// A 5×5×5 lattice with diagonals: one face held at 300 K, heat sources inside.
struct Case {
    net: Network,
    g: Vec<f64>,
    c: Vec<f64>,
    bcs: Constraints,
    t0: Vec<f64>,
    q: Vec<f64>,
}

fn case() -> Case {
    let n = 5;
    let (net, g, c) = lattice(n, 7, true);
    let bcs = resolve_fixed(&net, &[(face(n, 0), 300.0)], FloatingPolicy::Fail).unwrap();
    let nodes = net.n_nodes();
    let t0 = (0..nodes).map(|p| 290.0 + (p % 7) as f64).collect();
    let q = (0..nodes).map(|p| if p % 3 == 0 { 0.5 } else { 0.0 }).collect();
    Case {
        net,
        g,
        c,
        bcs,
        t0,
        q,
    }
}

/// What the observer saw: (t, temperatures).
type Snapshots = Vec<(f64, Vec<f64>)>;

/// Which solver a run uses.
#[derive(Clone, Copy, Debug)]
enum Solver {
    Explicit,
    Implicit(Scheme),
}

/// Output times that do not fall on steps (shortened steps, segments of different h; the
/// implicit steps of (1.1, 2.0] and (2.0, 2.3] differ by rounding only, so the second reuses
/// the first's linear system, which a run resumed inside it must rebuild).
const OUTPUT_TIMES: [f64; 5] = [0.0, 0.37, 1.1, 2.0, 2.3];
const T_END: f64 = 3.05;

/// A run of `solver` from `start`, sources replaced after every step as a function of the
/// temperatures (Q_p (1 + 0.01 (T_p − 300)) on the heated nodes), with `checkpoints`.
/// Returns the result and the snapshots the observer saw.
fn go(
    case: &Case,
    solver: Solver,
    start: TransientStart<'_>,
    checkpoints: Option<Checkpoints<'_>>,
) -> (Result<Transient, ThermalError>, Snapshots) {
    let system = ThermalSystem::new(&case.net, &case.g, &case.c, &case.bcs).unwrap();
    let mut snaps = Vec::new();
    let observer = |t: f64, v: &[f64]| snaps.push((t, v.to_vec()));
    let q = case.q.clone();
    let update = source_update_fn(move |_t, temps: &[f64]| {
        Ok::<_, demcon_thermal::ThermalError>(Some(
            q.iter()
                .zip(temps)
                .map(|(&q, &t)| q * (1.0 + 0.01 * (t - 300.0)))
                .collect(),
        ))
    });
    let r = match solver {
        Solver::Explicit => {
            let params = ExplicitParams {
                t_end: T_END,
                dt: TimeStep::Auto { safety: 0.9 },
                output_times: OUTPUT_TIMES.to_vec(),
                ..Default::default()
            };
            run_explicit_from(&system, start, &params, observer, update, checkpoints)
        }
        Solver::Implicit(scheme) => {
            let params = ImplicitParams {
                t_end: T_END,
                dt: 0.1,
                scheme,
                output_times: OUTPUT_TIMES.to_vec(),
                ..Default::default()
            };
            run_implicit_from(&system, start, &params, observer, update, checkpoints)
        }
    };
    (r, snaps)
}

/// Every report number but the wall time and the throughput, bit for bit.
fn assert_same(a: &Transient, b: &Transient, what: &str) {
    assert_eq!(
        bits(&a.temperatures),
        bits(&b.temperatures),
        "{what}: temperatures"
    );
    let (mut ra, mut rb) = (a.report.clone(), b.report.clone());
    for r in [&mut ra, &mut rb] {
        r.wall_s = 0.0;
        r.contacts_per_s = 0.0;
    }
    assert_eq!(format!("{ra:?}"), format!("{rb:?}"), "{what}: report");
    assert_eq!(ra, rb, "{what}: report");
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The uninterrupted run and every state it handed out every `k` steps.
fn states(case: &Case, solver: Solver, k: u64) -> (Transient, Snapshots, Vec<TransientState>) {
    let mut saved = Vec::new();
    let mut save = |s: TransientState| {
        saved.push(s);
        Ok(())
    };
    let input = TransientInput {
        temperatures: &case.t0,
        sources: &case.q,
    };
    let ck = Checkpoints {
        every: CheckpointEvery {
            steps: Some(k),
            seconds: None,
        },
        save: &mut save,
    };
    let (r, snaps) = go(case, solver, TransientStart::Initial(input), Some(ck));
    (r.unwrap(), snaps, saved)
}

fn resumed_runs_equal_the_uninterrupted_one(solver: Solver, k: u64) {
    let case = case();
    let input = TransientInput {
        temperatures: &case.t0,
        sources: &case.q,
    };
    let (plain, plain_snaps) = go(&case, solver, TransientStart::Initial(input), None);
    let plain = plain.unwrap();
    let (full, full_snaps, saved) = states(&case, solver, k);
    // Taking checkpoints changes nothing.
    assert_same(&plain, &full, "with checkpoints");
    assert_eq!(plain_snaps, full_snaps);
    assert!(saved.len() >= 5, "{solver:?}: {} checkpoints", saved.len());
    // Some checkpoints fall at the end of a segment (a stop), some inside one.
    assert!(saved.iter().any(|s| s.segment_steps == 0));
    assert!(saved.iter().any(|s| s.segment_steps > 0));
    assert!(saved.windows(2).all(|w| w[1].steps == w[0].steps + k));
    for s in &saved {
        let (r, snaps) = go(&case, solver, TransientStart::Resume(s), None);
        let what = format!("{solver:?} resumed at step {} (t = {})", s.steps, s.t);
        assert_same(&plain, &r.unwrap(), &what);
        // The observer sees the stops after the state, as the uninterrupted run did.
        let later: Vec<_> = plain_snaps.iter().filter(|(t, _)| *t > s.t).cloned().collect();
        assert_eq!(snaps, later, "{what}: snapshots");
    }
}

#[test]
fn explicit_resumed_at_any_checkpoint_equals_the_uninterrupted_run() {
    // Every step: every position, shortened steps and stops included.
    resumed_runs_equal_the_uninterrupted_one(Solver::Explicit, 1);
}

#[test]
fn backward_euler_resumed_at_any_checkpoint_equals_the_uninterrupted_run() {
    resumed_runs_equal_the_uninterrupted_one(Solver::Implicit(Scheme::BackwardEuler), 3);
}

#[test]
fn crank_nicolson_resumed_at_any_checkpoint_equals_the_uninterrupted_run() {
    resumed_runs_equal_the_uninterrupted_one(Solver::Implicit(Scheme::CrankNicolson), 4);
}

#[test]
fn a_run_stopped_by_its_checkpoint_sink_resumes_from_the_state_it_kept() {
    // The "kill": the sink keeps the state and stops the run; twice in a row.
    for solver in [Solver::Explicit, Solver::Implicit(Scheme::BackwardEuler)] {
        let case = case();
        let input = TransientInput {
            temperatures: &case.t0,
            sources: &case.q,
        };
        let (plain, _) = go(&case, solver, TransientStart::Initial(input), None);
        let plain = plain.unwrap();
        let stop_after = |start: TransientStart<'_>| {
            let mut kept = None;
            let mut save = |s: TransientState| {
                kept = Some(s);
                Err(ThermalError::invalid("test", "stop", "stopped on purpose"))
            };
            let ck = Checkpoints {
                every: CheckpointEvery {
                    steps: Some(5),
                    seconds: None,
                },
                save: &mut save,
            };
            let (r, _) = go(&case, solver, start, Some(ck));
            assert!(matches!(r, Err(ThermalError::InvalidParameter { ref field, .. }) if field == "test"));
            kept.unwrap()
        };
        let first = stop_after(TransientStart::Initial(input));
        assert_eq!(first.steps, 5);
        let second = stop_after(TransientStart::Resume(&first));
        assert_eq!(second.steps, 10);
        let (r, _) = go(&case, solver, TransientStart::Resume(&second), None);
        assert_same(&plain, &r.unwrap(), &format!("{solver:?} stopped twice"));
    }
}

#[test]
fn checkpoints_by_wall_time_change_nothing() {
    // A period far below a step's cost: a checkpoint after every step.
    for solver in [Solver::Explicit, Solver::Implicit(Scheme::CrankNicolson)] {
        let case = case();
        let input = TransientInput {
            temperatures: &case.t0,
            sources: &case.q,
        };
        let (plain, plain_snaps) = go(&case, solver, TransientStart::Initial(input), None);
        let plain = plain.unwrap();
        let mut count = 0u64;
        let mut last = None;
        let mut save = |s: TransientState| {
            count += 1;
            last = Some(s);
            Ok(())
        };
        let ck = Checkpoints {
            every: CheckpointEvery {
                steps: None,
                seconds: Some(1e-12),
            },
            save: &mut save,
        };
        let (r, snaps) = go(&case, solver, TransientStart::Initial(input), Some(ck));
        let r = r.unwrap();
        assert_same(&plain, &r, &format!("{solver:?} with timed checkpoints"));
        assert_eq!(plain_snaps, snaps);
        // One per step but the last (the run is then over).
        assert_eq!(count, r.report.steps - 1, "{solver:?}");
        assert!(last.unwrap().wall_s >= 0.0);
    }
}

#[test]
fn a_state_from_another_run_is_refused() {
    let case = case();
    let (_, _, saved) = states(&case, Solver::Implicit(Scheme::BackwardEuler), 10);
    let s = &saved[1];
    let refused = |solver: Solver, s: &TransientState| {
        let (r, _) = go(&case, solver, TransientStart::Resume(s), None);
        match r {
            Err(ThermalError::InvalidParameter { field, .. }) => field,
            other => panic!("{solver:?}: {other:?}"),
        }
    };
    // Another scheme.
    assert!(refused(Solver::Explicit, s).contains("scheme"));
    assert!(refused(Solver::Implicit(Scheme::CrankNicolson), s).contains("scheme"));
    // Another step or end time.
    let mut other = s.clone();
    other.dt = 0.2;
    assert!(refused(Solver::Implicit(Scheme::BackwardEuler), &other).contains("dt"));
    let mut other = s.clone();
    other.t_end = 4.0;
    assert!(refused(Solver::Implicit(Scheme::BackwardEuler), &other).contains("t_end"));
    // Another network size, or a value that is not finite.
    let mut other = s.clone();
    other.temperatures.pop();
    assert!(refused(Solver::Implicit(Scheme::BackwardEuler), &other).contains("temperatures"));
    let mut other = s.clone();
    other.sources[3] = f64::NAN;
    assert!(refused(Solver::Implicit(Scheme::BackwardEuler), &other).contains("sources"));
    // A position off the run's steps.
    for (segment, segment_steps, steps) in [(s.segment, s.segment_steps, s.steps + 1), (99, 0, s.steps)] {
        let mut other = s.clone();
        (other.segment, other.segment_steps, other.steps) = (segment, segment_steps, steps);
        assert!(refused(Solver::Implicit(Scheme::BackwardEuler), &other).contains("position"));
    }
    // A bad schedule.
    let input = TransientInput {
        temperatures: &case.t0,
        sources: &case.q,
    };
    let mut save = |_: TransientState| Ok(());
    let ck = Checkpoints {
        every: CheckpointEvery {
            steps: Some(0),
            seconds: None,
        },
        save: &mut save,
    };
    let (r, _) = go(&case, Solver::Explicit, TransientStart::Initial(input), Some(ck));
    assert!(
        matches!(r, Err(ThermalError::InvalidParameter { ref field, .. }) if field == "checkpoint.steps")
    );
}
