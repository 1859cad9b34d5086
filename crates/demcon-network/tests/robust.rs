//! Regression tests of issue "Robustness: no panic, no hang, no silent wrong number" (the
//! solver part): non-finite residuals, inputs that overflow f64, stagnation at high
//! conductivity contrast.

mod common;

use demcon_network::{
    FloatingPolicy, LinearSystem, MAX_RHS_ENTRY, Method, SolveError, SolveParams, resolve_fixed, solve_steady,
};

/// Every iterative method (and Auto) with a given tolerance.
fn iterative(rel_tol: f64) -> Vec<SolveParams> {
    let max_iter = 20_000;
    vec![
        SolveParams::new(Method::Cg, rel_tol, max_iter),
        SolveParams::new(Method::AmgCg, rel_tol, max_iter),
        SolveParams::new(Method::IcCg, rel_tol, max_iter),
        SolveParams::new(Method::Auto, rel_tol, max_iter),
    ]
}

fn expect_rhs_refused(r: Result<demcon_network::Solution, SolveError>, value: &str, method: SolveParams) {
    match r {
        Err(SolveError::InvalidParameter {
            field,
            value: v,
            allowed,
        }) => {
            assert!(field.contains("right-hand side"), "{method:?}: {field}");
            assert_eq!(v, value, "{method:?}");
            assert!(allowed.contains(&format!("{MAX_RHS_ENTRY:e}")), "{allowed}");
        }
        other => panic!("{method:?}: expected the right-hand side refused, got {other:?}"),
    }
}

#[test]
fn cg_treats_nan_residual_as_converged_fixed_value_1e300_is_refused() {
    let (net, g, x) = common::geometric_with(500, 1, |_, _| 1.0);
    let c = resolve_fixed(&net, &common::faces(&x, 0.0, 1e300), FloatingPolicy::Exclude).unwrap();
    let s = vec![0.0; net.n_nodes()];
    for method in iterative(1e-8)
        .into_iter()
        .chain([SolveParams::new(Method::Cholesky, 1e-8, 1)])
    {
        let r = solve_steady(&net, &g, &c, &s, &method);
        // The right-hand side of a node next to the hot face: a sum of conductance × 1e300.
        match &r {
            Err(SolveError::InvalidParameter { value, .. }) => {
                assert!(value.parse::<f64>().unwrap() >= 1e300, "{value}")
            }
            other => panic!("{method:?}: expected refusal, got {other:?}"),
        }
    }
}

#[test]
fn cg_treats_nan_residual_as_converged_heat_flux_1e160_is_refused() {
    let (net, g, x) = common::geometric_with(500, 2, |_, _| 1.0);
    let c = resolve_fixed(&net, &common::faces(&x, 0.0, 1.0), FloatingPolicy::Exclude).unwrap();
    let free = (0..net.n_nodes())
        .find(|&p| c.kinds()[p] == demcon_network::NodeKind::Free)
        .unwrap();
    let mut s = vec![0.0; net.n_nodes()];
    s[free] = 1e160;
    for method in iterative(1e-8) {
        expect_rhs_refused(solve_steady(&net, &g, &c, &s, &method), "1e160", method);
    }
}

#[test]
fn cg_treats_nan_residual_as_converged_resistivity_7e_minus_307_is_refused() {
    // A conductance of 1/7.3e-307 S between nodes at 0 and 1 V.
    let g_big = 1.0 / 7.3e-307;
    let (net, g, x) = common::geometric_with(500, 3, |_, _| g_big);
    let c = resolve_fixed(&net, &common::faces(&x, 0.0, 1.0), FloatingPolicy::Exclude).unwrap();
    let s = vec![0.0; net.n_nodes()];
    for method in iterative(1e-8) {
        match solve_steady(&net, &g, &c, &s, &method) {
            Err(SolveError::InvalidParameter { field, allowed, .. }) => {
                assert!(field.contains("right-hand side"), "{field}");
                assert!(allowed.contains("1e150"), "{allowed}");
            }
            other => panic!("{method:?}: expected refusal, got {other:?}"),
        }
    }
}

#[test]
fn cg_treats_nan_residual_as_converged_non_finite_residual_is_an_error() {
    // A warm start of 1e200 (finite, accepted) makes ‖b − A x0‖² overflow: every method
    // must report it, not return x0 as converged.
    let (net, g, x) = common::geometric_with(500, 4, |_, _| 1.0);
    let c = resolve_fixed(&net, &common::faces(&x, 0.0, 1.0), FloatingPolicy::Exclude).unwrap();
    let s = vec![0.0; net.n_nodes()];
    let x0 = vec![1e200; net.n_nodes()];
    for method in iterative(1e-8) {
        let sys = LinearSystem::new(&net, &g, None, &c, &method).unwrap();
        match sys.solve(&s, Some(&x0)) {
            Err(SolveError::NonFinite { value, .. }) => assert!(!value.is_finite()),
            other => panic!("{method:?}: expected NonFinite, got {other:?}"),
        }
    }
}

#[test]
fn cg_treats_nan_residual_as_converged_error_message_names_value() {
    let (net, g, x) = common::geometric_with(300, 5, |_, _| 1.0);
    let c = resolve_fixed(&net, &common::faces(&x, 0.0, 1e300), FloatingPolicy::Exclude).unwrap();
    let s = vec![0.0; net.n_nodes()];
    let e = solve_steady(&net, &g, &c, &s, &SolveParams::default()).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("e300") && msg.contains("1e150"), "{msg}");
}

#[test]
fn contrast_cliff_steady_solves_converge_at_contrast_1e6_and_1e_minus_6() {
    let n = 16;
    for ratio in [3e5, 1e6, 1e-6] {
        let (net, g, sets) = demcon_network::fixtures::inclusion_lattice(n, ratio);
        let c = resolve_fixed(&net, &sets, FloatingPolicy::Fail).unwrap();
        let s = vec![0.0; net.n_nodes()];
        let exact = solve_steady(&net, &g, &c, &s, &SolveParams::new(Method::Cholesky, 1e-8, 1)).unwrap();
        for method in iterative(1e-10) {
            let sol = solve_steady(&net, &g, &c, &s, &method)
                .unwrap_or_else(|e| panic!("contrast {ratio:e}, {method:?}: {e}"));
            let r = &sol.report;
            eprintln!(
                "contrast {ratio:e} {}: {} iterations, residual {:.2e}, attainable {:?}",
                r.method, r.iterations, r.relative_residual, r.attainable
            );
            assert!(r.iterations < 5_000, "{method:?}: {} iterations", r.iterations);
            let err = sol
                .values
                .iter()
                .zip(&exact.values)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(
                err < 1e-6,
                "contrast {ratio:e}, {method:?}: max |T − T_chol| = {err:e}"
            );
        }
    }
}
