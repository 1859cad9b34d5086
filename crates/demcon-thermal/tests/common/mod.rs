//! Test networks shared by the thermal crate's integration tests.
#![allow(dead_code)]

use demcon_network::Network;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// An n×n×n lattice, conductances in [0.5, 2] W/K, capacities in [0.2, 3] J/K; with
/// `diagonals`, about 30 % of the cells get an extra diagonal link (a polydisperse-like
/// spread of C/ΣH).
pub fn lattice(n: usize, seed: u64, diagonals: bool) -> (Network, Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let id = |i: usize, j: usize, k: usize| (i * n * n + j * n + k) as u32;
    let mut edges = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                if i + 1 < n {
                    edges.push([id(i, j, k), id(i + 1, j, k)]);
                }
                if j + 1 < n {
                    edges.push([id(i, j, k), id(i, j + 1, k)]);
                }
                if k + 1 < n {
                    edges.push([id(i, j, k), id(i, j, k + 1)]);
                }
                if diagonals && j + 1 < n && k + 1 < n && rng.random::<f64>() < 0.3 {
                    edges.push([id(i, j, k), id(i, j + 1, k + 1)]);
                }
            }
        }
    }
    let g = (0..edges.len()).map(|_| rng.random_range(0.5..2.0)).collect();
    let c = (0..n * n * n).map(|_| rng.random_range(0.2..3.0)).collect();
    (Network::new(n * n * n, &edges).unwrap(), g, c)
}

/// The nodes of the lattice face i = const.
pub fn face(n: usize, i: usize) -> Vec<u32> {
    (0..n * n).map(|r| (i * n * n + r) as u32).collect()
}
