//! `crack-penny` — ours (issue 14): an insulating penny crack of radius a at the centre of a
//! cube of edge L, normal to the imposed gradient, a/L = 1/8, 1/6, 1/4. In an infinite body
//! with a far-field flux q normal to it, the temperature jump across the crack faces is
//! (refs/analytic.md §8)
//!
//! [T](r) = (4q/(πλ)) √(a² − r²),  whose mean over the crack is (8/(3π)) q a/λ.
//!
//! Geometry: the cube of the composite cases (L = 0.1 m), one material (λ = 1 W/(m·K)),
//! temperatures held on YMin (0 °C) and YMax (1 °C) through wall links, steady state; the
//! crack is a `Disc` at the cube's centre with normal y. The network's jump is read on the
//! contacts the crack cuts: T of the upper particle minus T of the lower one (the normal
//! gradient vanishes on an insulated face, so the difference across a cut branch is the jump
//! at its crossing point, to first order), against [T](r) at the crossing's radius r. q is
//! the cracked cube's mean flux Q/A (the far field the crack sees), λ the model's own
//! homogeneous conductivity on the same packing (λ_hom = Q₀L/(AΔT) without the crack), so
//! that a surface model's homogeneous bias does not enter the comparison.
//!
//! Reported: the contact-averaged jump ratio Σ[T]_k / Σ[T]_ref,k − 1 (the mean jump), the
//! profile in five bands of r/a, per model (Laguerre, Terreros α, calibrated C_t), a/L and N;
//! and a crack across the whole section (a polygon at y = L/2 larger than the section), which
//! must pass no heat at all: |Q|/Q₀ to round-off.
//!
//! Tolerances, fixed before any number was seen: the through-section crack ≤ 10⁻¹² of Q₀
//! (every model: the two halves share no branch, each is held at one temperature; that run
//! solves to a relative residual of 10⁻¹³, [`THROUGH_REL_TOL`], since the flow it reads is a
//! sum of residual entries); the mean
//! jump of the Laguerre network within 20 % at the largest N for every a/L. Why 20 %: at
//! 2·10⁴ particles the crack radius a = L/8 spans about six particle radii, and which branches
//! the disc cuts near its rim moves its effective radius by about half a radius (≈ 8 % of a;
//! the mean jump ∝ a); the finite cube (fixed faces at 4a, adiabatic sides at 4a for
//! a/L = 1/8; 2a for 1/4) adds a few %, growing with a/L.
//!
//! The headline since issue 32 (by design): the Laguerre cells following the crack's faces
//! (`phase_rule: Conforming`: seed pairs mirrored across the disc, a model built with each
//! crack; the jump read on the same sites with the crack filled by a conductance too large to
//! matter). Gates: the a-priori 20 % in `--quick`, issue 32's 5 % at 10⁵ in `--full`.
//!
//! History. The first rule cut a facet whole when its segment crossed the crack (the segment
//! rule, still the contact models' rule): it missed the 20 % with 23–32 % at 2·10⁴. The rule
//! now used on the Laguerre cells (built after that run, from the diagnosis that a crack's edge
//! rounded to whole facets is larger than the crack) cuts each facet by the part the crack
//! covers ([`demcon_graph::blocked_contacts`]). The whole-facet Laguerre network runs beside it
//! ("Laguerre, whole facets cut"). The jump is read on the same contacts for every model: those
//! of the uncracked graph whose segment crosses the disc. A continuum check of the finite cube
//! (`scripts/penny_crack_fv.py`: cell-centred finite volumes on one eighth of the cube, 128³
//! cells, the crack's faces cut by covered area) gives a mean jump +1.9 / +2.0 / +4.1 % over
//! the infinite-body formula at a/L = 1/8, 1/6, 1/4 (Q/Q₀ = 0.9947 / 0.9875 / 0.9584), still
//! falling with the mesh: the finite cube is a few % of the excess, not most of it.
//!
//! Reference, method and tolerances, as documentation: `validation/notes/crack-penny.md`.

use demcon_scene::config::*;
use serde_json::{Map, Value};

use super::common::*;
use super::study::{Measured, Study};
use crate::table::Columns;
use crate::{CaseOutcome, Comparison, Ctx, Table};
use demcon_plot::{Chart, Scale, Series, draw};

/// Cube edge (m).
const L: f64 = 0.1;
/// Conductivity (W/(m·K)).
const LAMBDA: f64 = 1.0;
/// Crack radii over L.
const RATIOS: [f64; 3] = [1.0 / 8.0, 1.0 / 6.0, 1.0 / 4.0];
/// Independent packings per N.
const PACKINGS: u64 = 3;
/// Bands of r/a for the profile.
const BANDS: usize = 5;
/// Laguerre: largest accepted |mean jump ratio − 1| at the largest N, fixed before any number
/// was seen; `--full` gates at it.
const TOL_JUMP: f64 = 0.2;
/// The `--full` gate of the headline (fraction): issue 32's 5 % at 10⁵. (Before the conforming
/// cells `--quick` gated a 40 % regression bound, set after the first quick run missed the 20 %
/// with 23–32 % with whole facets cut; the covered-part rule gives 15–22 % at 2·10⁴.)
const FULL_JUMP: f64 = 0.05;
/// Through-section crack: largest accepted |Q|/Q₀.
const TOL_THROUGH: f64 = 1e-12;
/// Relative residual of the through-section solve. |Q|/Q₀ of that run is the sum of a
/// part's residual entries over Q₀, so a check at [`TOL_THROUGH`] needs a solve that tight:
/// at the scenes' default 10⁻¹⁰, smoothed-aggregation multigrid happened to leave residuals
/// whose sums over each part cancelled (|Q|/Q₀ ≤ 10⁻¹²), the K-cycle multigrid leaves
/// 3·10⁻¹¹–4·10⁻¹⁰. Solving to 10⁻¹³ (or to the round-off floor, which
/// the solver accepts and reports) tests the topology, not the solver's luck.
const THROUGH_REL_TOL: f64 = 1e-13;

/// The uncracked scene.
fn scene(n: usize, seed: u64) -> SceneConfig {
    let mut s = thermal_scene(
        "crack-penny",
        seed,
        packing(ContainerConfig::Box { size: (L, L, L) }, n),
        vec![material("solid", LAMBDA, 1000.0, 1000.0)],
        ThermalConfig {
            initial_temperature: 0.0,
            bcs: vec![wall(FaceConfig::YMin, 0.0), wall(FaceConfig::YMax, 1.0)],
            sources: Vec::new(),
            solver: ThermalSolverConfig::Steady,
            checkpoint: None,
        },
    );
    s.outputs.etc_axis = Some(AxisConfig::Y);
    s
}

/// `cfg` with one crack.
fn with_crack(cfg: &SceneConfig, crack: CrackConfig) -> SceneConfig {
    let mut c = cfg.clone();
    c.cracks = vec![crack];
    c
}

fn penny(a: f64) -> CrackConfig {
    CrackConfig::Disc {
        centre: (0.5 * L, 0.5 * L, 0.5 * L),
        normal: (0.0, 1.0, 0.0),
        radius: a,
        gap_conductance: None,
        gap_electric_resistance: None,
    }
}

fn through() -> CrackConfig {
    let y = 0.5 * L;
    CrackConfig::Polygon {
        points: vec![
            (-L, y, -L),
            (2.0 * L, y, -L),
            (2.0 * L, y, 2.0 * L),
            (-L, y, 2.0 * L),
        ],
        gap_conductance: None,
        gap_electric_resistance: None,
    }
}

/// The jump read on one crack.
#[derive(Debug, Clone)]
struct Jump {
    /// Contacts cut.
    cut: usize,
    /// Σ[T]_k / Σ[T]_ref,k − 1.
    mean_error: f64,
    /// Per band of r/a: (mean measured, mean reference), both over the centre jump 4qa/(πλ).
    bands: Vec<(f64, f64)>,
    /// Q/Q₀ (the crack's share of the flow).
    flow_ratio: f64,
}

/// A model of the cracked network: a surface model, and for the Laguerre cells whether the
/// crack cuts whole facets (the segment rule) or the part of each facet it covers.
#[derive(Debug, Clone, Copy, PartialEq)]
struct CrackModel {
    surface: Surface,
    whole_facets: bool,
    /// The Laguerre cells follow the crack's faces (`phase_rule: Conforming`, seed pairs
    /// across the disc): a model of its own per crack, built with it.
    conforming: bool,
}

impl CrackModel {
    /// The headline: the Laguerre cells following the crack's faces (issue 32, by design).
    const HEADLINE: CrackModel = CrackModel {
        surface: Surface::Laguerre,
        whole_facets: false,
        conforming: true,
    };
    /// The headline before the conforming cells: the covered part of each facet cut.
    const COVERED: CrackModel = CrackModel {
        surface: Surface::Laguerre,
        whole_facets: false,
        conforming: false,
    };
    /// Every model run, the headline first; the contact models have no facets (segment rule).
    const ALL: [CrackModel; 5] = [
        Self::HEADLINE,
        Self::COVERED,
        CrackModel {
            surface: Surface::Laguerre,
            whole_facets: true,
            conforming: false,
        },
        CrackModel {
            surface: Surface::Terreros,
            whole_facets: true,
            conforming: false,
        },
        CrackModel {
            surface: Surface::Calibrated,
            whole_facets: true,
            conforming: false,
        },
    ];

    fn id(self) -> String {
        if self.conforming {
            return "laguerre_conforming".into();
        }
        match (self.surface, self.whole_facets) {
            (Surface::Laguerre, true) => "laguerre_whole_facets".into(),
            (s, _) => s.id().into(),
        }
    }

    fn label(self) -> String {
        if self.conforming {
            return "Laguerre, conforming cells".into();
        }
        match (self.surface, self.whole_facets) {
            (Surface::Laguerre, true) => "Laguerre, whole facets cut".into(),
            (Surface::Laguerre, false) => "Laguerre (covered part of each facet)".into(),
            (s, _) => s.label().into(),
        }
    }
}

/// One model on one packing.
struct Run {
    model: CrackModel,
    lambda_hom: f64,
    jumps: Vec<Jump>,
    /// |Q|/Q₀ with the through-section crack.
    through: f64,
    solve_s: f64,
}

/// One packing.
struct PackingRun {
    n: usize,
    /// Mean particle radius (m).
    mean_radius: f64,
    pack_s: f64,
    runs: Vec<Run>,
}

impl PackingRun {
    fn run(&self, m: CrackModel) -> &Run {
        self.runs
            .iter()
            .find(|r| r.model == m)
            .expect("every model runs on every packing")
    }
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let ladder: Vec<usize> = ctx.pick(vec![5_000, 20_000], vec![20_000, 100_000]);
    let study = Study::run(
        &ladder,
        |_| PACKINGS,
        ctx.seed,
        |n, seed, _| measure_packing(n, seed),
    )?;
    let mut out = CaseOutcome::new("crack-penny", ctx.mode);
    out.n_particles = study.packings().iter().map(|p| p.rows.n).max().unwrap_or(0);
    compare(ctx.mode, &study, &mut out);
    report(ctx, &study, &mut out)?;
    Ok(out)
}

fn measure_packing(n: usize, seed: u64) -> anyhow::Result<PackingRun> {
    let cfg = scene(n, seed);
    let contacts = model_of(&with_surface_model(&cfg, Surface::Terreros, None))?;
    let pack_s = contacts.report.pack_s;
    let c_t = calibrate_ct(&contacts)?.c_t;
    let cells = laguerre_model(&cfg, &contacts)?;
    let mut runs = Vec::new();
    for model in CrackModel::ALL {
        let s = model.surface;
        let base = if s.needs_cells() { &cells } else { &contacts };
        let cfg_s = with_surface_model(&cfg, s, Some(c_t));
        let mut solve_s = 0.0;
        // The through-section run solves to THROUGH_REL_TOL: the heat leaving a part held at
        // one temperature is the sum of its residual entries, so |Q|/Q₀ can be no smaller than
        // the solve's relative residual allows.
        let mut cfg_through = cfg_s.clone();
        cfg_through.linear_solver.rel_tol = THROUGH_REL_TOL;
        let mut flow = |cfg: &SceneConfig, model: &Model| -> anyhow::Result<(f64, RunResult)> {
            let r = run_with(cfg, model)?;
            solve_s += r.thermal.as_ref().map_or(0.0, |t| t.report.wall_s);
            let q = r
                .etc
                .as_ref()
                .ok_or_else(|| anyhow::anyhow!("the scene produced no ETC"))?
                .heat_flow_w;
            Ok((q, r))
        };
        let (q0, _) = flow(&cfg_s, base)?;
        let lambda_hom = q0 * L / (L * L);
        // The model cut by `crack`, and the uncut one whose crossing branches read the jump
        // (for the conforming cells: the same sites, the crack filled with a conductance too
        // large to matter, so that its seeds are placed and no branch is cut).
        let cut = |crack: CrackConfig| -> anyhow::Result<(Model, Option<Model>)> {
            if model.conforming {
                let conforming = |crack: CrackConfig| {
                    let mut c = with_crack(&cfg_s, crack);
                    c.phase_rule = Some(PhaseRuleConfig::Conforming);
                    model_of(&c)
                };
                let mut filled = crack.clone();
                let (CrackConfig::Disc { gap_conductance, .. }
                | CrackConfig::Polygon { gap_conductance, .. }) = &mut filled;
                *gap_conductance = Some(1e30);
                Ok((conforming(crack)?, Some(conforming(filled)?)))
            } else {
                Ok((
                    with_scene_defects_rule(base, &with_crack(&cfg_s, crack), model.whole_facets)?,
                    None,
                ))
            }
        };
        let mut jumps = Vec::new();
        for ratio in RATIOS {
            let a = ratio * L;
            let (cracked, uncut) = cut(penny(a))?;
            let (q, r) = flow(&cfg_s, &cracked)?;
            let temps = &r
                .thermal
                .as_ref()
                .ok_or_else(|| anyhow::anyhow!("no temperatures"))?
                .temperatures;
            let reader = uncut.as_ref().unwrap_or(base);
            anyhow::ensure!(
                reader.particles.len() == temps.len(),
                "the jump's reader has other sites"
            );
            jumps.push(read_jump(reader, temps, a, q / (L * L), lambda_hom, q / q0));
        }
        let (q_through, _) = flow(&cfg_through, &cut(through())?.0)?;
        runs.push(Run {
            model,
            lambda_hom,
            jumps,
            through: (q_through / q0).abs(),
            solve_s,
        });
    }
    let radii = &contacts.particles.radii;
    Ok(PackingRun {
        n: contacts.particles.len(),
        mean_radius: radii.iter().sum::<f64>() / radii.len() as f64,
        pack_s,
        runs,
    })
}

/// The jump across the crack of radius `a`, read on the contacts of the uncracked `model`
/// whose segment crosses it (the same contacts whatever rule cut them): upper minus lower
/// temperature at the crossing's radius, against (4q/(πλ))√(a² − r²).
fn read_jump(model: &Model, temps: &[f64], a: f64, q: f64, lambda: f64, flow_ratio: f64) -> Jump {
    let centre = [0.5 * L, 0.5 * L];
    let j0 = 4.0 * q * a / (std::f64::consts::PI * lambda);
    let (mut sum, mut sum_ref) = (0.0, 0.0);
    let mut bands = vec![(0.0, 0.0, 0usize); BANDS];
    let mut cut = 0;
    let disc = demcon_graph::CrackShape::Disc {
        centre: demcon_core::Vec3::new(0.5 * L, 0.5 * L, 0.5 * L),
        normal: demcon_core::Vec3::y(),
        radius: a,
    };
    for (k, pair) in model.graph.pairs.iter().enumerate() {
        let from = model.particles.centres[pair[0] as usize];
        let Some(point) = disc.crossing(&from, &(from + model.graph.branch(k))) else {
            continue;
        };
        let [p, q_] = pair.map(|i| i as usize);
        let (lo, hi) = if model.particles.centres[p].y < model.particles.centres[q_].y {
            (p, q_)
        } else {
            (q_, p)
        };
        let jump = temps[hi] - temps[lo];
        let r = ((point[0] - centre[0]).powi(2) + (point[2] - centre[1]).powi(2)).sqrt();
        let reference = j0 * (1.0 - (r / a).powi(2)).max(0.0).sqrt();
        sum += jump;
        sum_ref += reference;
        let b = ((r / a) * BANDS as f64).floor().min(BANDS as f64 - 1.0) as usize;
        bands[b].0 += jump / j0;
        bands[b].1 += reference / j0;
        bands[b].2 += 1;
        cut += 1;
    }
    Jump {
        cut,
        mean_error: sum / sum_ref - 1.0,
        bands: bands
            .into_iter()
            .map(|(m, r, k)| {
                if k == 0 {
                    (f64::NAN, f64::NAN)
                } else {
                    (m / k as f64, r / k as f64)
                }
            })
            .collect(),
        flow_ratio,
    }
}

/// |mean jump error| of `s` at crack `i` over the packings of N = `n`.
fn spread(study: &Study<PackingRun>, n: usize, s: CrackModel, i: usize) -> Spread {
    study.spread(n, |p| p.run(s).jumps[i].mean_error.abs())
}

fn ratio_key(r: f64) -> String {
    format!("a_over_l_1_{}", (1.0 / r).round() as u32)
}

fn compare(mode: crate::Mode, study: &Study<PackingRun>, out: &mut CaseOutcome) {
    let ladder = study.sizes();
    let mut by_model = Map::new();
    for s in CrackModel::ALL {
        let mut cracks = Map::new();
        for (i, &r) in RATIOS.iter().enumerate() {
            let by_n: Map<String, Value> = ladder
                .iter()
                .map(|&n| (n.to_string(), spread(study, n, s, i).json()))
                .collect();
            cracks.insert(ratio_key(r), Value::Object(by_n));
        }
        by_model.insert(s.id(), Value::Object(cracks));
    }
    out.metric("mean_jump_abs_rel_error_by_model", Value::Object(by_model));
    let largest = study.largest();
    let (tol_jump, why) = match mode {
        crate::Mode::Full => (
            FULL_JUMP,
            "[T](r) = (4q/(πλ))√(a² − r²) (infinite body); issue 32's 5 % at 10⁵",
        ),
        crate::Mode::Quick => (
            TOL_JUMP,
            "[T](r) = (4q/(πλ))√(a² − r²); the a-priori 20 % (missed before the conforming cells: a 40 % regression \
             bound was gated since)",
        ),
    };
    for (i, &r) in RATIOS.iter().enumerate() {
        let e = spread(study, largest, CrackModel::HEADLINE, i);
        out.metric(&format!("mean_jump_rel_error_{}", ratio_key(r)), e.max);
        out.compare(Comparison::at_most(
            &format!(
                "{} (the headline), a/L = 1/{}, N = {largest}: max over {} packings of |mean \
                 jump / (8qa/(3πλ)) − 1| (contact-averaged)",
                CrackModel::HEADLINE.label(),
                (1.0 / r).round(),
                e.count
            ),
            e.max,
            tol_jump,
            why,
        ));
    }
    for (i, &r) in RATIOS.iter().enumerate() {
        let x = study.spread(largest, |p| {
            p.run(CrackModel::HEADLINE).jumps[i].mean_error * r * L / p.mean_radius
        });
        out.metric(
            &format!("laguerre_excess_radius_in_mean_radii_{}", ratio_key(r)),
            x.json(),
        );
    }
    for s in CrackModel::ALL {
        let t = Spread::of(study.packings().iter().map(|p| p.rows.run(s).through));
        out.metric(&format!("through_crack_flow_ratio_{}", s.id()), t.json());
        out.compare(Comparison::at_most(
            &format!(
                "{}, a crack across the whole section: max over {} packings of |Q|/Q₀",
                s.label(),
                t.count
            ),
            t.max,
            TOL_THROUGH,
            "no branch joins the two halves: no heat at all",
        ));
    }
    out.reference(
        "source",
        "penny crack in an infinite body, far-field flux q normal to it: [T](r) = (4q/(πλ))√(a² − r²) \
         (refs/analytic.md §8)",
    );
}

/// A line of the summary table.
struct Summary<'a> {
    n: usize,
    model: CrackModel,
    i: usize,
    packings: Vec<&'a PackingRun>,
}

impl Summary<'_> {
    fn jumps(&self) -> impl Iterator<Item = &Jump> + '_ {
        self.packings.iter().map(|p| &p.run(self.model).jumps[self.i])
    }
}

/// The tables, the notes and the profile chart.
fn report(ctx: &Ctx, study: &Study<PackingRun>, out: &mut CaseOutcome) -> anyhow::Result<()> {
    out.tables.push(jump_table(study));
    out.tables.push(packings_table(study));
    run_notes(ctx, study, out);
    profile_chart(ctx, study, out)
}

/// The jump per N, model and a/L: mean jump per packing, the profile in bands, the excess.
fn jump_table(study: &Study<PackingRun>) -> Table {
    let lines: Vec<Summary> = study
        .sizes()
        .iter()
        .flat_map(|&n| {
            CrackModel::ALL.iter().flat_map(move |&s| {
                (0..RATIOS.len()).map(move |i| Summary {
                    n,
                    model: s,
                    i,
                    packings: study.at(n).collect(),
                })
            })
        })
        .collect();
    Columns::new()
            .column("N", |l: &Summary| l.n.to_string())
            .column("model", |l| l.model.label())
            .column("a/L", |l| format!("1/{}", (1.0 / RATIOS[l.i]).round()))
            .column("cut contacts (mean)", |l| {
                format!("{:.0}", l.jumps().map(|j| j.cut as f64).sum::<f64>() / l.packings.len() as f64)
            })
            .column("mean jump − 1 (per packing)", |l| {
                l.jumps()
                    .map(|j| format!("{:+.1} %", 100.0 * j.mean_error))
                    .collect::<Vec<_>>()
                    .join(" / ")
            })
            .columns_for(
                0..BANDS,
                |b| format!("r/a ∈ [{:.1}, {:.1}): [T]/J₀ (ref)", *b as f64 / BANDS as f64, (*b + 1) as f64 / BANDS as f64),
                |b, l: &Summary| {
                    let k = l.packings.len() as f64;
                    let m = l.jumps().map(|j| j.bands[*b].0).sum::<f64>() / k;
                    let r = l.jumps().map(|j| j.bands[*b].1).sum::<f64>() / k;
                    format!("{m:.3} ({r:.3})")
                },
            )
            .column("jump excess as a radius, (mean error)·a/R̄", |l| {
                let k = l.packings.len() as f64;
                let x = l
                    .packings
                    .iter()
                    .map(|p| p.run(l.model).jumps[l.i].mean_error * RATIOS[l.i] * L / p.mean_radius)
                    .sum::<f64>();
                format!("{:.2}", x / k)
            })
            .column("Q/Q₀", |l| {
                format!("{:.4}", l.jumps().map(|j| j.flow_ratio).sum::<f64>() / l.packings.len() as f64)
            })
            .table(
                "Penny crack: the jump across its faces against (4q/(πλ))√(a² − r²), J₀ = 4qa/(πλ) (profile: mean \
                 over the cut contacts of each band, then over the packings)",
                &lines,
            )
}

/// λ_hom, the through-section flow and the cost of every model on every packing.
fn packings_table(study: &Study<PackingRun>) -> Table {
    let rows: Vec<&Measured<PackingRun>> = study.packings().iter().collect();
    Columns::new()
        .column("N", |p: &&Measured<PackingRun>| p.rows.n.to_string())
        .column("packing", |p| (p.k + 1).to_string())
        .columns_for(
            CrackModel::ALL,
            |s| format!("{}: λ_hom, |Q|/Q₀ through-section, solves (s)", s.id()),
            |s, p: &&Measured<PackingRun>| {
                let r = p.rows.run(*s);
                format!("{:.4} / {:.1e} / {:.2}", r.lambda_hom, r.through, r.solve_s)
            },
        )
        .column("packing (s)", |p| format!("{:.2}", p.rows.pack_s))
        .table("Every packing", &rows)
}

/// The run's sizes and this run's largest jump errors and excesses; the method is in the
/// case's notes file.
fn run_notes(ctx: &Ctx, study: &Study<PackingRun>, out: &mut CaseOutcome) {
    out.note(format!(
        "{} mode: N = {:?}, {PACKINGS} packings each (seeds {}…{}). Method, reference and tolerances: \
         validation/notes/crack-penny.md.",
        ctx.mode.name(),
        study.sizes(),
        ctx.seed,
        ctx.seed + PACKINGS - 1,
    ));
    let largest = study.largest();
    let worst = |m: CrackModel| {
        RATIOS
            .iter()
            .enumerate()
            .map(|(i, _)| spread(study, largest, m, i).max)
            .map(|e| format!("{:.0} %", 100.0 * e))
            .collect::<Vec<_>>()
            .join(" / ")
    };
    let excess = |m: CrackModel| {
        let xs: Vec<f64> = study
            .at(largest)
            .flat_map(|p| {
                RATIOS
                    .iter()
                    .enumerate()
                    .map(|(i, r)| p.run(m).jumps[i].mean_error * r * L / p.mean_radius)
            })
            .collect();
        let (lo, hi) = xs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            });
        format!("{lo:.1}–{hi:.1}")
    };
    let whole = CrackModel::ALL[2];
    out.note(format!(
        "Headline (conforming cells): largest mean-jump error {} (a/L = 1/8, 1/6, 1/4) at N = {largest}; the finite \
         cube's own excess (continuum) is +1.9 / +2.0 / +4.1 %.",
        worst(CrackModel::HEADLINE),
    ));
    out.note(format!(
        "At N = {largest} the largest mean-jump error over the packings is {} (a/L = 1/8, 1/6, 1/4) with the covered part \
         of each facet cut, {} with whole facets cut; read as a radius, (mean jump error)·a ≈ {} mean particle radii \
         ({} with whole facets).",
        worst(CrackModel::COVERED),
        worst(whole),
        excess(CrackModel::COVERED),
        excess(whole),
    ));
}

/// The profile: band means over the packings of the largest N against the formula.
fn profile_chart(ctx: &Ctx, study: &Study<PackingRun>, out: &mut CaseOutcome) -> anyhow::Result<()> {
    let largest = study.largest();
    let whole = CrackModel::ALL[2];
    let at_largest: Vec<&PackingRun> = study.at(largest).collect();
    let band_series = |m: CrackModel, i: usize| {
        let points = (0..BANDS)
            .filter_map(|b| {
                let xs: Vec<f64> = at_largest
                    .iter()
                    .map(|p| p.run(m).jumps[i].bands[b].0)
                    .filter(|x| x.is_finite())
                    .collect();
                (!xs.is_empty()).then(|| {
                    (
                        (b as f64 + 0.5) / BANDS as f64,
                        xs.iter().sum::<f64>() / xs.len() as f64,
                    )
                })
            })
            .collect();
        Series::markers(
            &format!("{}, a/L = 1/{}", m.label(), (1.0 / RATIOS[i]).round()),
            points,
        )
    };
    let mut series: Vec<Series> = (0..RATIOS.len())
        .map(|i| band_series(CrackModel::HEADLINE, i))
        .chain(std::iter::once(band_series(whole, 0)))
        .collect();
    series.push(Series::line(
        "(4q/(πλ))√(a² − r²) over 4qa/(πλ)",
        (0..=50)
            .map(|k| {
                let x = k as f64 / 50.0;
                (x, (1.0 - x * x).sqrt())
            })
            .collect(),
    ));
    draw(
        &Chart {
            title: format!(
                "Penny crack: jump across the faces over 4qa/(πλ), N = {largest}, mean of the packings"
            ),
            x_label: "r/a (band centres)".into(),
            y_label: "[T] / (4qa/(πλ))".into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            series,
        },
        &ctx.out.join("crack-penny.png"),
    )?;
    out.charts.push("crack-penny.png".into());
    Ok(())
}
