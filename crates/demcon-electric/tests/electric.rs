//! Integration tests of the electric solve: an exact lattice resistor, Kirchhoff balance,
//! Joule total = V·I, CG vs Cholesky, floating clusters and bad electrodes.

use demcon_electric::{ElectricError, ElectricParams, joule_power, solve_potential};
use demcon_network::{FloatingPolicy, Method, Network, SolveError, SolveParams};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// n×n×n simple cubic lattice; returns the network and the two end faces (x = 0, x = n−1).
fn cube(n: usize) -> (Network, Vec<u32>, Vec<u32>) {
    let id = |i: usize, j: usize, k: usize| (i * n * n + j * n + k) as u32;
    let mut edges = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                    if i + di < n && j + dj < n && k + dk < n {
                        edges.push([id(i, j, k), id(i + di, j + dj, k + dk)]);
                    }
                }
            }
        }
    }
    let face = |i: usize| (0..n * n).map(|r| (i * n * n + r) as u32).collect();
    (Network::new(n * n * n, &edges).unwrap(), face(0), face(n - 1))
}

#[test]
fn uniform_lattice_has_the_exact_resistance() {
    let n = 10;
    let (net, a, b) = cube(n);
    let g = vec![0.5; net.n_edges()];
    let sol = solve_potential(&net, &g, &[(a, 2.0), (b, -1.0)], &ElectricParams::default()).unwrap();
    // n² parallel chains of n − 1 resistors of 2 Ω: R = 2 (n − 1) / n².
    let exact = 2.0 * (n - 1) as f64 / (n * n) as f64;
    let r = sol.resistance_ohm.unwrap();
    assert!((r - exact).abs() < 1e-8 * exact, "{r} vs {exact}");
    assert!(sol.current_mismatch < 1e-8);
    assert!((sol.current_in - 3.0 / exact).abs() < 1e-7 * sol.current_in);
    // Joule total = V I.
    let p = joule_power(&net, &g, &sol.potentials, 1.0).unwrap();
    let total: f64 = p.iter().sum();
    assert!((total - 3.0 * sol.current_in).abs() < 1e-7 * total);
    let p_half = joule_power(&net, &g, &sol.potentials, 0.5).unwrap();
    assert!((p_half.iter().sum::<f64>() - 0.5 * total).abs() < 1e-9 * total);
}

#[test]
fn random_network_balances_currents_and_methods_agree() {
    let n = 12;
    let (net0, a, b) = cube(n);
    // Random conductances and some random long-range links.
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let mut edges = net0.edges().to_vec();
    for _ in 0..500 {
        let p = rng.random_range(0..net0.n_nodes() as u32);
        let q = rng.random_range(0..net0.n_nodes() as u32);
        if p != q {
            edges.push([p, q]);
        }
    }
    let net = Network::new(net0.n_nodes(), &edges).unwrap();
    let g: Vec<f64> = (0..edges.len()).map(|_| rng.random_range(0.1..10.0)).collect();
    let electrodes = [(a, 1.0), (b, 0.0)];
    let cg = solve_potential(&net, &g, &electrodes, &ElectricParams::default()).unwrap();
    let chol = solve_potential(
        &net,
        &g,
        &electrodes,
        &ElectricParams {
            solve: SolveParams::new(Method::Cholesky, 1e-8, 1),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(cg.current_mismatch < 1e-6, "{}", cg.current_mismatch);
    assert!(chol.current_mismatch < 1e-10);
    let (r1, r2) = (cg.resistance_ohm.unwrap(), chol.resistance_ohm.unwrap());
    assert!((r1 - r2).abs() < 1e-6 * r2);
    assert!(cg.report.iterations > 0 && cg.report.relative_residual <= 1e-8);
    // Kirchhoff at every interior particle: Σ currents leaving = 0.
    let mut net_out = vec![0.0; net.n_nodes()];
    for (e, &[p, q]) in net.edges().iter().enumerate() {
        net_out[p as usize] += chol.branch_currents[e];
        net_out[q as usize] -= chol.branch_currents[e];
    }
    let fixed: std::collections::BTreeSet<u32> =
        electrodes.iter().flat_map(|(s, _)| s.iter().copied()).collect();
    let worst = (0..net.n_nodes() as u32)
        .filter(|p| !fixed.contains(p))
        .map(|p| net_out[p as usize].abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9 * chol.current_in, "{worst}");
    let p = joule_power(&net, &g, &chol.potentials, 1.0).unwrap();
    assert!((p.iter().sum::<f64>() - chol.current_in).abs() < 1e-9 * chol.current_in);
}

#[test]
fn floating_clusters_fail_or_are_excluded() {
    // 0-1-2 between electrodes, 3-4 floating, 5 isolated.
    let net = Network::new(6, &[[0, 1], [1, 2], [3, 4]]).unwrap();
    let g = [1.0, 1.0, 1.0];
    let el = [(vec![0], 1.0), (vec![2], 0.0)];
    assert!(matches!(
        solve_potential(&net, &g, &el, &ElectricParams::default()),
        Err(ElectricError::Network(SolveError::FloatingCluster {
            nodes: 3,
            clusters: 2,
            ..
        }))
    ));
    let sol = solve_potential(
        &net,
        &g,
        &el,
        &ElectricParams {
            floating: FloatingPolicy::Exclude,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(sol.excluded, vec![3, 4, 5]);
    assert_eq!(sol.diagnostics.len(), 1);
    assert!((sol.resistance_ohm.unwrap() - 2.0).abs() < 1e-12);
    let p = joule_power(&net, &g, &sol.potentials, 1.0).unwrap();
    assert_eq!(&p[3..], &[0.0, 0.0, 0.0]);
    assert!(sol.potentials.iter().all(|v| v.is_finite()));
}

#[test]
fn bad_electrodes_and_eta_are_clear_errors() {
    let net = Network::new(3, &[[0, 1], [1, 2]]).unwrap();
    let g = [1.0, 1.0];
    let p = ElectricParams::default();
    assert_eq!(
        solve_potential(&net, &g, &[], &p),
        Err(ElectricError::NoElectrode)
    );
    assert_eq!(
        solve_potential(&net, &g, &[(vec![0], 1.0), (vec![], 0.0)], &p),
        Err(ElectricError::EmptyElectrode { index: 1 })
    );
    assert_eq!(
        solve_potential(&net, &g, &[(vec![0, 1], 1.0), (vec![1, 2], 1.0)], &p),
        Err(ElectricError::ElectrodesOverlap {
            first: 0,
            second: 1,
            node: 1
        })
    );
    assert!(matches!(
        solve_potential(&net, &g, &[(vec![0], 1.0), (vec![7], 0.0)], &p),
        Err(ElectricError::Network(SolveError::NodeOutOfRange { node: 7, .. }))
    ));
    assert!(matches!(
        solve_potential(&net, &[1.0, -1.0], &[(vec![0], 1.0), (vec![2], 0.0)], &p),
        Err(ElectricError::Network(SolveError::InvalidParameter { .. }))
    ));
    // One electrode: uniform potential, no current, no resistance.
    let one = solve_potential(&net, &g, &[(vec![0], 3.0)], &p).unwrap();
    assert!(
        one.potentials.iter().all(|v| (v - 3.0).abs() < 1e-12),
        "{:?}",
        one.potentials
    );
    assert_eq!(one.resistance_ohm, None);
    for eta in [-0.1, 1.5, f64::NAN] {
        assert!(matches!(
            joule_power(&net, &g, &[1.0, 0.5, 0.0], eta),
            Err(ElectricError::InvalidParameter { ref field, .. }) if field == "eta"
        ));
    }
    assert!(matches!(
        joule_power(&net, &g, &[1.0, f64::NAN, 0.0], 1.0),
        Err(ElectricError::Network(SolveError::InvalidParameter { .. }))
    ));
}

#[test]
fn contrast_cliff_electric_solves_converge_at_contrast_1e6_and_1e_minus_6() {
    let n = 16;
    for ratio in [1e6, 1e-6] {
        let (net, g, sets) = demcon_network::fixtures::inclusion_lattice(n, ratio);
        let exact = solve_potential(
            &net,
            &g,
            &sets,
            &ElectricParams {
                solve: SolveParams::new(Method::Cholesky, 1e-8, 1),
                ..Default::default()
            },
        )
        .unwrap();
        for method in [
            SolveParams::new(Method::Auto, 1e-10, 200_000),
            SolveParams::new(Method::Cg, 1e-10, 200_000),
            SolveParams::new(Method::AmgCg, 1e-10, 200_000),
        ] {
            let params = ElectricParams {
                solve: method,
                ..Default::default()
            };
            let sol = solve_potential(&net, &g, &sets, &params)
                .unwrap_or_else(|e| panic!("contrast {ratio:e}, {method:?}: {e}"));
            assert!(sol.report.iterations < 5_000, "{}", sol.report.iterations);
            let (r, r0) = (sol.resistance_ohm.unwrap(), exact.resistance_ohm.unwrap());
            assert!(
                (r - r0).abs() < 1e-6 * r0.abs(),
                "contrast {ratio:e}, {method:?}: R = {r} vs {r0}"
            );
        }
    }
}
