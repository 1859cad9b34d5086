//! The Laguerre tessellation: exact cells on a lattice, and on random polydisperse sets the
//! properties the network relies on — volumes tile the domain, every cell closes (Σ S n = 0
//! with its wall facets), facets agree from both sides, and Σ S d n⊗n = V I in a periodic box.

use demcon_core::{Container, Face, ParticleSet, Region, Vec3};
use demcon_graph::{CellWall, ContactGraph, GraphError, LaguerreParams, tessellate};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Random non-overlapping spheres (random sequential addition) with radii in [0.6, 1.4]·r,
/// centres inside `inside`, wrapped images in a periodic box.
fn random_spheres(n: usize, container: &Container, r: f64, seed: u64) -> ParticleSet {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let b = container.bounds();
    let period = container.period();
    let mut centres: Vec<Vec3> = Vec::new();
    let mut radii: Vec<f64> = Vec::new();
    let mut tries = 0;
    while centres.len() < n {
        tries += 1;
        assert!(tries < 1_000_000, "could not place {n} spheres");
        let rad = r * rng.random_range(0.6..1.4);
        let c = Vec3::new(
            rng.random_range(b.min.x..b.max.x),
            rng.random_range(b.min.y..b.max.y),
            rng.random_range(b.min.z..b.max.z),
        );
        if period.is_none() && container.wall_distance(&c) < rad {
            continue;
        }
        let free = centres.iter().zip(&radii).all(|(o, &ro)| {
            let mut d = c - o;
            if let Some(l) = period {
                for k in 0..3 {
                    d[k] -= l[k] * (d[k] / l[k]).round();
                }
            }
            d.norm() >= rad + ro
        });
        if free {
            centres.push(c);
            radii.push(rad);
        }
    }
    ParticleSet::new(centres, radii).unwrap()
}

/// Largest |Σ S n| over the cells (facets and walls), relative to the mean facet area.
fn worst_closure(graph: &ContactGraph) -> f64 {
    let cells = graph.cells.as_ref().unwrap();
    let mut sum = vec![Vec3::zeros(); graph.n_particles];
    for (k, &[p, q]) in graph.pairs.iter().enumerate() {
        let a = cells.facet_area[k] * graph.geometry[k].normal;
        sum[p as usize] += a;
        sum[q as usize] -= a;
    }
    for w in &cells.walls {
        sum[w.particle as usize] += w.area * w.normal;
    }
    let mean = cells.facet_area.iter().sum::<f64>() / cells.facet_area.len() as f64;
    sum.iter().map(|s| s.norm()).fold(0.0, f64::max) / mean
}

#[test]
fn a_cubic_lattice_gives_cubes() {
    // 4 × 3 × 2 spheres of radius 0.5 on a unit lattice in a 4 × 3 × 2 box.
    let mut centres = Vec::new();
    for k in 0..2 {
        for j in 0..3 {
            for i in 0..4 {
                centres.push(Vec3::new(0.5 + i as f64, 0.5 + j as f64, 0.5 + k as f64));
            }
        }
    }
    let n = centres.len();
    let p = ParticleSet::new(centres, vec![0.5; n]).unwrap();
    let c = Container::Box {
        size: [4.0, 3.0, 2.0],
    };
    let g = tessellate(&p, &c, None, &LaguerreParams::default()).unwrap();
    let cells = g.cells.as_ref().unwrap();
    // Only face neighbours: edge and corner neighbours meet in zero-area facets, dropped.
    assert_eq!(g.pairs.len(), 3 * 3 * 2 + 4 * 2 * 2 + 4 * 3);
    assert!(cells.facet_area.iter().all(|&a| (a - 1.0).abs() < 1e-12));
    assert!(cells.split.iter().all(|&s| (s - 0.5).abs() < 1e-12));
    assert!(cells.volume.iter().all(|&v| (v - 1.0).abs() < 1e-12));
    // The XMin wall holds 3 × 2 facets of area 1 at distance 0.5.
    let xmin: Vec<_> = cells.on_wall(CellWall::Face(Face::XMin)).collect();
    assert_eq!(xmin.len(), 6);
    assert!(
        xmin.iter()
            .all(|w| (w.area - 1.0).abs() < 1e-12 && (w.distance - 0.5).abs() < 1e-12)
    );
    assert!((xmin[0].normal + Vec3::x()).norm() < 1e-12);
    assert_eq!(cells.report.one_sided_facets, 0);
    assert!(cells.report.volume_error.abs() < 1e-12);
}

#[test]
fn random_polydisperse_cells_tile_the_box_and_close() {
    let c = Container::Box {
        size: [12.0, 10.0, 8.0],
    };
    let p = random_spheres(400, &c, 0.7, 1);
    let g = tessellate(&p, &c, None, &LaguerreParams::default()).unwrap();
    let cells = g.cells.as_ref().unwrap();
    let r = &cells.report;
    assert!(r.volume_error.abs() < 1e-12, "{r:?}");
    assert_eq!(r.one_sided_facets, 0, "{r:?}");
    assert!(r.max_area_mismatch < 1e-9, "{r:?}");
    assert!(worst_closure(&g) < 1e-10, "{}", worst_closure(&g));
    // The power plane lies between the spheres: h_p ≥ R_p for disjoint spheres.
    for (k, &[a, b]) in g.pairs.iter().enumerate() {
        let d = g.geometry[k].distance;
        assert!(cells.split[k] * d >= p.radii[a as usize] * (1.0 - 1e-12));
        assert!((1.0 - cells.split[k]) * d >= p.radii[b as usize] * (1.0 - 1e-12));
    }
    // Each cell contains its sphere.
    for i in 0..p.len() {
        assert!(cells.volume[i] >= p.volume(i));
    }
    assert_eq!(g.report.n_components, 1);
}

#[test]
fn every_cell_satisfies_the_divergence_theorem_with_its_facet_centroids() {
    // Σ_f S_f (c_f − x_p) ⊗ n_f = V_p I: the lever arms that make the per-particle flux exact.
    let c = Container::Box {
        size: [12.0, 10.0, 8.0],
    };
    let p = random_spheres(400, &c, 0.7, 8);
    let g = tessellate(&p, &c, None, &LaguerreParams::default()).unwrap();
    let cells = g.cells.as_ref().unwrap();
    let mut m = vec![nalgebra::Matrix3::<f64>::zeros(); p.len()];
    for (k, &[a, b]) in g.pairs.iter().enumerate() {
        let (n, s, lever) = (g.geometry[k].normal, cells.facet_area[k], cells.centroid[k]);
        m[a as usize] += s * lever * n.transpose();
        m[b as usize] += s * (lever - g.branch(k)) * (-n).transpose();
    }
    for w in &cells.walls {
        m[w.particle as usize] += w.area * w.centroid * w.normal.transpose();
    }
    for (i, mi) in m.iter().enumerate() {
        let v = cells.volume[i];
        assert!(
            (mi / v - nalgebra::Matrix3::identity()).abs().max() < 1e-9,
            "cell {i}: {mi} vs {v}"
        );
    }
}

#[test]
fn the_result_does_not_depend_on_the_thread_count() {
    let c = Container::Box {
        size: [12.0, 10.0, 8.0],
    };
    let p = random_spheres(400, &c, 0.7, 2);
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
    let a = one.install(|| tessellate(&p, &c, None, &LaguerreParams::default()).unwrap());
    let mut b = three.install(|| tessellate(&p, &c, None, &LaguerreParams::default()).unwrap());
    b.report.wall_time_s = a.report.wall_time_s;
    b.cells.as_mut().unwrap().report.wall_s = a.cells.as_ref().unwrap().report.wall_s;
    assert_eq!(a, b);
}

#[test]
fn periodic_cells_tile_the_period_and_give_v_times_identity() {
    let c = Container::Periodic {
        size: [14.0, 12.0, 13.0],
    };
    let p = random_spheres(900, &c, 0.7, 3);
    let g = tessellate(&p, &c, None, &LaguerreParams::default()).unwrap();
    let cells = g.cells.as_ref().unwrap();
    assert!(cells.walls.is_empty());
    assert!(cells.report.volume_error.abs() < 1e-12, "{:?}", cells.report);
    assert!(worst_closure(&g) < 1e-10);
    // Σ S d n⊗n = V I: the network reproduces any uniform gradient exactly.
    let mut m = nalgebra::Matrix3::<f64>::zeros();
    for (k, geo) in g.geometry.iter().enumerate() {
        m += cells.facet_area[k] * geo.distance * geo.normal * geo.normal.transpose();
    }
    let v = 14.0 * 12.0 * 13.0;
    assert!((m / v - nalgebra::Matrix3::identity()).abs().max() < 1e-12, "{m}");
}

#[test]
fn curved_walls_leave_a_small_measured_volume_error() {
    let cyl = Container::Cylinder {
        radius: 5.0,
        length: 8.0,
    };
    let p = random_spheres(300, &cyl, 0.7, 4);
    let g = tessellate(&p, &cyl, None, &LaguerreParams::default()).unwrap();
    let r = &g.cells.as_ref().unwrap().report;
    // Tangent planes never cut the inside: the cells cover the cylinder, overshooting by the
    // tolerance at most.
    assert!(r.volume_error >= -1e-12 && r.volume_error < 2e-3, "{r:?}");
    assert!(r.curved_cells > 0);
    let sph = Container::Sphere { radius: 5.0 };
    let p = random_spheres(250, &sph, 0.7, 5);
    let g = tessellate(&p, &sph, None, &LaguerreParams::default()).unwrap();
    let r = &g.cells.as_ref().unwrap().report;
    assert!(r.volume_error >= -1e-12 && r.volume_error < 2e-3, "{r:?}");
}

#[test]
fn a_carving_region_clips_the_cells() {
    let c = Container::Box {
        size: [10.0, 10.0, 10.0],
    };
    let region = Region::Sphere {
        centre: Vec3::repeat(5.0),
        radius: 4.5,
    };
    let all = random_spheres(500, &c, 0.6, 6);
    let (kept, _) = all.retain(|i| region.contains_point(&all.centres[i]));
    let g = tessellate(&kept, &c, Some(&region), &LaguerreParams::default()).unwrap();
    let cells = g.cells.as_ref().unwrap();
    assert!(cells.on_wall(CellWall::Carved).count() > 0);
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 4.5f64.powi(3);
    let sum: f64 = cells.volume.iter().sum();
    assert!(
        sum >= exact * (1.0 - 1e-9) && sum < exact * 1.002,
        "{sum} vs {exact}"
    );
}

#[test]
fn a_concave_carving_region_keeps_every_site_in_its_cell() {
    // A box with a slot cut from its top: the slot's inner corners are concave. A tangent plane
    // at a vertex's nearest surface point could cut the site off; the exit point along the
    // site-to-vertex segment does not.
    let c = Container::Box {
        size: [10.0, 10.0, 10.0],
    };
    let slot = Region::Box {
        min: Vec3::new(3.0, -1.0, 6.0),
        max: Vec3::new(7.0, 11.0, 11.0),
    };
    let region = Region::Difference(Box::new(c.region()), Box::new(slot));
    let all = random_spheres(700, &c, 0.6, 9);
    let (kept, _) = all.retain(|i| region.contains_sphere(&all.centres[i], all.radii[i]));
    let g = tessellate(&kept, &c, Some(&region), &LaguerreParams::default()).unwrap();
    let cells = g.cells.as_ref().unwrap();
    let sum: f64 = cells.volume.iter().sum();
    let exact = 1000.0 - 4.0 * 10.0 * 4.0;
    assert!((sum / exact - 1.0).abs() < 2e-3, "{sum} vs {exact}");
    assert!(cells.volume.iter().all(|&v| v > 0.0));
}

#[test]
fn bad_input_is_named() {
    let c = Container::Box {
        size: [4.0, 4.0, 4.0],
    };
    // Coincident centres.
    let p = ParticleSet::new(vec![Vec3::repeat(2.0), Vec3::repeat(2.0)], vec![0.5, 0.5]).unwrap();
    let e = tessellate(&p, &c, None, &LaguerreParams::default()).unwrap_err();
    assert!(matches!(e, GraphError::CoincidentCentres { .. }), "{e}");
    // A deep overlap.
    let p = ParticleSet::new(vec![Vec3::repeat(2.0), Vec3::new(2.5, 2.0, 2.0)], vec![0.5, 0.5]).unwrap();
    let e = tessellate(&p, &c, None, &LaguerreParams::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("particles[0] and particles[1]")
            && e.contains("an overlap of 1.000")
            && e.contains("at most 0.1"),
        "{e}"
    );
    // Outside the container.
    let p = ParticleSet::new(vec![Vec3::repeat(2.0), Vec3::new(5.0, 2.0, 2.0)], vec![0.5, 0.5]).unwrap();
    let e = tessellate(&p, &c, None, &LaguerreParams::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("particles[1]") && e.contains("inside the box"), "{e}");
    // A periodic box too small for the search.
    let per = Container::Periodic {
        size: [2.2, 2.2, 2.2],
    };
    let p = random_spheres(3, &per, 0.3, 7);
    let e = tessellate(&p, &per, None, &LaguerreParams::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("container.size") && e.contains("too small"), "{e}");
    // Bad parameters.
    let params = LaguerreParams {
        curved_tolerance: -1.0,
        ..LaguerreParams::default()
    };
    let p = ParticleSet::new(vec![Vec3::repeat(1.0), Vec3::repeat(3.0)], vec![0.5, 0.5]).unwrap();
    let e = tessellate(&p, &c, None, &params).unwrap_err().to_string();
    assert!(e.contains("laguerre.curved_tolerance"), "{e}");
}
