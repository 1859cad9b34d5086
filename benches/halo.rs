//! demcon-post over a size ladder: the Halo smoothing at k = 11 (10⁵ and 10⁶ particles; k = 4
//! at 10⁶ for comparison) and the raw-appended VTU writer at 10⁶ particles.
//!
//! Test set (demcon-post may not depend on the packing crate): a simple cubic lattice of
//! spacing 1 m, centres jittered by ±0.15 m per axis, Gaussian radii of mean 0.494 m and
//! std/mean 0.3 clipped to [0.1, 2] × mean — the mean radius that gives φ ≈ 0.64 at this
//! number density, so a k = 11 halo holds ~850 particles as in an LSA packing. Dipoles are
//! seeded random vectors, representative volumes `V_p/0.64`. Ids follow the lattice
//! (spatially ordered, as after a Morton renumbering). Sizes: 46³ = 97 336 and 100³ = 10⁶.
//!
//! Run: `cargo bench -p demcon-benches --bench halo`.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use demcon_benches::SplitMix;
use demcon_core::{Container, ParticleSet, Vec3};
use demcon_post::{Domain, Field, HaloParams, HaloPhases, halo_flux, write_vtu};

/// `m³` particles, their dipoles (W·m), representative volumes (m³) and walled box.
fn test_set(m: usize, seed: u64) -> (ParticleSet, Vec<Vec3>, Vec<f64>, Container) {
    let mean = 0.494;
    let mut rng = SplitMix(seed);
    let n = m * m * m;
    let mut centres = Vec::with_capacity(n);
    let mut radii = Vec::with_capacity(n);
    for i in 0..m {
        for j in 0..m {
            for k in 0..m {
                let mut c = Vec3::new(i as f64, j as f64, k as f64) + Vec3::repeat(0.5);
                for x in c.iter_mut() {
                    *x += 0.3 * rng.next_f64() - 0.15;
                }
                centres.push(c);
                radii.push((mean * (1.0 + 0.3 * rng.gauss())).clamp(0.1 * mean, 2.0 * mean));
            }
        }
    }
    let dipoles = (0..n)
        .map(|_| Vec3::new(rng.gauss(), rng.gauss(), rng.gauss()))
        .collect();
    let vrep = radii
        .iter()
        .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r * r * r / 0.64)
        .collect();
    let p = ParticleSet::new(centres, radii).expect("valid test set");
    (p, dipoles, vrep, Container::Box { size: [m as f64; 3] })
}

fn halo(c: &mut Criterion) {
    let mut g = c.benchmark_group("halo");
    g.sample_size(10);
    for (m, ks) in [(46usize, &[11.0][..]), (100, &[4.0, 11.0][..])] {
        let (p, d, v, container) = test_set(m, 42);
        let domain = Domain::of_container(&container).expect("valid box");
        g.throughput(Throughput::Elements(p.len() as u64));
        for &k in ks {
            let params = HaloParams::ratio(k);
            let r = halo_flux(&p, &d, &v, &domain, &params).expect("halo");
            eprintln!("halo k={k} N={}: {:?}", p.len(), r.report);
            g.bench_function(BenchmarkId::new(format!("k{k}"), p.len()), |b| {
                b.iter(|| black_box(halo_flux(&p, &d, &v, &domain, &params).expect("halo")))
            });
        }
        if m == 46 {
            // The default Halo tests each member's phase (one phase here, same result); the
            // all-phases Halo skips the test: their ratio is the cost of the phase test.
            let all = HaloParams {
                phases: HaloPhases::All,
                ..HaloParams::ratio(11.0)
            };
            g.bench_function(BenchmarkId::new("k11-all-phases", p.len()), |b| {
                b.iter(|| black_box(halo_flux(&p, &d, &v, &domain, &all).expect("halo")))
            });
        }
    }
    g.finish();
}

fn vtu(c: &mut Criterion) {
    let mut g = c.benchmark_group("vtu");
    g.sample_size(10);
    let (p, d, v, _) = test_set(100, 7);
    let t: Vec<f64> = p.centres.iter().map(|c| 20.0 + c.x).collect();
    let flags: Vec<i32> = (0..p.len()).map(|i| (i % 2) as i32).collect();
    let fields = [
        Field::scalars("temperature", &t),
        Field::vectors("flux", &d),
        Field::vectors("halo_flux", &d),
        Field::scalars("rep_volume", &v),
        Field::ints("truncated", &flags),
    ];
    let dir = std::env::temp_dir().join(format!("demcon-bench-vtu-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("particles.vtu");
    let bytes = write_vtu(&path, &p, &fields).expect("write");
    eprintln!("vtu N={}: {bytes} bytes", p.len());
    g.throughput(Throughput::Bytes(bytes));
    g.bench_function(BenchmarkId::new("write", p.len()), |b| {
        b.iter(|| black_box(write_vtu(&path, &p, &fields).expect("write")))
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, halo, vtu);
criterion_main!(benches);
