//! `cost-accuracy-thermal` — error against particle count and against wall time for the
//! slab (Haddad 2021 §2.2, Fig. 5, eq. 17) and the sphere (Figs. 7–8, corrected eq. 19),
//! explicit (forward Euler at 0.9 × the exact bound) against implicit (backward Euler:
//! 0.5 ms slab steps, 20 ms sphere steps), with the models of `slab-transient` and
//! `sphere-transient` (Terreros α surfaces, wall boundaries). The sphere runs to t = 10 s
//! (its centre error is largest there).
//!
//! No pass/fail threshold of its own beyond sanity (every run finishes with finite errors):
//! this case is the chart that tells a user which N and which solver buy which accuracy.

use serde_json::{Map, Value};

use super::common::*;
use super::study::Study;
use super::transient::{slab, sphere};
use crate::table::Columns;
use crate::{CaseOutcome, Comparison, Ctx};
use demcon_plot::{Chart, Scale, Series, draw};

/// The two problems.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Problem {
    /// The slab, relative error of the layer profile.
    Slab,
    /// The sphere to 10 s, largest absolute error of the centre temperature (°C).
    Sphere,
}

/// One run: a problem at one N with one solver.
struct Cost {
    problem: Problem,
    /// Requested particles.
    n: usize,
    /// Particles packed.
    particles: usize,
    /// `explicit` or `implicit`.
    solver: &'static str,
    /// Slab: relative error (fraction); sphere: °C.
    error: f64,
    /// Solver wall time (s).
    wall_s: f64,
    steps: u64,
    /// Packing and contacts of this problem at this N (s).
    build_s: f64,
}

/// Slab and sphere, explicit then implicit, per N (one packing each).
type Measured = Study<Vec<Cost>>;

/// The runs of one problem and solver, in N order.
fn of<'a>(m: &'a Measured, problem: Problem, solver: &'a str) -> impl Iterator<Item = &'a Cost> {
    m.rows()
        .flatten()
        .filter(move |c| c.problem == problem && c.solver == solver)
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let sizes: Vec<usize> = ctx.pick(
        vec![2_000, 5_000, 10_000, 20_000],
        vec![10_000, 30_000, 100_000, 300_000],
    );
    let m = Study::run(&sizes, |_| 1, ctx.seed, |n, seed, _| measure(n, seed))?;
    let mut out = CaseOutcome::new("cost-accuracy-thermal", ctx.mode);
    out.n_particles = m
        .rows()
        .flatten()
        .filter(|c| c.problem == Problem::Slab)
        .map(|c| c.particles)
        .max()
        .unwrap_or(0);
    compare(&m, &mut out);
    report(ctx, &m, &mut out)?;
    Ok(out)
}

/// Slab and sphere (to 10 s), explicit and implicit, at `n`.
fn measure(n: usize, seed: u64) -> anyhow::Result<Vec<Cost>> {
    let mut runs = Vec::new();
    // Slab.
    let (model, build_s) = model_of_timed(&slab::scene(n, seed, slab::explicit()))?;
    for (solver, cfg) in [
        ("explicit", slab::scene(n, seed, slab::explicit())),
        ("implicit", slab::scene(n, seed, slab::implicit())),
    ] {
        let e = slab::measure(&model, &cfg)?;
        runs.push(Cost {
            problem: Problem::Slab,
            n,
            particles: model.particles.len(),
            solver,
            error: e.profile,
            wall_s: e.wall_s,
            steps: e.steps,
            build_s,
        });
    }
    // Sphere, to 10 s.
    let (model, build_s) = model_of_timed(&sphere::scene(n, seed, sphere::explicit(10.0)))?;
    for (solver, cfg) in [
        ("explicit", sphere::scene(n, seed, sphere::explicit(10.0))),
        ("implicit", sphere::scene(n, seed, sphere::implicit(10.0))),
    ] {
        let e = sphere::measure(&model, &cfg)?;
        runs.push(Cost {
            problem: Problem::Sphere,
            n,
            particles: model.particles.len(),
            solver,
            error: e.max_abs_error_centre,
            wall_s: e.wall_s,
            steps: e.steps,
            build_s,
        });
    }
    Ok(runs)
}

/// Metrics keyed by N and the sanity check (every error finite).
fn compare(m: &Measured, out: &mut CaseOutcome) {
    let by_n = |problem: Problem, error_key: &str| -> Map<String, Value> {
        of(m, problem, "explicit")
            .zip(of(m, problem, "implicit"))
            .map(|(ex, im)| {
                let mut v = Map::new();
                v.insert(format!("explicit{error_key}"), Value::from(ex.error));
                v.insert(format!("implicit{error_key}"), Value::from(im.error));
                v.insert("explicit_s".into(), Value::from(ex.wall_s));
                v.insert("implicit_s".into(), Value::from(im.wall_s));
                (key(ex.n), Value::Object(v))
            })
            .collect()
    };
    let all_finite = m.rows().flatten().all(|c| c.error.is_finite());
    out.metric("slab_max_rel_error", Value::Object(by_n(Problem::Slab, "")));
    out.metric(
        "sphere_max_abs_error_centre_c",
        Value::Object(by_n(Problem::Sphere, "_c")),
    );
    out.reference("slab_max_rel_error", "paper 0.7 % at 1e5 DE");
    out.reference("sphere_max_abs_error_centre_c", "paper 1.93 °C at 1e5 DE");
    out.compare(Comparison {
        name: "every run finishes with finite errors".into(),
        measured: f64::from(u8::from(all_finite)),
        reference: 1.0,
        tolerance: 0.0,
        relative: false,
        source: "sanity".into(),
        pass: all_finite,
    });
}

/// The table, the four charts and the note.
fn report(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    let table = Columns::new()
        .column("problem", |c: &Cost| match c.problem {
            Problem::Slab => "slab".into(),
            Problem::Sphere => "sphere (to 10 s)".into(),
        })
        .column("N", |c| c.n.to_string())
        .column("solver", |c| c.solver.into())
        .column("error", |c| match c.problem {
            Problem::Slab => format!("{:.3} %", 100.0 * c.error),
            Problem::Sphere => format!("{:.3} °C", c.error),
        })
        .column("solver wall (s)", |c| format!("{:.2}", c.wall_s))
        .column("steps", |c| c.steps.to_string())
        .column("build (s)", |c| format!("{:.1}", c.build_s))
        .table("Error and cost against N", m.rows().flatten());
    out.tables.push(table);
    let against_n = |c: &Cost| (c.n as f64, c.error);
    let against_time = |c: &Cost| (c.wall_s.max(1e-3), c.error);
    let chart =
        |title: &str, x: &str, y: &str, problem: Problem, point: &dyn Fn(&Cost) -> (f64, f64), file: &str| {
            draw(
                &Chart {
                    title: title.into(),
                    x_label: x.into(),
                    y_label: y.into(),
                    x_scale: Scale::Log,
                    y_scale: Scale::Log,
                    series: vec![
                        Series::line(
                            "explicit (forward Euler)",
                            of(m, problem, "explicit").map(point).collect(),
                        ),
                        Series::line(
                            "implicit (backward Euler)",
                            of(m, problem, "implicit").map(point).collect(),
                        ),
                    ],
                },
                &ctx.out.join(file),
            )
        };
    chart(
        "Slab: error against N",
        "N (particles)",
        "max relative error of T(y)",
        Problem::Slab,
        &against_n,
        "cost-accuracy-slab-n.png",
    )?;
    chart(
        "Slab: error against solver wall time",
        "wall time (s)",
        "max relative error of T(y)",
        Problem::Slab,
        &against_time,
        "cost-accuracy-slab-time.png",
    )?;
    chart(
        "Sphere: centre error against N",
        "N (particles)",
        "max |T_centre − analytic| (°C)",
        Problem::Sphere,
        &against_n,
        "cost-accuracy-sphere-n.png",
    )?;
    chart(
        "Sphere: centre error against solver wall time",
        "wall time (s)",
        "max |T_centre − analytic| (°C)",
        Problem::Sphere,
        &against_time,
        "cost-accuracy-sphere-time.png",
    )?;
    for f in [
        "cost-accuracy-slab-n.png",
        "cost-accuracy-slab-time.png",
        "cost-accuracy-sphere-n.png",
        "cost-accuracy-sphere-time.png",
    ] {
        out.charts.push(f.into());
    }
    out.note("Wall times are the solver's only (packing and contacts in the `build` column), on this 2-core machine.");
    Ok(())
}
