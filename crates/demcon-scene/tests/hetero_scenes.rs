//! The heterogeneous example scenes (`scenes/halo-slab.ron`, `single-inclusion.ron`,
//! `multi-inclusion.ron`) load as shipped and run end to end once shrunk to a small packing;
//! the results are checked against physics that holds at any resolution.

use std::path::{Path, PathBuf};

use demcon_scene::config::PackingConfig;
use demcon_scene::{RunOptions, Scene, run};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

/// Loads a shipped scene and shrinks it to `n` particles, a Halo of `halo` radii and no files.
fn small(name: &str, n: usize, halo: f64) -> Scene {
    let s = Scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    s.edit(|c| {
        match &mut c.packing {
            PackingConfig::Generate { count, phi, .. } => {
                *count = n;
                // Looser wall layers weigh more in a small walled packing: keep the bulk at ≈ 0.64.
                *phi = 0.64 - 0.5 * (n as f64).powf(-1.0 / 3.0);
            }
            other => panic!("{name}: expected a generated packing, got {other:?}"),
        }
        c.outputs.vtk = false;
        c.outputs.halo = Some(halo);
    })
    .unwrap()
}

fn probe(r: &demcon_scene::RunResult, name: &str, field: &str) -> f64 {
    r.probes
        .iter()
        .find(|p| p.name == name && p.field == field)
        .unwrap_or_else(|| panic!("no probe {name}/{field}"))
        .value
}

#[test]
fn halo_slab_scene_gives_the_exact_flux_with_laguerre_cells() {
    // As shipped (Laguerre cells, wall temperatures): λ_e = λ and q = −λ∇T in every particle.
    let s = small("halo-slab.ron", 3000, 3.0);
    let r = run(&s, &RunOptions::default()).unwrap();
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!((etc / 33.0 - 1.0).abs() < 1e-8, "λ_e = {etc}");
    let exact = -33.0 * 10.0 / 0.1;
    for (q, h) in r.flux.as_ref().unwrap().iter().zip(&r.halo.as_ref().unwrap().0) {
        assert!(
            (q.y / exact - 1.0).abs() < 1e-7 && (h.y / exact - 1.0).abs() < 1e-7,
            "{q} {h}"
        );
    }
}

#[test]
fn halo_slab_scene_gives_the_uniform_flux() {
    // The paper's setup (calibrated C_t, particles held at the temperatures): the flux scatters
    // and the Halo reduces the scatter.
    let s = small("halo-slab.ron", 3000, 3.0)
        .edit(|c| {
            c.surface = demcon_scene::config::SurfaceConfig::Calibrated {
                c_t: demcon_scene::config::CtConfig::Auto,
            };
            c.thermal.as_mut().unwrap().bcs = vec![
                demcon_scene::config::ThermalBcConfig::FixedTemperature {
                    select: demcon_scene::config::SelectorConfig::Face(
                        demcon_scene::config::FaceConfig::YMin,
                    ),
                    value: 25.0,
                },
                demcon_scene::config::ThermalBcConfig::FixedTemperature {
                    select: demcon_scene::config::SelectorConfig::Face(
                        demcon_scene::config::FaceConfig::YMax,
                    ),
                    value: 35.0,
                },
            ];
        })
        .unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    // λ_e from fixed temperatures with C_t calibrated under an imposed flux: a few % of λ.
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!((etc / 33.0 - 1.0).abs() < 0.08, "λ_e = {etc}");
    // Linear profile: the centre is at the mean temperature.
    let tc = probe(&r, "centre", "temperature");
    assert!((tc - 30.0).abs() < 0.5, "T(centre) = {tc}");
    // The Halo reduces the scatter of q_y around the same mean (−λ_e ΔT/L).
    let flux = r.flux.as_ref().unwrap();
    let (halo, _, rep) = r.halo.as_ref().unwrap();
    assert_eq!(rep.ratio, 3.0);
    let fixed = &r.thermal_bcs.as_ref().unwrap().fixed_sets;
    let mut free = vec![true; flux.len()];
    for set in fixed {
        set.particles().iter().for_each(|&i| free[i as usize] = false);
    }
    // Volume-weighted mean (the volume average of the flux field) and CoV over free particles.
    let w = &r.thermal_setup.as_ref().unwrap().rep_volumes;
    let stats = |v: &[demcon_core::Vec3]| {
        let sel = || v.iter().zip(w).zip(&free).filter(|(_, f)| **f).map(|(x, _)| x);
        let sw: f64 = sel().map(|(_, w)| w).sum();
        let m = sel().map(|(q, w)| w * q.y).sum::<f64>() / sw;
        let var = sel().map(|(q, w)| w * (q.y - m).powi(2)).sum::<f64>() / sw;
        (m, var.sqrt() / m.abs())
    };
    let (m0, cov0) = stats(flux);
    let (m3, cov3) = stats(halo);
    let exact = -etc * 10.0 / 0.1;
    assert!(
        (m0 / exact - 1.0).abs() < 0.1,
        "mean q_y = {m0}, expected ≈ {exact}"
    );
    assert!(
        (m3 / exact - 1.0).abs() < 0.1,
        "mean Halo q_y = {m3}, expected ≈ {exact}"
    );
    assert!(cov3 < 0.7 * cov0, "CoV without Halo {cov0}, with k = 3 {cov3}");
}

#[test]
fn single_inclusion_scene_concentrates_the_flux_in_the_inclusion() {
    let s = small("single-inclusion.ron", 4000, 3.0);
    let r = run(&s, &RunOptions::default()).unwrap();
    assert_eq!(r.model.report.phase_counts.len(), 2);
    // The cells follow the sphere of radius L/3 (the default conforming cells): its share
    // of the body is (4π/3)/27 = 0.1551 to the tangent polyhedron's volume correction.
    let frac = r.model.report.phase_fractions[1];
    assert!(
        (frac / (4.0 * std::f64::consts::PI / 81.0) - 1.0).abs() < 0.01,
        "inclusion share {frac}"
    );
    // Symmetry: the centre sits at the mean temperature.
    let ta = probe(&r, "A", "temperature");
    assert!((ta - 30.0).abs() < 0.3, "T(A) = {ta}");
    // The conductive inclusion draws the heat: |q| in it exceeds the matrix's beside it
    // (FEM: 7767 against 2310 W/m²), and the ETC exceeds the matrix's.
    let qa = probe(&r, "A", "halo_flux_magnitude");
    let qb = probe(&r, "B", "halo_flux_magnitude");
    assert!(qa > 2.0 * qb, "|q| A = {qa}, B = {qb}");
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!(etc > 33.0 * 1.1 && etc < 33.0 * 1.5, "λ_e = {etc}");
}

#[test]
fn multi_inclusion_scene_places_the_silica() {
    let s = small("multi-inclusion.ron", 6000, 2.0);
    let r = run(&s, &RunOptions::default()).unwrap();
    let inc = r.model.report.inclusions.as_ref().unwrap();
    // f = 0.2, edge / diameter = 6: round(0.2 · 216 · 6/π) = 83 spheres of radius ≈ L/12
    // (grown to exactly f: (82.5/83)^(1/3) · L/12).
    assert_eq!(inc.count, 83);
    assert!((inc.radius / (0.1 / 12.0) - 1.0).abs() < 0.005, "{}", inc.radius);
    assert!((inc.fraction - 0.2).abs() < 1e-3, "{}", inc.fraction);
    // No two spheres overlap, none crosses a wall.
    for (i, a) in inc.centres.iter().enumerate() {
        for c in a {
            assert!(*c >= inc.radius * (1.0 - 1e-9) && *c <= 0.1 - inc.radius * (1.0 - 1e-9));
        }
        for b in &inc.centres[..i] {
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            assert!(d >= 2.0 * inc.radius * (1.0 - 1e-9), "overlap {d}");
        }
    }
    assert!(
        (inc.particle_fraction - 0.2).abs() < 0.04,
        "{}",
        inc.particle_fraction
    );
    // The ETC lies between the phases and near the effective-medium estimates
    // (Maxwell 0.289, third order 0.292 W/(m·K)), within the coarse packing's error.
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!(etc > 0.25 && etc < 0.34, "λ_e = {etc}");
    // Each point reads one temperature between the two fixed ones.
    for name in ["A", "B", "C", "D"] {
        let t = probe(&r, name, "temperature");
        assert!((25.0..=35.0).contains(&t), "T({name}) = {t}");
    }
}

#[test]
fn laminate_rule_resolves_the_inclusion_below_a_particle() {
    use demcon_scene::build_model;
    use demcon_scene::config::PhaseRuleConfig;
    let rule = |s: &Scene, r| s.clone().edit(|c| c.phase_rule = Some(r)).unwrap();
    let centre = rule(&small("single-inclusion.ron", 3000, 2.0), PhaseRuleConfig::Centre);
    let lam = rule(&centre, PhaseRuleConfig::Laminate);
    let mc = build_model(&centre, None).unwrap();
    let ml = build_model(&lam, None).unwrap();
    // Same packing, same phases by centre; only the laminate model carries mixes.
    assert_eq!(mc.particles.phases, ml.particles.phases);
    assert!(mc.mixes.is_empty());
    assert_eq!(ml.report.mixed_particles, ml.mixes.len());
    assert!(ml.mixes.len() > 50, "{} cut particles", ml.mixes.len());
    // Every cut particle straddles the sphere of radius L/3 and its normal is radial.
    let (c0, a) = (demcon_core::Vec3::new(0.05, 0.05, 0.05), 0.1 / 3.0);
    for m in &ml.mixes {
        let p = m.particle as usize;
        let d = ml.particles.centres[p] - c0;
        assert!((d.norm() - a).abs() < ml.particles.radii[p]);
        assert!(m.other_fraction > 0.0 && m.other_fraction < 1.0);
        assert!((d.normalize().dot(&m.normal).abs() - 1.0).abs() < 1e-6);
    }
    // Each cut particle's fraction in the other phase matches a count of grid points of its
    // ball (13³ grid over its box) on the other side of the sphere.
    for m in ml.mixes.iter().step_by(7) {
        let p = m.particle as usize;
        let (c, r) = (ml.particles.centres[p], ml.particles.radii[p]);
        let (mut inside_ball, mut other_side) = (0usize, 0usize);
        for i in 0..13 {
            for j in 0..13 {
                for k in 0..13 {
                    let u = demcon_core::Vec3::new(i as f64, j as f64, k as f64) / 6.0
                        - demcon_core::Vec3::new(1.0, 1.0, 1.0);
                    if u.norm() > 1.0 {
                        continue;
                    }
                    inside_ball += 1;
                    let x = c + r * u;
                    let in_sphere = (x - c0).norm() <= a;
                    let own_inclusion = ml.particles.phases[p] == 1;
                    if in_sphere != own_inclusion {
                        other_side += 1;
                    }
                }
            }
        }
        let sampled = other_side as f64 / inside_ball as f64;
        assert!(
            (sampled - m.other_fraction).abs() < 0.03,
            "particle {p}: {sampled} vs {}",
            m.other_fraction
        );
    }
    // The carried fractions of the two phases sum to 1.
    assert!((mc.report.phase_fractions[0] + mc.report.phase_fractions[1] - 1.0).abs() < 1e-12);
    assert!((ml.report.phase_fractions[0] + ml.report.phase_fractions[1] - 1.0).abs() < 1e-12);
    // The steady run goes through, with an ETC between the phases' conductivities.
    let r = run(&lam, &RunOptions::default()).unwrap();
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!(etc > 0.9 * 33.0 && etc < 165.0, "λ_e = {etc}");
    // The segment rule cuts the same particles with the same fractions; its normals point
    // into the other phase and its offsets are the centres' distances to the sphere.
    let seg = rule(&centre, PhaseRuleConfig::Segment);
    let ms = build_model(&seg, None).unwrap();
    assert_eq!(ms.mixes.len(), ml.mixes.len());
    for (m, b) in ms.mixes.iter().zip(&ml.mixes) {
        assert_eq!((m.particle, m.other_fraction), (b.particle, b.other_fraction));
        let d = ms.particles.centres[m.particle as usize] - c0;
        assert!((m.offset - (d.norm() - a).abs()).abs() < 1e-12);
        let outwards = d.normalize().dot(&m.normal);
        assert!(if ms.particles.phases[m.particle as usize] == 1 {
            outwards > 0.999
        } else {
            outwards < -0.999
        });
    }
    let r = run(&seg, &RunOptions::default()).unwrap();
    let etc_s = r.etc.as_ref().unwrap().lambda_e;
    assert!(etc_s > 0.9 * 33.0 && etc_s < 165.0, "λ_e = {etc_s}");
}

#[test]
fn cut_particles_conduct_heat_and_current_alike_and_store_heat_by_volume() {
    use demcon_model::{electric_conductances, thermal_setup};
    use demcon_scene::build_model;
    use demcon_scene::config::{PhaseRuleConfig, SurfaceConfig};
    for rule in [PhaseRuleConfig::Laminate, PhaseRuleConfig::Segment] {
        let s = small("single-inclusion.ron", 2000, 2.0)
            .edit(|c| {
                c.phase_rule = Some(rule);
                c.surface = SurfaceConfig::TerrerosAlpha;
                // ρ_e = 1/λ in each phase: the electric network must be the thermal one.
                for m in &mut c.materials {
                    m.resistivity = Some(1.0 / m.conductivity);
                }
                c.materials[1].density = 2.0 * c.materials[0].density;
            })
            .unwrap();
        let model = build_model(&s, None).unwrap();
        assert!(!model.mixes.is_empty());
        let problem = s.problem();
        let tp = problem.thermal.as_ref().unwrap();
        let setup = thermal_setup(&model, tp).unwrap();
        let ge = electric_conductances(&model, &tp.surface, tp.interface, None).unwrap();
        assert_eq!(ge.len(), model.graph.pairs.len());
        for (k, (e, t)) in ge.iter().zip(&setup.conductances).enumerate() {
            assert!((e - t).abs() <= 1e-9 * t, "{rule:?}, contact {k}: {e} vs {t}");
        }
        // Capacities: ρc mixes by the volume fractions (c equal, ρ_inclusion = 2 ρ_matrix).
        let lam = model.laminates();
        let (c0, c1) = (
            s.config().materials[0].density * s.config().materials[0].specific_heat,
            s.config().materials[1].density * s.config().materials[1].specific_heat,
        );
        let frac: Vec<f64> = setup
            .rep_volumes
            .iter()
            .enumerate()
            .map(|(p, r)| (model.particles.volume(p) / r).min(1.0))
            .collect();
        for m in &model.mixes {
            let p = m.particle as usize;
            let own = if model.particles.phases[p] == 1 { c1 } else { c0 };
            let other = if m.other_phase == 1 { c1 } else { c0 };
            let rc = (1.0 - m.other_fraction) * own + m.other_fraction * other;
            let expected = rc * model.particles.volume(p) / frac[p];
            let got = setup.capacities[p];
            assert!(
                (got - expected).abs() <= 1e-9 * expected,
                "{rule:?}, particle {p}: {got} vs {expected}"
            );
            assert!(lam.get(p).is_some());
        }
    }
}

/// `scenes/multi-inclusion-8m.ron`, shrunk to 1000 particles tiled 2 × 2 × 2: the tiling cut
/// to walls carries the wall temperatures, the 83 spheres are placed on the whole cube, and
/// the result is the coarse multi-inclusion answer (ETC between the phases, readings between
/// the fixed temperatures, every stage timed).
#[test]
fn paper_scale_scene_runs_shrunk() {
    // Shrunk in the text, so that the scene check (which refuses a run the machine cannot
    // hold) sees the small scene.
    let path = scene_path("multi-inclusion-8m.ron");
    let text = std::fs::read_to_string(&path).unwrap();
    let small_text = [
        ("count: 125000", "count: 1000"),
        ("size: (0.025, 0.025, 0.025)", "size: (0.05, 0.05, 0.05)"),
        ("repeat: (4, 4, 4)", "repeat: (2, 2, 2)"),
    ]
    .iter()
    .fold(text, |t, (from, to)| {
        assert!(t.contains(from), "multi-inclusion-8m.ron no longer has `{from}`");
        t.replace(from, to)
    });
    let s = Scene::parse(&small_text, &path, scene_path("")).unwrap();
    let PackingConfig::Tile { walls, .. } = &s.config().packing else {
        panic!("multi-inclusion-8m.ron: expected a tiled packing");
    };
    assert!(*walls);
    let s = s.edit(|c| c.outputs.halo = Some(2.0)).unwrap();
    let r = run(&s, &RunOptions::default()).unwrap();
    // The 8000 particles, less those the conforming seeds replace, and the seeds.
    let c = r
        .model
        .report
        .conform
        .as_ref()
        .expect("conforming cells by default");
    assert_eq!(r.model.particles.len(), 8000 - c.removed_particles + c.seeds);
    assert_eq!(c.seeds, r.model.seeds);
    assert_eq!(r.model.report.inclusions.as_ref().unwrap().count, 83);
    let etc = r.etc.as_ref().unwrap().lambda_e;
    assert!(etc > 0.22 && etc < 0.36, "λ_e = {etc}");
    for name in ["A", "B", "C", "D"] {
        let t = probe(&r, name, "temperature");
        assert!((25.0..=35.0).contains(&t), "T({name}) = {t}");
    }
    let stages: Vec<&str> = r.stages.records().iter().map(|s| s.stage).collect();
    assert_eq!(
        stages,
        [
            "packing",
            "phases",
            "tessellation",
            "bridges",
            "network",
            "thermal setup",
            "solve",
            "flux",
            "halo",
            "probes"
        ]
    );
}
