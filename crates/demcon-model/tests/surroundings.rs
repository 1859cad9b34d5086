//! Faces exchanging heat with their surroundings on the Laguerre network: a homogeneous bar
//! held at one end and convecting and/or radiating at the other is linear in x, with the
//! face's balance λ (T_h − T_f)/L = h (T_f − T∞) + ε σ (T_f⁴ − T_s⁴) solved here by bisection —
//! so the network is exact to round-off (the Robin link is the half-cell and the film in
//! series), and every cell's heat flux is the bar's, the cells on the exchanging face included.

mod common;

use common::{laguerre_model, ls_packed, metal};
use demcon_core::{Container, Face};
use demcon_graph::InterfaceRule;
use demcon_model::surroundings::{KELVIN, STEFAN_BOLTZMANN};
use demcon_model::*;
use demcon_network::FloatingPolicy;

const L: f64 = 4e-3;
const LAMBDA: f64 = 10.0;

fn bar(n: usize, seed: u64) -> Model {
    let container = Container::Box {
        size: [L, 2e-3, 2e-3],
    };
    laguerre_model(
        ls_packed(container, n, seed),
        vec![metal()],
        Default::default(),
        seed,
    )
}

fn problem(bcs: Vec<ThermalBc>, solver: ThermalSolver) -> ThermalProblem {
    ThermalProblem {
        surface: SurfaceSpec::Laguerre,
        interface: InterfaceRule::HarmonicMean,
        bcs,
        sources: Vec::new(),
        solver,
        initial_temperature: 20.0,
        output_times: Vec::new(),
        floating: FloatingPolicy::Fail,
        solve: demcon_network::SolveParams::new(demcon_network::Method::Auto, 1e-13, 200_000),
        progress: None,
    }
}

/// The face temperature of the exact bar (°C), by bisection on the face's balance.
fn exact_face(t_hot: f64, h: f64, t_inf: f64, eps: f64, t_s: f64) -> f64 {
    let f = |t: f64| {
        LAMBDA * (t_hot - t) / L
            - h * (t - t_inf)
            - eps * STEFAN_BOLTZMANN * ((t + KELVIN).powi(4) - (t_s + KELVIN).powi(4))
    };
    let (mut lo, mut hi) = (-KELVIN, t_hot.max(t_inf).max(t_s));
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

fn check(m: &Model, bcs: Vec<ThermalBc>, t_hot: f64, law: (f64, f64, f64, f64)) -> ThermalRun {
    let (h, t_inf, eps, t_s) = law;
    let p = problem(bcs, ThermalSolver::Steady);
    let setup = thermal_setup(m, &p).unwrap();
    let tb = thermal_bcs(m, &setup, &p).unwrap();
    let run = solve_thermal(m, &setup, &tb, &p).unwrap();
    let t_f = exact_face(t_hot, h, t_inf, eps, t_s);
    let grad = (t_f - t_hot) / L;
    for (i, t) in run.temperatures.iter().enumerate() {
        let want = t_hot + grad * m.particles.centres[i].x;
        assert!(
            (t - want).abs() < 1e-9 * t_hot.abs(),
            "particle {i}: {t} vs {want}"
        );
    }
    let q = flux_density(
        &setup.heat_dipoles(m, 0.0, &run.node_temperatures()),
        &setup.rep_volumes,
    );
    for (i, f) in q.iter().enumerate() {
        assert!(
            (f.x / (-LAMBDA * grad) - 1.0).abs() < 1e-8,
            "flux of particle {i}: {f}"
        );
    }
    let r = &run.report.faces[0];
    let area = 4e-6;
    assert!((r.area_m2 / area - 1.0).abs() < 1e-12, "{r:?}");
    let out = r.convection_w + r.radiation_w;
    assert!((out / (-LAMBDA * grad * area) - 1.0).abs() < 1e-9, "{r:?}");
    assert!(
        (r.surface_temperature[0] - t_f).abs() < 1e-9 * t_hot
            && (r.surface_temperature[1] - t_f).abs() < 1e-9 * t_hot
    );
    run
}

#[test]
fn convection_radiation_and_both_at_one_face_are_exact_in_a_homogeneous_bar() {
    let m = bar(1200, 3);
    let hot = ThermalBc::WallTemperature {
        face: Face::XMin,
        value: 400.0.into(),
    };
    let conv = ThermalBc::Convection {
        face: Face::XMax,
        h: 5e3,
        t_inf: 20.0.into(),
    };
    let rad = ThermalBc::Radiation {
        face: Face::XMax,
        emissivity: 0.8,
        t_surroundings: (-20.0).into(),
    };
    let run = check(&m, vec![hot.clone(), conv.clone()], 400.0, (5e3, 20.0, 0.0, 0.0));
    assert_eq!(run.report.nonlinear_iterations, 1);
    let run = check(&m, vec![hot.clone(), rad.clone()], 400.0, (0.0, 0.0, 0.8, -20.0));
    assert!(run.report.nonlinear_iterations <= 8, "{:?}", run.report);
    check(&m, vec![conv, hot, rad], 400.0, (5e3, 20.0, 0.8, -20.0));
}

#[test]
fn an_etc_is_refused_when_a_face_exchanges_heat() {
    let m = bar(300, 1);
    let bcs = vec![
        ThermalBc::WallTemperature {
            face: Face::XMin,
            value: 100.0.into(),
        },
        ThermalBc::WallTemperature {
            face: Face::XMax,
            value: 0.0.into(),
        },
        ThermalBc::Convection {
            face: Face::YMin,
            h: 10.0,
            t_inf: 20.0.into(),
        },
    ];
    let p = problem(bcs, ThermalSolver::Steady);
    let setup = thermal_setup(&m, &p).unwrap();
    let tb = thermal_bcs(&m, &setup, &p).unwrap();
    let run = solve_thermal(&m, &setup, &tb, &p).unwrap();
    let err = effective_conductivity(
        &m,
        demcon_core::Axis::X,
        &setup,
        &tb,
        &run.node_temperatures(),
        false,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("surroundings"), "{err}");
}
