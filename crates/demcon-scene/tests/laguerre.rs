//! The Laguerre network from a scene: a homogeneous box between two walls gives λ_e = λ and
//! the exact flux −λ∇T in every particle (the cell-split dipoles), and the papers' contact
//! models cannot be mixed with it in one scene.

use std::path::{Path, PathBuf};

use demcon_scene::{RunOptions, Scene, run};

fn scene(surface: &str, electric: &str) -> String {
    format!(
        r#"(
    seed: 5,
    packing: Generate(container: Box(size: (0.003, 0.002, 0.002)), count: 1500, phi: 0.55, radius_cov: 0.3),
    surface: {surface},
    materials: [(name: "m", conductivity: 4.0, density: 1000.0, specific_heat: 500.0, resistivity: Some(1.0))],
    thermal: (
        bcs: [WallTemperature(face: XMin, value: 10.0), WallTemperature(face: XMax, value: 40.0)],
        solver: Steady,
    ),
    electric: {electric},
    outputs: (etc_axis: Some(X), flux: true, vtk: false),
)"#
    )
}

#[test]
fn a_homogeneous_box_gives_the_exact_conductivity_and_flux_in_every_particle() {
    let s = Scene::parse(&scene("Laguerre", "None"), Path::new("l.ron"), PathBuf::new()).unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let etc = r.etc.as_ref().unwrap();
    assert!((etc.lambda_e / 4.0 - 1.0).abs() < 1e-9, "{}", etc.lambda_e);
    // −λ ∂T/∂x = −4 · 30 / 0.003 W/m² along x, in every particle (to the solver's 1e-10
    // residual: 1e-8 relative).
    let q = -4.0 * 30.0 / 0.003;
    for f in r.flux.as_ref().unwrap() {
        assert!(
            (f.x / q - 1.0).abs() < 1e-8 && f.y.abs() < 1e-8 * q.abs() && f.z.abs() < 1e-8 * q.abs(),
            "{f}"
        );
    }
}

#[test]
fn one_network_for_both_physics() {
    let mixed = scene(
        "Laguerre",
        "Some((electrodes: [(face: Some(XMin), potential: 0.0), (face: Some(XMax), potential: 1.0)], \
         surface: TerrerosAlpha, eta: 0.0))",
    );
    let e = Scene::parse(&mixed, Path::new("l.ron"), PathBuf::new())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("electric.surface") && e.contains("both physics"),
        "{e}"
    );
}

#[test]
fn face_electrodes_give_the_exact_current_density_in_every_particle_of_the_files() {
    // The current density is built as the heat flux (contacts at their facets' centroids,
    // electrode links, cell volumes): −∇u/ρ_e = −(1 V / 3 mm) / (1 Ω·m) along x in every
    // particle of particles.csv and particles.vtu (to the solver's 1e-10 residual: 1e-8
    // relative, as the heat flux above). With η = 0.5 the particles' Joule power adds up to
    // half the power the current dissipates (`joule_w`), and its density is per cell volume.
    let text = scene(
        "Laguerre",
        "Some((electrodes: [(face: Some(XMin), potential: 0.0), (face: Some(XMax), potential: 1.0)], \
         surface: Laguerre, eta: 0.5))",
    )
    // Joule heat inside: no ETC (refused with it).
    .replace("vtk: false", "vtk: true, particles_csv: true")
    .replace("etc_axis: Some(X), ", "");
    let s = Scene::parse(&text, Path::new("l.ron"), PathBuf::new()).unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let dir = std::env::temp_dir().join(format!("demcon-laguerre-current-{}", std::process::id()));
    demcon_scene::write_outputs("l", &s.config().outputs, &r, &dir).unwrap();
    let (header, cols) = demcon_post::read_csv(dir.join("particles.csv")).unwrap();
    let col = |name: &str| {
        &cols[header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("{name}"))]
    };
    let j = -1.0 / 0.003;
    let (jx, jy, jz) = (
        col("current_density_x"),
        col("current_density_y"),
        col("current_density_z"),
    );
    for p in 0..jx.len() {
        assert!(
            (jx[p] / j - 1.0).abs() < 1e-8 && jy[p].abs() < 1e-8 * j.abs() && jz[p].abs() < 1e-8 * j.abs(),
            "particle {p}: ({}, {}, {}) A/m²",
            jx[p],
            jy[p],
            jz[p]
        );
    }
    let (joule, density, volume) = (col("joule_power"), col("joule_power_density"), col("volume"));
    assert_eq!(volume, &r.model.graph.cells.as_ref().unwrap().volume);
    for p in 0..joule.len() {
        assert!(
            (density[p] * volume[p] / joule[p] - 1.0).abs() < 1e-12,
            "particle {p}"
        );
    }
    let e = &r.electric.as_ref().unwrap().report;
    let heat: f64 = joule.iter().sum();
    assert!(
        (heat / (0.5 * e.joule_w) - 1.0).abs() < 1e-9,
        "{heat} W of {}",
        e.joule_w
    );
    assert!((e.joule_w / (1.0 * e.current_in) - 1.0).abs() < 1e-9, "{e:?}");
    // The VTU carries the same vector (3 components) and scalars.
    let vtu = demcon_post::read_vtu(dir.join("particles.vtu")).unwrap();
    let cd = vtu.array("current_density").unwrap();
    assert_eq!(cd.components, 3);
    assert_eq!(cd.values.chunks(3).map(|c| c[0]).collect::<Vec<_>>(), *jx);
    for f in ["joule_power_density", "volume"] {
        assert!(vtu.array(f).is_some(), "particles.vtu lacks {f}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
