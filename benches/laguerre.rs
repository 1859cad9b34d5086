//! The Laguerre tessellation (`demcon_graph::tessellate`) at 10⁵ and 10⁶ particles, in a
//! walled box and in a periodic box (the target is 10⁶ particles in under 10 s on this
//! 2-core machine), and the periodic homogenisation of the resulting network at 10⁵ (three
//! load cases on one matrix: `demcon_network::homogenize`, default AMG-PCG to 1e-10).
//!
//! Test set: the jittered FCC lattice of the `contacts` benchmark (`demcon_benches::jittered_fcc`),
//! whose cells are all alike; an LSA packing's cells vary more (Gaussian radii), see
//! `docs/laguerre.md` for the figures measured on those.
//!
//! `conforming`: the conforming seeds (`demcon_graph::conforming_sites`) for a simple-cubic
//! array of 27 spheres at f = 0.3 in the periodic box of the 10⁵ test set, alone and with the
//! tessellation of the sites they leave — beside `laguerre/periodic/100000`, the same box
//! without them (docs/performance.md, "Conforming cells").
//!
//! Run: `cargo bench -p demcon-benches --bench laguerre`.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use demcon_benches::jittered_fcc;
use demcon_core::Container;
use demcon_core::Vec3;
use demcon_graph::{
    Body, ConformParams, Followed, LaguerreParams, SphereSurface, conforming_sites, tessellate,
};
use demcon_network::{Method, Network, SolveParams, homogenize};

fn laguerre(c: &mut Criterion) {
    let mut group = c.benchmark_group("laguerre");
    group.sample_size(10);
    for n in [100_000usize, 1_000_000] {
        let (p, container) = jittered_fcc(n, 42);
        let Container::Box { size } = container else {
            unreachable!("jittered_fcc builds a box")
        };
        let cases = [("box", container), ("periodic", Container::Periodic { size })];
        for (name, cont) in cases {
            if n == 1_000_000 && name == "periodic" {
                continue;
            }
            group.bench_with_input(BenchmarkId::new(name, p.len()), &p, |b, p| {
                b.iter(|| black_box(tessellate(p, &cont, None, &LaguerreParams::default()).unwrap()))
            });
        }
    }
    group.finish();
}

/// The jittered FCC test set of `n` particles in a periodic box: particles, box size (m), box.
fn periodic_fcc(n: usize) -> (demcon_core::ParticleSet, [f64; 3], Container) {
    let (p, container) = jittered_fcc(n, 42);
    let Container::Box { size } = container else {
        unreachable!("jittered_fcc builds a box")
    };
    (p, size, Container::Periodic { size })
}

fn homogenisation(c: &mut Criterion) {
    let mut group = c.benchmark_group("homogenize");
    group.sample_size(10);
    let (p, size, periodic) = periodic_fcc(100_000);
    let g = tessellate(&p, &periodic, None, &LaguerreParams::default()).unwrap();
    let cells = g.cells.as_ref().unwrap();
    let cond: Vec<f64> = (0..g.len())
        .map(|k| cells.facet_area[k] / g.geometry[k].distance)
        .collect();
    let branches: Vec<_> = (0..g.len()).map(|k| g.branch(k)).collect();
    let net = Network::new(p.len(), &g.pairs).unwrap();
    let params = SolveParams::new(Method::Auto, 1e-10, 10_000);
    let volume = size[0] * size[1] * size[2];
    group.bench_function(BenchmarkId::new("laguerre-periodic", p.len()), |b| {
        b.iter(|| black_box(homogenize(&net, &cond, &branches, volume, &params).unwrap()))
    });
    group.finish();
}

fn conforming(c: &mut Criterion) {
    let mut group = c.benchmark_group("conforming");
    group.sample_size(10);
    let (p, size, periodic) = periodic_fcc(100_000);
    // A 3 × 3 × 3 simple-cubic array of spheres filling 30 % of the box.
    let a = size[0] / 3.0;
    let radius = a * (0.3 * 3.0 / (4.0 * std::f64::consts::PI)).cbrt();
    let spheres: Vec<SphereSurface> = (0..27)
        .map(|k| SphereSurface {
            centre: Vec3::new(
                (k % 3) as f64 + 0.5,
                ((k / 3) % 3) as f64 + 0.5,
                (k / 9) as f64 + 0.5,
            ) * a,
            radius,
        })
        .collect();
    let h = (size[0] * size[1] * size[2] / p.len() as f64).cbrt();
    let params = ConformParams::default();
    let body = Body {
        container: &periodic,
        carve: None,
    };
    group.bench_function(BenchmarkId::new("sites", p.len()), |b| {
        b.iter(|| {
            black_box(
                conforming_sites(
                    &p,
                    body,
                    Followed {
                        spheres: &spheres,
                        ..Followed::default()
                    },
                    h,
                    &params,
                )
                .unwrap(),
            )
        })
    });
    group.bench_function(BenchmarkId::new("sites+tessellation", p.len()), |b| {
        b.iter(|| {
            let c = conforming_sites(
                &p,
                body,
                Followed {
                    spheres: &spheres,
                    ..Followed::default()
                },
                h,
                &params,
            )
            .unwrap();
            black_box(tessellate(&c.particles, &periodic, None, &LaguerreParams::default()).unwrap())
        })
    });
    group.finish();
}

criterion_group!(benches, laguerre, homogenisation, conforming);
criterion_main!(benches);
