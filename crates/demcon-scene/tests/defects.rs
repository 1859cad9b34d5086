//! Interfaces, cracks, damage and broken bonds in a scene: a valid scene with all of them
//! runs (and its Halo does not average across the crack); every bad value gets a clear error
//! naming its field before any packing — unknown material in `between`, a zero or negative
//! conductance, a crack of zero radius or a degenerate polygon, a damage factor outside
//! (0, 1], a broken-bond file with indices out of range or a bad line — and a crack outside
//! the domain is reported, not refused.

use std::path::{Path, PathBuf};

use demcon_scene::{RunOptions, Scene, SceneError, run};

/// A small two-phase scene with `defects` spliced in at the top level (RON text).
fn text(defects: &str, electric: bool) -> String {
    let electric = if electric {
        "electric: (electrodes: [(face: YMin, potential: 0.0), (face: YMax, potential: 1.0)], surface: Laguerre, eta: 0.0),"
    } else {
        ""
    };
    format!(
        r#"(
    packing: Generate(container: Box(size: (0.1, 0.1, 0.1)), count: 600, phi: 0.55, radius_cov: 0.2),
    surface: Laguerre,
    materials: [
        (name: "epoxy", conductivity: 0.2, density: 1200.0, specific_heat: 1000.0, resistivity: Some(1.0)),
        (name: "silica", conductivity: 1.4, density: 2200.0, specific_heat: 700.0, resistivity: Some(10.0)),
    ],
    phases: [Region(material: "silica", region: Sphere(centre: (0.05, 0.05, 0.05), radius: 0.03))],
    {defects}
    thermal: (
        bcs: [WallTemperature(face: YMin, value: 0.0), WallTemperature(face: YMax, value: 1.0)],
        solver: Steady,
    ),
    {electric}
    outputs: (vtk: false, halo: Some(3.0), etc_axis: Some(Y)),
)"#
    )
}

fn parse_in(t: &str, dir: &Path) -> Result<Scene, SceneError> {
    Scene::parse(t, &dir.join("defects.ron"), dir.to_path_buf())
}

fn parse(t: &str) -> Result<Scene, SceneError> {
    parse_in(t, &PathBuf::new())
}

fn error_of(t: &str) -> String {
    match parse(t) {
        Err(e) => e.to_string(),
        Ok(s) => match run(&s, &RunOptions::default()) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("the scene should have been rejected:\n{t}"),
        },
    }
}

fn assert_mentions(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "`{p}` missing from the error: {msg}");
    }
}

/// A fresh folder for the broken-bond files of one test.
fn folder(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("demcon-defects-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const ALL: &str = r#"
    interfaces: [(between: ("epoxy", "silica"), conductance: 50.0, electric_resistance: Some(1.0e-4))],
    cracks: [
        Disc(centre: (0.05, 0.08, 0.05), normal: (0.0, 1.0, 0.0), radius: 0.015),
        Polygon(points: [(0.0, 0.02, 0.0), (0.03, 0.02, 0.0), (0.03, 0.02, 0.03)], gap_conductance: Some(100.0),
                gap_electric_resistance: Some(0.01)),
    ],
    damage: [(region: Box(min: (0.0, 0.0, 0.0), max: (0.1, 0.03, 0.1)), factor: 0.5)],
    cut_contacts: Some(File("pairs.txt")),
"#;

#[test]
fn a_scene_with_every_defect_runs_and_reports_them() {
    let dir = folder("all");
    std::fs::write(
        dir.join("pairs.txt"),
        "# broken bonds\n0 1\n2, 3\n\n5 4 # comment\n",
    )
    .unwrap();
    let s = parse_in(&text(ALL, true), &dir).unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let d = r.model.report.defects.as_ref().unwrap();
    assert!(d.cut_by_cracks > 0 && d.filled_crack_contacts > 0, "{d:?}");
    assert!(d.damaged_contacts > 0 && d.interface_contacts > 0, "{d:?}");
    assert_eq!(d.broken_bonds + d.broken_not_contacts, 3);
    assert_eq!(r.model.contact_marks().len(), r.model.graph.len());
    assert!(!r.model.crack_face_particles().is_empty());
    assert!(
        r.diagnostics.iter().any(|m| m.contains("cut by cracks")),
        "{:?}",
        r.diagnostics
    );
    // Less heat and less current than without the defects.
    let plain = parse(&text("", true)).unwrap();
    let p = run(&plain, &RunOptions::default()).unwrap();
    assert!(r.etc.as_ref().unwrap().heat_flow_w < p.etc.as_ref().unwrap().heat_flow_w);
    let res = |x: &demcon_scene::RunResult| x.electric.as_ref().unwrap().report.resistance_ohm.unwrap();
    assert!(res(&r) > res(&p));
    // The Halo leaves out the members behind the crack: fewer members on average.
    assert!(r.halo.as_ref().unwrap().2.mean_members < p.halo.as_ref().unwrap().2.mean_members);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_unknown_material_in_between_names_the_known_ones() {
    let e = error_of(&text(
        r#"interfaces: [(between: ("epoxy", "epoxi"), conductance: 1.0e6)],"#,
        false,
    ));
    assert_mentions(
        &e,
        &[
            "interfaces[0].between[1]",
            "\"epoxi\"",
            "unknown material; known: epoxy, silica",
        ],
    );
}

#[test]
fn zero_or_negative_conductances_are_refused() {
    for v in ["0.0", "-5.0"] {
        let e = error_of(&text(
            &format!(r#"interfaces: [(between: ("epoxy", "silica"), conductance: {v})],"#),
            false,
        ));
        assert_mentions(&e, &["interfaces[0].conductance", "> 0"]);
    }
    let e = error_of(&text(
        r#"interfaces: [(between: ("epoxy", "silica"), conductance: 1.0, electric_resistance: Some(-1.0))],"#,
        false,
    ));
    assert_mentions(&e, &["interfaces[0].electric_resistance"]);
    let e = error_of(&text(
        r#"interfaces: [(between: ("epoxy", "epoxy"), conductance: 1.0)],"#,
        false,
    ));
    assert_mentions(&e, &["interfaces[0].between", "two different materials"]);
    let e = error_of(&text(
        r#"interfaces: [(between: ("epoxy", "silica"), conductance: 1.0), (between: ("silica", "epoxy"), conductance: 2.0)],"#,
        false,
    ));
    assert_mentions(&e, &["interfaces[1].between", "interfaces[0]"]);
    let e = error_of(&text(
        r#"cracks: [Disc(centre: (0.05, 0.05, 0.05), normal: (0.0, 1.0, 0.0), radius: 0.01, gap_conductance: Some(0.0))],"#,
        false,
    ));
    assert_mentions(&e, &["cracks[0].gap_conductance"]);
}

#[test]
fn degenerate_cracks_are_refused() {
    let e = error_of(&text(
        r#"cracks: [Disc(centre: (0.05, 0.05, 0.05), normal: (0.0, 1.0, 0.0), radius: 0.0)],"#,
        false,
    ));
    assert_mentions(&e, &["cracks[0].radius", "> 0"]);
    let e = error_of(&text(
        r#"cracks: [Disc(centre: (0.05, 0.05, 0.05), normal: (0.0, 0.0, 0.0), radius: 0.01)],"#,
        false,
    ));
    assert_mentions(&e, &["cracks[0].normal"]);
    let e = error_of(&text(
        r#"cracks: [Polygon(points: [(0.0, 0.0, 0.0), (0.01, 0.01, 0.01), (0.02, 0.02, 0.02)])],"#,
        false,
    ));
    assert_mentions(&e, &["cracks[0].points", "non-zero area"]);
    let e = error_of(&text(
        r#"cracks: [Polygon(points: [(0.0, 0.0, 0.0), (0.01, 0.0, 0.0)])],"#,
        false,
    ));
    assert_mentions(&e, &["cracks[0].points", "at least 3"]);
}

#[test]
fn a_filled_crack_needs_its_electric_resistance_in_an_electric_scene() {
    let crack = r#"cracks: [Disc(centre: (0.05, 0.05, 0.05), normal: (0.0, 1.0, 0.0), radius: 0.01, gap_conductance: Some(10.0))],"#;
    let e = error_of(&text(crack, true));
    assert_mentions(&e, &["cracks[0].gap_electric_resistance"]);
    assert!(parse(&text(crack, false)).is_ok());
}

#[test]
fn damage_factors_outside_zero_one_are_refused() {
    for f in ["0.0", "1.5", "-0.3"] {
        let e = error_of(&text(
            &format!("damage: [(region: Sphere(centre: (0.05, 0.05, 0.05), radius: 0.02), factor: {f})],"),
            false,
        ));
        assert_mentions(&e, &["damage[0].factor", "(0, 1]"]);
    }
}

#[test]
fn broken_bond_files_are_checked_before_packing() {
    let dir = folder("bad");
    std::fs::write(dir.join("range.txt"), "0 1\n600 2\n").unwrap();
    let t = text(r#"cut_contacts: Some(File("range.txt")),"#, false);
    let e = parse_in(&t, &dir).unwrap_err().to_string();
    assert_mentions(&e, &["cut_contacts[1][0]", "600", "0..600"]);
    std::fs::write(dir.join("line.txt"), "0 1\n2 x\n").unwrap();
    let t = text(r#"cut_contacts: Some(File("line.txt")),"#, false);
    let e = parse_in(&t, &dir).unwrap_err().to_string();
    assert_mentions(&e, &["line.txt:2", "two particle indices"]);
    let t = text(r#"cut_contacts: Some(File("missing.txt")),"#, false);
    let e = parse_in(&t, &dir).unwrap_err().to_string();
    assert_mentions(&e, &["missing.txt"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_crack_outside_the_domain_is_reported_not_refused() {
    let s = parse(&text(
        r#"cracks: [Disc(centre: (1.0, 1.0, 1.0), normal: (0.0, 1.0, 0.0), radius: 0.01)],"#,
        false,
    ))
    .unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    assert!(
        r.diagnostics
            .iter()
            .any(|m| m.contains("cracks[0] crosses no contact")),
        "{:?}",
        r.diagnostics
    );
}

#[test]
fn the_example_scene_runs_shrunk() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cracked-inclusion.ron");
    let s = Scene::load(&path)
        .unwrap()
        .edit(|c| {
            if let demcon_scene::config::PackingConfig::Generate { count, phi, .. } = &mut c.packing {
                *count = 3000;
                *phi = 0.64 - 0.5 * 3000f64.powf(-1.0 / 3.0);
            }
            c.outputs.vtk = false;
        })
        .unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let d = r.model.report.defects.as_ref().unwrap();
    assert!(
        d.cut_by_cracks > 0 && d.interface_contacts > 0 && d.damaged_contacts > 0,
        "{d:?}"
    );
    assert_eq!(d.broken_bonds + d.broken_not_contacts, 4);
    // The two probes sit on either side of the crack: a jump between them.
    let t = |name: &str| {
        r.probes
            .iter()
            .find(|p| p.name == name && p.field == "temperature")
            .unwrap()
            .value
    };
    assert!(t("above-crack") > t("below-crack"));
}
