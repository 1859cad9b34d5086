//! Face electrodes and the time-accurate ρ_e(T) coupling of a transient.
//!
//! On a simple-cubic lattice of touching spheres (NX × NX columns of NZ particles, spacing D)
//! with uniform surfaces S = D², every contact conducts σ D and a face electrode's link
//! σ S / (D/2) = 2 σ D. Each column is then NZ equal resistances of 1/(σ D) in series
//! (NZ − 1 contacts plus two half-links), so R = ρ_e (NZ D) / (NX D)² = ρ_e l / A exactly,
//! and every particle dissipates the same power (an end particle gets half a contact and a
//! whole link). With all thermal faces adiabatic the temperature stays uniform, so the
//! coupled transient obeys C dθ/dt = V²/(R0 (1 + β θ)) exactly:
//! θ(t) = (sqrt(1 + 2 β P0 t / C) − 1)/β.
//!
//! A priori bound on the coupled run (see docs/electric.md): the power in force lags the
//! temperature by at most `tol` (K), a relative power excess ≤ β tol/(1 + β θ), which
//! integrates to a relative error of θ ≤ tol ln(1 + βθ)/θ ≤ β tol; time stepping with the
//! sources of the step start (forward Euler on θ, f(θ) decreasing, errors contract) adds at
//! most β P0 Δt/(2C) relative.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use demcon_core::{Container, ParticleSet, Vec3};
use demcon_packing::write_xyzr;
use demcon_scene::{RunOptions, RunResult, Scene, run};

const D: f64 = 1e-3;
const NX: usize = 3;
const NZ: usize = 12;
const RHO0: f64 = 1e-6;
const V0: f64 = 0.1;
const T0: f64 = 20.0;
const BETA: f64 = 4e-3;
/// Tolerance of the re-solve (K): β tol = 2e-3.
const TOL: f64 = 0.5;

fn lattice_dir() -> PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("demcon-electric-transient-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut centres = Vec::new();
        for k in 0..NZ {
            for j in 0..NX {
                for i in 0..NX {
                    centres.push(Vec3::new(
                        (i as f64 + 0.5) * D,
                        (j as f64 + 0.5) * D,
                        (k as f64 + 0.5) * D,
                    ));
                }
            }
        }
        let p = ParticleSet::new(centres.clone(), vec![0.5 * D; centres.len()]).unwrap();
        let c = Container::Box {
            size: [NX as f64 * D, NX as f64 * D, NZ as f64 * D],
        };
        write_xyzr(&dir.join("lattice.xyzr"), &p, &c).unwrap();
        dir
    })
    .clone()
}

/// The lattice scene with `electrodes` and `thermal` as RON fragments.
fn scene(electrodes: &str, solver: &str, recouple: &str, outputs: &str) -> Result<Scene, String> {
    let text = format!(
        r#"(
            packing: File(path: "lattice.xyzr"),
            contacts: (tolerance: 0.01),
            surface: Calibrated(c_t: Value(1.2732395447351628)),
            materials: [(name: "metal", conductivity: 10.0, density: 8000.0, specific_heat: 500.0,
                         resistivity: {RHO0:?}, resistivity_temp_coeff: {BETA:?}, resistivity_ref_temp: {T0:?})],
            thermal: (initial_temperature: {T0:?}, bcs: [], solver: {solver}),
            electric: (
                electrodes: [{electrodes}],
                surface: Calibrated(c_t: Value(1.2732395447351628)),
                {recouple}
            ),
            outputs: (vtk: false, times: [{outputs}]),
        )"#
    );
    Scene::parse(&text, Path::new("transient.ron"), lattice_dir()).map_err(|e| e.to_string())
}

const FACES: &str = "(face: ZMin, potential: 0.0), (face: ZMax, potential: 0.1)";
const PARTICLES: &str = "(select: Face(ZMin), potential: 0.0), (select: Face(ZMax), potential: 0.1)";

#[test]
fn face_electrodes_give_the_continuum_resistance_and_uniform_joule_power() {
    // Steady without a fixed temperature is refused before any work: use an electric-only
    // scene instead.
    let err = scene(FACES, "Steady", "", "").unwrap_err();
    assert!(err.contains("at least one fixed temperature"), "{err}");
    let s = scene(FACES, "Explicit(t_end: 1e-3, dt: Auto(safety: 0.8))", "", "").unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let el = r.electric.as_ref().unwrap();
    let exact = RHO0 * (NZ as f64 * D) / ((NX * NX) as f64 * D * D);
    let rr = el.report.resistance_ohm.unwrap();
    assert!((rr / exact - 1.0).abs() < 1e-8, "R = {rr}, ρ l / A = {exact}");
    assert!(el.report.current_mismatch < 1e-8);
    // V I = V²/R, all of it in the particles (the faces take none).
    assert!((el.report.joule_w - V0 * V0 / rr).abs() < 1e-8 * el.report.joule_w);
    let (lo, hi) = el
        .joule
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &p| (a.min(p), b.max(p)));
    assert!(hi / lo - 1.0 < 1e-8, "Joule power per particle in [{lo}, {hi}]");
    // Particle electrodes: the electrode layers are equipotential, the network spans NZ − 1
    // contacts, R is (NZ − 1)/NZ of the continuum value.
    let s = scene(PARTICLES, "Explicit(t_end: 1e-3, dt: Auto(safety: 0.8))", "", "").unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    let rp = r.electric.as_ref().unwrap().report.resistance_ohm.unwrap();
    assert!((rp / exact - (NZ - 1) as f64 / NZ as f64).abs() < 1e-8, "{rp}");
}

/// θ̄(t) of every output time (mean over particles; all equal here).
fn rises(r: &RunResult) -> Vec<(f64, f64)> {
    r.thermal
        .as_ref()
        .unwrap()
        .snapshots
        .iter()
        .map(|(t, v)| (*t, v.iter().sum::<f64>() / v.len() as f64 - T0))
        .collect()
}

#[test]
fn coupled_transients_follow_the_exact_solution_within_the_a_priori_bound() {
    // R0 and C from a one-way run (the check is of the coupling, not of R).
    let probe = run(
        &scene(FACES, "Explicit(t_end: 1e-3, dt: Auto(safety: 0.8))", "", "").unwrap(),
        &RunOptions::default(),
    )
    .unwrap();
    let r0 = probe.electric.as_ref().unwrap().report.resistance_ohm.unwrap();
    let n = probe.model.particles.len();
    let c: f64 = probe.thermal_setup.as_ref().unwrap().capacities[..n].iter().sum();
    let p0 = V0 * V0 / r0;
    // Resistance doubles (β θ = 1) at the end: 2 β P0 t / C = 3.
    let t_end = 1.5 * c / (BETA * p0);
    let exact = |t: f64| ((1.0 + 2.0 * BETA * p0 * t / c).sqrt() - 1.0) / BETA;
    let times: Vec<String> = (1..=20)
        .map(|k| format!("{:?}", t_end * k as f64 / 20.0))
        .collect();
    let times = times.join(", ");
    let dt_implicit = t_end / 400.0;
    for solver in [
        "Explicit(t_end: T, dt: Auto(safety: 0.8))".replace('T', &format!("{t_end:?}")),
        format!("Implicit(t_end: {t_end:?}, dt: {dt_implicit:?})"),
    ] {
        let recouple = format!("recouple_tolerance: {TOL:?},");
        let r = run(
            &scene(FACES, &solver, &recouple, &times).unwrap(),
            &RunOptions::default(),
        )
        .unwrap();
        let th = r.thermal.as_ref().unwrap();
        let dt = th.report.dt;
        let bound = BETA * TOL + BETA * p0 * dt / (2.0 * c) + 1e-9;
        let err = rises(&r)
            .iter()
            .map(|&(t, th)| (th / exact(t) - 1.0).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "{solver}: err {err:.3e}, bound {bound:.3e}, {} solves, {} steps",
            r.electric.as_ref().unwrap().report.solves,
            th.report.steps
        );
        assert!(
            err <= bound,
            "{solver}: max relative error {err:.3e} > a priori bound {bound:.3e}"
        );
        // The coupling did re-solve (about θ_end / tol times) and says so.
        let el = r.electric.as_ref().unwrap();
        let expected = 1.0 / (BETA * TOL);
        assert!(
            (el.report.solves as f64) > 0.5 * expected && (el.report.solves as f64) < 2.0 * expected + 2.0,
            "{solver}: {} solves, about {expected} expected",
            el.report.solves
        );
        assert!(el.report.solves_wall_s > 0.0);
        assert!(
            r.diagnostics
                .iter()
                .any(|d| d.contains("potential solves during the transient"))
        );
        assert!(!r.diagnostics.iter().any(|d| d.contains("not time-accurate")));
        // The resistance in force at the end has doubled, within the lag.
        let rr = el.report.resistance_ohm.unwrap();
        assert!(
            (rr / r0 - 2.0).abs() < 2.0 * BETA * TOL + 0.01,
            "{rr} vs 2 × {r0}"
        );
        assert!(
            th.report.energy_balance_error < 1e-9,
            "{}",
            th.report.energy_balance_error
        );
        // The one-way model (β ignored) is far off: θ = P0 t / C, 50 % high at the end.
        let one_way = rises(&r)
            .iter()
            .map(|&(t, _)| (p0 * t / c / exact(t) - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(one_way > 0.4 && one_way > 100.0 * err, "{one_way} vs {err}");
        // Deterministic.
        let again = run(
            &scene(FACES, &solver, &recouple, &times).unwrap(),
            &RunOptions::default(),
        )
        .unwrap();
        assert_eq!(again.thermal.as_ref().unwrap().temperatures, th.temperatures);
    }
}

#[test]
fn bad_electrodes_are_named() {
    let both = "(select: Face(ZMin), face: ZMin, potential: 0.0), (face: ZMax, potential: 0.1)";
    let err = scene(both, "Steady", "", "").unwrap_err();
    assert!(
        err.contains("electric.electrodes[0]") && err.contains("exactly one"),
        "{err}"
    );
    let neither = "(potential: 0.0), (face: ZMax, potential: 0.1)";
    let err = scene(neither, "Steady", "", "").unwrap_err();
    assert!(
        err.contains("electric.electrodes[0]") && err.contains("neither"),
        "{err}"
    );
    // A face the container does not have: refused before any work.
    let err = scene(
        "(face: Outer, potential: 0.0), (face: ZMax, potential: 0.1)",
        "Explicit(t_end: 1e-3, dt: Auto(safety: 0.8))",
        "",
        "",
    )
    .unwrap_err();
    assert!(
        err.contains("electric.electrodes[0].face") && err.contains("Outer"),
        "{err}"
    );
    let explicit = "Explicit(t_end: 1e-3, dt: Auto(safety: 0.8))";
    for tol in ["-1.0", "0.0", "NaN", "inf"] {
        let err = scene(FACES, explicit, &format!("recouple_tolerance: {tol},"), "").unwrap_err();
        assert!(err.contains("electric.recouple_tolerance"), "{err}");
    }
}
