//! Grain boundaries: on a cubic lattice whose Laguerre cells are cubes, one h on every facet
//! between cells gives λ_e = L / (n d/λ + (n − 1)/h) exactly (the wall facets are not grain
//! boundaries); a spread draws the same factors for any thread count.

mod common;

use common::{laguerre_model, metal, two_walls};
use demcon_core::{Axis, Container, Face, ParticleSet, Vec3};
use demcon_graph::InterfaceRule;
use demcon_model::*;
use demcon_network::FloatingPolicy;

fn lattice(n: usize, gb: Option<GrainBoundary>) -> Model {
    let mut centres = Vec::new();
    for k in 0..n {
        for j in 0..3 {
            for i in 0..3 {
                centres.push(Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5));
            }
        }
    }
    let m = centres.len();
    let packed = Packed {
        particles: ParticleSet::new(centres, vec![0.5; m]).unwrap(),
        container: Container::Box {
            size: [3.0, 3.0, n as f64],
        },
        report: None,
        imported_from: None,
        pack_s: 0.0,
    };
    let defects = DefectSpec {
        grain_boundaries: gb.into_iter().collect(),
        ..Default::default()
    };
    laguerre_model(packed, vec![metal()], defects, 1)
}

fn etc(m: &Model) -> f64 {
    let p = ThermalProblem {
        surface: SurfaceSpec::Laguerre,
        interface: InterfaceRule::HarmonicMean,
        bcs: two_walls(Face::ZMin, 0.0, Face::ZMax, 1.0),
        sources: Vec::new(),
        solver: ThermalSolver::Steady,
        initial_temperature: 0.0,
        output_times: Vec::new(),
        floating: FloatingPolicy::Fail,
        solve: demcon_network::SolveParams::new(demcon_network::Method::Auto, 1e-13, 100_000),
        progress: None,
    };
    let setup = thermal_setup(m, &p).unwrap();
    let bcs = thermal_bcs(m, &setup, &p).unwrap();
    let run = solve_thermal(m, &setup, &bcs, &p).unwrap();
    effective_conductivity(m, Axis::Z, &setup, &bcs, &run.node_temperatures(), false)
        .unwrap()
        .lambda_e
}

fn boundary(h: f64, spread: Option<f64>) -> GrainBoundary {
    GrainBoundary {
        phase: 0,
        conductance: h,
        electric_resistance: None,
        spread,
        seed: 7,
    }
}

#[test]
fn one_conductance_on_every_facet_of_a_cubic_lattice_is_exact() {
    let n = 8;
    assert!((etc(&lattice(n, None)) / 10.0 - 1.0).abs() < 1e-10);
    for h in [1.0, 10.0, 100.0] {
        let exact = n as f64 / (n as f64 / 10.0 + (n - 1) as f64 / h);
        let got = etc(&lattice(n, Some(boundary(h, None))));
        assert!((got / exact - 1.0).abs() < 1e-10, "h = {h}: {got} vs {exact}");
    }
}

#[test]
fn a_spread_of_boundary_conductances_is_seeded_per_facet() {
    let a = etc(&lattice(6, Some(boundary(10.0, Some(0.5)))));
    let b = etc(&lattice(6, Some(boundary(10.0, Some(0.5)))));
    assert_eq!(a.to_bits(), b.to_bits());
    let uniform = etc(&lattice(6, Some(boundary(10.0, None))));
    // Log-normal factors of mean 1 on h: the mean resistance 1/h·E[1/X] = (1 + cv²)/h is
    // larger, so the body conducts less.
    assert!(a < uniform, "{a} vs {uniform}");
}
