//! Integration tests of the multigrid-preconditioned CG (`Method::AmgCg`): agreement with
//! sparse Cholesky on random packing-like networks (steady, shifted, high contrast, excluded
//! and kept floating clusters), reuse of one hierarchy across solves, independence of the
//! thread count, and its iteration count against Jacobi-PCG.

use demcon_network::{
    FloatingPolicy, LinearSystem, Method, Network, SolveError, SolveParams, resolve_fixed, solve_shifted,
    solve_steady,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod common;
use common::{faces, geometric_with};

/// The shared random geometric graph with conductance 1/distance × a random factor in
/// [0.5, 2].
fn geometric(n: usize, seed: u64) -> (Network, Vec<f64>, Vec<f64>) {
    geometric_with(n, seed, |rng, d| rng.random_range(0.5..2.0) / d.max(0.1))
}

fn amg(rel_tol: f64) -> SolveParams {
    SolveParams::new(Method::AmgCg, rel_tol, 500)
}

const CHOLESKY: SolveParams = SolveParams::new(Method::Cholesky, 1e-8, 1);

fn max_diff(u: &[f64], v: &[f64]) -> f64 {
    u.iter().zip(v).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn agrees_with_cholesky_on_random_networks_with_sources() {
    for seed in [1, 2] {
        let (net, g, x) = geometric(3000, seed);
        let bcs = resolve_fixed(&net, &faces(&x, 0.0, 1.0), FloatingPolicy::Exclude).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed + 10);
        let s: Vec<f64> = (0..net.n_nodes()).map(|_| rng.random_range(-0.2..0.2)).collect();
        let a = solve_steady(&net, &g, &bcs, &s, &amg(1e-10)).unwrap();
        let b = solve_steady(&net, &g, &bcs, &s, &CHOLESKY).unwrap();
        assert_eq!(a.report.method, "amg-pcg");
        assert!(a.report.relative_residual <= 1e-10);
        assert!(
            a.report.iterations >= 2 && a.report.iterations < 40,
            "{:?}",
            a.report
        );
        assert!(a.report.setup_s > 0.0);
        assert!(
            max_diff(&a.values, &b.values) < 1e-8,
            "{}",
            max_diff(&a.values, &b.values)
        );
        assert_eq!(a.excluded, b.excluded);
        // The hierarchy really has coarse levels at this size.
        let sys = LinearSystem::new(&net, &g, None, &bcs, &amg(1e-10)).unwrap();
        let info = sys.amg_info().unwrap();
        assert!(info.levels.len() >= 2, "{info:?}");
        // Unshifted systems are solved once or a few times: the hierarchy with the cheaper
        // setup.
        assert_eq!(info.cycle, "plain aggregation, K-cycle");
        assert_eq!(info.levels[0].rows, bcs.n_free());
        assert!(
            info.operator_complexity > 1.0 && info.operator_complexity < 2.0,
            "{info:?}"
        );
    }
}

#[test]
fn high_contrast_phases_converge_to_the_direct_solution() {
    // Conductances spanning five decades (inclusions 1000× the matrix, interfaces between).
    let (net, mut g, x) = geometric(2500, 3);
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let phase: Vec<bool> = (0..net.n_nodes()).map(|_| rng.random::<f64>() < 0.3).collect();
    for (gi, &[p, q]) in g.iter_mut().zip(net.edges()) {
        *gi *= match (phase[p as usize], phase[q as usize]) {
            (true, true) => 1000.0,
            (false, false) => 1.0,
            _ => 2.0 * 1000.0 / 1001.0,
        } * if rng.random::<f64>() < 0.05 { 1e-2 } else { 1.0 };
    }
    let bcs = resolve_fixed(&net, &faces(&x, 1.0, 0.0), FloatingPolicy::Exclude).unwrap();
    let s = vec![0.0; net.n_nodes()];
    let a = solve_steady(&net, &g, &bcs, &s, &amg(1e-11)).unwrap();
    let b = solve_steady(&net, &g, &bcs, &s, &CHOLESKY).unwrap();
    assert!(max_diff(&a.values, &b.values) < 1e-8);
    assert!(a.report.iterations < 80, "{:?}", a.report);
}

#[test]
fn shifted_systems_reuse_one_hierarchy_and_match_cholesky() {
    let (net, g, x) = geometric(2500, 5);
    // Floating clusters kept: the shift anchors them (an implicit step).
    let bcs = resolve_fixed(&net, &faces(&x, 0.0, 1.0), FloatingPolicy::Keep).unwrap();
    let d: Vec<f64> = (0..net.n_nodes()).map(|p| 0.05 + 0.1 * (p % 5) as f64).collect();
    let sys = LinearSystem::new(&net, &g, Some(&d), &bcs, &amg(1e-11)).unwrap();
    // Shifted systems are solved many times: the hierarchy with the cheaper cycle.
    assert_eq!(sys.amg_info().unwrap().cycle, "smoothed aggregation, V(1,1)");
    let direct = LinearSystem::new(&net, &g, Some(&d), &bcs, &CHOLESKY).unwrap();
    let mut prev: Option<Vec<f64>> = None;
    for k in 0..3 {
        let rhs: Vec<f64> = (0..net.n_nodes()).map(|p| ((p + k) % 7) as f64 * 0.1).collect();
        let a = sys.solve(&rhs, prev.as_deref()).unwrap();
        let b = direct.solve(&rhs, None).unwrap();
        assert!(max_diff(&a.values, &b.values) < 1e-8);
        // Setup is paid once and reported with every solve.
        assert_eq!(a.report.setup_s, sys.setup_s());
        prev = Some(a.values);
    }
    // The same through solve_shifted.
    let rhs = vec![1.0; net.n_nodes()];
    let a = solve_shifted(&net, &g, &d, &rhs, &bcs, None, &amg(1e-11)).unwrap();
    let b = direct.solve(&rhs, None).unwrap();
    assert!(max_diff(&a.values, &b.values) < 1e-8);
}

#[test]
fn excluded_floating_nodes_and_tiny_systems() {
    // Chain 0-1-2 anchored, 3-4 floating, 5 isolated: excluded, and below the coarse size
    // the hierarchy is one dense factor (one iteration).
    let net = Network::new(6, &[[0, 1], [1, 2], [3, 4]]).unwrap();
    let bcs = resolve_fixed(&net, &[(vec![0], 0.0), (vec![2], 2.0)], FloatingPolicy::Exclude).unwrap();
    let sol = solve_steady(&net, &[1.0, 3.0, 1.0], &bcs, &[0.0; 6], &amg(1e-12)).unwrap();
    assert!((sol.values[1] - 1.5).abs() < 1e-12);
    assert_eq!(sol.excluded, vec![3, 4, 5]);
    assert_eq!(sol.report.iterations, 1);
    // All nodes fixed: nothing to solve.
    let all = resolve_fixed(&net, &[(vec![0, 1, 2, 3, 4, 5], 1.0)], FloatingPolicy::Fail).unwrap();
    let sol = solve_steady(&net, &[1.0; 3], &all, &[0.0; 6], &amg(1e-12)).unwrap();
    assert_eq!(sol.values, vec![1.0; 6]);
    // Kept floating clusters without a shift are refused, as for every method.
    let kept = resolve_fixed(&net, &[(vec![0], 0.0)], FloatingPolicy::Keep).unwrap();
    assert!(matches!(
        solve_steady(&net, &[1.0; 3], &kept, &[0.0; 6], &amg(1e-8)),
        Err(SolveError::FloatingCluster { .. })
    ));
}

#[test]
fn results_do_not_depend_on_thread_count() {
    // 34³ = 39 304 nodes: several chunks per level and more than one parallel task.
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let side = 34usize;
    let id = |i: usize, j: usize, k: usize| (i * side * side + j * side + k) as u32;
    let mut edges = Vec::new();
    for i in 0..side {
        for j in 0..side {
            for k in 0..side {
                for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0)] {
                    if i + di < side
                        && j + dj < side
                        && k + dk < side
                        && (di + dj + dk == 1 || rng.random::<f64>() < 0.4)
                    {
                        edges.push([id(i, j, k), id(i + di, j + dj, k + dk)]);
                    }
                }
            }
        }
    }
    let nodes = side * side * side;
    let g: Vec<f64> = (0..edges.len()).map(|_| rng.random_range(0.1..10.0)).collect();
    let net = Network::new(nodes, &edges).unwrap();
    let face = |i: usize| -> Vec<u32> { (0..side * side).map(|r| (i * side * side + r) as u32).collect() };
    let bcs = resolve_fixed(
        &net,
        &[(face(0), 0.0), (face(side - 1), 1.0)],
        FloatingPolicy::Fail,
    )
    .unwrap();
    let s: Vec<f64> = (0..nodes).map(|p| ((p * 31) % 17) as f64 * 1e-3).collect();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| solve_steady(&net, &g, &bcs, &s, &amg(1e-9)).unwrap())
    };
    let one = run(1);
    let three = run(3);
    assert_eq!(one.values, three.values);
    assert_eq!(one.report.iterations, three.report.iterations);
    // Far fewer iterations than Jacobi-PCG on the same system.
    let jacobi = solve_steady(&net, &g, &bcs, &s, &SolveParams::new(Method::Cg, 1e-9, 10_000)).unwrap();
    assert!(
        one.report.iterations * 4 < jacobi.report.iterations,
        "amg {} jacobi {}",
        one.report.iterations,
        jacobi.report.iterations
    );
    assert!(max_diff(&one.values, &jacobi.values) < 1e-6);
}

#[test]
fn parameters_and_non_convergence_are_reported() {
    let (net, g, x) = geometric(1500, 6);
    let bcs = resolve_fixed(&net, &faces(&x, 0.0, 1.0), FloatingPolicy::Exclude).unwrap();
    let s = vec![0.0; net.n_nodes()];
    let bad = SolveParams::new(Method::AmgCg, 1.5, 10);
    assert!(matches!(
        solve_steady(&net, &g, &bcs, &s, &bad),
        Err(SolveError::InvalidParameter { ref field, .. }) if field == "method.rel_tol"
    ));
    let zero = SolveParams::new(Method::AmgCg, 1e-8, 0);
    assert!(matches!(
        solve_steady(&net, &g, &bcs, &s, &zero),
        Err(SolveError::InvalidParameter { ref field, .. }) if field == "method.max_iter"
    ));
    let short = SolveParams::new(Method::AmgCg, 1e-14, 2);
    match solve_steady(&net, &g, &bcs, &s, &short) {
        Err(SolveError::NotConverged {
            method,
            iterations,
            relative_residual,
            ..
        }) => {
            assert_eq!(method, "amg-pcg");
            assert!(iterations <= 2 && relative_residual > 1e-14);
        }
        other => panic!("expected NotConverged, got {other:?}"),
    }
}

#[test]
fn auto_picks_mic_for_small_and_multigrid_for_large_systems() {
    let auto = SolveParams::default();
    assert!(auto.method == Method::Auto);
    let (net, g, x) = geometric(2000, 8);
    let bcs = resolve_fixed(&net, &faces(&x, 0.0, 1.0), FloatingPolicy::Exclude).unwrap();
    let small = solve_steady(&net, &g, &bcs, &vec![0.0; net.n_nodes()], &auto).unwrap();
    assert_eq!(small.report.method, "mic-pcg");
    assert!(small.report.relative_residual <= 1e-8);
    assert_eq!(
        auto.method.resolve(demcon_network::AUTO_AMG_MIN_UNKNOWNS),
        Method::AmgCg
    );
    // A chain of 12 000 free nodes between two fixed ends: multigrid, and the linear profile.
    let n = 12_002;
    let edges: Vec<[u32; 2]> = (0..n as u32 - 1).map(|i| [i, i + 1]).collect();
    let chain = Network::new(n, &edges).unwrap();
    let ends = resolve_fixed(
        &chain,
        &[(vec![0], 0.0), (vec![n as u32 - 1], 1.0)],
        FloatingPolicy::Fail,
    )
    .unwrap();
    let g = vec![1.0; n - 1];
    let sys = LinearSystem::new(&chain, &g, None, &ends, &auto).unwrap();
    assert!(sys.method() == Method::AmgCg);
    let sol = sys.solve(&vec![0.0; n], None).unwrap();
    assert_eq!(sol.report.method, "amg-pcg");
    let worst = sol
        .values
        .iter()
        .enumerate()
        .map(|(i, v)| (v - i as f64 / (n - 1) as f64).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "{worst}");
}
