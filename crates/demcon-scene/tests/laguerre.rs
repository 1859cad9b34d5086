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
