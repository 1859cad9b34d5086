//! Lubachevsky–Stillinger packing speed: time to φ = 0.64 (or to jamming, whichever comes
//! first) and events per second, Gaussian radii (std/mean 0.3), N = 10⁴ and 10⁵, in a box
//! with hard walls and in a periodic box. Each case prints its stop reason, φ and events
//! (collisions, wall hits, neighbour-list rebuilds) per second once.
//!
//! `cargo bench -p demcon-benches --bench packing` (the 10⁵ cases take about a minute per
//! iteration; filter with `-- 10000` for the small ones).

use criterion::{Criterion, criterion_group, criterion_main};
use demcon_core::Container;
use demcon_packing::{PackingParams, RadiusDistribution, pack};

/// Edge of the cube holding `n` Gaussian-0.3 spheres of mean radius 1 at φ = 0.64.
fn edge(n: usize) -> f64 {
    let mean_r3 = 1.0 + 3.0 * 0.3f64.powi(2) * 0.911; // ⟨r³⟩ of the truncated normal
    (n as f64 * 4.0 / 3.0 * std::f64::consts::PI * mean_r3 / 0.64).cbrt()
}

fn packing(c: &mut Criterion) {
    let mut g = c.benchmark_group("pack_gaussian0.3_phi0.64");
    g.sample_size(10);
    for n in [10_000usize, 100_000] {
        let l = edge(n);
        for (name, container) in [
            ("box", Container::Box { size: [l; 3] }),
            ("periodic", Container::Periodic { size: [l; 3] }),
        ] {
            let params = PackingParams::new(container, n, 0.64, RadiusDistribution::gaussian(0.3));
            g.bench_function(format!("{name}/{n}"), |b| {
                let mut reported = false;
                b.iter(|| {
                    let (p, report) = pack(&params, 1, None).expect("packing");
                    if !reported {
                        // Deterministic: every iteration does the same events.
                        reported = true;
                        eprintln!(
                            "\n{name} N={n}: stop {:?} at φ = {:.4} (bulk {:?}), {} events, \
                             {:.3e} events/s, {:.2} s",
                            report.stop,
                            report.packing.phi,
                            report.packing.phi_bulk,
                            report.events,
                            report.events_per_s,
                            report.wall_s
                        );
                    }
                    p
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, packing);
criterion_main!(benches);
