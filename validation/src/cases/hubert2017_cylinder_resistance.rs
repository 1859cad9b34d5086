//! `cylinder-resistance` — Hubert et al. 2017 §3.1, Table 3 and Fig. 4: a cylinder r = 1 mm,
//! l = 5 mm of AISI 304L (ρ_e = 0.73e-6 Ω·m), a potential difference between the particles
//! touching its two end faces, N = 1000 … 20 000 particles, 3 packings per N. The equivalent
//! resistance ΔV / I is compared with the uniform-conductor value ρ_e l / A (1.16183 mΩ,
//! `analytic::uniform_resistance`).
//!
//! Compared quantity: the relative error |R − ρ_e l/A| / (ρ_e l/A), averaged over the 3
//! packings of each N (the paper's "absolute error"), for the three surface models on the same
//! packings: the Laguerre cells with the electrodes on the end faces (the cells' wall facets)
//! — `mean_rel_error` (and `max_rel_error`), the headline, chosen for the Laguerre network's
//! consistency property (a uniform field solves it exactly) before any of its numbers were
//! seen; the Terreros α surfaces, the paper's model, with the electrodes on the end faces
//! themselves (`electric.electrodes: [(face: ZMin, ..)]`, half-contacts σ S/h from each
//! particle touching the face; `mean_rel_error_terreros_face`, the headline before the
//! Laguerre cells) and with the paper's electrodes, the particle layers touching the faces
//! (`mean_rel_error_particle_electrodes`); the calibrated surfaces S = C_t π R_m² with C_t
//! calibrated on the same packing: `mean_rel_error_calibrated` (particle electrodes) and
//! `mean_rel_error_face_calibrated`. Each model's cost (network, calibration, solve) is
//! reported beside its error.
//!
//! Laguerre tolerance, chosen before its numbers were seen: every packing at every N within
//! the 1 % (the network is exact for the uniform field; what is left is the section
//! of the cells, which follow the mantle by tangent planes).
//!
//! Tolerances of the papers' models, fixed before the face-electrode runs: Terreros with face
//! electrodes must be no worse than the
//! paper's own mean error at the largest N of the run (2.85 % at 20 000, 3.77 % at 10 000:
//! the project's aim is to beat the papers' code); both electrode models' errors must fall
//! with N, as the paper's; face electrodes must not be worse than particle electrodes (they
//! remove the electrode-layer bias and add nothing else). Particle electrodes are reported
//! against the paper without a gate: they sit about 2 × its error (our α table is
//! reconstructed, `shared/refs/terreros-alpha.md`; the notes say why). The calibrated
//! surfaces are calibrated with a heat flux along the same axis on the same packing, so they
//! must do better than 2 %; this checks the scene's calibration path rather than the method.
//!
//! Samples, models, electrode biases and tolerances, as documentation:
//! `validation/notes/cylinder-resistance.md`.

use std::time::Instant;

use demcon_scene::config::*;
use serde_json::{Map, Value};

use super::common::*;
use super::cylinder::*;
use super::study::{Measured as Packing, Study};
use crate::analytic::uniform_resistance;
use crate::table::Columns;
use crate::{CaseOutcome, Comparison, Ctx, Table};
use demcon_plot::{Chart, Scale, Series, draw};

/// A line of the paper's Table 3.
struct PaperRow {
    n: usize,
    /// Errors of its 3 packings (%).
    errors_percent: [f64; 3],
}

/// The paper's Table 3 (its mean radii, 133 … 49 µm, are not used).
const PAPER: [PaperRow; 5] = [
    PaperRow {
        n: 1000,
        errors_percent: [6.08, 10.51, 9.19],
    },
    PaperRow {
        n: 2000,
        errors_percent: [12.28, 12.57, 15.56],
    },
    PaperRow {
        n: 5000,
        errors_percent: [4.11, 5.80, 4.04],
    },
    PaperRow {
        n: 10000,
        errors_percent: [3.60, 4.41, 3.31],
    },
    PaperRow {
        n: 20000,
        errors_percent: [2.60, 2.92, 3.04],
    },
];

impl PaperRow {
    /// Mean of the 3 packings' errors (%).
    fn mean_percent(&self) -> f64 {
        self.errors_percent.iter().sum::<f64>() / 3.0
    }
}

/// The paper's row at `n`, if it has that size.
fn paper_at(n: usize) -> Option<&'static PaperRow> {
    PAPER.iter().find(|p| p.n == n)
}

/// The paper's mean error (fraction) at `n`, if it has that size.
fn paper_mean(n: usize) -> Option<f64> {
    paper_at(n).map(|p| p.errors_percent.iter().sum::<f64>() / 300.0)
}

/// Potential difference (V) between the end faces, as the paper (1 V).
const V0: f64 = 1.0;

/// Packings per N.
const REALISATIONS: u64 = 3;

/// One packing's measurements.
struct Sample {
    n: usize,
    mean_radius: f64,
    /// Laguerre cells, face electrodes: R (Ω), tessellation (s), solve (ms), the cells' section
    /// on ZMax over π r² − 1.
    r_laguerre: f64,
    laguerre_network_s: f64,
    laguerre_ms: f64,
    laguerre_section: f64,
    /// Contact detection (s), calibration (s) and the calibrated model's solve (ms).
    contacts_s: f64,
    calibration_s: f64,
    calibrated_ms: f64,
    r_terreros: f64,
    r_terreros_62: f64,
    r_calibrated: f64,
    r_face: f64,
    r_face_calibrated: f64,
    face_ms: f64,
    c_t: f64,
    l_eff: f64,
    iterations: usize,
    solve_ms: f64,
    mismatch: f64,
    excluded: usize,
    pack_s: f64,
    phi: f64,
    z_wall: f64,
    z_bulk: f64,
}

/// Signed relative errors R/R_th − 1 of one packing's models.
struct Errors {
    /// Laguerre cells, face electrodes (the headline).
    laguerre: f64,
    /// Terreros α, particle electrodes, Z = 7.5.
    terreros: f64,
    /// The same at Z = 6.2.
    z62: f64,
    /// Calibrated C_t, particle electrodes.
    calibrated: f64,
    /// Terreros, particle electrodes, R · l / L_eff.
    length_corrected: f64,
    /// Terreros α, face electrodes.
    face: f64,
    /// Calibrated C_t, face electrodes.
    face_calibrated: f64,
}

impl Sample {
    /// The errors against the uniform-conductor resistance `r_th` (Ω).
    fn errors(&self, r_th: f64) -> Errors {
        Errors {
            laguerre: self.r_laguerre / r_th - 1.0,
            terreros: self.r_terreros / r_th - 1.0,
            z62: self.r_terreros_62 / r_th - 1.0,
            calibrated: self.r_calibrated / r_th - 1.0,
            // The network spans L_eff, not l: the resistance a length-l conductor of the
            // network's effective resistivity would have is R · l / L_eff.
            length_corrected: self.r_terreros * LENGTH / self.l_eff / r_th - 1.0,
            face: self.r_face / r_th - 1.0,
            face_calibrated: self.r_face_calibrated / r_th - 1.0,
        }
    }
}

/// One packing of the table: its measurements and errors.
struct PackingLine {
    s: Sample,
    e: Errors,
}

/// Means over the packings of one N: |errors| (fractions), C_t and the mean radius (m).
struct SizeMeans {
    n: usize,
    /// Laguerre: mean and largest |error| over the packings.
    laguerre: f64,
    laguerre_max: f64,
    terreros: f64,
    calibrated: f64,
    length_corrected: f64,
    z62: f64,
    c_t: f64,
    mean_radius: f64,
    face: f64,
    face_calibrated: f64,
}

/// Everything the case measures.
struct Measured {
    /// ρ_e l / A (Ω).
    r_th: f64,
    study: Study<PackingLine>,
    means: Vec<SizeMeans>,
    worst_mismatch: f64,
    excluded: usize,
    pack_s: f64,
    n_particles: usize,
}

/// Packs one realisation and measures every model on it.
fn measure_packing(n: usize, seed: u64) -> anyhow::Result<Sample> {
    let terreros = electric_scene(
        "cylinder-resistance",
        seed,
        n,
        None,
        SurfaceConfig::TerrerosAlpha,
        V0,
    );
    let model = model_of(&terreros)?;
    let pack_s = model.report.pack_s;
    let rt = run_with(&terreros, &model)?;
    let et = rt.electric.as_ref().expect("electric run");
    let t1 = Instant::now();
    let cal = calibrate_ct(&model)?;
    let calibration_s = t1.elapsed().as_secs_f64();
    let calibrated = electric_scene(
        "cylinder-resistance",
        seed,
        n,
        None,
        SurfaceConfig::Calibrated {
            c_t: CtConfig::Value(cal.c_t),
        },
        V0,
    );
    let rc = run_with(&calibrated, &model)?;
    let ec = rc.electric.as_ref().expect("electric run");
    // The same two surface models with the electrodes on the end faces themselves.
    let face = |mut cfg: SceneConfig| {
        if let Some(e) = cfg.electric.as_mut() {
            e.electrodes = face_electrodes(V0);
        }
        cfg
    };
    let rf = run_with(&face(terreros.clone()), &model)?;
    let ef = rf.electric.as_ref().expect("electric run");
    let rfc = run_with(&face(calibrated.clone()), &model)?;
    let efc = rfc.electric.as_ref().expect("electric run");
    // The Laguerre cells on the same particles, face electrodes (their wall facets).
    let laguerre_cfg = with_surface_model(&face(terreros.clone()), Surface::Laguerre, None);
    let cells = laguerre_model(&laguerre_cfg, &model)?;
    let rl = run_with(&laguerre_cfg, &cells)?;
    let el = rl.electric.as_ref().expect("electric run");
    let section = wall_facet_area(&cells, FaceConfig::ZMax).unwrap_or(f64::NAN)
        / (std::f64::consts::PI * RADIUS * RADIUS)
        - 1.0;
    let model62 = with_coordination(&model, 6.2)?;
    let r62 = run_with(&terreros, &model62)?;
    let (lo, hi) = electrode_layers(&model)?;
    // Mean coordination of the particles touching the curved wall (surface within half a
    // radius of it) and of the others.
    let deg = model.graph.degrees();
    let (mut zw, mut nw, mut zb, mut nb) = (0.0, 0.0, 0.0, 0.0);
    for (p, c) in model.particles.centres.iter().enumerate() {
        let r = model.particles.radii[p];
        if RADIUS - c.x.hypot(c.y) - r <= 0.5 * r {
            zw += deg[p] as f64;
            nw += 1.0;
        } else {
            zb += deg[p] as f64;
            nb += 1.0;
        }
    }
    let missing = |r: Option<f64>| r.ok_or_else(|| anyhow::anyhow!("no resistance: no current flowed"));
    Ok(Sample {
        n: model.particles.len(),
        mean_radius: model.particles.radius_stats().mean,
        r_laguerre: missing(el.report.resistance_ohm)?,
        laguerre_network_s: network_s(&cells),
        laguerre_ms: 1e3 * el.report.wall_s,
        laguerre_section: section,
        contacts_s: network_s(&model),
        calibration_s,
        calibrated_ms: 1e3 * ec.report.wall_s,
        r_terreros: missing(et.report.resistance_ohm)?,
        r_calibrated: missing(ec.report.resistance_ohm)?,
        r_face: missing(ef.report.resistance_ohm)?,
        r_face_calibrated: missing(efc.report.resistance_ohm)?,
        face_ms: 1e3 * ef.report.wall_s,
        r_terreros_62: missing(r62.electric.as_ref().expect("electric run").report.resistance_ohm)?,
        c_t: cal.c_t,
        l_eff: effective_length(&model, &lo, &hi),
        iterations: et.report.iterations,
        solve_ms: 1e3 * et.report.wall_s,
        mismatch: [et, ec, ef, efc, el]
            .iter()
            .map(|e| e.report.current_mismatch)
            .fold(0.0, f64::max),
        excluded: et.excluded.len(),
        pack_s,
        phi: model.report.packing.as_ref().map_or(f64::NAN, |p| p.packing.phi),
        z_wall: zw / nw,
        z_bulk: zb / nb,
    })
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let m = measure(ctx)?;
    let mut out = CaseOutcome::new("cylinder-resistance", ctx.mode);
    out.n_particles = m.n_particles;
    compare(&m, &mut out);
    report(ctx, &m, &mut out)?;
    Ok(out)
}

/// Every packing of every N, and the means per N.
fn measure(ctx: &Ctx) -> anyhow::Result<Measured> {
    let sizes: Vec<usize> = ctx.pick(
        vec![1000, 2000, 5000, 10_000],
        vec![1000, 2000, 5000, 10_000, 20_000],
    );
    let r_th = uniform_resistance(RHO_E, LENGTH, std::f64::consts::PI * RADIUS * RADIUS);
    let study = Study::run(
        &sizes,
        |_| REALISATIONS,
        ctx.seed,
        |n, seed, _| {
            let s = measure_packing(n, seed)?;
            let e = s.errors(r_th);
            Ok(PackingLine { s, e })
        },
    )?;
    let mut means = Vec::new();
    for &n in &sizes {
        let these: Vec<&PackingLine> = study.at(n).collect();
        let mean =
            |f: fn(&PackingLine) -> f64| these.iter().fold(0.0, |acc, p| acc + f(p)) / REALISATIONS as f64;
        means.push(SizeMeans {
            n,
            laguerre: mean(|p| p.e.laguerre.abs()),
            laguerre_max: these.iter().map(|p| p.e.laguerre.abs()).fold(0.0, f64::max),
            terreros: mean(|p| p.e.terreros.abs()),
            calibrated: mean(|p| p.e.calibrated.abs()),
            length_corrected: mean(|p| p.e.length_corrected.abs()),
            z62: mean(|p| p.e.z62.abs()),
            c_t: mean(|p| p.s.c_t),
            mean_radius: mean(|p| p.s.mean_radius),
            face: mean(|p| p.e.face.abs()),
            face_calibrated: mean(|p| p.e.face_calibrated.abs()),
        });
    }
    let packings = study.packings();
    Ok(Measured {
        r_th,
        worst_mismatch: packings.iter().map(|p| p.rows.s.mismatch).fold(0.0f64, f64::max),
        excluded: packings.iter().map(|p| p.rows.s.excluded).sum(),
        pack_s: packings.iter().fold(0.0, |acc, p| acc + p.rows.s.pack_s),
        n_particles: packings.iter().map(|p| p.rows.s.n).max().unwrap_or(0),
        study,
        means,
    })
}

/// Metrics, references and the checks (headline: Terreros with face electrodes).
fn compare(m: &Measured, out: &mut CaseOutcome) {
    let by_n = |f: fn(&SizeMeans) -> f64| -> Value {
        Value::Object(m.means.iter().map(|s| (key(s.n), Value::from(f(s)))).collect())
    };
    out.metric("headline_model", "laguerre, face electrodes");
    out.metric("mean_rel_error", by_n(|s| s.laguerre));
    out.metric("max_rel_error", by_n(|s| s.laguerre_max));
    out.metric("mean_rel_error_terreros_face", by_n(|s| s.face));
    out.metric("mean_rel_error_particle_electrodes", by_n(|s| s.terreros));
    out.metric("mean_rel_error_calibrated", by_n(|s| s.calibrated));
    out.metric("mean_rel_error_length_corrected", by_n(|s| s.length_corrected));
    out.metric("mean_rel_error_z62", by_n(|s| s.z62));
    out.metric("mean_rel_error_face_calibrated", by_n(|s| s.face_calibrated));
    out.metric("c_t", by_n(|s| s.c_t));
    out.metric("mean_radius_um", by_n(|s| 1e6 * s.mean_radius));
    out.metric("current_mismatch_max", m.worst_mismatch);
    out.metric("excluded_particles", m.excluded);
    out.metric("r_analytic_ohm", m.r_th);
    let paper_ref: Map<String, Value> = PAPER
        .iter()
        .map(|p| {
            (
                key(p.n),
                Value::from(p.errors_percent.iter().sum::<f64>() / 300.0),
            )
        })
        .collect();
    out.reference("mean_rel_error_terreros_face", Value::Object(paper_ref));
    out.reference("max_rel_error", "0.01 at every N (issue 10, Laguerre)");
    let wall = |f: fn(&PackingLine) -> f64| -> Value {
        Value::Object(
            m.study
                .sizes()
                .iter()
                .map(|&n| (key(n), Value::from(m.study.spread(n, f).mean)))
                .collect(),
        )
    };
    out.metric(
        "wall_s_laguerre",
        wall(|p| p.s.laguerre_network_s + 1e-3 * p.s.laguerre_ms),
    );
    out.metric(
        "wall_s_terreros_face",
        wall(|p| p.s.contacts_s + 1e-3 * p.s.face_ms),
    );
    out.metric(
        "wall_s_calibrated",
        wall(|p| p.s.contacts_s + p.s.calibration_s + 1e-3 * p.s.calibrated_ms),
    );
    out.metric(
        "laguerre_section_error_max",
        m.study
            .packings()
            .iter()
            .map(|p| p.rows.s.laguerre_section.abs())
            .fold(0.0, f64::max),
    );
    out.reference(
        "source",
        "Hubert 2017 §3.1 Table 3 / Fig. 4 (Terreros surfaces, 3 packings per N); analytic ρ_e l / A",
    );
    let (first, last) = (&m.means[0], &m.means[m.means.len() - 1]);
    let (n_min, n_max) = (first.n, last.n);
    out.compare(Comparison::at_most(
        &format!(
            "Laguerre (headline), face electrodes: largest |R/R_th − 1| over every packing at every N ({} packings)",
            m.study.packings().len()
        ),
        m.means.iter().map(|s| s.laguerre_max).fold(0.0, f64::max),
        0.01,
        "the issue's Laguerre target, 1 %",
    ));
    if let Some(p) = paper_mean(n_max) {
        out.compare(Comparison::at_most(
            &format!("Terreros, face electrodes: mean |R/R_th − 1| at N = {n_max}"),
            last.face,
            p,
            &format!(
                "the paper's mean {:.2} % at this N (its own code, Terreros)",
                100.0 * p
            ),
        ));
    }
    out.compare(Comparison::at_most(
        &format!("Terreros, face electrodes: the error falls with N (N = {n_max} against N = {n_min})"),
        last.face,
        first.face,
        "the paper's convergence (Fig. 4)",
    ));
    out.compare(Comparison::at_most(
        &format!("Terreros, particle electrodes: the error falls with N (N = {n_max} against N = {n_min})"),
        last.terreros,
        first.terreros,
        "the paper's convergence (Fig. 4)",
    ));
    out.compare(Comparison::at_most(
        &format!("Terreros, face electrodes: mean |R/R_th − 1| at N = {n_max}, against particle electrodes"),
        last.face,
        last.terreros,
        "face electrodes remove the electrode-layer bias (R low by about 2 r̄/l) and add nothing else",
    ));
    out.compare(Comparison::at_most(
        &format!("calibrated C_t: mean |R/R_th − 1| at N = {n_max}"),
        last.calibrated,
        0.02,
        "C_t calibrated on the same packing along the same axis",
    ));
    out.compare(Comparison::at_most(
        "Kirchhoff balance |I_in − I_out|/I_in",
        m.worst_mismatch,
        1e-6,
        "CG to a relative residual of 1e-10",
    ));
}

/// Signed error as a percentage cell.
fn pct(e: f64) -> String {
    format!("{:+.2} %", 100.0 * e)
}

/// The per-packing table, the chart and the notes.
fn report(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    out.tables.push(packings_table(m));
    error_chart(ctx, m, out)?;
    run_notes(ctx, m, out);
    Ok(())
}

/// Every packing: each model's R and error, the geometry columns and the costs.
fn packings_table(m: &Measured) -> Table {
    Columns::new()
        .column("N", |p: &Packing<PackingLine>| p.rows.s.n.to_string())
        .column("packing", |p| (p.k + 1).to_string())
        .column("r̄ (µm)", |p| format!("{:.1}", 1e6 * p.rows.s.mean_radius))
        .column("φ", |p| format!("{:.3}", p.rows.s.phi))
        .column("Z wall / bulk", |p| {
            format!("{:.2} / {:.2}", p.rows.s.z_wall, p.rows.s.z_bulk)
        })
        .column("R Laguerre, face electrodes (mΩ)", |p| {
            format!("{:.5}", 1e3 * p.rows.s.r_laguerre)
        })
        .column("error", |p| format!("{:+.4} %", 100.0 * p.rows.e.laguerre))
        .column("A_cells/A − 1", |p| {
            format!("{:+.1e}", p.rows.s.laguerre_section)
        })
        .column("Laguerre: tessellation (s); solve (ms)", |p| {
            format!("{:.3}; {:.1}", p.rows.s.laguerre_network_s, p.rows.s.laguerre_ms)
        })
        .column("R Terreros (mΩ)", |p| {
            format!("{:.5}", 1e3 * p.rows.s.r_terreros)
        })
        .column("error", |p| pct(p.rows.e.terreros))
        .column("error, Z = 6.2", |p| pct(p.rows.e.z62))
        .column("R calibrated (mΩ)", |p| {
            format!("{:.5}", 1e3 * p.rows.s.r_calibrated)
        })
        .column("error", |p| pct(p.rows.e.calibrated))
        .column("C_t (calibration s)", |p| {
            format!("{:.4} ({:.2})", p.rows.s.c_t, p.rows.s.calibration_s)
        })
        .column("L_eff / l", |p| format!("{:.4}", p.rows.s.l_eff / LENGTH))
        .column("Terreros error, L_eff-corrected", |p| {
            pct(p.rows.e.length_corrected)
        })
        .column("R Terreros, face electrodes (mΩ)", |p| {
            format!("{:.5}", 1e3 * p.rows.s.r_face)
        })
        .column("error", |p| pct(p.rows.e.face))
        .column("error, calibrated, face electrodes", |p| {
            pct(p.rows.e.face_calibrated)
        })
        .column("CG iter.", |p| p.rows.s.iterations.to_string())
        .column("solve (ms)", |p| format!("{:.1}", p.rows.s.solve_ms))
        .column("solve, face electrodes (ms)", |p| {
            format!("{:.1}", p.rows.s.face_ms)
        })
        .column("contacts (s)", |p| format!("{:.3}", p.rows.s.contacts_s))
        .column("paper error", |p| {
            paper_at(p.n_target)
                .map(|row| format!("{:.2} %", row.errors_percent[p.k as usize]))
                .unwrap_or_default()
        })
        .table(
            format!(
                "Equivalent resistance against ρ_e l / A = {:.5} mΩ, per packing",
                1e3 * m.r_th
            ),
            m.study.packings(),
        )
}

/// The mean error against N per model, with the paper's Table 3 (Fig. 4).
fn error_chart(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) -> anyhow::Result<()> {
    let series = |f: fn(&SizeMeans) -> f64| -> Vec<(f64, f64)> {
        m.means.iter().map(|s| (s.n as f64, 100.0 * f(s))).collect()
    };
    let paper: Vec<(f64, f64)> = PAPER
        .iter()
        .filter(|p| m.study.sizes().contains(&p.n))
        .map(|p| (p.n as f64, p.mean_percent()))
        .collect();
    draw(
        &Chart {
            title: "Cylinder resistance: mean |R − ρ_e l/A| / (ρ_e l/A) against N (Hubert 2017 Fig. 4)"
                .into(),
            x_label: "N (particles)".into(),
            y_label: "mean relative error (%)".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
            series: vec![
                Series::line(
                    "demcon, Laguerre cells, face electrodes (headline)",
                    series(|s| s.laguerre),
                ),
                Series::line("demcon, Terreros α, Z = 7.5", series(|s| s.terreros)),
                Series::line("demcon, Terreros α, Z = 6.2", series(|s| s.z62)),
                Series::line("demcon, calibrated C_t", series(|s| s.calibrated)),
                Series::line(
                    "demcon, Terreros α, Z = 7.5, L_eff-corrected (see notes)",
                    series(|s| s.length_corrected),
                ),
                Series::line("demcon, Terreros α, face electrodes", series(|s| s.face)),
                Series::line(
                    "demcon, calibrated C_t, face electrodes",
                    series(|s| s.face_calibrated),
                ),
                Series::markers("Hubert 2017 Table 3 (mean of 3)", paper),
            ],
        },
        &ctx.out.join("cylinder-resistance.png"),
    )?;
    out.charts.push("cylinder-resistance.png".into());
    Ok(())
}

/// The run's sizes, the headline's figures, and the pointer to the case's notes file.
fn run_notes(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) {
    out.note(format!(
        "Mode {}: N = {:?}, 3 packings each (seeds {}…{}). Packing took {:.1} s in all (shared by the models, not in their \
         wall time). Samples, models, electrode biases and tolerances: validation/notes/cylinder-resistance.md.",
        ctx.mode.name(),
        m.study.sizes(),
        ctx.seed,
        ctx.seed + REALISATIONS - 1,
        m.pack_s,
    ));
    let lag = Spread::of(m.study.packings().iter().map(|p| p.rows.e.laguerre.abs()));
    out.note(format!(
        "Headline (Laguerre cells, face electrodes): A_cells/A − 1 at most {:.1e}; over all {} packings |R/R_th − 1| mean \
         {:.2e}, max {:.2e}.",
        m.study
            .packings()
            .iter()
            .map(|p| p.rows.s.laguerre_section.abs())
            .fold(0.0, f64::max),
        lag.count,
        lag.mean,
        lag.max,
    ));
}
