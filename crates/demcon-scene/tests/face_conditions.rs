//! Face conditions through the scene — convection, radiation, time tables: what is refused
//! when the scene is read, and the heat balance of a run under each surface model.

use std::path::PathBuf;

use demcon_scene::{RunOptions, Scene, SceneError, run};

fn scene(surface: &str, bcs: &str, outputs: &str) -> String {
    scene_with(surface, bcs, "Steady", outputs)
}

fn scene_with(surface: &str, bcs: &str, solver: &str, outputs: &str) -> String {
    format!(
        r#"(
    packing: Generate(container: Box(size: (0.02, 0.01, 0.01)), count: 1500, phi: 0.55, radius_cov: 0.3),
    surface: {surface},
    materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0)],
    thermal: (bcs: [{bcs}], solver: {solver}),
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
            vec!["thermal.bcs[1].h", "-1", "> 0"],
        ),
        (
            "Convection(face: XMax, h: 0.0, t_inf: 20.0)",
            vec!["thermal.bcs[1].h", "adiabatic"],
        ),
        (
            "Radiation(face: XMax, emissivity: 0.0, t_surroundings: 20.0)",
            vec!["thermal.bcs[1].emissivity", "(0, 1]"],
        ),
        (
            "Convection(face: XMax, h: 10.0, t_inf: -300.0)",
            vec!["thermal.bcs[1].t_inf", "-300", "absolute zero"],
        ),
        (
            "Radiation(face: XMax, emissivity: 1.5, t_surroundings: 20.0)",
            vec!["thermal.bcs[1].emissivity", "1.5", "(0, 1]"],
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
        let faces = &th.report.faces;
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

const IMPLICIT: &str = "Implicit(t_end: 10.0, dt: 0.5)";

#[test]
fn bad_time_tables_are_refused_by_field_and_point() {
    let cases = [
        // A table in a steady solve.
        (
            "Steady",
            "WallTemperature(face: XMin, value: [(0.0, 20.0), (10.0, 30.0)])",
            vec!["thermal.bcs[0].value", "steady"],
        ),
        // Not covering [0, t_end].
        (
            IMPLICIT,
            "WallTemperature(face: XMin, value: [(0.0, 20.0), (5.0, 30.0)])",
            vec!["thermal.bcs[0].value", "[0, 10]"],
        ),
        (
            IMPLICIT,
            "HeatFlux(face: XMin, flux: [(1.0, 20.0), (10.0, 30.0)])",
            vec!["thermal.bcs[0].flux", "[0, 10]"],
        ),
        // Times out of order, three points at one time, empty.
        (
            IMPLICIT,
            "WallTemperature(face: XMin, value: [(0.0, 1.0), (8.0, 2.0), (4.0, 3.0), (10.0, 1.0)])",
            vec!["thermal.bcs[0].value[2]", "increasing"],
        ),
        (
            IMPLICIT,
            "Convection(face: XMin, h: 5.0, t_inf: [(0.0, 1.0), (0.0, 2.0), (0.0, 3.0), (10.0, 1.0)])",
            vec!["thermal.bcs[0].t_inf[2]", "at most two"],
        ),
        (
            IMPLICIT,
            "WallTemperature(face: XMin, value: [])",
            vec!["thermal.bcs[0].value", "at least one"],
        ),
        // A fluid colder than absolute zero at some time.
        (
            IMPLICIT,
            "Convection(face: XMin, h: 5.0, t_inf: [(0.0, 20.0), (10.0, -300.0)])",
            vec!["thermal.bcs[0].t_inf", "absolute zero"],
        ),
    ];
    for (solver, bc, parts) in cases {
        let m = refused(&scene_with("Laguerre", bc, solver, ""));
        for p in parts {
            assert!(m.contains(p), "`{p}` missing from: {m}");
        }
    }
    // A source table in a steady solve.
    let text = scene("Laguerre", "WallTemperature(face: XMin, value: 0.0)", "").replace(
        "solver: Steady)",
        "sources: [(select: All, power_density: [(0.0, 1.0), (1.0, 2.0)])], solver: Steady)",
    );
    let m = refused(&text);
    assert!(m.contains("thermal.sources[0].power_density"), "{m}");
}

#[test]
fn a_held_face_following_a_table_drives_the_body_and_its_heat_balances() {
    // The face steps from 0 to 100 °C at t = 1 s; the run lands a step on it
    // (`times_at_breakpoints`), the body heats, and the stored heat is what the face gave.
    let bc = "WallTemperature(face: XMin, value: [(0.0, 0.0), (1.0, 0.0), (1.0, 100.0), (10.0, 100.0)])";
    let text = scene_with("Laguerre", bc, IMPLICIT, "times_at_breakpoints: true");
    let r = run(&parse(&text).unwrap(), &RunOptions::default()).unwrap();
    let th = r.thermal.as_ref().unwrap();
    assert_eq!(
        th.snapshots.len(),
        1,
        "{:?}",
        th.snapshots.iter().map(|s| s.0).collect::<Vec<_>>()
    );
    assert_eq!(th.snapshots[0].0, 1.0);
    // Before the step nothing moved; after it the body warmed, never above the held value.
    assert!(th.snapshots[0].1.iter().all(|&t| t == 0.0));
    let (lo, hi) = th
        .temperatures
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
            (a.min(t), b.max(t))
        });
    assert!(lo >= 0.0 && hi > 1.0 && hi < 100.0, "{lo} … {hi}");
    assert!(th.report.energy_balance_error < 1e-9, "{:?}", th.report);
    let face = &th.report.faces[0];
    assert!(face.held_w < 0.0, "heat enters through the held face: {face:?}");
    assert_eq!(face.surface_temperature, [100.0, 100.0]);
}

#[test]
fn a_tensor_that_is_not_symmetric_positive_definite_and_a_current_without_two_electrodes_are_refused() {
    let with_tensor = |t: &str| {
        scene("Laguerre", HOT, "").replace(
            "specific_heat: 500.0)",
            &format!("specific_heat: 500.0, conductivity_tensor: Some({t}))"),
        )
    };
    let m = refused(&with_tensor(
        "Full(((1.0, 0.5, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)))",
    ));
    assert!(
        m.contains("conductivity_tensor") && m.contains("symmetric"),
        "{m}"
    );
    let m = refused(&with_tensor(
        "Full(((1.0, 2.0, 0.0), (2.0, 1.0, 0.0), (0.0, 0.0, 1.0)))",
    ));
    assert!(
        m.contains("conductivity_tensor") && m.contains("positive definite"),
        "{m}"
    );
    let m = refused(&with_tensor(
        "Transverse(axis: (0.0, 0.0, 0.0), along: 2.0, across: 1.0)",
    ));
    assert!(m.contains("conductivity_tensor"), "{m}");
    parse(&with_tensor(
        "Transverse(axis: (0.0, 0.0, 3.0), along: 2.0, across: 1.0)",
    ))
    .unwrap();
    // An imposed current needs exactly two electrodes.
    let electric = |electrodes: &str| {
        scene("Laguerre", HOT, "")
            .replace(
                "specific_heat: 500.0)",
                "specific_heat: 500.0, resistivity: Some(1e-6))",
            )
            .replace(
                "    outputs:",
                &format!(
                    "    electric: Some((electrodes: [{electrodes}], current: Some(2.0))),\n    outputs:"
                ),
            )
    };
    let m = refused(&electric(
        "(face: Some(XMin), potential: 0.0), (face: Some(XMax), potential: 0.0), (face: Some(YMin), potential: 1.0)",
    ));
    assert!(m.contains("electric.current") && m.contains("exactly two"), "{m}");
    parse(&electric(
        "(face: Some(XMin), potential: 0.0), (face: Some(XMax), potential: 0.0)",
    ))
    .unwrap();
}

#[test]
fn the_face_laws_tables_grain_boundaries_and_lambda_t_give_the_same_bits_on_one_and_two_threads() {
    // A transient with a convecting and radiating face, a tabled held face, λ(T) and grain
    // boundaries with a spread: every new source of nonlinearity and randomness at once.
    let text = scene_with(
        "Laguerre",
        "WallTemperature(face: XMin, value: [(0.0, 20.0), (0.0, 300.0), (10.0, 400.0)]), \
         Convection(face: XMax, h: 500.0, t_inf: 20.0), Radiation(face: XMax, emissivity: 0.8, t_surroundings: 0.0)",
        "Implicit(t_end: 10.0, dt: 0.5)",
        "",
    )
    .replace(
        "specific_heat: 500.0)",
        "specific_heat: 500.0, conductivity_temp_coeff: -5e-4)",
    )
    .replace(
        "    thermal:",
        "    grain_boundaries: [(material: \"steel\", conductance: 1e6, spread: Some(0.3))],\n    thermal:",
    );
    let scene = parse(&text).unwrap();
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| run(&scene, &RunOptions::default()).unwrap())
    };
    let (a, b) = (on(1), on(2));
    let bits = |r: &demcon_scene::RunResult| -> Vec<u64> {
        r.thermal
            .as_ref()
            .unwrap()
            .temperatures
            .iter()
            .map(|t| t.to_bits())
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    assert!(
        a.thermal
            .as_ref()
            .unwrap()
            .temperatures
            .iter()
            .any(|&t| t > 100.0)
    );
}

#[test]
fn the_etc_of_a_body_with_lambda_t_is_read_from_the_end_states_conductances() {
    // λ = 33 (1 − 0.002 T) between 100 °C and 0 °C: Kirchhoff gives λ_e = λ(50 °C) = 29.7.
    let bcs = "WallTemperature(face: XMin, value: 100.0), WallTemperature(face: XMax, value: 0.0)";
    let text = scene("Laguerre", bcs, "etc_axis: Some(X)").replace(
        "specific_heat: 500.0)",
        "specific_heat: 500.0, conductivity_temp_coeff: -2e-3, conductivity_ref_temp: 0.0)",
    );
    let r = run(&parse(&text).unwrap(), &RunOptions::default()).unwrap();
    let e = r.etc.as_ref().unwrap();
    assert!((e.lambda_e / 29.7 - 1.0).abs() < 1e-3, "{e:?}");
    assert!((e.hot_flow_w / e.cold_flow_w - 1.0).abs() < 1e-6, "{e:?}");
}

/// A carved rod in a box: its carved surface convects the heat of a uniform source away.
fn carved_rod(surface: &str, carve: &str, face: &str) -> String {
    format!(
        r#"(
    packing: Generate(container: Box(size: (0.012, 0.012, 0.01)), count: 3000, phi: 0.55, radius_cov: 0.3),
    surface: {surface},
    carve_rule: Centre,
    {carve}
    materials: [(name: "rod", conductivity: 10.0, density: 1000.0, specific_heat: 1000.0)],
    thermal: (
        initial_temperature: 20.0,
        bcs: [Convection(face: {face}, h: 1000.0, t_inf: 20.0)],
        sources: [(select: All, power_density: 1.0e6)],
        solver: Steady,
    ),
    outputs: (vtk: false),
)"#
    )
}

const ROD: &str = "carve: Some(Cylinder(base: (0.006, 0.006, 0.0), axis: Z, radius: 0.005, length: 0.01)),";

#[test]
fn the_carved_surface_is_a_face_only_of_a_carved_body_under_laguerre_cells() {
    let m = refused(&carved_rod("Laguerre", "", "Carved"));
    assert!(m.contains("thermal.bcs[0].face") && m.contains("carve"), "{m}");
    let m = refused(&carved_rod("TerrerosAlpha", ROD, "Carved"));
    assert!(m.contains("thermal.bcs[0].face") && m.contains("Laguerre"), "{m}");
}

#[test]
fn a_carved_surface_convects_what_the_body_generates() {
    let scene = parse(&carved_rod("Laguerre", ROD, "Carved")).unwrap();
    let r = run(&scene, &RunOptions::default()).unwrap();
    let th = r.thermal.as_ref().unwrap();
    let face = &th.report.faces[0];
    assert_eq!(face.face, "Carved");
    // The heat generated in the rod, q V, leaves through its carved surface (V: the cells'
    // volumes, which miss the rod's by the tangent planes' tolerance, ~10⁻⁵).
    let generated = 1.0e6 * std::f64::consts::PI * 0.005f64.powi(2) * 0.01;
    assert!((face.convection_w / generated - 1.0).abs() < 1e-4, "{face:?}");
    // The cells' facets on the surface make up its area (2πRL) to the tolerance of their
    // tangent planes.
    let area = 2.0 * std::f64::consts::PI * 0.005 * 0.01;
    assert!((face.area_m2 / area - 1.0).abs() < 1e-3, "{face:?}");
}

/// A periodic cell with three fibres along `dir` (a unit axis), homogenised; the fibres'
/// material is `tensor`, read in each fibre's frame when `in_frame`.
fn fibres(dir: (f64, f64, f64), tensor: &str, in_frame: bool) -> String {
    let (x, y, z) = dir;
    let fibre = |c: (f64, f64, f64)| {
        format!(
            "Cylinder(centre: ({}, {}, {}), axis: ({x}, {y}, {z}), radius: 0.0015, length: 0.006, ends: Round)",
            c.0, c.1, c.2
        )
    };
    format!(
        r#"(
    seed: 4,
    packing: Generate(container: Periodic(size: (0.01, 0.01, 0.01)), count: 3000, phi: 0.55, radius_cov: 0.3),
    surface: Laguerre,
    materials: [
        (name: "matrix", conductivity: 1.0, density: 1000.0, specific_heat: 1000.0),
        (name: "fibre", conductivity: 1.0, density: 1000.0, specific_heat: 1000.0,
         conductivity_tensor: Some({tensor}), tensor_in_shape_frame: {in_frame}),
    ],
    phases: [Shapes(material: "fibre", shapes: [{}, {}, {}])],
    thermal: (bcs: [], solver: Homogenize),
    outputs: (vtk: false),
)"#,
        fibre((0.005, 0.005, 0.005)),
        fibre((0.002, 0.0075, 0.003)),
        fibre((0.0078, 0.002, 0.0075)),
    )
}

fn thermal_tensor(text: &str) -> [[f64; 3]; 3] {
    let r = run(&parse(text).unwrap(), &RunOptions::default()).unwrap();
    r.homogenization.unwrap().thermal.unwrap().report.tensor
}

#[test]
fn a_tensor_in_the_shapes_frame_turns_with_each_shape() {
    // Fibres along x: a tensor about z in their frame is the tensor about x in the scene's.
    let along_z = "Transverse(axis: (0.0, 0.0, 1.0), along: 20.0, across: 2.0)";
    let along_x = "Transverse(axis: (1.0, 0.0, 0.0), along: 20.0, across: 2.0)";
    let framed = thermal_tensor(&fibres((1.0, 0.0, 0.0), along_z, true));
    let global = thermal_tensor(&fibres((1.0, 0.0, 0.0), along_x, false));
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (framed[i][j] - global[i][j]).abs() <= 1e-9 * global[0][0],
                "{framed:?} vs {global:?}"
            );
        }
    }
    // Along x the fibres conduct better than across.
    assert!(global[0][0] > 1.05 * global[1][1], "{global:?}");
    // A material no shape is made of has no shape's frame.
    let text = fibres((1.0, 0.0, 0.0), along_z, true)
        .replace(r#"Shapes(material: "fibre""#, r#"Shapes(material: "matrix""#);
    let m = refused(&text);
    assert!(m.contains("materials[1].tensor_in_shape_frame"), "{m}");
    // An isotropic material has no tensor to turn.
    let text = fibres((1.0, 0.0, 0.0), along_z, true)
        .replace(&format!("conductivity_tensor: Some({along_z}), "), "");
    let m = refused(&text);
    assert!(
        m.contains("tensor_in_shape_frame") && m.contains("conductivity_tensor"),
        "{m}"
    );
}
