//! A rank's block of a tiled packing (`demcon_packing::tile_block`) carries what its cells
//! need: the Laguerre cells of its owned particles, tessellated from the owned particles and
//! their ghosts alone, are the serial tessellation's cells (issue 37, step 3's premise).

use std::collections::HashMap;

use demcon_core::{Container, Vec3};
use demcon_graph::{LaguerreParams, tessellate};
use demcon_packing::{PackingParams, RadiusDistribution, pack, tile, tile_block};

#[test]
fn owned_cells_from_a_block_and_its_ghosts_are_the_serial_cells() {
    let c = Container::Periodic { size: [1e-3; 3] };
    let params = PackingParams::new(c, 400, 0.6, RadiusDistribution::gaussian(0.3));
    let (p, _) = pack(&params, 3, None).unwrap();
    let repeat = [2, 2, 2];
    let (whole, wc) = tile(&p, &c, repeat).unwrap();
    let lp = LaguerreParams::default();
    let serial = tessellate(&whole, &wc, None, &lp).unwrap();
    let cells = serial.cells.as_ref().unwrap();
    let l = wc.period().unwrap();
    let branch = |a: &Vec3, b: &Vec3| {
        let mut d = b - a;
        for k in 0..3 {
            d[k] -= l[k] * (d[k] / l[k]).round();
        }
        d.norm()
    };
    // The farthest facet neighbour: a ghost layer that wide holds every neighbour of a cell.
    let reach = serial
        .pairs
        .iter()
        .map(|&[a, b]| branch(&whole.centres[a as usize], &whole.centres[b as usize]))
        .fold(0.0, f64::max);
    let facets: HashMap<[u32; 2], f64> = serial
        .pairs
        .iter()
        .copied()
        .zip(cells.facet_area.iter().copied())
        .collect();
    for ranks in [2, 3, 4] {
        for rank in 0..ranks {
            let b = tile_block(&p, &c, repeat, rank, ranks, 1.01 * reach).unwrap();
            // The block's sites: owned then ghosts, each with its global index.
            let mut sites = b.owned.clone();
            sites.centres.extend_from_slice(&b.ghosts.centres);
            sites.radii.extend_from_slice(&b.ghosts.radii);
            sites.phases.extend_from_slice(&b.ghosts.phases);
            let global: Vec<u32> = (b.first..b.first + b.owned.len())
                .chain(b.ghost_ids.iter().copied())
                .map(|g| g as u32)
                .collect();
            let local = tessellate(&sites, &b.container, None, &lp).unwrap();
            let lc = local.cells.as_ref().unwrap();
            let n_owned = b.owned.len();
            for (&g, &v) in global[..n_owned].iter().zip(&lc.volume) {
                let want = cells.volume[g as usize];
                assert!(
                    (v - want).abs() <= 1e-10 * want,
                    "rank {rank}/{ranks}, particle {g}: {v} vs {want}"
                );
            }
            let mut seen = 0;
            for (&[a, q], &area) in local.pairs.iter().zip(&lc.facet_area) {
                if (a as usize) >= n_owned && (q as usize) >= n_owned {
                    continue;
                }
                let (ga, gq) = (global[a as usize], global[q as usize]);
                let key = [ga.min(gq), ga.max(gq)];
                let want = facets
                    .get(&key)
                    .copied()
                    .unwrap_or_else(|| panic!("facet {key:?} is not serial"));
                assert!(
                    (area - want).abs() <= 1e-9 * want.max(1e-12),
                    "{key:?}: {area} vs {want}"
                );
                seen += 1;
            }
            // Every serial facet of an owned cell is found.
            let owned = b.first as u32..(b.first + n_owned) as u32;
            let want = serial
                .pairs
                .iter()
                .filter(|[a, q]| owned.contains(a) || owned.contains(q))
                .count();
            assert_eq!(seen, want, "rank {rank}/{ranks}");
        }
    }
}
