//! Metamorphic tests: for random small scenes, invariances the physics guarantees, checked
//! through the whole pipeline (scene → packing file → Laguerre network → solve → post):
//!
//! - swapping two axes (packing, box, inclusion, held faces) permutes the answer;
//! - translating a periodic microstructure (wrapped) leaves its tensor unchanged, under
//!   every phase rule;
//! - scaling every length by s leaves λ_e unchanged and scales the resistance by 1/s (a scene
//!   in mm against the same in m is the case s = 10⁻³);
//! - swapping the two held temperatures reverses every particle's flux;
//! - splitting a material into two identical ones (a perfect interface between them)
//!   changes nothing, under every phase rule;
//! - a transient's energy balance closes.
//!
//! Every invariance is exact in exact arithmetic; the tolerances (relative, 10⁻⁸ unless said)
//! allow the solver's 10⁻¹² residual and round-off, fixed before any run. The number of random
//! cases per property is `DEMCON_METAMORPHIC_CASES` (default 6 in `cargo test`;
//! `cargo xtask fuzz --metamorphic` runs more).

use std::path::{Path, PathBuf};

use demcon_core::{Container, ParticleSet, Vec3};
use demcon_packing::{PackingParams, RadiusDistribution, pack, write_xyzr};
use demcon_scene::{RunOptions, RunResult, Scene, run};
use proptest::prelude::*;

/// Random cases per property.
fn cases() -> u32 {
    std::env::var("DEMCON_METAMORPHIC_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(6)
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: cases(),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// A fresh folder for one case's packing files.
fn folder(tag: &str) -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let d = std::env::temp_dir().join(format!(
        "demcon-metamorphic-{}-{tag}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A small packing (Gaussian radii, CoV 0.3) in `container`.
fn packing(container: Container, count: usize, seed: u64) -> ParticleSet {
    let p = PackingParams::new(container, count, 0.5, RadiusDistribution::gaussian(0.3));
    pack(&p, seed, None).unwrap().0
}

/// The particles with every centre and radius mapped.
fn mapped(p: &ParticleSet, centre: impl Fn(Vec3) -> Vec3, scale: f64) -> ParticleSet {
    ParticleSet::new(
        p.centres.iter().map(|&c| centre(c)).collect(),
        p.radii.iter().map(|r| r * scale).collect(),
    )
    .unwrap()
}

/// The scene's two materials: "a" and "b" (λ in W/(m·K), ρ_e in Ω·m).
fn materials(la: f64, lb: f64) -> String {
    format!(
        r#"materials: [
        (name: "a", conductivity: {la:e}, density: 1000.0, specific_heat: 500.0, resistivity: Some({ra:e})),
        (name: "b", conductivity: {lb:e}, density: 1000.0, specific_heat: 500.0, resistivity: Some({rb:e})),
    ],"#,
        ra = 1.0 / la,
        rb = 1.0 / lb
    )
}

/// A walled steady scene on the packing file `file`: one sphere of "b" (centre, radius) in
/// "a", the faces normal to `axis` held at `t` (min face, max face), and with `electric`
/// face electrodes on the same faces (1 V apart, no Joule heat).
struct Walled<'a> {
    file: &'a str,
    la: f64,
    lb: f64,
    sphere: (Vec3, f64),
    rule: &'a str,
    axis: char,
    t: (f64, f64),
    electric: bool,
}

impl Walled<'_> {
    fn text(&self) -> String {
        let (c, r) = self.sphere;
        let ax = self.axis.to_ascii_uppercase();
        let electric = if self.electric {
            format!(
                "electric: (electrodes: [(face: {ax}Min, potential: 0.0), (face: {ax}Max, potential: 1.0)], eta: 0.0),"
            )
        } else {
            String::new()
        };
        format!(
            r#"(
    packing: File(path: "{file}"),
    {materials}
    phases: [Spheres(material: "b", radius: {r:e}, centres: [({x:e}, {y:e}, {z:e})])],
    phase_rule: {rule},
    thermal: (bcs: [WallTemperature(face: {ax}Min, value: {t0:e}), WallTemperature(face: {ax}Max, value: {t1:e})], solver: Steady),
    {electric}
    linear_solver: (method: Auto, rel_tol: 1e-12, max_iter: 200000),
    outputs: (etc_axis: Some({ax}), flux: true),
)"#,
            file = self.file,
            materials = materials(self.la, self.lb),
            rule = self.rule,
            x = c.x,
            y = c.y,
            z = c.z,
            t0 = self.t.0,
            t1 = self.t.1,
        )
    }
}

fn run_in(dir: &Path, text: &str) -> RunResult {
    let s =
        Scene::parse(text, &dir.join("m.ron"), dir.to_path_buf()).unwrap_or_else(|e| panic!("{e}\n{text}"));
    run(&s, &RunOptions::default()).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn lambda_e(r: &RunResult) -> f64 {
    r.etc.as_ref().expect("etc").lambda_e
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs())
}

const RULES: [&str; 4] = ["Centre", "Segment", "Laminate", "Conforming"];

proptest! {
    #![proptest_config(config())]

    #[test]
    fn swapping_two_axes_permutes_the_answer(
        seed in 1u64..1000,
        lx in 0.8f64..1.5, ly in 0.8f64..1.5, lz in 0.8f64..1.5,
        u in 0.3f64..0.7, v in 0.3f64..0.7, w in 0.3f64..0.7,
        contrast in prop::sample::select(vec![0.1, 10.0, 50.0]),
        rule in prop::sample::select(RULES.to_vec()),
    ) {
        let d = folder("swap");
        let p = packing(Container::Box { size: [lx, ly, lz] }, 500, seed);
        write_xyzr(&d.join("p.xyzr"), &p, &Container::Box { size: [lx, ly, lz] }).unwrap();
        let swapped = mapped(&p, |c| Vec3::new(c.y, c.x, c.z), 1.0);
        write_xyzr(&d.join("q.xyzr"), &swapped, &Container::Box { size: [ly, lx, lz] }).unwrap();
        let r = 0.25 * lx.min(ly).min(lz);
        let centre = Vec3::new(u * lx, v * ly, w * lz);
        let base = Walled { file: "p.xyzr", la: 1.0, lb: contrast, sphere: (centre, r), rule, axis: 'y', t: (0.0, 1.0), electric: false };
        let a = lambda_e(&run_in(&d, &base.text()));
        let swap = Walled { file: "q.xyzr", sphere: (Vec3::new(centre.y, centre.x, centre.z), r), axis: 'x', ..base };
        let b = lambda_e(&run_in(&d, &swap.text()));
        prop_assert!(close(a, b, 1e-8), "λ_e along y {a} against along x of the swapped body {b}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn scaling_every_length_keeps_the_conductivity_and_scales_the_resistance(
        seed in 1u64..1000,
        s in prop::sample::select(vec![1e-3, 0.37, 2.5, 1e3]),
        contrast in prop::sample::select(vec![0.1, 10.0]),
        rule in prop::sample::select(RULES.to_vec()),
    ) {
        let d = folder("scale");
        let size = [1.0, 0.8, 1.2];
        let p = packing(Container::Box { size }, 500, seed);
        write_xyzr(&d.join("p.xyzr"), &p, &Container::Box { size }).unwrap();
        let q = mapped(&p, |c| c * s, s);
        write_xyzr(&d.join("q.xyzr"), &q, &Container::Box { size: size.map(|l| l * s) }).unwrap();
        let centre = Vec3::new(0.5, 0.4, 0.6);
        let base = Walled { file: "p.xyzr", la: 1.0, lb: contrast, sphere: (centre, 0.3), rule, axis: 'z', t: (10.0, 20.0), electric: true };
        let a = run_in(&d, &base.text());
        let scaled = Walled { file: "q.xyzr", sphere: (centre * s, 0.3 * s), ..base };
        let b = run_in(&d, &scaled.text());
        prop_assert!(close(lambda_e(&a), lambda_e(&b), 1e-8), "λ_e {} against {} at s = {s}", lambda_e(&a), lambda_e(&b));
        let ra = a.electric.as_ref().unwrap().report.resistance_ohm.unwrap();
        let rb = b.electric.as_ref().unwrap().report.resistance_ohm.unwrap();
        prop_assert!(close(ra / s, rb, 1e-8), "R {ra} / s against {rb} at s = {s}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn swapping_the_held_temperatures_reverses_every_flux(
        seed in 1u64..1000,
        t0 in -50.0f64..50.0, dt in 1.0f64..100.0,
        contrast in prop::sample::select(vec![0.1, 10.0]),
        rule in prop::sample::select(RULES.to_vec()),
    ) {
        let d = folder("reverse");
        let size = [1.0, 1.0, 1.0];
        let p = packing(Container::Box { size }, 500, seed);
        write_xyzr(&d.join("p.xyzr"), &p, &Container::Box { size }).unwrap();
        let base = Walled { file: "p.xyzr", la: 1.0, lb: contrast, sphere: (Vec3::repeat(0.5), 0.3), rule, axis: 'x', t: (t0, t0 + dt), electric: false };
        let a = run_in(&d, &base.text());
        let b = run_in(&d, &Walled { t: (t0 + dt, t0), ..base }.text());
        let (fa, fb) = (a.flux.as_ref().unwrap(), b.flux.as_ref().unwrap());
        let scale = fa.iter().map(|f| f.norm()).fold(0.0, f64::max);
        for (k, (x, y)) in fa.iter().zip(fb).enumerate() {
            prop_assert!((x + y).norm() <= 1e-8 * scale, "particle {k}: {x} against {y}");
        }
        prop_assert!(close(lambda_e(&a), lambda_e(&b), 1e-8));
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_material_split_in_two_identical_ones_changes_nothing(
        seed in 1u64..1000,
        lambda in 0.1f64..100.0,
        u in 0.2f64..0.8, v in 0.2f64..0.8, w in 0.2f64..0.8, r in 0.1f64..0.4,
        rule in prop::sample::select(RULES.to_vec()),
    ) {
        let d = folder("split");
        let size = [1.0, 1.0, 1.0];
        let p = packing(Container::Box { size }, 500, seed);
        write_xyzr(&d.join("p.xyzr"), &p, &Container::Box { size }).unwrap();
        let s = Walled { file: "p.xyzr", la: lambda, lb: lambda, sphere: (Vec3::new(u, v, w), r), rule, axis: 'y', t: (0.0, 1.0), electric: true };
        let res = run_in(&d, &s.text());
        prop_assert!(close(lambda_e(&res), lambda, 1e-8), "λ_e {} against λ {lambda}", lambda_e(&res));
        let rr = res.electric.as_ref().unwrap().report.resistance_ohm.unwrap();
        // R = ρ_e L / A with ρ_e = 1/λ and the unit cube.
        prop_assert!(close(rr, 1.0 / lambda, 1e-8), "R {rr} against {}", 1.0 / lambda);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn translating_a_periodic_microstructure_leaves_its_tensor_unchanged(
        seed in 1u64..1000,
        sx in 0.0f64..1.0, sy in 0.0f64..1.0, sz in 0.0f64..1.0,
        contrast in prop::sample::select(vec![0.1, 10.0]),
        rule in prop::sample::select(RULES.to_vec()),
    ) {
        let d = folder("translate");
        let size = [1.0, 1.0, 1.0];
        let cell = Container::Periodic { size };
        let p = packing(cell, 600, seed);
        write_xyzr(&d.join("p.xyzr"), &p, &cell).unwrap();
        let wrap = |c: Vec3| c.map(|x| x.rem_euclid(1.0));
        let shift = Vec3::new(sx, sy, sz);
        let q = mapped(&p, |c| wrap(c + shift), 1.0);
        write_xyzr(&d.join("q.xyzr"), &q, &cell).unwrap();
        // An inclusion near a corner: its images cut particles across the faces.
        let centre = Vec3::new(0.08, 0.9, 0.5);
        let text = |file: &str, c: Vec3| format!(
            r#"(
    packing: File(path: "{file}"),
    {materials}
    phases: [Spheres(material: "b", radius: 0.3, centres: [({x:e}, {y:e}, {z:e})])],
    phase_rule: {rule},
    thermal: (bcs: [], solver: Homogenize),
    linear_solver: (method: Auto, rel_tol: 1e-12, max_iter: 200000),
    outputs: (),
)"#,
            materials = materials(1.0, contrast), x = c.x, y = c.y, z = c.z
        );
        let a = run_in(&d, &text("p.xyzr", centre));
        let b = run_in(&d, &text("q.xyzr", wrap(centre + shift)));
        let ta = a.homogenization.as_ref().unwrap().thermal.as_ref().unwrap().report.tensor;
        let tb = b.homogenization.as_ref().unwrap().thermal.as_ref().unwrap().report.tensor;
        let scale = ta.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        for i in 0..3 {
            for k in 0..3 {
                prop_assert!((ta[i][k] - tb[i][k]).abs() <= 1e-8 * scale, "{ta:?} against {tb:?} shifted by {shift}");
            }
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_transient_energy_balance_closes(
        seed in 1u64..1000,
        power in 1e2f64..1e5,
        implicit in any::<bool>(),
    ) {
        let d = folder("energy");
        let size = [1.0, 1.0, 1.0];
        let p = packing(Container::Box { size }, 500, seed);
        write_xyzr(&d.join("p.xyzr"), &p, &Container::Box { size }).unwrap();
        let solver = if implicit {
            "Implicit(t_end: 200.0, dt: 20.0, scheme: CrankNicolson)"
        } else {
            "Explicit(t_end: 200.0, dt: Auto(safety: 0.9))"
        };
        let text = format!(
            r#"(
    packing: File(path: "p.xyzr"),
    {materials}
    phases: [Spheres(material: "b", radius: 0.3, centres: [(0.5, 0.5, 0.5)])],
    thermal: (
        initial_temperature: 20.0,
        bcs: [WallTemperature(face: ZMin, value: 0.0), HeatFlux(face: ZMax, flux: 10.0)],
        sources: [(select: Material("b"), power_density: {power:e})],
        solver: {solver},
    ),
    linear_solver: (method: Auto, rel_tol: 1e-12, max_iter: 200000),
    outputs: (),
)"#,
            materials = materials(1.0, 10.0)
        );
        let r = run_in(&d, &text);
        let e = r.thermal.as_ref().unwrap().report.energy_balance_error;
        prop_assert!(e < 1e-9, "energy balance error {e} ({solver})");
        let _ = std::fs::remove_dir_all(&d);
    }
}

/// The same scene in mm and in m: the same λ_e, a resistance 10³ larger in mm.
#[test]
fn a_scene_in_mm_agrees_with_the_same_in_m() {
    let d = folder("mm");
    let size = [0.02, 0.01, 0.01];
    let p = packing(Container::Box { size }, 800, 7);
    write_xyzr(&d.join("m.xyzr"), &p, &Container::Box { size }).unwrap();
    let mm = mapped(&p, |c| c * 1e3, 1e3);
    write_xyzr(
        &d.join("mm.xyzr"),
        &mm,
        &Container::Box {
            size: size.map(|l| l * 1e3),
        },
    )
    .unwrap();
    let m = Walled {
        file: "m.xyzr",
        la: 33.0,
        lb: 400.0,
        sphere: (Vec3::new(0.01, 0.005, 0.005), 0.004),
        rule: "Segment",
        axis: 'x',
        t: (20.0, 80.0),
        electric: true,
    };
    let a = run_in(&d, &m.text());
    let b = run_in(
        &d,
        &Walled {
            file: "mm.xyzr",
            sphere: (Vec3::new(10.0, 5.0, 5.0), 4.0),
            ..m
        }
        .text(),
    );
    assert!(
        close(lambda_e(&a), lambda_e(&b), 1e-8),
        "{} against {}",
        lambda_e(&a),
        lambda_e(&b)
    );
    let ra = a.electric.as_ref().unwrap().report.resistance_ohm.unwrap();
    let rb = b.electric.as_ref().unwrap().report.resistance_ohm.unwrap();
    assert!(close(ra * 1e-3, rb, 1e-8), "{ra} Ω in m, {rb} Ω in mm");
    let _ = std::fs::remove_dir_all(&d);
}
