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
use super::haddad2021_slab_transient as slab;
use super::haddad2021_sphere_transient as sphere;
use crate::chart::{Chart, Scale, Series, draw};
use crate::{CaseOutcome, Comparison, Ctx, Table};

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let sizes: Vec<usize> = ctx.pick(
        vec![2_000, 5_000, 10_000, 20_000],
        vec![10_000, 30_000, 100_000, 300_000],
    );
    let mut out = CaseOutcome::new("cost-accuracy-thermal", ctx.mode);
    let mut table = Table {
        title: "Error and cost against N".into(),
        header: vec![
            "problem".into(),
            "N".into(),
            "solver".into(),
            "error".into(),
            "solver wall (s)".into(),
            "steps".into(),
            "build (s)".into(),
        ],
        rows: Vec::new(),
    };
    let (mut se_n, mut si_n, mut se_t, mut si_t) = (vec![], vec![], vec![], vec![]);
    let (mut pe_n, mut pi_n, mut pe_t, mut pi_t) = (vec![], vec![], vec![], vec![]);
    let mut metrics_slab = Map::new();
    let mut metrics_sphere = Map::new();
    let mut all_finite = true;
    for &n in &sizes {
        // Slab.
        let t0 = std::time::Instant::now();
        let model = model_of(&slab::scene(n, ctx.seed, slab::explicit()))?;
        let build = t0.elapsed().as_secs_f64();
        out.n_particles = out.n_particles.max(model.particles.len());
        let ex = slab::measure(&model, &slab::scene(n, ctx.seed, slab::explicit()))?;
        let im = slab::measure(&model, &slab::scene(n, ctx.seed, slab::implicit()))?;
        all_finite &= ex.profile.is_finite() && im.profile.is_finite();
        se_n.push((n as f64, ex.profile));
        si_n.push((n as f64, im.profile));
        se_t.push((ex.wall_s.max(1e-3), ex.profile));
        si_t.push((im.wall_s.max(1e-3), im.profile));
        metrics_slab.insert(
            key(n),
            serde_json::json!({"explicit": ex.profile, "implicit": im.profile, "explicit_s": ex.wall_s, "implicit_s": im.wall_s}),
        );
        for (name, e) in [("explicit", &ex), ("implicit", &im)] {
            table.rows.push(vec![
                "slab".into(),
                n.to_string(),
                name.into(),
                format!("{:.3} %", 100.0 * e.profile),
                format!("{:.2}", e.wall_s),
                e.steps.to_string(),
                format!("{build:.1}"),
            ]);
        }
        // Sphere, to 10 s.
        let t0 = std::time::Instant::now();
        let model = model_of(&sphere::scene(n, ctx.seed, sphere::explicit(10.0)))?;
        let build = t0.elapsed().as_secs_f64();
        let ex = sphere::measure(&model, &sphere::scene(n, ctx.seed, sphere::explicit(10.0)))?;
        let im = sphere::measure(&model, &sphere::scene(n, ctx.seed, sphere::implicit(10.0)))?;
        all_finite &= ex.max_abs_error_centre.is_finite() && im.max_abs_error_centre.is_finite();
        pe_n.push((n as f64, ex.max_abs_error_centre));
        pi_n.push((n as f64, im.max_abs_error_centre));
        pe_t.push((ex.wall_s.max(1e-3), ex.max_abs_error_centre));
        pi_t.push((im.wall_s.max(1e-3), im.max_abs_error_centre));
        metrics_sphere.insert(
            key(n),
            serde_json::json!({"explicit_c": ex.max_abs_error_centre, "implicit_c": im.max_abs_error_centre, "explicit_s": ex.wall_s, "implicit_s": im.wall_s}),
        );
        for (name, e) in [("explicit", &ex), ("implicit", &im)] {
            table.rows.push(vec![
                "sphere (to 10 s)".into(),
                n.to_string(),
                name.into(),
                format!("{:.3} °C", e.max_abs_error_centre),
                format!("{:.2}", e.wall_s),
                e.steps.to_string(),
                format!("{build:.1}"),
            ]);
        }
    }
    out.metric("slab_max_rel_error", Value::Object(metrics_slab));
    out.metric("sphere_max_abs_error_centre_c", Value::Object(metrics_sphere));
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
    out.tables.push(table);
    let chart = |title: &str, x: &str, y: &str, a: Vec<(f64, f64)>, b: Vec<(f64, f64)>, file: &str| {
        draw(
            &Chart {
                title: title.into(),
                x_label: x.into(),
                y_label: y.into(),
                x_scale: Scale::Log,
                y_scale: Scale::Log,
                series: vec![
                    Series::line("explicit (forward Euler)", a),
                    Series::line("implicit (backward Euler)", b),
                ],
            },
            &ctx.out.join(file),
        )
    };
    chart(
        "Slab: error against N",
        "N (particles)",
        "max relative error of T(y)",
        se_n,
        si_n,
        "cost-accuracy-slab-n.png",
    )?;
    chart(
        "Slab: error against solver wall time",
        "wall time (s)",
        "max relative error of T(y)",
        se_t,
        si_t,
        "cost-accuracy-slab-time.png",
    )?;
    chart(
        "Sphere: centre error against N",
        "N (particles)",
        "max |T_centre − analytic| (°C)",
        pe_n,
        pi_n,
        "cost-accuracy-sphere-n.png",
    )?;
    chart(
        "Sphere: centre error against solver wall time",
        "wall time (s)",
        "max |T_centre − analytic| (°C)",
        pe_t,
        pi_t,
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
    Ok(out)
}
