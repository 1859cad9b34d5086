//! `packing: Tile(...)`: copies of a periodic packing. The homogenised tensor of a tiling is
//! the original's (the periodic problem is the same), a tiling cut to walls is exact for a
//! linear field, and what cannot be tiled is refused by name before any packing.

use std::path::{Path, PathBuf};

use demcon_scene::{RunOptions, Scene, SceneError, run, summary_json};

const L: f64 = 0.002;

/// A periodic two-phase scene: `packing` spliced in, one silica sphere of radius 0.3 L at the
/// centre of every original period listed in `centres`.
fn text(packing: &str, centres: &str, thermal: &str) -> String {
    format!(
        r#"(
    seed: 4,
    packing: {packing},
    surface: Laguerre,
    materials: [
        (name: "epoxy", conductivity: 0.2, density: 1000.0, specific_heat: 500.0),
        (name: "silica", conductivity: 1.5, density: 1000.0, specific_heat: 500.0),
    ],
    phases: [Spheres(material: "silica", radius: {r}, centres: [{centres}])],
    thermal: {thermal},
    outputs: (vtk: false),
)"#,
        r = 0.3 * L
    )
}

fn base() -> String {
    format!("Generate(container: Periodic(size: ({L}, {L}, {L})), count: 1500, phi: 0.55, radius_cov: 0.3)")
}

const HOMOGENIZE: &str = "Some((bcs: [], solver: Homogenize))";

fn parse(t: &str) -> Result<Scene, SceneError> {
    Scene::parse(t, Path::new("tile.ron"), PathBuf::new())
}

fn tensor(j: &serde_json::Value) -> [[f64; 3]; 3] {
    let t = &j["etc_tensor"];
    [0, 1, 2].map(|i| [0, 1, 2].map(|k| t[i][k].as_f64().unwrap()))
}

#[test]
fn a_tiling_has_the_homogenised_tensor_of_its_packing() {
    let h = L / 2.0;
    let one = parse(&text(&base(), &format!("({h}, {h}, {h})"), HOMOGENIZE)).unwrap();
    let tiled = parse(&text(
        &format!("Tile(packing: {}, repeat: (2, 1, 1))", base()),
        &format!("({h}, {h}, {h}), ({}, {h}, {h})", L + h),
        HOMOGENIZE,
    ))
    .unwrap();
    let a = run(&one, &RunOptions::default()).unwrap();
    let b = run(&tiled, &RunOptions::default()).unwrap();
    assert_eq!(b.model.particles.len(), 2 * a.model.particles.len());
    assert!((a.model.phi - b.model.phi).abs() < 1e-12);
    let (ta, tb) = (tensor(&summary_json("a", &a)), tensor(&summary_json("b", &b)));
    let scale = ta[0][0];
    assert!(scale > 0.2 && scale < 1.5, "{ta:?}");
    for i in 0..3 {
        for k in 0..3 {
            assert!(
                (ta[i][k] - tb[i][k]).abs() < 1e-6 * scale,
                "{ta:?} against {tb:?}"
            );
        }
    }
}

#[test]
fn a_tiling_cut_to_walls_is_exact_for_a_linear_field() {
    // One material: Laguerre cells give the exact conductivity between the cut faces.
    let t = format!(
        r#"(
    seed: 2,
    packing: Tile(packing: {}, repeat: (2, 2, 2), walls: true),
    surface: Laguerre,
    materials: [(name: "m", conductivity: 2.0, density: 1000.0, specific_heat: 500.0)],
    thermal: (bcs: [WallTemperature(face: YMin, value: 0.0), WallTemperature(face: YMax, value: 1.0)], solver: Steady),
    outputs: (etc_axis: Y, vtk: false),
)"#,
        base()
    );
    let r = run(&parse(&t).unwrap(), &RunOptions::default()).unwrap();
    assert_eq!(r.model.particles.len(), 8 * 1500);
    assert_eq!(r.model.container.kind(), "box");
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!((etc - 2.0).abs() < 1e-6, "λ_e = {etc}");
}

#[test]
fn what_cannot_be_tiled_is_refused_by_name_before_packing() {
    let h = L / 2.0;
    let c = format!("({h}, {h}, {h})");
    let walled = format!("Generate(container: Box(size: ({L}, {L}, {L})), count: 1500, phi: 0.55)");
    let cases = [
        (
            format!("Tile(packing: {walled}, repeat: (2, 2, 2))"),
            "packing.packing.container",
            "only a periodic packing can be tiled",
        ),
        (
            format!("Tile(packing: {}, repeat: (2, 0, 1))", base()),
            "packing.repeat[1]",
            "at least 1",
        ),
        (
            format!("Tile(packing: {}, repeat: (100000, 100000, 1))", base()),
            "packing.repeat",
            "32-bit",
        ),
        (
            format!("Tile(packing: {}, repeat: (100, 100, 10))", base()),
            "packing.repeat",
            "bytes per particle",
        ),
    ];
    for (packing, field, allowed) in cases {
        // Refused at load (no packing made): the scene check knows the container and count.
        let e = parse(&text(&packing, &c, HOMOGENIZE)).unwrap_err().to_string();
        assert!(e.contains(field) && e.contains(allowed), "{packing}: {e}");
    }
    let t = text(
        &format!("Tile(packing: {}, repeat: (2, 2, 2), walls: true)", base()),
        &c,
        HOMOGENIZE,
    )
    .replace("surface: Laguerre", "surface: Calibrated(c_t: Value(0.5))");
    let e = parse(&t).unwrap_err().to_string();
    assert!(e.contains("packing.walls") && e.contains("Laguerre"), "{e}");
}
