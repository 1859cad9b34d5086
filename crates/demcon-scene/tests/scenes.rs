//! Every example scene in `scenes/` parses and validates; the small first scene runs end to end
//! and writes its outputs; scene errors name the line or the field.

use std::path::{Path, PathBuf};

use demcon_scene::{RunOptions, Scene, SceneError, run, write_outputs};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

#[test]
fn every_example_scene_loads() {
    let mut n = 0;
    for entry in std::fs::read_dir(scenes_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) == Some("ron") {
            match Scene::load(&path) {
                Ok(_) => {}
                // The paper-scale scene needs ~12 GB: on a smaller machine its refusal must be
                // the memory estimate's, and nothing else.
                Err(e) if e.to_string().contains("bytes per particle") => {
                    assert!(
                        path.ends_with("multi-inclusion-8m.ron"),
                        "{}: {e}",
                        path.display()
                    );
                }
                Err(e) => panic!("{}: {e}", path.display()),
            }
            n += 1;
        }
    }
    assert!(n >= 4, "only {n} scenes found");
}

#[test]
fn first_scene_runs_end_to_end() {
    let scene = Scene::load(&scenes_dir().join("slab-steady.ron")).unwrap();
    let r = run(&scene, &RunOptions::default()).unwrap();
    // Steady slab between 25 and 35 °C: the effective conductivity is the material's within
    // the discretisation error (C_t calibrated on this packing), the centre near 30 °C.
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!((etc / 33.0 - 1.0).abs() < 0.05, "λ_e = {etc}");
    let centre = r
        .probes
        .iter()
        .find(|p| p.name == "centre" && p.field == "temperature")
        .unwrap()
        .value;
    assert!((centre - 30.0).abs() < 0.5, "T_centre = {centre}");
    let th = r.thermal.as_ref().unwrap();
    assert!(th.report.residual < 1e-8);
    assert!(
        th.temperatures
            .iter()
            .all(|t| t.is_finite() && (25.0 - 1e-9..=35.0 + 1e-9).contains(t))
    );
    let dir = std::env::temp_dir().join(format!("demcon-scene-test-{}", std::process::id()));
    let files = write_outputs("slab-steady", &scene.config().outputs, &r, &dir).unwrap();
    for f in [
        "particles.vtu",
        "particles.csv",
        "probes.csv",
        "profiles.csv",
        "summary.json",
    ] {
        assert!(files.iter().any(|x| x == f), "{f} not written");
        assert!(dir.join(f).metadata().unwrap().len() > 0);
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert!(summary["etc"]["lambda_e"].as_f64().unwrap() > 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unknown_field_names_the_line() {
    let text = "(\n  packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 10, phi: 0.3),\n  materals: [],\n)";
    let e = Scene::parse(text, Path::new("bad.ron"), PathBuf::new()).unwrap_err();
    match &e {
        SceneError::Parse { line, message, .. } => {
            assert_eq!(*line, 3, "{e}");
            assert!(message.contains("materals"), "{e}");
        }
        other => panic!("expected a parse error, got {other}"),
    }
}

#[test]
fn bad_values_name_the_field() {
    let base = |materials: &str, bcs: &str| {
        format!(
            "(packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 50, phi: 0.4), materials: [{materials}], \
             thermal: (bcs: [{bcs}], solver: Steady))"
        )
    };
    let good_m = "(name: \"a\", conductivity: 1.0, density: 1.0, specific_heat: 1.0)";
    let fixed = "FixedTemperature(select: Face(YMin), value: 0.0)";
    for (text, needle) in [
        (
            base(
                "(name: \"a\", conductivity: -1.0, density: 1.0, specific_heat: 1.0)",
                fixed,
            ),
            "materials[a].conductivity",
        ),
        (
            base(
                "(name: \"a\", conductivity: 1.0, density: 0.0, specific_heat: 1.0)",
                fixed,
            ),
            "materials[a].density",
        ),
        (
            base(good_m, "FixedTemperature(select: Material(\"b\"), value: 0.0)"),
            "thermal.bcs[0].select",
        ),
        (base(good_m, ""), "thermal.bcs"),
    ] {
        let e = Scene::parse(&text, Path::new("x.ron"), PathBuf::new())
            .and_then(|s| run(&s, &RunOptions::default()).map(|_| ()))
            .unwrap_err()
            .to_string();
        assert!(e.contains(needle), "expected `{needle}` in: {e}");
    }
    // A Halo ratio ≤ 0 and an unstable forced step are refused with the numbers.
    let halo = "(packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 50, phi: 0.4), \
                materials: [(name: \"a\", conductivity: 1.0, density: 1.0, specific_heat: 1.0)], \
                thermal: (bcs: [FixedTemperature(select: Face(YMin), value: 0.0)], solver: Steady), outputs: (halo: Some(0.0)))";
    let e = Scene::parse(halo, Path::new("h.ron"), PathBuf::new())
        .unwrap_err()
        .to_string();
    assert!(e.contains("outputs.halo"), "{e}");
}

#[test]
fn a_forced_unstable_step_is_refused_then_detected() {
    let scene = |allow: bool| {
        format!(
            "(packing: Generate(container: Box(size: (0.01, 0.01, 0.01)), count: 400, phi: 0.55, radius_cov: 0.3), \
             surface: TerrerosAlpha, \
             materials: [(name: \"a\", conductivity: 10.0, density: 1000.0, specific_heat: 100.0)], \
             thermal: (initial_temperature: 0.0, bcs: [FixedTemperature(select: Face(YMin), value: 0.0), \
                       FixedTemperature(select: Face(YMax), value: 100.0)], \
                       solver: Explicit(t_end: 1.0, dt: Fixed(dt: 0.5, allow_unstable: {allow}))))"
        )
    };
    let refused = Scene::parse(&scene(false), Path::new("u.ron"), PathBuf::new())
        .and_then(|s| run(&s, &RunOptions::default()).map(|_| ()))
        .unwrap_err()
        .to_string();
    assert!(refused.contains("exceeds the stability bound"), "{refused}");
    let diverged = Scene::parse(&scene(true), Path::new("u.ron"), PathBuf::new())
        .and_then(|s| run(&s, &RunOptions::default()).map(|_| ()))
        .unwrap_err()
        .to_string();
    assert!(diverged.contains("diverged"), "{diverged}");
}
