//! A phase of a voxel image as a region: the voxels of one label, with a signed distance sampled
//! at the voxel centres by an exact Euclidean distance transform (Felzenszwalb & Huttenlocher,
//! "Distance Transforms of Sampled Functions", Theory of Computing 8, 2012) and interpolated
//! trilinearly between them. Its zero level set runs half a voxel from the centres on either
//! side, so it passes through the voxel faces and smooths the staircase at edges and corners.
//! A walled image: outside it a point is outside the phase. A periodic image (the period of a
//! periodic box): distances and interpolation wrap round it, so its faces are no surface.

use std::sync::Arc;

use crate::{Aabb, CoreError, Vec3};

/// The voxels of one phase of an image and their signed distance (see the module doc). Cheap to
/// clone (shared).
#[derive(Clone)]
pub struct Voxels {
    inner: Arc<Inner>,
}

impl std::fmt::Debug for Voxels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.inner;
        f.debug_struct("Voxels")
            .field("dims", &s.dims)
            .field("voxel", &s.voxel)
            .field("origin", &s.origin)
            .field("count", &s.count)
            .finish()
    }
}

#[derive(Debug)]
struct Inner {
    dims: [usize; 3],
    /// Edge of a voxel (m).
    voxel: f64,
    /// The image's lower corner (m).
    origin: Vec3,
    /// Signed distance at each voxel centre (m), x fastest.
    sd: Vec<f32>,
    /// The box of the phase's voxels (m).
    bounds: Aabb,
    /// Voxels in the phase.
    count: usize,
    /// The image is one period of a periodic microstructure.
    periodic: bool,
}

impl PartialEq for Voxels {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.inner, &other.inner)
            || (self.inner.dims == other.inner.dims
                && self.inner.voxel == other.inner.voxel
                && self.inner.origin == other.inner.origin
                && self.inner.sd == other.inner.sd)
    }
}

/// Squared distance from every sample to the nearest feature (f = 0) along one line: the lower
/// envelope of the parabolas (q − p)² + f(p); `f` holds 0 at features and a large value
/// elsewhere, and is replaced by the result. `v`, `z` are scratch.
fn edt_1d(f: &mut [f64], v: &mut Vec<usize>, z: &mut Vec<f64>) {
    let n = f.len();
    v.clear();
    v.resize(n, 0);
    z.clear();
    z.resize(n + 1, 0.0);
    let mut k = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    let meet = |q: usize, p: usize, f: &[f64]| {
        ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64))
    };
    for q in 1..n {
        let mut s = meet(q, v[k], f);
        while s <= z[k] {
            k -= 1;
            s = meet(q, v[k], f);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    let mut out = Vec::with_capacity(n);
    k = 0;
    for q in 0..n {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        out.push((q as f64 - v[k] as f64).powi(2) + f[v[k]]);
    }
    f.copy_from_slice(&out);
}

/// Squared distance (in voxels²) from each voxel centre to the nearest centre where `feature`
/// is true (a large number when there is none); `periodic`: round the image's period (each
/// line is transformed three times over and its middle kept).
fn squared_distance(dims: [usize; 3], feature: impl Fn(usize) -> bool, periodic: bool) -> Vec<f64> {
    let big = 1e30;
    let [nx, ny, nz] = dims;
    let mut g: Vec<f64> = (0..nx * ny * nz)
        .map(|i| if feature(i) { 0.0 } else { big })
        .collect();
    let (mut v, mut z) = (Vec::new(), Vec::new());
    let mut line = Vec::new();
    // Along x, y, z in turn.
    for axis in 0..3 {
        let (n, stride) = match axis {
            0 => (nx, 1),
            1 => (ny, nx),
            _ => (nz, nx * ny),
        };
        for start in 0..nx * ny * nz {
            let coord = (start / stride) % n;
            if coord != 0 {
                continue;
            }
            let copies = if periodic { 3 } else { 1 };
            line.clear();
            line.extend((0..copies * n).map(|k| g[start + (k % n) * stride]));
            edt_1d(&mut line, &mut v, &mut z);
            let first = if periodic { n } else { 0 };
            for k in 0..n {
                g[start + k * stride] = line[first + k];
            }
        }
    }
    g
}

impl Voxels {
    /// The phase whose voxels are those of `mask` (x fastest, then y, then z) in an image of
    /// `dims` voxels of edge `voxel` (m) whose lower corner is `origin` (m); `periodic` when the
    /// image is one period of a periodic microstructure. Refusals name `field`: dimensions that
    /// do not match the mask, a voxel size that is not finite and > 0, a non-finite origin.
    pub fn from_mask(
        dims: [usize; 3],
        voxel: f64,
        origin: Vec3,
        mask: &[bool],
        periodic: bool,
        field: &str,
    ) -> Result<Self, CoreError> {
        if !(voxel.is_finite() && voxel > 0.0) {
            return Err(CoreError::invalid(
                format!("{field}.voxel"),
                voxel,
                "a finite size > 0 (m)",
            ));
        }
        if !origin.iter().all(|v| v.is_finite()) {
            return Err(CoreError::invalid(
                format!("{field}.origin"),
                format!("({}, {}, {})", origin.x, origin.y, origin.z),
                "a finite point (m)",
            ));
        }
        let n = dims.iter().product::<usize>();
        if n == 0 || n != mask.len() {
            return Err(CoreError::invalid(
                format!("{field}.dims"),
                format!("{dims:?} ({} voxels given)", mask.len()),
                "three sizes ≥ 1 whose product is the number of voxels",
            ));
        }
        let to_inside = squared_distance(dims, |i| mask[i], periodic);
        let to_outside = squared_distance(dims, |i| !mask[i], periodic);
        let sd: Vec<f32> = (0..n)
            .map(|i| {
                let s = if mask[i] {
                    -(to_outside[i].sqrt() - 0.5)
                } else {
                    to_inside[i].sqrt() - 0.5
                };
                (s * voxel) as f32
            })
            .collect();
        let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
        let mut count = 0;
        for (i, &m) in mask.iter().enumerate() {
            if m {
                let c = [i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1])];
                for k in 0..3 {
                    lo[k] = lo[k].min(c[k]);
                    hi[k] = hi[k].max(c[k] + 1);
                }
                count += 1;
            }
        }
        let bounds = if count == 0 {
            Aabb {
                min: origin,
                max: origin,
            }
        } else {
            Aabb {
                min: origin + Vec3::new(lo[0] as f64, lo[1] as f64, lo[2] as f64) * voxel,
                max: origin + Vec3::new(hi[0] as f64, hi[1] as f64, hi[2] as f64) * voxel,
            }
        };
        Ok(Self {
            inner: Arc::new(Inner {
                dims,
                voxel,
                origin,
                sd,
                bounds,
                count,
                periodic,
            }),
        })
    }

    /// The box of the phase's voxels (m).
    pub fn bounds(&self) -> Aabb {
        self.inner.bounds
    }

    /// The box of the whole image (m).
    pub fn image_box(&self) -> Aabb {
        let s = &self.inner;
        Aabb {
            min: s.origin,
            max: s.origin + Vec3::new(s.dims[0] as f64, s.dims[1] as f64, s.dims[2] as f64) * s.voxel,
        }
    }

    /// The phase's volume: its voxels' (m³).
    pub fn volume(&self) -> f64 {
        self.inner.count as f64 * self.inner.voxel.powi(3)
    }

    /// Voxels along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.inner.dims
    }

    /// Edge of a voxel (m).
    pub fn voxel(&self) -> f64 {
        self.inner.voxel
    }

    /// The image's lower corner (m).
    pub fn origin(&self) -> Vec3 {
        self.inner.origin
    }

    /// Whether the image is one period of a periodic microstructure.
    pub fn is_periodic(&self) -> bool {
        self.inner.periodic
    }

    /// Whether voxel `(i, j, k)` (each below its dimension) is in the phase.
    pub fn holds(&self, [i, j, k]: [usize; 3]) -> bool {
        let s = &self.inner;
        s.sd[(k * s.dims[1] + j) * s.dims[0] + i] < 0.0
    }

    /// The voxel holding `p` (m): `p` wrapped into a periodic image; `None` outside a walled
    /// one. A point on a face between two voxels belongs to the upper one.
    pub fn voxel_at(&self, p: &Vec3) -> Option<[usize; 3]> {
        let s = &self.inner;
        let mut ijk = [0usize; 3];
        for k in 0..3 {
            let n = s.dims[k];
            let u = (p[k] - s.origin[k]) / s.voxel;
            let u = if s.periodic { u.rem_euclid(n as f64) } else { u };
            if !(u >= 0.0 && u < n as f64) {
                return None;
            }
            ijk[k] = (u.floor() as usize).min(n - 1);
        }
        Some(ijk)
    }

    /// Whether the voxel holding `p` is in the phase: the staircase of voxel faces itself,
    /// where [`Self::signed_distance`] smooths its edges and corners.
    pub fn holds_point(&self, p: &Vec3) -> bool {
        self.voxel_at(p).is_some_and(|v| self.holds(v))
    }

    /// Signed distance (m) at `p`: the trilinear interpolation of the centres' values. A
    /// walled image: half a voxel beyond its outer centres the nearest centres' values, and
    /// outside it the distance to its box (a point there is outside the phase). A periodic
    /// image: `p` wrapped into it, the interpolation round its faces.
    pub fn signed_distance(&self, p: &Vec3) -> f64 {
        let s = &self.inner;
        let u = (p - s.origin) / s.voxel; // in voxels; centre of voxel i at i + 0.5
        let mut lo = [0usize; 3];
        let mut hi = [0usize; 3];
        let mut t = [0.0f64; 3];
        let mut outside = 0.0f64;
        for k in 0..3 {
            let n = s.dims[k];
            let nf = n as f64;
            if s.periodic {
                let x = (u[k] - 0.5).rem_euclid(nf);
                let i = (x.floor() as usize).min(n - 1);
                lo[k] = i;
                hi[k] = (i + 1) % n;
                t[k] = x - i as f64;
                continue;
            }
            if u[k] < 0.0 || u[k] > nf {
                outside += (if u[k] < 0.0 { -u[k] } else { u[k] - nf }).powi(2);
            }
            let x = (u[k] - 0.5).clamp(0.0, nf - 1.0);
            let i = (x.floor() as usize).min(n - 1);
            lo[k] = i;
            hi[k] = (i + 1).min(n - 1);
            t[k] = x - i as f64;
        }
        if outside > 0.0 {
            return outside.sqrt() * s.voxel;
        }
        let at = |i: usize, j: usize, k: usize| f64::from(s.sd[(k * s.dims[1] + j) * s.dims[0] + i]);
        let mut v = 0.0;
        for (i, wi) in [(lo[0], 1.0 - t[0]), (hi[0], t[0])] {
            for (j, wj) in [(lo[1], 1.0 - t[1]), (hi[1], t[1])] {
                for (k, wk) in [(lo[2], 1.0 - t[2]), (hi[2], t[2])] {
                    v += wi * wj * wk * at(i, j, k);
                }
            }
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slab_of_voxels_has_its_faces_as_zero_level() {
        // 8 × 4 × 4 voxels of 0.5 m, the slab x ∈ [1, 2.5) m (voxels 2..5) inside.
        let dims = [8, 4, 4];
        let mask: Vec<bool> = (0..128).map(|i| (2..5).contains(&(i % 8))).collect();
        let v = Voxels::from_mask(dims, 0.5, Vec3::zeros(), &mask, false, "image").unwrap();
        for (x, want) in [(1.0, 0.0), (2.5, 0.0), (1.75, -0.75), (0.5, 0.5), (3.5, 1.0)] {
            let got = v.signed_distance(&Vec3::new(x, 1.0, 1.0));
            assert!((got - want).abs() < 1e-6, "x = {x}: {got} vs {want}");
        }
        assert!((v.volume() - 3.0 * 16.0 * 0.125).abs() < 1e-12);
        assert_eq!(v.bounds().min.x, 1.0);
        assert_eq!(v.bounds().max.x, 2.5);
        // Outside the image: outside the phase, by the distance to the image.
        assert!((v.signed_distance(&Vec3::new(-1.0, 1.0, 1.0)) - 1.0).abs() < 1e-12);
        // The staircase itself: voxel lookup, upper voxel on a face, nothing outside.
        assert!(v.holds_point(&Vec3::new(1.0, 1.0, 1.0)));
        assert!(!v.holds_point(&Vec3::new(2.5, 1.0, 1.0)));
        assert!(!v.holds_point(&Vec3::new(-0.1, 1.0, 1.0)));
        assert_eq!(v.voxel_at(&Vec3::new(1.2, 0.3, 1.9)), Some([2, 0, 3]));
        let p = Voxels::from_mask(dims, 0.5, Vec3::zeros(), &mask, true, "image").unwrap();
        assert_eq!(p.voxel_at(&Vec3::new(4.0 + 1.2, -0.2, 1.9)), Some([2, 3, 3]));
    }

    #[test]
    fn a_periodic_slab_has_both_faces_round_the_period() {
        // 10 voxels of 0.1 m along x, voxels 0..3 inside: faces at x = 0 (= 1) and 0.3.
        let dims = [10, 2, 2];
        let mask: Vec<bool> = (0..40).map(|i| i % 10 < 3).collect();
        let v = Voxels::from_mask(dims, 0.1, Vec3::zeros(), &mask, true, "image").unwrap();
        for (x, want) in [
            (0.0, 0.0),
            (1.0, 0.0),
            (0.3, 0.0),
            (0.15, -0.15),
            (0.95, 0.05),
            (-0.05, 0.05),
            (1.1, -0.1),
        ] {
            let got = v.signed_distance(&Vec3::new(x, 0.05, 0.05));
            assert!((got - want).abs() < 1e-6, "x = {x}: {got} vs {want}");
        }
    }

    #[test]
    fn a_voxel_ball_is_close_to_its_ball() {
        let n = 40;
        let r = 12.0;
        let c = n as f64 / 2.0;
        let mask: Vec<bool> = (0..n * n * n)
            .map(|i| {
                let p = [i % n, (i / n) % n, i / (n * n)].map(|k| k as f64 + 0.5 - c);
                (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() <= r
            })
            .collect();
        let v = Voxels::from_mask([n, n, n], 1.0, Vec3::zeros(), &mask, false, "image").unwrap();
        // Along rays from the centre the zero crossing is within a voxel of r.
        for d in [
            Vec3::x(),
            Vec3::new(1.0, 1.0, 0.0).normalize(),
            Vec3::new(1.0, 1.0, 1.0).normalize(),
        ] {
            let at = |t: f64| v.signed_distance(&(Vec3::repeat(c) + t * d));
            let (mut lo, mut hi) = (0.0, 18.0);
            for _ in 0..60 {
                let m = 0.5 * (lo + hi);
                if at(m) <= 0.0 {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            assert!((lo - r).abs() < 1.0, "{lo}");
            // A gradient of magnitude about 1 near the surface.
            let g = (at(lo + 1.0) - at(lo - 1.0)) / 2.0;
            assert!((g - 1.0).abs() < 0.15, "{g}");
        }
    }

    #[test]
    fn bad_images_are_refused_by_field() {
        let e = Voxels::from_mask([2, 2, 2], 0.0, Vec3::zeros(), &[true; 8], false, "phases[1]").unwrap_err();
        assert!(e.to_string().contains("phases[1].voxel"));
        let e = Voxels::from_mask([2, 2, 3], 1.0, Vec3::zeros(), &[true; 8], false, "phases[1]").unwrap_err();
        assert!(e.to_string().contains("phases[1].dims"));
    }
}
