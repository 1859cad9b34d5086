//! Regression tests of the robustness issue, each named after the input that once slipped
//! through: scenes refused before any work with a message naming the field and the value,
//! text encodings, and output folders that never mix two runs.

use std::path::{Path, PathBuf};

use demcon_scene::output::{RUN_MARKER, check_output_dir};
use demcon_scene::{RunOptions, Scene, run, write_outputs};

/// A small steady slab scene (300 particles), with `extra` spliced into its top level and
/// `electric` as its electric section (empty for none).
fn slab(extra: &str, thermal: &str, electric: &str) -> String {
    format!(
        r#"(
            packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 300, phi: 0.55, radius_cov: 0.0),
            surface: TerrerosAlpha,
            materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0,
                         resistivity: Some(1e-6))],
            thermal: Some((bcs: [WallTemperature(face: YMin, value: 0.0), WallTemperature(face: YMax, value: 1.0)],
                      solver: {thermal})),
            {electric}
            {extra}
        )"#
    )
}

fn parse(text: &str) -> Result<Scene, String> {
    Scene::parse(text, Path::new("t.ron"), PathBuf::new()).map_err(|e| e.to_string())
}

#[test]
fn two_electrodes_on_one_face_are_refused() {
    for electrodes in [
        "(face: ZMin, potential: 0.0), (face: ZMin, potential: 1.0)",
        "(face: ZMin, potential: 0.0), (select: Face(ZMin), potential: 1.0), (face: ZMax, potential: 1.0)",
    ] {
        let e = format!("electric: Some((electrodes: [{electrodes}])),");
        let err = parse(&slab("", "Steady", &e)).unwrap_err();
        assert!(
            err.contains("electric.electrodes[1]") && err.contains("ZMin") && err.contains("one electrode"),
            "{err}"
        );
    }
    // Two particle selections of one face are a conflict only if their potentials differ:
    // the network refuses that (ConflictingFixed); the scene accepts the text.
    let e = "electric: Some((electrodes: [(face: ZMin, potential: 0.0), (face: ZMax, potential: 1.0)])),";
    parse(&slab("", "Steady", e)).unwrap();
}

#[test]
fn etc_axis_on_a_transient_is_refused() {
    let err = parse(&slab(
        "outputs: (etc_axis: Some(Y), vtk: false),",
        "Implicit(t_end: 1.0, dt: 0.1)",
        "",
    ))
    .unwrap_err();
    assert!(
        err.contains("outputs.etc_axis") && err.contains("steady"),
        "{err}"
    );
    parse(&slab("outputs: (etc_axis: Some(Y), vtk: false),", "Steady", "")).unwrap();
}

#[test]
fn near_zero_coordination_is_refused() {
    for z in ["7.5e-30", "0.0", "-1.0", "25.0", "NaN"] {
        let err = parse(&slab(
            &format!("contacts: (coordination: Some({z})),"),
            "Steady",
            "",
        ))
        .unwrap_err();
        assert!(
            err.contains("contacts.coordination") && err.contains("[2, 20]"),
            "{z}: {err}"
        );
    }
    for t in ["0.0", "1e-320", "2.0"] {
        let text = slab(&format!("contacts: (tolerance: Some({t})),"), "Steady", "");
        let err = parse(&text).unwrap_err();
        assert!(err.contains("contacts.tolerance"), "{t}: {err}");
    }
    // An accepted tolerance too small for this packing: the run stops after contact detection
    // and says how much of the packing holds together.
    let s = parse(&slab("contacts: (tolerance: Some(1e-9)),", "Steady", "")).unwrap();
    let err = run(&s, &RunOptions::default()).unwrap_err().to_string();
    assert!(
        err.contains("largest connected cluster") && err.contains("of 300"),
        "{err}"
    );
}

#[test]
fn tiny_numbers_in_messages_are_written_in_e_form() {
    let err = parse(&slab("contacts: (coordination: Some(1e-300)),", "Steady", "")).unwrap_err();
    assert!(err.contains("1e-300") && !err.contains("0.0000"), "{err}");
    assert!(err.len() < 300, "{err}");
}

#[test]
fn a_bom_and_cr_line_endings_are_accepted_and_non_utf8_is_named() {
    let text = slab("", "Steady", "");
    parse(&format!("\u{feff}{text}")).unwrap();
    parse(&text.replace('\n', "\r\n")).unwrap();
    parse(&text.replace('\n', "\r")).unwrap();
    // An error after CR-only line breaks still names the right line.
    let bad = "(\rpacking: Nope,\r)";
    let err = parse(bad).unwrap_err();
    assert!(err.contains("t.ron:2:"), "{err}");
    // Non-UTF-8 bytes: the line and what to do.
    let dir = std::env::temp_dir().join(format!("demcon-latin1-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("latin1.ron");
    let mut bytes = b"(\n  name: \"caf".to_vec();
    bytes.push(0xe9);
    bytes.extend_from_slice(b"\",\n)");
    std::fs::write(&path, &bytes).unwrap();
    let err = Scene::load(&path).unwrap_err().to_string();
    assert!(err.contains("latin1.ron:2:") && err.contains("UTF-8"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_deeply_nested_scene_names_no_parser_internals() {
    let mut region = String::from("Sphere(centre: (0.5, 0.5, 0.5), radius: 0.1)");
    for _ in 0..200 {
        region = format!("Union([{region}])");
    }
    let err = parse(&slab(&format!("carve: Some({region}),"), "Steady", "")).unwrap_err();
    assert!(
        !err.contains("ron::") && !err.contains("recursion_limit"),
        "{err}"
    );
}

#[test]
fn outputs_never_mix_runs() {
    let root = std::env::temp_dir().join(format!("demcon-outputs-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let out = root.join("run");
    // A first run with the per-particle CSV, a second without: the CSV must be gone.
    let with_csv = parse(&slab("outputs: (particles_csv: true, vtk: false),", "Steady", "")).unwrap();
    let r = run(&with_csv, &RunOptions::default()).unwrap();
    check_output_dir(&out).unwrap();
    write_outputs("a", &with_csv.config().outputs, &r, &out).unwrap();
    assert!(out.join("particles.csv").exists() && out.join(RUN_MARKER).exists());
    let without = parse(&slab("outputs: (vtk: false),", "Steady", "")).unwrap();
    let r = run(&without, &RunOptions::default()).unwrap();
    write_outputs("b", &without.config().outputs, &r, &out).unwrap();
    assert!(
        !out.join("particles.csv").exists(),
        "a stale file of the first run is left"
    );
    assert!(out.join("summary.json").exists());
    // No temporary folder is left beside it.
    let left: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("run")]);
    // A folder of other files, or a file, is refused before any work.
    let other = root.join("notes");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::write(other.join("thesis.tex"), b"keep me").unwrap();
    let err = check_output_dir(&other).unwrap_err().to_string();
    assert!(err.contains("other files"), "{err}");
    let err = check_output_dir(&other.join("thesis.tex"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("not a folder"), "{err}");
    assert!(check_output_dir(Path::new(".")).is_err());
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn allow_unstable_above_the_bound_adds_a_diagnostic() {
    let auto = parse(&slab(
        "outputs: (vtk: false),",
        "Explicit(t_end: 1e-3, dt: Auto(safety: 0.5))",
        "",
    ))
    .unwrap();
    let r = run(&auto, &RunOptions::default()).unwrap();
    let bound = r.thermal.as_ref().unwrap().report.dt_bound;
    assert!(!r.diagnostics.iter().any(|d| d.contains("allow_unstable")));
    let dt = 1.05 * bound;
    let text = slab(
        "outputs: (vtk: false),",
        &format!(
            "Explicit(t_end: {:e}, dt: Fixed(dt: {dt:e}, allow_unstable: true))",
            2.0 * dt
        ),
        "",
    );
    let r = run(&parse(&text).unwrap(), &RunOptions::default()).unwrap();
    assert!(
        r.diagnostics
            .iter()
            .any(|d| d.contains("allow_unstable") && d.contains("1.05")),
        "{:?}",
        r.diagnostics
    );
}

#[test]
fn lower_crate_messages_name_scene_fields() {
    use demcon_scene::SceneError;
    let e = SceneError::from(demcon_network::SolveError::FloatingCluster {
        clusters: 1,
        nodes: 2,
        largest: 2,
        example: 7,
    });
    let text = e.to_string();
    assert!(
        text.contains("`floating: Exclude`") && !text.contains("FloatingPolicy"),
        "{text}"
    );
    // The lower error is not also a `source`, so a chain printer shows it once.
    assert!(std::error::Error::source(&e).is_none());
    let e = SceneError::from(demcon_thermal::ThermalError::Unstable {
        dt: 1.0,
        dt_max: 0.5,
        node: 3,
    });
    assert!(e.to_string().contains("`dt: Auto(safety: ..)`"), "{e}");
}

/// A chain of four unit spheres touching the XMin wall and, apart, a pair of spheres that
/// touches nothing else: a floating cluster.
fn chain_and_pair(solver: &str, extra: &str) -> Scene {
    let dir = std::env::temp_dir().join(format!("demcon-floating-{}-{}", std::process::id(), solver.len()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut f = String::from("# container box 8 1 1\n");
    for x in [0.5, 1.5, 2.5, 3.5, 5.5, 6.5] {
        f.push_str(&format!("{x} 0.5 0.5 0.5\n"));
    }
    std::fs::write(dir.join("p.xyzr"), f).unwrap();
    let text = format!(
        r#"(
            packing: File(path: "p.xyzr"),
            contacts: (tolerance: Some(0.01)),
            surface: Calibrated(c_t: Value(1.0)),
            materials: [(name: "m", conductivity: 1.0, density: 2.0, specific_heat: 3.0)],
            thermal: Some((initial_temperature: 25.0,
                bcs: [WallTemperature(face: XMin, value: 25.0)],
                sources: [(select: Particles([4, 5]), power_density: 6.0)],
                solver: {solver})),
            outputs: (vtk: false, probes: [(name: "pair", point: (6.0, 0.5, 0.5), method: Ball(1.0))]),
            {extra}
        )"#
    );
    Scene::parse(&text, Path::new("floating.ron"), dir).unwrap()
}

#[test]
fn a_transient_keeps_the_sources_of_a_floating_cluster() {
    // Adiabatic pair under q = 6 W/m³ with ρc = 6 J/(m³·K): +1 K per second, exactly.
    let s = chain_and_pair("Implicit(t_end: 2.0, dt: 0.5)", "");
    let r = run(&s, &RunOptions::default()).unwrap();
    let p = r.probes.iter().find(|p| p.name == "pair").unwrap();
    assert!((p.value - 27.0).abs() < 1e-9, "T(pair) = {}", p.value);
    assert!(p.solved);
}

#[test]
fn probes_over_excluded_particles_are_flagged() {
    let s = chain_and_pair("Steady", "floating: Exclude,");
    let r = run(&s, &RunOptions::default()).unwrap();
    let p = r.probes.iter().find(|p| p.name == "pair").unwrap();
    assert!(
        !p.solved,
        "a probe over an excluded cluster reads {} as if solved",
        p.value
    );
}

/// A 1500-particle cube with a central sphere of conductivity `contrast` (matrix 1 W/(m·K)).
fn contrast_scene(contrast: f64, solver: &str, linear: &str) -> Scene {
    let text = format!(
        r#"(
            packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 1500, phi: 0.6, radius_cov: 0.3, allow_short: true),
            surface: TerrerosAlpha,
            materials: [(name: "matrix", conductivity: 1.0, density: 1.0, specific_heat: 1.0),
                        (name: "inclusion", conductivity: {contrast:e}, density: 1.0, specific_heat: 1.0)],
            phases: [Region(material: "inclusion", region: Sphere(centre: (0.5, 0.5, 0.5), radius: 0.3))],
            thermal: (bcs: [WallTemperature(face: YMin, value: 0.0), WallTemperature(face: YMax, value: 1.0)],
                      solver: {solver}),
            {linear}
            outputs: (vtk: false),
        )"#
    );
    Scene::parse(&text, Path::new("contrast.ron"), PathBuf::new()).unwrap()
}

#[test]
fn contrast_1e6_converges_for_steady_and_implicit_scenes() {
    for contrast in [1e6, 1e-6] {
        for solver in ["Steady", "Implicit(t_end: 1.0, dt: 0.25)"] {
            let r = run(&contrast_scene(contrast, solver, ""), &RunOptions::default())
                .unwrap_or_else(|e| panic!("contrast {contrast:e}, {solver}: {e}"));
            let rep = &r.thermal.as_ref().unwrap().report;
            assert!(
                rep.iterations > 0 && rep.residual <= 1e-8,
                "{contrast:e} {solver}: {rep:?}"
            );
        }
    }
    // The scene chooses the method and tolerance: Cholesky agrees with the default.
    let a = run(&contrast_scene(1e6, "Steady", ""), &RunOptions::default()).unwrap();
    let b = run(
        &contrast_scene(1e6, "Steady", "linear_solver: (method: Cholesky),"),
        &RunOptions::default(),
    )
    .unwrap();
    let (ta, tb) = (
        &a.thermal.as_ref().unwrap().temperatures,
        &b.thermal.as_ref().unwrap().temperatures,
    );
    let diff = ta.iter().zip(tb).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    assert!(diff < 1e-6, "CG and Cholesky differ by {diff:e} K");
}

#[test]
fn linear_solver_values_are_checked() {
    for (linear, field) in [
        ("linear_solver: (rel_tol: 0.0),", "linear_solver.rel_tol"),
        ("linear_solver: (rel_tol: 0.5),", "linear_solver.rel_tol"),
        ("linear_solver: (max_iter: 0),", "linear_solver.max_iter"),
    ] {
        let err = parse(&slab(linear, "Steady", "")).unwrap_err();
        assert!(err.contains(field), "{linear}: {err}");
    }
}
