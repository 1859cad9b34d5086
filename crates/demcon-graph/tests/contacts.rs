//! Contact detection against a brute-force O(N²) search, periodic minimum images, the
//! target-coordination tolerance, connectivity, determinism and bad input.

mod common;

use common::{brute_force, jittered_fcc, rsa};
use demcon_core::{Container, ParticleSet, Vec3};
use demcon_graph::*;

fn check_against_brute_force(p: &ParticleSet, container: &Container, eps: f64) {
    let reference = brute_force(p, container.period(), eps);
    assert!(
        reference.len() > p.len(),
        "test set too sparse: {} pairs",
        reference.len()
    );
    for search in [NeighbourSearch::CellGrid, NeighbourSearch::RTree] {
        let params = ContactParams {
            search,
            ..ContactParams::relative(eps)
        };
        let g = detect_contacts(p, container, &params).unwrap();
        let pairs: Vec<[u32; 2]> = reference.iter().map(|r| r.0).collect();
        assert_eq!(g.pairs, pairs, "{search:?} on {container:?}");
        for (k, (_, d)) in reference.iter().enumerate() {
            let geo = &g.geometry[k];
            assert!((geo.distance - d).abs() <= 1e-12 * d, "{search:?}: distance {k}");
            assert!((geo.normal.norm() - 1.0).abs() < 1e-14);
            let [a, b] = g.pairs[k];
            let (ra, rb) = (p.radii[a as usize], p.radii[b as usize]);
            let gap = g.gap(k, &p.radii);
            assert!((gap - (d - ra - rb)).abs() < 1e-12);
            assert!((g.mean_radius(k, &p.radii) - 0.5 * (ra + rb)).abs() < 1e-15);
            assert!(gap <= eps * (ra + rb) * (1.0 + 1e-12));
        }
        assert_eq!(g.report.search, search);
        assert_eq!(g.report.epsilon, eps);
    }
}

#[test]
fn agrees_with_brute_force_in_a_box() {
    let p = rsa(1200, 1.0, false, 7);
    check_against_brute_force(&p, &Container::Box { size: [1.0; 3] }, 0.6);
    let (f, l) = jittered_fcc(6, 3);
    check_against_brute_force(&f, &Container::Box { size: [l; 3] }, 0.25);
}

#[test]
fn agrees_with_brute_force_in_a_periodic_box() {
    let p = rsa(1200, 1.0, true, 11);
    check_against_brute_force(&p, &Container::Periodic { size: [1.0; 3] }, 0.6);
    let (f, l) = jittered_fcc(6, 5);
    check_against_brute_force(&f, &Container::Periodic { size: [l; 3] }, 0.25);
    // Few cells per axis (1 or 2): each neighbour cell must still be visited once.
    let (f, l) = jittered_fcc(2, 5);
    check_against_brute_force(&f, &Container::Periodic { size: [l; 3] }, 0.25);
}

/// Ids in no spatial order take the cell-order sweep: still exactly the brute-force pairs.
#[test]
fn agrees_with_brute_force_with_shuffled_ids() {
    for periodic in [false, true] {
        let (f, l) = jittered_fcc(6, 13);
        let n = f.len() as u32;
        let order: Vec<u32> = (0..n).map(|i| (i as u64 * 7919 % n as u64) as u32).collect();
        let container = if periodic {
            Container::Periodic { size: [l; 3] }
        } else {
            Container::Box { size: [l; 3] }
        };
        check_against_brute_force(&f.permuted(&order), &container, 0.25);
    }
}

#[test]
fn periodic_contacts_use_the_minimum_image() {
    // Two spheres of radius 0.1 m, 0.2 m apart through the x faces of a 2 m periodic box;
    // the second centre is given outside the box (−0.1 ≡ 1.9).
    let p = ParticleSet::new(
        vec![Vec3::new(0.1, 1.0, 1.0), Vec3::new(-0.1 - 2.0 * 0.0, 1.0, 1.0)],
        vec![0.1, 0.1],
    )
    .unwrap();
    let shifted = ParticleSet::new(
        vec![Vec3::new(0.1, 1.0, 1.0), Vec3::new(1.9, 1.0, 1.0)],
        vec![0.1, 0.1],
    )
    .unwrap();
    let periodic = Container::Periodic { size: [2.0; 3] };
    for set in [&p, &shifted] {
        let g = detect_contacts(set, &periodic, &ContactParams::relative(0.01)).unwrap();
        assert_eq!(g.pairs, vec![[0, 1]]);
        let geo = g.geometry[0];
        assert!((geo.distance - 0.2).abs() < 1e-12);
        assert!(
            (geo.normal - Vec3::new(-1.0, 0.0, 0.0)).norm() < 1e-12,
            "{:?}",
            geo.normal
        );
        assert!(g.gap(0, &set.radii).abs() < 1e-12);
        assert!((g.branch(0) - Vec3::new(-0.2, 0.0, 0.0)).norm() < 1e-12);
    }
    // In a walled box the same spheres are 1.8 m apart: no contact, two rattlers.
    let walled = Container::Box { size: [2.0; 3] };
    let g = detect_contacts(&shifted, &walled, &ContactParams::relative(0.01)).unwrap();
    assert!(g.pairs.is_empty());
    assert_eq!(g.report.rattlers, vec![0, 1]);
}

#[test]
fn target_coordination_is_reached_exactly() {
    let (p, l) = jittered_fcc(10, 1); // 4000 particles
    let n = p.len() as f64;
    for container in [
        Container::Periodic { size: [l; 3] },
        Container::Box { size: [l; 3] },
    ] {
        for target in [4.0, 7.5, 9.3] {
            let g = detect_contacts(&p, &container, &ContactParams::target(target)).unwrap();
            let z = g.coordination();
            // The fewest contacts giving Z ≥ target: overshoot below 2/N.
            assert!(z >= target && z - target < 2.0 / n, "Z = {z} for target {target}");
            assert_eq!(g.report.coordination, z);
            assert_eq!(g.report.target_coordination, Some(target));
            assert!(
                g.report
                    .diagnostics
                    .iter()
                    .all(|d| !matches!(d, Diagnostic::CoordinationOvershoot { .. }))
            );
            // The reported ε reproduces the same graph.
            let again = detect_contacts(&p, &container, &ContactParams::relative(g.report.epsilon)).unwrap();
            assert_eq!(again.pairs, g.pairs);
            // And one fewer contact would fall short: every contact's relative gap ≤ ε, and
            // ε lies below the first excluded pair's gap.
            let max_in = (0..g.len())
                .map(|k| g.gap(k, &p.radii) / (2.0 * g.mean_radius(k, &p.radii)))
                .fold(f64::NEG_INFINITY, f64::max);
            assert!(max_in <= g.report.epsilon);
            assert!(2.0 * (g.len() - 1) as f64 / n < target);
        }
    }
}

#[test]
fn target_needing_several_search_rounds() {
    // Sparse RSA set: Z = 4 needs a relative tolerance far above the initial 0.1.
    let p = rsa(1200, 1.0, false, 2);
    let g = detect_contacts(
        &p,
        &Container::Box { size: [1.0; 3] },
        &ContactParams::target(4.0),
    )
    .unwrap();
    assert!(g.report.search_rounds > 1, "{:?}", g.report);
    assert!(g.coordination() >= 4.0 && g.coordination() - 4.0 < 2.0 / p.len() as f64);
    let brute = brute_force(&p, None, g.report.epsilon);
    assert_eq!(brute.len(), g.len());
}

#[test]
fn lattice_ties_are_reported_as_overshoot() {
    // A perfect simple cubic lattice: all 6 neighbours at the same gap, so Z jumps 0 → 6.
    let m = 4;
    let centres = (0..m * m * m)
        .map(|i| Vec3::new((i % m) as f64, ((i / m) % m) as f64, (i / (m * m)) as f64) + Vec3::repeat(0.5))
        .collect();
    let p = ParticleSet::new(centres, vec![0.5; m * m * m]).unwrap();
    let g = detect_contacts(
        &p,
        &Container::Periodic { size: [m as f64; 3] },
        &ContactParams::target(3.0),
    )
    .unwrap();
    assert!((g.coordination() - 6.0).abs() < 1e-12);
    assert!(g.report.diagnostics.contains(&Diagnostic::CoordinationOvershoot {
        target: 3.0,
        reached: 6.0
    }));
}

#[test]
fn unreachable_target_says_what_was_found() {
    let p = rsa(300, 1.0, false, 4);
    let params = ContactParams {
        max_epsilon: 0.2,
        ..ContactParams::target(12.0)
    };
    match detect_contacts(&p, &Container::Box { size: [1.0; 3] }, &params) {
        Err(GraphError::UnreachableCoordination {
            target,
            max_coordination,
            max_epsilon,
        }) => {
            assert_eq!((target, max_epsilon), (12.0, 0.2));
            let expect = 2.0 * brute_force(&p, None, 0.2).len() as f64 / 300.0;
            assert!((max_coordination - expect).abs() < 1e-12);
        }
        other => panic!("expected UnreachableCoordination, got {other:?}"),
    }
    // Two particles can never reach Z = 1.5.
    let two = ParticleSet::new(vec![Vec3::zeros(), Vec3::new(1.0, 0.0, 0.0)], vec![0.5, 0.5]).unwrap();
    let e = detect_contacts(
        &two,
        &Container::Sphere { radius: 2.0 },
        &ContactParams::target(1.5),
    )
    .unwrap_err();
    assert!(e.to_string().contains("unreachable"), "{e}");
}

#[test]
fn rattlers_and_components_on_a_hand_built_set() {
    // Chain 0–1–2 along x, pair 3–4 far away, 5 alone; radius 0.5 m, touching at distance 1.
    let c = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 5.0, 0.0],
        [0.0, 6.0, 0.0],
        [5.0, 5.0, 5.0],
    ];
    let p = ParticleSet::new(
        c.iter().map(|v| Vec3::new(v[0], v[1], v[2])).collect(),
        vec![0.5; 6],
    )
    .unwrap();
    let g = detect_contacts(
        &p,
        &Container::Sphere { radius: 20.0 },
        &ContactParams::relative(0.01),
    )
    .unwrap();
    assert_eq!(g.pairs, vec![[0, 1], [1, 2], [3, 4]]);
    assert_eq!(g.degrees(), vec![1, 2, 1, 1, 1, 0]);
    let r = &g.report;
    assert_eq!(r.rattlers, vec![5]);
    assert_eq!(r.under_two_contacts, 5);
    assert_eq!((r.n_components, r.largest_component), (3, 3));
    assert!(r.diagnostics.contains(&Diagnostic::Rattlers { count: 1 }));
    assert!(r.diagnostics.contains(&Diagnostic::SingleContact { count: 4 }));
    assert!(r.diagnostics.contains(&Diagnostic::Disconnected {
        components: 3,
        largest: 3
    }));
    let comps = g.components();
    assert_eq!(comps.labels, vec![0, 0, 0, 1, 1, 2]);
    assert_eq!(comps.sizes, vec![3, 2, 1]);
    // Dropping the rattler and the pair leaves one component.
    let core = g.induced(&comps.members(0), &p.radii).unwrap();
    assert_eq!(core.pairs, vec![[0, 1], [1, 2]]);
    assert_eq!((core.report.n_components, core.report.rattlers.len()), (1, 0));
    assert!(g.induced(&[2, 1], &p.radii).is_err());
    assert!(g.induced(&[0, 6], &p.radii).is_err());
}

#[test]
fn overlaps_are_contacts_and_reported() {
    let p = ParticleSet::new(vec![Vec3::zeros(), Vec3::new(0.9, 0.0, 0.0)], vec![0.5, 0.5]).unwrap();
    let g = detect_contacts(
        &p,
        &Container::Sphere { radius: 3.0 },
        &ContactParams::relative(0.01),
    )
    .unwrap();
    assert_eq!(g.pairs, vec![[0, 1]]);
    assert!((g.gap(0, &p.radii) + 0.1).abs() < 1e-12);
    assert_eq!(g.report.overlaps, 1);
    match g
        .report
        .diagnostics
        .iter()
        .find(|d| matches!(d, Diagnostic::Overlaps { .. }))
    {
        Some(Diagnostic::Overlaps {
            count: 1,
            max_relative,
        }) => assert!((max_relative - 0.1).abs() < 1e-12),
        other => panic!("{other:?}"),
    }
}

#[test]
fn deterministic_across_runs_and_thread_counts() {
    let (p, l) = jittered_fcc(8, 9);
    // Shuffle ids so that the grid's cell order differs from the id order.
    let n = p.len() as u32;
    let order: Vec<u32> = (0..n).map(|i| (i as u64 * 7919 % n as u64) as u32).collect();
    let p = p.permuted(&order);
    let container = Container::Periodic { size: [l; 3] };
    let params = ContactParams::default();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| detect_contacts(&p, &container, &params).unwrap())
    };
    let a = run(1);
    let b = run(2);
    let c = run(2);
    for other in [&b, &c] {
        assert_eq!(a.pairs, other.pairs);
        assert_eq!(a.geometry, other.geometry);
        assert_eq!(a.report.epsilon, other.report.epsilon);
    }
    assert!(a.pairs.windows(2).all(|w| w[0] < w[1]) && a.pairs.iter().all(|[p, q]| p < q));
    assert!(a.report.wall_time_s > 0.0);
}

#[test]
fn bad_input_gets_a_clear_error() {
    let (p, l) = jittered_fcc(2, 1);
    let bx = Container::Box { size: [l; 3] };
    for (eps, field) in [
        (0.0, "tolerance.relative"),
        (-0.1, "tolerance.relative"),
        (f64::NAN, "tolerance.relative"),
    ] {
        let e = detect_contacts(&p, &bx, &ContactParams::relative(eps)).unwrap_err();
        assert!(e.to_string().contains(field), "{e}");
    }
    let e = detect_contacts(&p, &bx, &ContactParams::target(f64::INFINITY)).unwrap_err();
    assert!(e.to_string().contains("tolerance.target_coordination"), "{e}");
    let e = detect_contacts(
        &p,
        &bx,
        &ContactParams {
            max_epsilon: -1.0,
            ..ContactParams::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("max_epsilon"), "{e}");
    assert_eq!(
        detect_contacts(&ParticleSet::default(), &bx, &ContactParams::default()).unwrap_err(),
        GraphError::EmptyParticleSet
    );
    // Coincident centres.
    let twin = ParticleSet::new(vec![Vec3::repeat(1.0), Vec3::repeat(1.0)], vec![0.5, 0.5]).unwrap();
    let e = detect_contacts(&twin, &bx, &ContactParams::relative(0.1)).unwrap_err();
    assert!(
        matches!(e, GraphError::CoincidentCentres { p: 0, q: 1, .. }),
        "{e}"
    );
    // A periodic box too short for the minimum image to be unique.
    let e = detect_contacts(
        &twin,
        &Container::Periodic { size: [1.5; 3] },
        &ContactParams::relative(0.1),
    )
    .unwrap_err();
    assert!(e.to_string().contains("container.size"), "{e}");
    let e = detect_contacts(
        &p,
        &Container::Periodic { size: [l; 3] },
        &ContactParams::relative(0.9),
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("tolerance.relative") && e.to_string().contains("half the smallest period"),
        "{e}"
    );
    // Arrays that disagree (the fields are public).
    let mut broken = p.clone();
    broken.phases.pop();
    let e = detect_contacts(&broken, &bx, &ContactParams::relative(0.1)).unwrap_err();
    assert!(e.to_string().contains("particles.phases"), "{e}");
    let mut broken = p.clone();
    broken.radii[3] = f64::NAN;
    let e = detect_contacts(&broken, &bx, &ContactParams::relative(0.1)).unwrap_err();
    assert!(e.to_string().contains("particles.radii[3]"), "{e}");
    let e = detect_contacts(
        &p,
        &Container::Box {
            size: [1.0, 0.0, 1.0],
        },
        &ContactParams::relative(0.1),
    )
    .unwrap_err();
    assert!(e.to_string().contains("size.y"), "{e}");
}

#[test]
fn coordination_curve_matches_detection() {
    let (p, l) = jittered_fcc(6, 8);
    let container = Container::Periodic { size: [l; 3] };
    let eps = [0.02, 0.05, 0.1, 0.2, 0.3];
    let curve = coordination_curve(&p, &container, &eps, NeighbourSearch::CellGrid).unwrap();
    assert_eq!(curve.len(), eps.len());
    for (pt, &e) in curve.iter().zip(&eps) {
        let g = detect_contacts(&p, &container, &ContactParams::relative(e)).unwrap();
        assert_eq!(pt.epsilon, e);
        assert_eq!(pt.coordination, g.coordination());
        assert_eq!(
            pt.under_two_fraction,
            g.report.under_two_contacts as f64 / p.len() as f64
        );
    }
    assert!(curve.windows(2).all(|w| w[0].coordination <= w[1].coordination));
    let e = coordination_curve(&p, &container, &[0.1, -1.0], NeighbourSearch::CellGrid).unwrap_err();
    assert!(e.to_string().contains("epsilons[1]"), "{e}");
}
