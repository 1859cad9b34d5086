//! Checkpoints of scene runs: a transient stopped right after a checkpoint (as a kill would
//! leave it) and resumed writes the same files as an uninterrupted run — particles.csv,
//! particles.vtu, probes.csv, profiles.csv byte for byte, summary.json but its timings — for
//! an explicit thermal run and an implicit run with the ρ_e(T) coupling re-solved during it.
//! Resuming refuses a checkpoint of another scene or packing, a damaged one, a missing one,
//! and a steady scene; a fresh run refuses to overwrite an interrupted run's checkpoint.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use demcon_scene::checkpoint::{checkpoint_path, read_checkpoint};
use demcon_scene::{CheckpointOptions, RunOptions, Scene, SceneError, run, write_outputs};

/// A scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("demcon-scene-checkpoint-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// An explicit transient on 400 particles: a wall at 20 °C, a heat flux and a heated ball,
/// snapshots at three times (one off the step grid), probes, profiles, flux, every file.
const EXPLICIT: &str = r#"(
    name: "explicit",
    packing: PACKING,
    surface: TerrerosAlpha,
    materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0)],
    thermal: (
        initial_temperature: 20.0,
        bcs: [WallTemperature(face: YMin, value: 20.0), HeatFlux(face: YMax, flux: 1000.0)],
        sources: [(select: Region(Sphere(centre: (0.5, 0.5, 0.5), radius: 0.2)), power_density: 2e4)],
        solver: Explicit(t_end: 20000.0, dt: Auto(safety: 0.9)),
        checkpoint: (every_steps: 40),
    ),
    outputs: (
        times: [5000.0, 12345.0, 20000.0],
        probes: [(name: "c", point: (0.5, 0.5, 0.5), method: Ball(0.2))],
        profiles: [(name: "y", from: (0.5, 0.0, 0.5), to: (0.5, 1.0, 0.5), points: 5, method: Ball(0.2))],
        particles_csv: true,
        flux: true,
    ),
)"#;

const GENERATED: &str =
    "Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 400, phi: 0.55, radius_cov: 0.2)";

/// An implicit transient heated by 0.03 V between face electrodes, with ρ_e(T) re-solved
/// whenever a temperature moved by 0.5 K (some 30 K over the run).
const COUPLED: &str = r#"(
    name: "coupled",
    packing: Generate(container: Box(size: (1e-3, 1e-3, 2e-3)), count: 300, phi: 0.55, radius_cov: 0.2),
    surface: TerrerosAlpha,
    materials: [(name: "steel", conductivity: 15.0, density: 7900.0, specific_heat: 500.0,
                 resistivity: 7.3e-7, resistivity_temp_coeff: 4e-3, resistivity_ref_temp: 20.0)],
    thermal: (
        initial_temperature: 20.0,
        bcs: [WallTemperature(face: ZMin, value: 20.0)],
        solver: Implicit(t_end: 0.4, dt: 0.01, scheme: CrankNicolson),
        checkpoint: (every_steps: 7),
    ),
    electric: (
        electrodes: [(face: ZMin, potential: 0.0), (face: ZMax, potential: 0.03)],
        recouple_tolerance: 0.5,
    ),
    outputs: (
        times: [0.1, 0.25],
        probes: [(name: "c", point: (0.5e-3, 0.5e-3, 1e-3), method: Ball(0.3e-3))],
        particles_csv: true,
    ),
)"#;

fn scene(text: &str, dir: &Path) -> Scene {
    Scene::parse(text, Path::new("t.ron"), dir.to_path_buf()).unwrap()
}

/// Runs `scene` with checkpoints into `out` (`resume`, and a stop after the `stop`-th
/// checkpoint written); writes the outputs when it completes.
fn go(scene: &Scene, out: &Path, resume: bool, stop: Option<u64>) -> Result<(), SceneError> {
    let written = std::cell::Cell::new(0);
    let after_write = |_: u64, _: f64| {
        written.set(written.get() + 1);
        if stop == Some(written.get()) {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    };
    let opts = RunOptions {
        checkpoint: Some(CheckpointOptions {
            path: checkpoint_path(out).unwrap(),
            resume,
            after_write: Some(&after_write),
        }),
        ..Default::default()
    };
    let r = run(scene, &opts)?;
    write_outputs(&scene.config().name, &scene.config().outputs, &r, out)?;
    demcon_scene::checkpoint::remove_checkpoint(&checkpoint_path(out).unwrap())?;
    Ok(())
}

/// summary.json without its timings (every `…_s` and `…per_s` number, the stages) and with
/// the wall time of the coupling's solves cut from its diagnostic.
fn summary_without_timings(dir: &Path) -> serde_json::Value {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.retain(|k, _| !(k.ends_with("_s") || k == "stages" || k == "memory"));
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            serde_json::Value::String(s) if s.ends_with(" s") => {
                if let Some(i) = s.rfind(", ") {
                    s.truncate(i);
                }
            }
            _ => {}
        }
    }
    let mut v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    strip(&mut v);
    v
}

/// Every output file of `a` equals `b`'s (summary.json but its timings).
fn assert_same_outputs(a: &Path, b: &Path) {
    let mut names: Vec<_> = std::fs::read_dir(a)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert!(names.contains(&"particles.csv".to_string()), "{names:?}");
    for name in &names {
        if name == "summary.json" {
            assert_eq!(summary_without_timings(a), summary_without_timings(b));
        } else {
            let (x, y) = (
                std::fs::read(a.join(name)).unwrap(),
                std::fs::read(b.join(name)).unwrap(),
            );
            assert!(
                x == y,
                "{name} differs between {} and {}",
                a.display(),
                b.display()
            );
        }
    }
}

/// Runs `text` uninterrupted, then stopped after checkpoints `stops` in turn (each stop
/// resumed), and compares the outputs.
fn stopped_and_resumed_equals_uninterrupted(text: &str, tag: &str, stops: &[u64]) {
    let d = scratch(tag);
    let s = scene(text, &d);
    let full = d.join("full");
    go(&s, &full, false, None).unwrap();
    assert!(
        !checkpoint_path(&full).unwrap().exists(),
        "a completed run removes its checkpoint"
    );
    let out = d.join("resumed");
    let ck = checkpoint_path(&out).unwrap();
    let mut resume = false;
    let mut last_steps = 0;
    for &stop in stops {
        let err = go(&s, &out, resume, Some(stop)).unwrap_err();
        assert!(matches!(err, SceneError::Stopped { .. }), "{err}");
        // As a kill leaves it: the checkpoint, no output folder.
        assert!(ck.exists() && !out.exists());
        let (_, state) = read_checkpoint(&ck).unwrap();
        assert!(state.transient.steps > last_steps);
        last_steps = state.transient.steps;
        resume = true;
    }
    go(&s, &out, true, None).unwrap();
    assert!(!ck.exists(), "a completed run removes its checkpoint");
    assert_same_outputs(&full, &out);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn an_explicit_run_stopped_at_checkpoints_and_resumed_writes_the_uninterrupted_outputs() {
    // Stopped after its 1st checkpoint, then again after the 2nd of the resumed run.
    stopped_and_resumed_equals_uninterrupted(&EXPLICIT.replace("PACKING", GENERATED), "explicit", &[1, 2]);
}

#[test]
fn a_coupled_implicit_run_stopped_and_resumed_writes_the_uninterrupted_outputs() {
    let d = scratch("coupled-check");
    // The coupling re-solves the potential during the run, before and after the stop.
    let s = scene(COUPLED, &d);
    let r = run(&s, &RunOptions::default()).unwrap();
    let solves = r.electric.as_ref().unwrap().report.solves;
    assert!(solves > 5, "{solves} potential solves");
    let _ = std::fs::remove_dir_all(&d);
    stopped_and_resumed_equals_uninterrupted(COUPLED, "coupled", &[2]);
}

#[test]
fn resuming_refuses_another_scene_or_packing_a_damaged_or_missing_checkpoint_and_a_steady_scene() {
    let d = scratch("refusals");
    // A packing file, so that it can change under the same scene.
    let generated = scene(&EXPLICIT.replace("PACKING", GENERATED), &d);
    let model = demcon_scene::build_model(&generated, None).unwrap();
    let file = d.join("p.xyzr");
    demcon_packing::write_xyzr(&file, &model.particles, &model.container).unwrap();
    let text = EXPLICIT.replace("PACKING", r#"File(path: "p.xyzr")"#);
    let s = scene(&text, &d);
    let out = d.join("out");
    let ck = checkpoint_path(&out).unwrap();
    let refused = |s: &Scene| match go(s, &out, true, None) {
        Err(SceneError::Checkpoint { problem, .. }) => problem,
        other => panic!("{other:?}"),
    };
    // None yet.
    assert!(refused(&s).contains("does not exist"));
    assert!(matches!(
        go(&s, &out, false, Some(1)),
        Err(SceneError::Stopped { .. })
    ));
    let good = std::fs::read(&ck).unwrap();
    // A fresh run does not overwrite it.
    let err = go(&s, &out, false, None).unwrap_err().to_string();
    assert!(
        err.contains("interrupted run") && err.contains("--resume"),
        "{err}"
    );
    assert_eq!(std::fs::read(&ck).unwrap(), good);
    // Another scene: the differing fields are named; the schedule may change.
    let other = scene(&text.replace("t_end: 20000.0", "t_end: 30000.0"), &d);
    let problem = refused(&other);
    assert!(
        problem.contains("thermal.solver") && problem.contains("another scene"),
        "{problem}"
    );
    let other = scene(&text.replace("flux: 1000.0", "flux: 1001.0"), &d);
    assert!(refused(&other).contains("thermal.bcs"));
    // Another packing under the same scene.
    let mut p = model.particles.clone();
    p.radii[7] *= 0.999;
    demcon_packing::write_xyzr(&file, &p, &model.container).unwrap();
    assert!(refused(&s).contains("another packing"));
    demcon_packing::write_xyzr(&file, &model.particles, &model.container).unwrap();
    // Damaged: truncated, a flipped byte, not a checkpoint at all.
    for bad in [
        good[..good.len() / 2].to_vec(),
        good.iter()
            .enumerate()
            .map(|(i, &b)| if i == 100 { b ^ 1 } else { b })
            .collect(),
        Vec::new(),
    ] {
        std::fs::write(&ck, &bad).unwrap();
        assert!(refused(&s).contains("damaged"));
    }
    std::fs::write(&ck, b"x y z r\n").unwrap();
    assert!(refused(&s).contains("not a demcon checkpoint"));
    // The good checkpoint, with another schedule: resumed and completed.
    std::fs::write(&ck, &good).unwrap();
    go(
        &scene(&text.replace("every_steps: 40", "every_seconds: 3600.0"), &d),
        &out,
        true,
        None,
    )
    .unwrap();
    assert!(out.join("summary.json").exists() && !ck.exists());
    // A steady scene has nothing to resume.
    let steady = text
        .replace(
            "solver: Explicit(t_end: 20000.0, dt: Auto(safety: 0.9)),",
            "solver: Steady,",
        )
        .replace("checkpoint: (every_steps: 40),", "")
        .replace("times: [5000.0, 12345.0, 20000.0],", "");
    let err = go(&scene(&steady, &d), &d.join("steady"), true, None)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("thermal.solver") && err.contains("nothing to resume"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn checkpoint_settings_are_checked_with_their_field_path() {
    let d = scratch("settings");
    let text = EXPLICIT.replace("PACKING", GENERATED);
    for (setting, field) in [
        ("checkpoint: (every_steps: 0)", "thermal.checkpoint.every_steps"),
        (
            "checkpoint: (every_seconds: -1.0)",
            "thermal.checkpoint.every_seconds",
        ),
        (
            "checkpoint: (every_seconds: inf)",
            "thermal.checkpoint.every_seconds",
        ),
        ("checkpoint: ()", "thermal.checkpoint"),
    ] {
        let t = text.replace("checkpoint: (every_steps: 40)", setting);
        let err = Scene::parse(&t, Path::new("t.ron"), d.clone())
            .unwrap_err()
            .to_string();
        assert!(err.contains(&format!("`{field}`")), "{setting}: {err}");
    }
    let steady = text.replace(
        "solver: Explicit(t_end: 20000.0, dt: Auto(safety: 0.9)),",
        "solver: Steady,",
    );
    let err = Scene::parse(&steady, Path::new("t.ron"), d.clone())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("`thermal.checkpoint`") && err.contains("steady"),
        "{err}"
    );
    // Both periods together are fine.
    let both = text.replace(
        "checkpoint: (every_steps: 40)",
        "checkpoint: Some((every_steps: Some(40), every_seconds: Some(600.0)))",
    );
    Scene::parse(&both, Path::new("t.ron"), d.clone()).unwrap();
    let _ = std::fs::remove_dir_all(&d);
}
