//! `grain-boundaries` — a boundary conductance h on every facet between the grains
//! (particles) of one material (issue 35), with Laguerre cells.
//!
//! - **Cubic lattice, exact**: 4 × 4 × 12 touching spheres of diameter d = 1 mm (cells are
//!   cubes), λ = 10 W/(m·K), held at the two end faces (`WallTemperature`): every one of the
//!   n − 1 = 11 facet layers adds 1/h in series, the wall facets none, so
//!   λ_e = n d / (n d/λ + (n − 1)/h). Tolerance 10⁻⁹ (round-off and the linear solver), over
//!   h d/λ = 0.1, 1, 10.
//! - **Random polycrystal, no exact reference** (we know of none for a Laguerre polycrystal
//!   with a boundary conductance; we say so): a periodic cell of 2·10⁴ (`--full`: 10⁵) grains,
//!   λ_e (mean of the tensor's diagonal) against B = h D/λ, D = (V/N)^(1/3) the mean grain
//!   size, over 3 packings, beside the "brick" estimate λ/(1 + 1/B) (each grain a cube of side D
//!   in series with one boundary) for orientation only. Checked: λ_e rises with h, and a
//!   log-normal spread of h (coefficient of variation 0.5) lowers λ_e (E[1/h] grows by 1.25).

use demcon_scene::config::*;

use super::common::*;
use super::study::Study;
use crate::table::Columns;
use crate::{CaseOutcome, Comparison, Ctx};

const LAMBDA: f64 = 10.0;
/// Lattice: 4 × 4 × NZ spheres of diameter D_LATTICE (m).
const NZ: usize = 12;
const D_LATTICE: f64 = 1e-3;
/// h d/λ on the lattice, and B = h D/λ on the polycrystal.
const LATTICE_B: [f64; 3] = [0.1, 1.0, 10.0];
const POLY_B: [f64; 5] = [0.1, 0.3, 1.0, 3.0, 10.0];
const SPREAD: f64 = 0.5;
const EXACT_TOL: f64 = 1e-9;

fn grain_boundary(h: f64, spread: Option<f64>) -> GrainBoundaryConfig {
    GrainBoundaryConfig {
        material: "ceramic".into(),
        conductance: h,
        electric_resistance: None,
        spread,
    }
}

/// λ_e of the lattice at h d/λ = `b` and the exact value.
fn lattice(ctx: &Ctx, b: f64) -> anyhow::Result<(f64, f64)> {
    let path = write_cubic_lattice(&ctx.out, "grain-boundaries", [4, 4, NZ], D_LATTICE)?;
    let h = b * LAMBDA / D_LATTICE;
    let mut s = thermal_scene(
        "grain-boundaries",
        ctx.seed,
        PackingConfig::File {
            path: path.to_string_lossy().into_owned(),
            container: None,
        },
        vec![material("ceramic", LAMBDA, 3900.0, 880.0)],
        ThermalConfig {
            initial_temperature: 0.0,
            bcs: vec![wall(FaceConfig::ZMin, 0.0), wall(FaceConfig::ZMax, 1.0)],
            sources: Vec::new(),
            solver: ThermalSolverConfig::Steady,
            checkpoint: None,
        },
    );
    s.surface = SurfaceConfig::Laguerre;
    s.grain_boundaries = vec![grain_boundary(h, None)];
    s.outputs.etc_axis = Some(AxisConfig::Z);
    let model = model_of(&s)?;
    let r = run_with(&s, &model)?;
    let got = r.etc.as_ref().ok_or_else(|| anyhow::anyhow!("no ETC"))?.lambda_e;
    let n = NZ as f64;
    let exact = n * D_LATTICE / (n * D_LATTICE / LAMBDA + (n - 1.0) / h);
    Ok((got, exact))
}

/// One polycrystal's λ_e/λ at each B (uniform h), and at B = 1 with the spread.
struct Poly {
    ratio: Vec<f64>,
    spread_at_1: f64,
    uniform_at_1: f64,
}

fn polycrystal(n: usize, seed: u64) -> anyhow::Result<Poly> {
    let edge = 1e-3;
    let d = edge / (n as f64).cbrt();
    let scene = |gb: Vec<GrainBoundaryConfig>| {
        let mut s = thermal_scene(
            "grain-boundaries",
            seed,
            periodic_packing(edge, n),
            vec![material("ceramic", LAMBDA, 3900.0, 880.0)],
            homogenize_thermal(),
        );
        s.surface = SurfaceConfig::Laguerre;
        s.grain_boundaries = gb;
        s
    };
    let model = model_of(&scene(Vec::new()))?;
    let mean_diag = |gb| -> anyhow::Result<f64> {
        let s = scene(gb);
        let m = with_scene_defects(&model, &s)?;
        let t = thermal_tensor(&s, &m)?;
        Ok((t[0][0] + t[1][1] + t[2][2]) / (3.0 * LAMBDA))
    };
    let ratio = POLY_B
        .iter()
        .map(|b| mean_diag(vec![grain_boundary(b * LAMBDA / d, None)]))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let spread_at_1 = mean_diag(vec![grain_boundary(LAMBDA / d, Some(SPREAD))])?;
    let uniform_at_1 = ratio[POLY_B.iter().position(|&b| b == 1.0).expect("B = 1 listed")];
    Ok(Poly {
        ratio,
        spread_at_1,
        uniform_at_1,
    })
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let mut out = CaseOutcome::new("grain-boundaries", ctx.mode);
    let mut worst = 0.0f64;
    let mut lines = Vec::new();
    for b in LATTICE_B {
        let (got, exact) = lattice(ctx, b)?;
        worst = worst.max((got / exact - 1.0).abs());
        lines.push((b, got, exact));
    }
    out.tables.push(
        Columns::new()
            .column("h d/λ", |l: &(f64, f64, f64)| format!("{}", l.0))
            .column("λ_e (W/(m·K))", |l| format!("{:.10}", l.1))
            .column("exact", |l| format!("{:.10}", l.2))
            .column("error", |l| format!("{:.1e}", (l.1 / l.2 - 1.0).abs()))
            .table(
                format!("Cubic lattice 4 × 4 × {NZ}, Laguerre cells (cubes), h on every facet between cells"),
                &lines,
            ),
    );
    out.compare(Comparison::at_most(
        "cubic lattice, |λ_e/exact − 1| over h d/λ = 0.1, 1, 10",
        worst,
        EXACT_TOL,
        "exact: n d / (n d/λ + (n − 1)/h)",
    ));
    let n = ctx.pick(20_000, 100_000);
    let study = Study::run(&[n], |_| 3, ctx.seed, |n, seed, _| polycrystal(n, seed))?;
    out.n_particles = n.max(16 * NZ);
    let rows: Vec<(usize, f64)> = POLY_B.iter().copied().enumerate().collect();
    out.tables.push(
        Columns::new()
            .column("B = h D/λ", |(_, b): &(usize, f64)| format!("{b}"))
            .column("λ_e/λ, mean / max over 3 packings", |(i, _)| {
                let s = study.spread(n, |p| p.ratio[*i]);
                format!("{:.4} / {:.4}", s.mean, s.max)
            })
            .column("brick estimate 1/(1 + 1/B) (orientation only)", |(_, b)| {
                format!("{:.4}", 1.0 / (1.0 + 1.0 / b))
            })
            .table(
                format!("Random Laguerre polycrystal, {n} grains, periodic; no exact reference"),
                &rows,
            ),
    );
    let rising = study.rows().all(|p| p.ratio.windows(2).all(|w| w[1] > w[0]));
    out.compare(Comparison::at_most(
        "polycrystal: λ_e rises with h on every packing (1 = no)",
        if rising { 0.0 } else { 1.0 },
        0.0,
        "physics: a larger boundary conductance conducts better",
    ));
    let lowered = study.rows().all(|p| p.spread_at_1 < p.uniform_at_1);
    out.compare(Comparison::at_most(
        &format!("polycrystal: a spread of h (CoV {SPREAD}) lowers λ_e at B = 1 on every packing (1 = no)"),
        if lowered { 0.0 } else { 1.0 },
        0.0,
        "E[1/h] = (1 + CoV²)/h for a log-normal h of mean h",
    ));
    let s = study.spread(n, |p| p.spread_at_1 / p.uniform_at_1);
    out.metric("spread_over_uniform_at_b1_mean", s.mean);
    for (i, b) in POLY_B.iter().enumerate() {
        out.metric(
            &format!("polycrystal_ratio_b{b}"),
            study.spread(n, |p| p.ratio[i]).mean,
        );
    }
    Ok(out)
}
