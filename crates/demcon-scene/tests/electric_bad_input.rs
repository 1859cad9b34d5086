//! Bad input in electric scenes gets a clear error naming the field and what is allowed —
//! never a panic, never a NaN: missing or single electrodes, electrodes sharing particles,
//! an electrode selecting nothing, zero/negative/missing resistivity, η outside [0, 1], a
//! non-finite potential, and floating clusters (excluded and reported, or refused).
//!
//! The scenes run on a small simple-cubic lattice read from an `x y z r` file, so each test
//! takes milliseconds and the resistance is known exactly.

use std::path::{Path, PathBuf};

use demcon_core::{Container, ParticleSet, Vec3};
use demcon_packing::write_xyzr;
use demcon_scene::{RunOptions, Scene, SceneError, run};

/// Lattice spacing and sphere diameter (m).
const D: f64 = 1e-3;
/// Resistivity (Ω·m).
const RHO: f64 = 1e-6;

/// A fresh folder under the system temp dir for one test.
fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("demcon-electric-bad-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes an `nx × ny × nz` simple-cubic lattice of touching spheres (diameter D) into a box,
/// plus, when `island`, two touching spheres beside it that touch neither the lattice nor
/// the end faces (a floating cluster). Returns the folder holding `lattice.xyzr`.
fn lattice(test: &str, (nx, ny, nz): (usize, usize, usize), island: bool) -> PathBuf {
    let mut centres = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                centres.push(Vec3::new(
                    (i as f64 + 0.5) * D,
                    (j as f64 + 0.5) * D,
                    (k as f64 + 0.5) * D,
                ));
            }
        }
    }
    let extra = if island { 3 } else { 0 };
    if island {
        let z = 0.5 * nz as f64 * D;
        centres.push(Vec3::new((nx as f64 + 2.0) * D, 0.5 * D, z - 0.5 * D));
        centres.push(Vec3::new((nx as f64 + 2.0) * D, 0.5 * D, z + 0.5 * D));
    }
    let radii = vec![0.5 * D; centres.len()];
    let p = ParticleSet::new(centres, radii).unwrap();
    let c = Container::Box {
        size: [(nx + extra) as f64 * D, ny as f64 * D, nz as f64 * D],
    };
    let dir = temp_dir(test);
    write_xyzr(&dir.join("lattice.xyzr"), &p, &c).unwrap();
    dir
}

/// An electric scene on `lattice.xyzr` with calibrated surfaces S = (4/π) π R_m² = D², so
/// every contact conducts D/ρ_e. `material`, `electric` and `extra` are RON fragments.
fn scene_text(material: &str, electric: &str, extra: &str) -> String {
    format!(
        r#"(
            packing: File(path: "lattice.xyzr"),
            contacts: (tolerance: 0.01),
            surface: Calibrated(c_t: Value(1.2732395447351628)),
            materials: [(name: "metal", conductivity: 10.0, density: 8000.0, specific_heat: 500.0, {material})],
            electric: ({electric}),
            outputs: (vtk: false),
            {extra}
        )"#
    )
}

const ENDS: &str = r#"electrodes: [(select: Face(ZMin), potential: 0.0), (select: Face(ZMax), potential: 1.0)],
    surface: Calibrated(c_t: Value(1.2732395447351628))"#;

fn parse(dir: &Path, text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, Path::new("test.ron"), dir.to_path_buf())
}

/// Runs a scene that must fail, checks the message names `field`, and returns the message.
fn fails(dir: &Path, text: &str, field: &str) -> String {
    let err = match parse(dir, text) {
        Err(e) => e,
        Ok(s) => match run(&s, &RunOptions::default()) {
            Err(e) => e,
            Ok(_) => panic!("expected an error about `{field}`, the scene ran"),
        },
    };
    let msg = err.to_string();
    assert!(msg.contains(field), "message does not name `{field}`: {msg}");
    // A NaN in the message only when the input itself was NaN.
    assert!(!msg.contains("NaN") || text.contains("NaN"), "{msg}");
    msg
}

#[test]
fn the_lattice_resistance_is_exact() {
    // Reference for the other tests: (nz − 1) contacts of D/ρ in series per column, nx·ny
    // columns in parallel: R = (nz − 1) ρ / (D nx ny).
    let dir = lattice("exact", (3, 3, 8), false);
    let s = parse(&dir, &scene_text("resistivity: 1e-6", ENDS, "")).unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let el = r.electric.unwrap();
    let want = 7.0 * RHO / (D * 9.0);
    let got = el.report.resistance_ohm.unwrap();
    assert!((got / want - 1.0).abs() < 1e-8, "R = {got}, want {want}");
    assert!(el.report.current_mismatch < 1e-9);
    assert!(el.excluded.is_empty());
}

#[test]
fn no_electrode_or_a_single_one_is_refused() {
    let dir = lattice("none", (2, 2, 4), false);
    let msg = fails(
        &dir,
        &scene_text("resistivity: 1e-6", "electrodes: []", ""),
        "electric.electrodes",
    );
    assert!(msg.contains("at least two"), "{msg}");
    fails(
        &dir,
        &scene_text(
            "resistivity: 1e-6",
            "electrodes: [(select: Face(ZMin), potential: 0.0)]",
            "",
        ),
        "electric.electrodes",
    );
}

#[test]
fn electrodes_sharing_particles_are_refused() {
    let dir = lattice("overlap", (2, 2, 4), false);
    let both = r#"electrodes: [(select: Face(ZMin), potential: 0.0), (select: Face(ZMin), potential: 1.0)]"#;
    let msg = fails(
        &dir,
        &scene_text("resistivity: 1e-6", both, ""),
        "electrodes 0 and 1",
    );
    assert!(msg.contains("disjoint"), "{msg}");
    // Overlapping only in part: a region that also covers the bottom layer.
    let part = r#"electrodes: [(select: Face(ZMin), potential: 0.0),
        (select: Region(Box(min: (0.0, 0.0, 0.0), max: (0.002, 0.002, 0.0012))), potential: 1.0)]"#;
    fails(
        &dir,
        &scene_text("resistivity: 1e-6", part, ""),
        "electrodes 0 and 1",
    );
}

#[test]
fn an_electrode_selecting_nothing_is_refused() {
    let dir = lattice("empty", (2, 2, 4), false);
    let nowhere = r#"electrodes: [(select: Face(ZMin), potential: 0.0),
        (select: Region(Sphere(centre: (0.5, 0.5, 0.5), radius: 0.001)), potential: 1.0)]"#;
    fails(
        &dir,
        &scene_text("resistivity: 1e-6", nowhere, ""),
        "electric.electrodes[1].select",
    );
}

#[test]
fn zero_negative_or_missing_resistivity_is_refused() {
    let dir = lattice("rho", (2, 2, 4), false);
    for bad in ["resistivity: 0.0", "resistivity: -1e-6"] {
        let msg = fails(&dir, &scene_text(bad, ENDS, ""), "resistivity");
        assert!(msg.contains("metal"), "{msg}");
    }
    fails(&dir, &scene_text("", ENDS, ""), "materials[0].resistivity");
}

#[test]
fn eta_outside_zero_one_and_non_finite_potentials_are_refused() {
    let dir = lattice("eta", (2, 2, 4), false);
    for eta in ["1.5", "-0.1", "NaN"] {
        let e = format!("{ENDS}, eta: {eta}");
        let msg = fails(&dir, &scene_text("resistivity: 1e-6", &e, ""), "electric.eta");
        assert!(msg.contains("[0, 1]"), "{msg}");
    }
    let inf = r#"electrodes: [(select: Face(ZMin), potential: 0.0), (select: Face(ZMax), potential: inf)]"#;
    fails(
        &dir,
        &scene_text("resistivity: 1e-6", inf, ""),
        "electric.electrodes[1].potential",
    );
}

#[test]
fn a_floating_cluster_is_excluded_and_reported_or_refused() {
    let dir = lattice("floating", (3, 3, 6), true);
    // Exclude (the default): the island carries no current, is listed and reported, and the
    // lattice's resistance is unchanged.
    let s = parse(&dir, &scene_text("resistivity: 1e-6", ENDS, "")).unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let el = r.electric.as_ref().unwrap();
    let n = r.model.particles.len();
    assert_eq!(el.excluded, vec![(n - 2) as u32, (n - 1) as u32]);
    assert!(
        r.diagnostics
            .iter()
            .any(|d| d.starts_with("electric:") && d.contains("2 particle(s) in 1 floating cluster")),
        "{:?}",
        r.diagnostics
    );
    assert!(el.potentials.iter().all(|u| u.is_finite()));
    assert!(el.joule.iter().all(|p| p.is_finite()));
    let want = 5.0 * RHO / (D * 9.0);
    let got = el.report.resistance_ohm.unwrap();
    assert!((got / want - 1.0).abs() < 1e-8, "R = {got}, want {want}");
    // Fail: refused with the cluster's size.
    let msg = fails(
        &dir,
        &scene_text("resistivity: 1e-6", ENDS, "floating: Fail,"),
        "reach no fixed value",
    );
    assert!(msg.contains("2 node(s)"), "{msg}");
}
