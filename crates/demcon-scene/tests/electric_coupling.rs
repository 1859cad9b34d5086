//! The electro-thermal coupling of a scene: Joule power as the thermal source, and
//! ρ_e(T) = ρ_e0 (1 + β (T − T_ref)) with the potential re-solved until the temperatures
//! settle (`electric.recouple_tolerance`).
//!
//! On a simple-cubic lattice of touching spheres with uniform surfaces every column is the
//! same 1-D chain (no lateral current, no lateral heat flow), so the coupled steady state can
//! be computed independently here by a fixed point on the chain (series resistances and a
//! tridiagonal heat balance) and compared with the scene's result.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use demcon_core::{Container, ParticleSet, Vec3};
use demcon_packing::write_xyzr;
use demcon_scene::{RunOptions, RunResult, Scene, run};

/// Lattice spacing and sphere diameter (m).
const D: f64 = 1e-3;
/// Columns in x and y, particles per column.
const NX: usize = 3;
const NZ: usize = 12;
/// ρ_e0 (Ω·m), λ (W/(m·K)), applied potential (V), end temperature (°C).
const RHO0: f64 = 1e-6;
const LAMBDA: f64 = 10.0;
const V0: f64 = 0.1;
const T0: f64 = 20.0;

/// The folder holding `lattice.xyzr`, written once per test process.
fn lattice_dir() -> PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(write_lattice).clone()
}

fn write_lattice() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("demcon-electric-coupling-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("lattice.xyzr");
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
    let radii = vec![0.5 * D; centres.len()];
    let p = ParticleSet::new(centres, radii).unwrap();
    let c = Container::Box {
        size: [NX as f64 * D, NX as f64 * D, NZ as f64 * D],
    };
    write_xyzr(&path, &p, &c).unwrap();
    dir
}

/// The scene: both ends at T0 and at 0 / V0; surfaces S = D² (so every contact conducts
/// λ D (W/K) and D/ρ_e (S)). `beta` in 1/K; `recouple` is a RON fragment.
fn scene(beta: f64, recouple: &str) -> Scene {
    let text = format!(
        r#"(
            packing: File(path: "lattice.xyzr"),
            contacts: (tolerance: 0.01),
            surface: Calibrated(c_t: Value(1.2732395447351628)),
            materials: [(name: "metal", conductivity: {LAMBDA:?}, density: 8000.0, specific_heat: 500.0,
                         resistivity: {RHO0:?}, resistivity_temp_coeff: {beta:?}, resistivity_ref_temp: {T0:?})],
            thermal: (
                initial_temperature: {T0:?},
                bcs: [FixedTemperature(select: Face(ZMin), value: {T0:?}), FixedTemperature(select: Face(ZMax), value: {T0:?})],
                solver: Steady,
            ),
            electric: (
                electrodes: [(select: Face(ZMin), potential: 0.0), (select: Face(ZMax), potential: {V0:?})],
                surface: Calibrated(c_t: Value(1.2732395447351628)),
                {recouple}
            ),
            outputs: (vtk: false),
        )"#
    );
    Scene::parse(&text, Path::new("coupling.ron"), lattice_dir()).unwrap_or_else(|e| panic!("{e}"))
}

fn resistance(r: &RunResult) -> f64 {
    r.electric.as_ref().unwrap().report.resistance_ohm.unwrap()
}

/// The coupled steady state of one column, computed independently: node k at z_k, contacts
/// of conductance σ_harm D (S) and λ D (W/K), Joule power g Δu² of each contact shared half
/// and half. Returns (resistance of the whole lattice (Ω), temperatures of the column (°C)).
fn chain_reference(beta: f64) -> (f64, Vec<f64>) {
    let n = NZ;
    let mut t = vec![T0; n];
    let h = LAMBDA * D;
    for _ in 0..500 {
        // Electric: contacts in series.
        let sigma: Vec<f64> = t
            .iter()
            .map(|&tk| 1.0 / (RHO0 * (1.0 + beta * (tk - T0))))
            .collect();
        let g: Vec<f64> = (0..n - 1)
            .map(|k| {
                let (a, b) = (sigma[k], sigma[k + 1]);
                let s = if a == b { a } else { 2.0 * a * b / (a + b) };
                s * D
            })
            .collect();
        let r_col: f64 = g.iter().map(|gk| 1.0 / gk).sum();
        let i = V0 / r_col;
        let power: Vec<f64> = (0..n)
            .map(|k| {
                let left = if k > 0 { 0.5 * i * i / g[k - 1] } else { 0.0 };
                let right = if k + 1 < n { 0.5 * i * i / g[k] } else { 0.0 };
                left + right
            })
            .collect();
        // Thermal: h (T_{k−1} − 2 T_k + T_{k+1}) + P_k = 0 on the interior, T fixed at the ends
        // (Thomas algorithm on the interior unknowns).
        let m = n - 2;
        let (mut c, mut d) = (vec![0.0; m], vec![0.0; m]);
        for j in 0..m {
            let k = j + 1;
            let mut rhs = power[k] / h;
            if k == 1 {
                rhs += T0;
            }
            if k == n - 2 {
                rhs += T0;
            }
            // Row: −T_{k−1} + 2 T_k − T_{k+1} = rhs.
            let denom = if j == 0 { 2.0 } else { 2.0 + c[j - 1] };
            c[j] = -1.0 / denom;
            d[j] = (rhs + if j == 0 { 0.0 } else { d[j - 1] }) / denom;
        }
        let mut new = vec![T0; n];
        for j in (0..m).rev() {
            let next = if j + 1 < m { new[j + 2] } else { 0.0 };
            new[j + 1] = d[j] - c[j] * next;
        }
        let moved = new.iter().zip(&t).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        t = new;
        if moved < 1e-12 {
            return (r_col / (NX * NX) as f64, t);
        }
    }
    panic!("the reference chain did not converge");
}

fn column_temperatures(r: &RunResult) -> Vec<f64> {
    // Particle (i, j, k) has id k·NX² + j·NX + i; take the column i = j = 0.
    let t = &r.thermal.as_ref().unwrap().temperatures;
    (0..NZ).map(|k| t[k * NX * NX]).collect()
}

#[test]
fn constant_resistivity_gives_the_kohlrausch_temperature_on_every_particle() {
    let r = run(&scene(0.0, ""), &RunOptions::default()).unwrap();
    let el = r.electric.as_ref().unwrap();
    let th = r.thermal.as_ref().unwrap();
    let exact_rise = V0 * V0 / (8.0 * RHO0 * LAMBDA);
    for (u, t) in el.potentials.iter().zip(&th.temperatures) {
        let k = T0 + u * (V0 - u) / (2.0 * RHO0 * LAMBDA);
        assert!((t - k).abs() < 1e-7 * exact_rise, "T = {t}, Kohlrausch {k}");
    }
    // Total Joule power = V0 I = V0² / R, all of it conducted out through the two ends.
    let p: f64 = el.joule.iter().sum();
    assert!((p / (V0 * V0 / resistance(&r)) - 1.0).abs() < 1e-9);
    let (r_ref, t_ref) = chain_reference(0.0);
    assert!((resistance(&r) / r_ref - 1.0).abs() < 1e-9);
    for (a, b) in column_temperatures(&r).iter().zip(&t_ref) {
        assert!((a - b).abs() < 1e-7 * exact_rise, "{a} vs {b}");
    }
}

#[test]
fn positive_beta_recouples_to_the_independent_fixed_point_and_raises_r() {
    let beta = 4e-3;
    let cold = resistance(&run(&scene(0.0, ""), &RunOptions::default()).unwrap());
    let s = scene(beta, "recouple_tolerance: 1e-7,");
    let r = run(&s, &RunOptions::default()).unwrap();
    let rounds: usize = r
        .diagnostics
        .iter()
        .find_map(|d| {
            d.strip_prefix("electro-thermal coupling converged in ")
                .and_then(|s| s.split_whitespace().next())
                .and_then(|n| n.parse().ok())
        })
        .unwrap_or_else(|| panic!("no convergence diagnostic: {:?}", r.diagnostics));
    assert!(rounds >= 3, "{rounds} rounds");
    let hot = resistance(&r);
    // Heating raises ρ_e: R rises, by much more than the solver tolerance.
    assert!(hot > 1.1 * cold, "R hot {hot} vs cold {cold}");
    // The same fixed point computed independently on one column.
    let (r_ref, t_ref) = chain_reference(beta);
    assert!((hot / r_ref - 1.0).abs() < 1e-6, "R {hot} vs reference {r_ref}");
    for (a, b) in column_temperatures(&r).iter().zip(&t_ref) {
        assert!((a - b).abs() < 1e-5, "T {a} vs reference {b}");
    }
    // Self-consistency: the potential was solved with the final temperatures' ρ_e.
    let el = r.electric.as_ref().unwrap();
    let th = r.thermal.as_ref().unwrap();
    let problem = s.problem().clone();
    let again = demcon_model::solve_electric(
        &r.model,
        problem.electric.as_ref().unwrap(),
        Some(&th.temperatures),
    )
    .unwrap();
    let r_again = again.report.resistance_ohm.unwrap();
    assert!((r_again / hot - 1.0).abs() < 1e-6, "{r_again} vs {hot}");
    assert_eq!(el.potentials.len(), again.potentials.len());
}

#[test]
fn negative_beta_lowers_r_and_a_runaway_is_reported() {
    let cold = resistance(&run(&scene(0.0, ""), &RunOptions::default()).unwrap());
    let r = run(&scene(-1e-3, "recouple_tolerance: 1e-7,"), &RunOptions::default()).unwrap();
    let (r_ref, _) = chain_reference(-1e-3);
    assert!(resistance(&r) < 0.95 * cold, "{} vs {cold}", resistance(&r));
    assert!((resistance(&r) / r_ref - 1.0).abs() < 1e-6);
    // ρ_e would fall to zero long before the 125 K rise: a clear error, not NaN.
    let err = run(&scene(-2e-2, "recouple_tolerance: 1e-7,"), &RunOptions::default()).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("resistivity") || msg.contains("recouple_tolerance"),
        "{msg}"
    );
    assert!(!msg.contains("NaN"), "{msg}");
}

#[test]
fn the_coupled_run_is_deterministic() {
    let s = scene(4e-3, "recouple_tolerance: 1e-7,");
    let a = run(&s, &RunOptions::default()).unwrap();
    let b = demcon_scene::run_on_model(&s, a.model.clone()).unwrap();
    assert_eq!(
        a.thermal.as_ref().unwrap().temperatures,
        b.thermal.as_ref().unwrap().temperatures
    );
    assert_eq!(resistance(&a).to_bits(), resistance(&b).to_bits());
}

#[test]
fn bad_recouple_tolerances_are_refused_and_a_one_way_beta_is_reported() {
    for tol in ["0.0", "-1.0", "NaN", "inf"] {
        let text = scene(0.0, "").config().clone();
        let mut cfg = text.clone();
        cfg.electric.as_mut().unwrap().recouple_tolerance = Some(tol.parse().unwrap());
        let err = Scene::from_config(cfg, lattice_dir()).unwrap_err().to_string();
        assert!(err.contains("electric.recouple_tolerance"), "{err}");
    }
    // Without thermal physics there are no temperatures to recouple with.
    let mut cfg = scene(0.0, "").config().clone();
    cfg.thermal = None;
    cfg.electric.as_mut().unwrap().recouple_tolerance = Some(1e-3);
    let err = Scene::from_config(cfg, lattice_dir()).unwrap_err().to_string();
    assert!(err.contains("needs `thermal`"), "{err}");
    // β without recoupling: ρ_e at T_ref (same R as β = 0), and the run says so.
    let cold = resistance(&run(&scene(0.0, ""), &RunOptions::default()).unwrap());
    let r = run(&scene(4e-3, ""), &RunOptions::default()).unwrap();
    assert_eq!(resistance(&r), cold);
    assert!(
        r.diagnostics.iter().any(|d| d.contains("one-way coupling")),
        "{:?}",
        r.diagnostics
    );
}
