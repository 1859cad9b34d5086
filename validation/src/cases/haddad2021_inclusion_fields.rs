//! `inclusion-fields` — Haddad et al. 2021 §4.2, Table 2, Figs. 15–16: the single-inclusion
//! cube (inclusion radius L/3) with λ_m = 33 and λ_i = 165 W/(m·K), T = 25 °C on y = 0 and
//! 35 °C on y = L, steady state. Temperature and Halo-smoothed flux magnitude |q| (k = 11, the
//! paper's choice) at the paper's points A(0.5, 0.5, 0.5)L, B(0.08, 0.5, 0.5)L,
//! C(0.5, 0.92, 0.5)L against the FEM reference (`shared/refs/single-inclusion-fem.json`), and
//! slice pictures of T and |q| on Z = 0.5L.
//!
//! Compared quantity: the largest relative error over A, B, C of T (°C, the paper's measure)
//! and of |q|, reading the particle whose centre is nearest to the point (a ball average of
//! radius 0.02L is reported beside it). The paper's Table 2 at 1.5·10⁵ particles: 7796, 2370,
//! 6183 W/m² against its FE 7767, 2318, 6424, i.e. up to 4.0 % from our FEM reference (C is
//! 0.08L from a fixed-temperature face, B 0.08L from an adiabatic one: both inside the reach
//! of an 11-radius Halo, whose average is then one-sided and centred inward — for B, towards
//! the inclusion, which starts at 0.17L and carries three times B's flux).
//! Models: as `inclusion-etc`, every surface (calibrated C_t, Terreros α, Laguerre cells) ×
//! boundary × phase rule on the same packing, each with its wall time (network, calibration,
//! the run); the headline is [`Variant::HEADLINE`] (Laguerre cells, walls, conforming cells),
//! chosen for the Laguerre network's consistency property before any of its numbers were seen
//! (on 3 packings, gated on the largest error), and the
//! papers' recommended contact model ([`Variant::RECOMMENDED`]) keeps its checks. Both are
//! gated at the same a-priori tolerances, chosen before the Laguerre numbers were seen
//! (the case has no Laguerre target of its own). Tolerances: the paper's errors at 1.5·10⁵
//! particles (T < 1 %, |q| up to 4.0 %) scaled as an interface error ∝ N^(-1/3):
//! × (1.5·10⁵/N)^(1/3) (T 1.96 %, |q| 7.8 % at 2·10⁴). In `--quick` (2·10⁴ particles) the Halo
//! radius 11·R_p reaches 0.2–0.35L, far past B into the inclusion, so B is off by tens of %
//! and is reported, not gated: the quick |q| gate is at A (Halo inside the inclusion).
//!
//! Halo phases: the headline |q| is the default Halo, averaged over the particle's own phase
//! only (`HaloPhases::Same`); the paper's Halo over every particle in the ball
//! (`HaloPhases::All`) is reported beside it (`max_rel_error_q_all_phases`). The choice was
//! made by the physics, before any number: across the interface the normal flux is
//! continuous but the tangential flux `−λ ∂T/∂t` jumps with λ (5× here), so a Halo that
//! takes in particles of the other phase carries that jump into every particle within
//! `k·R` of the interface — B, in the matrix 0.087L from the inclusion with a Halo of up to
//! 0.35L, takes in inclusion particles of about three times its flux. Averaging each phase
//! over itself is the per-phase averaging of RVE post-processing. What is left at B is the
//! Halo's own smoothing of a field that has a minimum of |q| near B (beside the inclusion's
//! equator) and the one-sided Halo cut by the face x = 0, both shrinking with the Halo radius
//! ∝ N^(-1/3); so the quick gate stays at A.
//!
//! Reference, Halo phases, models and tolerances, as documentation:
//! `validation/notes/inclusion-fields.md`.

use std::time::Instant;

use demcon_core::{Axis, Vec3};
use demcon_post::HaloReport;
use demcon_scene::config::*;
use serde_json::{Map, Value};

use super::common::*;
use super::composite::*;
use crate::table::Columns;
use crate::{CaseOutcome, Comparison, Ctx, Table};

/// The scene: matrix 33, inclusion 165 W/(m·K), Halo k = 11, probes at `points` (name, point
/// in units of L) read at the nearest particle and as a ball average (named `<name>-ball`).
pub fn scene(n: usize, seed: u64, points: &[(String, [f64; 3])]) -> SceneConfig {
    let mut s = slab_scene(
        "inclusion-fields",
        seed,
        n,
        vec![
            material("matrix", 33.0, 7800.0, 0.9),
            material("inclusion", 165.0, 7800.0, 0.9),
        ],
        vec![centred_inclusion("inclusion")],
    );
    s.outputs.halo = Some(HALO_K);
    s.outputs.probes = probes(points, n);
    s
}

/// The FEM reference at one of the paper's points.
struct FemRef {
    name: String,
    /// Point in units of L.
    point: [f64; 3],
    /// T (°C).
    t: f64,
    /// |q| at the point (W/m²).
    q: f64,
    /// |q| ball average over r = 0.02L (W/m²).
    q_ball: f64,
}

/// One run's reading at a point.
#[derive(Debug, Clone)]
struct Reading {
    name: String,
    /// T at the nearest particle and ball average (°C).
    t: f64,
    t_ball: f64,
    /// |q| of the headline (own-phase) Halo, nearest and ball (W/m²).
    q: f64,
    q_ball: f64,
    /// |q| of the all-phases Halo, nearest and ball (W/m²).
    q_all: f64,
    q_all_ball: f64,
    /// Whether the nearest particle's Halo is cut by the boundary.
    cut: bool,
}

/// Readings at `points` (units of L); `q_all` is the all-phases Halo |q| per particle.
fn readings(r: &RunResult, refs: &[FemRef], q_all: &[f64], n: usize) -> anyhow::Result<Vec<Reading>> {
    refs.iter()
        .map(|f| {
            let (name, p) = (&f.name, f.point);
            let point = Vec3::new(p[0] * L, p[1] * L, p[2] * L);
            let (q_all, q_all_ball) = probe_pair(r, q_all, point, ball_radius(n))?;
            Ok(Reading {
                name: name.clone(),
                t: probe_value(r, name, "temperature")?,
                t_ball: probe_value(r, &format!("{name}-ball"), "temperature")?,
                q: probe_value(r, name, "halo_flux_magnitude")?,
                q_ball: probe_value(r, &format!("{name}-ball"), "halo_flux_magnitude")?,
                q_all,
                q_all_ball,
                cut: nearest_truncated(r, point),
            })
        })
        .collect()
}

/// Relative difference |a − b|/|b|.
fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Largest relative error over the points of reading `f` against reference `g`.
fn max_err(rd: &[Reading], refs: &[FemRef], f: fn(&Reading) -> f64, g: fn(&FemRef) -> f64) -> f64 {
    rd.iter()
        .zip(refs)
        .map(|(m, r)| rel(f(m), g(r)))
        .fold(0.0f64, f64::max)
}

/// One model's errors on the first N.
struct ModelErrors {
    id: String,
    /// The model's own cost (s): network (contacts or tessellation), calibration, the run
    /// (steady solve and post-processing: flux, Halo, probes).
    wall_s: f64,
    /// Largest relative error of T, |q| (own phase) and |q| (all phases) over the points.
    t: f64,
    q: f64,
    q_all: f64,
    /// Relative error of |q| at A.
    q_a: f64,
    readings: Vec<Reading>,
}

/// The headline model's readings at one N.
struct SizeReadings {
    /// Particles.
    n: usize,
    readings: Vec<Reading>,
}

/// Everything the case measures.
struct Measured {
    /// Requested sizes.
    sizes: Vec<usize>,
    refs: Vec<FemRef>,
    /// The paper's Table 2 as stored in the reference file.
    paper_table2: Value,
    /// Every model on the first N, the headline first.
    by_model: Vec<ModelErrors>,
    /// The headline model at each N.
    by_size: Vec<SizeReadings>,
    /// The headline on the further packings at the first N.
    repeats: Vec<ModelErrors>,
    /// The headline model's run on the first N.
    first: RunResult,
    /// Its calibrations.
    cts: Calibrations,
    /// The all-phases Halo report of that run.
    all_phases: HaloReport,
}

impl Measured {
    /// The headline model's readings on the first N.
    fn main(&self) -> &[Reading] {
        &self.by_size[0].readings
    }

    /// A model's errors on the first packing, by id.
    fn model(&self, id: &str) -> &ModelErrors {
        self.by_model
            .iter()
            .find(|e| e.id == id)
            .expect("every model runs on the first packing")
    }

    /// The headline's errors `f` over every packing at the first N.
    fn headline_spread(&self, f: fn(&ModelErrors) -> f64) -> Spread {
        Spread::of(std::iter::once(&self.by_model[0]).chain(&self.repeats).map(f))
    }

    /// Particles of the first N.
    fn n0(&self) -> usize {
        self.by_size[0].n
    }

    /// The a-priori tolerances of T and |q| at the first N.
    fn tolerances(&self) -> (f64, f64) {
        (
            scaled_tolerance(0.01, 150_000.0, self.n0()),
            scaled_tolerance(0.04, 150_000.0, self.n0()),
        )
    }
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let m = measure(ctx)?;
    let mut out = CaseOutcome::new("inclusion-fields", ctx.mode);
    out.n_particles = m.first.model.particles.len();
    compare(ctx, &m, &mut out);
    report(ctx, &m, &mut out)?;
    Ok(out)
}

/// The FEM reference at A, B, C and the paper's Table 2.
fn fem_reference() -> anyhow::Result<(Vec<FemRef>, Value)> {
    let fem = crate::refs::single_inclusion_fem();
    let f5 = &fem["fields_contrast_5"];
    let mut refs = Vec::new();
    for name in ["A", "B", "C"] {
        let p = f5["points_in_units_of_L"][name]
            .as_array()
            .ok_or_else(|| anyhow::anyhow!("FEM reference: no point {name}"))?;
        let p: Vec<f64> = p.iter().filter_map(Value::as_f64).collect();
        anyhow::ensure!(p.len() == 3, "FEM reference: point {name} needs 3 coordinates");
        let get = |k: &str| {
            f5["fem"][name][k]
                .as_f64()
                .ok_or_else(|| anyhow::anyhow!("FEM reference: no {k} at {name}"))
        };
        refs.push(FemRef {
            name: name.to_string(),
            point: [p[0], p[1], p[2]],
            t: get("T_C")?,
            q: get("q_mag_W_m2")?,
            q_ball: get("q_mag_ball_avg_r0.02L_W_m2")?,
        });
    }
    Ok((refs, f5["paper_table2"].clone()))
}

/// A model's errors from its readings.
fn errors_of(id: String, rd: Vec<Reading>, refs: &[FemRef], wall_s: f64) -> ModelErrors {
    ModelErrors {
        id,
        wall_s,
        t: max_err(&rd, refs, |m| m.t, |f| f.t),
        q: max_err(&rd, refs, |m| m.q, |f| f.q),
        q_all: max_err(&rd, refs, |m| m.q_all, |f| f.q),
        q_a: rel(rd[0].q, refs[0].q),
        readings: rd,
    }
}

/// Packings at the first N: every model on the first, the headline on the others.
const PACKINGS: u64 = 3;

/// Every model on the first N, the headline on the others and on further packings.
fn measure(ctx: &Ctx) -> anyhow::Result<Measured> {
    let sizes = ctx.pick(vec![20_000], vec![150_000, 500_000]);
    let (refs, paper_table2) = fem_reference()?;
    let points: Vec<(String, [f64; 3])> = refs.iter().map(|f| (f.name.clone(), f.point)).collect();
    let variants = Variant::with_laguerre();
    let mut by_model = Vec::new();
    let mut by_size = Vec::new();
    let mut first_run = None;
    for (i, &n) in sizes.iter().enumerate() {
        let base = scene(n, ctx.seed, &points);
        let centre_model = model_of(&base)?;
        let set = ModelSet::new(&base, &centre_model, &[(centred_sphere(), 1)])?;
        let cts = Calibrations::of(&centre_model)?;
        let vs = if i == 0 { &variants[..] } else { &variants[..1] };
        let mut headline = None;
        for v in vs {
            let cfg = v.calibrated_scene(&base, &cts);
            let model = set.get(v);
            let t0 = Instant::now();
            let r = run_with(&cfg, model)?;
            let wall_s = t0.elapsed().as_secs_f64() + network_s(model) + cts.cost_s(v);
            let (q_all, rep_all) = all_phases_halo(&r)?;
            let rd = readings(&r, &refs, &q_all, n)?;
            if i == 0 {
                by_model.push(errors_of(v.id(), rd.clone(), &refs, wall_s));
            }
            if headline.is_none() {
                headline = Some((r, rd, rep_all));
            }
        }
        let (r, rd, rep_all) = headline.expect("at least the headline model");
        by_size.push(SizeReadings {
            // The packing's particles (the conforming seeds are sites, not particles).
            n: r.model.particles.len() - r.model.seeds,
            readings: rd,
        });
        if i == 0 {
            first_run = Some((r, cts, rep_all));
        }
    }
    // The headline on further packings at the first N: its own Laguerre model, no contacts.
    let mut repeats = Vec::new();
    for k in 1..PACKINGS {
        let v = Variant::HEADLINE;
        let cfg = v.scene(&scene(sizes[0], ctx.seed + k, &points), 1.0);
        // Built with the scene's own inclusion under the headline's rule.
        let model = model_of(&cfg)?;
        let t1 = Instant::now();
        let r = run_with(&cfg, &model)?;
        let wall_s = t1.elapsed().as_secs_f64() + network_s(&model);
        let (q_all, _) = all_phases_halo(&r)?;
        let rd = readings(&r, &refs, &q_all, sizes[0])?;
        repeats.push(errors_of(v.id(), rd, &refs, wall_s));
    }
    let (first, cts, all_phases) = first_run.expect("at least one size");
    Ok(Measured {
        sizes,
        refs,
        paper_table2,
        by_model,
        by_size,
        repeats,
        first,
        cts,
        all_phases,
    })
}

/// The first run's metrics: calibration, solve, Halo, the main model's errors and every
/// size's readings at the points.
fn field_metrics(m: &Measured, out: &mut CaseOutcome) {
    let (first, main, refs) = (&m.first, m.main(), &m.refs);
    let th = first.thermal.as_ref().expect("thermal");
    let (_, _, hrep) = first.halo.as_ref().expect("halo requested");
    let headline = &m.by_model[0].id;
    let recommended = Variant::RECOMMENDED.id();
    out.metric("c_t_particles", m.cts.particles);
    out.metric("c_t_walls", m.cts.walls);
    out.metric("headline_model", headline.clone());
    out.metric("recommended_model", recommended.clone());
    out.metric("steady_solve_s", th.report.wall_s);
    out.metric("cg_iterations", th.report.iterations);
    out.metric("halo_phases", format!("{:?}", hrep.phases));
    out.metric("halo_wall_s", hrep.wall_s);
    out.metric("halo_mean_members", hrep.mean_members);
    out.metric("halo_all_phases_wall_s", m.all_phases.wall_s);
    out.metric("halo_all_phases_mean_members", m.all_phases.mean_members);

    let err_t = max_err(main, refs, |x| x.t, |f| f.t);
    let err_q = max_err(main, refs, |x| x.q, |f| f.q);
    out.metric("max_rel_error_T", err_t);
    out.metric("max_rel_error_q", err_q);
    out.metric(
        "max_rel_error_q_ball",
        max_err(main, refs, |x| x.q_ball, |f| f.q_ball),
    );
    out.metric(
        "max_rel_error_q_all_phases",
        max_err(main, refs, |x| x.q_all, |f| f.q),
    );
    out.metric(
        "max_rel_error_q_ball_all_phases",
        max_err(main, refs, |x| x.q_all_ball, |f| f.q_ball),
    );
    for s in &m.by_size {
        let points: Map<String, Value> = s
            .readings
            .iter()
            .map(|x| {
                (
                    x.name.clone(),
                    serde_json::json!({
                        "T": x.t, "q": x.q, "T_ball": x.t_ball, "q_ball": x.q_ball,
                        "q_all_phases": x.q_all, "q_ball_all_phases": x.q_all_ball, "halo_cut": x.cut
                    }),
                )
            })
            .collect();
        out.metric(&format!("points_{}", s.n), Value::Object(points));
    }
}

/// Every model's errors and wall time, and the headline's spread over the packings.
fn model_metrics(m: &Measured, out: &mut CaseOutcome) {
    let by_model = |f: fn(&ModelErrors) -> f64| -> Value {
        Value::Object(
            m.by_model
                .iter()
                .map(|e| (e.id.clone(), Value::from(f(e))))
                .collect(),
        )
    };
    out.metric("max_rel_error_T_by_model", by_model(|e| e.t));
    out.metric("max_rel_error_q_by_model", by_model(|e| e.q));
    out.metric("max_rel_error_q_all_phases_by_model", by_model(|e| e.q_all));
    out.metric("rel_error_q_A_by_model", by_model(|e| e.q_a));
    out.metric("wall_s_by_model", by_model(|e| e.wall_s));
    out.metric("max_rel_error_q_headline", m.headline_spread(|e| e.q).json());
    out.metric("rel_error_q_A_headline", m.headline_spread(|e| e.q_a).json());
}

/// Metrics, references and the checks of T and |q| (the quick |q| gate is at A).
fn compare(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) {
    let (main, refs) = (m.main(), &m.refs);
    let headline = &m.by_model[0].id;
    let recommended = Variant::RECOMMENDED.id();
    field_metrics(m, out);
    out.reference("max_rel_error_T", 0.01);
    out.reference("max_rel_error_q", 0.040);
    out.reference(
        "source",
        "Haddad 2021 §4.2 Table 2 (1.5·10⁵ DE: |q| 7796, 2370, 6183 W/m²); FEM: shared/refs/single-inclusion-fem.json",
    );
    let (tol_t, tol_q) = m.tolerances();
    let spread_t = m.headline_spread(|e| e.t);
    out.metric("max_rel_error_T_headline", spread_t.json());
    out.compare(Comparison::at_most(
        &format!(
            "max relative error of T at A, B, C ({headline}, the headline; largest of {} packing(s))",
            spread_t.count
        ),
        spread_t.max,
        tol_t,
        "paper < 1 % at 1.5·10⁵ DE",
    ));
    let rec = m.model(&recommended);
    out.compare(Comparison::at_most(
        &format!("max relative error of T at A, B, C ({recommended}, the recommended contact model)"),
        rec.t,
        tol_t,
        "paper < 1 % at 1.5·10⁵ DE",
    ));
    let err_q_a = rel(main[0].q, refs[0].q);
    out.metric("rel_error_q_A", err_q_a);
    out.metric("rel_error_q_A_all_phases", rel(main[0].q_all, refs[0].q));
    model_metrics(m, out);
    let (err_q_rec, err_q_a_rec) = (rec.q, rec.q_a);
    for (id, what, q, q_a) in [
        (
            headline,
            format!("the headline; largest of {} packing(s)", spread_t.count),
            m.headline_spread(|e| e.q).max,
            m.headline_spread(|e| e.q_a).max,
        ),
        (
            &recommended,
            "the recommended contact model".to_string(),
            err_q_rec,
            err_q_a_rec,
        ),
    ] {
        match ctx.mode {
            crate::Mode::Full => out.compare(Comparison::at_most(
                &format!("max relative error of |q| (Halo 11) at A, B, C ({id}, {what})"),
                q,
                tol_q,
                "paper up to 4.0 % from our FEM at 1.5·10⁵ DE",
            )),
            crate::Mode::Quick => out.compare(Comparison::at_most(
                &format!("relative error of |q| (Halo 11) at A ({id}, {what}; B and C: see the notes)"),
                q_a,
                tol_q,
                "paper up to 4.0 % from our FEM at 1.5·10⁵ DE",
            )),
        }
    }
}

/// A line of the points table: a reading of ours against the FEM, or a line of the paper's
/// Table 2.
enum PointLine<'a> {
    /// Particles, our reading, the FEM at that point.
    Ours(usize, &'a Reading, &'a FemRef),
    /// The paper's values at a point.
    Paper(&'a str),
}

/// The slices, the two tables and the notes.
fn report(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    slices(ctx, m, out)?;
    out.tables.push(models_table(m));
    out.tables.push(points_table(m));
    run_notes(ctx, m, out);
    Ok(())
}

/// The slice pictures of T and |q| on Z = 0.5L (Figs. 15a, 16a), and the note on their cost.
fn slices(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    let r = &m.first;
    let th = r.thermal.as_ref().expect("thermal");
    let (halo, _, hrep) = r.halo.as_ref().expect("halo requested");
    let qmag: Vec<f64> = halo.iter().map(|v| v.norm()).collect();
    let cov_t = slice_picture(
        r,
        &th.temperatures,
        Axis::Z,
        0.5 * L,
        &format!(
            "T on Z = 0.5L, N = {} (Haddad 2021 Fig. 15a)",
            r.model.particles.len()
        ),
        "T (°C)",
        &ctx.out.join("inclusion-fields-T.png"),
    )?;
    slice_picture(
        r,
        &qmag,
        Axis::Z,
        0.5 * L,
        &format!(
            "|q| (Halo k = 11) on Z = 0.5L, N = {} (Haddad 2021 Fig. 16a)",
            r.model.particles.len()
        ),
        "|q| (W/m²)",
        &ctx.out.join("inclusion-fields-q.png"),
    )?;
    out.charts.push("inclusion-fields-T.png".into());
    out.charts.push("inclusion-fields-q.png".into());
    out.note(format!(
        "Slices: {:.0} % of the pixels lie in a particle's section by the plane (the rest show the particle with the \
         nearest centre). Halo k = 11 cost {:.2} s ({:.0} members on \
         average, own phase; all phases: {:.2} s, {:.0} members), the steady solve {:.2} s ({} CG iterations).",
        100.0 * cov_t,
        hrep.wall_s,
        hrep.mean_members,
        m.all_phases.wall_s,
        m.all_phases.mean_members,
        th.report.wall_s,
        th.report.iterations
    ));
    Ok(())
}

/// The relative errors of T and |q| at A, B, C for every model on the first N.
fn models_table(m: &Measured) -> Table {
    let n0 = m.n0();
    let refs = &m.refs;
    Columns::new()
        .column("model", |e: &ModelErrors| e.id.clone())
        .column("wall time (s)", |e| format!("{:.2}", e.wall_s))
        .columns_for(
            0..refs.len(),
            |&k| format!("T {}", refs[k].name),
            |&k, e| {
                let f = &refs[k];
                format!("{:+.2} %", 100.0 * (e.readings[k].t - f.t) / f.t)
            },
        )
        .columns_for(
            0..refs.len(),
            |&k| format!("|q| {}", refs[k].name),
            |&k, e| {
                let f = &refs[k];
                format!("{:+.1} %", 100.0 * (e.readings[k].q - f.q) / f.q)
            },
        )
        .columns_for(
            0..refs.len(),
            |&k| format!("all {}", refs[k].name),
            |&k, e| {
                let f = &refs[k];
                format!("{:+.1} %", 100.0 * (e.readings[k].q_all - f.q) / f.q)
            },
        )
        .table(
            format!(
                "Relative errors of T and |q| (Halo 11, nearest particle; own-phase Halo, then all-phases) at A, B, C \
                 for every model, N = {n0} (surface-boundary-phase rule; the first is the headline; wall time = network + \
                 calibration + the run with its Halo)"
            ),
            &m.by_model,
        )
}

/// T and |q| at the paper's points for every N, with the FEM and the paper's Table 2.
fn points_table(m: &Measured) -> Table {
    let refs = &m.refs;
    let paper = &m.paper_table2;
    let ours = |l: &PointLine, cell: &dyn Fn(usize, &Reading, &FemRef) -> String| match l {
        PointLine::Ours(n, x, f) => cell(*n, x, f),
        PointLine::Paper(_) => String::new(),
    };
    let lines: Vec<PointLine> = m
        .by_size
        .iter()
        .flat_map(|s| {
            s.readings
                .iter()
                .zip(refs)
                .map(|(x, f)| PointLine::Ours(s.n, x, f))
        })
        .chain(refs.iter().map(|f| PointLine::Paper(&f.name)))
        .collect();
    Columns::new()
        .column("N", |l: &PointLine| match l {
            PointLine::Ours(n, ..) => n.to_string(),
            PointLine::Paper(_) => "paper 150 000".into(),
        })
        .column("point", |l| match l {
            PointLine::Ours(_, x, _) => x.name.clone(),
            PointLine::Paper(name) => name.to_string(),
        })
        .column("T (°C)", |l| match l {
            PointLine::Ours(_, x, _) => format!("{:.3}", x.t),
            PointLine::Paper(name) => format!("{}", paper[*name]["T_C"]),
        })
        .column("T FEM", |l| ours(l, &|_, _, f| format!("{:.3}", f.t)))
        .column("|q| (W/m²)", |l| match l {
            PointLine::Ours(_, x, _) => format!("{:.0}", x.q),
            PointLine::Paper(name) => format!("{}", paper[*name]["q_mag_W_m2"]["DE_150k"]),
        })
        .column("|q| ball", |l| ours(l, &|_, x, _| format!("{:.0}", x.q_ball)))
        .column("|q| all phases", |l| {
            ours(l, &|_, x, _| format!("{:.0}", x.q_all))
        })
        .column("|q| FEM", |l| match l {
            PointLine::Ours(_, _, f) => format!("{:.1}", f.q),
            PointLine::Paper(name) => format!("{} (its FE)", paper[*name]["q_mag_W_m2"]["FE"]),
        })
        .column("err |q|", |l| {
            ours(l, &|_, x, f| format!("{:.2} %", 100.0 * (x.q - f.q) / f.q))
        })
        .column("err all phases", |l| {
            ours(l, &|_, x, f| format!("{:.2} %", 100.0 * (x.q_all - f.q) / f.q))
        })
        .column("Halo cut", |l| {
            ours(l, &|_, x, _| if x.cut { "yes" } else { "no" }.into())
        })
        .table(
            "T and |q| at the paper's points (nearest particle; ball = volume average over r = 0.02L)",
            &lines,
        )
}

/// The tolerances at this N and the headline's spread over the packings, the run's sizes, and
/// the pointer to the case's notes file.
fn run_notes(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) {
    let (tol_t, tol_q) = m.tolerances();
    out.note(format!(
        "Tolerances at N = {}: T {:.2} % and |q| {:.2} % (the paper's errors at 1.5·10⁵ scaled by N^(-1/3)), for the \
         headline ({}) and the recommended contact model ({}). The headline also ran on {} more packing(s) (seeds {}…): \
         over all, T error {}, |q| error {}, |q| error at A {} (mean / max).",
        m.n0(),
        100.0 * tol_t,
        100.0 * tol_q,
        m.by_model[0].id,
        Variant::RECOMMENDED.id(),
        m.repeats.len(),
        ctx.seed + 1,
        m.headline_spread(|e| e.t).percent(),
        m.headline_spread(|e| e.q).percent(),
        m.headline_spread(|e| e.q_a).percent()
    ));
    out.note(format!(
        "{} mode: N = {:?}; the metrics use the first N. Method, reference, Halo phases and tolerances: \
         validation/notes/inclusion-fields.md.",
        ctx.mode.name(),
        m.sizes
    ));
}
