//! Checkpoints of transients on a model: a coupled ρ_e(T) transient (potential re-solved
//! during the run) and a one-way one, stopped at a checkpoint and resumed, end bit for bit as
//! the uninterrupted run — temperatures, snapshots, thermal report, potentials, Joule power
//! and electric report (wall times aside), the count of potential solves included. Steady
//! solves refuse to resume; a checkpoint of another kind of run is refused.

mod common;

use common::{C_T, lattice};
use demcon_core::{Face, Material};
use demcon_graph::InterfaceRule;
use demcon_model::*;
use demcon_network::FloatingPolicy;
use demcon_thermal::{CheckpointEvery, Scheme};

/// The lattice's metal with ρ_e(T) = ρ_e0 (1 + β (T − 20 °C)), β = 4e-3 1/K.
fn warming_metal() -> Material {
    Material {
        resistivity: Some(2.0e-7),
        resistivity_temp_coeff: 4e-3,
        resistivity_ref_temp: 20.0,
        ..Material::thermal("metal", 10.0, 8000.0, 500.0)
    }
}

/// A 2 × 2 × 8 column held at 20 °C at z = 0, heated by 0.02 V between its end faces
/// (about 1 kW: some 15 K over the 10⁶ s of the run), snapshots at 2.5·10⁵ and 5·10⁵ s.
fn problems(solver: ThermalSolver, recouple: Option<f64>) -> (ThermalProblem, ElectricProblem) {
    let thermal = ThermalProblem {
        surface: SurfaceSpec::Calibrated(CtSpec::Value(C_T)),
        interface: InterfaceRule::HarmonicMean,
        bcs: vec![ThermalBc::WallTemperature {
            face: Face::ZMin,
            value: 20.0.into(),
        }],
        sources: Vec::new(),
        solver,
        initial_temperature: 20.0,
        output_times: vec![2.5e5, 5e5],
        floating: FloatingPolicy::Fail,
        solve: default_solve_params(),
        progress: None,
    };
    let electric = ElectricProblem {
        surface: SurfaceSpec::Calibrated(CtSpec::Value(C_T)),
        interface: InterfaceRule::HarmonicMean,
        electrodes: vec![
            Electrode {
                at: ElectrodeAt::Face(Face::ZMin),
                potential: 0.0.into(),
            },
            Electrode {
                at: ElectrodeAt::Face(Face::ZMax),
                potential: 0.02.into(),
            },
        ],
        eta: 1.0,
        floating: FloatingPolicy::Fail,
        recouple_tolerance: recouple,
        current: None,
        solve: default_solve_params(),
    };
    (thermal, electric)
}

const EXPLICIT: ThermalSolver = ThermalSolver::Explicit {
    t_end: 1e6,
    dt: TimeStepSpec::Auto { safety: 0.3 },
};
const IMPLICIT: ThermalSolver = ThermalSolver::Implicit {
    t_end: 1e6,
    dt: 4.3e4,
    scheme: Scheme::CrankNicolson,
};

/// Runs the coupled problem with checkpoints every `k` steps from `resume`; returns the
/// result and the checkpoints handed out.
fn run(
    model: &Model,
    (thermal, electric): &(ThermalProblem, ElectricProblem),
    k: u64,
    resume: Option<&RunCheckpoint>,
) -> (Result<Coupled, ModelError>, Vec<RunCheckpoint>) {
    let setup = thermal_setup(model, thermal).unwrap();
    let bcs = thermal_bcs(model, &setup, thermal).unwrap();
    let mut saved = Vec::new();
    let mut sink = |c: RunCheckpoint| {
        saved.push(c);
        Ok(())
    };
    let ck = Checkpointing {
        every: CheckpointEvery {
            steps: Some(k),
            seconds: None,
        },
        resume,
        sink: &mut sink,
    };
    let r = couple_checkpointed(model, &setup, &bcs, thermal, electric, Some(ck));
    (r, saved)
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Every number but the wall times, bit for bit.
fn assert_same(a: &Coupled, b: &Coupled, what: &str) {
    let (ta, tb) = (&a.thermal, &b.thermal);
    assert_eq!(
        bits(&ta.temperatures),
        bits(&tb.temperatures),
        "{what}: temperatures"
    );
    assert_eq!(
        bits(&ta.wall_temperatures),
        bits(&tb.wall_temperatures),
        "{what}: walls"
    );
    assert_eq!(ta.snapshots, tb.snapshots, "{what}: snapshots");
    let thermal_report = |c: &Coupled| {
        let mut r = c.thermal.report.clone();
        (r.wall_s, r.contacts_per_s) = (0.0, 0.0);
        format!("{r:?}")
    };
    assert_eq!(thermal_report(a), thermal_report(b), "{what}: thermal report");
    let (ea, eb) = (&a.electric, &b.electric);
    assert_eq!(bits(&ea.potentials), bits(&eb.potentials), "{what}: potentials");
    assert_eq!(bits(&ea.joule), bits(&eb.joule), "{what}: Joule power");
    let electric_report = |c: &Coupled| {
        let mut r = c.electric.report.clone();
        (r.wall_s, r.solves_wall_s) = (0.0, 0.0);
        format!("{r:?}")
    };
    assert_eq!(electric_report(a), electric_report(b), "{what}: electric report");
}

#[test]
fn a_coupled_transient_resumed_at_any_checkpoint_equals_the_uninterrupted_run() {
    let model = lattice(2, 2, 8, vec![warming_metal()]);
    for (solver, k) in [(EXPLICIT, 3), (IMPLICIT, 2)] {
        let p = problems(solver, Some(0.5));
        let c = &p.0;
        let setup = thermal_setup(&model, c).unwrap();
        let bcs = thermal_bcs(&model, &setup, c).unwrap();
        let plain = couple(&model, &setup, &bcs, &p.0, &p.1).unwrap();
        // The potential is re-solved many times during the run.
        assert!(
            plain.electric.report.solves > 10,
            "{}",
            plain.electric.report.solves
        );
        let (full, saved) = run(&model, &p, k, None);
        assert_same(&plain, &full.unwrap(), "with checkpoints");
        assert!(saved.len() > 5);
        // The checkpoints follow the coupling: its solve count grows along the run.
        let solves: Vec<u64> = saved
            .iter()
            .map(|c| c.coupling.as_ref().unwrap().solves)
            .collect();
        assert!(solves.windows(2).all(|w| w[0] <= w[1]) && solves[0] < solves[solves.len() - 1]);
        for ck in &saved {
            let (r, _) = run(&model, &p, k, Some(ck));
            let what = format!("{solver:?} resumed at step {}", ck.transient.steps);
            assert_same(&plain, &r.unwrap(), &what);
        }
    }
}

#[test]
fn a_one_way_coupled_transient_resumes_bit_for_bit() {
    let model = lattice(2, 2, 8, vec![common::metal()]);
    let p = problems(IMPLICIT, None);
    let setup = thermal_setup(&model, &p.0).unwrap();
    let bcs = thermal_bcs(&model, &setup, &p.0).unwrap();
    let plain = couple(&model, &setup, &bcs, &p.0, &p.1).unwrap();
    let (_, saved) = run(&model, &p, 5, None);
    assert!(saved.iter().all(|c| c.coupling.is_none()));
    for ck in &saved {
        let (r, _) = run(&model, &p, 5, Some(ck));
        assert_same(&plain, &r.unwrap(), "one-way");
    }
}

#[test]
fn steady_solves_refuse_to_resume_and_checkpoints_of_another_run_are_refused() {
    let model = lattice(2, 2, 8, vec![warming_metal()]);
    let coupled = problems(IMPLICIT, Some(0.5));
    let (_, saved) = run(&model, &coupled, 5, None);
    let ck = &saved[0];
    // A steady fixed point, and a steady thermal solve, have nothing to resume.
    let steady = problems(ThermalSolver::Steady, Some(0.5));
    let err = run(&model, &steady, 5, Some(ck)).0.unwrap_err().to_string();
    assert!(
        err.contains("`solver`") && err.contains("nothing to resume"),
        "{err}"
    );
    let setup = thermal_setup(&model, &steady.0).unwrap();
    let bcs = thermal_bcs(&model, &setup, &steady.0).unwrap();
    let mut sink = |_: RunCheckpoint| Ok(());
    let ck_steady = Checkpointing {
        every: CheckpointEvery::default(),
        resume: Some(ck),
        sink: &mut sink,
    };
    let extra = ExtraSources {
        initial: None,
        update: &mut |_, _| Ok(None),
    };
    let err = solve_thermal_checkpointed(&model, &setup, &bcs, &steady.0, extra, Some(ck_steady))
        .unwrap_err()
        .to_string();
    assert!(err.contains("nothing to resume"), "{err}");
    // A coupled run's checkpoint in a one-way run, and the reverse.
    let one_way = problems(IMPLICIT, None);
    let err = run(&model, &one_way, 5, Some(ck)).0.unwrap_err().to_string();
    assert!(err.contains("checkpoint.coupling"), "{err}");
    let (_, plain_saved) = run(&model, &one_way, 5, None);
    let err = run(&model, &coupled, 5, Some(&plain_saved[0]))
        .0
        .unwrap_err()
        .to_string();
    assert!(err.contains("checkpoint.coupling"), "{err}");
    // Another solver.
    let err = run(&model, &problems(EXPLICIT, Some(0.5)), 5, Some(ck))
        .0
        .unwrap_err()
        .to_string();
    assert!(err.contains("resume state") && err.contains("scheme"), "{err}");
}

#[test]
fn a_checkpoint_sink_error_stops_the_run_with_that_error() {
    let model = lattice(2, 2, 8, vec![warming_metal()]);
    let p = problems(IMPLICIT, Some(0.5));
    let setup = thermal_setup(&model, &p.0).unwrap();
    let bcs = thermal_bcs(&model, &setup, &p.0).unwrap();
    let mut calls = 0;
    let mut sink = |_: RunCheckpoint| {
        calls += 1;
        Err(ModelError::invalid("test", "stop", "stopped on purpose"))
    };
    let ck = Checkpointing {
        every: CheckpointEvery {
            steps: Some(4),
            seconds: None,
        },
        resume: None,
        sink: &mut sink,
    };
    let err = couple_checkpointed(&model, &setup, &bcs, &p.0, &p.1, Some(ck)).unwrap_err();
    assert!(
        matches!(err, ModelError::Invalid { ref field, .. } if field == "test"),
        "{err}"
    );
    assert_eq!(calls, 1);
}
