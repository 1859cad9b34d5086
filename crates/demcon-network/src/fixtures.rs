//! Networks with a known character for the tests and benchmarks of this crate and the solver
//! crates above it (thermal, electric): one definition instead of a copy in each.

use crate::Network;

/// Fixed sets: (nodes, value).
pub type FixedSets = Vec<(Vec<u32>, f64)>;

/// An n×n×n lattice (unit spacing, conductance 1 with ±30 % deterministic noise) whose edges
/// inside a centred sphere of radius 0.3 n have their conductance multiplied by `ratio` (the
/// contrast); the faces i = 0 and i = n − 1 are held at 0 and 1. Returns the network, the
/// conductances (one per edge) and the fixed sets. n ≥ 2.
pub fn inclusion_lattice(n: usize, ratio: f64) -> (Network, Vec<f64>, FixedSets) {
    assert!(n >= 2, "an inclusion lattice needs n ≥ 2");
    let id = |i: usize, j: usize, k: usize| (i * n * n + j * n + k) as u32;
    let c = (n as f64 - 1.0) / 2.0;
    let inside = |i: usize, j: usize, k: usize| {
        let d2 = (i as f64 - c).powi(2) + (j as f64 - c).powi(2) + (k as f64 - c).powi(2);
        d2 < (0.3 * n as f64).powi(2)
    };
    // SplitMix64 of the edge index: noise in [0.7, 1.3).
    let noise = |k: u64| {
        let mut z = k.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        0.7 + 0.6 * (z >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut edges, mut g) = (Vec::new(), Vec::new());
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                for (a, b, e) in [(i + 1, j, k), (i, j + 1, k), (i, j, k + 1)] {
                    if a < n && b < n && e < n {
                        let base = noise(edges.len() as u64);
                        edges.push([id(i, j, k), id(a, b, e)]);
                        g.push(if inside(i, j, k) && inside(a, b, e) {
                            base * ratio
                        } else {
                            base
                        });
                    }
                }
            }
        }
    }
    let face = |i: usize| -> Vec<u32> { (0..n * n).map(|r| (i * n * n + r) as u32).collect() };
    let net = Network::new(n * n * n, &edges).expect("a lattice is a valid network");
    (net, g, vec![(face(0), 0.0), (face(n - 1), 1.0)])
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_inclusion_lattice_has_its_contrast() {
        let (net, g, sets) = super::inclusion_lattice(6, 1e3);
        assert_eq!(net.n_nodes(), 216);
        assert_eq!(g.len(), 3 * 6 * 6 * 5);
        assert!(g.iter().any(|&x| x > 500.0) && g.iter().any(|&x| x < 1.5));
        assert_eq!(sets.len(), 2);
    }
}
