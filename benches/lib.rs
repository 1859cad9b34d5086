//! Shared helpers of the criterion benchmarks (the benchmarks themselves are `[[bench]]` targets).

use demcon_core::{Container, ParticleSet, Vec3};

/// SplitMix64: a small seeded generator, enough for jitter, radii and random vectors of the
/// benchmark test sets (the same stream for the same seed on every machine).
#[derive(Debug, Clone)]
pub struct SplitMix(pub u64);

impl SplitMix {
    /// A uniform number in [0, 1) (53 random bits).
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A standard normal number (Box–Muller, cosine branch).
    pub fn gauss(&mut self) -> f64 {
        let u = self.next_f64().max(1e-300);
        let v = self.next_f64();
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// A jittered FCC lattice of about `n` particles and its walled box: nearest-neighbour
/// distance 1 m, centres jittered by ±0.01 m per axis, radii N(0.47, 0.015) m clipped to
/// [0.40, 0.4827] m so that no spheres overlap.
pub fn jittered_fcc(n: usize, seed: u64) -> (ParticleSet, Container) {
    let m = ((n as f64 / 4.0).cbrt().round() as usize).max(1);
    let a = std::f64::consts::SQRT_2;
    let jitter = 0.01;
    let rmax = 0.5 - 3f64.sqrt() * jitter;
    let mut rng = SplitMix(seed);
    let basis = [[0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]];
    let mut centres = Vec::with_capacity(4 * m * m * m);
    let mut radii = Vec::with_capacity(4 * m * m * m);
    for i in 0..m {
        for j in 0..m {
            for k in 0..m {
                for b in basis {
                    let mut c = Vec3::new(
                        i as f64 + b[0] + 0.25,
                        j as f64 + b[1] + 0.25,
                        k as f64 + b[2] + 0.25,
                    ) * a;
                    for x in c.iter_mut() {
                        *x += jitter * (2.0 * rng.next_f64() - 1.0);
                    }
                    centres.push(c);
                    radii.push((0.47 + 0.015 * rng.gauss()).clamp(0.4, rmax));
                }
            }
        }
    }
    let size = m as f64 * a;
    (
        ParticleSet::new(centres, radii).unwrap(),
        Container::Box { size: [size; 3] },
    )
}

/// Whether criterion's name filter (the first positional argument, a regex; matched here
/// as `|`-separated plain substrings, a trailing `$` anchoring one at the end, e.g.
/// `contacts/grid/1000000$`) selects `id`, so that unselected cases are neither built nor
/// summarised.
pub fn wanted(id: &str) -> bool {
    let filter = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-') && a != "--bench");
    filter.is_none_or(|f| {
        f.split('|').any(|part| {
            part.strip_suffix('$')
                .map_or(id.contains(part), |p| id.ends_with(p))
        })
    })
}

/// Whether only the one-off summary lines are wanted (`DEMCON_BENCH_SUMMARY_ONLY=1`): no
/// criterion sampling.
pub fn summary_only() -> bool {
    std::env::var("DEMCON_BENCH_SUMMARY_ONLY").is_ok_and(|v| v == "1")
}

/// How many times each one-off summary line is measured and printed
/// (`DEMCON_BENCH_REPEAT=k`, default 1): repeated solves on the network already built, so
/// that a comparison of two binaries on a busy host rests on several samples per process.
pub fn summary_repeats() -> usize {
    std::env::var("DEMCON_BENCH_REPEAT")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .map_or(1, |k| k.max(1))
}
