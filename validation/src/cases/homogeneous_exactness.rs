//! `homogeneous-exactness` — ours (issue 10 §4): the effective conductivity of a HOMOGENEOUS
//! body, λ_e/λ − 1, for each transmission-surface model. A continuum answers exactly 0; what a
//! model gives instead is a bias it carries into every case, before any interface or
//! transient enters.
//!
//! Geometries, steady state, temperatures held on two opposite faces through wall
//! half-contacts (`WallTemperature`), every other surface adiabatic, λ_e = (Q/A) L / ΔT from the
//! heat flow Q out of the hot face:
//! - the cube of the composite cases (L = 0.1 m), along x, y and z in turn;
//! - the cylinder of the electric cases (r = 1 mm, l = 5 mm), along its axis (faces ZMin,
//!   ZMax; the curved mantle adiabatic).
//!
//! Models, all on the same packings: calibrated C_t π R_m² with C_t calibrated on THAT packing
//! by the paper's protocol (flux on the top face, the particles touching the bottom held,
//! `calibrate_ct`; a calibration with the faces held through wall links along the measured
//! axis would give 0 by construction — an identity, not a measurement — so it is not used);
//! Terreros α; Laguerre cells. ≥ 3 packings (seeds) per geometry; the figures are the mean and
//! the max over them of the largest |λ_e/λ − 1| over the axes.
//!
//! Tolerance, fixed before any Laguerre number was seen (issue 10 §4): Laguerre ≤ 10⁻⁹ — its
//! network solves a linear field exactly, so what is left is the linear solver's residual.
//! In the cylinder the cells follow the curved mantle by tangent planes (to 10⁻³ of a
//! radius), so the network's section differs from π r² by a geometric amount; the exactness
//! check divides by the cells' own section (Σ of their wall facets on the hot face) and the
//! nominal λ_e/λ − 1 (over π r²) is reported beside it, with the section itself checked to
//! 10⁻³ (twice the tangent-plane tolerance times R/r, a bound chosen a priori). The two
//! contact models are reported, not judged: their bias is the finding.
//!
//! Periodic part ([`measure_periodic`]): on a periodic packing of the same size, the
//! homogenised tensor (`solver: Homogenize`, three load cases) of each model; the error is the
//! largest of its nine entries, max |Λ_ij/λ − δ_ij|. The calibrated model takes the C_t of the
//! cube packings of the same seeds (a C_t calibrated on the periodic packing by homogenisation
//! would make the mean of the diagonal exact by construction: an identity, not a
//! measurement). The Laguerre tolerance is the same 10⁻⁹, chosen with the others.
//!
//! Set-up, models and tolerances, as documentation: `validation/notes/homogeneous-exactness.md`.

use std::time::Instant;

use demcon_scene::config::*;
use serde_json::{Map, Value};

use super::common::*;
use super::cylinder::{RADIUS, cylinder_packing};
use super::study::{Measured as Packing, Study};
use crate::table::Columns;
use crate::{CaseOutcome, Comparison, Ctx, Table};

/// Conductivity (W/(m·K)) of the homogeneous material (Haddad 2021 Table 1 steel).
const LAMBDA: f64 = 33.0;
/// Cube edge (m).
const L: f64 = 0.1;
/// Laguerre: largest accepted |λ_e/λ − 1| (over the cells' own section).
const TOL_LAGUERRE: f64 = 1e-9;
/// Laguerre cylinder: largest accepted |A_cells/(π r²) − 1|.
const TOL_SECTION: f64 = 1e-3;
/// Independent packings per geometry.
const PACKINGS: u64 = 3;
/// Cold and hot face temperatures (°C).
const T_COLD: f64 = 0.0;
const T_HOT: f64 = 1.0;

/// The two geometries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Geometry {
    Cube,
    Cylinder,
}

/// An axis of a run: its name for the ETC and its two faces (cold, hot).
struct AxisFaces {
    axis: AxisConfig,
    cold: FaceConfig,
    hot: FaceConfig,
    name: &'static str,
    /// 0, 1, 2 for x, y, z.
    index: usize,
}

const X: AxisFaces = AxisFaces {
    axis: AxisConfig::X,
    cold: FaceConfig::XMin,
    hot: FaceConfig::XMax,
    name: "x",
    index: 0,
};
const Y: AxisFaces = AxisFaces {
    axis: AxisConfig::Y,
    cold: FaceConfig::YMin,
    hot: FaceConfig::YMax,
    name: "y",
    index: 1,
};
const Z: AxisFaces = AxisFaces {
    axis: AxisConfig::Z,
    cold: FaceConfig::ZMin,
    hot: FaceConfig::ZMax,
    name: "z",
    index: 2,
};

impl Geometry {
    const ALL: [Geometry; 2] = [Geometry::Cube, Geometry::Cylinder];

    fn id(self) -> &'static str {
        match self {
            Geometry::Cube => "box",
            Geometry::Cylinder => "cylinder",
        }
    }

    /// The axes it runs along.
    fn axes(self) -> &'static [AxisFaces] {
        match self {
            Geometry::Cube => &[X, Y, Z],
            Geometry::Cylinder => &[Z],
        }
    }

    /// The steady scene along `axis` with the contact surfaces (calibrated at `Auto`).
    fn scene(self, n: usize, seed: u64, axis: &AxisFaces) -> SceneConfig {
        let packing = match self {
            Geometry::Cube => packing(ContainerConfig::Box { size: (L, L, L) }, n),
            Geometry::Cylinder => cylinder_packing(n),
        };
        let mut s = thermal_scene(
            "homogeneous-exactness",
            seed,
            packing,
            vec![table1_steel()],
            ThermalConfig {
                initial_temperature: T_COLD,
                bcs: vec![wall(axis.cold, T_COLD), wall(axis.hot, T_HOT)],
                sources: Vec::new(),
                solver: ThermalSolverConfig::Steady,
                checkpoint: None,
            },
        );
        s.outputs.etc_axis = Some(axis.axis);
        s
    }

    /// The nominal section normal to the axes it runs along (m²).
    fn section(self) -> f64 {
        match self {
            Geometry::Cube => L * L,
            Geometry::Cylinder => std::f64::consts::PI * RADIUS * RADIUS,
        }
    }
}

/// One model on one packing.
struct ModelRun {
    surface: Surface,
    /// λ_e/λ − 1 along each axis, over the nominal section.
    errors: Vec<f64>,
    /// Laguerre: λ_e/λ − 1 along each axis over the cells' own section (else = `errors`).
    exact: Vec<f64>,
    /// Laguerre: A_cells/A − 1 on the hot face of each axis (else 0).
    section: Vec<f64>,
    /// Network (contacts or tessellation), calibration and solves (s).
    network_s: f64,
    calibration_s: f64,
    solve_s: f64,
}

impl ModelRun {
    fn max_abs(v: &[f64]) -> f64 {
        v.iter().map(|e| e.abs()).fold(0.0, f64::max)
    }

    /// Model-specific cost (s): network, calibration, solves (the packing is shared).
    fn wall_s(&self) -> f64 {
        self.network_s + self.calibration_s + self.solve_s
    }
}

/// One packing of one geometry.
struct PackingRun {
    geometry: Geometry,
    n: usize,
    phi: f64,
    c_t: f64,
    pack_s: f64,
    /// Laguerre tessellation: Σ V_cells / V − 1, dropped facets, cells on curved walls.
    volume_error: f64,
    dropped_facets: usize,
    curved_cells: usize,
    /// Laguerre: facets found by one cell only, the largest |S_p − S_q|/S of a facet seen
    /// from its two cells, and the largest closure defect over the axes run
    /// ([`closure_defect`]).
    one_sided: usize,
    area_mismatch: f64,
    closure: f64,
    runs: Vec<ModelRun>,
}

impl PackingRun {
    fn run(&self, s: Surface) -> &ModelRun {
        self.runs
            .iter()
            .find(|r| r.surface == s)
            .expect("every model runs on every packing")
    }
}

/// Everything the case measures.
struct Measured {
    n: usize,
    /// The packings of each geometry, in [`Geometry::ALL`] order.
    studies: Vec<(Geometry, Study<PackingRun>)>,
    periodic: Vec<PeriodicRun>,
}

impl Measured {
    fn of(&self, g: Geometry) -> impl Iterator<Item = &PackingRun> {
        self.studies
            .iter()
            .filter(move |(h, _)| *h == g)
            .flat_map(|(_, s)| s.at(self.n))
    }

    /// Every packing, geometry by geometry.
    fn packings(&self) -> impl Iterator<Item = &Packing<PackingRun>> {
        self.studies.iter().flat_map(|(_, s)| s.packings())
    }

    /// Mean and max over the packings of `g` of `f(run of s)`.
    fn spread(&self, g: Geometry, s: Surface, f: fn(&ModelRun) -> f64) -> Spread {
        Spread::of(self.of(g).map(|p| f(p.run(s))))
    }
}

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let m = measure(ctx)?;
    let mut out = CaseOutcome::new("homogeneous-exactness", ctx.mode);
    out.n_particles = m.packings().map(|p| p.rows.n).max().unwrap_or(0);
    compare(&m, &mut out);
    report(ctx, &m, &mut out);
    Ok(out)
}

/// Every geometry, every packing, every model.
fn measure(ctx: &Ctx) -> anyhow::Result<Measured> {
    let n = ctx.pick(10_000, 100_000);
    let mut scenes: Vec<SceneConfig> = Geometry::ALL
        .iter()
        .flat_map(|g| (0..PACKINGS).map(move |k| g.scene(n, ctx.seed + k, &g.axes()[0])))
        .collect();
    scenes.extend((0..PACKINGS).map(|k| periodic_scene(n, ctx.seed + k)));
    prepack(&scenes)?;
    let mut studies = Vec::new();
    for g in Geometry::ALL {
        let study = Study::run(
            &[n],
            |_| PACKINGS,
            ctx.seed,
            |n, seed, _| measure_packing(g, n, seed),
        )?;
        studies.push((g, study));
    }
    let seeds: Vec<(u64, f64)> = studies
        .iter()
        .filter(|(g, _)| *g == Geometry::Cube)
        .flat_map(|(_, s)| s.packings())
        .map(|p| (ctx.seed + p.k, p.rows.c_t))
        .collect();
    let periodic = measure_periodic(n, &seeds)?;
    Ok(Measured { n, studies, periodic })
}

/// One packing: its contact model (calibrated and Terreros) and its Laguerre model.
fn measure_packing(g: Geometry, n: usize, seed: u64) -> anyhow::Result<PackingRun> {
    let axes = g.axes();
    let contacts = model_of(&g.scene(n, seed, &axes[0]))?;
    let pack_s = contacts.report.pack_s;
    let cells = laguerre_model(&g.scene(n, seed, &axes[0]), &contacts)?;
    let t1 = Instant::now();
    let c_t = calibrate_ct(&contacts)?.c_t;
    let calibration_s = t1.elapsed().as_secs_f64();
    let mut runs = Vec::new();
    for s in Surface::ALL {
        let model = if s.needs_cells() { &cells } else { &contacts };
        let mut r = ModelRun {
            surface: s,
            errors: Vec::new(),
            exact: Vec::new(),
            section: Vec::new(),
            network_s: network_s(model),
            calibration_s: if s == Surface::Calibrated {
                calibration_s
            } else {
                0.0
            },
            solve_s: 0.0,
        };
        for axis in axes {
            let cfg = with_surface_model(&g.scene(n, seed, axis), s, Some(c_t));
            let res = run_with(&cfg, model)?;
            let etc = res
                .etc
                .as_ref()
                .ok_or_else(|| anyhow::anyhow!("the scene produced no ETC"))?;
            r.solve_s += res.thermal.as_ref().map_or(0.0, |t| t.report.wall_s);
            let e = etc.lambda_e / LAMBDA - 1.0;
            // The cells' own section on the hot face: the network's A (Laguerre only).
            let a = wall_facet_area(model, axis.hot).unwrap_or(etc.area_m2);
            r.errors.push(e);
            r.exact.push((1.0 + e) * etc.area_m2 / a - 1.0);
            r.section.push(a / g.section() - 1.0);
        }
        runs.push(r);
    }
    let t = cells.report.tessellation.as_ref();
    Ok(PackingRun {
        geometry: g,
        n: contacts.particles.len(),
        phi: contacts.phi,
        c_t,
        pack_s,
        volume_error: t.map_or(f64::NAN, |t| t.volume_error),
        dropped_facets: t.map_or(0, |t| t.dropped_facets),
        curved_cells: t.map_or(0, |t| t.curved_cells),
        one_sided: t.map_or(0, |t| t.one_sided_facets),
        area_mismatch: t.map_or(f64::NAN, |t| t.max_area_mismatch),
        closure: axes
            .iter()
            .filter_map(|a| closure_defect(&cells, a.index))
            .fold(0.0, f64::max),
        runs,
    })
}

/// The largest |λ_e/λ − 1| over the axes (nominal section).
fn worst(r: &ModelRun) -> f64 {
    ModelRun::max_abs(&r.errors)
}

/// The same over the cells' own section.
fn worst_exact(r: &ModelRun) -> f64 {
    ModelRun::max_abs(&r.exact)
}

/// The largest |A_cells/A − 1|.
fn worst_section(r: &ModelRun) -> f64 {
    ModelRun::max_abs(&r.section)
}

/// Metrics (mean and max over the packings, per geometry and model) and the Laguerre checks.
fn compare(m: &Measured, out: &mut CaseOutcome) {
    for g in Geometry::ALL {
        let by_model = |f: fn(&ModelRun) -> f64| -> Value {
            Value::Object(
                Surface::ALL
                    .iter()
                    .map(|&s| (s.id().to_string(), m.spread(g, s, f).json()))
                    .collect::<Map<String, Value>>(),
            )
        };
        out.metric(&format!("max_abs_error_{}", g.id()), by_model(worst));
        out.metric(&format!("wall_s_{}", g.id()), by_model(ModelRun::wall_s));
        out.metric(
            &format!("laguerre_exact_error_{}", g.id()),
            m.spread(g, Surface::Laguerre, worst_exact).json(),
        );
        out.metric(
            &format!("laguerre_section_error_{}", g.id()),
            m.spread(g, Surface::Laguerre, worst_section).json(),
        );
        out.metric(
            &format!("laguerre_volume_error_{}", g.id()),
            Spread::of(m.of(g).map(|p| p.volume_error.abs())).json(),
        );
        out.metric(
            &format!("laguerre_closure_defect_{}", g.id()),
            Spread::of(m.of(g).map(|p| p.closure)).json(),
        );
        out.metric(
            &format!("laguerre_facet_area_mismatch_{}", g.id()),
            Spread::of(m.of(g).map(|p| p.area_mismatch)).json(),
        );
        out.metric(
            &format!("c_t_{}", g.id()),
            Spread::of(m.of(g).map(|p| p.c_t)).json(),
        );
    }
    out.reference("max_abs_error_box", 0.0);
    out.reference("max_abs_error_cylinder", 0.0);
    out.reference(
        "source",
        "a homogeneous continuum: λ_e = λ exactly (issue 10 §4; DESIGN.md §1, the Laguerre model)",
    );
    for g in Geometry::ALL {
        let e = m.spread(g, Surface::Laguerre, worst_exact);
        out.compare(Comparison::at_most(
            &format!(
                "Laguerre, {}: max over {} packings of max |λ_e/λ − 1|{}",
                g.id(),
                e.count,
                if g == Geometry::Cylinder {
                    " (over the cells' section)"
                } else {
                    " (x, y, z)"
                }
            ),
            e.max,
            TOL_LAGUERRE,
            "exact for a linear field: solver residual only",
        ));
    }
    for sf in Surface::ALL {
        let e = Spread::of(m.periodic.iter().map(|p| p.of(sf).0));
        out.metric(&format!("max_abs_error_periodic_{}", sf.id()), e.json());
        out.metric(
            &format!("wall_s_periodic_{}", sf.id()),
            Spread::of(m.periodic.iter().map(|p| p.of(sf).2)).json(),
        );
        if sf == Surface::Laguerre {
            out.compare(Comparison::at_most(
                &format!(
                    "Laguerre, periodic: max over {} packings of max |Λ_ij/λ − δ_ij| (nine entries)",
                    e.count
                ),
                e.max,
                TOL_LAGUERRE,
                "exact for a linear field: Σ S d n nᵀ = V I over the periodic cells",
            ));
        }
    }
    let sec = m.spread(Geometry::Cylinder, Surface::Laguerre, worst_section);
    out.compare(Comparison::at_most(
        "Laguerre, cylinder: max |A_cells/(π r²) − 1| (tangent planes on the mantle)",
        sec.max,
        TOL_SECTION,
        "curved_tolerance 10⁻³ R: area excess ≤ 2·10⁻³ R/r",
    ));
}

/// One packing of the periodic part: each model's tensor error and cost.
struct PeriodicRun {
    k: u64,
    n: usize,
    /// (model, max |Λ_ij/λ − δ_ij| over the nine entries, symmetry error, cost (s)).
    runs: Vec<(Surface, f64, f64, f64)>,
}

impl PeriodicRun {
    fn of(&self, s: Surface) -> (f64, f64, f64) {
        let r = self
            .runs
            .iter()
            .find(|r| r.0 == s)
            .expect("every model runs on every packing");
        (r.1, r.2, r.3)
    }
}

/// The periodic part: per packing, the homogenised tensor of each model.
fn measure_periodic(n: usize, seeds: &[(u64, f64)]) -> anyhow::Result<Vec<PeriodicRun>> {
    let mut out = Vec::new();
    for (k, &(seed, c_t)) in seeds.iter().enumerate() {
        let cfg = periodic_scene(n, seed);
        let contacts = model_of(&with_surface_model(&cfg, Surface::Terreros, None))?;
        let cells = laguerre_model(&cfg, &contacts)?;
        let mut runs = Vec::new();
        for s in Surface::ALL {
            let model = if s.needs_cells() { &cells } else { &contacts };
            let res = run_with(&with_surface_model(&cfg, s, Some(c_t)), model)?;
            let t = res
                .homogenization
                .as_ref()
                .and_then(|h| h.thermal.as_ref())
                .ok_or_else(|| anyhow::anyhow!("the homogenisation produced no tensor"))?;
            let mut err: f64 = 0.0;
            for (i, row) in t.report.tensor.iter().enumerate() {
                for (j, v) in row.iter().enumerate() {
                    let delta = if i == j { 1.0 } else { 0.0 };
                    err = err.max((v / LAMBDA - delta).abs());
                }
            }
            runs.push((
                s,
                err,
                t.report.symmetry_error,
                network_s(model) + t.report.wall_s,
            ));
        }
        out.push(PeriodicRun {
            k: k as u64,
            n: contacts.particles.len(),
            runs,
        });
    }
    Ok(out)
}

/// The periodic homogenisation scene: a cube of edge L, steel, no boundary condition.
fn periodic_scene(n: usize, seed: u64) -> SceneConfig {
    thermal_scene(
        "homogeneous-exactness-periodic",
        seed,
        packing(ContainerConfig::Periodic { size: (L, L, L) }, n),
        vec![table1_steel()],
        ThermalConfig {
            initial_temperature: T_COLD,
            bcs: Vec::new(),
            sources: Vec::new(),
            solver: ThermalSolverConfig::Homogenize,
            checkpoint: None,
        },
    )
}

/// A line of the per-packing table.
struct Line<'a> {
    p: &'a Packing<PackingRun>,
    r: &'a ModelRun,
}

/// A line of the summary table.
struct Summary {
    geometry: Geometry,
    surface: Surface,
    error: Spread,
    wall_s: Spread,
}

/// Tables and notes.
fn report(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) {
    out.tables.push(summary_table(m));
    out.tables.push(packings_table(m));
    run_notes(ctx, m, out);
    out.tables.push(periodic_table(m));
}

/// λ_e/λ − 1 per geometry and model: mean and max over the packings, with the wall time.
fn summary_table(m: &Measured) -> Table {
    let summary: Vec<Summary> = Geometry::ALL
        .iter()
        .flat_map(|&g| {
            Surface::ALL.iter().map(move |&s| Summary {
                geometry: g,
                surface: s,
                error: m.spread(g, s, worst),
                wall_s: m.spread(g, s, ModelRun::wall_s),
            })
        })
        .collect();
    Columns::new()
        .column("geometry", |l: &Summary| l.geometry.id().to_string())
        .column("model", |l| l.surface.label().to_string())
        .column("mean |λ_e/λ − 1|", |l| format!("{:.3e}", l.error.mean))
        .column("max |λ_e/λ − 1|", |l| format!("{:.3e}", l.error.max))
        .column("packings", |l| l.error.count.to_string())
        .column("wall time (s), mean / max", |l| {
            format!("{:.2} / {:.2}", l.wall_s.mean, l.wall_s.max)
        })
        .table(
            format!(
                "λ_e/λ − 1 of a homogeneous body, N = {} (largest over the axes, then mean and max over the \
                     packings; nominal section; wall time = network + calibration + solves)",
                m.n
            ),
            &summary,
        )
}

/// Every packing and model: the error per axis (nominal and over the cells' section), the
/// cells' section, and the costs.
fn packings_table(m: &Measured) -> Table {
    let lines: Vec<Line> = m
        .packings()
        .flat_map(|p| p.rows.runs.iter().map(move |r| Line { p, r }))
        .collect();
    let axes = |l: &Line, v: &[f64]| {
        l.p.rows
            .geometry
            .axes()
            .iter()
            .zip(v)
            .map(|(a, e)| format!("{} {:+.3e}", a.name, e))
            .collect::<Vec<_>>()
            .join("; ")
    };
    Columns::new()
        .column("geometry", |l: &Line| l.p.rows.geometry.id().to_string())
        .column("packing", |l| (l.p.k + 1).to_string())
        .column("N", |l| l.p.rows.n.to_string())
        .column("φ", |l| format!("{:.4}", l.p.rows.phi))
        .column("model", |l| l.r.surface.label().to_string())
        .column("λ_e/λ − 1 (nominal section)", move |l| axes(l, &l.r.errors))
        .column("over the cells' section", move |l| {
            if l.r.surface.needs_cells() {
                axes(l, &l.r.exact)
            } else {
                String::new()
            }
        })
        .column("A_cells/A − 1", move |l| {
            if l.r.surface.needs_cells() {
                axes(l, &l.r.section)
            } else {
                String::new()
            }
        })
        .column("network (s)", |l| format!("{:.2}", l.r.network_s))
        .column("calibration (s)", |l| {
            if l.r.calibration_s > 0.0 {
                format!("{:.2} (C_t = {:.4})", l.r.calibration_s, l.p.rows.c_t)
            } else {
                String::new()
            }
        })
        .column("solves (s)", |l| format!("{:.2}", l.r.solve_s))
        .table("Every packing and model", &lines)
}

/// The run's sizes and packing time, the tessellations' checks, and the pointer to the case's
/// notes file (and, when the Laguerre cylinder misses its target, the figures of why).
fn run_notes(ctx: &Ctx, m: &Measured, out: &mut CaseOutcome) {
    let tess = |g: Geometry| {
        let ps: Vec<&PackingRun> = m.of(g).collect();
        format!(
            "{}: Σ V_cells/V − 1 up to {:.1e}, {} dropped and {} one-sided facets, facet areas seen from their two \
             cells differing by up to {:.1e} (relative), closure defect max |Σ S n·e|/Σ S {:.1e}, {} cells clipped by a \
             curved-wall plane (largest over the packings)",
            g.id(),
            ps.iter().map(|p| p.volume_error.abs()).fold(0.0, f64::max),
            ps.iter().map(|p| p.dropped_facets).max().unwrap_or(0),
            ps.iter().map(|p| p.one_sided).max().unwrap_or(0),
            ps.iter().map(|p| p.area_mismatch).fold(0.0, f64::max),
            ps.iter().map(|p| p.closure).fold(0.0, f64::max),
            ps.iter().map(|p| p.curved_cells).max().unwrap_or(0),
        )
    };
    out.note(format!(
        "{} mode: N = {} per packing, {PACKINGS} packings per geometry (seeds {}…{}); the cube along x, y and z, the \
         cylinder along its axis. Packing took {:.1} s in all (shared by the models, not in their wall time). Set-up, \
         models and tolerances: validation/notes/homogeneous-exactness.md.",
        ctx.mode.name(),
        m.n,
        ctx.seed,
        ctx.seed + PACKINGS - 1,
        m.packings().map(|p| p.rows.pack_s).sum::<f64>(),
    ));
    out.note(format!(
        "Laguerre tessellations — {}; {}.",
        tess(Geometry::Cube),
        tess(Geometry::Cylinder)
    ));
    let cyl: Vec<&PackingRun> = m.of(Geometry::Cylinder).collect();
    let exact = m.spread(Geometry::Cylinder, Surface::Laguerre, worst_exact);
    if exact.max > TOL_LAGUERRE {
        out.note(format!(
            "The Laguerre cylinder misses the 10⁻⁹ target ({:.1e} over the cells' own section): a facet near the mantle has \
             a different area seen from its two cells (up to {:.2} relative here), and the closure defect reaches {:.1e} \
             along the axis, against {:.1e} in the box (why: the notes file).",
            exact.max,
            cyl.iter().map(|p| p.area_mismatch).fold(0.0, f64::max),
            cyl.iter().map(|p| p.closure).fold(0.0, f64::max),
            m.of(Geometry::Cube).map(|p| p.closure).fold(0.0, f64::max),
        ));
    }
}

/// The periodic packings: each model's homogenised-tensor error, symmetry and cost.
fn periodic_table(m: &Measured) -> Table {
    let rows: Vec<&PeriodicRun> = m.periodic.iter().collect();
    Columns::new()
        .column("packing", |p: &&PeriodicRun| p.k.to_string())
        .column("N", |p: &&PeriodicRun| p.n.to_string())
        .columns_for(
            Surface::ALL,
            |s| format!("{} max |Λ_ij/λ − δ_ij| (symmetry, s)", s.id()),
            |s, p: &&PeriodicRun| {
                let (e, sym, t) = p.of(*s);
                format!("{e:.2e} ({sym:.0e}, {t:.2})")
            },
        )
        .table(
            "Periodic packings: the homogenised tensor of a homogeneous body (Homogenize, three load cases)",
            &rows,
        )
}
