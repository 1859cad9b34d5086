//! Slices: a raster of the particles cut by an axis-aligned plane, for pictures made elsewhere.

use demcon_core::check::{check_finite, check_len};
use demcon_core::{Axis, ParticleSet, Vec3};

use crate::domain::{Domain, Plane};
use crate::error::{PostError, check_particles};

/// Inputs of [`slice_grid`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliceParams {
    /// The cutting plane.
    pub plane: Plane,
    /// Number of (square) cells along the longer in-plane side of the domain, 1…20 000.
    pub resolution: usize,
}

/// A raster of a scalar field on a plane. Cell `(iu, iv)` is entry `iv · nu + iu`; `u` and `v`
/// are the two in-plane axes in x, y, z order (x-normal: u = y, v = z; y-normal: u = x, v = z;
/// z-normal: u = x, v = y). No entry is NaN: cells no particle covers have `covered = false`
/// and value 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// The plane.
    pub plane: Plane,
    /// In-plane axes `[u, v]`.
    pub axes: [Axis; 2],
    /// Coordinates (u, v) of the lower corner of cell (0, 0) (m).
    pub origin: [f64; 2],
    /// Cell edge (m).
    pub cell: f64,
    /// Number of cells `[nu, nv]`.
    pub shape: [usize; 2],
    /// Value in each cell (unit of the field); 0 where not covered.
    pub values: Vec<f64>,
    /// Whether a particle's section covers the cell centre.
    pub covered: Vec<bool>,
    /// The particle whose section covers the cell centre (the one of least power distance
    /// `|x − c|² − R²` when sections overlap); `None` where not covered.
    pub particle: Vec<Option<u32>>,
}

impl Grid {
    /// Centre of cell `(iu, iv)` in space (m).
    pub fn centre(&self, iu: usize, iv: usize) -> Vec3 {
        let mut p = Vec3::zeros();
        p[self.plane.axis.index()] = self.plane.position;
        p[self.axes[0].index()] = self.origin[0] + (iu as f64 + 0.5) * self.cell;
        p[self.axes[1].index()] = self.origin[1] + (iv as f64 + 0.5) * self.cell;
        p
    }

    /// Fraction of the cells that are covered.
    pub fn coverage(&self) -> f64 {
        self.covered.iter().filter(|&&c| c).count() as f64 / self.covered.len().max(1) as f64
    }
}

/// The in-plane axes of a plane normal to `axis`.
pub(crate) fn in_plane(axis: Axis) -> [Axis; 2] {
    match axis {
        Axis::X => [Axis::Y, Axis::Z],
        Axis::Y => [Axis::X, Axis::Z],
        Axis::Z => [Axis::X, Axis::Y],
    }
}

/// Rasterises a scalar particle field on a plane: each cell takes the value of the particle
/// whose section by the plane covers the cell centre. The raster spans the domain's bounding
/// box in the plane; in a periodic domain the sections of images across the faces are drawn.
/// Errors: values of the wrong length or non-finite, a plane outside the domain's bounds, a
/// resolution outside 1…20 000.
pub fn slice_grid(
    particles: &ParticleSet,
    values: &[f64],
    domain: &Domain,
    params: &SliceParams,
) -> Result<Grid, PostError> {
    domain.validate()?;
    check_particles(particles)?;
    check_len("values", values.len(), particles.len())?;
    check_finite("values", values)?;
    let Plane { axis, position } = params.plane;
    let a = axis.index();
    let bounds = domain.region.bounds();
    if !(position.is_finite() && position >= bounds.min[a] && position <= bounds.max[a]) {
        return Err(PostError::invalid(
            "plane.position",
            position,
            format!(
                "within the domain, [{}, {}] m along {axis:?}",
                bounds.min[a], bounds.max[a]
            ),
        ));
    }
    if !(1..=20_000).contains(&params.resolution) {
        return Err(PostError::invalid(
            "resolution",
            params.resolution,
            "1 to 20000 cells along the longer side",
        ));
    }
    let axes = in_plane(axis);
    let (u, v) = (axes[0].index(), axes[1].index());
    let origin = [bounds.min[u], bounds.min[v]];
    let ext = [bounds.max[u] - bounds.min[u], bounds.max[v] - bounds.min[v]];
    let cell = ext[0].max(ext[1]) / params.resolution as f64;
    if !(cell.is_finite() && cell > 0.0) {
        return Err(PostError::invalid(
            "domain",
            format!("{ext:?}"),
            "an extent > 0 in the plane (m)",
        ));
    }
    let shape = [0, 1].map(|k| ((ext[k] / cell).round() as usize).max(1));
    let ncell = shape[0] * shape[1];
    let mut best = vec![(f64::INFINITY, u32::MAX); ncell];

    let period = domain.period;
    let shifts_normal: Vec<f64> = match period {
        Some(l) => vec![-l[a], 0.0, l[a]],
        None => vec![0.0],
    };
    let shifts_plane: Vec<[f64; 2]> = match period {
        Some(l) => {
            let mut s = Vec::new();
            for i in -1..=1 {
                for j in -1..=1 {
                    s.push([i as f64 * l[u], j as f64 * l[v]]);
                }
            }
            s
        }
        None => vec![[0.0, 0.0]],
    };
    for (id, (c, &r)) in particles.centres.iter().zip(&particles.radii).enumerate() {
        let c = domain.wrap(c);
        for &sn in &shifts_normal {
            let h = c[a] + sn - position;
            let rho2 = r * r - h * h;
            if rho2 <= 0.0 {
                continue;
            }
            let rho = rho2.sqrt();
            for s in &shifts_plane {
                let cu = c[u] + s[0];
                let cv = c[v] + s[1];
                let span = |x: f64, k: usize| -> Option<(usize, usize)> {
                    let lo = ((x - rho - origin[k]) / cell).floor();
                    let hi = ((x + rho - origin[k]) / cell).floor();
                    let last = (shape[k] - 1) as f64;
                    (hi >= 0.0 && lo <= last).then(|| (lo.max(0.0) as usize, hi.min(last) as usize))
                };
                let (Some((u0, u1)), Some((v0, v1))) = (span(cu, 0), span(cv, 1)) else {
                    continue;
                };
                for iv in v0..=v1 {
                    let dv = origin[1] + (iv as f64 + 0.5) * cell - cv;
                    for iu in u0..=u1 {
                        let du = origin[0] + (iu as f64 + 0.5) * cell - cu;
                        let pow = du * du + dv * dv - rho2;
                        let slot = &mut best[iv * shape[0] + iu];
                        if pow <= 0.0 && (pow, id as u32) < *slot {
                            *slot = (pow, id as u32);
                        }
                    }
                }
            }
        }
    }
    let particle: Vec<Option<u32>> = best
        .iter()
        .map(|&(_, id)| (id != u32::MAX).then_some(id))
        .collect();
    Ok(Grid {
        plane: params.plane,
        axes,
        origin,
        cell,
        shape,
        values: particle
            .iter()
            .map(|p| p.map_or(0.0, |i| values[i as usize]))
            .collect(),
        covered: particle.iter().map(Option::is_some).collect(),
        particle,
    })
}
