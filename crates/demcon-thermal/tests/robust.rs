//! Regression tests of issue "Robustness: no panic, no hang, no silent wrong number" (the
//! thermal part): the energy balance's scale, the implicit step cap, progress reports,
//! high conductivity contrast.

mod common;

use common::{face, lattice};
use demcon_network::{FloatingPolicy, Method, SolveParams, resolve_fixed};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::{Arc, Mutex};

use demcon_thermal::{
    DEFAULT_MAX_STEPS, ExplicitParams, ImplicitParams, ProgressFn, ThermalSystem, TimeStep, TransientInput,
    run_explicit, run_implicit, solve_steady_temperature,
};

/// The faces i = 0 (at `lo`) and i = n − 1 (at `hi`).
fn faces(n: usize, lo: f64, hi: f64) -> Vec<(Vec<u32>, f64)> {
    vec![(face(n, 0), lo), (face(n, n - 1), hi)]
}

#[test]
fn energy_balance_is_not_one_on_a_steady_run_between_two_fixed_sets() {
    let n = 12;
    let (net, g, _) = lattice(n, 1, false);
    let c = resolve_fixed(&net, &faces(n, 300.0, 400.0), FloatingPolicy::Fail).unwrap();
    // The balance error is Σ of the free rows' residuals over the gross flow: it follows the
    // solver's tolerance (3e-9 at the default 1e-8), so solve tightly here.
    let params = SolveParams::new(Method::Auto, 1e-12, 20_000);
    let st = solve_steady_temperature(&net, &g, &c, &vec![0.0; net.n_nodes()], &params).unwrap();
    // The net flow is ~0 (what flows in at the hot face leaves at the cold one): it was the
    // scale, which made the error ~1.
    assert!(st.balance_error < 1e-9, "balance error {:e}", st.balance_error);
}

#[test]
fn energy_balance_is_not_one_on_an_adiabatic_explicit_run() {
    let n = 8;
    let (net, g, caps) = lattice(n, 2, false);
    let c = resolve_fixed(&net, &[], FloatingPolicy::Keep).unwrap();
    let system = ThermalSystem::new(&net, &g, &caps, &c).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let t0: Vec<f64> = (0..net.n_nodes())
        .map(|_| rng.random_range(250.0..350.0))
        .collect();
    let run = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &vec![0.0; net.n_nodes()],
        },
        &ExplicitParams {
            t_end: 0.5,
            ..Default::default()
        },
        |_, _| {},
        (),
    )
    .unwrap();
    let r = &run.report;
    assert!(r.steps > 10);
    assert!(
        r.energy_balance_error < 1e-9,
        "balance error {:e}",
        r.energy_balance_error
    );
}

#[test]
fn energy_balance_is_not_one_on_an_implicit_run_between_two_fixed_sets() {
    let n = 8;
    let (net, g, caps) = lattice(n, 4, false);
    let c = resolve_fixed(&net, &faces(n, 300.0, 400.0), FloatingPolicy::Fail).unwrap();
    let system = ThermalSystem::new(&net, &g, &caps, &c).unwrap();
    let t0 = vec![350.0; net.n_nodes()];
    let run = run_implicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &vec![0.0; net.n_nodes()],
        },
        &ImplicitParams {
            t_end: 5.0,
            dt: 0.1,
            ..Default::default()
        },
        |_, _| {},
        (),
    )
    .unwrap();
    assert!(
        run.report.energy_balance_error < 1e-7,
        "balance error {:e}",
        run.report.energy_balance_error
    );
}

#[test]
fn implicit_solver_has_no_step_cap_t_end_1e12_with_dt_1_is_refused_before_the_first_step() {
    let n = 4;
    let (net, g, caps) = lattice(n, 5, false);
    let c = resolve_fixed(&net, &faces(n, 300.0, 400.0), FloatingPolicy::Fail).unwrap();
    let system = ThermalSystem::new(&net, &g, &caps, &c).unwrap();
    let t0 = vec![350.0; net.n_nodes()];
    let q = vec![0.0; net.n_nodes()];
    let input = || TransientInput {
        temperatures: &t0,
        sources: &q,
    };
    let started = std::time::Instant::now();
    let e = run_implicit(
        &system,
        input(),
        &ImplicitParams {
            t_end: 1e12,
            dt: 1.0,
            ..Default::default()
        },
        |_, _| panic!("no output expected"),
        (),
    )
    .unwrap_err();
    assert!(started.elapsed().as_secs_f64() < 1.0);
    let msg = e.to_string();
    assert!(
        msg.contains("max_steps = 100000000") && msg.contains("1e0"),
        "{msg}"
    );
    assert_eq!(ImplicitParams::default().max_steps, DEFAULT_MAX_STEPS);
    assert_eq!(ExplicitParams::default().max_steps, DEFAULT_MAX_STEPS);
    // The explicit solver says the same for the same step count.
    let e = run_explicit(
        &system,
        input(),
        &ExplicitParams {
            t_end: 1e12,
            dt: TimeStep::Fixed {
                dt: 1e-3,
                allow_unstable: false,
            },
            ..Default::default()
        },
        |_, _| {},
        (),
    )
    .unwrap_err();
    assert!(e.to_string().contains("more than max_steps = 100000000"), "{e}");
    // A smaller cap applies to the implicit solver too.
    let e = run_implicit(
        &system,
        input(),
        &ImplicitParams {
            t_end: 10.0,
            dt: 1.0,
            max_steps: 5,
            ..Default::default()
        },
        |_, _| {},
        (),
    )
    .unwrap_err();
    assert!(e.to_string().contains("max_steps = 5"), "{e}");
}

#[test]
fn implicit_solver_has_no_step_cap_progress_is_reported_at_most_100_times() {
    let n = 4;
    let (net, g, caps) = lattice(n, 6, false);
    let c = resolve_fixed(&net, &faces(n, 300.0, 400.0), FloatingPolicy::Fail).unwrap();
    let system = ThermalSystem::new(&net, &g, &caps, &c).unwrap();
    let t0 = vec![350.0; net.n_nodes()];
    let q = vec![0.0; net.n_nodes()];
    let calls = Arc::new(Mutex::new(Vec::new()));
    let sink = calls.clone();
    let progress = Some(ProgressFn::new(move |done, total| {
        sink.lock().unwrap().push((done, total))
    }));
    let run = run_implicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &q,
        },
        &ImplicitParams {
            t_end: 1.0,
            dt: 1e-3,
            output_times: vec![0.25, 0.5],
            progress: progress.clone(),
            ..Default::default()
        },
        |_, _| {},
        (),
    )
    .unwrap();
    let seen = std::mem::take(&mut *calls.lock().unwrap());
    assert!(seen.len() <= 101 && seen.len() >= 50, "{} calls", seen.len());
    assert_eq!(*seen.last().unwrap(), (run.report.steps, run.report.steps));
    assert!(seen.windows(2).all(|w| w[0].0 < w[1].0));
    let run = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &q,
        },
        &ExplicitParams {
            t_end: 20.0,
            output_times: vec![3.0],
            progress,
            ..Default::default()
        },
        |_, _| {},
        (),
    )
    .unwrap();
    let seen = calls.lock().unwrap();
    assert!(run.report.steps > 200, "{}", run.report.steps);
    assert!(seen.len() <= 101, "{} calls", seen.len());
    assert_eq!(*seen.last().unwrap(), (run.report.steps, run.report.steps));
}

#[test]
fn contrast_cliff_implicit_steps_converge_at_contrast_1e6_and_1e_minus_6() {
    let n = 14;
    for ratio in [1e6, 1e-6] {
        let (net, g, sets) = demcon_network::fixtures::inclusion_lattice(n, ratio);
        let c = resolve_fixed(&net, &sets, FloatingPolicy::Fail).unwrap();
        let caps = vec![1.0; net.n_nodes()];
        let system = ThermalSystem::new(&net, &g, &caps, &c).unwrap();
        let t0 = vec![0.5; net.n_nodes()];
        let q = vec![0.0; net.n_nodes()];
        for method in [
            SolveParams::new(Method::Auto, 1e-10, 200_000),
            SolveParams::new(Method::Cg, 1e-10, 200_000),
            SolveParams::new(Method::AmgCg, 1e-10, 200_000),
        ] {
            let run = run_implicit(
                &system,
                TransientInput {
                    temperatures: &t0,
                    sources: &q,
                },
                &ImplicitParams {
                    t_end: 10.0,
                    dt: 1.0,
                    solve: method,
                    ..Default::default()
                },
                |_, _| {},
                (),
            )
            .unwrap_or_else(|e| panic!("contrast {ratio:e}, {method:?}: {e}"));
            let r = &run.report;
            assert!(
                r.solver_iterations < 20_000,
                "{method:?}: {} iterations",
                r.solver_iterations
            );
            assert!(
                r.t_range[0] >= -1e-9 && r.t_range[1] <= 1.0 + 1e-9,
                "{:?}",
                r.t_range
            );
        }
    }
}
