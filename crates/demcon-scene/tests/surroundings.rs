//! Faces exchanging heat with their surroundings through the scene: what is refused when the
//! scene is read, and the heat balance of a run under each surface model.

use std::path::PathBuf;

use demcon_scene::{RunOptions, Scene, SceneError, run};

fn scene(surface: &str, bcs: &str, outputs: &str) -> String {
    format!(
        r#"(
    packing: Generate(container: Box(size: (0.02, 0.01, 0.01)), count: 1500, phi: 0.55, radius_cov: 0.3),
    surface: {surface},
    materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0)],
    thermal: (bcs: [{bcs}], solver: Steady),
    outputs: (vtk: false, {outputs}),
)"#
    )
}

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, &PathBuf::from("surroundings.ron"), PathBuf::new())
}

fn refused(text: &str) -> String {
    match parse(text) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("the scene should be refused when read:\n{text}"),
    }
}

const HOT: &str = "WallTemperature(face: XMin, value: 300.0)";

#[test]
fn bad_laws_and_clashing_faces_are_refused_when_the_scene_is_read() {
    let cases = [
        (
            "Convection(face: XMax, h: -1.0, t_inf: 20.0)",
            vec!["thermal.bcs[1].h", "-1", "≥ 0"],
        ),
        (
            "Convection(face: XMax, h: 10.0, t_inf: -300.0)",
            vec!["thermal.bcs[1].t_inf", "-300", "absolute zero"],
        ),
        (
            "Radiation(face: XMax, emissivity: 1.5, t_surroundings: 20.0)",
            vec!["thermal.bcs[1].emissivity", "1.5", "[0, 1]"],
        ),
        (
            "Radiation(face: XMax, emissivity: 0.5, t_surroundings: -274.0)",
            vec!["thermal.bcs[1].t_surroundings", "absolute zero"],
        ),
        (
            "Convection(face: Outer, h: 10.0, t_inf: 20.0)",
            vec!["thermal.bcs[1].face", "Outer"],
        ),
        (
            "Convection(face: XMin, h: 10.0, t_inf: 20.0)",
            vec!["thermal.bcs[1]", "WallTemperature", "XMin"],
        ),
        (
            "Convection(face: XMax, h: 10.0, t_inf: 20.0), Convection(face: XMax, h: 5.0, t_inf: 20.0)",
            vec!["thermal.bcs[2]", "Convection", "XMax"],
        ),
    ];
    for (bc, parts) in cases {
        let m = refused(&scene("Laguerre", &format!("{HOT}, {bc}"), ""));
        for p in parts {
            assert!(m.contains(p), "`{p}` missing from: {m}");
        }
    }
    // A convecting face next to two held ones: no λ_e.
    let bcs = format!(
        "{HOT}, WallTemperature(face: XMax, value: 0.0), Convection(face: YMin, h: 10.0, t_inf: 20.0)"
    );
    let m = refused(&scene("Laguerre", &bcs, "etc_axis: Some(X)"));
    assert!(
        m.contains("outputs.etc_axis") && m.contains("surroundings"),
        "{m}"
    );
    // Convection and radiation share a face; convection alone makes a steady state well posed.
    parse(&scene("Laguerre", &format!("{HOT}, Convection(face: XMax, h: 10.0, t_inf: 20.0), Radiation(face: XMax, emissivity: 0.9, t_surroundings: 20.0)"), "")).unwrap();
    parse(&scene(
        "Laguerre",
        "Convection(face: XMax, h: 10.0, t_inf: 20.0)",
        "",
    ))
    .unwrap();
}

#[test]
fn the_heat_held_in_leaves_by_the_exchanging_faces_under_every_surface_model() {
    for surface in ["Laguerre", "Calibrated(c_t: Auto)", "TerrerosAlpha"] {
        let bcs = format!(
            "{HOT}, Convection(face: XMax, h: 2000.0, t_inf: 20.0), Radiation(face: XMax, emissivity: 0.9, \
             t_surroundings: 0.0), Convection(face: YMax, h: 50.0, t_inf: 20.0)"
        );
        let r = run(&parse(&scene(surface, &bcs, "")).unwrap(), &RunOptions::default()).unwrap();
        let th = r.thermal.as_ref().unwrap();
        let faces = &th.report.surroundings;
        assert_eq!(faces.len(), 2, "{faces:?}");
        assert_eq!(faces[0].bcs, ["thermal.bcs[1]", "thermal.bcs[2]"]);
        // The exposed areas are the faces' (cells' facets, or the particles' shares).
        assert!(
            (faces[0].area_m2 / 1e-4 - 1.0).abs() < 1e-9,
            "{surface}: {faces:?}"
        );
        assert!(
            (faces[1].area_m2 / 2e-4 - 1.0).abs() < 1e-9,
            "{surface}: {faces:?}"
        );
        // What the held face puts in leaves through the two exchanging faces.
        let s = r.thermal_setup.as_ref().unwrap();
        let b = r.thermal_bcs.as_ref().unwrap();
        let nodes = th.node_temperatures();
        let held = b.fixed_sets[0].nodes(&s.walls);
        let q_in =
            demcon_network::boundary_flow(s.network(&r.model), &s.conductances, &nodes, &held).unwrap();
        let out: f64 = faces.iter().map(|f| f.convection_w + f.radiation_w).sum();
        assert!(
            q_in > 0.0 && (out / q_in - 1.0).abs() < 1e-7,
            "{surface}: in {q_in} W, out {out} W"
        );
        assert!(
            faces[0].radiation_w > 0.0 && th.report.nonlinear_iterations > 1,
            "{surface}: {:?}",
            th.report
        );
    }
}
