//! `inclusion-etc` — Haddad et al. 2021 §4.1, Fig. 14: a cube L = 0.1 m with a centred
//! spherical inclusion of radius L/3 (f = 0.1551), T = 25 °C on y = 0 and 35 °C on y = L,
//! other faces adiabatic, perfect interface (harmonic mean of the two conductivities on the
//! contacts that cross it, eq. 24). Steady state by one linear solve per contrast.
//!
//! Compared quantity: λ_e/λ_m for the contrasts λ_i/λ_m of the FEM reference
//! (`shared/refs/single-inclusion-fem.json`: 0.01 … 100), and Maxwell beside it. λ_m here is
//! the conductivity MEASURED on the same packing with one phase and the same model (same
//! contacts, surfaces and boundary layers): the DEM sample also carries the discretisation
//! error of the homogeneous matrix, and the paper's ratio is about the inclusion, not about
//! that. The raw ratio to the nominal λ_m is reported beside it.
//!
//! Models: the three transmission-surface models — calibrated C_t π R_m² (C_t cancels from
//! the normalised ratio), Terreros α, and the Laguerre cells — each with every boundary
//! (temperatures on the particles touching the faces, or on the faces through wall
//! half-contacts; the Laguerre cells with walls only) and phase rule (centre, laminate,
//! segment, and the Laguerre cells following the inclusion's surface: conforming), all on the
//! same packing ([`Variant`]). The headline is [`Variant::HEADLINE`]
//! (Laguerre cells, walls, conforming cells), chosen for the Laguerre network's consistency
//! property (a linear field solves it exactly: no calibration, no bias in a homogeneous body)
//! before any of its numbers were seen; the papers' recommended model
//! ([`Variant::RECOMMENDED`], Terreros α, walls, segment rule) keeps its own check. The three
//! surface models with walls and the segment rule also run on two more packings (mean and max
//! over 3 packings) and on a ladder of smaller N for the accuracy-against-cost chart; every
//! model's wall time (network, calibration, solves; the packing is shared) is reported beside
//! its error.
//!
//! Tolerances: the paper reports a maximum error of 0.65 % at 1.5·10⁵ particles. Our error
//! is dominated by the resolution of the interface and of the boundary layers by particles,
//! an error ∝ particle size ∝ N^(-1/3); the recommended contact model's tolerance is the
//! paper's error scaled so, 0.65 % × (1.5·10⁵/N)^(1/3): 1.27 % at 2·10⁴ (`--quick`), 0.65 % at
//! 1.5·10⁵ (`--full`), on the first packing as before. The Laguerre headline, on the largest
//! error over the 3 packings: `--quick` the same scaled tolerance (1.27 % at 2·10⁴), chosen
//! before this case's Laguerre numbers were seen; `--full` issue 32's 0.2 % at every contrast.
//! The headline was the segment rule until issue 32: its first `--quick` run missed the 1.27 %
//! (1.83 %, at contrast 0.01: the series rule's error when the flux must go around an
//! insulating inclusion, falling only about as N^(-0.4)), and it was gated by a 2.5 %
//! regression bound since. The conforming cells (the headline since, by design) meet the
//! a-priori tolerance, which is gated again; the segment rule is reported beside them.
//!
//! Method, reference and tolerances, as documentation: `validation/notes/inclusion-etc.md`.

use std::time::Instant;

/// The `--full` gate of the headline (fraction): issue 32's 0.2 % at every contrast at 1.5·10⁵.
const FULL_TARGET: f64 = 0.002;

use demcon_scene::config::*;
use serde_json::{Map, Value};

use super::common::*;
use super::composite::*;
use crate::analytic::maxwell;
use crate::table::Columns;
use crate::{CaseOutcome, Comparison, Ctx, Table};
use demcon_plot::{Chart, Scale, Series, draw};

/// Matrix conductivity λ_m (W/(m·K)).
const LAMBDA_M: f64 = 33.0;

/// The scene of this case: matrix 33 W/(m·K), inclusion 33·contrast.
pub fn scene(n: usize, seed: u64, contrast: f64) -> SceneConfig {
    slab_scene(
        "inclusion-etc",
        seed,
        n,
        vec![
            material("matrix", LAMBDA_M, 7800.0, 0.9),
            material("inclusion", LAMBDA_M * contrast, 7800.0, 0.9),
        ],
        vec![centred_inclusion("inclusion")],
    )
}

/// One contrast of the FEM reference.
struct FemPoint {
    /// λ_i/λ_m.
    contrast: f64,
    /// FEM λ_e/λ_m.
    ratio: f64,
}

/// One contrast of one model's sweep.
struct Ratio {
    /// λ_i/λ_m.
    contrast: f64,
    /// λ_e/λ_hom (λ_hom measured with one phase on the same model).
    normalised: f64,
    /// λ_e/λ_m with the nominal λ_m.
    raw: f64,
}

/// One model's sweep over the contrasts, on one packing.
struct Sweep {
    v: Variant,
    /// λ measured with one phase (W/(m·K)).
    lambda_hom: f64,
    ratios: Vec<Ratio>,
    iterations: u64,
    solve_s: f64,
    /// Wall time of the sweep's runs (s).
    wall_s: f64,
    /// The model's own cost (s): its network (contacts or tessellation), its calibration, the
    /// sweep (the packing is shared by the models and not counted).
    cost_s: f64,
}

impl Sweep {
    /// Largest relative error of `pick(ratio)` against `against(contrast)`.
    fn max_err(&self, pick: fn(&Ratio) -> f64, against: &dyn Fn(f64) -> f64) -> f64 {
        self.ratios
            .iter()
            .map(|r| (pick(r) - against(r.contrast)).abs() / against(r.contrast))
            .fold(0.0f64, f64::max)
    }
}

/// One packing's side-by-side sweeps ([`Variant::side_by_side`]), at a size of the ladder or
/// on a further packing at the case's N.
struct SideBySide {
    /// Particles.
    n: usize,
    /// Packing and contacts (s).
    build_s: f64,
    /// One sweep per surface model, the headline first.
    sweeps: Vec<Sweep>,
}

/// Everything the case measures.
struct Measured {
    fem: Vec<FemPoint>,
    /// Particles.
    n: usize,
    /// Overall solid fraction of the walled packing.
    phi: f64,
    /// One sweep per variant on the first packing, the headline first.
    sweeps: Vec<Sweep>,
    /// The side-by-side variants on the further packings at the same N.
    repeats: Vec<SideBySide>,
    /// The side-by-side variants on smaller packings (the cost chart's ladder).
    ladder: Vec<SideBySide>,
    cts: Calibrations,
    /// Inclusion share of the solid by centre, with the laminate rule, and the bulk estimate.
    f_centre: f64,
    f_laminate: f64,
    f_bulk: f64,
    /// Particles cut by the interface (laminate rule).
    cut_particles: usize,
    /// Packing, contacts and phases (s).
    build_s: f64,
    /// Σ V_cells / V − 1 of the Laguerre tessellation (first packing).
    volume_error: f64,
}

impl Measured {
    /// The FEM ratio at a contrast of the reference.
    fn fem_of(&self, c: f64) -> f64 {
        self.fem
            .iter()
            .find(|r| r.contrast == c)
            .map(|r| r.ratio)
            .unwrap_or(f64::NAN)
    }

    /// The headline model's sweep on the first packing.
    fn headline(&self) -> &Sweep {
        &self.sweeps[0]
    }

    /// A variant's sweep on the first packing.
    fn sweep(&self, v: Variant) -> &Sweep {
        self.sweeps
            .iter()
            .find(|s| s.v == v)
            .expect("every variant runs on the first packing")
    }

    /// Largest relative error of a sweep's λ_e/λ_hom against the FEM.
    fn err_fem(&self, sw: &Sweep) -> f64 {
        sw.max_err(|r| r.normalised, &|c| self.fem_of(c))
    }

    /// A side-by-side variant's error over every packing at the case's N.
    fn spread(&self, v: Variant) -> Spread {
        Spread::of(
            std::iter::once(self.sweep(v))
                .chain(
                    self.repeats
                        .iter()
                        .flat_map(|r| r.sweeps.iter().filter(move |s| s.v == v)),
                )
                .map(|sw| self.err_fem(sw)),
        )
    }

    /// A side-by-side variant's cost (s) over every packing at the case's N.
    fn cost(&self, v: Variant) -> Spread {
        Spread::of(
            std::iter::once(self.sweep(v))
                .chain(
                    self.repeats
                        .iter()
                        .flat_map(|r| r.sweeps.iter().filter(move |s| s.v == v)),
                )
                .map(|sw| sw.cost_s),
        )
    }

    /// The a-priori tolerance of the contact models (and of the Laguerre headline in `--quick`).
    fn tolerance(&self) -> f64 {
        scaled_tolerance(0.0065, 150_000.0, self.n)
    }

    /// The Laguerre target (0.3 % at 1.5·10⁵) scaled the same way to this N.
    fn laguerre_target(&self) -> f64 {
        scaled_tolerance(0.003, 150_000.0, self.n)
    }
}

/// Maxwell's λ_e/λ_m at the nominal inclusion fraction.
fn maxwell_nominal(c: f64) -> f64 {
    maxwell(1.0, c, F_SINGLE)
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let m = measure(ctx)?;
    let mut out = CaseOutcome::new("inclusion-etc", ctx.mode);
    out.n_particles = m.n;
    compare(ctx, &m, &mut out);
    report(ctx, &m, &mut out)?;
    Ok(out)
}

/// The FEM reference points, sorted by contrast.
fn fem_reference() -> anyhow::Result<Vec<FemPoint>> {
    let fem = crate::refs::single_inclusion_fem();
    let table = fem["etc_vs_contrast"]
        .as_object()
        .ok_or_else(|| anyhow::anyhow!("single-inclusion-fem.json: no etc_vs_contrast"))?;
    let mut refs: Vec<FemPoint> = table
        .iter()
        .map(|(k, v)| {
            Ok(FemPoint {
                contrast: k.parse::<f64>()?,
                ratio: v["fem_lambda_eff_over_lambda_m"]
                    .as_f64()
                    .ok_or_else(|| anyhow::anyhow!("no FEM value for contrast {k}"))?,
            })
        })
        .collect::<anyhow::Result<_>>()?;
    refs.sort_by(|a, b| a.contrast.total_cmp(&b.contrast));
    Ok(refs)
}

/// One variant's sweep over the contrasts of `fem` on its model of `set`.
fn sweep(
    v: Variant,
    base: &SceneConfig,
    set: &ModelSet,
    cts: &Calibrations,
    fem: &[FemPoint],
) -> anyhow::Result<Sweep> {
    let t1 = Instant::now();
    let model = set.get(&v);
    let cfg = v.calibrated_scene(base, cts);
    let hom = etc_of(&cfg, with_conductivities(model, &[LAMBDA_M, LAMBDA_M]))?;
    let mut sw = Sweep {
        v,
        lambda_hom: hom.lambda_e,
        ratios: Vec::new(),
        iterations: hom.iterations,
        solve_s: hom.solve_s,
        wall_s: 0.0,
        cost_s: 0.0,
    };
    for point in fem {
        let c = point.contrast;
        let e = etc_of(&cfg, with_conductivities(model, &[LAMBDA_M, LAMBDA_M * c]))?;
        sw.ratios.push(Ratio {
            contrast: c,
            normalised: e.lambda_e / hom.lambda_e,
            raw: e.lambda_e / LAMBDA_M,
        });
        sw.iterations += e.iterations;
        sw.solve_s += e.solve_s;
    }
    sw.wall_s = t1.elapsed().as_secs_f64();
    sw.cost_s = sw.wall_s + network_s(model) + cts.cost_s(&v);
    Ok(sw)
}

/// A packing of `n` particles with the side-by-side variants.
fn side_by_side(n: usize, seed: u64, fem: &[FemPoint]) -> anyhow::Result<SideBySide> {
    let base = scene(n, seed, 1.0);
    let (model, build_s) = model_of_timed(&base)?;
    let set = ModelSet::new(&base, &model, &[(centred_sphere(), 1)])?;
    let cts = Calibrations::of(&model)?;
    let sweeps = Variant::side_by_side()
        .into_iter()
        .map(|v| sweep(v, &base, &set, &cts, fem))
        .collect::<anyhow::Result<_>>()?;
    Ok(SideBySide {
        n: model.particles.len(),
        build_s,
        sweeps,
    })
}

/// The first packing with every variant, two more with the side-by-side ones, and the ladder.
fn measure(ctx: &Ctx) -> anyhow::Result<Measured> {
    let n = ctx.pick(20_000, 150_000);
    let ladder_sizes = ctx.pick(vec![5_000, 10_000], vec![20_000, 50_000]);
    let fem = fem_reference()?;
    let base = scene(n, ctx.seed, 1.0);
    let (centre_model, build_s) = model_of_timed(&base)?;
    let set = ModelSet::new(&base, &centre_model, &[(centred_sphere(), 1)])?;
    let laminate_model = set.by_rule(Surface::Terreros).get(PhaseRuleConfig::Laminate);
    let cts = Calibrations::of(&centre_model)?;
    let sweeps = Variant::with_laguerre()
        .into_iter()
        .map(|v| sweep(v, &base, &set, &cts, &fem))
        .collect::<anyhow::Result<Vec<_>>>()?;
    debug_assert_eq!(sweeps[0].v, Variant::HEADLINE);
    let repeats = (1..PACKINGS)
        .map(|k| side_by_side(n, ctx.seed + k, &fem))
        .collect::<anyhow::Result<_>>()?;
    let ladder = ladder_sizes
        .into_iter()
        .map(|nl| side_by_side(nl, ctx.seed, &fem))
        .collect::<anyhow::Result<_>>()?;
    Ok(Measured {
        fem,
        n: centre_model.particles.len(),
        phi: centre_model.phi,
        sweeps,
        repeats,
        ladder,
        cts,
        f_centre: phase_fraction(&centre_model, 1),
        f_laminate: phase_fraction(laminate_model, 1),
        // The sphere's share of the solid if the solid were uniform at the bulk φ: the walled
        // packing is looser in its wall layers, so the inner sphere holds more than 4π/81 of it.
        f_bulk: F_SINGLE * 0.64 / centre_model.phi,
        cut_particles: laminate_model.mixes.len(),
        build_s,
        volume_error: set
            .laguerre
            .report
            .tessellation
            .as_ref()
            .map_or(f64::NAN, |t| t.volume_error),
    })
}

/// Packings at the case's N (the first with every model, the others with the three side by side).
const PACKINGS: u64 = 3;

/// Metrics, references and the checks (the Laguerre headline and the recommended contact
/// model against the FEM).
fn compare(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) {
    let fem_of = |c: f64| m.fem_of(c);
    let maxwell_particles = |c: f64| maxwell(1.0, c, m.f_centre);
    let head = m.headline();
    let rec = m.sweep(Variant::RECOMMENDED);
    let e_head = m.spread(Variant::HEADLINE);
    out.metric("max_rel_error_vs_fem", e_head.max);
    out.metric("max_rel_error_vs_fem_headline", e_head.json());
    out.metric("headline_model", head.v.id());
    out.metric("recommended_model", rec.v.id());
    out.metric("max_rel_error_vs_fem_recommended", m.err_fem(rec));
    out.metric(
        "max_rel_error_vs_maxwell",
        head.max_err(|r| r.normalised, &maxwell_nominal),
    );
    out.metric(
        "max_rel_error_vs_maxwell_particle_fraction",
        head.max_err(|r| r.normalised, &maxwell_particles),
    );
    out.metric("max_rel_error_vs_fem_raw", head.max_err(|r| r.raw, &fem_of));
    let mut by_variant = Map::new();
    let mut cost_by_variant = Map::new();
    for sw in &m.sweeps {
        by_variant.insert(sw.v.id(), Value::from(m.err_fem(sw)));
        cost_by_variant.insert(sw.v.id(), Value::from(sw.cost_s));
        let ratios: Map<String, Value> = sw
            .ratios
            .iter()
            .map(|r| (format!("{}", r.contrast), Value::from(r.normalised)))
            .collect();
        out.metric(&format!("etc_ratio_{}", sw.v.id()), Value::Object(ratios));
        out.metric(
            &format!("lambda_hom_over_lambda_{}", sw.v.id()),
            sw.lambda_hom / LAMBDA_M,
        );
    }
    out.metric("max_rel_error_vs_fem_by_model", Value::Object(by_variant));
    out.metric("wall_s_by_model", Value::Object(cost_by_variant));
    let side: Map<String, Value> = Variant::side_by_side()
        .iter()
        .map(|&v| {
            (
                v.id(),
                serde_json::json!({ "error": m.spread(v).json(), "wall_s": m.cost(v).json() }),
            )
        })
        .collect();
    out.metric("side_by_side", Value::Object(side));
    out.metric("solve_s", m.sweeps.iter().map(|s| s.solve_s).sum::<f64>());
    out.metric(
        "cg_iterations",
        m.sweeps.iter().map(|s| s.iterations).sum::<u64>(),
    );
    out.metric("c_t_particles", m.cts.particles);
    out.metric("c_t_walls", m.cts.walls);
    out.metric("inclusion_particle_fraction", m.f_centre);
    out.metric("inclusion_fraction_laminate", m.f_laminate);
    out.metric("inclusion_fraction_bulk_estimate", m.f_bulk);
    out.metric("cut_particles", m.cut_particles);
    out.metric("build_s", m.build_s);
    out.metric("phi", m.phi);
    out.metric("laguerre_volume_error", m.volume_error);
    out.reference("max_rel_error_vs_fem", 0.0065);
    out.reference(
        "source",
        "Haddad 2021 §4.1 Fig. 14 (1.5·10⁵ DE, 0.65 %); FEM: shared/refs/single-inclusion-fem.json; Laguerre \
         target 0.3 % (issue 10)",
    );
    let (tol_head, why) = match ctx.mode {
        crate::Mode::Full => (
            FULL_TARGET,
            "issue 32's target for the cells that follow the surfaces, 0.2 % at every contrast at 1.5·10⁵",
        ),
        crate::Mode::Quick => (
            m.tolerance(),
            "quick: the a-priori 0.65 % × (1.5·10⁵/N)^(1/3) (the paper's error at 1.5·10⁵ scaled by N^(-1/3))",
        ),
    };
    out.compare(Comparison::at_most(
        &format!(
            "max |λ_e/λ_hom − FEM|/FEM over the contrasts, largest of {} packings ({}, the headline)",
            e_head.count,
            head.v.id()
        ),
        e_head.max,
        tol_head,
        why,
    ));
    out.compare(Comparison::at_most(
        &format!(
            "max |λ_e/λ_hom − FEM|/FEM over the contrasts, first packing ({}, the recommended contact model)",
            rec.v.id()
        ),
        m.err_fem(rec),
        m.tolerance(),
        "paper 0.65 % at 1.5·10⁵ DE",
    ));
}

/// A line of the contrast table: one contrast of the reference with every model's error, or
/// one of the summary lines.
enum ContrastLine {
    /// The i-th contrast.
    Contrast(usize),
    /// Largest error per model.
    MaxErr,
    /// λ_hom/λ and solve time per model.
    Cost,
    /// The model's own wall time: network, calibration, solves.
    Wall,
}

/// A line of the side-by-side table.
struct SideLine {
    v: Variant,
    error: Spread,
    cost: Spread,
}

/// The tables, the charts and the notes.
fn report(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    out.tables.push(contrast_table(m));
    out.tables.push(side_table(m));
    etc_chart(ctx, m, out)?;
    cost_chart(ctx, m, out)?;
    run_notes(ctx, m, out);
    Ok(())
}

/// λ_e/λ_hom against the contrast: FEM, Maxwell and every model's error, first packing.
fn contrast_table(m: &Measured) -> Table {
    let head = m.headline();
    let contrast = |i: usize| head.ratios[i].contrast;
    let blank_unless = |line: &ContrastLine, label: &str, cell: &dyn Fn(usize) -> String| match line {
        ContrastLine::Contrast(i) => cell(*i),
        _ => label.to_string(),
    };
    let lines: Vec<ContrastLine> = (0..head.ratios.len())
        .map(ContrastLine::Contrast)
        .chain([ContrastLine::MaxErr, ContrastLine::Cost, ContrastLine::Wall])
        .collect();
    Columns::new()
        .column("λ_i/λ_m", |l: &ContrastLine| match l {
            ContrastLine::Contrast(i) => format!("{}", contrast(*i)),
            ContrastLine::MaxErr => "max |err|".into(),
            ContrastLine::Cost => "λ_hom/λ; solves (s)".into(),
            ContrastLine::Wall => "wall time (s)".into(),
        })
        .column("FEM", |l| {
            blank_unless(l, "", &|i| format!("{:.5}", m.fem_of(contrast(i))))
        })
        .column("Maxwell", |l| {
            blank_unless(l, "", &|i| format!("{:.5}", maxwell_nominal(contrast(i))))
        })
        .column("headline λ_e/λ_hom", |l| {
            blank_unless(l, "", &|i| format!("{:.5}", head.ratios[i].normalised))
        })
        .columns_for(
            m.sweeps.iter(),
            |sw| sw.v.id(),
            |sw, l| match l {
                ContrastLine::Contrast(i) => {
                    let f = m.fem_of(contrast(*i));
                    format!("{:+.2} %", 100.0 * (sw.ratios[*i].normalised - f) / f)
                }
                ContrastLine::MaxErr => format!("{:.2} %", 100.0 * m.err_fem(sw)),
                ContrastLine::Cost => format!("{:.4}; {:.2}", sw.lambda_hom / LAMBDA_M, sw.solve_s),
                ContrastLine::Wall => format!("{:.2}", sw.cost_s),
            },
        )
        .table(
            format!(
                "λ_e/λ_hom against the contrast, N = {}, first packing: FEM, Maxwell, and the relative error of each model \
                 (surface-boundary-phase rule; the first is the headline)",
                m.n,
            ),
            &lines,
        )
}

/// The three surface models side by side over every packing: error and cost.
fn side_table(m: &Measured) -> Table {
    let side: Vec<SideLine> = Variant::side_by_side()
        .into_iter()
        .map(|v| SideLine {
            v,
            error: m.spread(v),
            cost: m.cost(v),
        })
        .collect();
    Columns::new()
        .column("model", |l: &SideLine| l.v.id())
        .column("packings", |l| l.error.count.to_string())
        .column("max error over the contrasts, mean / max", |l| l.error.percent())
        .column("wall time (s), mean / max", |l| {
            format!("{:.2} / {:.2}", l.cost.mean, l.cost.max)
        })
        .table(
            format!(
                "The three surface models side by side (walls, segment rule), N = {}: error against the FEM and \
                 cost (network + calibration + solves) over every packing",
                m.n
            ),
            &side,
        )
}

/// λ_e/λ_m against the contrast (Fig. 14): the headline, the recommended and the former
/// headline model, FEM and Maxwell.
fn etc_chart(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    let head = m.headline();
    let rec = m.sweep(Variant::RECOMMENDED);
    let maxwell_curve: Vec<(f64, f64)> = (0..=40)
        .map(|i| {
            let c = 10f64.powf(-2.0 + 4.0 * i as f64 / 40.0);
            (c, maxwell_nominal(c))
        })
        .collect();
    let curve = |sw: &Sweep| sw.ratios.iter().map(|r| (r.contrast, r.normalised)).collect();
    let former = m.sweep(Variant::all()[1]);
    draw(
        &Chart {
            title: format!(
                "Single inclusion: λ_e/λ_m against contrast, N = {} (Haddad 2021 Fig. 14)",
                m.n
            ),
            x_label: "contrast λ_i/λ_m".into(),
            y_label: "λ_e/λ_m".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
            series: vec![
                Series::line(&format!("DEM {} (headline)", head.v.id()), curve(head)),
                Series::line(
                    &format!("DEM {} (recommended contact model)", rec.v.id()),
                    curve(rec),
                ),
                Series::line(&format!("DEM {}", former.v.id()), curve(former)),
                Series::markers("FEM", m.fem.iter().map(|p| (p.contrast, p.ratio)).collect()),
                Series::line("Maxwell", maxwell_curve),
            ],
        },
        &ctx.out.join("inclusion-etc.png"),
    )?;
    out.charts.push("inclusion-etc.png".into());
    Ok(())
}

/// Accuracy against cost: the ladder and the first packing, one curve per surface model.
fn cost_chart(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    let series: Vec<Series> = Variant::side_by_side()
        .iter()
        .map(|&v| {
            let pts = m
                .ladder
                .iter()
                .flat_map(|r| r.sweeps.iter())
                .chain(std::iter::once(m.sweep(v)))
                .filter(|sw| sw.v == v)
                .map(|sw| (sw.cost_s, 100.0 * m.err_fem(sw)))
                .collect();
            Series::line(&format!("{} ({})", v.surface.label(), v.id()), pts)
        })
        .collect();
    let ladder_n: Vec<usize> = m.ladder.iter().map(|r| r.n).chain([m.n]).collect();
    draw(
        &Chart {
            title: format!("Single inclusion: max error vs FEM against wall time, N = {ladder_n:?}"),
            x_label: "wall time (s): network + calibration + 9 steady solves".into(),
            y_label: "max |λ_e/λ_hom − FEM|/FEM over 8 contrasts (%)".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            series,
        },
        &ctx.out.join("inclusion-etc-cost.png"),
    )?;
    out.charts.push("inclusion-etc-cost.png".into());
    Ok(())
}

/// The notes that carry this run's figures, and the pointer to the case's notes file.
fn run_notes(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) {
    let head = m.headline();
    let rec = m.sweep(Variant::RECOMMENDED);
    out.note(format!(
        "{} mode: {} particles; the first packing runs {} contrasts × {} models (surface × boundary × phase rule), each a \
         steady solve ({} iterations, {:.2} s of solves in all, {:.1} s for the headline's sweep); the three surface models \
         with walls and the segment rule also run on {} more packings (seeds {}…{}) and on N = {:?} (seed {}) for the cost \
         chart. λ_hom of the headline: {:.6}·λ. C_t (calibrated model, our own calibration): {:.4} with particle-fixed \
         faces, {:.4} with walls. The Laguerre cells tile the cube (Σ V_cells/V − 1 = {:.1e}).",
        ctx.mode.name(),
        m.n,
        m.fem.len(),
        m.sweeps.len(),
        m.sweeps.iter().map(|s| s.iterations).sum::<u64>(),
        m.sweeps.iter().map(|s| s.solve_s).sum::<f64>(),
        head.wall_s,
        PACKINGS - 1,
        ctx.seed + 1,
        ctx.seed + PACKINGS - 1,
        m.ladder.iter().map(|r| r.n).collect::<Vec<_>>(),
        ctx.seed,
        head.lambda_hom / LAMBDA_M,
        m.cts.particles,
        m.cts.walls,
        m.volume_error,
    ));
    out.note(format!(
        "Headline {}, recommended contact model {}. Method, reference and tolerances: validation/notes/inclusion-etc.md.",
        head.v.id(),
        rec.v.id()
    ));
    out.note(format!(
        "Inclusion volume carried: {:.4} of the solid by centre, {:.4} with the laminate rule ({} cut particles), against \
         the nominal 4π/81 = {F_SINGLE:.4}; overall φ = {:.4} (≈ 0.64 in the bulk), so the inner sphere holds ≈ {:.4} \
         of the solid.",
        m.f_centre, m.f_laminate, m.cut_particles, m.phi, m.f_bulk
    ));
    out.note(format!(
        "Tolerance at N = {}: {:.2} % (the paper's 0.65 % × (1.5·10⁵/N)^(1/3)). Issue 10's 0.3 % scaled to this N, \
         {:.2} %, is reported, not gated: the headline is {} it.",
        m.n,
        100.0 * m.tolerance(),
        100.0 * m.laguerre_target(),
        if m.spread(Variant::HEADLINE).max <= m.laguerre_target() {
            "within"
        } else {
            "outside"
        }
    ));
    for r in m.repeats.iter().chain(&m.ladder) {
        out.note(format!(
            "Packing of {} particles (side-by-side models): packing and contacts {:.1} s; errors {}.",
            r.n,
            r.build_s,
            r.sweeps
                .iter()
                .map(|sw| format!(
                    "{} {:.2} % ({:.2} s)",
                    sw.v.id(),
                    100.0 * m.err_fem(sw),
                    sw.cost_s
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
}
