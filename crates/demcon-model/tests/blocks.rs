//! A rank's block of a tiled packing (`demcon_packing::tile_block`) carries what its cells
//! need: the Laguerre cells of its owned particles, built from the owned particles and their
//! ghosts alone (`tessellate_part`) with a ghost layer as wide as the cells' reach asks
//! (`ghost_width_needed`), are the serial tessellation's cells, periodic or walled (issue 37).

use std::collections::HashMap;

use demcon_core::{Container, ParticleSet};
use demcon_graph::{LaguerreParams, ghost_width_needed, tessellate, tessellate_part};
use demcon_packing::{Block, PackingParams, RadiusDistribution, pack, tile, tile_block};

/// The block's sites (owned then ghosts) and their global indices.
fn sites(b: &Block) -> (ParticleSet, Vec<u32>) {
    let mut s = b.owned.clone();
    s.centres.extend_from_slice(&b.ghosts.centres);
    s.radii.extend_from_slice(&b.ghosts.radii);
    s.phases.extend_from_slice(&b.ghosts.phases);
    let global = (b.first..b.first + b.owned.len())
        .chain(b.ghost_ids.iter().copied())
        .map(|g| g as u32)
        .collect();
    (s, global)
}

#[test]
fn owned_cells_from_a_block_and_its_ghosts_are_the_serial_cells() {
    let c = Container::Periodic { size: [1e-3; 3] };
    let params = PackingParams::new(c, 400, 0.6, RadiusDistribution::gaussian(0.3));
    let (p, _) = pack(&params, 3, None).unwrap();
    let r_max = p.radii.iter().copied().fold(0.0, f64::max);
    let d_mean = 2.0 * p.radii.iter().sum::<f64>() / p.len() as f64;
    let repeat = [2, 2, 2];
    let lp = LaguerreParams::default();
    for walls in [false, true] {
        let (whole, wc) = tile(&p, &c, repeat).unwrap();
        let wc = if walls {
            Container::Box {
                size: wc.period().unwrap(),
            }
        } else {
            wc
        };
        let serial = tessellate(&whole, &wc, None, &lp).unwrap();
        let cells = serial.cells.as_ref().unwrap();
        let facets: HashMap<[u32; 2], f64> = serial
            .pairs
            .iter()
            .copied()
            .zip(cells.facet_area.iter().copied())
            .collect();
        for ranks in [2, 3, 4] {
            for rank in 0..ranks {
                // The run's rule: start at 1.5 mean diameters, widen to what the cells ask.
                let mut width = 1.5 * d_mean;
                let (b, local) = loop {
                    let b = tile_block(&p, &c, repeat, walls, rank, ranks, width).unwrap();
                    let (s, _) = sites(&b);
                    let (g, reach) = tessellate_part(&s, &b.container, None, &lp, b.owned.len()).unwrap();
                    let need = ghost_width_needed(&b.owned.radii, &reach, r_max);
                    if need <= width {
                        break (b, g);
                    }
                    width = 1.05 * need;
                };
                let (_, global) = sites(&b);
                let lc = local.cells.as_ref().unwrap();
                let n_owned = b.owned.len();
                for (&g, &v) in global[..n_owned].iter().zip(&lc.volume) {
                    let want = cells.volume[g as usize];
                    assert!(
                        (v - want).abs() <= 1e-10 * want,
                        "rank {rank}/{ranks}, particle {g}: {v} vs {want}"
                    );
                }
                // Every facet is an owned cell's, and a serial one.
                for (&[a, q], &area) in local.pairs.iter().zip(&lc.facet_area) {
                    assert!((a as usize) < n_owned, "a facet between two ghosts");
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
                }
                // Every serial facet of an owned cell is found, and every wall facet.
                let owned = b.first as u32..(b.first + n_owned) as u32;
                let want = serial
                    .pairs
                    .iter()
                    .filter(|[a, q]| owned.contains(a) || owned.contains(q))
                    .count();
                assert_eq!(local.pairs.len(), want, "rank {rank}/{ranks}, walls {walls}");
                let walls_want = cells.walls.iter().filter(|w| owned.contains(&w.particle)).count();
                assert_eq!(lc.walls.len(), walls_want, "rank {rank}/{ranks}");
            }
        }
    }
}
