//! Test sets shared by the integration tests: seeded lattices of spheres and their contacts.
#![allow(dead_code)]

pub mod vtk_reader;

use demcon_core::{ParticleSet, Vec3};

/// Deterministic pseudo-random numbers in [0, 1) (SplitMix64).
pub struct Mix(pub u64);

impl Mix {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A simple cubic lattice of `n³` spheres of radius `r` (spacing 2r) filling `[0, 2nr]³`, with
/// its nearest-neighbour contacts and branch vectors.
pub fn cubic(n: usize, r: f64) -> (ParticleSet, Vec<[u32; 2]>, Vec<Vec3>) {
    let d = 2.0 * r;
    let id = |i: usize, j: usize, k: usize| (i * n * n + j * n + k) as u32;
    let mut centres = Vec::new();
    let mut pairs = Vec::new();
    let mut branches = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                centres.push(Vec3::new(i as f64, j as f64, k as f64) * d + Vec3::repeat(r));
                for (di, dj, dk, e) in [(1, 0, 0, Vec3::x()), (0, 1, 0, Vec3::y()), (0, 0, 1, Vec3::z())] {
                    if i + di < n && j + dj < n && k + dk < n {
                        pairs.push([id(i, j, k), id(i + di, j + dj, k + dk)]);
                        branches.push(e * d);
                    }
                }
            }
        }
    }
    (
        ParticleSet::new(centres, vec![r; n * n * n]).unwrap(),
        pairs,
        branches,
    )
}

/// `m³` spheres on a unit lattice in `[0, m]³`, each centre jittered by up to ±0.15, radii
/// 0.5 × (1 + 0.3 g) with g roughly standard normal, clipped to [0.2, 0.8].
pub fn jittered(m: usize, seed: u64) -> ParticleSet {
    let mut rng = Mix(seed);
    let mut c = Vec::with_capacity(m * m * m);
    let mut r = Vec::with_capacity(m * m * m);
    for i in 0..m {
        for j in 0..m {
            for k in 0..m {
                let jit = Vec3::new(rng.next(), rng.next(), rng.next()) * 0.3 - Vec3::repeat(0.15);
                c.push(Vec3::new(i as f64, j as f64, k as f64) + Vec3::repeat(0.5) + jit);
                let g = (0..12).map(|_| rng.next()).sum::<f64>() - 6.0;
                r.push((0.5 * (1.0 + 0.3 * g)).clamp(0.2, 0.8));
            }
        }
    }
    ParticleSet::new(c, r).unwrap()
}
