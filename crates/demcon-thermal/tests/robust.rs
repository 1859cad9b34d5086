//! Regression tests of issue "Robustness: no panic, no hang, no silent wrong number" (the
//! thermal part): the energy balance's scale, the implicit step cap, progress reports,
//! high conductivity contrast.

use demcon_network::{FloatingPolicy, Method, Network, SolveParams, resolve_fixed};
use demcon_thermal::{
    ExplicitParams, ImplicitParams, ThermalSystem, TimeStep, TransientInput, run_explicit, run_implicit,
    solve_steady_temperature,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// An n×n×n lattice, conductances in [0.5, 2] W/K, capacities in [0.2, 3] J/K.
fn lattice(n: usize, seed: u64) -> (Network, Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let id = |i: usize, j: usize, k: usize| (i * n * n + j * n + k) as u32;
    let mut edges = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                if i + 1 < n {
                    edges.push([id(i, j, k), id(i + 1, j, k)]);
                }
                if j + 1 < n {
                    edges.push([id(i, j, k), id(i, j + 1, k)]);
                }
                if k + 1 < n {
                    edges.push([id(i, j, k), id(i, j, k + 1)]);
                }
            }
        }
    }
    let g = (0..edges.len()).map(|_| rng.random_range(0.5..2.0)).collect();
    let c = (0..n * n * n).map(|_| rng.random_range(0.2..3.0)).collect();
    (Network::new(n * n * n, &edges).unwrap(), g, c)
}

/// The faces i = 0 (at `lo`) and i = n − 1 (at `hi`).
fn faces(n: usize, lo: f64, hi: f64) -> Vec<(Vec<u32>, f64)> {
    let face = |i: usize| -> Vec<u32> { (0..n * n).map(|r| (i * n * n + r) as u32).collect() };
    vec![(face(0), lo), (face(n - 1), hi)]
}

#[test]
fn energy_balance_is_not_one_on_a_steady_run_between_two_fixed_sets() {
    let n = 12;
    let (net, g, _) = lattice(n, 1);
    let c = resolve_fixed(&net, &faces(n, 300.0, 400.0), FloatingPolicy::Fail).unwrap();
    // The balance error is Σ of the free rows' residuals over the gross flow: it follows the
    // solver's tolerance (3e-9 at the default 1e-8), so solve tightly here.
    let params = SolveParams {
        method: Method::Auto {
            rel_tol: 1e-12,
            max_iter: 20_000,
        },
    };
    let st = solve_steady_temperature(&net, &g, &c, &vec![0.0; net.n_nodes()], &params).unwrap();
    // The net flow is ~0 (what flows in at the hot face leaves at the cold one): it was the
    // scale, which made the error ~1.
    assert!(st.balance_error < 1e-9, "balance error {:e}", st.balance_error);
}

#[test]
fn energy_balance_is_not_one_on_an_adiabatic_explicit_run() {
    let n = 8;
    let (net, g, caps) = lattice(n, 2);
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
    let (net, g, caps) = lattice(n, 4);
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
