//! `phase_rule: Conforming` from a scene: the seeds are counted in `summary.json` and flagged
//! in the particle files, a homogeneous body split by a sphere of the same material stays
//! exact, and the rule is refused without the Laguerre cells.

use std::path::{Path, PathBuf};

use demcon_scene::{RunOptions, Scene, run, summary_json};

fn scene(surface: &str, lambda_b: f64) -> String {
    format!(
        r#"(
    seed: 2,
    packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 3000, phi: 0.55, radius_cov: 0.3),
    surface: {surface},
    materials: [
        (name: "a", conductivity: 2.0, density: 1000.0, specific_heat: 500.0),
        (name: "b", conductivity: {lambda_b:e}, density: 1000.0, specific_heat: 500.0),
    ],
    phases: [Spheres(material: "b", radius: 0.3, centres: [(0.5, 0.5, 0.5)])],
    phase_rule: Conforming,
    thermal: (bcs: [WallTemperature(face: XMin, value: 0.0), WallTemperature(face: XMax, value: 1.0)], solver: Steady),
    linear_solver: (method: Auto, rel_tol: 1e-12, max_iter: 200000),
    outputs: (etc_axis: Some(X), vtk: false, particles_csv: true),
)"#
    )
}

fn parse(text: &str) -> Scene {
    Scene::parse(text, Path::new("c.ron"), PathBuf::new()).unwrap()
}

#[test]
fn seeds_are_counted_flagged_and_a_same_material_sphere_changes_nothing() {
    let s = parse(&scene("Laguerre", 2.0));
    let r = run(&s, &RunOptions::default()).unwrap();
    assert!((r.etc.as_ref().unwrap().lambda_e / 2.0 - 1.0).abs() < 1e-9);
    let j = summary_json("c", &r);
    let seeds = j["build"]["conform"]["seeds"].as_u64().unwrap() as usize;
    assert!(seeds > 100 && seeds == r.model.seeds, "{}", j["build"]["conform"]);
    assert!(j["build"]["conform"]["removed_particles"].as_u64().unwrap() > 0);
    let dir = std::env::temp_dir().join(format!("demcon-conforming-{}", std::process::id()));
    demcon_scene::write_outputs("c", &s.config().outputs, &r, &dir).unwrap();
    let (header, cols) = demcon_post::read_csv(dir.join("particles.csv")).unwrap();
    let k = header
        .iter()
        .position(|h| h == "surface_seed")
        .expect("surface_seed column");
    let flagged = cols[k].iter().filter(|&&v| v == 1.0).count();
    assert_eq!(flagged, seeds);
    // The seeds are the last particles, and the inner ones carry the sphere's phase.
    let n = r.model.particles.len();
    assert!(cols[k][n - seeds..].iter().all(|&v| v == 1.0));
    let inner = r.model.particles.phases[n - seeds..]
        .iter()
        .filter(|&&p| p == 1)
        .count();
    assert!(inner > 0 && inner < seeds, "{inner} of {seeds}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_conducting_sphere_raises_the_conductivity_and_the_rule_needs_the_cells() {
    let r = run(&parse(&scene("Laguerre", 20.0)), &RunOptions::default()).unwrap();
    assert!(r.etc.as_ref().unwrap().lambda_e > 2.0);
    let e = Scene::parse(&scene("TerrerosAlpha", 20.0), Path::new("c.ron"), PathBuf::new())
        .expect_err("refused")
        .to_string();
    assert!(e.contains("phase_rule") && e.contains("Laguerre"), "{e}");
}

/// A layer of `b` (λ = 7) between z = 0.37 and 0.71 in a unit cube of `a` (λ = 2), with an
/// interface conductance `h` (W/(m²·K); `None`: perfect), in a walled box with the gradient
/// along `axis` or in a periodic cell homogenised.
fn layers(container: &str, h: Option<f64>, thermal: &str) -> String {
    let interfaces = h.map_or(String::new(), |h| {
        format!("interfaces: [(between: (\"a\", \"b\"), conductance: {h:e})],")
    });
    format!(
        r#"(
    seed: 3,
    packing: Generate(container: {container}(size: (1.0, 1.0, 1.0)), count: 3000, phi: 0.55, radius_cov: 0.3),
    materials: [
        (name: "a", conductivity: 2.0, density: 1000.0, specific_heat: 500.0),
        (name: "b", conductivity: 7.0, density: 1000.0, specific_heat: 500.0),
    ],
    phases: [Region(material: "b", region: Box(min: (-1.0, -1.0, 0.37), max: (2.0, 2.0, 0.71)))],
    {interfaces}
    phase_rule: Conforming,
    thermal: {thermal},
    linear_solver: (method: Auto, rel_tol: 1e-13, max_iter: 200000),
    outputs: (vtk: false),
)"#
    )
}

/// The layered answers: parallel (λ along the layers), series (across, with 2/h for the two
/// interfaces).
fn layered(h: Option<f64>) -> (f64, f64) {
    let parallel = 2.0 * 0.66 + 7.0 * 0.34;
    let series = 1.0 / (0.66 / 2.0 + 0.34 / 7.0 + h.map_or(0.0, |h| 2.0 / h));
    (parallel, series)
}

#[test]
fn layers_in_series_and_in_parallel_are_exact_with_and_without_an_interface() {
    for h in [None, Some(20.0)] {
        let (parallel, series) = layered(h);
        for (axis, want) in [("X", parallel), ("Z", series)] {
            let thermal = format!(
                "(bcs: [WallTemperature(face: {axis}Min, value: 0.0), WallTemperature(face: {axis}Max, value: 1.0)], \
                 solver: Steady)"
            );
            let text = layers("Box", h, &thermal).replace(
                "outputs: (vtk: false)",
                &format!("outputs: (etc_axis: Some({axis}), vtk: false)"),
            );
            let r = run(&parse(&text), &RunOptions::default()).unwrap();
            let got = r.etc.as_ref().unwrap().lambda_e;
            assert!(
                (got / want - 1.0).abs() < 1e-9,
                "h {h:?}, {axis}: {got} for {want}"
            );
            let c = r.model.report.conform.as_ref().unwrap();
            assert_eq!((c.planes, c.dropped_seeds), (2, 0), "{c:?}");
        }
        // Periodic: the layer's faces at 0.37 and 0.71 are the cell's two interfaces.
        let r = run(
            &parse(&layers("Periodic", h, "(bcs: [], solver: Homogenize)")),
            &RunOptions::default(),
        )
        .unwrap();
        let t = r
            .homogenization
            .as_ref()
            .unwrap()
            .thermal
            .as_ref()
            .unwrap()
            .report
            .tensor;
        for (k, want) in [(0, parallel), (1, parallel), (2, series)] {
            assert!(
                (t[k][k] / want - 1.0).abs() < 1e-9,
                "h {h:?}, periodic {k}: {} for {want}",
                t[k][k]
            );
        }
    }
}

#[test]
fn tangent_overlapping_and_wall_touching_spheres_are_counted_not_broken() {
    // Two spheres touching each other, a third overlapping the second, a fourth touching the
    // XMin wall: every pair that cannot be placed is dropped and counted, the run finishes
    // with a finite conductivity between the phases'.
    let text = scene("Laguerre", 20.0).replace(
        "phases: [Spheres(material: \"b\", radius: 0.3, centres: [(0.5, 0.5, 0.5)])],",
        "phases: [Spheres(material: \"b\", radius: 0.15, centres: [(0.3, 0.5, 0.5), (0.6, 0.5, 0.5), \
         (0.7, 0.55, 0.5), (0.15, 0.2, 0.2)])],",
    );
    let r = run(&parse(&text), &RunOptions::default()).unwrap();
    let c = r.model.report.conform.as_ref().unwrap();
    assert!(c.dropped_seeds > 0 && c.narrowed_pairs > 0, "{c:?}");
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!(etc.is_finite() && etc > 2.0 && etc < 20.0, "{etc}");
    let t = &r.thermal.as_ref().unwrap().temperatures;
    assert!(
        t.iter()
            .all(|v| v.is_finite() && (-1e-9..=1.0 + 1e-9).contains(v))
    );
}

#[test]
fn an_open_crack_along_the_gradient_costs_nothing_under_the_conforming_cells() {
    // A penny crack whose plane contains the gradient: the continuum passes the same heat
    // with or without it. The cells follow its faces, so only the branches normal to it are
    // cut; by centre the cut branches' obliquity costs a share of the flow.
    let text = |rule: &str| {
        scene("Laguerre", 2.0)
            .replace(
                "phases: [Spheres(material: \"b\", radius: 0.3, centres: [(0.5, 0.5, 0.5)])],",
                "cracks: [Disc(centre: (0.5, 0.5, 0.5), normal: (0.0, 1.0, 0.0), radius: 0.3)],",
            )
            .replace("phase_rule: Conforming", &format!("phase_rule: {rule}"))
    };
    let loss = |rule: &str| {
        let r = run(&parse(&text(rule)), &RunOptions::default()).unwrap();
        1.0 - r.etc.as_ref().unwrap().lambda_e / 2.0
    };
    let (conforming, centre) = (loss("Conforming"), loss("Centre"));
    assert!(conforming.abs() < 2e-4, "conforming: {conforming}");
    assert!(
        centre > 10.0 * conforming.abs(),
        "centre {centre}, conforming {conforming}"
    );
}

#[test]
fn seeds_stay_inside_a_curved_container() {
    // A sphere touching a cylinder's mantle and a crack reaching close to it: the pairs whose
    // seeds would leave the cylinder are dropped (counted); the run goes through.
    let text = r#"(
    seed: 3,
    packing: Generate(container: Cylinder(radius: 0.5, length: 2.0), count: 4000, phi: 0.55, radius_cov: 0.3),
    materials: [
        (name: "a", conductivity: 2.0, density: 1000.0, specific_heat: 500.0),
        (name: "b", conductivity: 20.0, density: 1000.0, specific_heat: 500.0),
    ],
    phases: [Spheres(material: "b", radius: 0.2, centres: [(0.3, 0.0, 0.6)])],
    cracks: [Disc(centre: (0.0, 0.0, 1.3), normal: (0.0, 0.0, 1.0), radius: 0.45)],
    thermal: (bcs: [WallTemperature(face: ZMin, value: 0.0), WallTemperature(face: ZMax, value: 1.0)], solver: Steady),
    outputs: (etc_axis: Some(Z), vtk: false),
)"#;
    let r = run(&parse(text), &RunOptions::default()).unwrap();
    let c = r.model.report.conform.as_ref().unwrap();
    assert!(c.dropped_seeds > 0 && c.seeds > 0, "{c:?}");
    let cylinder = &r.model.container;
    let n = r.model.particles.len();
    for x in &r.model.particles.centres[n - r.model.seeds..] {
        assert!(cylinder.wall_distance(x) > 0.0, "{x}");
    }
    assert!(r.etc.as_ref().unwrap().lambda_e.is_finite());
}

#[test]
fn seeds_stay_inside_a_carved_body() {
    // A sphere and a crack crossing the carving region's boundary: no seed outside the body.
    let text = r#"(
    seed: 3,
    packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 4000, phi: 0.55, radius_cov: 0.3),
    carve: Some(Box(min: (0.0, 0.0, 0.0), max: (0.6, 1.0, 1.0))),
    materials: [
        (name: "a", conductivity: 2.0, density: 1000.0, specific_heat: 500.0),
        (name: "b", conductivity: 20.0, density: 1000.0, specific_heat: 500.0),
    ],
    phases: [Spheres(material: "b", radius: 0.2, centres: [(0.5, 0.5, 0.5)])],
    cracks: [Disc(centre: (0.3, 0.2, 0.5), normal: (0.0, 1.0, 0.0), radius: 0.4)],
    thermal: (bcs: [WallTemperature(face: YMin, value: 0.0), WallTemperature(face: YMax, value: 1.0)], solver: Steady),
    outputs: (etc_axis: Some(Y), vtk: false),
)"#;
    let r = run(&parse(text), &RunOptions::default()).unwrap();
    let n = r.model.particles.len();
    assert!(r.model.seeds > 0);
    assert!(
        r.model.particles.centres[n - r.model.seeds..]
            .iter()
            .all(|x| x.x < 0.6)
    );
    assert!(r.etc.as_ref().unwrap().lambda_e.is_finite());
}

#[test]
fn the_memory_estimate_counts_the_conforming_seeds() {
    // The f = 0.5 random composite of the validation (206 spheres of radius 0.834 mm in a
    // 1 cm periodic cell) at 2·10⁵ particles: 1.12·10⁵ sites added, measured.
    let centres: Vec<String> = (0..206)
        .map(|k| format!("({:e}, 0.005, 0.005)", 1e-3 + 4e-5 * k as f64))
        .collect();
    let text = format!(
        r#"(
    packing: Generate(container: Periodic(size: (0.01, 0.01, 0.01)), count: 200000, phi: 0.6, radius_cov: 0.3),
    materials: [
        (name: "a", conductivity: 2.0, density: 1000.0, specific_heat: 500.0),
        (name: "b", conductivity: 20.0, density: 1000.0, specific_heat: 500.0),
    ],
    phases: [Spheres(material: "b", radius: 8.3369e-4, centres: [{}])],
    thermal: (bcs: [], solver: Homogenize),
    outputs: (vtk: false),
)"#,
        centres.join(", ")
    );
    let cfg = parse(&text).config().clone();
    let cell = demcon_core::Container::Periodic { size: [0.01; 3] };
    let extra = demcon_scene::validate::conforming_extra_sites(200_000, &cfg, &cell);
    assert!((0.9e5..1.4e5).contains(&(extra as f64)), "{extra}");
    let mut centre = cfg.clone();
    centre.phase_rule = Some(demcon_scene::config::PhaseRuleConfig::Centre);
    assert_eq!(
        demcon_scene::validate::conforming_extra_sites(200_000, &centre, &cell),
        0
    );
}
