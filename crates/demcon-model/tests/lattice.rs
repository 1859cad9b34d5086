//! The model's physics on a simple-cubic lattice of touching unit spheres, where the network
//! is exact: with C_t = 4/π every contact surface is d² = 1 m², so a column of n spheres
//! between two walls (half-links of h = R, S = 1 m²) conducts exactly like the continuum
//! (λ_e = λ, R = ρ_e L / A). Each test states the exact value it checks.

mod common;

use approx::assert_relative_eq;
use common::{C_T, lattice, metal, two_walls, z_face_electrodes};
use demcon_core::{Container, Face, Selector};
use demcon_graph::InterfaceRule;
use demcon_model::*;
use demcon_network::FloatingPolicy;

fn steady(bcs: Vec<ThermalBc>) -> ThermalProblem {
    ThermalProblem {
        surface: SurfaceSpec::Calibrated(CtSpec::Value(C_T)),
        interface: InterfaceRule::HarmonicMean,
        bcs,
        sources: Vec::new(),
        solver: ThermalSolver::Steady,
        initial_temperature: 0.0,
        output_times: Vec::new(),
        floating: FloatingPolicy::Fail,
        solve: default_solve_params(),
        progress: None,
    }
}

#[test]
fn walls_give_the_continuum_conductivity_exactly() {
    let model = lattice(3, 6, 3, vec![metal()]);
    let problem = steady(two_walls(Face::YMin, 0.0, Face::YMax, 1.0));
    let setup = thermal_setup(&model, &problem).unwrap();
    // Contacts: λ S / d = 10 W/K; wall links: λ S / h = 20 W/K, one per face particle.
    assert!(
        setup
            .contact_conductances()
            .iter()
            .all(|&g| (g - 10.0).abs() < 1e-9)
    );
    assert_eq!(setup.walls.len(), 2 * 9);
    assert!(setup.wall_conductances().iter().all(|&g| (g - 20.0).abs() < 1e-9));
    let bcs = thermal_bcs(&model, &setup, &problem).unwrap();
    let run = solve_thermal(&model, &setup, &bcs, &problem).unwrap();
    assert_eq!(run.wall_temperatures, vec![0.0, 1.0]);
    // A linear field: the layer at y = j + 0.5 sits at (j + 0.5)/6.
    for (p, t) in run.temperatures.iter().enumerate() {
        let y = model.particles.centres[p].y;
        assert_relative_eq!(*t, y / 6.0, epsilon = 1e-8);
    }
    // The heat flow through the hot wall: λ A ΔT / L = 10 · 9 / 6 = 15 W.
    let hot = bcs.fixed_sets[1].nodes(&setup.walls);
    let q = demcon_network::boundary_flow(
        setup.network(&model),
        &setup.conductances,
        &run.node_temperatures(),
        &hot,
    )
    .unwrap();
    assert_relative_eq!(q, 15.0, epsilon = 1e-7);
}

#[test]
fn calibration_with_walls_finds_four_over_pi_on_the_lattice() {
    // With C_t = 1 the lattice conducts π/4 of the continuum, so C_t = 4/π.
    let model = lattice(3, 5, 3, vec![metal()]);
    let cal = calibrate_ct_with(&model, CalibrationBc::Walls).unwrap();
    assert_relative_eq!(cal.c_t, C_T, epsilon = 1e-8);
    assert_eq!(cal.method, "walls-y");
    // The same lattice in a periodic box is calibrated by homogenisation: 4/π again, and the
    // calibrated network then homogenises to λ I.
    let mut packed = model.clone();
    packed.container = Container::Periodic {
        size: [3.0, 5.0, 3.0],
    };
    let periodic = build_model(
        Packed {
            particles: packed.particles.clone(),
            container: packed.container,
            report: None,
            imported_from: None,
            pack_s: 0.0,
        },
        &ModelParams {
            materials: packed.materials.clone(),
            carve: None,
            phases: Vec::new(),
            phase_rule: PhaseRule::Centre,
            contacts: demcon_graph::ContactParams::relative(0.01),
            laguerre: None,
            defects: Default::default(),
            seed: 1,
            fields: FieldNames::default(),
        },
    )
    .unwrap();
    let cal = calibrate_ct(&periodic).unwrap();
    assert_eq!(cal.method, "homogenized");
    assert_relative_eq!(cal.c_t, C_T, epsilon = 1e-8);
    let h = homogenize_thermal(
        &periodic,
        &SurfaceSpec::Calibrated(CtSpec::Auto),
        InterfaceRule::HarmonicMean,
        &default_solve_params(),
    )
    .unwrap();
    assert_eq!(h.report.axes.map(|x| (x - 10.0).abs() < 1e-8), [true; 3]);
}

#[test]
fn face_electrodes_give_rho_l_over_a_and_one_way_joule_heat() {
    let model = lattice(2, 2, 8, vec![metal()]);
    let electric = z_face_electrodes(SurfaceSpec::Calibrated(CtSpec::Value(C_T)), 1e-3);
    let el = solve_electric(&model, &electric, None).unwrap();
    let r_exact = 2.0e-7 * 8.0 / 4.0;
    assert_relative_eq!(el.report.resistance_ohm.unwrap(), r_exact, max_relative = 1e-8);
    // Every Joule watt is booked to a particle: Σ P = V² / R.
    assert_relative_eq!(el.report.joule_w, 1e-6 / r_exact, max_relative = 1e-8);
    // One-way coupling: the steady thermal solve with the uniform Joule sources, both faces
    // held at 0 °C, gives the chain's discrete parabola in every column.
    let thermal = steady(two_walls(Face::ZMin, 0.0, Face::ZMax, 0.0));
    let setup = thermal_setup(&model, &thermal).unwrap();
    let bcs = thermal_bcs(&model, &setup, &thermal).unwrap();
    let c = couple(&model, &setup, &bcs, &thermal, &electric).unwrap();
    assert_eq!(c.electric.report.solves, 1);
    let q = el.report.joule_w / 32.0; // W per particle (each stands for 1 m³)
    let mean = c.thermal.temperatures.iter().sum::<f64>() / 32.0;
    let exact = discrete_mean_rise(8, q, 10.0);
    assert_relative_eq!(mean, exact, max_relative = 1e-7);
}

/// Mean temperature of the n nodes of a chain (unit spacing, conductance λ between nodes and
/// 2λ to the two walls at 0), each with the source q (W per unit cell).
fn discrete_mean_rise(n: usize, q: f64, lambda: f64) -> f64 {
    let mut a = vec![vec![0.0; n]; n];
    for j in 0..n {
        let left = if j == 0 { 2.0 * lambda } else { lambda };
        let right = if j == n - 1 { 2.0 * lambda } else { lambda };
        a[j][j] = left + right;
        if j > 0 {
            a[j][j - 1] = -lambda;
        }
        if j + 1 < n {
            a[j][j + 1] = -lambda;
        }
    }
    // Thomas algorithm.
    let mut b = vec![q; n];
    for j in 1..n {
        let m = a[j][j - 1] / a[j - 1][j - 1];
        a[j][j] -= m * a[j - 1][j];
        b[j] -= m * b[j - 1];
    }
    let mut t = vec![0.0; n];
    for j in (0..n).rev() {
        let next = if j + 1 < n { a[j][j + 1] * t[j + 1] } else { 0.0 };
        t[j] = (b[j] - next) / a[j][j];
    }
    t.iter().sum::<f64>() / n as f64
}

#[test]
fn bad_selections_name_the_field() {
    let model = lattice(2, 2, 2, vec![metal()]);
    let problem = steady(vec![
        ThermalBc::FixedTemperature {
            select: Selector::Particles(vec![]),
            value: 0.0,
        },
        ThermalBc::WallTemperature {
            face: Face::ZMax,
            value: 1.0.into(),
        },
    ]);
    let setup = thermal_setup(&model, &problem).unwrap();
    let err = thermal_bcs(&model, &setup, &problem).unwrap_err().to_string();
    assert!(err.contains("`bcs[0]"), "{err}");
    // A wall on a face the container lacks.
    let bad = steady(vec![ThermalBc::WallTemperature {
        face: Face::Outer,
        value: 1.0.into(),
    }]);
    let err = thermal_setup(&model, &bad).unwrap_err().to_string();
    assert!(err.contains("bcs"), "{err}");
    // A steady solve with nothing fixed.
    let none = steady(vec![]);
    let setup = thermal_setup(&model, &none).unwrap();
    let err = thermal_bcs(&model, &setup, &none).unwrap_err().to_string();
    assert!(err.contains("at least one fixed temperature"), "{err}");
}

#[test]
fn refusals_name_the_callers_fields() {
    let mut model = lattice(2, 2, 2, vec![metal()]);
    let no_hold = steady(Vec::new());
    let setup = thermal_setup(&model, &no_hold).unwrap();
    let by_default = thermal_bcs(&model, &setup, &no_hold).unwrap_err().to_string();
    assert!(by_default.starts_with("field `bcs`"), "{by_default}");
    model.fields = FieldNames {
        bcs: "study.holds",
        ..FieldNames::MODEL
    };
    let named = thermal_bcs(&model, &setup, &no_hold).unwrap_err().to_string();
    assert!(named.starts_with("field `study.holds`"), "{named}");
    let nowhere = steady(vec![ThermalBc::FixedTemperature {
        select: Selector::Phase(7),
        value: 1.0,
    }]);
    let err = thermal_bcs(&model, &setup, &nowhere).unwrap_err().to_string();
    assert!(err.contains("`study.holds[0].select`"), "{err}");
}
