//! End-to-end tests of `demcon run --resume`: a run killed after a checkpoint (by the test
//! hook `--exit-after-checkpoints`, and by a real SIGKILL at a moment of the OS's choosing)
//! and resumed writes the files of an uninterrupted run — byte for byte, summary.json but its
//! timings; the checkpoint is removed once the run completes; a fresh run refuses to overwrite
//! it; `--resume` without a checkpoint, or on a steady scene, says why it cannot.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{demcon, scratch, text};

/// A transient of 100 particles: `STEPS` explicit steps of 1 s, a checkpoint every `EVERY`.
fn scene(steps: u64, every: u64) -> String {
    format!(
        r#"(
    packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 100, phi: 0.5, radius_cov: 0.2),
    surface: TerrerosAlpha,
    materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0)],
    thermal: (
        initial_temperature: 20.0,
        bcs: [WallTemperature(face: YMin, value: 20.0), HeatFlux(face: YMax, flux: 1000.0)],
        sources: [(select: Region(Sphere(centre: (0.5, 0.5, 0.5), radius: 0.3)), power_density: 100.0)],
        solver: Explicit(t_end: {steps}.0, dt: Fixed(dt: 1.0)),
        checkpoint: (every_steps: {every}),
    ),
    outputs: (
        times: [{half}.5, {steps}.0],
        probes: [(name: "c", point: (0.5, 0.5, 0.5), method: Ball(0.3))],
        particles_csv: true,
    ),
)"#,
        half = steps / 2
    )
}

fn run(scene: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend(extra);
    demcon(&args)
}

/// summary.json without its timings (every `…_s` and `…per_s` number, the stages).
fn summary_without_timings(dir: &Path) -> serde_json::Value {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.retain(|k, _| !(k.ends_with("_s") || k == "stages" || k == "memory"));
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    strip(&mut v);
    v
}

/// Every output file of a transient but `summary.json` (the time series included), sorted.
fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "summary.json")
        .collect();
    names.sort();
    names
}

fn assert_same_outputs(a: &Path, b: &Path) {
    let names = files(a);
    assert_eq!(names, files(b), "the same files");
    for want in [
        "particles.csv",
        "particles.pvd",
        "particles_0000.vtu",
        "probes.csv",
    ] {
        assert!(names.iter().any(|n| n == want), "{want} written: {names:?}");
    }
    for name in &names {
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
    assert_eq!(summary_without_timings(a), summary_without_timings(b));
}

#[test]
fn a_run_killed_after_a_checkpoint_and_resumed_writes_the_uninterrupted_outputs() {
    let d = scratch("cli-resume", "hook");
    let s = d.join("t.ron");
    std::fs::write(&s, scene(2000, 300)).unwrap();
    let full = d.join("full");
    let o = run(&s, &full, &[]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(!d.join("full.checkpoint").exists());
    // Killed right after its 3rd checkpoint (step 900): exit code 75, no outputs, the
    // checkpoint beside the output folder.
    let out = d.join("out");
    let ck = d.join("out.checkpoint");
    let o = run(&s, &out, &["--exit-after-checkpoints", "3"]);
    assert_eq!(o.status.code(), Some(75), "{}", text(&o));
    assert!(ck.exists() && !out.exists());
    // A fresh run refuses to overwrite it.
    let o = run(&s, &out, &[]);
    assert!(!o.status.success());
    let err = text(&o);
    assert!(
        err.contains("out.checkpoint") && err.contains("--resume"),
        "{err}"
    );
    // Killed again after the resumed run's first checkpoint, then resumed to the end.
    let o = run(&s, &out, &["--resume", "--exit-after-checkpoints", "1"]);
    assert_eq!(o.status.code(), Some(75), "{}", text(&o));
    let o = run(&s, &out, &["--resume"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("resumed from") && text(&o).contains("at step 1200"),
        "{}",
        text(&o)
    );
    assert!(!ck.exists(), "the completed run removes its checkpoint");
    assert_same_outputs(&full, &out);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_run_killed_by_sigkill_at_any_moment_resumes_to_the_uninterrupted_outputs() {
    // Long enough (~1 s of steps) for the kill to land mid-run, whenever the OS runs the test.
    let d = scratch("cli-resume", "sigkill");
    let s = d.join("t.ron");
    std::fs::write(&s, scene(200_000, 2000)).unwrap();
    let out = d.join("out");
    let ck = d.join("out.checkpoint");
    let mut child = Command::new(env!("CARGO_BIN_EXE_demcon"))
        .args([
            "run",
            s.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !ck.exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before its first checkpoint"
        );
        assert!(t0.elapsed() < Duration::from_secs(60), "no checkpoint after 60 s");
        std::thread::sleep(Duration::from_millis(1));
    }
    child.kill().unwrap();
    let status = child.wait().unwrap();
    assert!(!status.success(), "the run completed before the kill: {status}");
    assert!(ck.exists() && !out.exists());
    let o = run(&s, &out, &["--resume"]);
    assert!(o.status.success(), "{}", text(&o));
    // Neither the checkpoint nor a temporary file the kill may have cut short is left.
    assert!(!ck.exists() && !d.join("out.checkpoint.tmp").exists());
    let full = d.join("full");
    let o = run(&s, &full, &[]);
    assert!(o.status.success(), "{}", text(&o));
    assert_same_outputs(&full, &out);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn resume_says_why_it_cannot() {
    let d = scratch("cli-resume", "refusals");
    let s = d.join("t.ron");
    std::fs::write(&s, scene(100, 10)).unwrap();
    let o = run(&s, &d.join("out"), &["--resume"]);
    assert!(!o.status.success());
    let err = text(&o);
    assert!(
        err.contains("out.checkpoint") && err.contains("no interrupted run"),
        "{err}"
    );
    let steady = scene(100, 10)
        .replace(
            "solver: Explicit(t_end: 100.0, dt: Fixed(dt: 1.0)),",
            "solver: Steady,",
        )
        .replace("checkpoint: (every_steps: 10),", "")
        .replace("times: [50.5, 100.0],", "");
    std::fs::write(&s, steady).unwrap();
    let o = run(&s, &d.join("out"), &["--resume"]);
    assert!(!o.status.success());
    let err = text(&o);
    assert!(
        err.contains("thermal.solver") && err.contains("nothing to resume"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
