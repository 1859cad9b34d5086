//! Shaped-inclusion phases from a scene: listed spheroids and cylinders, a shapes file, shapes
//! placed at random; what `summary.json` reports of them (count, fraction, orientation tensor,
//! the body's phase fractions); the anisotropy of aligned fibres; and every refusal by name.
//! Also each particle's phase from a labelled packing file (`x y z r label`).

use std::path::Path;

use demcon_scene::{RunOptions, Scene, SceneError, run, summary_json, write_outputs};

/// A small periodic homogenisation of a matrix `m` (λ = 1) with inclusions `f` (λ = 10); the
/// phases (and a phase rule line) are spliced in.
fn text(container: &str, phases: &str, extra: &str) -> String {
    format!(
        r#"(
    seed: 3,
    packing: Generate(container: {container}, count: 3000, phi: 0.55, radius_cov: 0.3),
    surface: Laguerre,
    materials: [
        (name: "m", conductivity: 1.0, density: 1000.0, specific_heat: 500.0),
        (name: "f", conductivity: 10.0, density: 1000.0, specific_heat: 500.0),
    ],
    phases: [{phases}],
    thermal: Some((bcs: [], solver: Homogenize)),
    outputs: (vtk: false),
    {extra}
)"#
    )
}

const PERIODIC: &str = "Periodic(size: (1.0, 1.0, 1.0))";

fn parse(t: &str, base: &Path) -> Result<Scene, SceneError> {
    Scene::parse(t, Path::new("shapes.ron"), base.to_path_buf())
}

fn error_of(t: &str, base: &Path) -> String {
    match parse(t, base) {
        Err(e) => e.to_string(),
        Ok(s) => run(&s, &RunOptions::default())
            .err()
            .map(|e| e.to_string())
            .expect("the scene must be refused"),
    }
}

fn tensor(j: &serde_json::Value) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [0, 1, 2].map(|k| j[i][k].as_f64().unwrap()))
}

#[test]
fn aligned_fibres_conduct_more_along_their_axis_and_are_reported() {
    // Four prolate spheroids along z (a = 0.3, b = 0.1), one crossing the periodic faces.
    let phases = r#"Shapes(material: "f", shapes: [
        Spheroid(centre: (0.25, 0.25, 0.5), axis: (0.0, 0.0, 2.0), a: 0.3, b: 0.1),
        Spheroid(centre: (0.75, 0.25, 0.5), axis: (0.0, 0.0, 1.0), a: 0.3, b: 0.1),
        Spheroid(centre: (0.25, 0.75, 0.5), axis: (0.0, 0.0, 1.0), a: 0.3, b: 0.1),
        Spheroid(centre: (0.75, 0.75, 0.05), axis: (0.0, 0.0, 1.0), a: 0.3, b: 0.1),
    ])"#;
    let s = parse(&text(PERIODIC, phases, ""), Path::new("")).unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let j = summary_json("s", &r);
    let t = tensor(&j["etc_tensor"]);
    assert!(t[2][2] > t[0][0] * 1.02 && t[2][2] > t[1][1] * 1.02, "{t:?}");
    assert!((t[0][0] - t[1][1]).abs() < 0.02 * t[0][0], "{t:?}");
    let sh = &j["build"]["shapes"][0];
    assert_eq!(sh["count"], 4);
    let exact = 4.0 * 4.0 / 3.0 * std::f64::consts::PI * 0.3 * 0.01;
    assert!((sh["fraction"].as_f64().unwrap() - exact).abs() < 1e-12, "{sh}");
    assert!((sh["orientation_tensor"][2][2].as_f64().unwrap() - 1.0).abs() < 1e-12);
    // The body's share of the inclusion phase follows the exact fraction (conforming cells,
    // the default with the Laguerre cells, follow the shapes).
    let carried = j["build"]["phase_fractions"][1].as_f64().unwrap();
    assert!((carried - exact).abs() < 0.1 * exact, "{carried} vs {exact}");
    assert_eq!(j["build"]["phase_rule"], "Conforming");
    // The shapes themselves for ParaView: four closed surfaces of 2 · 16 · 7 triangles each.
    let dir = std::env::temp_dir().join(format!("demcon-shapes-vtp-{}", std::process::id()));
    let mut outputs = s.config().outputs.clone();
    outputs.vtk = true;
    write_outputs("s", &outputs, &r, &dir).unwrap();
    let vtp = std::fs::read(dir.join("inclusions.vtp")).unwrap();
    let head = String::from_utf8_lossy(&vtp[..vtp.len().min(2000)]);
    assert!(head.contains("NumberOfPolys=\"896\""), "{head}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_shapes_file_equals_the_same_shapes_listed() {
    let dir = std::env::temp_dir().join(format!("demcon-shapes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("shapes.txt"),
        "# kind x y z ux uy uz a b | radius length ends\n\
         spheroid 0.3 0.3 0.5 1 0 0 0.25 0.12\n\
         cylinder, 0.7, 0.7, 0.5, 0, 1, 1, 0.1, 0.5, flat\n",
    )
    .unwrap();
    let listed = r#"Shapes(material: "f", shapes: [
        Spheroid(centre: (0.3, 0.3, 0.5), axis: (1.0, 0.0, 0.0), a: 0.25, b: 0.12),
        Cylinder(centre: (0.7, 0.7, 0.5), axis: (0.0, 1.0, 1.0), radius: 0.1, length: 0.5, ends: Flat),
    ])"#;
    let filed = r#"Shapes(material: "f", file: Some("shapes.txt"))"#;
    let a = run(
        &parse(&text(PERIODIC, listed, ""), &dir).unwrap(),
        &RunOptions::default(),
    )
    .unwrap();
    let b = run(
        &parse(&text(PERIODIC, filed, ""), &dir).unwrap(),
        &RunOptions::default(),
    )
    .unwrap();
    let (ja, jb) = (summary_json("a", &a), summary_json("b", &b));
    assert_eq!(ja["etc_tensor"], jb["etc_tensor"]);
    assert_eq!(ja["build"]["phase_fractions"], jb["build"]["phase_fractions"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn random_fibres_reach_their_fraction_and_report_the_tensor_they_drew() {
    let phases = r#"RandomShapes(material: "f", shape: Cylinder(ends: Round), aspect: 4.0, radius: 0.03,
        fraction: 0.1, min_gap: 0.005, orientation: Aligned((1.0, 0.0, 0.0)))"#;
    let s = parse(&text(PERIODIC, phases, ""), Path::new("")).unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let j = summary_json("s", &r);
    let sh = &j["build"]["shapes"][0];
    let placed = &sh["placement"];
    assert!((sh["fraction"].as_f64().unwrap() - 0.1).abs() < 0.002, "{sh}");
    assert!(placed["min_distance"].as_f64().unwrap() >= 0.005);
    assert!((sh["orientation_tensor"][0][0].as_f64().unwrap() - 1.0).abs() < 1e-12);
    let t = tensor(&j["etc_tensor"]);
    assert!(t[0][0] > t[1][1] && t[0][0] > t[2][2], "{t:?}");
    // Same scene, same seed: the same bits.
    let again = summary_json("s", &run(&s, &RunOptions::default()).unwrap());
    assert_eq!(j["etc_tensor"], again["etc_tensor"]);
    // The placed shapes are written as a shapes file, which a `Shapes` entry reads back to
    // the same microstructure, bit for bit.
    let dir = std::env::temp_dir().join(format!("demcon-random-shapes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    demcon_scene::write_outputs("s", &s.config().outputs, &r, &dir).unwrap();
    let listed = r#"Shapes(material: "f", file: Some("shapes-0.txt"), disjoint: true)"#;
    let back = parse(&text(PERIODIC, listed, ""), &dir).unwrap();
    let jb = summary_json("b", &run(&back, &RunOptions::default()).unwrap());
    assert_eq!(j["etc_tensor"], jb["etc_tensor"]);
    assert_eq!(j["build"]["phase_fractions"], jb["build"]["phase_fractions"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn shapes_thinner_than_one_and_a_half_site_spacings_are_warned_of() {
    // 3000 sites in the unit cell: h = 0.069 m.
    let one = |b: f64| {
        format!(
            r#"Shapes(material: "f", shapes: [Spheroid(centre: (0.5, 0.5, 0.5), axis: (0.0, 0.0, 1.0), a: 0.3, b: {b})])"#
        )
    };
    let warned = |phases: &str| {
        parse(&text(PERIODIC, phases, ""), Path::new(""))
            .unwrap()
            .warnings()
            .iter()
            .any(|w| w.contains("phases[0]: the thinnest shape"))
    };
    assert!(warned(&one(0.05))); // 1.44 h across
    assert!(!warned(&one(0.055))); // 1.59 h
    assert!(!warned(&one(0.1)));
    let fibres = r#"RandomShapes(material: "f", shape: Cylinder(ends: Round), aspect: 10.0, radius: 0.02, fraction: 0.1)"#;
    assert!(warned(fibres));
}

#[test]
fn thin_shapes_keep_their_volume_in_the_cells() {
    // 3000 sites in the unit cell: h = 0.069 m. A platelet 2.3 h thick (its rim's radius of
    // curvature h / 4) and a needle 1.75 h across (its tips' h / 8), along z and oblique:
    // the two faces of a thin part share its thickness, every ring closes round the axis, so
    // no pair is dropped off the tips' caps and the cells carry the shape's own volume.
    for (shape, bound) in [
        ("axis: (0.0, 0.0, 1.0), a: 0.08, b: 0.4", 0.002),
        ("axis: (0.0, 0.0, 1.0), a: 0.42, b: 0.06", 0.006),
        ("axis: (1.0, 1.0, 1.0), a: 0.42, b: 0.06", 0.006),
    ] {
        let phases =
            format!(r#"Shapes(material: "f", shapes: [Spheroid(centre: (0.5, 0.5, 0.5), {shape})])"#);
        let s = parse(&text(PERIODIC, &phases, ""), Path::new("")).unwrap();
        let j = summary_json("s", &run(&s, &RunOptions::default()).unwrap());
        let exact = j["build"]["shapes"][0]["fraction"].as_f64().unwrap();
        let carried = j["build"]["phase_fractions"][1].as_f64().unwrap();
        assert!(
            (carried / exact - 1.0).abs() < bound,
            "{shape}: {carried} vs {exact}"
        );
        assert_eq!(j["build"]["conform"]["dropped_seeds"], 0, "{shape}");
    }
}

#[test]
fn bad_shapes_are_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("demcon-bad-shapes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bad.txt"), "spheroid 0.5 0.5 0.5 1 0 0 0.2\n").unwrap();
    let one = |s: &str| format!(r#"Shapes(material: "f", shapes: [{s}])"#);
    let cases: Vec<(String, String, &str)> = vec![
        (
            one("Spheroid(centre: (0.5, 0.5, 0.5), axis: (0.0, 0.0, 0.0), a: 0.2, b: 0.1)"),
            String::new(),
            "phases[0].shapes[0].axis",
        ),
        (
            one("Spheroid(centre: (0.5, 0.5, 0.5), axis: (0.0, 0.0, 1.0), a: -0.2, b: 0.1)"),
            String::new(),
            "phases[0].shapes[0].a",
        ),
        (
            one("Cylinder(centre: (0.5, 0.5, 0.5), axis: (0.0, 0.0, 1.0), radius: 0.2, length: 0.3)"),
            String::new(),
            "phases[0].shapes[0].length",
        ),
        (
            r#"Shapes(material: "f", shapes: [])"#.into(),
            String::new(),
            "phases[0].shapes",
        ),
        (
            r#"Shapes(material: "f", file: Some("nowhere.txt"))"#.into(),
            String::new(),
            "nowhere.txt",
        ),
        (
            r#"Shapes(material: "f", file: Some("bad.txt"))"#.into(),
            String::new(),
            "bad.txt:1",
        ),
        (
            r#"RandomShapes(material: "f", shape: Spheroid, aspect: 0.0, radius: 0.05, fraction: 0.1)"#
                .into(),
            String::new(),
            "phases[0].aspect",
        ),
        (
            r#"RandomShapes(material: "f", shape: Spheroid, aspect: 2.0, radius: 0.05, fraction: 0.1,
                orientation: Tensor(((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))))"#
                .into(),
            String::new(),
            "phases[0].orientation",
        ),
        (
            r#"RandomShapes(material: "g", shape: Spheroid, aspect: 2.0, radius: 0.05, fraction: 0.1)"#
                .into(),
            String::new(),
            "phases[0].material",
        ),
    ];
    // All of these before packing: the scene does not parse.
    let before = |t: &str| {
        parse(t, &dir)
            .err()
            .map(|e| e.to_string())
            .expect("refused at parse")
    };
    for (phases, extra, field) in cases {
        let e = before(&text(PERIODIC, &phases, &extra));
        assert!(e.contains(field), "expected `{field}` in: {e}");
    }
    // Shapes that must not overlap, and do.
    let two = r#"Shapes(material: "f", disjoint: true, shapes: [
        Spheroid(centre: (0.3, 0.5, 0.5), axis: (1.0, 0.0, 0.0), a: 0.2, b: 0.1),
        Cylinder(centre: (0.55, 0.5, 0.5), axis: (0.0, 1.0, 0.0), radius: 0.1, length: 0.4),
    ])"#;
    let e = before(&text(PERIODIC, two, ""));
    assert!(
        e.contains("phases[0].shapes[1]") && e.contains("shapes[0]") && e.contains("disjoint"),
        "{e}"
    );
    assert!(
        parse(
            &text(PERIODIC, &two.replace("disjoint: true", "disjoint: false"), ""),
            &dir
        )
        .is_ok()
    );
    // Walled: a shape must lie wholly inside; random shapes need a box.
    let walled = text(
        "Box(size: (1.0, 1.0, 1.0))",
        &one("Spheroid(centre: (0.5, 0.5, 0.9), axis: (0.0, 0.0, 1.0), a: 0.2, b: 0.1)"),
        "",
    )
    .replace("bcs: [], solver: Homogenize", "bcs: [WallTemperature(face: ZMin, value: 0.0), WallTemperature(face: ZMax, value: 1.0)], solver: Steady");
    let e = before(&walled);
    assert!(e.contains("phases[0].shapes[0]") && e.contains("inside"), "{e}");
    let cylinder = text(
        "Cylinder(radius: 0.5, length: 1.0)",
        r#"RandomShapes(material: "f", shape: Spheroid, aspect: 2.0, radius: 0.05, fraction: 0.1)"#,
        "",
    )
    .replace("bcs: [], solver: Homogenize", "bcs: [WallTemperature(face: ZMin, value: 0.0), WallTemperature(face: ZMax, value: 1.0)], solver: Steady");
    let e = before(&cylinder);
    assert!(e.contains("phases[0]") && e.contains("Box or a Periodic"), "{e}");
    // A fraction random addition cannot reach: refused with the fraction reached, when the
    // scene is read (the shapes are placed then, before packing).
    let dense = text(
        PERIODIC,
        r#"RandomShapes(material: "f", shape: Cylinder(ends: Round), aspect: 10.0, radius: 0.02, fraction: 0.6)"#,
        "",
    );
    let e = parse(&dense, &dir)
        .err()
        .map(|e| e.to_string())
        .expect("refused at parse");
    assert!(e.contains("phases[0]") && e.contains("attainable"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A simple-cubic lattice of 10³ spheres in the periodic unit cell, labelled by layer: x < 0.5
/// `m`, the others `f` (by name) or `1` (by index); the Laguerre cells are cubes, so the layers
/// conduct exactly: in series along x, in parallel across.
#[test]
fn phases_come_from_a_labelled_packing_file() {
    let dir = std::env::temp_dir().join(format!("demcon-labels-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut text = String::from("# container periodic 1 1 1\n");
    let h = 1.0 / 10.0;
    for i in 0..10 {
        for j in 0..10 {
            for k in 0..10 {
                let label = match (i < 5, (i + j + k) % 2) {
                    (true, _) => "m",
                    (false, 0) => "f",
                    (false, _) => "1",
                };
                let c = [i, j, k].map(|v| (v as f64 + 0.5) * h);
                text.push_str(&format!("{} {} {} {} {label}\n", c[0], c[1], c[2], 0.5 * h));
            }
        }
    }
    std::fs::write(dir.join("layers.xyzr"), &text).unwrap();
    let scene = r#"(
    packing: File(path: "layers.xyzr"),
    surface: Laguerre,
    materials: [
        (name: "m", conductivity: 1.0, density: 1000.0, specific_heat: 500.0),
        (name: "f", conductivity: 10.0, density: 1000.0, specific_heat: 500.0),
    ],
    thermal: Some((bcs: [], solver: Homogenize)),
    outputs: (vtk: false),
)"#;
    let r = run(&parse(scene, &dir).unwrap(), &RunOptions::default()).unwrap();
    let j = summary_json("labels", &r);
    let t = tensor(&j["etc_tensor"]);
    let (series, parallel) = (2.0 / (1.0 + 0.1), 5.5);
    assert!((t[0][0] - series).abs() < 1e-9 * series, "{t:?}");
    assert!((t[1][1] - parallel).abs() < 1e-9 * parallel, "{t:?}");
    assert_eq!(j["build"]["phase_counts"], serde_json::json!([500, 500]));
    // An unknown label is refused naming the file, the line and the label.
    std::fs::write(
        dir.join("bad.xyzr"),
        "# container periodic 1 1 1\n0.5 0.5 0.5 0.1 glass\n",
    )
    .unwrap();
    let e = error_of(&scene.replace("layers.xyzr", "bad.xyzr"), &dir);
    assert!(
        e.contains("bad.xyzr:2") && e.contains("glass") && e.contains("packing.path"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
