//! The distributed solve (PETSc KSPCG + PCGAMG, `--features petsc`) on one rank — the test
//! process itself is a world of one — against the serial multigrid solve: same solution to
//! the tolerance, the same stopping rule on the true residual, the errors of a bad session.
//! Several ranks are tested through the CLI (`crates/demcon/tests/distributed.rs`).
#![cfg(feature = "petsc")]

use demcon_network::distributed::{Session, stats};
use demcon_network::fixtures::inclusion_lattice;
use demcon_network::{FloatingPolicy, LinearSystem, Method, SolveError, SolveParams, resolve_fixed};

/// One test function: PETSc starts once per process, and libtest runs tests in threads.
#[test]
fn distributed_solve_matches_the_serial_one_on_one_rank() {
    let session = Session::init().expect("PETSc starts");
    assert_eq!((session.rank(), session.size()), (0, 1));
    // A second session in the same process is refused, not a crash.
    assert!(matches!(
        Session::init(),
        Err(SolveError::DistributedUnavailable { .. })
    ));

    let (net, g, sets) = inclusion_lattice(14, 100.0);
    let bcs = resolve_fixed(&net, &sets, FloatingPolicy::Fail).unwrap();
    let rel_tol = 1e-10;
    let serial = LinearSystem::new(
        &net,
        &g,
        None,
        &bcs,
        &SolveParams::new(Method::AmgCg, rel_tol, 1000),
    )
    .unwrap();
    let dist = LinearSystem::new(
        &net,
        &g,
        None,
        &bcs,
        &SolveParams::new(Method::Distributed, rel_tol, 1000),
    )
    .unwrap();
    // Two right-hand sides on one prepared system: the set-up is reused.
    for source in [0.0, 0.05] {
        let rhs = vec![source; net.n_nodes()];
        let a = serial.solve(&rhs, None).unwrap();
        let b = dist.solve(&rhs, None).unwrap();
        assert_eq!(b.report.method, "petsc-cg-gamg");
        assert!(b.report.relative_residual <= rel_tol, "{:?}", b.report);
        assert!(b.report.iterations > 0);
        let scale = a.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (p, (x, y)) in a.values.iter().zip(&b.values).enumerate() {
            assert!(
                (x - y).abs() <= 1e-8 * scale,
                "node {p}: serial {x}, distributed {y}"
            );
        }
    }
    let s = stats();
    assert_eq!((s.ranks, s.systems), (1, 1));
    assert!(s.ksp_solves >= 2 && s.iterations > 0 && s.setup_s > 0.0);

    // Too few iterations: the restart loop reports it as for the serial path.
    let starved = LinearSystem::new(
        &net,
        &g,
        None,
        &bcs,
        &SolveParams::new(Method::Distributed, 1e-12, 2),
    )
    .unwrap();
    let err = starved.solve(&vec![0.0; net.n_nodes()], None).unwrap_err();
    assert!(
        matches!(
            err,
            SolveError::NotConverged {
                method: "petsc-cg-gamg",
                ..
            }
        ),
        "{err}"
    );
    drop((serial, dist, starved));
    drop(session);
}
