//! Test packings made without demcon-packing (a sibling crate): a jittered FCC lattice with
//! Gaussian-ish radii, random sequential addition, and a brute-force O(N²) contact finder.
#![allow(dead_code)]

use demcon_core::{ParticleSet, Vec3};
use demcon_graph::relative_gap;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Standard normal sample (Box–Muller).
fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let u: f64 = rng.random::<f64>().max(1e-300);
    let v: f64 = rng.random();
    (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
}

/// FCC lattice of `m³` cubic cells (4 particles each, nearest-neighbour distance 1 m),
/// centres jittered by up to ±0.02 m per axis, radii ~ N(0.42, 0.03) m clipped to
/// [0.3, 0.465] so that no two spheres overlap. Box size `m·√2` (m) per axis.
pub fn jittered_fcc(m: usize, seed: u64) -> (ParticleSet, f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let a = std::f64::consts::SQRT_2;
    let jitter = 0.02;
    let rmax = 0.5 - 3f64.sqrt() * jitter;
    let basis = [[0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]];
    let mut centres = Vec::new();
    let mut radii = Vec::new();
    for i in 0..m {
        for j in 0..m {
            for k in 0..m {
                for b in basis {
                    let mut c = Vec3::new(
                        (i as f64 + b[0] + 0.25) * a,
                        (j as f64 + b[1] + 0.25) * a,
                        (k as f64 + b[2] + 0.25) * a,
                    );
                    for x in c.iter_mut() {
                        *x += jitter * (2.0 * rng.random::<f64>() - 1.0);
                    }
                    centres.push(c);
                    radii.push((0.42 + 0.03 * gauss(&mut rng)).clamp(0.3, rmax));
                }
            }
        }
    }
    (ParticleSet::new(centres, radii).unwrap(), m as f64 * a)
}

/// Random sequential addition of `n` non-overlapping spheres, radii uniform in
/// [0.02, 0.04] m, centres uniform in `[0, size]³` (overlap tested with the minimum image
/// when `periodic`). Size 1 m gives φ ≈ 0.18 at n = 1200.
pub fn rsa(n: usize, size: f64, periodic: bool, seed: u64) -> ParticleSet {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut centres: Vec<Vec3> = Vec::new();
    let mut radii: Vec<f64> = Vec::new();
    let period = periodic.then_some([size; 3]);
    let mut attempts = 0;
    while centres.len() < n {
        attempts += 1;
        assert!(attempts < 1000 * n, "RSA could not place {n} spheres");
        let r = 0.02 + 0.02 * rng.random::<f64>();
        let c = if periodic {
            Vec3::new(rng.random(), rng.random(), rng.random()) * size
        } else {
            Vec3::new(rng.random(), rng.random(), rng.random()) * (size - 2.0 * r) + Vec3::repeat(r)
        };
        let free = centres
            .iter()
            .zip(&radii)
            .all(|(o, ro)| min_image(&c, o, period).norm() >= r + ro);
        if free {
            centres.push(c);
            radii.push(r);
        }
    }
    ParticleSet::new(centres, radii).unwrap()
}

/// Vector from `a` to `b` (m), minimum image by rounding (independent of the crate's code).
pub fn min_image(a: &Vec3, b: &Vec3, period: Option<[f64; 3]>) -> Vec3 {
    let mut d = b - a;
    if let Some(l) = period {
        for k in 0..3 {
            d[k] -= l[k] * (d[k] / l[k]).round();
        }
    }
    d
}

/// Every pair p < q with relative gap ≤ `eps`, with its centre distance (m), by testing all
/// N(N−1)/2 pairs.
pub fn brute_force(p: &ParticleSet, period: Option<[f64; 3]>, eps: f64) -> Vec<([u32; 2], f64)> {
    let mut out = Vec::new();
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let d = min_image(&p.centres[i], &p.centres[j], period).norm();
            if relative_gap(d, p.radii[i], p.radii[j]) <= eps {
                out.push(([i as u32, j as u32], d));
            }
        }
    }
    out
}
