//! MIC-PCG ([`Method::IcCg`]): agreement with the direct solve on random packing-like
//! networks (with sources, high-contrast phases, shifts and warm starts), fewer iterations
//! than Jacobi-PCG, and clear failures.

use demcon_network::{
    FloatingPolicy, LinearSystem, Method, Network, SolveError, SolveParams, resolve_fixed, solve_steady,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod common;
use common::{faces, geometric_with};

/// The shared random geometric graph with conductances log-uniform over a decade.
fn geometric(n: usize, seed: u64) -> (Network, Vec<f64>, Vec<f64>) {
    geometric_with(n, seed, |rng, _| 10f64.powf(rng.random::<f64>()))
}

const MIC: SolveParams = SolveParams::new(Method::IcCg, 1e-10, 2000);

fn max_diff(u: &[f64], v: &[f64]) -> f64 {
    u.iter().zip(v).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn agrees_with_cholesky_and_beats_jacobi_on_iterations() {
    for seed in [1, 2] {
        let (net, g, x) = geometric(2000, seed);
        let bcs = resolve_fixed(&net, &faces(&x, 0.0, 1.0), FloatingPolicy::Exclude).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed + 10);
        let s: Vec<f64> = (0..net.n_nodes()).map(|_| rng.random_range(-0.2..0.2)).collect();
        let a = solve_steady(&net, &g, &bcs, &s, &MIC).unwrap();
        let b = solve_steady(&net, &g, &bcs, &s, &SolveParams::new(Method::Cholesky, 1e-8, 1)).unwrap();
        let j = solve_steady(&net, &g, &bcs, &s, &SolveParams::new(Method::Cg, 1e-10, 5000)).unwrap();
        assert_eq!(a.report.method, "mic-pcg");
        assert!(a.report.relative_residual <= 1e-10, "{:?}", a.report);
        assert!(
            max_diff(&a.values, &b.values) < 1e-8,
            "{}",
            max_diff(&a.values, &b.values)
        );
        assert_eq!(a.excluded, b.excluded);
        assert!(
            3 * a.report.iterations < 2 * j.report.iterations,
            "MIC {} vs Jacobi {} iterations {:?}",
            a.report.iterations,
            j.report.iterations,
            a.report
        );
    }
}

#[test]
fn high_contrast_shifted_and_warm_started_systems_match_cholesky() {
    let (net, mut g, x) = geometric(2000, 3);
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let phase: Vec<bool> = (0..net.n_nodes()).map(|_| rng.random::<f64>() < 0.3).collect();
    for (gi, &[p, q]) in g.iter_mut().zip(net.edges()) {
        *gi *= match (phase[p as usize], phase[q as usize]) {
            (true, true) => 1000.0,
            (false, false) => 1.0,
            _ => 2.0 * 1000.0 / 1001.0,
        };
    }
    // Floating clusters kept: the shift anchors them (an implicit step).
    let bcs = resolve_fixed(&net, &faces(&x, 1.0, 0.0), FloatingPolicy::Keep).unwrap();
    let d: Vec<f64> = (0..net.n_nodes()).map(|p| 0.05 + 0.1 * (p % 5) as f64).collect();
    let sys = LinearSystem::new(&net, &g, Some(&d), &bcs, &MIC).unwrap();
    let direct = LinearSystem::new(
        &net,
        &g,
        Some(&d),
        &bcs,
        &SolveParams::new(Method::Cholesky, 1e-8, 1),
    )
    .unwrap();
    let mut prev: Option<Vec<f64>> = None;
    for k in 0..3 {
        let rhs: Vec<f64> = (0..net.n_nodes()).map(|p| ((p + k) % 7) as f64 * 0.1).collect();
        let a = sys.solve(&rhs, prev.as_deref()).unwrap();
        let b = direct.solve(&rhs, None).unwrap();
        assert!(max_diff(&a.values, &b.values) < 1e-8, "step {k}");
        assert!(a.report.relative_residual <= 1e-10);
        prev = Some(a.values);
    }
    // Same input, same bits: no thread-count or run dependence.
    let rhs = vec![0.3; net.n_nodes()];
    assert_eq!(
        sys.solve(&rhs, None).unwrap().values,
        sys.solve(&rhs, None).unwrap().values
    );
}

#[test]
fn too_few_iterations_is_reported() {
    let (net, g, x) = geometric(1500, 6);
    let bcs = resolve_fixed(&net, &faces(&x, 0.0, 1.0), FloatingPolicy::Exclude).unwrap();
    let p = SolveParams::new(Method::IcCg, 1e-12, 3);
    match solve_steady(&net, &g, &bcs, &vec![0.0; net.n_nodes()], &p) {
        Err(SolveError::NotConverged {
            method, iterations, ..
        }) => {
            assert_eq!(method, "mic-pcg");
            assert!(iterations <= 3 + 1);
        }
        other => panic!("expected NotConverged, got {other:?}"),
    }
}
