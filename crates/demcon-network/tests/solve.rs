//! Integration tests of the network solves: exact small cases, residual checks on random
//! graphs, agreement of the three methods, determinism across thread counts, failures.

use demcon_network::{
    FloatingPolicy, LinearSystem, Method, Network, SolveError, SolveParams, boundary_flow, edge_flows,
    resolve_fixed, solve_shifted, solve_steady,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A jittered n×n×n lattice with nearest-neighbour and some diagonal edges, random
/// conductances in [0.5, 2]; node ids in lexicographic order.
fn lattice(n: usize, seed: u64) -> (Network, Vec<f64>) {
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
                if i + 1 < n && j + 1 < n && rng.random::<f64>() < 0.3 {
                    edges.push([id(i, j, k), id(i + 1, j + 1, k)]);
                }
            }
        }
    }
    let g = (0..edges.len()).map(|_| rng.random_range(0.5..2.0)).collect();
    (Network::new(n * n * n, &edges).unwrap(), g)
}

/// Fixed 0 on the face i = 0 and 1 on the face i = n − 1 of [`lattice`].
fn faces(n: usize) -> Vec<(Vec<u32>, f64)> {
    let face = |i: usize| -> Vec<u32> { (0..n * n).map(|r| (i * n * n + r) as u32).collect() };
    vec![(face(0), 0.0), (face(n - 1), 1.0)]
}

fn cg(rel_tol: f64) -> SolveParams {
    SolveParams::new(Method::Cg, rel_tol, 10_000)
}

/// ‖K x − s‖ over free rows, relative to ‖s + lift‖, recomputed from scratch.
fn free_residual(net: &Network, g: &[f64], x: &[f64], s: &[f64], fixed: &[u32]) -> f64 {
    let kx = net.apply_laplacian(g, x).unwrap();
    let mut is_fixed = vec![false; net.n_nodes()];
    fixed.iter().for_each(|&p| is_fixed[p as usize] = true);
    let mut num = 0.0;
    for p in 0..net.n_nodes() {
        if !is_fixed[p] {
            num += (kx[p] - s[p]).powi(2);
        }
    }
    num.sqrt()
}

#[test]
fn three_node_chain_is_exact_for_every_method() {
    let net = Network::new(3, &[[0, 1], [1, 2]]).unwrap();
    let g = [2.0, 6.0];
    let bcs = resolve_fixed(&net, &[(vec![0], 1.0), (vec![2], 9.0)], FloatingPolicy::Fail).unwrap();
    // Node 1: (2·1 + 6·9)/(2 + 6) = 7; with 4 W injected: (2 + 54 + 4)/8 = 7.5.
    for method in [
        SolveParams::default(),
        SolveParams::new(Method::Cg, 1e-12, 10),
        SolveParams::new(Method::IcCg, 1e-12, 10),
        SolveParams::new(Method::AmgCg, 1e-12, 10),
        SolveParams::new(Method::Cholesky, 1e-12, 1),
    ] {
        let p = method;
        let sol = solve_steady(&net, &g, &bcs, &[0.0; 3], &p).unwrap();
        assert!((sol.values[1] - 7.0).abs() < 1e-12, "{method:?}");
        assert_eq!((sol.values[0], sol.values[2]), (1.0, 9.0));
        let sol = solve_steady(&net, &g, &bcs, &[0.0, 4.0, 0.0], &p).unwrap();
        assert!((sol.values[1] - 7.5).abs() < 1e-12, "{method:?}");
        assert_eq!(sol.report.n_unknowns, 1);
        let flows = edge_flows(&net, &g, &sol.values).unwrap();
        // Flow 0 → 1 is 2·(1 − 7.5) = −13, flow 1 → 2 is 6·(7.5 − 9) = −9.
        assert!((flows[0] + 13.0).abs() < 1e-10 && (flows[1] + 9.0).abs() < 1e-10);
    }
}

#[test]
fn cg_residual_and_agreement_with_cholesky_and_multigrid() {
    let n = 12;
    let (net, g) = lattice(n, 7);
    let bcs = resolve_fixed(&net, &faces(n), FloatingPolicy::Fail).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let s: Vec<f64> = (0..net.n_nodes()).map(|_| rng.random_range(-0.1..0.1)).collect();
    let a = solve_steady(&net, &g, &bcs, &s, &cg(1e-10)).unwrap();
    let b = solve_steady(&net, &g, &bcs, &s, &SolveParams::new(Method::Cholesky, 1e-8, 1)).unwrap();
    let c = solve_steady(
        &net,
        &g,
        &bcs,
        &s,
        &SolveParams::new(Method::AmgCg, 1e-10, 10_000),
    )
    .unwrap();
    assert!(a.report.relative_residual <= 1e-10 && a.report.iterations > 5);
    assert!(b.report.relative_residual <= 1e-12);
    assert!(c.report.relative_residual <= 1e-10);
    let scale = 1.0 + s.iter().map(|v| v.abs()).sum::<f64>();
    let res = free_residual(&net, &g, &a.values, &s, bcs.fixed_nodes());
    assert!(res < 1e-8 * scale, "residual {res}");
    let max_diff = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    assert!(max_diff(&a.values, &b.values) < 1e-7);
    assert!(max_diff(&c.values, &b.values) < 1e-7);
    // Without sources, heat in at the hot face = heat out at the cold face (to rounding).
    let d = solve_steady(&net, &g, &bcs, &vec![0.0; net.n_nodes()], &cg(1e-12)).unwrap();
    let hot = boundary_flow(&net, &g, &d.values, &faces(n)[1].0).unwrap();
    let cold = boundary_flow(&net, &g, &d.values, &faces(n)[0].0).unwrap();
    assert!(hot > 0.0 && (hot + cold).abs() < 1e-9 * hot, "{hot} {cold}");
    // Maximum principle.
    assert!(d.values.iter().all(|&v| (-1e-12..=1.0 + 1e-12).contains(&v)));
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let n = 34; // 39 304 nodes: ten chunks, more than one parallel task.
    let (net, g) = lattice(n, 11);
    let bcs = resolve_fixed(&net, &faces(n), FloatingPolicy::Fail).unwrap();
    let s = vec![0.01; net.n_nodes()];
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| solve_steady(&net, &g, &bcs, &s, &cg(1e-9)).unwrap())
    };
    let one = run(1);
    let three = run(3);
    assert_eq!(one.values, three.values);
    assert_eq!(one.report.iterations, three.report.iterations);
}

#[test]
fn shifted_solve_matches_cholesky_and_warm_start_saves_iterations() {
    let n = 10;
    let (net, g) = lattice(n, 5);
    let bcs = resolve_fixed(&net, &faces(n), FloatingPolicy::Fail).unwrap();
    let d: Vec<f64> = (0..net.n_nodes()).map(|p| 0.5 + (p % 7) as f64).collect();
    let rhs: Vec<f64> = (0..net.n_nodes()).map(|p| (p % 5) as f64 * 0.3).collect();
    let a = solve_shifted(&net, &g, &d, &rhs, &bcs, None, &cg(1e-11)).unwrap();
    let sys = LinearSystem::new(
        &net,
        &g,
        Some(&d),
        &bcs,
        &SolveParams::new(Method::Cholesky, 1e-8, 1),
    )
    .unwrap();
    let b = sys.solve(&rhs, None).unwrap();
    assert!(b.report.relative_residual < 1e-12);
    for p in 0..net.n_nodes() {
        assert!((a.values[p] - b.values[p]).abs() < 1e-8);
    }
    // (D + K) x = rhs on free rows, checked independently.
    let kx = net.apply_laplacian(&g, &a.values).unwrap();
    let mut fixed = vec![false; net.n_nodes()];
    bcs.fixed_nodes().iter().for_each(|&p| fixed[p as usize] = true);
    let worst = (0..net.n_nodes())
        .filter(|&p| !fixed[p])
        .map(|p| (d[p] * a.values[p] + kx[p] - rhs[p]).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-8, "worst row residual {worst}");
    let warm = solve_shifted(&net, &g, &d, &rhs, &bcs, Some(&a.values), &cg(1e-11)).unwrap();
    assert!(
        warm.report.iterations < a.report.iterations / 2,
        "warm {} cold {}",
        warm.report.iterations,
        a.report.iterations
    );
}

#[test]
fn excluded_floating_clusters_are_reported_and_do_not_break_the_solve() {
    // Chain 0-1-2 anchored; 3-4 floating; 5 isolated (a rattler).
    let net = Network::new(6, &[[0, 1], [1, 2], [3, 4]]).unwrap();
    let g = [1.0, 1.0, 1.0];
    let sets = [(vec![0], 0.0), (vec![2], 2.0)];
    assert!(matches!(
        solve_steady(
            &net,
            &g,
            &resolve_fixed(&net, &sets, FloatingPolicy::Exclude).unwrap(),
            &[0.0; 6],
            &SolveParams::default()
        ),
        Ok(ref s) if s.excluded == vec![3, 4, 5] && (s.values[1] - 1.0).abs() < 1e-12
            && s.values[3..].iter().all(|v| *v == 0.0)
    ));
    // Kept floating clusters make a steady solve singular: refused.
    let kept = resolve_fixed(&net, &sets, FloatingPolicy::Keep).unwrap();
    assert!(matches!(
        solve_steady(&net, &g, &kept, &[0.0; 6], &SolveParams::default()),
        Err(SolveError::FloatingCluster { .. })
    ));
    // With a positive shift they are fine.
    let sol = solve_shifted(&net, &g, &[1.0; 6], &[1.0; 6], &kept, None, &cg(1e-12)).unwrap();
    assert!((sol.values[5] - 1.0).abs() < 1e-12);
}

#[test]
fn non_convergence_and_bad_input_are_clear_errors() {
    let n = 10;
    let (net, g) = lattice(n, 1);
    let bcs = resolve_fixed(&net, &faces(n), FloatingPolicy::Fail).unwrap();
    let s = vec![0.0; net.n_nodes()];
    for method in [
        SolveParams::new(Method::Cg, 1e-12, 3),
        SolveParams::new(Method::IcCg, 1e-12, 3),
    ] {
        match solve_steady(&net, &g, &bcs, &s, &method) {
            Err(SolveError::NotConverged {
                iterations,
                relative_residual,
                ..
            }) => {
                assert!(iterations <= 3 && relative_residual > 1e-12);
            }
            other => panic!("expected NotConverged, got {other:?}"),
        }
    }
    let bad = SolveParams::new(Method::Cg, 0.0, 5);
    assert!(matches!(
        solve_steady(&net, &g, &bcs, &s, &bad),
        Err(SolveError::InvalidParameter { ref field, .. }) if field == "method.rel_tol"
    ));
    let mut s_nan = s.clone();
    s_nan[4] = f64::NAN;
    assert!(matches!(
        solve_steady(&net, &g, &bcs, &s_nan, &SolveParams::default()),
        Err(SolveError::InvalidParameter { ref field, .. }) if field == "rhs[4]"
    ));
    assert!(matches!(
        solve_steady(&net, &g[1..], &bcs, &s, &SolveParams::default()),
        Err(SolveError::LengthMismatch { .. })
    ));
    let neg = vec![-1.0; net.n_nodes()];
    assert!(matches!(
        solve_shifted(&net, &g, &neg, &s, &bcs, None, &SolveParams::default()),
        Err(SolveError::InvalidParameter { ref field, .. }) if field == "shift[0]"
    ));
}
