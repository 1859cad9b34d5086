//! `sphere-transient` — Haddad et al. 2021 §2.2, Figs. 7–8: an aluminium sphere D = 0.1 m
//! (λ = 185 W/(m·K), ρ = 2700 kg/m³, c = 900 J/(kg·K)) initially at 20 °C, its surface held
//! at 200 °C. Centre temperature at t = 0.5 … 30 s and T(r) at 10 s against the CORRECTED
//! series (`shared/refs/analytic.md` §2; the paper's eqs. 18–19 swap T0 and Ti and miss R).
//!
//! The centre temperature is the volume-weighted mean over the particles whose centre lies
//! within R/10 of the centre (a point value of a particle field needs a small average).
//! Models, on the same packing, the surface temperature held on the sphere surface (wall
//! half-contacts): the Laguerre cells, clipped by planes tangent to the sphere (the headline,
//! chosen for its consistency property — a linear field solves the network exactly — before
//! any of its numbers were seen; explicit, and implicit in `--full`), Terreros α (explicit and
//! implicit) and the calibrated model (implicit); each with its cost.
//!
//! Tolerances: the papers' models keep the paper's maximum absolute error, 1.93 °C at 10⁵
//! particles; `--quick` runs 2·10⁴ particles and accepts the same scaled by N^(-1/3)
//! (3.3 °C). The Laguerre headline (explicit, the largest error over the packings run:
//! `--full` 3, `--quick` [`packings`]): the target 0.3 °C at 10⁵ in `--full`, scaled by
//! N^(-1/3) in `--quick` (0.51 °C at 2·10⁴), both chosen before any Laguerre number was seen.
//! Its implicit run (backward Euler, 20 ms) is reported, not gated: the step's own error is
//! of that order (Terreros: explicit and implicit differ by about 0.4 °C). The explicit solver
//! runs at 0.9 × the exact bound.
//!
//! The compared quantity of the Laguerre gate was changed after its first numbers were seen
//! (the tolerance was not): the centre probe is a ball average over r < R/10, and the ball
//! average of the ANALYTIC field differs from its centre value by up to 0.8 °C (t = 2 s;
//! 0.7 °C at 5 s) — a bias of the probe, the same at every N, larger than the 0.3 °C target.
//! The gate compares the probe with the analytic field probed the same way (T_an(|x_p|, t) over
//! the same particles with the same weights, `max_abs_error_centre_c_same_ball`); the error
//! against the centre value (`max_abs_error_centre_c`, the paper's comparison) is reported
//! beside it for every model, and the papers' models keep their checks on it.
//!
//! Reference, probe, models and tolerances, as documentation: `validation/notes/sphere-transient.md`.

use super::common::*;
use super::transient::sphere::{
    A_AL, R, SphereErrors, explicit, implicit, measure as errors_of, scene, scene_calibrated, scene_laguerre,
};
use crate::analytic::{sphere_centre_temperature, sphere_temperature};
use crate::table::Columns;
use crate::{CaseOutcome, Comparison, Ctx, Table};
use demcon_plot::{Chart, Scale, Series, draw};

/// The corrected eq. 19 centre temperature (°C) at `t` (s).
fn centre_analytic(t: f64) -> f64 {
    sphere_centre_temperature(t, R, 20.0, 200.0, A_AL)
}

/// Packings of the Laguerre headline (the first carries every model).
fn packings(ctx: &Ctx) -> u64 {
    ctx.pick(1, 3)
}

/// The Laguerre headline on one packing.
struct LaguerreRun {
    explicit: SphereErrors,
    /// Backward Euler (`--full` only).
    implicit: Option<SphereErrors>,
    /// Tessellation (s) and Σ V_cells/V − 1.
    network_s: f64,
    volume_error: f64,
}

/// Everything the case measures, on one packing (and the headline on further ones).
struct Measured {
    /// Particles.
    n: usize,
    /// Requested particles (the tolerances scale with it).
    n_requested: usize,
    /// Contact detection (s).
    contacts_s: f64,
    /// Laguerre cells, every packing (the first first).
    laguerre: Vec<LaguerreRun>,
    /// Terreros α, walls: explicit and implicit.
    explicit: SphereErrors,
    implicit: SphereErrors,
    /// Calibrated C_t, implicit.
    calibrated: SphereErrors,
}

impl Measured {
    /// The paper's 1.93 °C at 10⁵ particles scaled by N^(-1/3).
    fn tolerance(&self) -> f64 {
        1.93 * (100_000.0 / self.n_requested as f64).cbrt()
    }

    /// The Laguerre tolerance: 0.3 °C at 10⁵ (`--full`), scaled by N^(-1/3) (`--quick`).
    fn tolerance_laguerre(&self, ctx: &Ctx) -> f64 {
        ctx.pick(0.3 * (100_000.0 / self.n_requested as f64).cbrt(), 0.3)
    }

    /// The headline on the first packing.
    fn headline(&self) -> &LaguerreRun {
        &self.laguerre[0]
    }

    /// The headline's explicit centre error over its packings, against the centre value.
    fn spread(&self) -> Spread {
        Spread::of(self.laguerre.iter().map(|r| r.explicit.max_abs_error_centre))
    }

    /// The same against the analytic field probed like the DEM one (the gated quantity).
    fn spread_same_ball(&self) -> Spread {
        Spread::of(
            self.laguerre
                .iter()
                .map(|r| r.explicit.max_abs_error_centre_same_ball),
        )
    }
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let m = measure(ctx)?;
    let mut out = CaseOutcome::new("sphere-transient", ctx.mode);
    out.n_particles = m.n;
    compare(ctx, &m, &mut out);
    report(ctx, &m, &mut out)?;
    Ok(out)
}

/// The Laguerre model of a packing (of `model`, or packed here) and its runs.
fn laguerre_run(ctx: &Ctx, n: usize, seed: u64, model: Option<&Model>) -> anyhow::Result<LaguerreRun> {
    let cfg = scene_laguerre(n, seed, explicit(30.0));
    let cells = match model {
        Some(m) => laguerre_model(&cfg, m)?,
        None => model_of(&cfg)?,
    };
    let implicit = match ctx.mode {
        crate::Mode::Full => Some(errors_of(&cells, &scene_laguerre(n, seed, implicit(30.0)))?),
        crate::Mode::Quick => None,
    };
    Ok(LaguerreRun {
        explicit: errors_of(&cells, &cfg)?,
        implicit,
        network_s: network_s(&cells),
        volume_error: cells
            .report
            .tessellation
            .as_ref()
            .map_or(f64::NAN, |t| t.volume_error),
    })
}

/// One packing, every model to 30 s; the headline on further packings.
fn measure(ctx: &Ctx) -> anyhow::Result<Measured> {
    let n = ctx.pick(20_000, 100_000);
    let model = model_of(&scene(n, ctx.seed, explicit(30.0)))?;
    let mut laguerre = vec![laguerre_run(ctx, n, ctx.seed, Some(&model))?];
    for k in 1..packings(ctx) {
        laguerre.push(laguerre_run(ctx, n, ctx.seed + k, None)?);
    }
    Ok(Measured {
        n: model.particles.len(),
        n_requested: n,
        contacts_s: network_s(&model),
        laguerre,
        explicit: errors_of(&model, &scene(n, ctx.seed, explicit(30.0)))?,
        implicit: errors_of(&model, &scene(n, ctx.seed, implicit(30.0)))?,
        calibrated: errors_of(&model, &scene_calibrated(n, ctx.seed, implicit(30.0)))?,
    })
}

/// Metrics, references and the checks.
fn compare(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) {
    let (ex, im, cal) = (&m.explicit, &m.implicit, &m.calibrated);
    let head = m.headline();
    let spread = m.spread();
    out.metric("headline_model", "laguerre");
    out.metric("max_abs_error_centre_c", head.explicit.max_abs_error_centre);
    out.metric("max_abs_error_centre_c_laguerre", spread.json());
    let same = m.spread_same_ball();
    out.metric("max_abs_error_centre_c_same_ball", same.json());
    out.metric(
        "max_abs_error_centre_c_same_ball_terreros",
        ex.max_abs_error_centre_same_ball,
    );
    out.metric(
        "max_abs_error_centre_c_same_ball_terreros_implicit",
        im.max_abs_error_centre_same_ball,
    );
    out.metric(
        "max_abs_error_centre_c_same_ball_calibrated",
        cal.max_abs_error_centre_same_ball,
    );
    if let Some(i) = &head.implicit {
        out.metric("max_abs_error_centre_c_implicit", i.max_abs_error_centre);
    }
    out.metric("centre_t10_c", head.explicit.centre_t10);
    out.metric(
        "max_abs_error_profile_t10_c",
        head.explicit.max_abs_error_profile_t10,
    );
    out.metric("max_abs_error_centre_c_calibrated", cal.max_abs_error_centre);
    out.metric("c_t", cal.c_t);
    out.metric("max_abs_error_centre_c_terreros", ex.max_abs_error_centre);
    out.metric("centre_t10_c_terreros", ex.centre_t10);
    out.metric(
        "max_abs_error_centre_c_terreros_implicit",
        im.max_abs_error_centre,
    );
    out.metric(
        "max_abs_error_profile_t10_c_terreros",
        ex.max_abs_error_profile_t10,
    );
    out.metric("wall_s_explicit", head.explicit.wall_s);
    out.metric("wall_s_explicit_terreros", ex.wall_s);
    out.metric("wall_s_implicit_terreros", im.wall_s);
    out.metric("wall_s_implicit_calibrated", cal.wall_s);
    out.metric("network_s_laguerre", head.network_s);
    out.metric("network_s_contacts", m.contacts_s);
    out.metric("steps_explicit", head.explicit.steps);
    out.metric("steps_explicit_terreros", ex.steps);
    out.metric(
        "laguerre_volume_error",
        Spread::of(m.laguerre.iter().map(|r| r.volume_error.abs())).json(),
    );
    out.reference("max_abs_error_centre_c", 1.93);
    out.reference("centre_t10_c", centre_analytic(10.0));
    out.reference(
        "source",
        "Haddad 2021 §2.2 Figs. 7–8 (10⁵ DE, 1.93 °C); analytic: corrected eq. 19; Laguerre target 0.3 °C at 10⁵ \
         (issue 10)",
    );
    out.compare(Comparison::at_most(
        &format!(
            "Laguerre (headline), explicit: max |T_centre − analytic probed the same way| (°C), largest of {} \
             packing(s)",
            same.count
        ),
        same.max,
        m.tolerance_laguerre(ctx),
        "the issue's 0.3 °C at 10⁵ (quick: scaled by N^(-1/3)); compared quantity changed after the first run (notes)",
    ));
    let tol = m.tolerance();
    out.compare(Comparison::at_most(
        "Terreros α, explicit: max |T_centre − analytic| (°C)",
        ex.max_abs_error_centre,
        tol,
        "paper 1.93 °C at 10⁵ DE",
    ));
    out.compare(Comparison::at_most(
        "Terreros α, implicit: max |T_centre − analytic| (°C)",
        im.max_abs_error_centre,
        tol,
        "paper 1.93 °C at 10⁵ DE",
    ));
    out.compare(Comparison::absolute(
        "Terreros α: T_centre(10 s) (°C)",
        ex.centre_t10,
        centre_analytic(10.0),
        tol,
        "corrected eq. 19: 182.18 °C",
    ));
}

/// A line of the centre table.
struct CentreLine {
    t: f64,
    /// The analytic field probed like the DEM one (Laguerre run's particles and weights).
    same_ball: f64,
    laguerre: f64,
    explicit: f64,
    implicit: f64,
}

/// A line of the side-by-side table.
struct ModelLine<'a> {
    name: &'static str,
    solver: &'static str,
    e: &'a SphereErrors,
    network_s: f64,
}

/// The tables, the two charts and the notes.
fn report(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    out.tables.push(models_table(m));
    out.tables.push(centre_table(m));
    centre_chart(ctx, m, out)?;
    profile_chart(ctx, m, out)?;
    run_notes(ctx, m, out);
    Ok(())
}

/// The models side by side on the first packing: errors, steps and costs.
fn models_table(m: &Measured) -> Table {
    let (ex, im, cal) = (&m.explicit, &m.implicit, &m.calibrated);
    let head = m.headline();
    let mut models = vec![ModelLine {
        name: "Laguerre (headline)",
        solver: "explicit",
        e: &head.explicit,
        network_s: head.network_s,
    }];
    if let Some(i) = &head.implicit {
        models.push(ModelLine {
            name: "Laguerre (headline)",
            solver: "implicit",
            e: i,
            network_s: head.network_s,
        });
    }
    models.extend([
        ModelLine {
            name: "Terreros α",
            solver: "explicit",
            e: ex,
            network_s: m.contacts_s,
        },
        ModelLine {
            name: "Terreros α",
            solver: "implicit",
            e: im,
            network_s: m.contacts_s,
        },
        ModelLine {
            name: "calibrated C_t",
            solver: "implicit",
            e: cal,
            network_s: m.contacts_s,
        },
    ]);
    Columns::new()
        .column("model", |l: &ModelLine| l.name.to_string())
        .column("solver", |l| l.solver.to_string())
        .column("max |T_centre − analytic| (°C)", |l| {
            format!("{:.3}", l.e.max_abs_error_centre)
        })
        .column("same, analytic probed alike (°C)", |l| {
            format!("{:.3}", l.e.max_abs_error_centre_same_ball)
        })
        .column("max |T(r) − analytic| at 10 s (°C)", |l| {
            format!("{:.3}", l.e.max_abs_error_profile_t10)
        })
        .column("steps", |l| l.e.steps.to_string())
        .column("solver (s)", |l| format!("{:.2}", l.e.wall_s))
        .column("network (s)", |l| format!("{:.2}", l.network_s))
        .table(
            format!(
                "The models side by side on one packing, N = {} (calibration time not counted)",
                m.n
            ),
            &models,
        )
}

/// The centre temperature against time: the models, the analytic centre value and its ball
/// average.
fn centre_table(m: &Measured) -> Table {
    let (ex, im) = (&m.explicit, &m.implicit);
    let head = m.headline();
    let lines: Vec<CentreLine> = ex
        .centre
        .iter()
        .enumerate()
        .map(|(i, &(t, v))| CentreLine {
            t,
            laguerre: head.explicit.centre.get(i).map(|c| c.1).unwrap_or(f64::NAN),
            same_ball: head
                .explicit
                .centre_same_ball
                .get(i)
                .map(|c| c.1)
                .unwrap_or(f64::NAN),
            explicit: v,
            implicit: im.centre.get(i).map(|c| c.1).unwrap_or(f64::NAN),
        })
        .collect();
    Columns::new()
        .column("t (s)", |l: &CentreLine| format!("{}", l.t))
        .column("Laguerre, explicit (°C)", |l| format!("{:.2}", l.laguerre))
        .column("Terreros α, explicit (°C)", |l| format!("{:.2}", l.explicit))
        .column("Terreros α, implicit (°C)", |l| format!("{:.2}", l.implicit))
        .column("analytic (°C)", |l| format!("{:.2}", centre_analytic(l.t)))
        .column("analytic, ball average like the probe (°C)", |l| {
            format!("{:.2}", l.same_ball)
        })
        .table(
            "Centre temperature (ball average over r < R/10; the analytic field at the centre and averaged alike)",
            &lines,
        )
}

/// The centre temperature against time (Fig. 7).
fn centre_chart(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    let (ex, im) = (&m.explicit, &m.implicit);
    let head = m.headline();
    let curve: Vec<(f64, f64)> = (1..=120)
        .map(|i| i as f64 * 0.25)
        .map(|t| (t, centre_analytic(t)))
        .collect();
    draw(
        &Chart {
            title: format!("Sphere: centre temperature, N = {} (Haddad 2021 Fig. 7)", m.n),
            x_label: "t (s)".into(),
            y_label: "T centre (°C)".into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            series: vec![
                Series::line("analytic (corrected eq. 19)", curve),
                Series::markers("DEM Laguerre, explicit", head.explicit.centre.clone()),
                Series::markers("DEM Terreros α, explicit", ex.centre.clone()),
                Series::markers("DEM Terreros α, implicit (BE, 20 ms)", im.centre.clone()),
            ],
        },
        &ctx.out.join("sphere-transient.png"),
    )?;
    out.charts.push("sphere-transient.png".into());
    Ok(())
}

/// T(r) at 10 s.
fn profile_chart(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    let (ex, head) = (&m.explicit, m.headline());
    let radial: Vec<(f64, f64)> = (0..=50)
        .map(|i| i as f64 / 50.0)
        .map(|x| (x, sphere_temperature(x * R, 10.0, R, 20.0, 200.0, A_AL)))
        .collect();
    draw(
        &Chart {
            title: "Sphere: T(r) at t = 10 s".into(),
            x_label: "r / R".into(),
            y_label: "T (°C)".into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            series: vec![
                Series::line("analytic", radial),
                Series::markers(
                    "DEM Laguerre, explicit (radial layers)",
                    head.explicit.profile_t10.clone(),
                ),
                Series::markers("DEM Terreros α, explicit (radial layers)", ex.profile_t10.clone()),
            ],
        },
        &ctx.out.join("sphere-profile-t10.png"),
    )?;
    out.charts.push("sphere-profile-t10.png".into());
    Ok(())
}

/// The notes that carry this run's figures, and the pointer to the case's notes file.
fn run_notes(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) {
    let (ex, im, cal) = (&m.explicit, &m.implicit, &m.calibrated);
    let head = m.headline();
    out.note(format!(
        "Headline (Laguerre cells; Σ V_cells/V − 1 = {:.1e}) over {} packing(s) (seeds {}…): explicit centre error {:.3} / \
         {:.3} °C against the analytic field probed alike, {:.3} / {:.3} °C against its centre value (mean / max). \
         Method, reference, the probe's bias and tolerances: validation/notes/sphere-transient.md.",
        head.volume_error,
        m.laguerre.len(),
        ctx.seed,
        m.spread_same_ball().mean,
        m.spread_same_ball().max,
        m.spread().mean,
        m.spread().max,
    ));
    out.note(format!(
        "The papers' models on the same packing: Terreros α {:.2} °C explicit, {:.2} °C implicit; calibrated surfaces \
         (C_t = {:.4}, our own calibration on this sphere), implicit, a largest centre error of {:.2} °C \
         (`max_abs_error_centre_c_calibrated`). Explicit {} steps (Laguerre; Terreros {}); implicit backward Euler \
         Δt = 20 ms.",
        ex.max_abs_error_centre,
        im.max_abs_error_centre,
        cal.c_t,
        cal.max_abs_error_centre,
        head.explicit.steps,
        ex.steps
    ));
}
