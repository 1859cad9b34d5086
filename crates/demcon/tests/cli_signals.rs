//! End-to-end tests of `demcon run` stopped by SIGTERM or SIGINT (sent with `kill`): the run
//! exits with 143 or 130, leaves no hidden `.OUT.partial-PID` or `.OUT.old-PID` folder beside
//! its output folder, keeps an earlier run's folder whole, and keeps its checkpoint.

#![cfg(unix)]

mod common;

use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{demcon, scratch, text};

/// Starts `demcon run scene --out out --quiet`.
fn start(scene: &Path, out: &Path) -> Child {
    Command::new(env!("CARGO_BIN_EXE_demcon"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start demcon")
}

/// Sends `signal` (`TERM`, `INT`) to the process.
fn send(child: &Child, signal: &str) {
    let s = Command::new("kill")
        .args(["-s", signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(s.success());
}

/// Waits (polling every millisecond, at most a minute) until `ready` holds, or the process
/// has ended; true when `ready` holds.
fn wait_until(child: &mut Child, ready: impl Fn() -> bool) -> bool {
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(60) {
        if ready() {
            return true;
        }
        if child.try_wait().unwrap().is_some() {
            return ready();
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    false
}

/// The hidden folders a run writes beside `out` (`.out.partial-PID`, `.out.old-PID`).
fn leftovers(out: &Path) -> Vec<PathBuf> {
    let prefix = format!(".{}.", out.file_name().unwrap().to_str().unwrap());
    std::fs::read_dir(out.parent().unwrap())
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.file_name().unwrap().to_str().unwrap().starts_with(&prefix))
        .collect()
}

fn exited(o: &Output, code: i32) {
    assert_eq!(
        (o.status.code(), o.status.signal()),
        (Some(code), None),
        "{}",
        text(o)
    );
}

/// A transient of 100 particles and 10⁷ explicit steps (long enough to be stopped in its
/// solve), a checkpoint every 10⁴ steps.
const LONG: &str = r#"(
    packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 100, phi: 0.5, radius_cov: 0.2),
    surface: TerrerosAlpha,
    materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0)],
    thermal: (
        bcs: [WallTemperature(face: YMin, value: 20.0), WallTemperature(face: YMax, value: 30.0)],
        solver: Explicit(t_end: 1.0e7, dt: Fixed(dt: 1.0)),
        checkpoint: (every_steps: 10000),
    ),
    outputs: (times: [1.0e7], particles_csv: true),
)"#;

#[test]
fn sigterm_in_the_solve_exits_143_and_keeps_the_checkpoint() {
    let d = scratch("cli-signals", "solve");
    let (scene, out) = (d.join("long.ron"), d.join("out"));
    std::fs::write(&scene, LONG).unwrap();
    let checkpoint = d.join("out.checkpoint");
    let mut child = start(&scene, &out);
    assert!(
        wait_until(&mut child, || checkpoint.exists()),
        "no checkpoint was written"
    );
    send(&child, "TERM");
    let o = child.wait_with_output().unwrap();
    exited(&o, 143);
    assert!(text(&o).contains("interrupted by SIGTERM"), "{}", text(&o));
    assert!(text(&o).contains("kept the checkpoint"), "{}", text(&o));
    assert!(!out.exists(), "a stopped run wrote outputs");
    assert!(leftovers(&out).is_empty(), "{:?}", leftovers(&out));
    assert!(checkpoint.exists() && !d.join("out.checkpoint.tmp").exists());
    std::fs::remove_dir_all(&d).unwrap();
}

/// 5000 particles, 100 output times with the particles' and the contacts' VTK files: about
/// 200 MB written over a few tenths of a second, time to be stopped while writing.
fn heavy_writer() -> String {
    let times: Vec<String> = (1..=100).map(|k| format!("{:.2}", 0.01 * k as f64)).collect();
    format!(
        r#"(
    packing: Generate(container: Box(size: (1.0e-3, 1.0e-3, 1.0e-3)), count: 5000, phi: 0.55, radius_cov: 0.2),
    surface: TerrerosAlpha,
    materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0)],
    thermal: (bcs: [WallTemperature(face: YMin, value: 20.0), WallTemperature(face: YMax, value: 30.0)],
              solver: Implicit(t_end: 1.0, dt: 0.01)),
    outputs: (times: [{}], vtk: true, contacts_vtk: true, flux: true),
)"#,
        times.join(", ")
    )
}

/// Stopped while it writes into `.out.partial-PID` over an earlier run's `out`: the partial
/// folder goes, the earlier run's folder stays as it was.
#[test]
fn sigint_while_writing_removes_the_partial_folder_and_keeps_the_earlier_run() {
    let d = scratch("cli-signals", "write");
    let (small, scene, out) = (d.join("small.ron"), d.join("heavy.ron"), d.join("out"));
    std::fs::write(
        &small,
        LONG.replace("t_end: 1.0e7", "t_end: 10.0")
            .replace("times: [1.0e7]", "times: [10.0]"),
    )
    .unwrap();
    std::fs::write(&scene, heavy_writer()).unwrap();
    let o = demcon(&[
        "run",
        small.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let earlier = std::fs::read(out.join("summary.json")).unwrap();
    let listing = |dir: &Path| {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    let files = listing(&out);

    let mut child = start(&scene, &out);
    let partial = d.join(format!(".out.partial-{}", child.id()));
    assert!(
        wait_until(&mut child, || partial.exists()),
        "the run ended before it wrote its outputs"
    );
    send(&child, "INT");
    let o = child.wait_with_output().unwrap();
    exited(&o, 130);
    let said = text(&o);
    assert!(said.contains("interrupted by SIGINT"), "{said}");
    assert!(!said.contains("error"), "{said}");
    assert!(leftovers(&out).is_empty(), "{:?}", leftovers(&out));
    assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), earlier);
    assert_eq!(listing(&out), files);
    std::fs::remove_dir_all(&d).unwrap();
}
