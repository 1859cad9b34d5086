//! Issue 32: periodic arrays of spheres (simple, body- and face-centred cubic), the effective
//! conductivity against an independent multipole solution
//! (`validation/data/sphere-arrays-multipole.json`, `scripts/sphere_array_multipole.py`,
//! `validation/notes/sphere-arrays.md`: Rayleigh / Sangani–Acrivos, Ewald lattice sums,
//! truncation error ≤ 1.6·10⁻¹⁰ relative).
//!
//! Each lattice's conventional cubic cell (1, 2 or 4 spheres) is one periodic packing,
//! homogenised (`thermal.solver: Homogenize`); λ_xx, λ_yy, λ_zz are each compared with the
//! reference (the tensor is isotropic for the three lattices), on three packings. Cases: each
//! lattice at f = 0.3 and nearly touching (SC 0.5, BCC 0.65, FCC 0.7; gaps 3–4 % of the
//! radius), contrast 10, SC f = 0.3 at contrast 0.1, and SC f = 0.3, contrast 10 with an interface
//! conductance h (h a/λ_m = 1 and 0.1; their tolerance, f = 0.3's, after seeing h a/λ_m = 1 on one
//! packing at 10⁴: −0.016 %), and the three nearly touching arrays with an interface (SC 0.5 and
//! BCC 0.65 at h a/λ_m = 1, FCC 0.7 at 10: the interface where the flux crowds between the
//! spheres; the nearly touching tolerance, added with it). Models: the Laguerre cells with the
//! phase by centre, the segment rule and the conforming seeds (issue 32's rule).
//!
//! Tolerance of the conforming rule, on the largest error over the three packings and three
//! axes: 0.3 % (f = 0.3) and 1 % (nearly touching) at the quick 2·10⁴ sites — the issue's
//! 2·10⁵ targets (0.1 % / 0.3 %) scaled as a surface error ∝ N^(-1/3) and rounded up; chosen
//! after seeing SC f = 0.3 and 0.5 at contrast 10 on one packing (−0.14 % and −0.55 % at 10⁴)
//! and before any other case. The first quick run missed the 1 % at FCC f = 0.7 (1.09 %; every
//! other case within its tolerance); once the narrowed pairs of both spheres fit in the gap
//! (docs/laguerre.md §4) the nearly touching arrays read 0.05–0.14 % and the a-priori 1 % is
//! gated again. `--full` gates the targets at 2·10⁵. Centre and segment are reported,
//! not gated.

use demcon_scene::config::*;
use serde_json::Value;

use super::common::*;
use crate::table::Columns;
use crate::{CaseOutcome, Comparison, Ctx};

/// Edge of the periodic cell (m).
const CELL: f64 = 0.01;

/// The quick gate on nearly touching arrays: the a-priori 1 % (missed at FCC f = 0.7, 1.09 %,
/// before both spheres' pairs fitted in the gap; 0.14 % since).
const NEARLY_TOUCHING_QUICK_BOUND: f64 = 0.01;

/// The conductivity of the matrix (W/(m·K)).
const LAMBDA_M: f64 = 1.0;

/// One array of the comparison.
struct Array {
    lattice: &'static str,
    f: f64,
    contrast: f64,
    /// Nearly touching (the looser tolerance).
    touching: bool,
    /// An interface conductance h, as h a / λ_m (`None`: perfect interface).
    interface: Option<f64>,
}

const ARRAYS: [Array; 12] = [
    Array {
        lattice: "sc",
        f: 0.3,
        contrast: 10.0,
        touching: false,
        interface: None,
    },
    Array {
        lattice: "sc",
        f: 0.5,
        contrast: 10.0,
        touching: true,
        interface: None,
    },
    Array {
        lattice: "bcc",
        f: 0.3,
        contrast: 10.0,
        touching: false,
        interface: None,
    },
    Array {
        lattice: "bcc",
        f: 0.65,
        contrast: 10.0,
        touching: true,
        interface: None,
    },
    Array {
        lattice: "fcc",
        f: 0.3,
        contrast: 10.0,
        touching: false,
        interface: None,
    },
    Array {
        lattice: "fcc",
        f: 0.7,
        contrast: 10.0,
        touching: true,
        interface: None,
    },
    Array {
        lattice: "sc",
        f: 0.3,
        contrast: 0.1,
        touching: false,
        interface: None,
    },
    Array {
        lattice: "sc",
        f: 0.3,
        contrast: 10.0,
        touching: false,
        interface: Some(1.0),
    },
    Array {
        lattice: "sc",
        f: 0.3,
        contrast: 10.0,
        touching: false,
        interface: Some(0.1),
    },
    Array {
        lattice: "sc",
        f: 0.5,
        contrast: 10.0,
        touching: true,
        interface: Some(1.0),
    },
    Array {
        lattice: "bcc",
        f: 0.65,
        contrast: 10.0,
        touching: true,
        interface: Some(1.0),
    },
    Array {
        lattice: "fcc",
        f: 0.7,
        contrast: 10.0,
        touching: true,
        interface: Some(10.0),
    },
];

/// The models compared, the gated one first.
const RULES: [(&str, PhaseRuleConfig); 3] = [
    ("laguerre-conforming", PhaseRuleConfig::Conforming),
    ("laguerre-centre", PhaseRuleConfig::Centre),
    ("laguerre-segment", PhaseRuleConfig::Segment),
];

/// The reference λ_e/λ_m and the cell side over the radius of one array.
fn reference(refs: &Value, a: &Array) -> anyhow::Result<(f64, f64)> {
    let table = if a.interface.is_some() {
        "interface_rows"
    } else {
        "rows"
    };
    refs[table]
        .as_array()
        .into_iter()
        .flatten()
        .find(|r| {
            r["lattice"] == a.lattice
                && (r["f"].as_f64().unwrap_or(-1.0) - a.f).abs() < 1e-12
                && (r["contrast"].as_f64().unwrap_or(-1.0) - a.contrast).abs() < 1e-12
                && match a.interface {
                    None => r["h_a_over_lambda_m"].is_null(),
                    Some(h) => (r["h_a_over_lambda_m"].as_f64().unwrap_or(-1.0) - h).abs() < 1e-12,
                }
        })
        .and_then(|r| {
            Some((
                r["lambda_e_over_lambda_m"].as_f64()?,
                r["cell_side_over_radius"].as_f64()?,
            ))
        })
        .ok_or_else(|| {
            anyhow::anyhow!(
                "sphere-arrays-multipole.json: no row for {} f = {} contrast {}",
                a.lattice,
                a.f,
                a.contrast
            )
        })
}

/// The sphere centres of a lattice's conventional cell (unit cell coordinates).
fn basis(lattice: &str) -> Vec<[f64; 3]> {
    match lattice {
        "sc" => vec![[0.5, 0.5, 0.5]],
        "bcc" => vec![[0.25, 0.25, 0.25], [0.75, 0.75, 0.75]],
        _ => vec![
            [0.25, 0.25, 0.25],
            [0.75, 0.75, 0.25],
            [0.75, 0.25, 0.75],
            [0.25, 0.75, 0.75],
        ],
    }
}

/// The homogenisation scene of one array under one phase rule.
fn scene(a: &Array, side_over_radius: f64, n: usize, seed: u64, rule: PhaseRuleConfig) -> SceneConfig {
    let mut s = thermal_scene(
        &format!("sphere-arrays-{}-{}-{}", a.lattice, a.f, a.contrast),
        seed,
        periodic_packing(CELL, n),
        vec![
            material("matrix", LAMBDA_M, 1000.0, 1000.0),
            material("spheres", LAMBDA_M * a.contrast, 1000.0, 1000.0),
        ],
        homogenize_thermal(),
    );
    s.surface = SurfaceConfig::Laguerre;
    s.phases = vec![PhaseConfig::Spheres {
        material: "spheres".into(),
        radius: CELL / side_over_radius,
        centres: basis(a.lattice)
            .iter()
            .map(|c| (c[0] * CELL, c[1] * CELL, c[2] * CELL))
            .collect(),
    }];
    s.phase_rule = Some(rule);
    if let Some(h) = a.interface {
        // h a / λ_m given: h = that × λ_m / a (W/(m²·K)).
        s.interfaces = vec![InterfaceResistanceConfig {
            between: ("matrix".into(), "spheres".into()),
            conductance: h * LAMBDA_M * side_over_radius / CELL,
            electric_resistance: None,
        }];
    }
    s.outputs = OutputsConfig::default();
    s
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let mut out = CaseOutcome::new("sphere-arrays", ctx.mode);
    let refs: Value = serde_json::from_str(include_str!("../../data/sphere-arrays-multipole.json"))?;
    let n = ctx.pick(20_000, 200_000);
    let seeds = 3u64;
    let mut rows = Vec::new();
    for a in &ARRAYS {
        let (lambda, side) = reference(&refs, a)?;
        // errors[model] over the packings and axes, signed.
        let mut errors = vec![Vec::new(); RULES.len()];
        for k in 0..seeds {
            for (m, (_, rule)) in RULES.iter().enumerate() {
                let cfg = scene(a, side, n, ctx.seed + k, *rule);
                let model = model_of(&cfg)?;
                // The packing's particles (the conforming seeds are sites, not particles).
                out.n_particles = out.n_particles.max(model.particles.len() - model.seeds);
                let r = run_with(&cfg, &model)?;
                let h = r
                    .homogenization
                    .as_ref()
                    .and_then(|h| h.thermal.as_ref())
                    .ok_or_else(|| anyhow::anyhow!("no thermal homogenisation"))?;
                errors[m].extend(h.report.axes.iter().map(|x| x / LAMBDA_M / lambda - 1.0));
            }
        }
        let id = match a.interface {
            None => format!("{}_f{}_c{}", a.lattice, a.f, a.contrast),
            Some(h) => format!("{}_f{}_c{}_ha{}", a.lattice, a.f, a.contrast, h),
        };
        for (m, (name, _)) in RULES.iter().enumerate() {
            let abs = Spread::of(errors[m].iter().map(|e| e.abs()));
            let bias = errors[m].iter().sum::<f64>() / errors[m].len() as f64;
            out.metric(&format!("{name}_{id}_max_abs_rel_error"), abs.max);
            out.metric(&format!("{name}_{id}_bias"), bias);
        }
        let conforming = Spread::of(errors[0].iter().map(|e| e.abs()));
        let tol = match (a.touching, ctx.pick(true, false)) {
            (false, true) => 0.003,
            (true, true) => NEARLY_TOUCHING_QUICK_BOUND,
            (false, false) => 0.001,
            (true, false) => 0.003,
        };
        out.compare(Comparison::at_most(
            &format!(
                "{} f = {} contrast {}{}: max |λ/λ_ref − 1| (conforming, 3 packings × 3 axes)",
                a.lattice,
                a.f,
                a.contrast,
                a.interface.map_or(String::new(), |h| format!(", h a/λ_m = {h}"))
            ),
            conforming.max,
            tol,
            "multipole (validation/data/sphere-arrays-multipole.json); tolerance in the case's notes",
        ));
        rows.push((a, lambda, errors));
    }
    type Row<'a> = (&'a Array, f64, Vec<Vec<f64>>);
    let cols = Columns::new()
        .column("lattice", |r: &Row<'_>| r.0.lattice.to_string())
        .column("f", |r: &Row<'_>| format!("{}", r.0.f))
        .column("contrast", |r: &Row<'_>| format!("{}", r.0.contrast))
        .column("h a/λ_m", |r: &Row<'_>| {
            r.0.interface.map_or("—".into(), |h| format!("{h}"))
        })
        .column("λ_e/λ_m (multipole)", |r: &Row<'_>| format!("{:.6}", r.1));
    let mut table = cols.table(
        format!("Sphere arrays at N = {n}: mean signed error / largest |error| over 3 packings × 3 axes"),
        &rows,
    );
    for (m, (name, _)) in RULES.iter().enumerate() {
        table.header.push((*name).into());
        for (row, r) in table.rows.iter_mut().zip(&rows) {
            let e = &r.2[m];
            let bias = e.iter().sum::<f64>() / e.len() as f64;
            let max = e.iter().fold(0.0f64, |x, v| x.max(v.abs()));
            row.push(format!("{:+.3} % / {:.3} %", 100.0 * bias, 100.0 * max));
        }
    }
    out.tables.push(table);
    out.note(format!(
        "One periodic packing per seed (φ = 0.6, Gaussian radii CoV 0.3, {n} particles before the conforming \
         seeds replace those next to the spheres), the lattice's conventional cubic cell, `thermal.solver: \
         Homogenize`; each diagonal entry of the tensor against the multipole value (its own error ≤ 1.6·10⁻¹⁰). \
         The conforming rule is gated (0.3 % at 2·10⁴, 0.1 % at 2·10⁵; nearly touching 0.3 % at 2·10⁵), chosen \
         after seeing two SC values on one packing; the a-priori 1 % for nearly touching arrays at 2·10⁴ was \
         missed at FCC f = 0.7 (1.09 %) on the first run, and is met since both spheres' narrowed pairs fit in \
         the gap (docs/laguerre.md §4). Centre and segment are reported, not gated."
    ));
    Ok(out)
}
