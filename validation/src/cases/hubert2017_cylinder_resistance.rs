//! `cylinder-resistance` — Hubert et al. 2017 §3.1, Table 3 and Fig. 4: a cylinder r = 1 mm,
//! l = 5 mm of AISI 304L (ρ_e = 0.73e-6 Ω·m), a potential difference between the particles
//! touching its two end faces, N = 1000 … 20 000 particles, 3 packings per N. The equivalent
//! resistance ΔV / I is compared with the uniform-conductor value ρ_e l / A (1.16183 mΩ,
//! `analytic::uniform_resistance`).
//!
//! Compared quantity: the relative error |R − ρ_e l/A| / (ρ_e l/A), averaged over the 3
//! packings of each N (the paper's "absolute error"), for the Terreros α surfaces, the
//! paper's model, with the electrodes on the end faces themselves (`electric.electrodes:
//! [(face: ZMin, ..)]`, half-contacts σ S/h from each particle touching the face) —
//! `mean_rel_error`, the headline: the electrodes of the continuum problem are the end faces —
//! and with the paper's electrodes, the particle layers touching the faces
//! (`mean_rel_error_particle_electrodes`). The calibrated surfaces S = C_t π R_m² with C_t
//! calibrated on the same packing: `mean_rel_error_calibrated` (particle electrodes) and
//! `mean_rel_error_face_calibrated`.
//!
//! Tolerances, fixed before the face-electrode runs: the headline must be no worse than the
//! paper's own mean error at the largest N of the run (2.85 % at 20 000, 3.77 % at 10 000:
//! the project's aim is to beat the papers' code); both electrode models' errors must fall
//! with N, as the paper's; face electrodes must not be worse than particle electrodes (they
//! remove the electrode-layer bias and add nothing else). Particle electrodes are reported
//! against the paper without a gate: they sit about 2 × its error (our α table is
//! reconstructed, `shared/refs/terreros-alpha.md`; the notes say why). The calibrated
//! surfaces are calibrated with a heat flux along the same axis on the same packing, so they
//! must do better than 2 %; this checks the scene's calibration path rather than the method.

use std::time::Instant;

use demcon_scene::config::*;
use serde_json::{Map, Value};

use super::common::*;
use super::cylinder::*;
use crate::analytic::uniform_resistance;
use crate::chart::{Chart, Scale, Series, draw};
use crate::{CaseOutcome, Comparison, Ctx, Table};

/// The paper's Table 3: (N, mean radius µm, errors of the 3 packings in %).
const PAPER: [(usize, f64, [f64; 3]); 5] = [
    (1000, 133.0, [6.08, 10.51, 9.19]),
    (2000, 106.0, [12.28, 12.57, 15.56]),
    (5000, 78.0, [4.11, 5.80, 4.04]),
    (10000, 62.0, [3.60, 4.41, 3.31]),
    (20000, 49.0, [2.60, 2.92, 3.04]),
];

/// The paper's mean error (fraction) at `n`, if it has that size.
fn paper_mean(n: usize) -> Option<f64> {
    PAPER
        .iter()
        .find(|p| p.0 == n)
        .map(|p| p.2.iter().sum::<f64>() / 300.0)
}

/// Potential difference (V) between the end faces, as the paper (1 V).
const V0: f64 = 1.0;

/// One packing's measurements.
struct Sample {
    n: usize,
    mean_radius: f64,
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

fn measure(n: usize, seed: u64) -> anyhow::Result<Sample> {
    let t0 = Instant::now();
    let terreros = electric_scene(
        "cylinder-resistance",
        seed,
        n,
        None,
        SurfaceConfig::TerrerosAlpha,
        V0,
    );
    let model = model_of(&terreros)?;
    let pack_s = t0.elapsed().as_secs_f64();
    let rt = run_with(&terreros, &model)?;
    let et = rt.electric.as_ref().expect("electric run");
    let cal = calibrate_ct(&model)?;
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
        mismatch: [et, ec, ef, efc]
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
    let sizes: Vec<usize> = ctx.pick(
        vec![1000, 2000, 5000, 10_000],
        vec![1000, 2000, 5000, 10_000, 20_000],
    );
    let realisations = 3u64;
    let r_th = uniform_resistance(RHO_E, LENGTH, std::f64::consts::PI * RADIUS * RADIUS);
    let mut out = CaseOutcome::new("cylinder-resistance", ctx.mode);
    let mut maps: [Map<String, Value>; 8] = Default::default();
    let mut table = Table {
        title: format!(
            "Equivalent resistance against ρ_e l / A = {:.5} mΩ, per packing",
            1e3 * r_th
        ),
        header: [
            "N",
            "packing",
            "r̄ (µm)",
            "φ",
            "Z wall / bulk",
            "R Terreros (mΩ)",
            "error",
            "error, Z = 6.2",
            "R calibrated (mΩ)",
            "error",
            "C_t",
            "L_eff / l",
            "Terreros error, L_eff-corrected",
            "R Terreros, face electrodes (mΩ)",
            "error",
            "error, calibrated, face electrodes",
            "CG iter.",
            "solve (ms)",
            "solve, face electrodes (ms)",
            "paper error",
        ]
        .iter()
        .map(|h| h.to_string())
        .collect(),
        rows: Vec::new(),
    };
    let mut pts: [Vec<(f64, f64)>; 7] = Default::default();
    let (mut worst_mismatch, mut excluded, mut pack_s) = (0.0f64, 0usize, 0.0);
    let mut by_n = Vec::new();
    for &n in &sizes {
        let mut sums = [0.0; 8];
        for k in 0..realisations {
            let s = measure(n, ctx.seed + k)?;
            let err_t = s.r_terreros / r_th - 1.0;
            let err_62 = s.r_terreros_62 / r_th - 1.0;
            let err_c = s.r_calibrated / r_th - 1.0;
            // The network spans L_eff, not l: the resistance a length-l conductor of the
            // network's effective resistivity would have is R · l / L_eff.
            let err_l = s.r_terreros * LENGTH / s.l_eff / r_th - 1.0;
            let err_f = s.r_face / r_th - 1.0;
            let err_fc = s.r_face_calibrated / r_th - 1.0;
            for (acc, v) in sums.iter_mut().zip([
                err_t.abs(),
                err_c.abs(),
                err_l.abs(),
                err_62.abs(),
                s.c_t,
                s.mean_radius,
                err_f.abs(),
                err_fc.abs(),
            ]) {
                *acc += v;
            }
            worst_mismatch = worst_mismatch.max(s.mismatch);
            excluded += s.excluded;
            pack_s += s.pack_s;
            out.n_particles = out.n_particles.max(s.n);
            let paper = PAPER
                .iter()
                .find(|p| p.0 == n)
                .map(|p| format!("{:.2} %", p.2[k as usize]))
                .unwrap_or_default();
            table.rows.push(vec![
                s.n.to_string(),
                (k + 1).to_string(),
                format!("{:.1}", 1e6 * s.mean_radius),
                format!("{:.3}", s.phi),
                format!("{:.2} / {:.2}", s.z_wall, s.z_bulk),
                format!("{:.5}", 1e3 * s.r_terreros),
                format!("{:+.2} %", 100.0 * err_t),
                format!("{:+.2} %", 100.0 * err_62),
                format!("{:.5}", 1e3 * s.r_calibrated),
                format!("{:+.2} %", 100.0 * err_c),
                format!("{:.4}", s.c_t),
                format!("{:.4}", s.l_eff / LENGTH),
                format!("{:+.2} %", 100.0 * err_l),
                format!("{:.5}", 1e3 * s.r_face),
                format!("{:+.2} %", 100.0 * err_f),
                format!("{:+.2} %", 100.0 * err_fc),
                s.iterations.to_string(),
                format!("{:.1}", s.solve_ms),
                format!("{:.1}", s.face_ms),
                paper,
            ]);
        }
        let mean = sums.map(|v| v / realisations as f64);
        let values = [
            mean[0],
            mean[1],
            mean[2],
            mean[3],
            mean[4],
            1e6 * mean[5],
            mean[6],
            mean[7],
        ];
        for (m, v) in maps.iter_mut().zip(values) {
            m.insert(key(n), Value::from(v));
        }
        for (p, v) in pts.iter_mut().zip(&mean[..4]) {
            p.push((n as f64, 100.0 * v));
        }
        pts[5].push((n as f64, 100.0 * mean[6]));
        pts[6].push((n as f64, 100.0 * mean[7]));
        by_n.push((n, mean[0], mean[1], mean[6]));
    }
    for p in PAPER.iter().filter(|p| sizes.contains(&p.0)) {
        pts[4].push((p.0 as f64, p.2.iter().sum::<f64>() / 3.0));
    }
    let [m_t, m_c, m_l, m_62, m_ct, m_rad, m_f, m_fc] = maps;
    out.metric("mean_rel_error", Value::Object(m_f));
    out.metric("mean_rel_error_particle_electrodes", Value::Object(m_t));
    out.metric("mean_rel_error_calibrated", Value::Object(m_c));
    out.metric("mean_rel_error_length_corrected", Value::Object(m_l));
    out.metric("mean_rel_error_z62", Value::Object(m_62));
    out.metric("mean_rel_error_face_calibrated", Value::Object(m_fc));
    out.metric("c_t", Value::Object(m_ct));
    out.metric("mean_radius_um", Value::Object(m_rad));
    out.metric("current_mismatch_max", worst_mismatch);
    out.metric("excluded_particles", excluded);
    out.metric("r_analytic_ohm", r_th);
    let mut paper_ref = Map::new();
    for p in PAPER.iter() {
        paper_ref.insert(key(p.0), Value::from(p.2.iter().sum::<f64>() / 300.0));
    }
    out.reference("mean_rel_error", Value::Object(paper_ref));
    out.reference(
        "source",
        "Hubert 2017 §3.1 Table 3 / Fig. 4 (Terreros surfaces, 3 packings per N); analytic ρ_e l / A",
    );
    let (n_min, e_first, _, e_f_first) = by_n[0];
    let (n_max, e_t, e_c, e_f) = by_n[by_n.len() - 1];
    if let Some(p) = paper_mean(n_max) {
        out.compare(Comparison::at_most(
            &format!("Terreros, face electrodes: mean |R/R_th − 1| at N = {n_max}"),
            e_f,
            p,
            &format!(
                "the paper's mean {:.2} % at this N (its own code, Terreros)",
                100.0 * p
            ),
        ));
    }
    out.compare(Comparison::at_most(
        &format!("Terreros, face electrodes: the error falls with N (N = {n_max} against N = {n_min})"),
        e_f,
        e_f_first,
        "the paper's convergence (Fig. 4)",
    ));
    out.compare(Comparison::at_most(
        &format!("Terreros, particle electrodes: the error falls with N (N = {n_max} against N = {n_min})"),
        e_t,
        e_first,
        "the paper's convergence (Fig. 4)",
    ));
    out.compare(Comparison::at_most(
        &format!("Terreros, face electrodes: mean |R/R_th − 1| at N = {n_max}, against particle electrodes"),
        e_f,
        e_t,
        "face electrodes remove the electrode-layer bias (R low by about 2 r̄/l) and add nothing else",
    ));
    out.compare(Comparison::at_most(
        &format!("calibrated C_t: mean |R/R_th − 1| at N = {n_max}"),
        e_c,
        0.02,
        "C_t calibrated on the same packing along the same axis",
    ));
    out.compare(Comparison::at_most(
        "Kirchhoff balance |I_in − I_out|/I_in",
        worst_mismatch,
        1e-6,
        "CG to a relative residual of 1e-10",
    ));
    out.tables.push(table);
    let [p_t, p_c, p_l, p_62, p_paper, p_f, p_fc] = pts;
    draw(
        &Chart {
            title: "Cylinder resistance: mean |R − ρ_e l/A| / (ρ_e l/A) against N (Hubert 2017 Fig. 4)"
                .into(),
            x_label: "N (particles)".into(),
            y_label: "mean relative error (%)".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
            series: vec![
                Series::line("demcon, Terreros α, Z = 7.5", p_t),
                Series::line("demcon, Terreros α, Z = 6.2", p_62),
                Series::line("demcon, calibrated C_t", p_c),
                Series::line("demcon, Terreros α, Z = 7.5, L_eff-corrected (see notes)", p_l),
                Series::line("demcon, Terreros α, face electrodes", p_f),
                Series::line("demcon, calibrated C_t, face electrodes", p_fc),
                Series::markers("Hubert 2017 Table 3 (mean of 3)", p_paper),
            ],
        },
        &ctx.out.join("cylinder-resistance.png"),
    )?;
    out.charts.push("cylinder-resistance.png".into());
    out.note(format!(
        "Mode {}: N = {:?}, 3 packings each (seeds {}…{}); `--full` adds 20 000. LS packings in \
         the cylinder, Gaussian radii std/mean 0.3, aiming at φ = 0.64 and accepting the jammed state (column φ: the narrow \
         cylinder's wall layers jam below 0.64); contacts for Z = 7.5 (the column 'Z = 6.2' re-detects the contacts of the same \
         packing for the electric paper's coordination); electrodes = particles touching each end face (surface within half a \
         radius), {V0} V apart. Packing and contacts took {pack_s:.1} s in all.",
        ctx.mode.name(),
        sizes,
        ctx.seed,
        ctx.seed + realisations - 1,
    ));
    out.note(
        "With the paper's particle electrodes (`mean_rel_error_particle_electrodes`), Terreros α is worse than the paper \
         (R too LOW, about twice the paper's error at 5000–10 000 particles) and \
         worse still at the paper's Z = 6.2: our α(n) is reconstructed from the regular polyhedra (the 2013 table was not \
         available), and α rises steeply at low neighbour counts (α(4) = 10.4 against α(6) = 4). In this narrow cylinder a \
         large share of the particles touch the wall and have fewer neighbours (column 'Z wall / bulk'), so they get large \
         surfaces and the network conducts too well; the error shrinks with N as that share does. Most of the gap, though, is the \
         particle electrodes' own bias (next note): with the faces as electrodes the same surfaces land within the paper's \
         error.",
    );
    out.note(
        "Electrode layers: the network only spans the distance L_eff between the mean centres of the two electrode layers \
         (about one mean radius inside each face), and the electrode particles are equipotential, so the measured R is \
         biased LOW by about 2 r̄ / l (5 % at 1000 particles, 2 % at 20 000). The column and the series 'L_eff-corrected' \
         report R · l / L_eff, the resistance of a length-l conductor with the network's effective resistivity: it is NOT \
         the paper's measure and is shown only to separate that bias from the bulk error of the surfaces.",
    );
    out.note(
        "Face electrodes (headline: `mean_rel_error`): each end face is one node held at its potential and linked to \
         every particle touching it by a half-contact σ_p S_p / h_p (h_p the centre-to-face distance, S_p the particle's own \
         surface), as the thermal `WallTemperature`. The network then spans the whole length l, so the electrode-layer bias \
         (R low by about 2 r̄/l) is gone; what remains is the bulk error of the surfaces, which is why the check asks the \
         face-electrode error to be no larger than the particle-electrode one. With the calibrated surfaces the C_t used is \
         the paper-protocol one (particle boundary layers, column C_t), which absorbs the electrode-layer bias of THAT \
         protocol, so with face electrodes R comes out HIGH ('error, calibrated, face electrodes'). Calibrating C_t with the \
         faces held through wall links (`CalibrationBc::Walls`) would make R exact by construction (the same network up \
         to the factor σ/λ), an identity and not a measurement, so it is not shown.",
    );
    out.note(
        "Calibrated surfaces: C_t comes from a heat-flux calibration on the SAME packing along the same axis (the scene's \
         `c_t: Auto`), so its error mostly measures the difference between a flux and a fixed-potential boundary on the \
         top layer; it is a consistency check, not an independent prediction.",
    );
    Ok(out)
}
