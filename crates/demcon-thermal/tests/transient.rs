//! Integration tests of the thermal solvers on hand-built networks: exact two-node
//! exchange, energy balance, maximum principle, explicit/implicit/steady agreement,
//! stability refusal and divergence detection, determinism, bad input.

mod common;

use common::{face, lattice};
use demcon_network::{FloatingPolicy, Method, Network, SolveParams, resolve_fixed};
use demcon_thermal::{
    ExplicitParams, ImplicitParams, Scheme, ThermalError, ThermalSystem, TimeStep, TransientInput,
    paper_dt_estimate, run_explicit, run_implicit, solve_steady_temperature, source_update_fn,
    stable_dt_bound,
};

#[test]
fn two_nodes_follow_the_discrete_forward_euler_solution() {
    let net = Network::new(2, &[[0, 1]]).unwrap();
    let free = resolve_fixed(&net, &[], FloatingPolicy::Keep).unwrap();
    let params = ExplicitParams {
        t_end: 1.0,
        dt: TimeStep::Fixed {
            dt: 0.1,
            allow_unstable: false,
        },
        ..Default::default()
    };
    let run = run_explicit(
        &ThermalSystem::new(&net, &[1.0], &[1.0, 1.0], &free).unwrap(),
        TransientInput {
            temperatures: &[0.0, 1.0],
            sources: &[0.0; 2],
        },
        &params,
        |_, _| {},
        (),
    )
    .unwrap();
    // ΔT_n = (1 − 2Δt)^n, mean conserved.
    let diff = run.temperatures[1] - run.temperatures[0];
    assert!((diff - 0.8f64.powi(10)).abs() < 1e-12, "{diff}");
    assert!((run.temperatures[0] + run.temperatures[1] - 1.0).abs() < 1e-14);
    assert_eq!(run.report.steps, 10);
    assert_eq!(run.report.dt_bound, 1.0);
}

#[test]
fn explicit_conserves_energy_and_obeys_the_maximum_principle() {
    let n = 8;
    let (net, g, c) = lattice(n, 2, true);
    let bcs = resolve_fixed(
        &net,
        &[(face(n, 0), 300.0), (face(n, n - 1), 350.0)],
        FloatingPolicy::Fail,
    )
    .unwrap();
    let system = ThermalSystem::new(&net, &g, &c, &bcs).unwrap();
    let t0 = vec![300.0; net.n_nodes()];
    let params = ExplicitParams {
        t_end: 5.0,
        output_times: vec![0.0, 0.37, 2.0],
        ..Default::default()
    };
    let mut seen = Vec::new();
    let run = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &vec![0.0; net.n_nodes()],
        },
        &params,
        |t, temps| {
            seen.push(t);
            // Maximum principle: every value within [300, 350] K.
            assert!(temps.iter().all(|&v| (300.0 - 1e-9..=350.0 + 1e-9).contains(&v)));
        },
        (),
    )
    .unwrap();
    assert_eq!(seen, vec![0.0, 0.37, 2.0]);
    let r = &run.report;
    assert!(
        r.energy_boundary_j > 0.0 && r.energy_balance_error < 1e-10,
        "{r:?}"
    );
    assert!(r.dt <= 0.8 * r.dt_bound * (1.0 + 1e-15));
    assert!(r.t_range[0] >= 300.0 && r.t_range[1] <= 350.0);
    // With sources: Σ C ΔT = ∫ Q + boundary inflow.
    let q: Vec<f64> = (0..net.n_nodes()).map(|p| ((p % 3) as f64 - 0.5) * 2.0).collect();
    let run = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &q,
        },
        &params,
        |_, _| {},
        (),
    )
    .unwrap();
    assert!(run.report.energy_sources_j.abs() > 1.0);
    assert!(run.report.energy_balance_error < 1e-10, "{:?}", run.report);
}

#[test]
fn explicit_implicit_and_steady_agree() {
    let n = 6;
    let (net, g, c) = lattice(n, 4, true);
    let bcs = resolve_fixed(
        &net,
        &[(face(n, 0), 0.0), (face(n, n - 1), 1.0)],
        FloatingPolicy::Fail,
    )
    .unwrap();
    let system = ThermalSystem::new(&net, &g, &c, &bcs).unwrap();
    let q = vec![0.05; net.n_nodes()];
    let t0 = vec![0.0; net.n_nodes()];
    let t_mid = 3.0;
    let ex = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &q,
        },
        &ExplicitParams {
            t_end: t_mid,
            dt: TimeStep::Auto { safety: 0.1 },
            ..Default::default()
        },
        |_, _| {},
        (),
    )
    .unwrap();
    let implicit = |scheme, dt, method, t_end| {
        run_implicit(
            &system,
            TransientInput {
                temperatures: &t0,
                sources: &q,
            },
            &ImplicitParams {
                t_end,
                dt,
                scheme,
                output_times: vec![],
                solve: method,
                ..Default::default()
            },
            |_, _| {},
            (),
        )
        .unwrap()
    };
    let cg = SolveParams::new(Method::Cg, 1e-12, 1000);
    let cn = implicit(Scheme::CrankNicolson, ex.report.dt_bound, cg, t_mid);
    let be = implicit(
        Scheme::BackwardEuler,
        ex.report.dt_bound * 0.1,
        SolveParams::new(Method::Cholesky, 1e-12, 1),
        t_mid,
    );
    let max_diff = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    let range = ex.report.t_range[1] - ex.report.t_range[0];
    assert!(max_diff(&ex.temperatures, &cn.temperatures) < 2e-3 * range);
    assert!(max_diff(&ex.temperatures, &be.temperatures) < 5e-3 * range);
    assert!(cn.report.energy_balance_error < 1e-8 && be.report.energy_balance_error < 1e-8);
    assert!(cn.report.solver_iterations > 0 && cn.report.max_relative_residual <= 1e-12);
    // Long implicit run with big steps reaches the steady state.
    let steady = solve_steady_temperature(&net, &g, &bcs, &q, &SolveParams::default()).unwrap();
    assert!(steady.balance_error < 1e-7, "{}", steady.balance_error);
    let late = implicit(Scheme::BackwardEuler, 50.0, cg, 5000.0);
    assert!(max_diff(&late.temperatures, &steady.solution.values) < 1e-7);
}

#[test]
fn a_step_above_the_bound_is_refused_and_divergence_is_detected() {
    // Chain of 12 nodes, C = 1 J/K, H = 1 W/K, ends fixed: bound = 0.5 s, 2/λ_max > 0.5 s.
    let m = 12;
    let edges: Vec<[u32; 2]> = (0..m - 1).map(|i| [i as u32, i as u32 + 1]).collect();
    let net = Network::new(m, &edges).unwrap();
    let g = vec![1.0; m - 1];
    let c = vec![1.0; m];
    let bcs = resolve_fixed(
        &net,
        &[(vec![0], 0.0), (vec![m as u32 - 1], 1.0)],
        FloatingPolicy::Fail,
    )
    .unwrap();
    let system = ThermalSystem::new(&net, &g, &c, &bcs).unwrap();
    let b = stable_dt_bound(&net, &g, &c, &bcs).unwrap();
    assert_eq!(b.dt_max, 0.5);
    let t0: Vec<f64> = (0..m).map(|i| if i % 2 == 0 { 0.2 } else { 0.8 }).collect();
    let fixed = |dt, allow_unstable| ExplicitParams {
        t_end: 100.0,
        dt: TimeStep::Fixed { dt, allow_unstable },
        paper_dt: Some(paper_dt_estimate(1.0, 1.0, 2.0, 1.0)),
        ..Default::default()
    };
    let run = |p: &ExplicitParams| {
        run_explicit(
            &system,
            TransientInput {
                temperatures: &t0,
                sources: &vec![0.0; m],
            },
            p,
            |_, _| {},
            (),
        )
    };
    match run(&fixed(0.75, false)) {
        Err(ThermalError::Unstable { dt, dt_max, .. }) => assert_eq!((dt, dt_max), (0.75, 0.5)),
        other => panic!("expected Unstable, got {other:?}"),
    }
    // 0.75 s > 2/λ_max (λ_max → 4): the oscillating mode grows and is caught early.
    match run(&fixed(0.75, true)) {
        Err(ThermalError::Diverged {
            step, value, lo, hi, ..
        }) => {
            assert!(step < 200, "caught late: step {step}");
            assert!(!(lo..=hi).contains(&value));
        }
        other => panic!("expected Diverged, got {other:?}"),
    }
    // At the bound it is fine, and the paper estimate is reported.
    let ok = run(&ExplicitParams {
        t_end: 1000.0,
        ..fixed(0.5, false)
    })
    .unwrap();
    assert_eq!(ok.report.paper_dt, Some(1.0 / 3.0));
    assert!((ok.temperatures[6] - 6.0 / 11.0).abs() < 1e-9);
}

#[test]
fn explicit_does_not_depend_on_thread_count() {
    let n = 34; // 39 304 nodes: ten chunks, more than one parallel task.
    let (net, g, c) = lattice(n, 9, true);
    let bcs = resolve_fixed(&net, &[(face(n, 0), 1.0)], FloatingPolicy::Fail).unwrap();
    let system = ThermalSystem::new(&net, &g, &c, &bcs).unwrap();
    let params = ExplicitParams {
        t_end: 0.3,
        ..Default::default()
    };
    let go = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                run_explicit(
                    &system,
                    TransientInput {
                        temperatures: &vec![0.0; net.n_nodes()],
                        sources: &vec![0.01; net.n_nodes()],
                    },
                    &params,
                    |_, _| {},
                    (),
                )
                .unwrap()
            })
    };
    assert_eq!(go(1).temperatures, go(2).temperatures);
}

#[test]
fn floating_clusters_evolve_alone_when_kept() {
    // 0-1 fixed chain end; 2 isolated with a source; 3-4 floating pair.
    let net = Network::new(5, &[[0, 1], [3, 4]]).unwrap();
    let bcs = resolve_fixed(&net, &[(vec![0], 10.0)], FloatingPolicy::Keep).unwrap();
    let q = [0.0, 0.0, 2.0, 0.0, 0.0];
    let t0 = [0.0, 0.0, 0.0, 0.0, 4.0];
    let c = [1.0, 1.0, 4.0, 1.0, 1.0];
    let g = [1.0, 1.0];
    let system = ThermalSystem::new(&net, &g, &c, &bcs).unwrap();
    let ex = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &q,
        },
        &ExplicitParams {
            t_end: 40.0,
            ..Default::default()
        },
        |_, _| {},
        (),
    )
    .unwrap();
    let im = run_implicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &q,
        },
        &ImplicitParams {
            t_end: 40.0,
            dt: 0.5,
            ..Default::default()
        },
        |_, _| {},
        (),
    )
    .unwrap();
    for t in [&ex.temperatures, &im.temperatures] {
        assert!((t[2] - 20.0).abs() < 1e-9, "isolated node heats at Q/C: {}", t[2]);
        assert!((t[3] - 2.0).abs() < 1e-6 && (t[4] - 2.0).abs() < 1e-6);
        assert!((t[1] - 10.0).abs() < 1e-6);
    }
    // A steady solve refuses them.
    assert!(matches!(
        solve_steady_temperature(&net, &g, &bcs, &q, &SolveParams::default()),
        Err(ThermalError::Network(
            demcon_network::SolveError::FloatingCluster { .. }
        ))
    ));
}

#[test]
fn bad_input_is_named() {
    let net = Network::new(2, &[[0, 1]]).unwrap();
    let free = resolve_fixed(&net, &[], FloatingPolicy::Keep).unwrap();
    // A bad part of the system is refused when the system is built, before any run.
    let go = |t0: &[f64], c: &[f64], p: &ExplicitParams| {
        ThermalSystem::new(&net, &[1.0], c, &free).and_then(|system| {
            let input = TransientInput {
                temperatures: t0,
                sources: &[0.0; 2],
            };
            run_explicit(&system, input, p, |_, _| {}, ())
        })
    };
    let d = ExplicitParams::default();
    assert!(matches!(go(&[0.0, f64::NAN], &[1.0; 2], &d),
        Err(ThermalError::InvalidParameter { ref field, .. }) if field == "initial temperatures[1]"));
    assert!(matches!(go(&[0.0; 2], &[1.0, 0.0], &d),
        Err(ThermalError::InvalidParameter { ref field, .. }) if field == "capacities[1]"));
    let p = ExplicitParams {
        output_times: vec![0.5, 0.2],
        ..Default::default()
    };
    assert!(matches!(go(&[0.0; 2], &[1.0; 2], &p),
        Err(ThermalError::InvalidParameter { ref field, .. }) if field == "output_times[1]"));
    let p = ExplicitParams {
        t_end: -1.0,
        ..Default::default()
    };
    assert!(matches!(
        go(&[0.0; 2], &[1.0; 2], &p),
        Err(ThermalError::InvalidParameter { .. })
    ));
    let p = ExplicitParams {
        dt: TimeStep::Fixed {
            dt: 1e-9,
            allow_unstable: false,
        },
        t_end: 1.0,
        max_steps: 1000,
        ..Default::default()
    };
    assert!(matches!(go(&[0.0; 2], &[1.0; 2], &p),
        Err(ThermalError::InvalidParameter { ref field, .. }) if field == "dt"));
}

/// Sources updated during a run (the `SourceUpdate` of `run_explicit` / `run_implicit`):
/// a lattice heated by Q_p = q_p / (1 + T_p) (a resistance rising with temperature), the
/// hook re-evaluating Q every step. The explicit run equals a hand-written loop over the
/// stepper with `set_sources`; both ledgers close; a hook error stops the run.
#[test]
fn sources_updated_during_a_run_follow_the_hook_and_keep_the_ledger() {
    use demcon_thermal::ExplicitStepper;
    let n = 5;
    let (net, g, c) = lattice(n, 11, true);
    let m = n * n * n;
    let bcs = resolve_fixed(&net, &[(face(n, 0), 0.0)], FloatingPolicy::Fail).unwrap();
    let system = ThermalSystem::new(&net, &g, &c, &bcs).unwrap();
    let q0: Vec<f64> = (0..m).map(|p| 0.5 + (p % 7) as f64 * 0.1).collect();
    let src = |t: &[f64]| -> Vec<f64> { q0.iter().zip(t).map(|(q, t)| q / (1.0 + t.abs())).collect() };
    let t0 = vec![0.0; m];
    let dt = 0.5 * stable_dt_bound(&net, &g, &c, &bcs).unwrap().dt_max;
    let steps = 40;
    let params = ExplicitParams {
        t_end: steps as f64 * dt,
        dt: TimeStep::Fixed {
            dt,
            allow_unstable: false,
        },
        ..Default::default()
    };
    let mut calls = 0;
    let run = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &src(&t0),
        },
        &params,
        |_, _| {},
        source_update_fn(|_, t| {
            calls += 1;
            Ok::<_, ThermalError>(Some(src(t)))
        }),
    )
    .unwrap();
    assert_eq!(calls, steps);
    // The same by hand.
    let mut st = ExplicitStepper::new(&system, &src(&t0), dt).unwrap();
    let (mut cur, mut next) = (t0.clone(), t0.clone());
    for _ in 0..steps {
        st.step(&cur, &mut next);
        std::mem::swap(&mut cur, &mut next);
        st.set_sources(&src(&cur)).unwrap();
    }
    for (a, b) in run.temperatures.iter().zip(&cur) {
        assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{a} vs {b}");
    }
    // The sources did change (otherwise the test proves nothing) and the ledger closes.
    let first: f64 = src(&t0).iter().sum();
    let last: f64 = src(&cur).iter().sum();
    assert!(last < 0.99 * first, "{last} vs {first}");
    assert!(
        run.report.energy_balance_error < 1e-10,
        "{}",
        run.report.energy_balance_error
    );
    // Implicit: the ledger closes too, for both schemes.
    for scheme in [Scheme::BackwardEuler, Scheme::CrankNicolson] {
        let p = ImplicitParams {
            t_end: 40.0 * dt,
            dt: 4.0 * dt,
            scheme,
            solve: SolveParams::new(Method::Cg, 1e-13, 10_000),
            ..Default::default()
        };
        let mut calls = 0;
        let im = run_implicit(
            &system,
            TransientInput {
                temperatures: &t0,
                sources: &src(&t0),
            },
            &p,
            |_, _| {},
            source_update_fn(|_, t| {
                calls += 1;
                Ok::<_, ThermalError>(Some(src(t)))
            }),
        )
        .unwrap();
        assert_eq!(calls, 10);
        assert!(
            im.report.energy_balance_error < 1e-9,
            "{scheme:?}: {}",
            im.report.energy_balance_error
        );
    }
    // Bad sources from the hook and a hook error are reported, not panics.
    let bad = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &q0,
        },
        &params,
        |_, _| {},
        source_update_fn(|_, _| Ok::<_, ThermalError>(Some(vec![f64::NAN; m]))),
    );
    assert!(
        matches!(bad, Err(ThermalError::InvalidParameter { .. })),
        "{bad:?}"
    );
    let short = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &q0,
        },
        &params,
        |_, _| {},
        source_update_fn(|_, _| Ok::<_, ThermalError>(Some(vec![0.0; 3]))),
    );
    assert!(
        matches!(short, Err(ThermalError::InvalidParameter { .. })),
        "{short:?}"
    );
    let stop = run_explicit(
        &system,
        TransientInput {
            temperatures: &t0,
            sources: &q0,
        },
        &params,
        |_, _| {},
        source_update_fn(|t, _| Err(ThermalError::invalid("hook", t, "stopped"))),
    );
    assert!(matches!(stop, Err(ThermalError::InvalidParameter { ref field, .. }) if field == "hook"));
}

/// Brings a block's ghost temperature from its neighbour block after every step (the
/// `SourceUpdate::exchange` of `demcon run --distributed` by blocks, here over a channel).
struct Neighbour {
    /// Local node whose value the other block needs, and the local ghost node it fills.
    send: usize,
    ghost: usize,
    tx: std::sync::mpsc::Sender<f64>,
    rx: std::sync::mpsc::Receiver<f64>,
}

impl demcon_thermal::SourceUpdate for Neighbour {
    type Error = ThermalError;

    fn update(&mut self, _t: f64, _temps: &[f64]) -> Result<Option<Vec<f64>>, ThermalError> {
        Ok(None)
    }

    fn exchange(&mut self, temps: &mut [f64]) -> Result<(), ThermalError> {
        self.tx.send(temps[self.send]).unwrap();
        temps[self.ghost] = self.rx.recv().unwrap();
        Ok(())
    }
}

#[test]
fn two_blocks_exchanging_their_ghosts_every_step_march_as_the_whole_chain() {
    // A chain of 12 nodes, blocks 0..6 and 6..12, each with one ghost across the cut.
    let n = 12;
    let k = 6;
    let chain =
        |m: usize| Network::new(m, &(0..m as u32 - 1).map(|i| [i, i + 1]).collect::<Vec<_>>()).unwrap();
    // Each block's initial range is the whole chain's: the march's maximum-principle envelope
    // is each process's own (its initial and fixed values).
    let t0: Vec<f64> = (0..n).map(|i| [20.0, 45.0, 31.5, 27.25][i % 4]).collect();
    let params = ExplicitParams {
        t_end: 3.0,
        dt: TimeStep::Fixed {
            dt: 0.4,
            allow_unstable: false,
        },
        ..Default::default()
    };
    let march = |net: &Network, t: &[f64], update: Option<Neighbour>| {
        let m = net.n_nodes();
        let free = resolve_fixed(net, &[], FloatingPolicy::Keep).unwrap();
        let g = vec![1.0; m - 1];
        let c = vec![1.0; m];
        let system = ThermalSystem::new(net, &g, &c, &free).unwrap();
        let input = TransientInput {
            temperatures: t,
            sources: &vec![0.0; m],
        };
        match update {
            Some(u) => run_explicit(&system, input, &params, |_, _| {}, u),
            None => run_explicit(&system, input, &params, |_, _| {}, ()),
        }
        .unwrap()
        .temperatures
    };
    let whole = march(&chain(n), &t0, None);
    let (a_tx, b_rx) = std::sync::mpsc::channel();
    let (b_tx, a_rx) = std::sync::mpsc::channel();
    // Block A: global 0..=k (k its ghost); block B: global k-1..n (local 0 its ghost).
    let a = Neighbour {
        send: k - 1,
        ghost: k,
        tx: a_tx,
        rx: a_rx,
    };
    let b = Neighbour {
        send: 1,
        ghost: 0,
        tx: b_tx,
        rx: b_rx,
    };
    let (ta, tb) = (t0[..=k].to_vec(), t0[k - 1..].to_vec());
    let (left, right) = std::thread::scope(|s| {
        let left = s.spawn(|| march(&chain(k + 1), &ta, Some(a)));
        let right = s.spawn(|| march(&chain(n - k + 1), &tb, Some(b)));
        (left.join().unwrap(), right.join().unwrap())
    });
    let joined: Vec<f64> = left[..k].iter().chain(&right[1..]).copied().collect();
    assert_eq!(
        joined, whole,
        "the owned nodes of the two blocks are the whole chain's, bit for bit"
    );
    // The march moved them (otherwise the test proves nothing).
    assert!((whole[0] - t0[0]).abs() > 1.0);
}
