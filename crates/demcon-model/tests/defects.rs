//! Interfaces, cracks, damage and broken bonds on a simple-cubic lattice of unit spheres, where
//! every series resistance is exact: with C_t = 4/π (contacts) or the Laguerre cells (unit
//! cubes) each contact has S = 1 m², d = 1 m, and a column between two walls is a chain of
//! resistances 1/λ per metre plus whatever the defects add. Each test states its exact value.

mod common;

use approx::assert_relative_eq;
use common::{C_T, two_walls};
use demcon_core::{Container, Face, Material, MaterialTable, ParticleSet, Region, Vec3};
use demcon_graph::{ContactParams, CrackShape, InterfaceRule, LaguerreParams};
use demcon_model::*;
use demcon_network::FloatingPolicy;
use std::sync::OnceLock;

const LAMBDA: [f64; 2] = [10.0, 2.0];
const RHO_E: [f64; 2] = [2.0e-7, 5.0e-6];

fn materials() -> MaterialTable {
    MaterialTable::new(vec![
        Material {
            resistivity: Some(RHO_E[0]),
            ..Material::thermal("a", LAMBDA[0], 8000.0, 500.0)
        },
        Material {
            resistivity: Some(RHO_E[1]),
            ..Material::thermal("b", LAMBDA[1], 2000.0, 800.0)
        },
    ])
    .unwrap()
}

/// An nx × ny × nz lattice of spheres of radius 0.5 m in a box of the same size, phase 1 for
/// the region `layer` (by `rule`), the Laguerre cells or contacts, with `defects`.
fn lattice(
    n: [usize; 3],
    layer: Option<Region>,
    rule: PhaseRule,
    laguerre: bool,
    defects: DefectSpec,
) -> Result<Model, ModelError> {
    let mut centres = Vec::new();
    for i in 0..n[0] {
        for j in 0..n[1] {
            for k in 0..n[2] {
                centres.push(Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5));
            }
        }
    }
    let count = centres.len();
    let packed = Packed {
        particles: ParticleSet::new(centres, vec![0.5; count]).unwrap(),
        container: Container::Box {
            size: n.map(|v| v as f64),
        },
        report: None,
        imported_from: None,
        pack_s: 0.0,
    };
    let params = ModelParams {
        materials: materials(),
        carve: None,
        phases: layer
            .map(|region| vec![PhaseSpec::Region { phase: 1, region }])
            .unwrap_or_default(),
        phase_rule: rule,
        contacts: ContactParams::relative(0.01),
        laguerre: laguerre.then(LaguerreParams::default),
        defects,
        seed: 1,
        fields: FieldNames::default(),
    };
    build_model(packed, &params)
}

fn surface(laguerre: bool) -> SurfaceSpec {
    if laguerre {
        SurfaceSpec::Laguerre
    } else {
        SurfaceSpec::Calibrated(CtSpec::Value(C_T))
    }
}

fn steady(laguerre: bool, floating: FloatingPolicy) -> ThermalProblem {
    ThermalProblem {
        surface: surface(laguerre),
        interface: InterfaceRule::HarmonicMean,
        bcs: two_walls(Face::YMin, 0.0, Face::YMax, 1.0),
        sources: Vec::new(),
        solver: ThermalSolver::Steady,
        initial_temperature: 0.0,
        output_times: Vec::new(),
        floating,
        solve: default_solve_params(),
        progress: None,
    }
}

/// The heat flow (W) into the hot wall (YMax, 1 °C) with the cold wall (YMin) at 0 °C.
fn heat_flow(model: &Model, floating: FloatingPolicy) -> Result<f64, ModelError> {
    let laguerre = model.graph.cells.is_some();
    let problem = steady(laguerre, floating);
    let setup = thermal_setup(model, &problem)?;
    let bcs = thermal_bcs(model, &setup, &problem)?;
    let run = solve_thermal(model, &setup, &bcs, &problem)?;
    let hot = bcs.fixed_sets[1].nodes(&setup.walls);
    Ok(demcon_network::boundary_flow(
        setup.network(model),
        &setup.conductances,
        &run.node_temperatures(),
        &hot,
    )?)
}

fn layer(y0: f64, y1: f64) -> Region {
    Region::Box {
        min: Vec3::new(-1.0, y0, -1.0),
        max: Vec3::new(10.0, y1, 10.0),
    }
}

fn plane_y(y: f64) -> CrackShape {
    CrackShape::Polygon {
        points: vec![
            Vec3::new(-1.0, y, -1.0),
            Vec3::new(10.0, y, -1.0),
            Vec3::new(10.0, y, 10.0),
            Vec3::new(-1.0, y, 10.0),
        ],
    }
}

fn interface(h: f64, r_c: Option<f64>) -> DefectSpec {
    DefectSpec {
        interfaces: vec![InterfaceResistance {
            phases: [0, 1],
            conductance: h,
            electric_resistance: r_c,
        }],
        ..DefectSpec::default()
    }
}

#[test]
fn a_layered_bar_adds_one_over_h_per_interface_exactly() {
    // 3 × 6 × 3 cells, phase b for 2 < y < 4 (by centre: the layers y = 2.5, 3.5), two
    // interfaces on the facets y = 2 and y = 4: R·A = 4/λ_a + 2/λ_b + 2/h over A = 9 m².
    let h = 3.0;
    for laguerre in [true, false] {
        let m = lattice(
            [3, 6, 3],
            Some(layer(2.0, 4.0)),
            PhaseRule::Centre,
            laguerre,
            interface(h, None),
        )
        .unwrap();
        assert_eq!(m.defects.report.interface_contacts, 18);
        assert_eq!(
            m.contact_marks()
                .iter()
                .filter(|&&b| b & MARK_INTERFACE != 0)
                .count(),
            18
        );
        let q = heat_flow(&m, FloatingPolicy::Fail).unwrap();
        let r = 4.0 / LAMBDA[0] + 2.0 / LAMBDA[1] + 2.0 / h;
        assert_relative_eq!(q, 9.0 / r, max_relative = 1e-9);
    }
}

#[test]
fn the_segment_rule_puts_the_interface_where_it_cuts_the_chain() {
    // A 1 × 6 × 1 column, phase b above y = 2.3 (inside the particle at y = 2.5): the chain is
    // exactly 2.3/λ_a + 3.7/λ_b + 1/h.
    let h = 7.0;
    let m = lattice(
        [1, 6, 1],
        Some(layer(2.3, 10.0)),
        PhaseRule::Segment,
        false,
        interface(h, None),
    )
    .unwrap();
    assert_eq!(m.defects.report.interface_contacts, 1);
    let q = heat_flow(&m, FloatingPolicy::Fail).unwrap();
    assert_relative_eq!(
        q,
        1.0 / (2.3 / LAMBDA[0] + 3.7 / LAMBDA[1] + 1.0 / h),
        max_relative = 1e-9
    );
}

#[test]
fn the_electric_interface_resistance_is_in_series() {
    // Layers normal to z: phase b for 1 < z < 2 in a 2 × 2 × 4 lattice, face electrodes on
    // ZMin and ZMax: R = (3 ρ_a + ρ_b + 2 r_c)/A with A = 4 m².
    let r_c = 1.0e-6;
    let region = Region::Box {
        min: Vec3::new(-1.0, -1.0, 1.0),
        max: Vec3::new(10.0, 10.0, 2.0),
    };
    for laguerre in [true, false] {
        let m = lattice(
            [2, 2, 4],
            Some(region.clone()),
            PhaseRule::Centre,
            laguerre,
            interface(5.0, Some(r_c)),
        )
        .unwrap();
        let run = solve_electric(&m, &common::z_face_electrodes(surface(laguerre), 1.0), None).unwrap();
        let expect = (3.0 * RHO_E[0] + RHO_E[1] + 2.0 * r_c) / 4.0;
        assert_relative_eq!(run.report.resistance_ohm.unwrap(), expect, max_relative = 1e-8);
    }
}

#[test]
fn a_crack_across_the_whole_section_passes_no_heat() {
    for laguerre in [true, false] {
        let defects = DefectSpec {
            cracks: vec![Crack {
                shape: plane_y(3.0),
                gap_conductance: None,
                gap_electric_resistance: None,
            }],
            ..DefectSpec::default()
        };
        let m = lattice([3, 6, 3], None, PhaseRule::Centre, laguerre, defects).unwrap();
        assert_eq!(m.cut_contacts().len(), 9);
        assert_eq!(m.crack_face_particles().len(), 18);
        assert_eq!(m.defects.report.components_after_cuts, 2);
        assert!(
            m.cut_contacts()
                .iter()
                .all(|c| matches!(c.cause, CutCause::Crack { crack: 0, point } if point[1] == 3.0))
        );
        let q = heat_flow(&m, FloatingPolicy::Fail).unwrap();
        assert!(q.abs() < 1e-12, "{q}");
    }
}

/// A crack in the plane y = 3 covering x < `edge` over the whole depth.
fn half_plane_y(edge: f64) -> CrackShape {
    CrackShape::Polygon {
        points: vec![
            Vec3::new(-1.0, 3.0, -1.0),
            Vec3::new(edge, 3.0, -1.0),
            Vec3::new(edge, 3.0, 10.0),
            Vec3::new(-1.0, 3.0, 10.0),
        ],
    }
}

#[test]
fn an_open_crack_cuts_laguerre_facets_by_the_part_it_covers() {
    let spec = |edge: f64, whole: bool| DefectSpec {
        cracks: vec![Crack {
            shape: half_plane_y(edge),
            gap_conductance: None,
            gap_electric_resistance: None,
        }],
        whole_facet_cuts: whole,
        ..DefectSpec::default()
    };
    let flow = |edge: f64, whole: bool| {
        let m = lattice([4, 6, 4], None, PhaseRule::Centre, true, spec(edge, whole)).unwrap();
        (heat_flow(&m, FloatingPolicy::Fail).unwrap(), m)
    };
    // The edge through the middle of the facets of the third column (x = 2.5): the first two
    // columns are cut, the third keeps about half of each facet.
    let (q_half, m) = flow(2.5, false);
    assert_eq!(m.cut_contacts().len(), 8);
    let partly = m
        .contact_marks()
        .iter()
        .filter(|&&b| b & MARK_PARTLY_CUT != 0)
        .count();
    assert_eq!(partly, 4);
    assert_eq!(m.defects.report.partly_cut_by_cracks, 4);
    // Edges between the columns (x = 2, x = 3; the facets, read as discs of their area,
    // overhang them a little) bracket the half-covered one.
    let (q_two, _) = flow(2.0, false);
    let (q_three, _) = flow(3.0, false);
    assert!(q_three < q_half && q_half < q_two, "{q_three} {q_half} {q_two}");
    // The segment rule cuts whole facets only.
    let (_, whole) = flow(2.4, true);
    assert_eq!(whole.defects.report.partly_cut_by_cracks, 0);
    assert_eq!(whole.cut_contacts().len(), 8);
}

#[test]
fn a_filled_crack_adds_its_gap_resistance_and_damage_scales() {
    let h_gap = 4.0;
    let defects = DefectSpec {
        cracks: vec![Crack {
            shape: plane_y(3.0),
            gap_conductance: Some(h_gap),
            gap_electric_resistance: None,
        }],
        ..DefectSpec::default()
    };
    let m = lattice([3, 6, 3], None, PhaseRule::Centre, true, defects).unwrap();
    assert!(m.cut_contacts().is_empty());
    assert_eq!(
        m.contact_marks()
            .iter()
            .filter(|&&b| b & MARK_FILLED_CRACK != 0)
            .count(),
        9
    );
    let q = heat_flow(&m, FloatingPolicy::Fail).unwrap();
    assert_relative_eq!(q, 9.0 / (6.0 / LAMBDA[0] + 1.0 / h_gap), max_relative = 1e-9);
    // Damage 0.5 below y = 2.9 by midpoint: the wall links (midpoint y = 0.25) and the
    // contacts at y = 1, 2 double their resistance: R·A = (1 + 2 + 2 + 3·1 + 0.5)/λ.
    let defects = DefectSpec {
        damage: vec![Damage {
            region: layer(-1.0, 2.9),
            factor: 0.5,
        }],
        ..DefectSpec::default()
    };
    let m = lattice([3, 6, 3], None, PhaseRule::Centre, true, defects).unwrap();
    // 18 along y and 36 across (in the layers y = 0.5, 1.5, 2.5; they carry no flow).
    assert_eq!(m.defects.report.damaged_contacts, 54);
    let q = heat_flow(&m, FloatingPolicy::Fail).unwrap();
    assert_relative_eq!(q, 9.0 / (8.5 / LAMBDA[0]), max_relative = 1e-9);
}

#[test]
fn a_cracked_off_slab_is_a_floating_cluster() {
    let defects = DefectSpec {
        cracks: [2.0, 4.0]
            .map(|y| Crack {
                shape: plane_y(y),
                gap_conductance: None,
                gap_electric_resistance: None,
            })
            .to_vec(),
        ..DefectSpec::default()
    };
    let m = lattice([3, 6, 3], None, PhaseRule::Centre, true, defects).unwrap();
    assert_eq!(m.defects.report.components_after_cuts, 3);
    let e = heat_flow(&m, FloatingPolicy::Fail).unwrap_err().to_string();
    assert!(e.contains("float") || e.contains("Float"), "{e}");
    let problem = steady(true, FloatingPolicy::Exclude);
    let setup = thermal_setup(&m, &problem).unwrap();
    let bcs = thermal_bcs(&m, &setup, &problem).unwrap();
    assert_eq!(bcs.constraints.excluded().len(), 18);
}

#[test]
fn broken_bonds_are_cut_and_bad_pairs_reported() {
    // Particle ids on the lattice: (i·ny + j)·nz + k; 0–1 are neighbours along z, 0–5 not.
    let defects = DefectSpec {
        cut_pairs: vec![[1, 0], [0, 5], [0, 1]],
        ..DefectSpec::default()
    };
    let m = lattice([2, 2, 4], None, PhaseRule::Centre, false, defects).unwrap();
    assert_eq!(m.cut_contacts().len(), 1);
    assert_eq!(m.cut_contacts()[0].pair, [0, 1]);
    let r = m.report.defects.as_ref().unwrap();
    assert_eq!((r.broken_bonds, r.broken_not_contacts), (1, 1));
    let defects = DefectSpec {
        cut_pairs: vec![[0, 1], [3, 16]],
        ..DefectSpec::default()
    };
    let e = lattice([2, 2, 4], None, PhaseRule::Centre, false, defects)
        .unwrap_err()
        .to_string();
    assert!(e.contains("`cut_pairs[1][1]`") && e.contains("0..16"), "{e}");
}

#[test]
fn bad_defects_are_refused_with_their_field() {
    let cases: Vec<(DefectSpec, &str)> = vec![
        (interface(0.0, None), "interfaces[0].conductance"),
        (interface(-1.0, None), "interfaces[0].conductance"),
        (
            DefectSpec {
                interfaces: vec![InterfaceResistance {
                    phases: [0, 2],
                    conductance: 1.0,
                    electric_resistance: None,
                }],
                ..DefectSpec::default()
            },
            "interfaces[0].between[1]",
        ),
        (
            DefectSpec {
                cracks: vec![Crack {
                    shape: CrackShape::Disc {
                        centre: Vec3::zeros(),
                        normal: Vec3::z(),
                        radius: 0.0,
                    },
                    gap_conductance: None,
                    gap_electric_resistance: None,
                }],
                ..DefectSpec::default()
            },
            "cracks[0].radius",
        ),
        (
            DefectSpec {
                damage: vec![Damage {
                    region: layer(0.0, 1.0),
                    factor: 1.5,
                }],
                ..DefectSpec::default()
            },
            "damage[0].factor",
        ),
    ];
    for (spec, field) in cases {
        let e = lattice([1, 2, 1], None, PhaseRule::Centre, false, spec)
            .unwrap_err()
            .to_string();
        assert!(e.contains(field), "{field}: {e}");
    }
}

#[test]
fn a_crack_outside_the_domain_is_reported() {
    let defects = DefectSpec {
        cracks: vec![Crack {
            shape: CrackShape::Disc {
                centre: Vec3::new(50.0, 50.0, 50.0),
                normal: Vec3::y(),
                radius: 1.0,
            },
            gap_conductance: None,
            gap_electric_resistance: None,
        }],
        ..DefectSpec::default()
    };
    let m = lattice([2, 2, 2], None, PhaseRule::Centre, false, defects).unwrap();
    let w = &m.report.defects.as_ref().unwrap().warnings;
    assert!(w.len() == 1 && w[0].contains("cracks[0]"), "{w:?}");
}

#[test]
fn periodic_cracks_and_determinism_on_a_random_packing() {
    use demcon_packing::{PackingParams, RadiusDistribution, pack};
    let container = Container::Periodic { size: [1e-3; 3] };
    let mut pp = PackingParams::new(container, 800, 0.6, RadiusDistribution::gaussian(0.3));
    pp.max_wall_s = 60.0;
    let (particles, _) = pack(&pp, 3, None).unwrap();
    // A penny crack that crosses the cell boundary x = 0: its images cut contacts there too.
    let defects = DefectSpec {
        cracks: vec![Crack {
            shape: CrackShape::Disc {
                centre: Vec3::new(0.0, 0.5e-3, 0.5e-3),
                normal: Vec3::z(),
                radius: 0.3e-3,
            },
            gap_conductance: None,
            gap_electric_resistance: None,
        }],
        damage: vec![Damage {
            region: Region::Sphere {
                centre: Vec3::new(0.5e-3, 0.5e-3, 0.5e-3),
                radius: 0.2e-3,
            },
            factor: 0.3,
        }],
        ..DefectSpec::default()
    };
    let build = || {
        laguerre_model(
            &particles,
            container,
            Vec::new(),
            PhaseRule::Centre,
            defects.clone(),
        )
    };
    let (a, b) = (build(), build());
    let cut = a.cut_contacts();
    assert!(cut.len() > 10, "{}", cut.len());
    // Cut on both sides of the boundary x = 0 (points wrapped into the cell or not).
    assert!(
        cut.iter()
            .any(|c| matches!(c.cause, CutCause::Crack { point, .. } if point[0] < 0.0 || point[0] > 0.9e-3))
    );
    assert!(
        cut.iter()
            .any(|c| matches!(c.cause, CutCause::Crack { point, .. } if (0.0..0.3e-3).contains(&point[0])))
    );
    assert_eq!(a.cut_contacts(), b.cut_contacts());
    assert_eq!(a.contact_marks(), b.contact_marks());
    let solve = default_solve_params();
    let ha = homogenize_thermal(&a, &SurfaceSpec::Laguerre, InterfaceRule::HarmonicMean, &solve).unwrap();
    let hb = homogenize_thermal(&b, &SurfaceSpec::Laguerre, InterfaceRule::HarmonicMean, &solve).unwrap();
    assert_eq!(ha.report.tensor, hb.report.tensor);
    // The crack (normal z) and the damage lower λ_zz below λ.
    assert!(
        ha.report.tensor[2][2] < 0.99 * LAMBDA[0],
        "{:?}",
        ha.report.tensor
    );
}

#[test]
fn a_cut_leaves_the_surfaces_of_the_other_contacts_unchanged() {
    // Terreros α reads the neighbour count: it must be the packing's, cut contacts included,
    // or a crack would widen the surfaces of every contact of its face particles.
    let crack = DefectSpec {
        cracks: vec![Crack {
            shape: plane_y(3.0),
            gap_conductance: None,
            gap_electric_resistance: None,
        }],
        ..DefectSpec::default()
    };
    let plain = lattice([3, 6, 3], None, PhaseRule::Centre, false, DefectSpec::default()).unwrap();
    let cut = lattice([3, 6, 3], None, PhaseRule::Centre, false, crack).unwrap();
    let mut problem = steady(false, FloatingPolicy::Fail);
    problem.surface = SurfaceSpec::TerrerosAlpha;
    let a = thermal_setup(&plain, &problem).unwrap();
    let b = thermal_setup(&cut, &problem).unwrap();
    let area_of = |m: &Model, s: &ThermalSetup, pair: [u32; 2]| {
        let k = m.graph.pairs.iter().position(|&p| p == pair).unwrap();
        s.areas(m)[k]
    };
    for &pair in &cut.graph.pairs {
        assert_eq!(area_of(&plain, &a, pair), area_of(&cut, &b, pair));
    }
    assert_eq!(a.wall_conductances(), b.wall_conductances());
}

#[test]
fn a_crack_between_the_face_and_the_first_layer_cuts_the_wall_links() {
    // The plane y = 0.25 lies between the face y = 0 and the centres of the first layer: it
    // cuts no contact, only the 9 wall links of YMin, so no heat flows.
    for laguerre in [true, false] {
        let defects = DefectSpec {
            cracks: vec![Crack {
                shape: plane_y(0.25),
                gap_conductance: None,
                gap_electric_resistance: None,
            }],
            ..DefectSpec::default()
        };
        let m = lattice([3, 6, 3], None, PhaseRule::Centre, laguerre, defects).unwrap();
        assert!(m.cut_contacts().is_empty());
        // It crosses the wall links, so it is no crack "that crosses nothing".
        let report = m.report.defects.as_ref().unwrap();
        assert_eq!(report.crack_wall_links, 9);
        assert!(report.warnings.is_empty(), "{:?}", report.warnings);
        let problem = steady(laguerre, FloatingPolicy::Fail);
        let setup = thermal_setup(&m, &problem).unwrap();
        assert_eq!(setup.walls.len(), 9);
        assert!(setup.walls.links(0).is_empty());
        assert!(heat_flow(&m, FloatingPolicy::Fail).unwrap().abs() < 1e-12);
    }
}

#[test]
fn an_open_crack_cuts_whatever_filled_cracks_the_segment_also_crosses() {
    // A filled crack listed first at y = 2.9 and an open one at y = 3.0: the branches between
    // the layers y = 2.5 and 3.5 cross both and are cut; nothing flows.
    let defects = DefectSpec {
        cracks: vec![
            Crack {
                shape: plane_y(2.9),
                gap_conductance: Some(1.0),
                gap_electric_resistance: None,
            },
            Crack {
                shape: plane_y(3.0),
                gap_conductance: None,
                gap_electric_resistance: None,
            },
        ],
        ..DefectSpec::default()
    };
    let m = lattice([3, 6, 3], None, PhaseRule::Centre, true, defects).unwrap();
    assert_eq!(m.cut_contacts().len(), 9);
    assert!(
        m.cut_contacts()
            .iter()
            .all(|c| matches!(c.cause, CutCause::Crack { crack: 1, .. }))
    );
    assert!(heat_flow(&m, FloatingPolicy::Fail).unwrap().abs() < 1e-12);
    // Two filled cracks on the same branches add their gaps.
    let (h1, h2) = (4.0, 6.0);
    let defects = DefectSpec {
        cracks: [(2.9, h1), (3.0, h2)]
            .map(|(y, h)| Crack {
                shape: plane_y(y),
                gap_conductance: Some(h),
                gap_electric_resistance: None,
            })
            .to_vec(),
        ..DefectSpec::default()
    };
    let m = lattice([3, 6, 3], None, PhaseRule::Centre, true, defects).unwrap();
    let q = heat_flow(&m, FloatingPolicy::Fail).unwrap();
    assert_relative_eq!(
        q,
        9.0 / (6.0 / LAMBDA[0] + 1.0 / h1 + 1.0 / h2),
        max_relative = 1e-9
    );
}

/// The bar of the random-packing tests (m): 40 × 100 × 40 mm, the gradient along y.
const BAR: [f64; 3] = [0.04, 0.1, 0.04];

/// A Gaussian-0.3 LS packing of 2000 spheres in [`BAR`] (made once), tessellated, material a,
/// with `defects`.
/// The Laguerre model of `particles` in `container` with `phases` under `rule` and `defects`.
fn laguerre_model(
    particles: &ParticleSet,
    container: Container,
    phases: Vec<PhaseSpec>,
    rule: PhaseRule,
    defects: DefectSpec,
) -> Model {
    let packed = Packed {
        particles: particles.clone(),
        container,
        report: None,
        imported_from: None,
        pack_s: 0.0,
    };
    let params = ModelParams {
        materials: materials(),
        carve: None,
        phases,
        phase_rule: rule,
        contacts: ContactParams::default(),
        laguerre: Some(LaguerreParams::default()),
        defects,
        seed: 1,
        fields: FieldNames::default(),
    };
    build_model(packed, &params).unwrap()
}

fn laguerre_bar(defects: DefectSpec) -> Model {
    use demcon_packing::{PackingParams, RadiusDistribution, pack};
    static PACKING: OnceLock<ParticleSet> = OnceLock::new();
    let container = Container::Box { size: BAR };
    let particles = PACKING.get_or_init(|| {
        let params = PackingParams::new(container, 2000, 0.55, RadiusDistribution::gaussian(0.3));
        pack(&params, 1, None).unwrap().0
    });
    laguerre_model(particles, container, Vec::new(), PhaseRule::Centre, defects)
}

/// The plane y = `y` over the bar's section, reaching `margin` (m) past its side walls (0:
/// exactly the section).
fn bar_section(y: f64, margin: f64) -> CrackShape {
    let (lo, x, z) = (-margin, BAR[0] + margin, BAR[2] + margin);
    CrackShape::Polygon {
        points: vec![
            Vec3::new(lo, y, lo),
            Vec3::new(x, y, lo),
            Vec3::new(x, y, z),
            Vec3::new(lo, y, z),
        ],
    }
}

#[test]
fn an_open_crack_over_exactly_the_section_of_a_random_bar_passes_no_heat() {
    // The facets along the side walls, read as discs of their area, reach past the walls; only
    // their tubes inside the bar count, so a crack that ends at the walls covers them wholly
    // (before: 36 % of the uncracked heat flow passed).
    for margin in [0.0, 0.01] {
        let m = laguerre_bar(DefectSpec {
            cracks: vec![Crack {
                shape: bar_section(0.0503, margin),
                gap_conductance: None,
                gap_electric_resistance: None,
            }],
            ..DefectSpec::default()
        });
        assert_eq!(m.defects.report.partly_cut_by_cracks, 0, "margin {margin}");
        assert_eq!(m.defects.report.components_after_cuts, 2);
        let q = heat_flow(&m, FloatingPolicy::Fail).unwrap();
        assert!(q.abs() < 1e-12, "margin {margin}: {q} W");
    }
}

/// Electrodes on the faces YMin (0 V) and YMax (1 V) of the Laguerre cells.
fn y_face_electrodes() -> ElectricProblem {
    let mut e = common::z_face_electrodes(SurfaceSpec::Laguerre, 1.0);
    e.electrodes[0].at = ElectrodeAt::Face(Face::YMin);
    e.electrodes[1].at = ElectrodeAt::Face(Face::YMax);
    e
}

#[test]
fn a_filled_crack_across_a_random_bar_is_the_exact_series() {
    // A filled crack over the whole section is an interface on a surface: each branch it
    // crosses gets 1/(h S |e·n|) (r_gap/(S |e·n|)), so the piecewise-linear continuum field
    // solves the Laguerre network exactly (Σ S e = 0 per cell), wherever the plane cuts the
    // cells. λ_e = L/(L/λ + 1/h) and R = (ρ_e L + r_gap)/A, with the gap half of the total.
    //
    // Tolerance: 1e-9 relative, as the homogeneous bars (the solve's residual, 1e-10). An
    // a-priori 0.5 % would already have caught the error this test was written for: without
    // |e·n| the gap's resistance was too small on every oblique branch, λ_e +18.4 % and R
    // −31 % on this bar (19.54 for 16.5 at λ = 33, h = 330, the figures of issue 31).
    let l = BAR[1];
    let area = BAR[0] * BAR[2];
    let h = LAMBDA[0] / l;
    let r_gap = RHO_E[0] * l;
    let lambda_e = l / (l / LAMBDA[0] + 1.0 / h);
    let resistance = (RHO_E[0] * l + r_gap) / area;
    // Mid-length, over exactly the section and reaching past it; and between the face YMin
    // and the nearest centres, where it crosses wall links as well as contacts.
    for (y, margin) in [(0.0503, 0.0), (0.0503, 0.01), (0.001, 0.0)] {
        let m = laguerre_bar(DefectSpec {
            cracks: vec![Crack {
                shape: bar_section(y, margin),
                gap_conductance: Some(h),
                gap_electric_resistance: Some(r_gap),
            }],
            ..DefectSpec::default()
        });
        let report = m.report.defects.as_ref().unwrap();
        assert!(
            report.filled_crack_contacts > 0 && report.warnings.is_empty(),
            "{report:?}"
        );
        assert_eq!(report.crack_wall_links > 0, y < 0.01, "{report:?}");
        let q = heat_flow(&m, FloatingPolicy::Fail).unwrap();
        assert_relative_eq!(q * l / area, lambda_e, max_relative = 1e-9);
        let run = solve_electric(&m, &y_face_electrodes(), None).unwrap();
        assert_relative_eq!(
            run.report.resistance_ohm.unwrap(),
            resistance,
            max_relative = 1e-9
        );
    }
}

#[test]
fn a_filled_crack_between_the_face_and_the_first_layer_fills_the_wall_links() {
    // The plane y = 0.25 crosses only the 9 wall links of YMin: the chain is 6/λ + 1/h.
    let h = 4.0;
    for laguerre in [true, false] {
        let defects = DefectSpec {
            cracks: vec![Crack {
                shape: plane_y(0.25),
                gap_conductance: Some(h),
                gap_electric_resistance: None,
            }],
            ..DefectSpec::default()
        };
        let m = lattice([3, 6, 3], None, PhaseRule::Centre, laguerre, defects).unwrap();
        let report = m.report.defects.as_ref().unwrap();
        assert_eq!((report.filled_crack_contacts, report.crack_wall_links), (0, 9));
        assert!(report.warnings.is_empty(), "{:?}", report.warnings);
        let q = heat_flow(&m, FloatingPolicy::Fail).unwrap();
        assert_relative_eq!(q, 9.0 / (6.0 / LAMBDA[0] + 1.0 / h), max_relative = 1e-9);
    }
}

#[test]
fn a_filled_crack_covers_laguerre_facets_in_part() {
    // As the open crack above: the edge x = 2.5 through the middle of the third column's
    // facets puts the gap on about half of each (in parallel with the open half), between the
    // edges x = 2 and x = 3; the whole-facet rule puts it on the whole facet or none.
    let spec = |edge: f64, whole: bool| DefectSpec {
        cracks: vec![Crack {
            shape: half_plane_y(edge),
            gap_conductance: Some(0.5),
            gap_electric_resistance: None,
        }],
        whole_facet_cuts: whole,
        ..DefectSpec::default()
    };
    let flow = |edge: f64, whole: bool| {
        let m = lattice([4, 6, 4], None, PhaseRule::Centre, true, spec(edge, whole)).unwrap();
        (heat_flow(&m, FloatingPolicy::Fail).unwrap(), m)
    };
    let (q_half, m) = flow(2.5, false);
    assert_eq!(m.defects.report.filled_crack_contacts, 12);
    let (q_two, _) = flow(2.0, false);
    let (q_three, _) = flow(3.0, false);
    assert!(q_three < q_half && q_half < q_two, "{q_three} {q_half} {q_two}");
    let (q_whole, whole) = flow(2.4, true);
    assert_eq!(whole.defects.report.filled_crack_contacts, 8);
    assert!(q_whole > q_half, "{q_whole} {q_half}");
}

/// Two spheres of phase 1 whose gap (5·10⁻⁴ of the cube) is far below what the conforming
/// seed pairs can follow (and below the cells, by centre): the cells inside them meet across
/// the gap ("bridges"), and an
/// interface conductance h is read at both crossings, each with its own |e·n|:
/// 1/G = 1/G₀ + (1/h)(1/|e·n|_exit + 1/|e·n|_entry)/S, G₀ the same facet without the interface.
#[test]
fn nearly_touching_spheres_read_their_interface_at_both_crossings() {
    use demcon_packing::{PackingParams, RadiusDistribution, pack};
    let container = Container::Box { size: [1.0; 3] };
    let params = PackingParams::new(container, 3000, 0.55, RadiusDistribution::gaussian(0.2));
    let particles = pack(&params, 3, None).unwrap().0;
    let (radius, gap) = (0.2, 5e-4);
    let centres = vec![
        Vec3::new(0.5 - radius - 0.5 * gap, 0.5, 0.5),
        Vec3::new(0.5 + radius + 0.5 * gap, 0.5, 0.5),
    ];
    let h = 50.0;
    for rule in [PhaseRule::Conforming, PhaseRule::Centre] {
        let build = |defects: DefectSpec| {
            let phases = vec![PhaseSpec::Spheres {
                phase: 1,
                radius,
                centres: centres.clone(),
            }];
            laguerre_model(&particles, container, phases, rule, defects)
        };
        let perfect = build(DefectSpec::default());
        let barrier = build(interface(h, None));
        assert_eq!(perfect.graph.pairs, barrier.graph.pairs);
        assert!(!barrier.bridges.is_empty(), "no bridge across a gap of {gap} m");
        let report = barrier.report.defects.as_ref().unwrap();
        assert_eq!(report.bridged_contacts, barrier.bridges.len());
        if rule == PhaseRule::Conforming {
            let conform = barrier.report.conform.as_ref().unwrap();
            assert_eq!(conform.bridged_facets, barrier.bridges.len());
        } else {
            // Re-phasing by centre with the same spheres finds the same bridges; a cut rule none.
            let spheres = Region::Union(
                centres
                    .iter()
                    .map(|&centre| Region::Sphere { centre, radius })
                    .collect(),
            );
            let mut again = barrier.clone();
            set_region_phases(&mut again, &[(spheres.clone(), 1)], PhaseRule::Centre).unwrap();
            assert_eq!(again.bridges, barrier.bridges);
            set_region_phases(&mut again, &[(spheres, 1)], PhaseRule::Segment).unwrap();
            assert!(again.bridges.is_empty());
        }
        let problem = steady(true, FloatingPolicy::Fail);
        let g0 = thermal_setup(&perfect, &problem).unwrap().conductances;
        let g = thermal_setup(&barrier, &problem).unwrap().conductances;
        let area = &barrier.graph.cells.as_ref().unwrap().facet_area;
        for b in &barrier.bridges {
            let k = barrier.graph.pairs.binary_search(&b.pair).unwrap();
            let [p, q] = b.pair.map(|i| barrier.particles.phases[i as usize]);
            assert_eq!((p, q, b.gap_phase), (1, 1, 0));
            assert!(b.cos_exit > 0.0 && b.cos_exit <= 1.0 && b.cos_entry > 0.0 && b.cos_entry <= 1.0);
            assert_ne!(barrier.defects.marks[k] & MARK_INTERFACE, 0);
            let expected = 1.0 / (1.0 / g0[k] + (1.0 / h) * (1.0 / b.cos_exit + 1.0 / b.cos_entry) / area[k]);
            assert_relative_eq!(g[k], expected, max_relative = 1e-12);
        }
        // Every other facet between two phase-1 cells keeps its conductance.
        for (k, &[p, q]) in barrier.graph.pairs.iter().enumerate() {
            let bridged = barrier.bridges.iter().any(|b| b.pair == [p, q]);
            if !bridged && barrier.particles.phases[p as usize] == barrier.particles.phases[q as usize] {
                assert_eq!(g[k], g0[k]);
            }
        }
    }
}

/// A sphere nearly touching its own periodic image (the simple-cubic array at f → π/6): the
/// branches across the gap join two images of one sphere and are bridges too, under the
/// conforming cells and by centre.
#[test]
fn a_sphere_nearly_touching_its_periodic_image_is_bridged() {
    use demcon_packing::{PackingParams, RadiusDistribution, pack};
    let container = Container::Periodic { size: [1.0; 3] };
    let params = PackingParams::new(container, 3000, 0.55, RadiusDistribution::gaussian(0.2));
    let particles = pack(&params, 4, None).unwrap().0;
    let phases = vec![PhaseSpec::Spheres {
        phase: 1,
        radius: 0.5 - 2.5e-4,
        centres: vec![Vec3::new(0.5, 0.5, 0.5)],
    }];
    let problem = ThermalProblem {
        bcs: Vec::new(),
        ..steady(true, FloatingPolicy::Fail)
    };
    for rule in [PhaseRule::Conforming, PhaseRule::Centre] {
        let h = 20.0;
        let perfect = laguerre_model(&particles, container, phases.clone(), rule, DefectSpec::default());
        let barrier = laguerre_model(&particles, container, phases.clone(), rule, interface(h, None));
        assert!(
            !barrier.bridges.is_empty(),
            "{rule:?}: no bridge across the periodic gap"
        );
        let g0 = thermal_setup(&perfect, &problem).unwrap().conductances;
        let g = thermal_setup(&barrier, &problem).unwrap().conductances;
        let area = &barrier.graph.cells.as_ref().unwrap().facet_area;
        for b in &barrier.bridges {
            let k = barrier.graph.pairs.binary_search(&b.pair).unwrap();
            let expected = 1.0 / (1.0 / g0[k] + (1.0 / h) * (1.0 / b.cos_exit + 1.0 / b.cos_entry) / area[k]);
            assert_relative_eq!(g[k], expected, max_relative = 1e-12);
        }
    }
}
