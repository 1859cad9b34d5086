//! Test networks shared by the solver integration tests.

use demcon_network::Network;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Random geometric graph: `n` uniform points in a cube of unit density, links closer than
/// 1.2143 (mean coordination ≈ 7.5, like a packing), the conductance of a link of length d
/// given by `conductance(rng, d)`. Returns the network, the conductances and the x
/// coordinates.
pub fn geometric_with(
    n: usize,
    seed: u64,
    mut conductance: impl FnMut(&mut ChaCha8Rng, f64) -> f64,
) -> (Network, Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let l = (n as f64).cbrt();
    let pts: Vec<[f64; 3]> = (0..n)
        .map(|_| [0, 1, 2].map(|_| rng.random::<f64>() * l))
        .collect();
    let mut edges = Vec::new();
    let mut g = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            let d = (0..3)
                .map(|a| (pts[i][a] - pts[j][a]).powi(2))
                .sum::<f64>()
                .sqrt();
            if d < 1.2143 {
                edges.push([i as u32, j as u32]);
                g.push(conductance(&mut rng, d));
            }
        }
    }
    let x = pts.iter().map(|p| p[0]).collect();
    (Network::new(n, &edges).unwrap(), g, x)
}

/// Nodes with x < 1 at `lo`, x > L − 1 at `hi`.
pub fn faces(x: &[f64], lo: f64, hi: f64) -> Vec<(Vec<u32>, f64)> {
    let l = x.iter().cloned().fold(0.0, f64::max);
    let sel = |f: &dyn Fn(f64) -> bool| -> Vec<u32> {
        x.iter()
            .enumerate()
            .filter(|(_, v)| f(**v))
            .map(|(i, _)| i as u32)
            .collect()
    };
    vec![(sel(&|v| v < 1.0), lo), (sel(&|v| v > l - 1.0), hi)]
}
