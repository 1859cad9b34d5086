//! Criterion benchmarks of the network solvers: the explicit heat step (contacts/s, Morton
//! vs random particle order) against a STREAM-like triad, the steady heat solve, and the
//! electric solve with Jacobi-, MIC- and multigrid-preconditioned CG and sparse Cholesky, over a size ladder.
//!
//! Networks are packing-like random geometric graphs built here (Poisson points of unit
//! density, links within r = 1.214, mean coordination ≈ 7.5), so the benchmark does not
//! depend on the packing crate. Run one group with e.g.
//! `cargo bench -p demcon-benches --bench solvers -- explicit_step`.
//! Before the groups, a one-off measurement prints the explicit step's effective bandwidth
//! as a fraction of the triad's (f64 and f32 weights), `explicit_accuracy/summary` what f32
//! weights change (energy drift, temperature difference over a long adiabatic run), and each solve case prints its iterations, setup and solve
//! times once. With `DEMCON_BENCH_SUMMARY_ONLY=1` only these one-off lines are produced
//! (no criterion sampling), which is how the 10⁶-particle figures are taken quickly.
//! `DEMCON_BENCH_SEED=k` builds every random network with its seed shifted by k: other
//! realisations for figures over several networks. `DEMCON_BENCH_REPEAT=k` measures and
//! prints each solve case's line k times on the same network.
//!
//! The electric paper's own case is benchmarked too (`electric_cylinder`): an LS packing of
//! 5000 particles in the cylinder r = 1 mm, l = 5 mm (Gaussian radii, CoV 0.3), contacts for
//! Z = 7.5, Terreros α surfaces, AISI 304L, the particles touching the end faces held at
//! 1 V and 0 V — the network the `electric-solver-timing` validation case times.

use std::hint::black_box;
use std::time::Instant;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use demcon_benches::{summary_only, summary_repeats, wanted};
use demcon_core::mem::huge_filled;
use demcon_core::{Container, Face, Selector, Vec3, morton_order};
use demcon_electric::{ElectricParams, ElectricSolution, solve_potential};
use demcon_graph::{ContactParams, SurfaceModel, conductances, contact_surfaces, detect_contacts};
use demcon_network::{
    Constraints, FloatingPolicy, LinearSystem, Method, Network, SolveParams, resolve_fixed, solve_steady,
};
use demcon_thermal::{ExplicitStepper, ThermalSystem, WeightPrecision};
use rand::seq::SliceRandom;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Link distance for a mean coordination of 7.5 at unit density: 4/3 π r³ = 7.5.
const LINK: f64 = 1.2143;

/// A packing-like network of `n` nodes: node ids in Morton order, or randomly permuted.
struct Case {
    net: Network,
    g: Vec<f64>,
    caps: Vec<f64>,
    /// Nodes with x < 1 and x > L − 1 (the two "electrodes"/fixed faces).
    faces: [Vec<u32>; 2],
}

fn build(n: usize, random_order: bool, seed: u64) -> Case {
    // `DEMCON_BENCH_SEED=k` shifts every case's network seed by k (other realisations of
    // the same network class; 0 by default).
    let shift = std::env::var("DEMCON_BENCH_SEED").map_or(0, |v| v.parse::<u64>().unwrap_or(0));
    let mut rng = ChaCha8Rng::seed_from_u64(seed + shift);
    let l = (n as f64).cbrt();
    let pts: Vec<Vec3> = (0..n)
        .map(|_| {
            Vec3::new(
                rng.random::<f64>() * l,
                rng.random::<f64>() * l,
                rng.random::<f64>() * l,
            )
        })
        .collect();
    let bounds = demcon_core::Aabb {
        min: Vec3::zeros(),
        max: Vec3::new(l, l, l),
    };
    let mut order: Vec<u32> = morton_order(&pts, &bounds);
    if random_order {
        order.shuffle(&mut rng);
    }
    let pts: Vec<Vec3> = order.iter().map(|&i| pts[i as usize]).collect();
    // Cell grid of size LINK.
    let m = ((l / LINK).floor() as usize).max(1);
    let cell = |p: &Vec3| -> [usize; 3] { [0, 1, 2].map(|a| ((p[a] / l * m as f64) as usize).min(m - 1)) };
    let mut heads = vec![u32::MAX; m * m * m];
    let mut next = vec![u32::MAX; n];
    for (i, p) in pts.iter().enumerate() {
        let [a, b, c] = cell(p);
        let k = (a * m + b) * m + c;
        next[i] = heads[k];
        heads[k] = i as u32;
    }
    let mut edges = Vec::new();
    for (i, p) in pts.iter().enumerate() {
        let [a, b, c] = cell(p);
        for da in a.saturating_sub(1)..=(a + 1).min(m - 1) {
            for db in b.saturating_sub(1)..=(b + 1).min(m - 1) {
                for dc in c.saturating_sub(1)..=(c + 1).min(m - 1) {
                    let mut j = heads[(da * m + db) * m + dc];
                    while j != u32::MAX {
                        if (j as usize) > i && (pts[j as usize] - p).norm() < LINK {
                            edges.push([i as u32, j]);
                        }
                        j = next[j as usize];
                    }
                }
            }
        }
    }
    let g = edges
        .iter()
        .map(|&[p, q]| 1.0 / (pts[p as usize] - pts[q as usize]).norm().max(0.1))
        .collect();
    let caps = (0..n).map(|_| rng.random_range(0.5..2.0)).collect();
    let lo = pts
        .iter()
        .enumerate()
        .filter(|(_, p)| p.x < 1.0)
        .map(|(i, _)| i as u32)
        .collect();
    let hi = pts
        .iter()
        .enumerate()
        .filter(|(_, p)| p.x > l - 1.0)
        .map(|(i, _)| i as u32)
        .collect();
    Case {
        net: Network::new(n, &edges).expect("valid generated network"),
        g,
        caps,
        faces: [lo, hi],
    }
}

fn constraints(case: &Case) -> Constraints {
    resolve_fixed(
        &case.net,
        &[(case.faces[0].clone(), 0.0), (case.faces[1].clone(), 1.0)],
        FloatingPolicy::Exclude,
    )
    .expect("two non-empty faces")
}

/// STREAM triad a = b + s c over `len` doubles; returns GB/s (24 bytes per element).
fn triad_gbs(len: usize, reps: usize) -> f64 {
    let b = vec![1.0f64; len];
    let c = vec![2.0f64; len];
    let mut a = vec![0.0f64; len];
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let t = Instant::now();
        triad(&mut a, &b, &c, 3.0);
        best = best.min(t.elapsed().as_secs_f64());
    }
    black_box(&a);
    24.0 * len as f64 / best / 1e9
}

fn triad(a: &mut [f64], b: &[f64], c: &[f64], s: f64) {
    use rayon::prelude::*;
    a.par_chunks_mut(1 << 16)
        .zip(b.par_chunks(1 << 16))
        .zip(c.par_chunks(1 << 16))
        .for_each(|((a, b), c)| {
            for ((x, y), z) in a.iter_mut().zip(b).zip(c) {
                *x = y + s * z;
            }
        });
}

fn stepper<'a>(case: &'a Case, bcs: &'a Constraints, precision: WeightPrecision) -> ExplicitStepper<'a> {
    let system = ThermalSystem::new(&case.net, &case.g, &case.caps, bcs).expect("valid inputs");
    let dt = system.stable_dt_bound().dt_max;
    let zeros = vec![0.0; case.net.n_nodes()];
    ExplicitStepper::with_precision(&system, &zeros, 0.8 * dt, precision).expect("valid inputs")
}

/// One-off: what f32 conductances change. Adiabatic walls (no fixed node), no source,
/// temperatures drawn in [250, 350] K, `steps` steps at 0.8 of the bound with each
/// precision: the relative drift of Σ C_p T_p for each, and the largest |T_f32 − T_f64|.
fn accuracy_summary(n: usize, steps: usize) {
    let case = build(n, false, 1);
    let bcs = resolve_fixed(&case.net, &[], FloatingPolicy::Keep).expect("no fixed node");
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let t0: Vec<f64> = (0..n).map(|_| rng.random_range(250.0..350.0)).collect();
    let energy = |t: &[f64]| t.iter().zip(&case.caps).map(|(t, c)| t * c).sum::<f64>();
    let e0 = energy(&t0);
    let mut finals = Vec::new();
    for precision in [WeightPrecision::F64, WeightPrecision::F32] {
        let st = stepper(&case, &bcs, precision);
        let (mut a, mut b) = (t0.clone(), vec![0.0; n]);
        for _ in 0..steps {
            st.step(&a, &mut b);
            std::mem::swap(&mut a, &mut b);
        }
        let (lo, hi) = a.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
        println!(
            "explicit accuracy n = {n}, {steps} steps, {precision:?} weights: relative drift of sum C T {:.1e}, T now in [{lo:.3}, {hi:.3}] K",
            (energy(&a) - e0) / e0
        );
        finals.push(a);
    }
    let diff = finals[0]
        .iter()
        .zip(&finals[1])
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    println!(
        "explicit accuracy n = {n}, {steps} steps: max |T_f32 - T_f64| = {diff:.2e} K (initial spread 100 K)"
    );
}

/// One-off: effective bandwidth of the explicit step vs the triad, printed.
fn bandwidth_summary() {
    let gbs = triad_gbs(1 << 24, 10);
    println!("triad bandwidth: {gbs:.2} GB/s (3 x 128 MiB arrays, best of 10)");
    for (n, random) in [(100_000, false), (1_000_000, false), (1_000_000, true)] {
        let case = build(n, random, 1);
        let bcs = constraints(&case);
        for precision in [WeightPrecision::F64, WeightPrecision::F32] {
            let st = stepper(&case, &bcs, precision);
            // In huge pages, as `run_explicit` allocates them.
            let mut a = huge_filled(n, 0.5);
            let mut b = huge_filled(n, 0.0);
            let mut best = f64::INFINITY;
            for _ in 0..30 {
                let t = Instant::now();
                black_box(st.step(&a, &mut b));
                best = best.min(t.elapsed().as_secs_f64());
                std::mem::swap(&mut a, &mut b);
            }
            let eff = st.bytes_per_step() / best / 1e9;
            println!(
                "explicit step n = {n} ({}, {precision:?} weights), {} contacts: {:.3} ms (best of 30), {:.0} M contacts/s, {:.1} B/contact, {:.2} GB/s = {:.0} % of triad",
                if random { "random order" } else { "Morton order" },
                case.net.n_edges(),
                best * 1e3,
                case.net.n_edges() as f64 / best / 1e6,
                st.bytes_per_step() / case.net.n_edges() as f64,
                eff,
                100.0 * eff / gbs
            );
        }
    }
}

fn bench_triad(c: &mut Criterion) {
    if wanted("stream_triad/summary") {
        bandwidth_summary();
    }
    if wanted("explicit_accuracy/summary") {
        accuracy_summary(100_000, 5000);
        accuracy_summary(1_000_000, 500);
    }
    let len = 1 << 24;
    let b = vec![1.0f64; len];
    let cc = vec![2.0f64; len];
    let mut a = vec![0.0f64; len];
    let mut group = c.benchmark_group("stream_triad");
    group.sample_size(20);
    group.throughput(Throughput::Bytes(24 * len as u64));
    group.bench_function("16M", |bch| bch.iter(|| triad(&mut a, &b, &cc, 3.0)));
    group.finish();
}

fn bench_explicit(c: &mut Criterion) {
    let mut group = c.benchmark_group("explicit_step");
    group.sample_size(20);
    for n in [100_000usize, 1_000_000] {
        for (label, random, precision) in [
            ("morton", false, WeightPrecision::F64),
            ("random", true, WeightPrecision::F64),
            ("morton-f32", false, WeightPrecision::F32),
        ] {
            if !wanted(&format!("explicit_step/{label}/{n}")) {
                continue;
            }
            let case = build(n, random, 1);
            let bcs = constraints(&case);
            let st = stepper(&case, &bcs, precision);
            // In huge pages, as `run_explicit` allocates them.
            let mut a = huge_filled(n, 0.5);
            let mut b = huge_filled(n, 0.0);
            // Elements = contacts, so criterion reports contacts per second.
            group.throughput(Throughput::Elements(case.net.n_edges() as u64));
            group.bench_with_input(BenchmarkId::new(label, n), &n, |bch, _| {
                bch.iter(|| {
                    black_box(st.step(&a, &mut b));
                    std::mem::swap(&mut a, &mut b);
                })
            });
        }
    }
    group.finish();
}

const JACOBI: SolveParams = SolveParams::new(Method::Cg, 1e-8, 100_000);
const MIC: SolveParams = SolveParams::new(Method::IcCg, 1e-8, 20_000);
const AMG: SolveParams = SolveParams::new(Method::AmgCg, 1e-8, 10_000);
const CHOLESKY: SolveParams = SolveParams::new(Method::Cholesky, 1e-8, 1);

fn bench_steady(c: &mut Criterion) {
    let mut group = c.benchmark_group("steady_solve");
    group.sample_size(10);
    for n in [10_000usize, 100_000] {
        if !["jacobi-pcg", "amg-pcg"]
            .iter()
            .any(|m| wanted(&format!("steady_solve/{m}/{n}")))
        {
            continue;
        }
        let case = build(n, false, 2);
        let bcs = constraints(&case);
        let q = vec![0.0; n];
        for method in [JACOBI, AMG] {
            if !wanted(&format!("steady_solve/{}/{n}", method.method.name())) {
                continue;
            }
            let p = method;
            for _ in 0..summary_repeats() {
                let r = solve_steady(&case.net, &case.g, &bcs, &q, &p).expect("converges");
                println!(
                    "steady n = {n}, {} contacts, {}: {} iterations, residual {:.1e}, setup {:.4} s, solve {:.4} s",
                    case.net.n_edges(),
                    method.method.name(),
                    r.report.iterations,
                    r.report.relative_residual,
                    r.report.setup_s,
                    r.report.wall_s
                );
            }
            if let Some(info) = LinearSystem::new(&case.net, &case.g, None, &bcs, &p)
                .expect("valid system")
                .amg_info()
            {
                println!(
                    "  {} hierarchy (rows, nnz): {:?}, operator complexity {:.2}, grid complexity {:.2}",
                    info.cycle,
                    info.levels.iter().map(|l| (l.rows, l.nnz)).collect::<Vec<_>>(),
                    info.operator_complexity,
                    info.grid_complexity
                );
            }
            if summary_only() {
                continue;
            }
            group.bench_with_input(BenchmarkId::new(method.method.name(), n), &n, |bch, _| {
                bch.iter(|| solve_steady(&case.net, &case.g, &bcs, &q, &p).expect("converges"))
            });
        }
    }
    group.finish();
}

/// The one-off line of an electric solve: contacts, method, iterations, residual, setup and
/// solve times (s), resistance (Ω).
fn electric_line(label: &str, net: &Network, method: SolveParams, r: &ElectricSolution) -> String {
    format!(
        "{label}, {} contacts, {}: {} iterations, residual {:.1e}, setup {:.4} s, solve {:.4} s, R = {:.6e} ohm",
        net.n_edges(),
        method.method.name(),
        r.report.iterations,
        r.report.relative_residual,
        r.report.setup_s,
        r.report.wall_s,
        r.resistance_ohm.unwrap_or(f64::NAN),
    )
}

fn bench_electric(c: &mut Criterion) {
    let mut group = c.benchmark_group("electric_solve");
    group.sample_size(10);
    let ladder: [(usize, &[SolveParams]); 3] = [
        (5_000, &[JACOBI, MIC, AMG, CHOLESKY]),
        (100_000, &[JACOBI, MIC, AMG, CHOLESKY]),
        (1_000_000, &[JACOBI, AMG]),
    ];
    for (n, methods) in ladder {
        if !methods
            .iter()
            .any(|m| wanted(&format!("electric_solve/{}/{n}", m.method.name())))
        {
            continue;
        }
        let case = build(n, false, 3);
        let electrodes = [(case.faces[0].clone(), 1.0), (case.faces[1].clone(), 0.0)];
        for &method in methods {
            if !wanted(&format!("electric_solve/{}/{n}", method.method.name())) {
                continue;
            }
            let p = ElectricParams {
                floating: FloatingPolicy::Exclude,
                solve: method,
            };
            for _ in 0..summary_repeats() {
                let r = solve_potential(&case.net, &case.g, &electrodes, &p).expect("solves");
                let line = electric_line(&format!("electric n = {n}"), &case.net, method, &r);
                println!("{line}, in/out mismatch {:.1e}", r.current_mismatch);
            }
            if summary_only() {
                continue;
            }
            group.bench_with_input(BenchmarkId::new(method.method.name(), n), &n, |bch, _| {
                bch.iter(|| solve_potential(&case.net, &case.g, &electrodes, &p).expect("solves"))
            });
        }
    }
    group.finish();
}

/// The electric paper's 5000-particle cylinder (see the module documentation): network,
/// branch conductances (S) and the two electrode sets.
fn cylinder_case() -> (Network, Vec<f64>, [Vec<u32>; 2]) {
    let container = Container::Cylinder {
        radius: 1e-3,
        length: 5e-3,
    };
    let params = demcon_packing::PackingParams::new(
        container,
        5000,
        0.64,
        demcon_packing::RadiusDistribution::gaussian(0.3),
    );
    // A cylinder ~13 mean radii wide jams below 0.64 (wall layers): the jammed state is used.
    // `pack` returns the particles in Morton order.
    let (set, _) = demcon_packing::pack(&params, 1, None).expect("packs");
    let graph = detect_contacts(&set, &container, &ContactParams::target(7.5)).expect("contacts");
    let s = contact_surfaces(&graph, &set, &SurfaceModel::TerrerosAlpha).expect("surfaces");
    let sigma = vec![1.0 / 0.73e-6; graph.pairs.len()];
    let g = conductances(&graph, &s.area, &sigma).expect("conductances");
    let net = Network::new(set.len(), &graph.pairs).expect("network");
    let face = |f: Face| {
        Selector::Face(f)
            .select_nonempty(&set, &container, f.name())
            .expect("electrode")
    };
    (net, g, [face(Face::ZMin), face(Face::ZMax)])
}

fn bench_electric_cylinder(c: &mut Criterion) {
    let methods = [JACOBI, MIC, CHOLESKY];
    if !methods
        .iter()
        .any(|m| wanted(&format!("electric_cylinder/{}/5000", m.method.name())))
    {
        return;
    }
    let (net, g, [lo, hi]) = cylinder_case();
    let electrodes = [(hi, 1.0), (lo, 0.0)];
    let mut group = c.benchmark_group("electric_cylinder");
    group.sample_size(20);
    for method in methods {
        if !wanted(&format!("electric_cylinder/{}/5000", method.method.name())) {
            continue;
        }
        let p = ElectricParams {
            floating: FloatingPolicy::Exclude,
            solve: method,
        };
        let r = solve_potential(&net, &g, &electrodes, &p).expect("solves");
        let label = format!("electric cylinder n = {}", net.n_nodes());
        println!("{}", electric_line(&label, &net, method, &r));
        if summary_only() {
            continue;
        }
        group.bench_with_input(BenchmarkId::new(method.method.name(), 5000), &5000, |bch, _| {
            bch.iter(|| solve_potential(&net, &g, &electrodes, &p).expect("solves"))
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    bench_triad,
    bench_explicit,
    bench_steady,
    bench_electric,
    bench_electric_cylinder
);
criterion_main!(benches);
