//! The electric example scenes (`scenes/cylinder-resistance.ron`, `scenes/notch-joule.ron`)
//! load as shipped with the paper's parameters, and run end to end once shrunk to a small
//! packing, writing a `.vtu` with the potential, current density, Joule power and
//! temperature. Checked against physics that holds at any resolution: the Kohlrausch
//! temperature rise V0²/(8 ρ_e λ), the current balance, the groove raising the resistance.

use std::path::{Path, PathBuf};

use demcon_scene::config::{ContainerConfig, PackingConfig};
use demcon_scene::{RunOptions, RunResult, Scene, run, write_outputs};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

fn load(name: &str) -> Scene {
    Scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The shipped scene shrunk to `n` packed particles.
fn small(name: &str, n: usize) -> Scene {
    load(name)
        .edit(|c| match &mut c.packing {
            PackingConfig::Generate { count, .. } => *count = n,
            other => panic!("{name}: expected a generated packing, got {other:?}"),
        })
        .unwrap()
}

/// Checks the paper's parameters: AISI 304L, the r = 1 mm, l = 5 mm cylinder, electrodes on
/// the end faces, ends at 20 °C, VTK on.
fn check_parameters(s: &Scene) {
    let c = s.config();
    match &c.packing {
        PackingConfig::Generate {
            container: ContainerConfig::Cylinder { radius, length },
            ..
        } => {
            assert_eq!((*radius, *length), (1e-3, 5e-3));
        }
        other => panic!("expected a generated cylinder packing, got {other:?}"),
    }
    let m = &c.materials[0];
    assert_eq!(m.resistivity, Some(0.73e-6));
    assert_eq!(
        (m.conductivity, m.density, m.specific_heat),
        (15.0, 7900.0, 500.0)
    );
    let e = c.electric.as_ref().unwrap();
    assert_eq!(e.electrodes.len(), 2);
    // The end faces themselves (the paper's particle electrodes are kept as comments).
    assert_eq!(e.electrodes[0].face, Some(demcon_scene::config::FaceConfig::ZMin));
    assert_eq!(e.electrodes[1].face, Some(demcon_scene::config::FaceConfig::ZMax));
    assert_eq!(e.eta, 1.0);
    assert!(c.outputs.vtk);
    assert!(c.thermal.is_some());
}

/// Kohlrausch: with the same boundary structure for potential and temperature and the same
/// surfaces for both networks, T_max − T0 = V0²/(8 ρ_e λ) on the network too.
fn check_joule(r: &RunResult, v0: f64) {
    let el = r.electric.as_ref().unwrap();
    let th = r.thermal.as_ref().unwrap();
    let exact = v0 * v0 / (8.0 * 0.73e-6 * 15.0);
    let mut solved = vec![true; el.potentials.len()];
    el.excluded.iter().for_each(|&p| solved[p as usize] = false);
    let t_max = th
        .temperatures
        .iter()
        .zip(&solved)
        .filter(|(_, s)| **s)
        .map(|(t, _)| *t)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        ((t_max - 20.0) / exact - 1.0).abs() < 1e-2,
        "ΔT_max = {}, exact {exact}",
        t_max - 20.0
    );
    assert!(el.report.current_mismatch < 1e-6);
    assert!((el.report.joule_w / (v0 * el.report.current_in) - 1.0).abs() < 1e-6);
}

fn vtu_has_fields(dir: &Path) {
    let bytes = std::fs::read(dir.join("particles.vtu")).unwrap();
    let text = String::from_utf8_lossy(&bytes);
    for f in ["potential", "current_density", "joule_power", "temperature"] {
        assert!(text.contains(&format!("Name=\"{f}\"")), "particles.vtu lacks {f}");
    }
}

fn out_dir(test: &str) -> PathBuf {
    std::env::temp_dir().join(format!("demcon-electric-scenes-{}-{test}", std::process::id()))
}

#[test]
fn shipped_electric_scenes_have_the_papers_parameters() {
    for name in ["cylinder-resistance.ron", "notch-joule.ron"] {
        check_parameters(&load(name));
    }
    assert!(load("notch-joule.ron").config().carve.is_some());
}

#[test]
fn cylinder_and_notch_scenes_run_small_and_write_vtk() {
    let n = 2500;
    let cyl = small("cylinder-resistance.ron", n);
    let rc = run(&cyl, &RunOptions::default()).unwrap();
    check_joule(&rc, 0.01);
    let r_cyl = rc.electric.as_ref().unwrap().report.resistance_ohm.unwrap();
    // ρ_e l / A within the discretisation error of a 2500-particle packing.
    let r_th = 0.73e-6 * 5e-3 / (std::f64::consts::PI * 1e-6);
    assert!((r_cyl / r_th - 1.0).abs() < 0.15, "R = {r_cyl}, ρl/A = {r_th}");
    let dir = out_dir("cylinder");
    write_outputs("cylinder-resistance", &cyl.config().outputs, &rc, &dir).unwrap();
    vtu_has_fields(&dir);

    let notch = small("notch-joule.ron", n);
    let rn = run(&notch, &RunOptions::default()).unwrap();
    check_joule(&rn, 0.01);
    let r_notch = rn.electric.as_ref().unwrap().report.resistance_ohm.unwrap();
    // The groove halves the radius over a fifth of the length: FEM gives R_groove/R_plain =
    // 1.84 (1-D series lower bound 1.60). At this coarse size the discretised groove is
    // rough (docs/electric.md), hence the wide band.
    let ratio = r_notch / r_cyl;
    assert!((1.4..3.5).contains(&ratio), "R groove / R plain = {ratio}");
    // Every particle kept by the carving (`carve_rule: Centre`) has its centre inside the
    // grooved body.
    let p = &rn.model.particles;
    for c in &p.centres {
        if (2e-3..=3e-3).contains(&c.z) {
            assert!(
                c.x.hypot(c.y) <= 0.5e-3 * (1.0 + 1e-9),
                "particle centre at {c:?} outside the groove"
            );
        }
    }
    // The reduced section is not cut off: the middle of the groove carries the current.
    let el = rn.electric.as_ref().unwrap();
    assert!(
        el.excluded.len() * 20 < p.len(),
        "{} particles floating",
        el.excluded.len()
    );
    let dir = out_dir("notch");
    write_outputs("notch-joule", &notch.config().outputs, &rn, &dir).unwrap();
    vtu_has_fields(&dir);
    let _ = std::fs::remove_dir_all(out_dir("cylinder"));
    let _ = std::fs::remove_dir_all(out_dir("notch"));
}

/// `scenes/joule-transient.ron`, shrunk (500 particles, a tenth of the time): the coupled
/// transient re-solves the potential, the resistance in force at the end has risen as
/// R0 (1 + β θ̄) within the lag (β tol = 1e-3) and the non-uniformity of the packing, and the
/// heat stored is the Joule energy.
#[test]
fn joule_transient_scene_recouples_during_the_run() {
    let s = small("joule-transient.ron", 500)
        .edit(|c| {
            let Some(demcon_scene::config::ThermalConfig {
                solver: demcon_scene::config::ThermalSolverConfig::Implicit { t_end, dt, .. },
                ..
            }) = c.thermal.as_mut()
            else {
                panic!("joule-transient.ron: expected an implicit thermal solver");
            };
            *t_end = 26.0;
            *dt = 0.65;
            c.outputs.times = vec![13.0, 26.0];
            c.outputs.probes.clear();
        })
        .unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let el = r.electric.as_ref().unwrap();
    let th = r.thermal.as_ref().unwrap();
    assert!(el.report.solves > 10, "{} solves", el.report.solves);
    assert!(th.report.energy_balance_error < 1e-9);
    // Mean rise over the particles that carry current (rattlers stay at 20 °C).
    let deg = r.model.graph.degrees();
    let hot: Vec<f64> = th
        .temperatures
        .iter()
        .zip(&deg)
        .filter(|(_, d)| **d > 0)
        .map(|(t, _)| t - 20.0)
        .collect();
    let theta = hot.iter().sum::<f64>() / hot.len() as f64;
    assert!(theta > 10.0, "θ̄ = {theta}");
    let one_way = s
        .clone()
        .edit(|c| c.electric.as_mut().unwrap().recouple_tolerance = None)
        .unwrap();
    let r0 = run(&one_way, &RunOptions::default()).unwrap();
    let (re, r00) = (
        el.report.resistance_ohm.unwrap(),
        r0.electric.as_ref().unwrap().report.resistance_ohm.unwrap(),
    );
    let expected = 1.0 + 4e-3 * theta;
    assert!(
        (re / r00 / expected - 1.0).abs() < 0.01,
        "R/R0 = {}, 1 + βθ̄ = {expected}",
        re / r00
    );
}
