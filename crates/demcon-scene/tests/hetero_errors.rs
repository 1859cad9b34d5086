//! Bad input in heterogeneous scenes gets a clear error naming the field, the value and
//! what is allowed — never a panic: undefined materials, non-positive conductivities,
//! inclusions that cannot be placed, probes outside the domain, Halo ratios ≤ 0.

use std::path::{Path, PathBuf};

use demcon_scene::{RunOptions, Scene, SceneError, run};

/// A small two-phase scene; `phases`, `materials` and `outputs` are spliced in as RON text.
fn text(materials: &str, phases: &str, outputs: &str) -> String {
    format!(
        r#"(
    packing: Generate(container: Box(size: (0.1, 0.1, 0.1)), count: 400, phi: 0.55, radius_cov: 0.0),
    contacts: (coordination: 6.0),
    materials: [{materials}],
    phases: [{phases}],
    thermal: (
        bcs: [
            FixedTemperature(select: Face(YMin), value: 25.0),
            FixedTemperature(select: Face(YMax), value: 35.0),
        ],
        solver: Steady,
    ),
    outputs: ({outputs}),
)"#
    )
}

const TWO: &str = r#"(name: "matrix", conductivity: 33.0, density: 7800.0, specific_heat: 0.9),
                     (name: "inclusion", conductivity: 165.0, density: 7800.0, specific_heat: 0.9)"#;
const SPHERE: &str =
    r#"Region(material: "inclusion", region: Sphere(centre: (0.05, 0.05, 0.05), radius: 0.03))"#;

fn parse(t: &str) -> Result<Scene, SceneError> {
    Scene::parse(t, Path::new("hetero.ron"), PathBuf::new())
}

/// Parses and runs; returns the error text (the scene must fail).
fn error_of(t: &str) -> String {
    let e = match parse(t) {
        Err(e) => e,
        Ok(s) => match run(&s, &RunOptions::default()) {
            Err(e) => e,
            Ok(_) => panic!("the scene should have been rejected:\n{t}"),
        },
    };
    e.to_string()
}

fn assert_mentions(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "`{p}` missing from the error: {msg}");
    }
}

#[test]
fn the_valid_two_phase_scene_runs() {
    let s = parse(&text(TWO, SPHERE, "vtk: false, halo: 2.0, etc_axis: Y")).unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    assert!(r.model.report.phase_counts[1] > 0);
    assert!(r.halo.is_some() && r.etc.is_some());
    // The default Halo averages each particle over its own phase.
    assert_eq!(r.halo.as_ref().unwrap().2.phases, demcon_post::HaloPhases::Same);
}

#[test]
fn halo_phases_is_read_and_needs_a_halo() {
    let s = parse(&text(TWO, SPHERE, "vtk: false, halo: 2.0, halo_phases: All")).unwrap();
    assert_eq!(
        s.config().outputs.halo_phases,
        Some(demcon_scene::config::HaloPhasesConfig::All)
    );
    let e = parse(&text(TWO, SPHERE, "vtk: false, halo_phases: Same"))
        .unwrap_err()
        .to_string();
    assert_mentions(&e, &["outputs.halo_phases", "Same", "halo: Some(k)"]);
}

#[test]
fn a_phase_with_an_undefined_material_is_rejected_before_packing() {
    let phases =
        r#"Region(material: "unobtanium", region: Sphere(centre: (0.05, 0.05, 0.05), radius: 0.03))"#;
    let e = parse(&text(TWO, phases, "vtk: false")).unwrap_err().to_string();
    assert_mentions(&e, &["phases[0].material", "unobtanium", "matrix, inclusion"]);
    let phases = r#"Inclusions(material: "glass", fraction: 0.2, size_ratio: 6.0)"#;
    let e = parse(&text(TWO, phases, "vtk: false")).unwrap_err().to_string();
    assert_mentions(&e, &["phases[0].material", "glass"]);
}

#[test]
fn a_boundary_condition_on_an_undefined_material_is_rejected() {
    let t = text(TWO, SPHERE, "vtk: false").replace("Face(YMin)", r#"Material("copper")"#);
    let e = parse(&t).unwrap_err().to_string();
    assert_mentions(&e, &["thermal.bcs[0].select", "copper"]);
}

#[test]
fn non_positive_conductivities_are_rejected() {
    for bad in ["0.0", "-165.0"] {
        let m = TWO.replace("conductivity: 165.0", &format!("conductivity: {bad}"));
        let e = parse(&text(&m, SPHERE, "vtk: false")).unwrap_err().to_string();
        assert_mentions(
            &e,
            &["materials[inclusion].conductivity", bad.trim_end_matches(".0")],
        );
    }
}

#[test]
fn inclusions_that_cannot_be_placed_say_the_fraction_reached() {
    // Eight spheres of diameter L/2 fill a cube at f = π/6 ≈ 0.524 only in a perfect simple
    // cubic arrangement; f = 0.55 cannot be reached with walls.
    let phases = r#"Inclusions(material: "inclusion", fraction: 0.55, size_ratio: 2.0)"#;
    let e = error_of(&text(TWO, phases, "vtk: false"));
    assert_mentions(
        &e,
        &[
            "phases.Inclusions.fraction",
            "0.55",
            "could not be placed",
            "reached φ =",
        ],
    );
    // Outside the accepted range: rejected at once.
    for (f, r) in [("0.7", "6.0"), ("0.0", "6.0"), ("0.2", "0.5")] {
        let phases = format!(r#"Inclusions(material: "inclusion", fraction: {f}, size_ratio: {r})"#);
        let e = error_of(&text(TWO, &phases, "vtk: false"));
        assert_mentions(&e, &["phases.Inclusions"]);
    }
}

#[test]
fn a_probe_outside_the_domain_is_rejected_before_packing() {
    let outputs = r#"vtk: false, probes: [(name: "far", point: (0.05, 0.15, 0.05))]"#;
    let e = parse(&text(TWO, SPHERE, outputs)).unwrap_err().to_string();
    assert_mentions(
        &e,
        &["outputs.probes[0].point (far)", "0.15", "inside the domain"],
    );
}

#[test]
fn a_halo_ratio_of_zero_or_less_is_rejected() {
    for k in ["0.0", "-2.0"] {
        let e = parse(&text(TWO, SPHERE, &format!("vtk: false, halo: {k}")))
            .unwrap_err()
            .to_string();
        assert_mentions(&e, &["outputs.halo", "must be > 0"]);
    }
}
