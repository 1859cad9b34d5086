//! Transmission surfaces, representative volumes, interface rule and conductances: the
//! lattice checks of analytic.md §7 and literature-notes.md §1, and the Platonic α/f_v table.

mod common;

use std::f64::consts::PI;

use demcon_core::{Container, ParticleSet, Region, Vec3};
use demcon_graph::*;

/// Bravais lattice `basis` in cubic cells of side `a` (m), `m³` cells, all radii `r` (m).
fn lattice(basis: &[[f64; 3]], a: f64, m: usize, r: f64) -> (ParticleSet, Container) {
    let mut centres = Vec::new();
    for i in 0..m {
        for j in 0..m {
            for k in 0..m {
                for b in basis {
                    centres.push(Vec3::new(i as f64 + b[0], j as f64 + b[1], k as f64 + b[2]) * a);
                }
            }
        }
    }
    let n = centres.len();
    (
        ParticleSet::new(centres, vec![r; n]).unwrap(),
        Container::Periodic {
            size: [m as f64 * a; 3],
        },
    )
}

/// Network conductivity tensor component k_ii = Σ_contacts g ℓ_i² / V (W/(m·K)) for a unit
/// gradient along axis i: the lattice sum, no solver.
fn lattice_conductivity(graph: &ContactGraph, g: &[f64], volume: f64, axis: usize) -> f64 {
    (0..graph.len())
        .map(|k| g[k] * graph.branch(k)[axis].powi(2))
        .sum::<f64>()
        / volume
}

#[test]
fn simple_cubic_with_terreros_gives_exactly_lambda() {
    let r = 0.25e-3; // m
    let lambda = 33.0; // W/(m·K)
    let (p, container) = lattice(&[[0.5, 0.5, 0.5]], 2.0 * r, 5, r);
    let graph = detect_contacts(&p, &container, &ContactParams::relative(0.01)).unwrap();
    assert_eq!(graph.len(), 3 * p.len());
    assert!(graph.degrees().iter().all(|&d| d == 6));
    let s = contact_surfaces(&graph, &p, &SurfaceModel::TerrerosAlpha).unwrap();
    assert_eq!(s.clamped, 0);
    assert!(s.area.iter().all(|&a| (a - 4.0 * r * r).abs() < 1e-15 * r * r));
    let prop = contact_property(&graph, &p.phases, &[lambda], InterfaceRule::HarmonicMean).unwrap();
    let g = conductances(&graph, &s.area, &prop).unwrap();
    let volume = container.volume();
    for axis in 0..3 {
        let k = lattice_conductivity(&graph, &g, volume, axis);
        assert!(
            (k / lambda - 1.0).abs() < 1e-12,
            "axis {axis}: k/λ = {}",
            k / lambda
        );
    }
    // Representative volume V/f_v(6) = (2r)³: the cells tile the box.
    let v = representative_volumes(&graph, &p, &SurfaceModel::TerrerosAlpha, 0.5).unwrap();
    assert!(v.iter().all(|&x| (x / (8.0 * r * r * r) - 1.0).abs() < 1e-12));
    assert!((v.iter().sum::<f64>() / volume - 1.0).abs() < 1e-12);
}

#[test]
fn bcc_with_octahedra_gives_nine_eighths_lambda() {
    // literature-notes §1: k = g z ℓ²/(6 V_c) = 1.125 λ for BCC 8-NN with α(8) = 3√3/2.
    let r = 1.0;
    let a = 4.0 * r / 3f64.sqrt(); // nearest-neighbour distance √3 a/2 = 2r
    let (p, container) = lattice(&[[0.0, 0.0, 0.0], [0.5, 0.5, 0.5]], a, 3, r);
    let graph = detect_contacts(&p, &container, &ContactParams::relative(0.01)).unwrap();
    assert!(graph.degrees().iter().all(|&d| d == 8));
    let s = contact_surfaces(&graph, &p, &SurfaceModel::TerrerosAlpha).unwrap();
    let prop = vec![1.0; graph.len()];
    let g = conductances(&graph, &s.area, &prop).unwrap();
    let k = lattice_conductivity(&graph, &g, container.volume(), 0);
    assert!((k - 1.125).abs() < 1e-12, "k/λ = {k}");
}

#[test]
#[allow(clippy::approx_constant)] // the reference table is quoted as printed
fn platonic_table_and_volume_identity() {
    let s3 = 3f64.sqrt();
    let s5 = 5f64.sqrt();
    // Edge a = 1: face area, inradius, volume from the standard formulas of each solid.
    let pent = 0.25 * (25.0 + 10.0 * s5).sqrt();
    let solids = [
        (4, s3 / 4.0, 1.0 / (2.0 * 6f64.sqrt()), 1.0 / (6.0 * 2f64.sqrt())),
        (6, 1.0, 0.5, 1.0),
        (8, s3 / 4.0, 1.0 / 6f64.sqrt(), 2f64.sqrt() / 3.0),
        (
            12,
            pent,
            (250.0 + 110.0 * s5).sqrt() / 20.0,
            (15.0 + 7.0 * s5) / 4.0,
        ),
        (20, s3 / 4.0, s3 * (3.0 + s5) / 12.0, 5.0 * (3.0 + s5) / 12.0),
    ];
    for (k, (n, face, inr, vol)) in solids.into_iter().enumerate() {
        let v = terreros_alpha(n);
        assert_eq!(TERREROS_NODES[k], n);
        assert!(!v.clamped);
        assert!((v.alpha - face / (inr * inr)).abs() < 1e-12 * v.alpha, "α({n})");
        let fv = 4.0 / 3.0 * PI * inr.powi(3) / vol;
        assert!((v.volume_fraction - fv).abs() < 1e-12, "f_v({n})");
        // The pyramid identity f_v = 4π/(n α).
        assert!(
            (v.volume_fraction - 4.0 * PI / (n as f64 * v.alpha)).abs() < 1e-12,
            "identity at {n}"
        );
    }
    // Reference values (terreros-alpha.md; its dodecahedron α is printed 1.3879, the exact
    // value is 1.38757 — the f_v it prints, 0.75470, agrees with the exact one).
    let reference = [
        (4, 10.392, 0.30230),
        (6, 4.000, 0.52360),
        (8, 2.598, 0.60460),
        (12, 1.3876, 0.75470),
        (20, 0.75810, 0.82880),
    ];
    for (n, alpha, fv) in reference {
        let v = terreros_alpha(n);
        assert!((v.alpha - alpha).abs() < 5e-4, "α({n}) = {}", v.alpha);
        assert!(
            (v.volume_fraction - fv).abs() < 5e-5,
            "f_v({n}) = {}",
            v.volume_fraction
        );
    }
    assert_eq!(terreros_alpha(6).alpha, 4.0);
}

#[test]
fn calibrated_surfaces_and_volumes() {
    let (p, l) = common::jittered_fcc(4, 2);
    let container = Container::Periodic { size: [l; 3] };
    let graph = detect_contacts(&p, &container, &ContactParams::target(7.5)).unwrap();
    let model = SurfaceModel::Calibrated { c_t: 0.8 };
    let s = contact_surfaces(&graph, &p, &model).unwrap();
    assert_eq!(s.clamped, 0);
    for (k, &[a, b]) in graph.pairs.iter().enumerate() {
        let rm = 0.5 * (p.radii[a as usize] + p.radii[b as usize]);
        assert!((s.area[k] - 0.8 * PI * rm * rm).abs() < 1e-15);
    }
    let phi = p.solid_volume() / container.volume();
    let v = representative_volumes(&graph, &p, &model, phi).unwrap();
    assert!((v.iter().sum::<f64>() / container.volume() - 1.0).abs() < 1e-12);
    // Terreros on the same graph: per-particle α from the degree; symmetric geometric mean.
    let t = contact_surfaces(&graph, &p, &SurfaceModel::TerrerosAlpha).unwrap();
    let deg = graph.degrees();
    assert_eq!(t.clamped, deg.iter().filter(|&&d| !(4..=20).contains(&d)).count());
    for (k, &[a, b]) in graph.pairs.iter().enumerate() {
        let (a, b) = (a as usize, b as usize);
        let expect = surface_terreros(deg[a], p.radii[a], deg[b], p.radii[b]);
        assert_eq!(t.area[k], expect);
    }
    // Bad input.
    for c_t in [0.0, -1.0, f64::NAN] {
        let e = contact_surfaces(&graph, &p, &SurfaceModel::Calibrated { c_t }).unwrap_err();
        assert!(e.to_string().contains("surface.c_t"), "{e}");
    }
    for phi in [0.0, 1.5, f64::NAN] {
        let e = representative_volumes(&graph, &p, &model, phi).unwrap_err();
        assert!(e.to_string().contains("phi"), "{e}");
    }
    let (other, _) = common::jittered_fcc(2, 2);
    assert!(contact_surfaces(&graph, &other, &model).is_err());
}

#[test]
fn interface_rule_across_phases() {
    // Chain of 4 touching spheres; particles 2 and 3 become phase 1 through a region.
    let mut p = ParticleSet::new(
        (0..4).map(|i| Vec3::new(i as f64, 0.0, 0.0)).collect(),
        vec![0.5; 4],
    )
    .unwrap();
    let region = Region::Box {
        min: Vec3::new(1.5, -1.0, -1.0),
        max: Vec3::new(5.0, 1.0, 1.0),
    };
    assert_eq!(assign_phase(&mut p, &region, 1), 2);
    let graph = detect_contacts(
        &p,
        &Container::Sphere { radius: 10.0 },
        &ContactParams::relative(0.01),
    )
    .unwrap();
    let (lm, li) = (0.195, 1.5); // epoxy, silica (W/(m·K))
    let h = contact_property(&graph, &p.phases, &[lm, li], InterfaceRule::HarmonicMean).unwrap();
    let a = contact_property(&graph, &p.phases, &[lm, li], InterfaceRule::ArithmeticMean).unwrap();
    assert_eq!(h[0], lm);
    assert_eq!(h[2], li);
    assert!((h[1] - 2.0 * lm * li / (lm + li)).abs() < 1e-15);
    assert!((a[1] - 0.5 * (lm + li)).abs() < 1e-15);
    // Harmonic mean = two half-bonds in series: g_Γ = 1/(1/g_p + 1/g_q) with g = 2λS/d.
    let s = [1.0; 3];
    let g = conductances(&graph, &s, &h).unwrap();
    let half = |l: f64| 2.0 * l * 1.0 / 1.0;
    assert!((g[1] - 1.0 / (1.0 / half(lm) + 1.0 / half(li))).abs() < 1e-14);
    // Bad input names the field.
    let e = contact_property(&graph, &p.phases, &[lm], InterfaceRule::HarmonicMean).unwrap_err();
    assert!(e.to_string().contains("phases[2]"), "{e}");
    let e = contact_property(&graph, &p.phases, &[lm, -1.0], InterfaceRule::HarmonicMean).unwrap_err();
    assert!(e.to_string().contains("per_phase[1]"), "{e}");
    let e = contact_property(&graph, &p.phases[..3], &[lm, li], InterfaceRule::HarmonicMean).unwrap_err();
    assert!(e.to_string().contains("phases"), "{e}");
    let e = conductances(&graph, &s[..2], &h).unwrap_err();
    assert!(e.to_string().contains("areas"), "{e}");
    let e = conductances(&graph, &[1.0, f64::NAN, 1.0], &h).unwrap_err();
    assert!(e.to_string().contains("areas[1]"), "{e}");
}
