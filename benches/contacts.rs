//! Contact detection over a size ladder (10⁴, 10⁵, 10⁶ particles): the cell grid (default)
//! against the rstar R-tree self-join, both at the paper's target coordination Z = 7.5.
//!
//! Packing: not an LSA packing (demcon-graph's tests and benches do not use the sibling
//! crate) but a jittered FCC lattice — nearest-neighbour distance 1 m, centres jittered by
//! ±0.01 m per axis, Gaussian-ish radii N(0.47, 0.015) m clipped to [0.40, 0.4827] m so that
//! no spheres overlap — in a walled box. Its Z = 7.5 tolerance (ε ≈ 0.08) and candidate
//! count (~5 per particle at the initial search tolerance 0.1) are close to an LSA packing's
//! (ε ≈ 0.065), but its radius spread is narrower than the Gaussian σ/μ = 0.3 of the paper,
//! whose largest particles set the grid's cell size. Ids follow the lattice (spatially
//! ordered); the `shuffled` case renumbers them at random.
//!
//! Run: `cargo bench -p demcon-benches --bench contacts`; one case with e.g.
//! `cargo bench -p demcon-benches --bench contacts -- 'contacts/grid/1000188$'` (a case is
//! named by the lattice's particle count: 10 976, 97 556, 1 000 188). With
//! `DEMCON_BENCH_SUMMARY_ONLY=1` only the one-off line per case is printed.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use demcon_benches::{SplitMix, jittered_fcc, summary_only, wanted};
use demcon_core::ParticleSet;
use demcon_graph::{ContactParams, NeighbourSearch, detect_contacts};

/// The same set with ids in a pseudo-random order (a fixed permutation).
fn shuffled(p: &ParticleSet, seed: u64) -> ParticleSet {
    let mut rng = SplitMix(seed);
    let mut order: Vec<u32> = (0..p.len() as u32).collect();
    for i in (1..order.len()).rev() {
        let j = (rng.next_f64() * (i + 1) as f64) as usize;
        order.swap(i, j.min(i));
    }
    p.permuted(&order)
}

fn contacts(c: &mut Criterion) {
    let mut group = c.benchmark_group("contacts");
    group.sample_size(10);
    for n in [10_000usize, 100_000, 1_000_000] {
        // The lattice's particle count (4 m³), which names the case.
        let m = ((n as f64 / 4.0).cbrt().round() as usize).max(1);
        let len = 4 * m * m * m;
        if !["grid", "rtree", "grid-shuffled"]
            .iter()
            .any(|c| wanted(&format!("contacts/{c}/{len}")))
        {
            continue;
        }
        let (p, container) = jittered_fcc(n, 42);
        let mut cases = vec![
            ("grid", p.clone(), NeighbourSearch::CellGrid),
            ("rtree", p.clone(), NeighbourSearch::RTree),
        ];
        if n == 1_000_000 {
            cases.push(("grid-shuffled", shuffled(&p, 7), NeighbourSearch::CellGrid));
        }
        for (name, set, search) in cases {
            if !wanted(&format!("contacts/{name}/{len}")) {
                continue;
            }
            let params = ContactParams {
                search,
                ..ContactParams::target(7.5)
            };
            let g = detect_contacts(&set, &container, &params).unwrap();
            eprintln!(
                "contacts/{name}/{}: {} contacts, Z = {:.4}, ε = {:.5}, {} candidates, {} search rounds, {} rattlers, {:.3} s",
                set.len(),
                g.len(),
                g.coordination(),
                g.report.epsilon,
                g.report.candidates,
                g.report.search_rounds,
                g.report.rattlers.len(),
                g.report.wall_time_s
            );
            if summary_only() {
                continue;
            }
            group.bench_with_input(BenchmarkId::new(name, set.len()), &set, |b, set| {
                b.iter(|| black_box(detect_contacts(set, &container, &params).unwrap()))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, contacts);
criterion_main!(benches);
