//! λ(T) = λ0 (1 + β (T − T_ref)) on the Laguerre network: a bar held at its two ends against
//! the Kirchhoff-transform profile (u = ∫ λ dT linear in x), steady in a few Anderson-mixed
//! Picard solves; a λ(T) that reaches 0 in the range met is refused by particle and temperature.

mod common;

use common::{laguerre_model, ls_packed, two_walls};
use demcon_core::{Container, Face, Material};
use demcon_graph::InterfaceRule;
use demcon_model::thermal::PICARD_TOLERANCE;
use demcon_model::*;
use demcon_network::FloatingPolicy;

const L: f64 = 4e-3;

fn bar(beta: f64) -> Model {
    let container = Container::Box {
        size: [L, 2e-3, 2e-3],
    };
    let material = Material {
        conductivity_temp_coeff: beta,
        conductivity_ref_temp: 0.0,
        ..Material::thermal("polymer", 0.3, 1200.0, 1500.0)
    };
    laguerre_model(
        ls_packed(container, 2000, 5),
        vec![material],
        Default::default(),
        5,
    )
}

fn steady(m: &Model, t_hot: f64) -> Result<ThermalRun, ModelError> {
    let p = ThermalProblem {
        surface: SurfaceSpec::Laguerre,
        interface: InterfaceRule::HarmonicMean,
        bcs: two_walls(Face::XMin, t_hot, Face::XMax, 0.0),
        sources: Vec::new(),
        solver: ThermalSolver::Steady,
        initial_temperature: 0.0,
        output_times: Vec::new(),
        floating: FloatingPolicy::Fail,
        solve: demcon_network::SolveParams::new(demcon_network::Method::Auto, 1e-12, 100_000),
        progress: None,
    };
    let setup = thermal_setup(m, &p)?;
    let bcs = thermal_bcs(m, &setup, &p)?;
    solve_thermal(m, &setup, &bcs, &p)
}

#[test]
fn a_bar_with_linear_conductivity_follows_the_kirchhoff_profile() {
    // λ falls 20 % from 0 to 100 °C.
    let beta = -2e-3;
    let m = bar(beta);
    let run = steady(&m, 100.0).unwrap();
    // u(T) = T + β T²/2 (per λ0) is linear in x: u(x) = u_h (1 − x/L).
    let u_h = 100.0 + 0.5 * beta * 100.0 * 100.0;
    let worst = run
        .temperatures
        .iter()
        .zip(&m.particles.centres)
        .map(|(t, c)| {
            let u = u_h * (1.0 - c.x / L);
            let exact = ((1.0 + 2.0 * beta * u).sqrt() - 1.0) / beta;
            (t - exact).abs() / 100.0
        })
        .fold(0.0, f64::max);
    eprintln!(
        "λ(T) bar: max error {worst:.3e} of the span, {} solves",
        run.report.nonlinear_iterations
    );
    assert!(worst < 1e-3, "{worst}");
    assert!(run.report.nonlinear_iterations <= 5, "{:?}", run.report);
    assert!(run.report.nonlinear_change <= PICARD_TOLERANCE);
}

#[test]
fn a_conductivity_reaching_zero_is_refused_with_the_particle_and_its_temperature() {
    // λ = 0 at 50 °C: the bar held at 100 °C crosses it.
    let m = bar(-2e-2);
    let e = steady(&m, 100.0).unwrap_err().to_string();
    assert!(
        e.contains("conductivity_temp_coeff") && e.contains("particle") && e.contains("°C"),
        "{e}"
    );
}

#[test]
fn a_table_through_the_same_line_gives_the_same_bar() {
    let beta = -2e-3;
    let linear = steady(&bar(beta), 100.0).unwrap();
    let mut m = bar(0.0);
    m.materials.materials[0].conductivity_table = Some(
        demcon_core::TimeValue::table(
            vec![
                (-10.0, 0.3 * (1.0 - 10.0 * beta)),
                (110.0, 0.3 * (1.0 + 110.0 * beta)),
            ],
            "t",
        )
        .unwrap(),
    );
    let tabled = steady(&m, 100.0).unwrap();
    for (a, b) in linear.temperatures.iter().zip(&tabled.temperatures) {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
    assert_eq!(
        linear.report.nonlinear_iterations,
        tabled.report.nonlinear_iterations
    );
}
