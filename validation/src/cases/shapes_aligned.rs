//! `shapes-aligned` — ours (issue 34): periodic cells of aligned spheroids, prolate (fibres,
//! a/b = 3, 5, 20) and oblate (platelets, a/b = 1/3, 1/10), f = 0.10–0.20, contrasts 10 and
//! 0.1, the diagonal of the effective tensor against a voxel FFT reference on the identical
//! microstructure. `--quick` runs a/b = 3 and 1/3; `--full` all five.
//!
//! Microstructures: three per shape, spheroids along z with a gap ≥ 0.02 L (ten of a/b = 3 and
//! 1/3 at f = 0.15; 30 of a/b = 5 at f = 0.20 and of 1/10 at f = 0.10; 354 of a/b = 20 at
//! f = 0.10), placed once by `demcon_packing::place_shapes` (random sequential addition, seeds
//! 1–3) and stored in `validation/data/shapes-fft.json`, so the case reads them and does not
//! depend on the generator. Each microstructure gets its own packing (seed `ctx.seed + k`).
//!
//! Reference: `scripts/voxel_fft/voxel_fft.py` (ours, independent of the network code:
//! Fourier–Galerkin CG on laminate composite voxels at 65³, 99³ and 125³, extrapolated to zero
//! voxel size; its `recommended` value and error, stored per entry in the data file).
//!
//! Models: the Laguerre cells following the spheroids (conforming cells, the default with
//! shapes and the headline), and cut by their level set under the `Segment`, `Laminate` and
//! `Centre` rules.
//! Conforming cells (added later; bounds set just before their first run in this case, after
//! `shapes-dilute` had shown them within 2 % of the exact dilute increment at 2·10⁴): largest
//! error ≤ 2 % at 2·10⁴, ≤ 0.5 % (the target) at the largest N of `--full`, over
//! every shape but a/b = 20 (reported).
//! Segment-rule tolerances, chosen before any run of this case: at 2·10⁴ (quick) its largest
//! error ≤ 5 % (the segment rule's error on spheres is −0.3 … −2.2 %, and a spheroid here is 3
//! to 6 particles thick); at the largest N of `--full` ≤ 2.5 %, and its mean error below the
//! mean at 2·10⁴. The target, ≤ 0.5 % at 2·10⁵, is reported beside. The three later
//! shapes (tolerances also chosen before their first run): every shape's mean error must fall
//! from 2·10⁴ to 2·10⁵; a/b = 5 (8 site spacings across at 2·10⁵) and 1/10 (2.3 across) ≤ 5 %;
//! a/b = 20 (1.75 across: under-resolved at 2·10⁵) is reported. Figures and notes:
//! `validation/notes/shapes-aligned.md`.

use demcon_scene::config::*;
use serde_json::Value;

use super::common::*;
use super::study::Study;
use crate::table::Columns;
use crate::{CaseOutcome, Comparison, Ctx};

/// The cell edge (m): the reference's unit cell.
const CELL: f64 = 1.0;
/// Matrix conductivity (W/(m·K)).
const LAMBDA_M: f64 = 1.0;
/// Contrasts λ_i/λ_m.
const CONTRASTS: [f64; 2] = [10.0, 0.1];
/// Shapes: the data file's microstructure prefix, its label, and whether `--quick` runs it
/// (the others run in `--full`).
const SHAPES: [(&str, &str, bool); 5] = [
    ("prolate", "prolate a/b = 3, f = 0.15", true),
    ("oblate", "oblate a/b = 1/3, f = 0.15", true),
    ("prolate5", "prolate a/b = 5, f = 0.20", false),
    ("oblate01", "oblate a/b = 1/10, f = 0.10", false),
    ("prolate20", "prolate a/b = 20, f = 0.10", false),
];
/// Microstructures (and packings) per shape.
const PACKINGS: u64 = 3;
/// Phase rules: the headline first.
const RULES: [(&str, PhaseRuleConfig); 4] = [
    ("segment", PhaseRuleConfig::Segment),
    ("laminate", PhaseRuleConfig::Laminate),
    ("centre", PhaseRuleConfig::Centre),
    ("conforming", PhaseRuleConfig::Conforming),
];
/// The headline's largest error at 2·10⁴ (`--quick`) and at the largest N of `--full`.
const BOUNDS: [f64; 2] = [0.05, 0.025];
/// The target at 2·10⁵.
const TARGET: f64 = 0.005;
/// Conforming cells' largest error at 2·10⁴ (`--quick`) and at the largest N of `--full`.
const CONFORMING_BOUNDS: [f64; 2] = [0.02, 0.005];
/// The largest error at the largest N of `--full` for a/b = 5 and 1/10.
const LATER_BOUND: f64 = 0.05;

/// One microstructure of the data file.
struct Micro {
    shapes: Vec<ShapeConfig>,
    /// Reference diagonal (W/(m·K)) and its error, by contrast.
    refs: Vec<(f64, [f64; 3], [f64; 3])>,
}

fn micro(data: &Value, id: &str) -> anyhow::Result<Micro> {
    let m = data["microstructures"]
        .as_array()
        .into_iter()
        .flatten()
        .find(|m| m["id"] == id)
        .ok_or_else(|| anyhow::anyhow!("shapes-fft.json: no microstructure {id}"))?;
    let v3 = |v: &Value| -> anyhow::Result<(f64, f64, f64)> {
        let x = |k: usize| {
            v[k].as_f64()
                .ok_or_else(|| anyhow::anyhow!("shapes-fft.json: bad vector"))
        };
        Ok((x(0)?, x(1)?, x(2)?))
    };
    let num = |v: &Value| {
        v.as_f64()
            .ok_or_else(|| anyhow::anyhow!("shapes-fft.json: bad number"))
    };
    let shapes = m["shapes"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|s| {
            Ok(ShapeConfig::Spheroid {
                centre: v3(&s["centre"])?,
                axis: v3(&s["axis"])?,
                a: num(&s["a"])?,
                b: num(&s["b"])?,
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let refs = data["references"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|r| r["microstructure"] == id)
        .map(|r| {
            let d = v3(&r["diagonal"])?;
            let e = v3(&r["error"])?;
            Ok((num(&r["contrast"])?, [d.0, d.1, d.2], [e.0, e.1, e.2]))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok(Micro { shapes, refs })
}

fn scene(n: usize, seed: u64, shapes: &[ShapeConfig], contrast: f64, rule: PhaseRuleConfig) -> SceneConfig {
    shapes_scene(
        "shapes-aligned",
        seed,
        TwoPhaseCell {
            edge: CELL,
            count: n,
            lambda_m: LAMBDA_M,
            contrast,
        },
        shapes.to_vec(),
        rule,
    )
}

/// One (shape, contrast, rule) on one packing: the signed relative error of each diagonal
/// entry, and the reference's own relative error.
struct Row {
    shape: &'static str,
    contrast: f64,
    rule: usize,
    errors: [f64; 3],
    ref_error: f64,
    particles: usize,
}

fn measure(data: &Value, shapes: &[&'static str], n: usize, seed: u64, k: u64) -> anyhow::Result<Vec<Row>> {
    let mut rows = Vec::new();
    for &shape in shapes {
        let m = micro(data, &format!("{shape}-{}", k + 1))?;
        for contrast in CONTRASTS {
            let (_, diag, err) = m
                .refs
                .iter()
                .find(|r| (r.0 - contrast).abs() < 1e-12)
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "shapes-fft.json: no reference for {shape}-{} at {contrast}",
                        k + 1
                    )
                })?;
            for (rule, (_, phase_rule)) in RULES.iter().enumerate() {
                let cfg = scene(n, seed, &m.shapes, contrast, *phase_rule);
                let model = model_of(&cfg)?;
                let t = thermal_tensor(&cfg, &model)?;
                rows.push(Row {
                    shape,
                    contrast,
                    rule,
                    errors: [0, 1, 2].map(|i| t[i][i] / diag[i] - 1.0),
                    ref_error: (0..3).map(|i| err[i] / diag[i]).fold(0.0, f64::max),
                    particles: model.particles.len(),
                });
            }
        }
    }
    Ok(rows)
}

/// |error| over the packings and axes of one (size, rule) and the shapes `pick` keeps,
/// optionally one contrast.
fn spread_of(
    study: &Study<Vec<Row>>,
    n: usize,
    rule: usize,
    pick: impl Fn(&str) -> bool,
    contrast: Option<f64>,
) -> Spread {
    Spread::of(
        study
            .at(n)
            .flatten()
            .filter(|r| r.rule == rule && pick(r.shape) && contrast.is_none_or(|c| r.contrast == c))
            .flat_map(|r| r.errors.map(f64::abs)),
    )
}

/// |error| over the packings and axes of one (size, rule), optionally one (shape, contrast).
fn spread(study: &Study<Vec<Row>>, n: usize, rule: usize, only: Option<(&str, f64)>) -> Spread {
    match only {
        Some((shape, c)) => spread_of(study, n, rule, |s| s == shape, Some(c)),
        None => spread_of(study, n, rule, |_| true, None),
    }
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let data: Value = serde_json::from_str(include_str!("../../data/shapes-fft.json"))?;
    let sizes = ctx.pick(vec![20_000], vec![20_000, 60_000, 200_000]);
    let shapes: Vec<&str> = SHAPES
        .iter()
        .filter(|s| s.2 || ctx.mode == crate::Mode::Full)
        .map(|s| s.0)
        .collect();
    let study = Study::run(
        &sizes,
        |_| PACKINGS,
        ctx.seed,
        |n, seed, k| measure(&data, &shapes, n, seed, k),
    )?;
    let mut out = CaseOutcome::new("shapes-aligned", ctx.mode);
    out.n_particles = study
        .packings()
        .iter()
        .flat_map(|p| p.rows.iter().map(|r| r.particles))
        .max()
        .unwrap_or(0);
    let (small, large) = (sizes[0], study.largest());
    for &n in study.sizes() {
        for (rule, (name, _)) in RULES.iter().enumerate() {
            let s = spread(&study, n, rule, None);
            out.metric(&format!("{name}_{n}_mean_abs_rel_error"), s.mean);
            out.metric(&format!("{name}_{n}_max_abs_rel_error"), s.max);
        }
    }
    // Conforming cells, the default with shapes: ≤ 2 % at 2·10⁴, the 0.5 % at the
    // largest N of --full, every shape.
    // a/b = 20 (fibres under two site spacings across at 2·10⁵) is reported only.
    let resolved = |s: &str| s != "prolate20";
    let conforming = spread_of(&study, large, 3, resolved, None);
    out.compare(Comparison::at_most(
        &format!(
            "conforming cells, N = {large}: max |λ_ii/λ_ref − 1| ({} shapes × 2 contrasts × 3 packings × 3 axes)",
            shapes.iter().filter(|s| resolved(s)).count()
        ),
        conforming.max,
        ctx.pick(CONFORMING_BOUNDS[0], CONFORMING_BOUNDS[1]),
        "voxel FFT, composite voxels extrapolated (validation/data/shapes-fft.json); tolerance in the module notes",
    ));
    // The segment rule on the first two shapes (a/b = 3, 1/3): gated since their first run.
    let first = |s: &str| SHAPES.iter().any(|x| x.0 == s && x.2);
    let head = spread_of(&study, large, 0, first, None);
    out.compare(Comparison::at_most(
        &format!("segment rule, N = {large}: max |λ_ii/λ_ref − 1| (a/b = 3, 1/3 × 2 contrasts × 3 packings × 3 axes)"),
        head.max,
        ctx.pick(BOUNDS[0], BOUNDS[1]),
        "voxel FFT, composite voxels extrapolated (validation/data/shapes-fft.json); tolerance in the module notes",
    ));
    if large != small {
        for &shape in &shapes {
            let one = |s: &str| s == shape;
            out.compare(Comparison::at_most(
                &format!("segment rule, {shape}: mean error at N = {large} over the mean at N = {small}"),
                spread_of(&study, large, 0, one, None).mean / spread_of(&study, small, 0, one, None).mean,
                1.0,
                "convergence: more particles must buy accuracy",
            ));
        }
        // a/b = 5 and 1/10: thickness 8 and 2.3 site spacings at 2·10⁵.
        let later = |s: &str| s == "prolate5" || s == "oblate01";
        out.compare(Comparison::at_most(
            &format!("segment rule, N = {large}: max |λ_ii/λ_ref − 1| (a/b = 5, 1/10)"),
            spread_of(&study, large, 0, later, None).max,
            LATER_BOUND,
            "voxel FFT, composite voxels extrapolated; tolerance in the module notes",
        ));
    }
    out.metric("issue_target_at_2e5", TARGET);
    out.reference(
        "fft",
        "scripts/voxel_fft/voxel_fft.py, laminate composite voxels at 65³, 99³, 125³, extrapolated",
    );
    report(ctx, &study, &shapes, &mut out);
    Ok(out)
}

fn report(ctx: &Ctx, study: &Study<Vec<Row>>, shapes: &[&'static str], out: &mut CaseOutcome) {
    type Line = (usize, &'static str, f64);
    let mut lines: Vec<Line> = Vec::new();
    for &n in study.sizes() {
        for &shape in shapes {
            for c in CONTRASTS {
                lines.push((n, shape, c));
            }
        }
    }
    let mut cols = Columns::new()
        .column("N", |l: &Line| l.0.to_string())
        .column("spheroids", |l: &Line| {
            SHAPES
                .iter()
                .find(|s| s.0 == l.1)
                .map_or(l.1, |s| s.1)
                .to_string()
        })
        .column("contrast", |l: &Line| format!("{}", l.2))
        .column("reference error", |l: &Line| {
            let e = study
                .at(l.0)
                .flatten()
                .filter(|r| r.shape == l.1 && r.contrast == l.2)
                .map(|r| r.ref_error)
                .fold(0.0, f64::max);
            format!("{:.3} %", 100.0 * e)
        });
    for (rule, (name, _)) in RULES.iter().enumerate() {
        cols = cols.column(*name, move |l: &Line| {
            let s = spread(study, l.0, rule, Some((l.1, l.2)));
            let bias = Spread::of(
                study
                    .at(l.0)
                    .flatten()
                    .filter(|r| r.rule == rule && r.shape == l.1 && r.contrast == l.2)
                    .flat_map(|r| r.errors),
            )
            .mean;
            format!("{:+.2} % / {:.2} %", 100.0 * bias, 100.0 * s.max)
        });
    }
    out.tables.push(cols.table(
        "Aligned spheroids: mean signed error / largest |error| of λ_xx, λ_yy, λ_zz over 3 packings",
        &lines,
    ));
    out.note(format!(
        "{} mode: per shape three microstructures of spheroids along z (validation/data/shapes-fft.json), one \
         periodic packing each (φ = 0.6, Gaussian radii CoV 0.3, seeds {}…{}), Laguerre cells, `Homogenize`. \
         Conforming cells (the default) are gated at {:.1} % (2·10⁴) and the issue's {:.1} % (largest N of \
         --full; a/b = 20 reported); the segment rule at {:.1} % (2·10⁴) and {:.1} % (largest N of --full), its \
         mean falling with N.",
        ctx.mode.name(),
        ctx.seed,
        ctx.seed + PACKINGS - 1,
        100.0 * CONFORMING_BOUNDS[0],
        100.0 * CONFORMING_BOUNDS[1],
        100.0 * BOUNDS[0],
        100.0 * BOUNDS[1],
    ));
}
