//! One timed packing for speed and structure comparisons (Gaussian radii, cov 0.3):
//!
//! ```sh
//! cargo run --release -p demcon-packing --example pack_speed -- N [box|periodic] [PHI|auto|jam] [GROWTH] [SEED]
//! ```
//!
//! `auto` (default) is the issue-12 target φ = 0.64 − 0.5 N^(-1/3); `jam` asks for the
//! largest allowed φ, so the run stops at jamming (p* ≥ 10⁶). Prints the report, the bulk
//! coordination (neighbours closer than 1 % and 5 % of the mean radius, spheres more than two
//! mean diameters from every wall) and a hash of the packing (determinism checks). Time it
//! with `/usr/bin/time -v` for CPU seconds. With `PACK_TRACE=1`, φ, the events and p* are
//! printed to stderr every 5 s of the run (where the time goes: the start, the fast stage,
//! the approach to the target).

use demcon_core::{Container, ParticleSet, Vec3};
use demcon_packing::{MAX_PHI_ABOVE_JAMMING, PackingParams, RadiusDistribution, jamming_estimate, pack};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.first().map_or(100_000, |s| s.parse().expect("N"));
    let kind = args.get(1).map_or("box", String::as_str);
    let radii = RadiusDistribution::gaussian(0.3);
    let phi = match args.get(2).map_or("auto", String::as_str) {
        "auto" => 0.64 - 0.5 * (n as f64).powf(-1.0 / 3.0),
        "jam" => jamming_estimate(&radii) + MAX_PHI_ABOVE_JAMMING - 1e-9,
        s => s.parse().expect("PHI"),
    };
    let growth: f64 = args.get(3).map_or(0.02, |s| s.parse().expect("GROWTH"));
    let seed: u64 = args.get(4).map_or(1, |s| s.parse().expect("SEED"));
    // Mean radius 1 at φ = 0.64 (the size only scales the packing).
    let mean_r3 = 1.0 + 3.0 * 0.3f64.powi(2) * 0.911;
    let l = (n as f64 * 4.0 / 3.0 * std::f64::consts::PI * mean_r3 / 0.64).cbrt();
    let container = match kind {
        "box" => Container::Box { size: [l; 3] },
        "periodic" => Container::Periodic { size: [l; 3] },
        _ => panic!("container must be box or periodic"),
    };
    let mut params = PackingParams::new(container, n, phi, radii);
    params.growth_rate = growth;
    if let Ok(s) = std::env::var("PACK_SKIN") {
        params.neighbour_skin = s.parse().expect("PACK_SKIN");
    }
    if let Ok(s) = std::env::var("PACK_CPHI") {
        params.compression_phi = s.parse().expect("PACK_CPHI");
    }
    if let Ok(s) = std::env::var("PACK_CG") {
        params.compression_growth_rate = s.parse().expect("PACK_CG");
    }
    let last = std::cell::Cell::new(-1.0f64);
    let trace = |pr: &demcon_packing::PackProgress| {
        if pr.wall_s - last.get() >= 5.0 {
            last.set(pr.wall_s);
            eprintln!(
                "  {:7.1} s  φ {:.4}  events {:.3e}  p* {:.3e}",
                pr.wall_s, pr.phi, pr.events as f64, pr.reduced_pressure
            );
        }
    };
    let progress: Option<&dyn Fn(&demcon_packing::PackProgress)> =
        std::env::var_os("PACK_TRACE").is_some().then_some(&trace as _);
    let (p, r) = pack(&params, seed, progress).expect("packing");
    let (z1, z5) = coordination(&p, &container);
    let mut h: u64 = 0xcbf29ce484222325;
    for (c, r) in p.centres.iter().zip(&p.radii) {
        for x in [c.x, c.y, c.z, *r] {
            h = (h ^ x.to_bits()).wrapping_mul(0x100000001b3);
        }
    }
    println!(
        "N {n} {kind} seed {seed} g {growth}: stop {:?} φ {:.5} bulk {:.5} | events {} coll {} wall {} \
         stale {} rescales {} p* {:.3e} | {:.3e} ev/s loop, {:.2} s wall | z(1%) {z1:.3} z(5%) {z5:.3} | hash {h:016x}",
        r.stop,
        r.packing.phi,
        r.packing.phi_bulk.unwrap_or(f64::NAN),
        r.events,
        r.collisions,
        r.wall_collisions,
        r.stale_events,
        r.thermostat_rescales,
        r.reduced_pressure,
        r.events_per_s,
        r.wall_s,
    );
}

/// Mean number of neighbours with a gap below 1 % and 5 % of the mean radius, over the
/// spheres more than two mean diameters from every wall (all spheres when periodic).
fn coordination(p: &ParticleSet, c: &Container) -> (f64, f64) {
    let n = p.len();
    let mean = p.radii.iter().sum::<f64>() / n as f64;
    let rmax = p.radii.iter().copied().fold(0.0, f64::max);
    let b = c.bounds();
    let ext = b.extent();
    let period = c.period();
    let cell = 2.0 * rmax + 0.05 * mean;
    let m = [0, 1, 2].map(|k| ((ext[k] / cell).floor() as usize).max(1));
    let idx =
        |x: &Vec3| [0, 1, 2].map(|k| (((x[k] - b.min[k]) / ext[k] * m[k] as f64) as usize).min(m[k] - 1));
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); m[0] * m[1] * m[2]];
    for (i, x) in p.centres.iter().enumerate() {
        let q = idx(x);
        cells[(q[2] * m[1] + q[1]) * m[0] + q[0]].push(i as u32);
    }
    let margin = 4.0 * mean;
    let (mut z1, mut z5, mut count) = (0usize, 0usize, 0usize);
    for (i, x) in p.centres.iter().enumerate() {
        if period.is_none() && (0..3).any(|k| x[k] - b.min[k] < margin || b.max[k] - x[k] < margin) {
            continue;
        }
        count += 1;
        let q = idx(x);
        for dz in -1i64..=1 {
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let d = [dx, dy, dz];
                    let mut cc = [0usize; 3];
                    let mut ok = true;
                    for k in 0..3 {
                        let v = q[k] as i64 + d[k];
                        let mk = m[k] as i64;
                        cc[k] = if period.is_some() {
                            v.rem_euclid(mk) as usize
                        } else if v < 0 || v >= mk {
                            ok = false;
                            0
                        } else {
                            v as usize
                        };
                    }
                    if !ok || (period.is_some() && m.iter().any(|&mk| mk < 3)) {
                        continue;
                    }
                    for &j in &cells[(cc[2] * m[1] + cc[1]) * m[0] + cc[0]] {
                        let j = j as usize;
                        if j == i {
                            continue;
                        }
                        let mut dv = p.centres[j] - x;
                        if let Some(l) = period {
                            for k in 0..3 {
                                dv[k] -= l[k] * (dv[k] / l[k]).round();
                            }
                        }
                        let gap = dv.norm() - p.radii[i] - p.radii[j];
                        if gap < 0.01 * mean {
                            z1 += 1;
                        }
                        if gap < 0.05 * mean {
                            z5 += 1;
                        }
                    }
                }
            }
        }
    }
    (z1 as f64 / count as f64, z5 as f64 / count as f64)
}
