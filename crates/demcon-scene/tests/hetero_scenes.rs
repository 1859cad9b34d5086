//! The heterogeneous example scenes (`scenes/halo-slab.ron`, `single-inclusion.ron`,
//! `multi-inclusion.ron`) load as shipped and run end to end once shrunk to a small packing;
//! the results are checked against physics that holds at any resolution.

use std::path::{Path, PathBuf};

use demcon_scene::config::PackingConfig;
use demcon_scene::{RunOptions, Scene, run};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

/// Loads a shipped scene and shrinks it to `n` particles, a Halo of `halo` radii and no files.
fn small(name: &str, n: usize, halo: f64) -> Scene {
    let mut s = Scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    match &mut s.config.packing {
        PackingConfig::Generate { count, phi, .. } => {
            *count = n;
            // Looser wall layers weigh more in a small walled packing: keep the bulk at ≈ 0.64.
            *phi = 0.64 - 0.5 * (n as f64).powf(-1.0 / 3.0);
        }
        other => panic!("{name}: expected a generated packing, got {other:?}"),
    }
    s.config.outputs.vtk = false;
    s.config.outputs.halo = Some(halo);
    s
}

fn probe(r: &demcon_scene::RunResult, name: &str, field: &str) -> f64 {
    r.probes
        .iter()
        .find(|p| p.name == name && p.field == field)
        .unwrap_or_else(|| panic!("no probe {name}/{field}"))
        .value
}

#[test]
fn halo_slab_scene_gives_the_uniform_flux() {
    let s = small("halo-slab.ron", 3000, 3.0);
    let r = run(&s, &RunOptions::default()).unwrap();
    // λ_e from fixed temperatures with C_t calibrated under an imposed flux: a few % of λ.
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!((etc / 33.0 - 1.0).abs() < 0.08, "λ_e = {etc}");
    // Linear profile: the centre is at the mean temperature.
    let tc = probe(&r, "centre", "temperature");
    assert!((tc - 30.0).abs() < 0.5, "T(centre) = {tc}");
    // The Halo reduces the scatter of q_y around the same mean (−λ_e ΔT/L).
    let flux = r.flux.as_ref().unwrap();
    let (halo, _, rep) = r.halo.as_ref().unwrap();
    assert_eq!(rep.ratio, 3.0);
    let fixed = &r.thermal_bcs.as_ref().unwrap().fixed_sets;
    let mut free = vec![true; flux.len()];
    for (_, ids, _) in fixed {
        ids.iter().for_each(|&i| free[i as usize] = false);
    }
    // Volume-weighted mean (the volume average of the flux field) and CoV over free particles.
    let w = &r.thermal_setup.as_ref().unwrap().rep_volumes;
    let stats = |v: &[demcon_core::Vec3]| {
        let sel = || v.iter().zip(w).zip(&free).filter(|(_, f)| **f).map(|(x, _)| x);
        let sw: f64 = sel().map(|(_, w)| w).sum();
        let m = sel().map(|(q, w)| w * q.y).sum::<f64>() / sw;
        let var = sel().map(|(q, w)| w * (q.y - m).powi(2)).sum::<f64>() / sw;
        (m, var.sqrt() / m.abs())
    };
    let (m0, cov0) = stats(flux);
    let (m3, cov3) = stats(halo);
    let exact = -etc * 10.0 / 0.1;
    assert!(
        (m0 / exact - 1.0).abs() < 0.1,
        "mean q_y = {m0}, expected ≈ {exact}"
    );
    assert!(
        (m3 / exact - 1.0).abs() < 0.1,
        "mean Halo q_y = {m3}, expected ≈ {exact}"
    );
    assert!(cov3 < 0.7 * cov0, "CoV without Halo {cov0}, with k = 3 {cov3}");
}

#[test]
fn single_inclusion_scene_concentrates_the_flux_in_the_inclusion() {
    let s = small("single-inclusion.ron", 4000, 3.0);
    let r = run(&s, &RunOptions::default()).unwrap();
    let counts = &r.model.report.phase_counts;
    assert_eq!(counts.len(), 2);
    // About 15.5 % of the particles (by centre) fall in the sphere of radius L/3.
    let frac = counts[1] as f64 / r.model.particles.len() as f64;
    assert!((frac - 0.155).abs() < 0.03, "inclusion particles {frac}");
    // Symmetry: the centre sits at the mean temperature.
    let ta = probe(&r, "A", "temperature");
    assert!((ta - 30.0).abs() < 0.3, "T(A) = {ta}");
    // The conductive inclusion draws the heat: |q| in it exceeds the matrix's beside it
    // (FEM: 7767 against 2310 W/m²), and the ETC exceeds the matrix's.
    let qa = probe(&r, "A", "halo_flux_magnitude");
    let qb = probe(&r, "B", "halo_flux_magnitude");
    assert!(qa > 2.0 * qb, "|q| A = {qa}, B = {qb}");
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!(etc > 33.0 * 1.1 && etc < 33.0 * 1.5, "λ_e = {etc}");
}

#[test]
fn multi_inclusion_scene_places_the_silica() {
    let s = small("multi-inclusion.ron", 6000, 2.0);
    let r = run(&s, &RunOptions::default()).unwrap();
    let inc = r.model.report.inclusions.as_ref().unwrap();
    // f = 0.2, edge / diameter = 6: round(0.2 · 216 · 6/π) = 83 spheres of radius ≈ L/12
    // (grown to exactly f: (82.5/83)^(1/3) · L/12).
    assert_eq!(inc.count, 83);
    assert!((inc.radius / (0.1 / 12.0) - 1.0).abs() < 0.005, "{}", inc.radius);
    assert!((inc.fraction - 0.2).abs() < 1e-3, "{}", inc.fraction);
    // No two spheres overlap, none crosses a wall.
    for (i, a) in inc.centres.iter().enumerate() {
        for c in a {
            assert!(*c >= inc.radius * (1.0 - 1e-9) && *c <= 0.1 - inc.radius * (1.0 - 1e-9));
        }
        for b in &inc.centres[..i] {
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            assert!(d >= 2.0 * inc.radius * (1.0 - 1e-9), "overlap {d}");
        }
    }
    assert!(
        (inc.particle_fraction - 0.2).abs() < 0.04,
        "{}",
        inc.particle_fraction
    );
    // The ETC lies between the phases and near the effective-medium estimates
    // (Maxwell 0.289, third order 0.292 W/(m·K)), within the coarse packing's error.
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!(etc > 0.25 && etc < 0.34, "λ_e = {etc}");
    // Each point reads one temperature between the two fixed ones.
    for name in ["A", "B", "C", "D"] {
        let t = probe(&r, name, "temperature");
        assert!((25.0..=35.0).contains(&t), "T({name}) = {t}");
    }
}
