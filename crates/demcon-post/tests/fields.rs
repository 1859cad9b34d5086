//! Integration tests of the field post-processing: Halo, probes, profiles and slices on
//! lattices where the answer is known.

mod common;

use common::{Mix, cubic, jittered};
use demcon_core::{Axis, Container, Vec3};
use demcon_post::*;

const LAMBDA: f64 = 40.0; // W/(m·K)

#[test]
fn halo_of_a_uniform_field_is_that_field() {
    let p = jittered(12, 1);
    let mut rng = Mix(2);
    let vrep: Vec<f64> = p.radii.iter().map(|r| r.powi(3) * (3.0 + rng.next())).collect();
    let q0 = Vec3::new(-1200.0, 35.0, 7.5); // W/m²
    // Every particle carries the flux q0: D = −2 V q0.
    let d: Vec<Vec3> = vrep.iter().map(|v| -2.0 * v * q0).collect();
    let domain = Domain::of_container(&Container::Box { size: [12.0; 3] }).unwrap();
    for k in [0.0, 1.0, 4.0, 11.0] {
        let h = halo_flux(&p, &d, &vrep, &domain, &HaloParams::ratio(k)).unwrap();
        for f in &h.flux {
            assert!((f - q0).norm() < 1e-12 * q0.norm(), "k={k}: {f:?}");
        }
    }
}

#[test]
fn halo_on_a_cubic_lattice_is_exact_away_from_walls_and_flags_truncation() {
    let (n, r) = (14, 0.5e-3);
    let (p, pairs, branches) = cubic(n, r);
    let g = vec![LAMBDA * 4.0 * r * r / (2.0 * r); pairs.len()];
    let grad = Vec3::new(500.0, 0.0, -200.0);
    let t: Vec<f64> = p.centres.iter().map(|c| 300.0 + grad.dot(c)).collect();
    let vrep = vec![(2.0 * r).powi(3); p.len()];
    let d = particle_dipoles(&pairs, &branches, &g, &t).unwrap();
    let container = Container::Box {
        size: [2.0 * r * n as f64; 3],
    };
    let domain = Domain::of_container(&container).unwrap();
    let k = 4.0;
    let h = halo_flux(&p, &d, &vrep, &domain, &HaloParams::ratio(k)).unwrap();
    let expected = -LAMBDA * grad;
    let mut exact = 0;
    for (i, c) in p.centres.iter().enumerate() {
        let depth = container.wall_distance(c);
        assert_eq!(h.truncated[i], depth < k * r, "particle {i} at depth {depth}");
        // No surface-layer particle (depth r) in the halo: the average is exact.
        if depth >= k * r + 1.5 * r {
            exact += 1;
            assert!(
                (h.flux[i] - expected).norm() < 1e-9 * expected.norm(),
                "{i}: {:?}",
                h.flux[i]
            );
        }
    }
    assert!(exact > 100);
    assert_eq!(h.report.n_truncated, h.truncated.iter().filter(|&&x| x).count());
    // Interior halos hold the lattice points within 2 spacings: 33 of them.
    assert_eq!(h.report.max_members, 33);
}

#[test]
fn halo_ratio_zero_equals_the_particle_flux() {
    let (p, pairs, branches) = cubic(6, 1.0);
    let mut rng = Mix(9);
    let g: Vec<f64> = pairs.iter().map(|_| 0.5 + rng.next()).collect();
    let t: Vec<f64> = p.centres.iter().map(|_| rng.next() * 100.0).collect();
    let vrep = vec![8.0; p.len()];
    let q = particle_flux(&pairs, &branches, &g, &vrep, &t).unwrap();
    let d = particle_dipoles(&pairs, &branches, &g, &t).unwrap();
    let domain = Domain::around(&p).unwrap();
    let h = halo_flux(&p, &d, &vrep, &domain, &HaloParams::ratio(0.0)).unwrap();
    assert_eq!(h.flux, q);
    assert_eq!(h.report.n_truncated, 0);
}

#[test]
fn halo_does_not_depend_on_the_thread_count() {
    // Stated tolerance: none. Each particle's sum runs sequentially in a fixed order, so the
    // result is bitwise identical for any number of threads.
    let p = jittered(16, 5);
    let mut rng = Mix(6);
    let d: Vec<Vec3> = p
        .centres
        .iter()
        .map(|_| Vec3::new(rng.next(), rng.next(), rng.next()))
        .collect();
    let vrep: Vec<f64> = p.radii.iter().map(|r| 6.5 * r.powi(3)).collect();
    let domain = Domain::of_container(&Container::Periodic { size: [16.0; 3] }).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| halo_flux(&p, &d, &vrep, &domain, &HaloParams::ratio(6.0)).unwrap())
    };
    let one = run(1);
    let three = run(3);
    assert_eq!(one.report.threads, 1);
    assert_eq!(three.report.threads, 3);
    assert_eq!(one.flux, three.flux);
    assert!(one.report.mean_members > 50.0, "{:?}", one.report);
}

#[test]
fn probes_and_profiles_on_a_linear_field() {
    let (n, r) = (10, 1.0);
    let (p, _, _) = cubic(n, r);
    let t: Vec<f64> = p
        .centres
        .iter()
        .map(|c| 5.0 + 2.0 * c.x - c.y + 0.5 * c.z)
        .collect();
    let vrep = vec![8.0; p.len()];
    let domain = Domain::of_container(&Container::Box { size: [20.0; 3] }).unwrap();
    let index = ProbeIndex::new(&p, &vrep, &domain).unwrap();
    // Nearest: the particle centred at (5, 7, 9).
    let x = Vec3::new(5.3, 6.8, 9.6);
    let v = index.probe(&t, &x, &ProbeMethod::Nearest).unwrap();
    assert_eq!(v, 5.0 + 10.0 - 7.0 + 4.5);
    // A ball average centred on a lattice point is exact for a linear field (symmetric stencil).
    let ball = ProbeMethod::BallAverage { radius: 2.1 };
    let st = index.stencil(&Vec3::new(9.0, 9.0, 9.0), &ball).unwrap();
    assert_eq!(st.len(), 7);
    assert!((st.iter().map(|s| s.1).sum::<f64>() - 1.0).abs() < 1e-15);
    // A profile along a lattice line, through lattice points: exactly linear in s.
    let line = Line {
        from: Vec3::new(3.0, 9.0, 9.0),
        to: Vec3::new(17.0, 9.0, 9.0),
        n_points: 8,
    };
    for method in [ProbeMethod::Nearest, ball] {
        let prof = index.profile(&t, &line, &method).unwrap();
        assert_eq!(prof.len(), 8);
        for (s, v) in prof {
            let want = 5.0 + 2.0 * (3.0 + s) - 9.0 + 4.5;
            assert!((v - want).abs() < 1e-12, "{method:?} s={s}: {v} vs {want}");
        }
    }
    // Same with the free functions.
    let a = probe(&p, &vrep, &t, &x, &ProbeMethod::Nearest, &domain).unwrap();
    assert_eq!(a, v);
    assert_eq!(profile(&p, &vrep, &t, &line, &ball, &domain).unwrap().len(), 8);
    // A vector field probe.
    let q: Vec<Vec3> = t.iter().map(|&v| Vec3::new(v, 0.0, 1.0)).collect();
    let qv = index.probe_vector(&q, &x, &ProbeMethod::Nearest).unwrap();
    assert_eq!(qv, Vec3::new(v, 0.0, 1.0));
}

#[test]
fn ball_average_matches_a_direct_weighted_mean_and_wraps_in_periodic_boxes() {
    let p = jittered(10, 3);
    let mut rng = Mix(4);
    let w: Vec<f64> = p.radii.iter().map(|r| r.powi(3) * (1.0 + rng.next())).collect();
    let t: Vec<f64> = p.centres.iter().map(|_| rng.next()).collect();
    let domain = Domain::of_container(&Container::Periodic { size: [10.0; 3] }).unwrap();
    let index = ProbeIndex::new(&p, &w, &domain).unwrap();
    let x = Vec3::new(0.2, 9.9, 5.0); // near a corner: the ball wraps.
    let rad = 1.7;
    let mut sw = 0.0;
    let mut swt = 0.0;
    for (i, c) in p.centres.iter().enumerate() {
        let e = (c - x).map(|v| v - 10.0 * (v / 10.0).round());
        if e.norm() <= rad {
            sw += w[i];
            swt += w[i] * t[i];
        }
    }
    let m = ProbeMethod::BallAverage { radius: rad };
    let v = index.probe(&t, &x, &m).unwrap();
    assert!((v - swt / sw).abs() < 1e-14, "{v} vs {}", swt / sw);
    // The same point one period away gives the same value; so does the nearest probe.
    let v2 = index.probe(&t, &(x + Vec3::new(-10.0, 10.0, 20.0)), &m).unwrap();
    assert!((v - v2).abs() < 1e-14);
    let n1 = index.probe(&t, &x, &ProbeMethod::Nearest).unwrap();
    let best = (0..p.len())
        .min_by(|&a, &b| {
            let da = (p.centres[a] - x).map(|v| v - 10.0 * (v / 10.0).round()).norm();
            let db = (p.centres[b] - x).map(|v| v - 10.0 * (v / 10.0).round()).norm();
            da.total_cmp(&db)
        })
        .unwrap();
    assert_eq!(n1, t[best]);
}

#[test]
fn probe_errors_are_clear() {
    let (p, _, _) = cubic(4, 1.0);
    let t = vec![1.0; p.len()];
    let vrep = vec![8.0; p.len()];
    let domain = Domain::of_container(&Container::Box { size: [8.0; 3] }).unwrap();
    let index = ProbeIndex::new(&p, &vrep, &domain).unwrap();
    let e = index
        .probe(&t, &Vec3::new(4.0, 9.0, 4.0), &ProbeMethod::Nearest)
        .unwrap_err();
    assert!(matches!(e, PostError::ProbeOutside { .. }), "{e}");
    assert!(e.to_string().contains("outside"), "{e}");
    let e = index
        .probe(
            &t,
            &Vec3::new(4.0, 4.0, 4.0),
            &ProbeMethod::BallAverage { radius: 0.5 },
        )
        .unwrap_err();
    assert!(matches!(e, PostError::EmptyProbe { .. }), "{e}");
    let e = index
        .probe(
            &t,
            &Vec3::new(4.0, 4.0, 4.0),
            &ProbeMethod::BallAverage { radius: -1.0 },
        )
        .unwrap_err();
    assert!(e.to_string().contains("radius"), "{e}");
    let e = index
        .probe(&t[1..], &Vec3::new(4.0, 4.0, 4.0), &ProbeMethod::Nearest)
        .unwrap_err();
    assert!(e.to_string().contains("values"), "{e}");
    let line = Line {
        from: Vec3::zeros(),
        to: Vec3::new(20.0, 1.0, 1.0),
        n_points: 5,
    };
    assert!(matches!(
        index.profile(&t, &line, &ProbeMethod::Nearest),
        Err(PostError::ProbeOutside { .. })
    ));
    let line = Line { n_points: 1, ..line };
    assert!(
        index
            .profile(&t, &line, &ProbeMethod::Nearest)
            .unwrap_err()
            .to_string()
            .contains("n_points")
    );
    let e = ProbeIndex::new(&p, &vrep[1..], &domain).unwrap_err();
    assert!(e.to_string().contains("rep_volumes"), "{e}");
}

#[test]
fn slice_of_a_cubic_lattice() {
    let (n, r) = (6, 1.0);
    let (p, _, _) = cubic(n, r);
    let t: Vec<f64> = (0..p.len()).map(|i| i as f64).collect();
    let domain = Domain::of_container(&Container::Box { size: [12.0; 3] }).unwrap();
    let params = SliceParams {
        plane: Plane {
            axis: Axis::Z,
            position: 5.0,
        },
        resolution: 240,
    };
    let g = slice_grid(&p, &t, &domain, &params).unwrap();
    assert_eq!(g.shape, [240, 240]);
    assert_eq!(g.axes, [Axis::X, Axis::Y]);
    // Circles of radius r on a square grid of spacing 2r cover π/4 of the plane.
    assert!(
        (g.coverage() - std::f64::consts::FRAC_PI_4).abs() < 0.01,
        "{}",
        g.coverage()
    );
    for iv in 0..g.shape[1] {
        for iu in 0..g.shape[0] {
            let k = iv * g.shape[0] + iu;
            assert!(g.values[k].is_finite());
            match g.particle[k] {
                Some(id) => {
                    let c = g.centre(iu, iv);
                    assert!((c - p.centres[id as usize]).norm() <= r + 1e-12);
                    assert_eq!(g.values[k], t[id as usize]);
                    assert!(g.covered[k]);
                }
                None => assert!(!g.covered[k] && g.values[k] == 0.0),
            }
        }
    }
    // A plane through no centre cuts smaller circles: less coverage.
    let off = SliceParams {
        plane: Plane {
            axis: Axis::Z,
            position: 5.8,
        },
        ..params
    };
    assert!(slice_grid(&p, &t, &domain, &off).unwrap().coverage() < 0.4);
    let bad = SliceParams {
        plane: Plane {
            axis: Axis::Y,
            position: 13.0,
        },
        ..params
    };
    assert!(
        slice_grid(&p, &t, &domain, &bad)
            .unwrap_err()
            .to_string()
            .contains("plane.position")
    );
    let bad = SliceParams {
        resolution: 0,
        ..params
    };
    assert!(slice_grid(&p, &t, &domain, &bad).is_err());
}

#[test]
fn cov_of_the_lattice_flux_and_etc_from_a_plane_flow() {
    let (n, r) = (8, 0.5);
    let (p, pairs, branches) = cubic(n, r);
    let g = vec![LAMBDA * 4.0 * r * r / (2.0 * r); pairs.len()];
    let (t_hot, t_cold) = (100.0, 20.0);
    let len = 2.0 * r * (n - 1) as f64; // between the first and last layer of centres
    let t: Vec<f64> = p
        .centres
        .iter()
        .map(|c| t_hot + (t_cold - t_hot) * (c.x - r) / len)
        .collect();
    let vrep = vec![1.0; p.len()];
    let q = particle_flux(&pairs, &branches, &g, &vrep, &t).unwrap();
    // Interior particles all carry the same flux: CoV 0.
    let interior: Vec<bool> = p.centres.iter().map(|c| c.x > 1.0 && c.x < 7.0).collect();
    let cov = coefficient_of_variation(&components(&q, Axis::X), Some(&interior)).unwrap();
    assert!(cov < 1e-12, "{cov}");
    let f = flow_across_plane(
        &p,
        &pairs,
        &branches,
        &g,
        &t,
        Plane {
            axis: Axis::X,
            position: 4.2,
        },
        None,
    )
    .unwrap();
    let area = (2.0 * r * n as f64).powi(2);
    let lam = effective_conductivity(f.flow, area, len, t_hot - t_cold).unwrap();
    assert!((lam - LAMBDA).abs() < 1e-12 * LAMBDA, "{lam}");
}

#[test]
fn periodic_slice_draws_images_across_the_faces() {
    // One sphere of radius 1 centred at (0.2, 5, 5) in a periodic 10 m box: its section by
    // z = 5 also shows at x ≈ 10.
    let p = demcon_core::ParticleSet::new(vec![Vec3::new(0.2, 5.0, 5.0)], vec![1.0]).unwrap();
    let domain = Domain::of_container(&Container::Periodic { size: [10.0; 3] }).unwrap();
    let params = SliceParams {
        plane: Plane {
            axis: Axis::Z,
            position: 5.0,
        },
        resolution: 100,
    };
    let g = slice_grid(&p, &[7.0], &domain, &params).unwrap();
    let at = |x: f64, y: f64| {
        let (iu, iv) = ((x / g.cell) as usize, (y / g.cell) as usize);
        g.covered[iv * g.shape[0] + iu]
    };
    assert!(at(0.5, 5.0) && at(9.5, 5.0) && !at(5.0, 5.0) && !at(8.5, 5.0));
    // Area of the disc, π r², within the raster's resolution.
    let area = g.covered.iter().filter(|&&c| c).count() as f64 * g.cell * g.cell;
    assert!((area - std::f64::consts::PI).abs() < 0.05, "{area}");
}
