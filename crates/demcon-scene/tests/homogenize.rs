//! Periodic homogenisation from a scene: the tensors in `summary.json`, and the refusals of
//! what a homogenisation cannot take (a walled container, boundary conditions, electrodes,
//! one physics homogenised and not the other, outputs under boundary conditions, a Laguerre
//! network for one physics only).

use std::path::{Path, PathBuf};

use demcon_scene::{RunOptions, Scene, SceneError, run, summary_json};

/// A small periodic scene; `container`, `thermal`, `electric` and `outputs` are spliced in.
fn text(container: &str, thermal: &str, electric: &str, outputs: &str) -> String {
    format!(
        r#"(
    seed: 4,
    packing: Generate(container: {container}, count: 1500, phi: 0.55, radius_cov: 0.3),
    surface: Laguerre,
    materials: [(name: "m", conductivity: 2.0, density: 1000.0, specific_heat: 500.0, resistivity: Some(0.5))],
    thermal: {thermal},
    electric: {electric},
    outputs: ({outputs}),
)"#
    )
}

const PERIODIC: &str = "Periodic(size: (0.002, 0.002, 0.002))";
const THERMAL_H: &str = "Some((bcs: [], solver: Homogenize))";
const ELECTRIC_H: &str = "Some((electrodes: [], homogenize: true, surface: Laguerre))";

fn parse(t: &str) -> Result<Scene, SceneError> {
    Scene::parse(t, Path::new("homogenize.ron"), PathBuf::new())
}

fn error_of(t: &str) -> String {
    match parse(t) {
        Err(e) => e.to_string(),
        Ok(s) => run(&s, &RunOptions::default())
            .err()
            .map(|e| e.to_string())
            .expect("the scene must be refused"),
    }
}

#[test]
fn a_homogeneous_periodic_scene_gives_lambda_and_sigma_times_identity() {
    let s = parse(&text(PERIODIC, THERMAL_H, ELECTRIC_H, "vtk: false")).unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let j = summary_json("h", &r);
    for (key, value) in [("etc_tensor", 2.0), ("conductivity_tensor", 2.0)] {
        let t = &j[key];
        for i in 0..3 {
            for k in 0..3 {
                let want = if i == k { value } else { 0.0 };
                let got = t[i][k].as_f64().unwrap();
                assert!((got - want).abs() < 1e-9 * value, "{key}: {t}");
            }
        }
    }
    assert!(j["homogenization"]["thermal"]["symmetry_error"].as_f64().unwrap() < 1e-9);
}

#[test]
fn what_a_homogenisation_cannot_take_is_refused_by_name() {
    let cases = [
        (
            text("Box(size: (0.002, 0.002, 0.002))", THERMAL_H, "None", ""),
            "thermal.solver",
            "Periodic",
        ),
        (
            text(
                PERIODIC,
                "Some((bcs: [WallTemperature(face: XMin, value: 0.0)], solver: Homogenize))",
                "None",
                "",
            ),
            "thermal.bcs",
            "bcs: []",
        ),
        (
            text(
                PERIODIC,
                THERMAL_H,
                "Some((electrodes: [(face: Some(XMin), potential: 0.0)], homogenize: true, surface: Laguerre))",
                "",
            ),
            "electric.electrodes",
            "electrodes: []",
        ),
        (
            text(
                PERIODIC,
                THERMAL_H,
                "Some((electrodes: [], surface: Laguerre))",
                "",
            ),
            "electric.homogenize",
            "homogenises the whole scene",
        ),
        (
            text(PERIODIC, THERMAL_H, "None", "etc_axis: Some(X)"),
            "outputs.etc_axis",
            "tensor",
        ),
        (
            text(PERIODIC, THERMAL_H, "None", "plots: true"),
            "outputs.plots",
            "tensor",
        ),
        (
            text(
                PERIODIC,
                THERMAL_H,
                "Some((electrodes: [], homogenize: true, surface: TerrerosAlpha))",
                "",
            ),
            "electric.surface",
            "both physics",
        ),
    ];
    for (scene, field, why) in cases {
        let e = error_of(&scene);
        assert!(
            e.contains(field) && e.contains(why),
            "expected {field} / {why}: {e}"
        );
    }
}

#[test]
fn listed_spheres_count_their_periodic_images() {
    // One sphere centred on a corner of the periodic cell: its images fill all eight corners.
    let scene = format!(
        r#"(
    seed: 4,
    packing: Generate(container: {PERIODIC}, count: 1500, phi: 0.55, radius_cov: 0.3),
    surface: Laguerre,
    materials: [
        (name: "m", conductivity: 1.0, density: 1000.0, specific_heat: 500.0),
        (name: "s", conductivity: 10.0, density: 1000.0, specific_heat: 500.0),
    ],
    phases: [Spheres(material: "s", radius: 0.0006, centres: [(0.0, 0.0, 0.0)])],
    thermal: Some((bcs: [], solver: Homogenize)),
    outputs: (vtk: false),
)"#
    );
    let r = run(&parse(&scene).unwrap(), &RunOptions::default()).unwrap();
    let p = &r.model.particles;
    let mut corners = [false; 8];
    for (i, c) in p.centres.iter().enumerate() {
        if p.phases[i] == 1 {
            let k = (0..3).map(|a| usize::from(c[a] > 0.001) << a).sum::<usize>();
            corners[k] = true;
        }
    }
    assert_eq!(corners, [true; 8]);
    let f = r.model.report.inclusions.as_ref().unwrap().particle_fraction;
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.0006f64.powi(3) / 0.002f64.powi(3);
    // The cells follow the sphere and its images (the default conforming cells).
    assert!((f / exact - 1.0).abs() < 0.02, "{f} vs {exact}");
    // The tensor is isotropic to the discretisation and above the matrix's.
    let axes = r.homogenization.unwrap().thermal.unwrap().report.axes;
    assert!(
        axes.iter().all(|&a| a > 1.0 && (a / axes[0] - 1.0).abs() < 0.02),
        "{axes:?}"
    );
    // A centre outside the cell is named.
    let bad = scene.replace("(0.0, 0.0, 0.0)", "(0.0, 0.003, 0.0)");
    let e = error_of(&bad);
    assert!(
        e.contains("phases[0].centres[0]") && e.contains("bounding box"),
        "{e}"
    );
}
