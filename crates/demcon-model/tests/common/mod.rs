//! The lattice model shared by the model crate's integration tests.
#![allow(dead_code)]

use demcon_core::Face;
use demcon_core::{Container, Material, MaterialTable, ParticleSet, Vec3};
use demcon_graph::ContactParams;
use demcon_graph::InterfaceRule;
use demcon_model::{
    ElectricProblem, Electrode, ElectrodeAt, FieldNames, Model, ModelParams, Packed, PhaseRule, SurfaceSpec,
    ThermalBc, build_model, default_solve_params,
};
use demcon_network::FloatingPolicy;

/// A Gaussian-0.3 LS packing of `n` spheres at φ = 0.55 in `container`, from `seed`.
pub fn ls_packed(container: Container, n: usize, seed: u64) -> Packed {
    let params = demcon_packing::PackingParams::new(
        container,
        n,
        0.55,
        demcon_packing::RadiusDistribution::gaussian(0.3),
    );
    let (particles, report) = demcon_packing::pack(&params, seed, None).unwrap();
    Packed {
        particles,
        container,
        report: Some(report),
        imported_from: None,
        pack_s: 0.0,
    }
}

/// The Laguerre model of `packed`: `materials` (the first everywhere), `defects`.
pub fn laguerre_model(
    packed: Packed,
    materials: Vec<Material>,
    defects: demcon_model::DefectSpec,
    seed: u64,
) -> Model {
    let params = ModelParams {
        materials: MaterialTable::new(materials).unwrap(),
        carve: None,
        phases: Vec::new(),
        phase_rule: PhaseRule::Centre,
        contacts: ContactParams::default(),
        laguerre: Some(demcon_graph::LaguerreParams::default()),
        defects,
        seed,
        fields: FieldNames::default(),
    };
    build_model(packed, &params).unwrap()
}

/// An nx × ny × nz lattice of spheres of radius 0.5 m in a box of the same size (m).
pub fn lattice(nx: usize, ny: usize, nz: usize, materials: Vec<Material>) -> Model {
    let mut centres = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                centres.push(Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5));
            }
        }
    }
    let n = centres.len();
    let packed = Packed {
        particles: ParticleSet::new(centres, vec![0.5; n]).unwrap(),
        container: Container::Box {
            size: [nx as f64, ny as f64, nz as f64],
        },
        report: None,
        imported_from: None,
        pack_s: 0.0,
    };
    let params = ModelParams {
        materials: MaterialTable::new(materials).unwrap(),
        carve: None,
        phases: Vec::new(),
        phase_rule: PhaseRule::Centre,
        contacts: ContactParams::relative(0.01),
        laguerre: None,
        defects: Default::default(),
        seed: 1,
        fields: FieldNames::default(),
    };
    build_model(packed, &params).unwrap()
}

/// The lattice's metal: λ = 10 W/(m·K), ρ = 8000 kg/m³, c = 500 J/(kg·K), ρ_e = 2e-7 Ω·m.
pub fn metal() -> Material {
    Material {
        resistivity: Some(2.0e-7),
        ..Material::thermal("metal", 10.0, 8000.0, 500.0)
    }
}

/// C_t at which every contact surface of the lattice is d² = 1 m².
pub const C_T: f64 = 4.0 / std::f64::consts::PI;

/// Electrodes on the faces ZMin (0 V) and ZMax (`volts`), η = 1, under `surface`.
pub fn z_face_electrodes(surface: SurfaceSpec, volts: f64) -> ElectricProblem {
    ElectricProblem {
        surface,
        interface: InterfaceRule::HarmonicMean,
        electrodes: vec![
            Electrode {
                at: ElectrodeAt::Face(Face::ZMin),
                potential: 0.0.into(),
            },
            Electrode {
                at: ElectrodeAt::Face(Face::ZMax),
                potential: volts.into(),
            },
        ],
        eta: 1.0,
        floating: FloatingPolicy::Fail,
        recouple_tolerance: None,
        current: None,
        solve: default_solve_params(),
    }
}

/// The two faces `lo` and `hi` held at `t_lo` and `t_hi` (°C) through wall links.
pub fn two_walls(lo: Face, t_lo: f64, hi: Face, t_hi: f64) -> Vec<ThermalBc> {
    vec![
        ThermalBc::WallTemperature {
            face: lo,
            value: t_lo.into(),
        },
        ThermalBc::WallTemperature {
            face: hi,
            value: t_hi.into(),
        },
    ]
}
