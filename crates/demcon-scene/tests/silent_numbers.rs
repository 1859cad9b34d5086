//! Issue 31's examples of a plausible wrong number printed with exit 0, each as a test: the
//! right number, a refusal naming the field (before any packing where the scene alone shows
//! it), or a warning in the run's diagnostics. Small Laguerre scenes of steel (λ = 33
//! W/(m·K)), 2000 particles, whose exact answers hold to round-off.

use std::path::PathBuf;

use demcon_scene::{RunOptions, RunResult, Scene, SceneError, run};

const STEEL: &str = r#"(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0, resistivity: Some(1.0e-6))"#;

/// A 2000-particle scene in a 0.1 × 0.05 × 0.2 m box: `body` is spliced in at the top level
/// (carving, phases…), `thermal` and `outputs` are the two sections' contents.
fn scene_text(container: &str, body: &str, thermal: &str, outputs: &str) -> String {
    format!(
        r#"(
    packing: Generate(container: {container}, count: 2000, phi: 0.55, radius_cov: 0.3),
    materials: [{STEEL}],
    {body}
    thermal: ({thermal}),
    outputs: (vtk: false, {outputs}),
)"#
    )
}

const BOX: &str = "Box(size: (0.1, 0.05, 0.2))";

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, &PathBuf::from("silent.ron"), PathBuf::new())
}

fn run_text(text: &str) -> Result<RunResult, SceneError> {
    run(&parse(text)?, &RunOptions::default())
}

/// The message of a scene refused when it is read (before packing).
fn refused_on_reading(text: &str) -> String {
    match parse(text) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("the scene should be refused before packing:\n{text}"),
    }
}

fn assert_mentions(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "`{p}` missing from: {msg}");
    }
}

const WALLS_Y: &str = "bcs: [WallTemperature(face: YMin, value: 20.0), WallTemperature(face: YMax, value: 30.0)], solver: Steady";

#[test]
fn the_etc_between_held_faces_is_exact_and_reports_what_it_used() {
    let r = run_text(&scene_text(BOX, "", WALLS_Y, "etc_axis: Some(Y)")).unwrap();
    let e = r.etc.as_ref().unwrap();
    assert!((e.lambda_e / 33.0 - 1.0).abs() < 1e-9, "{e:?}");
    assert!((e.length_m - 0.05).abs() < 1e-15, "{e:?}");
    assert!((e.area_m2 / (0.1 * 0.2) - 1.0).abs() < 1e-9, "{e:?}");
    assert!((e.hot_flow_w / e.cold_flow_w - 1.0).abs() < 1e-8, "{e:?}");
    assert!(e.warnings.is_empty(), "{e:?}");
}

#[test]
fn an_etc_axis_the_held_faces_are_not_normal_to_is_refused() {
    // Walls on X, etc_axis Y: the container's Y section and length gave 8.25 for 33.
    let walls_x = "bcs: [WallTemperature(face: XMin, value: 20.0), WallTemperature(face: XMax, value: 30.0)], solver: Steady";
    let m = refused_on_reading(&scene_text(BOX, "", walls_x, "etc_axis: Some(Y)"));
    assert_mentions(&m, &["outputs.etc_axis", "XMin", "not normal to Y"]);
    // Held particles of the X faces (FixedTemperature) with etc_axis Y.
    let held_x = "bcs: [FixedTemperature(select: Face(XMin), value: 20.0), FixedTemperature(select: Face(XMax), value: 30.0)], solver: Steady";
    let m = refused_on_reading(&scene_text(BOX, "", held_x, "etc_axis: Some(Y)"));
    assert_mentions(&m, &["outputs.etc_axis", "not normal to Y"]);
    // Held regions that do not face each other along Y: found once the particles exist.
    let slabs = "bcs: [FixedTemperature(select: Region(Box(min: (0.0, 0.0, 0.0), max: (0.02, 0.05, 0.2))), value: 20.0), \
                 FixedTemperature(select: Region(Box(min: (0.08, 0.0, 0.0), max: (0.1, 0.05, 0.2))), value: 30.0)], solver: Steady";
    let m = run_text(&scene_text(BOX, "", slabs, "etc_axis: Some(Y)"))
        .unwrap_err()
        .to_string();
    assert_mentions(&m, &["outputs.etc_axis", "do not face each other along Y"]);
}

#[test]
fn the_etc_of_a_carved_body_uses_its_own_section() {
    // The body is the half x < 0.05 of the box: the container's section gave 16.5 for 33.
    let carve = "carve: Some(Box(min: (0.0, 0.0, 0.0), max: (0.05, 0.05, 0.2))), carve_rule: Centre,";
    let r = run_text(&scene_text(BOX, carve, WALLS_Y, "etc_axis: Some(Y)")).unwrap();
    let e = r.etc.as_ref().unwrap();
    assert!((e.lambda_e / 33.0 - 1.0).abs() < 1e-9, "{e:?}");
    assert!((e.area_m2 / (0.05 * 0.2) - 1.0).abs() < 1e-9, "{e:?}");
    // A carving box larger than the container: the body is the container (4.0 m³ before).
    let big = "carve: Some(Box(min: (-1.0, -1.0, -1.0), max: (1.0, 1.0, 1.0))), carve_rule: Centre,";
    let r = run_text(&scene_text(BOX, big, WALLS_Y, "etc_axis: Some(Y)")).unwrap();
    assert!((r.model.domain_volume / (0.1 * 0.05 * 0.2) - 1.0).abs() < 1e-12);
    assert!(r.model.phi > 0.3 && r.model.phi < 0.7, "φ = {}", r.model.phi);
    assert!((r.etc.unwrap().lambda_e / 33.0 - 1.0).abs() < 1e-9);
}

#[test]
fn the_etc_of_a_periodic_box_is_refused() {
    let slabs = "bcs: [FixedTemperature(select: Region(Box(min: (0.0, 0.0, 0.0), max: (0.1, 0.01, 0.2))), value: 20.0), \
                 FixedTemperature(select: Region(Box(min: (0.0, 0.03, 0.0), max: (0.1, 0.04, 0.2))), value: 30.0)], solver: Steady";
    let m = refused_on_reading(&scene_text(
        "Periodic(size: (0.1, 0.05, 0.2))",
        "",
        slabs,
        "etc_axis: Some(Y)",
    ));
    assert_mentions(&m, &["outputs.etc_axis", "periodic", "Homogenize"]);
}

#[test]
fn the_etc_with_heat_added_inside_is_refused() {
    let src = format!("{WALLS_Y}, sources: [(select: All, power_density: 1e5)]");
    let m = refused_on_reading(&scene_text(BOX, "", &src, "etc_axis: Some(Y)"));
    assert_mentions(&m, &["outputs.etc_axis", "thermal.sources"]);
    let flux = "bcs: [WallTemperature(face: YMin, value: 20.0), WallTemperature(face: YMax, value: 30.0), \
                HeatFlux(face: XMin, flux: 100.0)], solver: Steady";
    let m = refused_on_reading(&scene_text(BOX, "", flux, "etc_axis: Some(Y)"));
    assert_mentions(&m, &["outputs.etc_axis", "thermal.bcs[2]", "heat flux"]);
    let joule = scene_text(
        BOX,
        "electric: (electrodes: [(face: ZMin, potential: 0.0), (face: ZMax, potential: 0.01)]),",
        WALLS_Y,
        "etc_axis: Some(Y)",
    );
    let m = refused_on_reading(&joule);
    assert_mentions(&m, &["outputs.etc_axis", "Joule", "eta"]);
    // With eta: 0.0 the electric physics adds no heat: the ETC is the body's again.
    let cold = joule.replace("potential: 0.01)]", "potential: 0.01)], eta: 0.0");
    let r = run_text(&cold).unwrap();
    assert!((r.etc.unwrap().lambda_e / 33.0 - 1.0).abs() < 1e-9);
}

#[test]
fn contradictory_conditions_are_refused_together_before_packing() {
    let two_on_one_face = "bcs: [WallTemperature(face: YMin, value: 20.0), WallTemperature(face: YMin, value: 30.0), \
                           HeatFlux(face: YMax, flux: 10.0), WallTemperature(face: YMax, value: 25.0)], solver: Steady";
    let text = scene_text(
        BOX,
        "",
        two_on_one_face,
        r#"probes: [(name: "a", point: (0.05, 0.02, 0.1)), (name: "a", point: (0.05, 0.03, 0.1))]"#,
    );
    let e = parse(&text).unwrap_err();
    let all: Vec<String> = e.each().iter().map(|e| e.to_string()).collect();
    assert_eq!(all.len(), 3, "{e}");
    assert_mentions(&all[0], &["thermal.bcs[1]", "thermal.bcs[0]", "YMin"]);
    assert_mentions(&all[1], &["thermal.bcs[3]", "HeatFlux", "YMax"]);
    assert_mentions(&all[2], &["outputs.probes[1].name", "outputs.probes[0]"]);
    assert_mentions(&e.to_string(), &["3 problems in the scene", "\n  1. ", "\n  3. "]);
}

#[test]
fn a_steady_run_with_output_times_is_refused() {
    let m = refused_on_reading(&scene_text(BOX, "", WALLS_Y, "times: [1.0]"));
    assert_mentions(&m, &["outputs.times", "steady"]);
}

#[test]
fn a_phase_that_claims_no_particle_is_refused_and_unused_materials_are_warned() {
    let materials = r#"(name: "copper", conductivity: 400.0, density: 8900.0, specific_heat: 385.0)"#;
    let far = format!(
        "materials: [{STEEL}, {materials}], phases: [Region(material: \"copper\", region: Sphere(centre: (5.0, 5.0, 5.0), radius: 0.01))],"
    );
    let text = scene_text(BOX, "", WALLS_Y, "").replace(&format!("materials: [{STEEL}],"), &far);
    let m = run_text(&text).unwrap_err().to_string();
    assert_mentions(&m, &["phases[0]", "claims no particle"]);
    // A listed material no phase uses, and an interface with it: warnings, not refusals.
    let unused = format!(
        "materials: [{STEEL}, {materials}], interfaces: [(between: (\"steel\", \"copper\"), conductance: 1e4)],"
    );
    let text =
        scene_text(BOX, "", WALLS_Y, "etc_axis: Some(Y)").replace(&format!("materials: [{STEEL}],"), &unused);
    let r = run_text(&text).unwrap();
    let d = r.diagnostics.join("\n");
    assert_mentions(
        &d,
        &[
            "materials[1] (`copper`) is used by no phase",
            "interfaces[0]",
            "never met",
        ],
    );
    assert!((r.etc.unwrap().lambda_e / 33.0 - 1.0).abs() < 1e-9);
}

#[test]
fn a_source_on_a_held_particle_is_warned() {
    let held = "bcs: [FixedTemperature(select: Face(YMin), value: 20.0), WallTemperature(face: YMax, value: 30.0)], \
                sources: [(select: All, power_density: 1e3)], solver: Steady";
    let r = run_text(&scene_text(BOX, "", held, "")).unwrap();
    assert_mentions(
        &r.diagnostics.join("\n"),
        &["held at a fixed temperature also receive a source"],
    );
}

#[test]
fn an_adiabatic_run_where_nothing_changes_balances_exactly() {
    let still = "initial_temperature: 20.0, bcs: [], solver: Explicit(t_end: 1.0, dt: Auto(safety: 0.9))";
    let r = run_text(&scene_text(BOX, "", still, "")).unwrap();
    let rep = &r.thermal.as_ref().unwrap().report;
    assert_eq!(rep.energy_balance_error, 0.0, "{rep:?}");
}

#[test]
fn a_body_heated_from_zero_by_a_uniform_source_is_not_called_diverged() {
    // The envelope's round-off margin came from the initial range alone, zero here.
    let heated = "initial_temperature: 0.0, bcs: [], sources: [(select: All, power_density: 1e7)], \
                  solver: Explicit(t_end: 1.0, dt: Auto(safety: 0.9))";
    let r = run_text(&scene_text(BOX, "", heated, "")).unwrap();
    let t = &r.thermal.as_ref().unwrap();
    // Uniform heating: ΔT = q t / (ρ c) everywhere.
    let expected = 1e7 * 1.0 / (7800.0 * 500.0);
    for &v in &t.temperatures {
        assert!((v / expected - 1.0).abs() < 1e-9, "{v} against {expected}");
    }
    assert!(t.report.energy_balance_error < 1e-9, "{:?}", t.report);
}

#[test]
fn the_default_surface_is_laguerre_and_the_electric_one_follows_it() {
    // No `surface` and no `electric.surface`: both Laguerre, so a homogeneous body is exact
    // (the calibrated default read +3 % here) and the two physics agree (the electric default
    // used to refuse to run beside `surface: Laguerre`).
    let text = scene_text(
        BOX,
        "electric: (electrodes: [(face: ZMin, potential: 0.0), (face: ZMax, potential: 0.01)], eta: 0.0),",
        WALLS_Y,
        "etc_axis: Some(Y)",
    );
    let r = run_text(&text).unwrap();
    assert!((r.etc.as_ref().unwrap().lambda_e / 33.0 - 1.0).abs() < 1e-9);
    let el = r.electric.as_ref().unwrap();
    let resistance = el.report.resistance_ohm.unwrap();
    // ρ_e L / A of the bar along z.
    let exact = 1e-6 * 0.2 / (0.1 * 0.05);
    assert!(
        (resistance / exact - 1.0).abs() < 1e-9,
        "{resistance} against {exact}"
    );
}

#[test]
fn phase_fractions_are_the_bodys() {
    // A copper sphere of radius 0.04 m in a 0.1 m steel cube: body fraction 0.268. The
    // spheres' share read high at the walls (0.1194 for 0.1131 in the issue's case), as the
    // packing is looser there. A priori tolerance: the cells by centre along the surface, ~600
    // of them at this size, each off by ±0.3 h³ at random: 0.5 % (1σ); we allow 1.5 %.
    let copper = r#"(name: "copper", conductivity: 400.0, density: 8900.0, specific_heat: 385.0, resistivity: Some(1.7e-8))"#;
    let body = format!(
        "materials: [{STEEL}, {copper}], phases: [Region(material: \"copper\", region: Sphere(centre: (0.05, 0.05, 0.05), radius: 0.04))],"
    );
    let text = scene_text("Box(size: (0.1, 0.1, 0.1))", "", WALLS_Y, "")
        .replace(&format!("materials: [{STEEL}],"), &body)
        .replace("count: 2000", "count: 5000");
    let r = run_text(&text).unwrap();
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.04f64.powi(3) / 1e-3;
    let f = &r.model.report.phase_fractions;
    assert!((f[0] + f[1] - 1.0).abs() < 1e-12, "{f:?}");
    assert!(
        (f[1] / exact - 1.0).abs() < 0.015,
        "body fraction {} against {exact}",
        f[1]
    );
    let s = &r.model.report.sphere_phase_fractions;
    assert!((s[0] + s[1] - 1.0).abs() < 1e-12, "{s:?}");
}

#[test]
fn heat_imposed_on_a_cluster_left_out_of_the_solve_is_reported() {
    // An open crack across the whole section cuts the slab y > 0.04 off the held face: that
    // cluster floats (excluded) and the flux imposed on its face never enters the body. The
    // energy ledger of the solved part balances, so only a warning says where it went.
    let cut = "cracks: [Polygon(points: [(-0.01, 0.04, -0.01), (0.11, 0.04, -0.01), (0.11, 0.04, 0.21), (-0.01, 0.04, 0.21)])],";
    let bcs =
        "bcs: [WallTemperature(face: YMin, value: 20.0), HeatFlux(face: YMax, flux: 1000.0)], solver: Steady";
    let r = run_text(&scene_text(BOX, cut, bcs, "")).unwrap();
    let d = r.diagnostics.join("\n");
    assert_mentions(
        &d,
        &[
            "W of imposed flux and sources",
            "(100.000 % of",
            "excluded from the solve",
        ],
    );
}

#[test]
fn a_recoupled_transients_potential_probe_is_labelled_with_the_end_time() {
    let electric = "electric: (electrodes: [(face: ZMin, potential: 0.0), (face: ZMax, potential: 0.001)], \
                    recouple_tolerance: Some(0.01)),";
    let materials = r#"materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0,
        resistivity: Some(1.0e-6), resistivity_temp_coeff: 0.004, resistivity_ref_temp: 20.0)],"#;
    let transient = "initial_temperature: 20.0, bcs: [WallTemperature(face: ZMin, value: 20.0)], \
                     solver: Implicit(t_end: 50.0, dt: 10.0, scheme: BackwardEuler)";
    let text = scene_text(
        BOX,
        electric,
        transient,
        r#"probes: [(name: "c", point: (0.05, 0.025, 0.1), method: Ball(0.02))]"#,
    )
    .replace(&format!("materials: [{STEEL}],"), materials);
    let r = run_text(&text).unwrap();
    let p = r.probes.iter().find(|p| p.field == "potential").unwrap();
    assert_eq!(p.t, 50.0, "{p:?}");
}

#[test]
fn parse_errors_name_scene_words_not_rust_types() {
    let text =
        scene_text(BOX, "", WALLS_Y, "").replace("specific_heat: 500.0,", "specific_heat: 500.0, colour: 3,");
    let m = refused_on_reading(&text);
    assert_mentions(&m, &["`colour`", "a material (`materials`)"]);
    assert!(!m.contains("Config"), "{m}");
}

#[test]
fn a_homogenisations_refusals_come_in_one_run() {
    let text = scene_text(
        "Periodic(size: (0.1, 0.05, 0.2))",
        "",
        "bcs: [WallTemperature(face: YMin, value: 0.0)], sources: [(select: All, power_density: 1.0)], solver: Homogenize",
        r#"halo: Some(3.0), flux: true, probes: [(name: "p", point: (0.05, 0.02, 0.1))]"#,
    );
    let e = parse(&text).unwrap_err();
    let all = e.to_string();
    for field in [
        "thermal.bcs",
        "thermal.sources",
        "outputs.halo",
        "outputs.probes",
        "outputs.flux",
    ] {
        assert!(all.contains(&format!("`{field}`")), "{field} missing: {all}");
    }
    assert!(e.each().len() >= 5, "{all}");
}
