//! `inclusion-etc` — Haddad et al. 2021 §4.1, Fig. 14: a cube L = 0.1 m with a centred
//! spherical inclusion of radius L/3 (f = 0.1551), T = 25 °C on y = 0 and 35 °C on y = L,
//! other faces adiabatic, perfect interface (harmonic mean of the two conductivities on the
//! contacts that cross it, eq. 24). Steady state by one linear solve per contrast.
//!
//! Compared quantity: λ_e/λ_m for the contrasts λ_i/λ_m of the FEM reference
//! (`shared/refs/single-inclusion-fem.json`: 0.01 … 100), and Maxwell beside it. λ_m here is
//! the conductivity MEASURED on the same packing with one phase (same contacts, surfaces and
//! boundary layers): the DEM sample also carries the discretisation error of the homogeneous
//! matrix (what the C_t calibration makes ≈ 1 with a different boundary condition), and the
//! paper's ratio is about the inclusion, not about that. The raw ratio to the nominal λ_m is
//! reported beside it. Both surface models run on the same packing: calibrated
//! (C_t from our own calibration, Haddad) — the metric — and Terreros α (Hubert).
//!
//! Tolerance: the paper reports a maximum error of 0.65 % at 1.5·10⁵ particles (`--full`).
//! The centred inclusion is represented by the particles whose centre lies inside it, so its
//! volume fraction and its surface carry an error of the order of one particle radius over
//! the inclusion radius (≈ 1.0 mm / 33 mm = 3 % at 1.5·10⁵, 2.0 mm / 33 mm = 6 % at 2·10⁴),
//! which weighs most at the extreme contrasts; we accept that order, R̄/a: 3 % at 1.5·10⁵
//! (`--full`) and 5 % in `--quick` (2·10⁴ particles), and report the number. Measured (seed 1):
//! 4.6 % at 2·10⁴ and 2.8 % at 1.5·10⁵ (worst at contrast 100), Terreros α 3.2 % and 1.9 %:
//! four times the paper's 0.65 % at the same N, decreasing about as R̄.
//!
//! This file also holds the slab helpers the other heterogeneous cases share.

use std::time::Instant;

use demcon_scene::config::*;
use demcon_scene::thermal::calibrate_ct;
use serde_json::{Map, Value};

use super::common::*;
use crate::analytic::maxwell;
use crate::chart::{Chart, Scale, Series, draw};
use crate::{CaseOutcome, Comparison, Ctx, Table};

/// Cube edge (m).
pub const L: f64 = 0.1;
/// Temperature on y = 0 (°C).
pub const T_COLD: f64 = 25.0;
/// Temperature on y = L (°C).
pub const T_HOT: f64 = 35.0;
/// Volume fraction of the centred inclusion of radius L/3.
pub const F_SINGLE: f64 = 4.0 / 3.0 * std::f64::consts::PI / 27.0;

/// The paper's cube (§2.2 conditions) at steady state: T = 25 °C on y = 0, 35 °C on y = L,
/// other faces adiabatic, ETC along y; `materials[0]` is the matrix. Gaussian radii (std/mean
/// 0.3), bulk φ ≈ 0.64 (`common::packing`).
pub fn slab_scene(
    name: &str,
    seed: u64,
    n: usize,
    materials: Vec<MaterialConfig>,
    phases: Vec<PhaseConfig>,
) -> SceneConfig {
    let mut s = thermal_scene(
        name,
        seed,
        packing(ContainerConfig::Box { size: (L, L, L) }, n),
        materials,
        ThermalConfig {
            initial_temperature: T_COLD,
            bcs: vec![fixed(FaceConfig::YMin, T_COLD), fixed(FaceConfig::YMax, T_HOT)],
            sources: Vec::new(),
            solver: ThermalSolverConfig::Steady,
        },
    );
    s.phases = phases;
    s.outputs.etc_axis = Some(AxisConfig::Y);
    s
}

/// The centred spherical inclusion of radius L/3.
pub fn centred_inclusion(material: &str) -> PhaseConfig {
    PhaseConfig::Region {
        material: material.into(),
        region: RegionConfig::Sphere {
            centre: (0.5 * L, 0.5 * L, 0.5 * L),
            radius: L / 3.0,
        },
    }
}

/// A clone of `model` whose materials have the conductivities `lambdas` (W/(m·K), one per
/// phase): same packing, contacts and phases, other physics.
pub fn with_conductivities(model: &Model, lambdas: &[f64]) -> Model {
    let mut m = model.clone();
    for (mat, &l) in m.materials.materials.iter_mut().zip(lambdas) {
        mat.conductivity = l;
    }
    m
}

/// Volume fraction of the particles of `phase` (their solid volume over all the solid).
pub fn phase_fraction(model: &Model, phase: u16) -> f64 {
    let p = &model.particles;
    let v: f64 = (0..p.len())
        .filter(|&i| p.phases[i] == phase)
        .map(|i| p.volume(i))
        .sum();
    v / p.solid_volume()
}

/// An ETC measurement: λ_e (W/(m·K)) and the cost of its steady solve.
#[derive(Debug, Clone, Copy)]
pub struct Etc {
    /// λ_e = (Q/A) L / ΔT (W/(m·K)).
    pub lambda_e: f64,
    /// CG iterations.
    pub iterations: u64,
    /// Solve wall time (s).
    pub solve_s: f64,
    /// Relative residual reached.
    pub residual: f64,
}

/// Runs the steady slab `cfg` on `model` (whose conductivities are already set) and
/// returns λ_e along y with its cost.
pub fn etc_of(cfg: &SceneConfig, model: Model) -> anyhow::Result<Etc> {
    let r = run_with(cfg, &model)?;
    let etc = r
        .etc
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("the scene produced no ETC"))?;
    let th = r
        .thermal
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("no thermal run"))?;
    Ok(Etc {
        lambda_e: etc.lambda_e,
        iterations: th.report.iterations,
        solve_s: th.report.wall_s,
        residual: th.report.residual,
    })
}

/// `cfg` with the calibrated surface model at a given C_t (so a calibration made once serves
/// every run on the same packing) or the Terreros α model.
pub fn with_surface(cfg: &SceneConfig, c_t: Option<f64>) -> SceneConfig {
    let mut c = cfg.clone();
    c.surface = match c_t {
        Some(v) => SurfaceConfig::Calibrated {
            c_t: CtConfig::Value(v),
        },
        None => SurfaceConfig::TerrerosAlpha,
    };
    c
}

/// The scene of this case: matrix 33 W/(m·K), inclusion 33·contrast.
pub fn scene(n: usize, seed: u64, contrast: f64) -> SceneConfig {
    slab_scene(
        "inclusion-etc",
        seed,
        n,
        vec![
            material("matrix", 33.0, 7800.0, 0.9),
            material("inclusion", 33.0 * contrast, 7800.0, 0.9),
        ],
        vec![centred_inclusion("inclusion")],
    )
}

/// One surface model's sweep over the contrasts.
struct Sweep {
    name: &'static str,
    /// λ measured with one phase (W/(m·K)).
    lambda_hom: f64,
    /// (contrast, λ_e/λ_hom, λ_e/λ_m nominal).
    ratios: Vec<(f64, f64, f64)>,
    iterations: u64,
    solve_s: f64,
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let n = ctx.pick(20_000, 150_000);
    let lm = 33.0;
    let mut out = CaseOutcome::new("inclusion-etc", ctx.mode);
    let fem = crate::refs::single_inclusion_fem();
    let table = fem["etc_vs_contrast"]
        .as_object()
        .ok_or_else(|| anyhow::anyhow!("single-inclusion-fem.json: no etc_vs_contrast"))?;
    let mut refs: Vec<(f64, f64)> = table
        .iter()
        .map(|(k, v)| {
            Ok((
                k.parse::<f64>()?,
                v["fem_lambda_eff_over_lambda_m"]
                    .as_f64()
                    .ok_or_else(|| anyhow::anyhow!("no FEM value for contrast {k}"))?,
            ))
        })
        .collect::<anyhow::Result<_>>()?;
    refs.sort_by(|a, b| a.0.total_cmp(&b.0));

    let t0 = Instant::now();
    let base = scene(n, ctx.seed, 1.0);
    let model = model_of(&base)?;
    let build_s = t0.elapsed().as_secs_f64();
    out.n_particles = model.particles.len();
    let cal = calibrate_ct(&model)?;
    let f_particles = phase_fraction(&model, 1);

    let mut sweeps = Vec::new();
    for (name, c_t) in [("calibrated", Some(cal.c_t)), ("terreros", None)] {
        let cfg = with_surface(&base, c_t);
        let hom = etc_of(&cfg, with_conductivities(&model, &[lm, lm]))?;
        let mut sw = Sweep {
            name,
            lambda_hom: hom.lambda_e,
            ratios: Vec::new(),
            iterations: hom.iterations,
            solve_s: hom.solve_s,
        };
        for &(c, _) in &refs {
            let e = etc_of(&cfg, with_conductivities(&model, &[lm, lm * c]))?;
            sw.ratios.push((c, e.lambda_e / hom.lambda_e, e.lambda_e / lm));
            sw.iterations += e.iterations;
            sw.solve_s += e.solve_s;
        }
        sweeps.push(sw);
    }

    let err = |sw: &Sweep, pick: fn(&(f64, f64, f64)) -> f64, against: &dyn Fn(f64) -> f64| {
        sw.ratios
            .iter()
            .map(|r| (pick(r) - against(r.0)).abs() / against(r.0))
            .fold(0.0f64, f64::max)
    };
    let fem_of = |c: f64| refs.iter().find(|r| r.0 == c).map(|r| r.1).unwrap_or(f64::NAN);
    let maxwell_nominal = |c: f64| maxwell(1.0, c, F_SINGLE);
    let maxwell_particles = |c: f64| maxwell(1.0, c, f_particles);
    let norm = |r: &(f64, f64, f64)| r.1;
    let raw = |r: &(f64, f64, f64)| r.2;
    let (cal_sw, ter_sw) = (&sweeps[0], &sweeps[1]);
    let e_fem = err(cal_sw, norm, &fem_of);
    out.metric("max_rel_error_vs_fem", e_fem);
    out.metric("max_rel_error_vs_maxwell", err(cal_sw, norm, &maxwell_nominal));
    out.metric(
        "max_rel_error_vs_maxwell_particle_fraction",
        err(cal_sw, norm, &maxwell_particles),
    );
    out.metric("max_rel_error_vs_fem_raw", err(cal_sw, raw, &fem_of));
    out.metric("max_rel_error_vs_fem_terreros", err(ter_sw, norm, &fem_of));
    out.metric("max_rel_error_vs_fem_terreros_raw", err(ter_sw, raw, &fem_of));
    for sw in &sweeps {
        let mut m = Map::new();
        for r in &sw.ratios {
            m.insert(format!("{}", r.0), Value::from(r.1));
        }
        out.metric(&format!("etc_ratio_{}", sw.name), Value::Object(m));
        out.metric(&format!("lambda_hom_over_lambda_{}", sw.name), sw.lambda_hom / lm);
        out.metric(&format!("solve_s_{}", sw.name), sw.solve_s);
        out.metric(&format!("cg_iterations_{}", sw.name), sw.iterations);
    }
    out.metric("c_t", cal.c_t);
    out.metric("inclusion_particle_fraction", f_particles);
    out.metric("build_s", build_s);
    out.metric("phi", model.phi);
    out.reference("max_rel_error_vs_fem", 0.0065);
    out.reference(
        "source",
        "Haddad 2021 §4.1 Fig. 14 (1.5·10⁵ DE, 0.65 %); FEM: shared/refs/single-inclusion-fem.json",
    );
    let tol = ctx.pick(0.05, 0.03);
    out.compare(Comparison::at_most(
        "max |λ_e/λ_hom − FEM|/FEM over the contrasts (calibrated C_t)",
        e_fem,
        tol,
        "paper 0.65 % at 1.5·10⁵ DE",
    ));

    let mut t = Table {
        title: format!(
            "λ_e/λ_m against the contrast, N = {}, inclusion particle fraction {:.4} (nominal {:.4})",
            model.particles.len(),
            f_particles,
            F_SINGLE
        ),
        header: vec![
            "λ_i/λ_m".into(),
            "DEM calibrated".into(),
            "DEM Terreros α".into(),
            "FEM".into(),
            "Maxwell".into(),
            "err calibrated".into(),
            "err Terreros".into(),
            "raw calibrated (λ_e/33)".into(),
        ],
        rows: Vec::new(),
    };
    for (i, r) in cal_sw.ratios.iter().enumerate() {
        let f = fem_of(r.0);
        let rt = ter_sw.ratios[i];
        t.rows.push(vec![
            format!("{}", r.0),
            format!("{:.5}", r.1),
            format!("{:.5}", rt.1),
            format!("{f:.5}"),
            format!("{:.5}", maxwell_nominal(r.0)),
            format!("{:.3} %", 100.0 * (r.1 - f) / f),
            format!("{:.3} %", 100.0 * (rt.1 - f) / f),
            format!("{:.5}", r.2),
        ]);
    }
    out.tables.push(t);

    let maxwell_curve: Vec<(f64, f64)> = (0..=40)
        .map(|i| {
            let c = 10f64.powf(-2.0 + 4.0 * i as f64 / 40.0);
            (c, maxwell_nominal(c))
        })
        .collect();
    draw(
        &Chart {
            title: format!(
                "Single inclusion: λ_e/λ_m against contrast, N = {} (Haddad 2021 Fig. 14)",
                model.particles.len()
            ),
            x_label: "contrast λ_i/λ_m".into(),
            y_label: "λ_e/λ_m".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
            series: vec![
                Series::line(
                    "DEM calibrated C_t",
                    cal_sw.ratios.iter().map(|r| (r.0, r.1)).collect(),
                ),
                Series::line(
                    "DEM Terreros α",
                    ter_sw.ratios.iter().map(|r| (r.0, r.1)).collect(),
                ),
                Series::markers("FEM", refs.clone()),
                Series::line("Maxwell", maxwell_curve),
            ],
        },
        &ctx.out.join("inclusion-etc.png"),
    )?;
    out.charts.push("inclusion-etc.png".into());
    out.note(format!(
        "{} mode: {} particles, one packing, {} contrasts × 2 surface models, each a steady CG solve \
         ({} iterations, {:.2} s in all for the calibrated model). λ_e/λ_m divides by λ measured on the same packing with \
         one phase: {:.4}·λ (calibrated, C_t = {:.4} from our flux-BC calibration) and {:.4}·λ (Terreros α).",
        ctx.mode.name(),
        model.particles.len(),
        refs.len(),
        cal_sw.iterations,
        cal_sw.solve_s,
        cal_sw.lambda_hom / lm,
        cal.c_t,
        ter_sw.lambda_hom / lm
    ));
    out.note(format!(
        "The inclusion is the set of particles whose centre lies in the sphere: their volume fraction of the solid is {f_particles:.4} \
         against the nominal {F_SINGLE:.4}; Maxwell at the particle fraction is given as a metric to separate this \
         geometric error from the network's."
    ));
    Ok(out)
}
