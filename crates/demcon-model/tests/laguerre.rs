//! The Laguerre network on LS packings: exact for a linear field by construction, so a
//! homogeneous body between two walls gives λ_e = λ and T_p = linear in x_p to round-off,
//! face electrodes give R = ρ_e L/A, and an imposed flux enters through the cells' wall facets.

mod common;

use approx::assert_relative_eq;
use common::{laguerre_model, ls_packed, metal, two_walls, z_face_electrodes};
use demcon_core::{Container, Face, MaterialTable};
use demcon_graph::{ContactParams, InterfaceRule};
use demcon_model::*;
use demcon_network::FloatingPolicy;

/// A Gaussian-0.3 LS packing of `n` spheres in `container`, tessellated.
fn model(container: Container, n: usize, seed: u64) -> Model {
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
        initial_temperature: 0.0,
        output_times: Vec::new(),
        floating: FloatingPolicy::Fail,
        solve: default_solve_params(),
        progress: None,
    }
}

#[test]
fn a_homogeneous_box_between_two_walls_is_exact() {
    let m = model(
        Container::Box {
            size: [3e-3, 2e-3, 2e-3],
        },
        1500,
        1,
    );
    let t = m.report.tessellation.as_ref().unwrap();
    assert!(t.volume_error.abs() < 1e-12, "{t:?}");
    let p = problem(two_walls(Face::XMin, 0.0, Face::XMax, 3.0), ThermalSolver::Steady);
    let setup = thermal_setup(&m, &p).unwrap();
    // Capacities: the cells tile the box, so Σ C = ρ c V.
    let c: f64 = setup.capacities[..m.particles.len()].iter().sum();
    assert_relative_eq!(c, 8000.0 * 500.0 * 12e-9, max_relative = 1e-12);
    let bcs = thermal_bcs(&m, &setup, &p).unwrap();
    let run = solve_thermal(&m, &setup, &bcs, &p).unwrap();
    for (i, t) in run.temperatures.iter().enumerate() {
        assert_relative_eq!(*t, m.particles.centres[i].x * 1e3, epsilon = 1e-9);
    }
    let hot = bcs.fixed_sets[1].nodes(&setup.walls);
    let q = demcon_network::boundary_flow(
        setup.network(&m),
        &setup.conductances,
        &run.node_temperatures(),
        &hot,
    )
    .unwrap();
    // λ A ΔT / L = 10 · 4e-6 · 3 / 3e-3.
    assert_relative_eq!(q, 0.04, max_relative = 1e-9);
}

#[test]
fn face_electrodes_give_rho_l_over_a() {
    let m = model(
        Container::Box {
            size: [2e-3, 2e-3, 4e-3],
        },
        1500,
        2,
    );
    let e = z_face_electrodes(SurfaceSpec::Laguerre, 1e-3);
    let run = solve_electric(&m, &e, None).unwrap();
    assert_relative_eq!(
        run.report.resistance_ohm.unwrap(),
        2.0e-7 * 4e-3 / 4e-6,
        max_relative = 1e-9
    );
    // An imposed current of 3 A, entering by the first electrode (ZMin) and leaving by the
    // second (ZMax), which keeps its 1 mV: the found drop is I R exactly, the power I² R.
    let driven = ElectricProblem {
        current: Some(3.0),
        ..e.clone()
    };
    let run = solve_electric(&m, &driven, None).unwrap();
    let r = 2.0e-7 * 4e-3 / 4e-6;
    let [v_in, v_out] = run.report.electrode_potentials[..] else {
        panic!("{:?}", run.report.electrode_potentials)
    };
    assert_eq!(v_out, 1e-3);
    assert_relative_eq!(v_in - v_out, 3.0 * r, max_relative = 1e-9);
    assert_relative_eq!(run.report.current_in, 3.0, max_relative = 1e-9);
    assert_relative_eq!(run.report.joule_w, 9.0 * r, max_relative = 1e-9);
    // Three electrodes cannot share one current.
    let mut three = driven.clone();
    three.electrodes.push(three.electrodes[0].clone());
    assert!(solve_electric(&m, &three, None).is_err());
}

#[test]
fn an_imposed_flux_enters_through_the_wall_facets() {
    // A transient with a flux on XMin and nothing else: the heat stored is the heat injected.
    let m = model(
        Container::Box {
            size: [2e-3, 2e-3, 2e-3],
        },
        1000,
        3,
    );
    let p = ThermalProblem {
        output_times: vec![0.05],
        ..problem(
            vec![ThermalBc::HeatFlux {
                face: Face::XMin,
                flux: 1e4.into(),
            }],
            ThermalSolver::Implicit {
                t_end: 0.05,
                dt: 0.01,
                scheme: demcon_thermal::Scheme::BackwardEuler,
            },
        )
    };
    let setup = thermal_setup(&m, &p).unwrap();
    let bcs = thermal_bcs(&m, &setup, &p).unwrap();
    let total: f64 = bcs.sources.iter().sum();
    assert_relative_eq!(total, 1e4 * 4e-6, max_relative = 1e-12);
    let run = solve_thermal(&m, &setup, &bcs, &p).unwrap();
    let stored: f64 = run
        .temperatures
        .iter()
        .zip(&setup.capacities)
        .map(|(t, c)| t * c)
        .sum();
    assert_relative_eq!(stored, total * 0.05, max_relative = 1e-8);
}

#[test]
fn mixing_the_laguerre_surface_with_a_contact_graph_is_refused() {
    let packed = Packed {
        particles: demcon_core::ParticleSet::new(
            vec![
                demcon_core::Vec3::new(0.5, 0.5, 0.5),
                demcon_core::Vec3::new(1.5, 0.5, 0.5),
            ],
            vec![0.5, 0.5],
        )
        .unwrap(),
        container: Container::Box {
            size: [2.0, 1.0, 1.0],
        },
        report: None,
        imported_from: None,
        pack_s: 0.0,
    };
    let params = ModelParams {
        materials: MaterialTable::new(vec![metal()]).unwrap(),
        carve: None,
        phases: Vec::new(),
        phase_rule: PhaseRule::Centre,
        contacts: ContactParams::relative(0.01),
        laguerre: None,
        defects: Default::default(),
        seed: 1,
        fields: FieldNames::default(),
    };
    let m = build_model(packed, &params).unwrap();
    let p = problem(Vec::new(), ThermalSolver::Steady);
    let e = thermal_setup(&m, &p).unwrap_err().to_string();
    assert!(e.contains("Laguerre"), "{e}");
}

#[test]
fn a_homogeneous_periodic_packing_homogenises_to_lambda_times_identity() {
    let m = model(
        Container::Periodic {
            size: [2e-3, 2e-3, 2e-3],
        },
        1500,
        4,
    );
    let solve = default_solve_params();
    let h = homogenize_thermal(&m, &SurfaceSpec::Laguerre, InterfaceRule::HarmonicMean, &solve).unwrap();
    for i in 0..3 {
        for j in 0..3 {
            let expect = if i == j { 10.0 } else { 0.0 };
            assert!(
                (h.report.tensor[i][j] - expect).abs() < 1e-9 * 10.0,
                "{:?}",
                h.report.tensor
            );
        }
    }
    let e = homogenize_electric(&m, &SurfaceSpec::Laguerre, InterfaceRule::HarmonicMean, &solve).unwrap();
    for k in 0..3 {
        assert_relative_eq!(e.report.axes[k], 1.0 / 2.0e-7, max_relative = 1e-9);
    }
    // The papers' models on the same packing: a calibrated C_t (by homogenisation) gives λ on
    // average over the axes by construction; Terreros α carries its bias.
    let c = homogenize_thermal(
        &m,
        &SurfaceSpec::Calibrated(CtSpec::Auto),
        InterfaceRule::HarmonicMean,
        &solve,
    )
    .unwrap();
    assert_eq!(c.calibration.as_ref().unwrap().method, "homogenized");
    assert_relative_eq!(c.report.axes.iter().sum::<f64>() / 3.0, 10.0, max_relative = 1e-9);
    // A box is refused with the field named.
    let b = model(
        Container::Box {
            size: [2e-3, 2e-3, 2e-3],
        },
        500,
        5,
    );
    let err = homogenize_thermal(&b, &SurfaceSpec::Laguerre, InterfaceRule::HarmonicMean, &solve)
        .unwrap_err()
        .to_string();
    assert!(err.contains("`solver`") && err.contains("Periodic"), "{err}");
}

#[test]
fn a_homogeneous_cylinder_between_its_end_walls_is_exact() {
    // The mantle is one polygon of tangent planes for every cell: the cells along it close, so
    // the axial field is exact; the section is the polygon's.
    let m = model(
        Container::Cylinder {
            radius: 1e-3,
            length: 3e-3,
        },
        2000,
        6,
    );
    let p = problem(two_walls(Face::ZMin, 0.0, Face::ZMax, 3.0), ThermalSolver::Steady);
    let setup = thermal_setup(&m, &p).unwrap();
    let bcs = thermal_bcs(&m, &setup, &p).unwrap();
    let run = solve_thermal(&m, &setup, &bcs, &p).unwrap();
    for (i, t) in run.temperatures.iter().enumerate() {
        assert_relative_eq!(*t, m.particles.centres[i].z * 1e3, epsilon = 1e-9);
    }
    let t = m.report.tessellation.as_ref().unwrap();
    assert!(t.volume_error > 0.0 && t.volume_error < 1e-3, "{t:?}");
    assert!(t.max_area_mismatch < 1e-9, "{t:?}");
}

#[test]
fn the_heat_flux_and_the_current_density_are_exact_in_every_particle() {
    // One construction for both fields (flux_dipoles: contacts at their facets' centroids, wall
    // links, divided by twice the cell volume): in a uniform field every particle's flux is
    // −λ∇T, every particle's current density −∇u/ρ_e, along the bar, wall cells included.
    // Solved to 1e-13 so that round-off, not the solve, bounds them: 1e-9 relative.
    let m = model(
        Container::Box {
            size: [2e-3, 4e-3, 2e-3],
        },
        1500,
        7,
    );
    let tight = demcon_network::SolveParams::new(demcon_network::Method::Auto, 1e-13, 200_000);
    let check = |what: &str, field: &[demcon_core::Vec3], exact: f64| {
        for (p, f) in field.iter().enumerate() {
            assert!(
                (f.y / exact - 1.0).abs() < 1e-9
                    && f.x.abs() < 1e-9 * exact.abs()
                    && f.z.abs() < 1e-9 * exact.abs(),
                "{what} of particle {p}: {f} for {exact} along y"
            );
        }
    };
    // Heat: 0 °C on YMin, 4 °C on YMax: q = −λ ∂T/∂y = −10 · 1000 W/m².
    let p = ThermalProblem {
        solve: tight,
        ..problem(two_walls(Face::YMin, 0.0, Face::YMax, 4.0), ThermalSolver::Steady)
    };
    let setup = thermal_setup(&m, &p).unwrap();
    let bcs = thermal_bcs(&m, &setup, &p).unwrap();
    let run = solve_thermal(&m, &setup, &bcs, &p).unwrap();
    let d = flux_dipoles(&m, &setup.walls, &setup.conductances, &run.node_temperatures());
    check("heat flux", &flux_density(&d, &setup.rep_volumes), -1e4);
    // Current: 0 V on YMin, 1 mV on YMax: j = −(1 mV / 4 mm) / ρ_e, from YMax to YMin.
    let mut e = z_face_electrodes(SurfaceSpec::Laguerre, 1e-3);
    e.electrodes[0].at = ElectrodeAt::Face(Face::YMin);
    e.electrodes[1].at = ElectrodeAt::Face(Face::YMax);
    e.solve = tight;
    let el = solve_electric(&m, &e, None).unwrap();
    assert_eq!(el.rep_volumes, m.graph.cells.as_ref().unwrap().volume);
    check("current density", &el.current_density(&m), -0.25 / 2.0e-7);
}

#[test]
fn the_joule_power_is_what_the_current_dissipates_and_eta_of_it_heats() {
    // ΔV = 1 mV across a bar of resistance R: the current dissipates ΔV²/R = ΔV·I whatever η
    // (`joule_w`, and Σ I²/G over the branches: contacts.vtp's sum); η = 0.5 of it heats the
    // particles (`joule_heat_w`, Σ of the per-particle power).
    let m = model(
        Container::Box {
            size: [2e-3, 2e-3, 4e-3],
        },
        1000,
        8,
    );
    let mut e = z_face_electrodes(SurfaceSpec::Laguerre, 1e-3);
    e.eta = 0.5;
    let el = solve_electric(&m, &e, None).unwrap();
    let r = el.report.resistance_ohm.unwrap();
    assert_relative_eq!(el.report.joule_w, 1e-6 / r, max_relative = 1e-9);
    assert_relative_eq!(
        el.report.joule_w,
        1e-3 * el.report.current_in,
        max_relative = 1e-9
    );
    let branches: f64 = el
        .branch_currents
        .iter()
        .zip(&el.conductances)
        .map(|(i, g)| i * i / g)
        .sum();
    assert_relative_eq!(branches, el.report.joule_w, max_relative = 1e-9);
    let heat: f64 = el.joule.iter().sum();
    assert_relative_eq!(el.report.joule_heat_w, heat, max_relative = 1e-12);
    assert_relative_eq!(heat, 0.5 * el.report.joule_w, max_relative = 1e-9);
}
