//! End-to-end tests of `demcon run` on bad input: each error once, before any work, with no
//! output left behind.

mod common;

use common::demcon;

const SCENE: &str = r#"(
    packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 200, phi: 0.5, radius_cov: 0.0),
    surface: TerrerosAlpha,
    materials: [(name: "steel", conductivity: 33.0, density: DENSITY, specific_heat: 500.0)],
    thermal: (bcs: [WallTemperature(face: YMin, value: 0.0), WallTemperature(face: YMax, value: 1.0)],
              solver: Steady),
    outputs: (vtk: false),
)"#;

#[test]
fn no_message_repeats_itself() {
    let d = common::scratch("cli-run", "repeat");
    let scene = d.join("bad.ron");
    std::fs::write(&scene, SCENE.replace("DENSITY", "0.0")).unwrap();
    let o = demcon(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        d.join("out").to_str().unwrap(),
        "--quiet",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("density"), "{err}");
    // Every ": "-separated part of the message appears once.
    let parts: Vec<&str> = err.trim().split(": ").collect();
    for (i, p) in parts.iter().enumerate() {
        assert!(
            p.len() < 8 || !parts[i + 1..].contains(p),
            "`{p}` repeats in: {err}"
        );
    }
    assert!(!d.join("out").exists());
}

#[test]
fn run_out_is_checked_before_the_run() {
    let d = common::scratch("cli-run", "out");
    let scene = d.join("ok.ron");
    std::fs::write(&scene, SCENE.replace("DENSITY", "7800.0")).unwrap();
    // A file where the output folder should be: refused at once, the file untouched.
    let file = d.join("a-file");
    std::fs::write(&file, b"keep").unwrap();
    let o = demcon(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        file.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("not a folder") && !err.contains("packing"), "{err}");
    assert_eq!(std::fs::read(&file).unwrap(), b"keep");
    // A good run, then a re-run into the same folder: one run's files only.
    let out = d.join("out");
    let o = demcon(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.join("summary.json").exists());
}

/// `--distributed` in a build without PETSc: refused before any work, naming the build
/// command, no output folder.
#[cfg(not(feature = "petsc"))]
#[test]
fn distributed_without_petsc_is_refused() {
    let d = common::scratch("cli-run", "distributed");
    let scene = d.join("ok.ron");
    std::fs::write(&scene, SCENE.replace("DENSITY", "7800.0")).unwrap();
    let out = d.join("out");
    let o = demcon(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--distributed",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("built without PETSc") && err.contains("--features petsc"),
        "{err}"
    );
    assert!(!err.contains("packing"), "refused before the run: {err}");
    assert!(!out.exists());
}
