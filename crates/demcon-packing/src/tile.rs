//! Tiling: a large periodic packing made of copies of a small one.
//!
//! A periodic packing of period `L` is also a periodic packing of period `(nx Lx, ny Ly, nz Lz)`
//! once copied `nx × ny × nz` times: no copy overlaps a neighbour copy, because every pair
//! across a copy boundary is a pair across the period of the original, which the packer kept
//! apart. Tiling keeps the local structure (the radius distribution, φ, the contacts and the
//! pair correlation up to half a period) exactly, and adds a long-range periodicity: the
//! structure repeats every original period. Quantities that average over many particles — an
//! effective conductivity, a field smoothed over a few diameters — do not see it; a
//! quantity correlated over more than one original period (a long-wavelength fluctuation, a
//! crack path longer than the period) does.

use demcon_core::{Container, CoreError, ParticleSet, Vec3, morton_order};

use crate::error::PackingError;
use crate::params::{MAX_COUNT, MemoryLimit};

/// Peak memory of tiling into an `x y z r` file, per particle of the result (bytes): the
/// copies (centres, radii and phases, 34 B), their Morton order and the renumbered copy, and
/// the file's text (~83 B per line). Measured 123 B (maximum resident set of `demcon tile`
/// making 4·10⁶ particles, 2026-11-26), rounded up.
pub const TILE_BYTES_PER_PARTICLE: u64 = 160;

/// Copies of a periodic packing along each axis: `[nx, ny, nz]`, each ≥ 1.
pub type Repeat = [usize; 3];

/// Number of particles of `count` particles tiled `repeat` times, or an error naming
/// `field` when a count is 0 or the product exceeds [`MAX_COUNT`].
pub fn tiled_count(count: usize, repeat: Repeat, field: &str) -> Result<usize, CoreError> {
    if let Some(k) = repeat.iter().position(|&r| r == 0) {
        return Err(CoreError::invalid(
            format!("{field}[{k}]"),
            0,
            "every repeat count must be at least 1 (1 = no copy along that axis)",
        ));
    }
    let total = repeat
        .iter()
        .try_fold(count, |acc, &r| acc.checked_mul(r))
        .filter(|&t| t <= MAX_COUNT);
    total.ok_or_else(|| {
        CoreError::invalid(
            field,
            format!("{repeat:?}"),
            format!(
                "{count} particles × {} copies exceed the largest particle count {MAX_COUNT} (ids are 32-bit)",
                repeat.iter().map(|&r| r as f64).product::<f64>()
            ),
        )
    })
}

/// Refuses a tiling into `total` particles whose memory (`total` ×
/// [`TILE_BYTES_PER_PARTICLE`]) exceeds `limit`, before any copy is made; the error names
/// `field` and gives the estimate, the limit and the largest count that fits.
pub fn check_tile_memory(total: usize, limit: &MemoryLimit, field: &str) -> Result<(), CoreError> {
    let (bytes, source) = limit.bytes_and_source();
    let need = (total as u64).saturating_mul(TILE_BYTES_PER_PARTICLE);
    if need > bytes {
        return Err(CoreError::invalid(
            field,
            format!("{total} particles"),
            format!(
                "tiling needs ~{TILE_BYTES_PER_PARTICLE} bytes per particle of the result, {:.3e} bytes, above the \
                 {source} of {:.3e} bytes: at most {} particles",
                need as f64,
                bytes as f64,
                bytes / TILE_BYTES_PER_PARTICLE
            ),
        ));
    }
    Ok(())
}

/// The periodic packing `particles` in `container` copied `repeat` times along x, y and z:
/// the particles of the copies, renumbered along a Morton curve of the new box, and the new
/// periodic container. Phases are copied with the particles.
///
/// Errors: a container that is not periodic (copies of a walled packing would meet at the
/// walls with gaps and layering), a repeat count of 0 or a total above [`MAX_COUNT`].
pub fn tile(
    particles: &ParticleSet,
    container: &Container,
    repeat: Repeat,
) -> Result<(ParticleSet, Container), PackingError> {
    let Container::Periodic { size } = *container else {
        return Err(CoreError::invalid(
            "container",
            container.kind(),
            "only a periodic packing can be tiled: copies of a walled packing would meet at its walls, \
             with the gaps and layering of a wall between them",
        )
        .into());
    };
    let total = tiled_count(particles.len(), repeat, "repeat")?;
    let mut centres = Vec::with_capacity(total);
    let mut radii = Vec::with_capacity(total);
    let mut phases = Vec::with_capacity(total);
    for iz in 0..repeat[2] {
        for iy in 0..repeat[1] {
            for ix in 0..repeat[0] {
                let shift = Vec3::new(ix as f64 * size[0], iy as f64 * size[1], iz as f64 * size[2]);
                centres.extend(particles.centres.iter().map(|c| c + shift));
                radii.extend_from_slice(&particles.radii);
                phases.extend_from_slice(&particles.phases);
            }
        }
    }
    let tiled = Container::Periodic {
        size: [0, 1, 2].map(|k| size[k] * repeat[k] as f64),
    };
    let mut set = ParticleSet::new(centres, radii)?;
    set.phases = phases;
    let order = morton_order(&set.centres, &tiled.bounds());
    Ok((set.permuted(&order), tiled))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::{PackingParams, RadiusDistribution, max_overlap, pack};

    /// A 300-particle periodic packing in a box of unequal sides (m).
    pub(crate) fn small() -> (ParticleSet, Container) {
        let c = Container::Periodic {
            size: [1e-3, 1.2e-3, 0.9e-3],
        };
        let params = PackingParams::new(c, 300, 0.6, RadiusDistribution::gaussian(0.3));
        (pack(&params, 5, None).unwrap().0, c)
    }

    #[test]
    fn a_tiling_larger_than_the_memory_is_refused_with_the_estimate() {
        let limit = MemoryLimit::Available(1 << 30);
        assert!(check_tile_memory(1_000_000, &limit, "repeat").is_ok());
        let e = check_tile_memory(100_000_000, &limit, "repeat")
            .unwrap_err()
            .to_string();
        assert!(e.contains("repeat") && e.contains("100000000 particles"), "{e}");
        assert!(
            e.contains("1.600e10 bytes") && e.contains("at most 6710886 particles"),
            "{e}"
        );
    }

    #[test]
    fn copies_keep_phi_and_stay_apart_across_the_copies() {
        let (p, c) = small();
        let (t, tc) = tile(&p, &c, [2, 3, 1]).unwrap();
        assert_eq!(t.len(), 6 * p.len());
        assert_eq!(tc.period(), Some([2e-3, 3.6e-3, 0.9e-3]));
        let phi = |s: &ParticleSet, c: &Container| s.solid_volume() / c.volume();
        assert!((phi(&t, &tc) - phi(&p, &c)).abs() < 1e-12);
        // Pairs across copy boundaries are the original's pairs across its period.
        let before = max_overlap(&p, Some(&c));
        let after = max_overlap(&t, Some(&tc));
        assert!(after <= before.max(1e-12) * (1.0 + 1e-9), "{after} > {before}");
        // Every copy of every particle is present exactly once.
        let mut r: Vec<f64> = t.radii.clone();
        let mut want: Vec<f64> = p.radii.iter().flat_map(|&r| [r; 6]).collect();
        r.sort_by(f64::total_cmp);
        want.sort_by(f64::total_cmp);
        assert_eq!(r, want);
    }

    #[test]
    fn refuses_walls_zero_and_too_many_copies() {
        let (p, _) = small();
        let walled = Container::Box { size: [1e-3; 3] };
        let e = tile(&p, &walled, [2, 2, 2]).unwrap_err().to_string();
        assert!(e.contains("container = box") && e.contains("periodic"), "{e}");
        let e = tile(&p, &Container::Periodic { size: [1e-3; 3] }, [2, 0, 2])
            .unwrap_err()
            .to_string();
        assert!(e.contains("repeat[1]") && e.contains("at least 1"), "{e}");
        let e = tiled_count(300, [100_000, 100_000, 1], "packing.repeat")
            .unwrap_err()
            .to_string();
        assert!(e.contains("packing.repeat") && e.contains("32-bit"), "{e}");
        let e = tiled_count(300, [usize::MAX, 2, 1], "packing.repeat")
            .unwrap_err()
            .to_string();
        assert!(e.contains("packing.repeat"), "{e}");
    }
}
