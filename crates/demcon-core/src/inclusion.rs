//! Shaped inclusions: spheroids (prolate fibres, oblate platelets) and finite cylinders with flat
//! or hemispherical ends, each with a centre, a size and an axis of any orientation. Each has an
//! exact signed distance (the spheroid's by the distance to its meridian ellipse), an exact
//! bounding box and an exact volume, so that the phase rules that read a level set (centre,
//! laminate, segment) cut cells by the shape itself.

use crate::{Aabb, CoreError, Vec3};

/// The ends of a [`Inclusion::Cylinder`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ends {
    /// Flat discs.
    Flat,
    /// Hemispheres of the cylinder's radius (a capsule, or spherocylinder).
    Round,
}

/// One shaped inclusion. `axis` is a unit vector (the constructors normalise it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Inclusion {
    /// A spheroid: semi-axis `a` along `axis`, `b` across it (m). Prolate (a fibre) when
    /// a > b, oblate (a platelet) when a < b, a sphere when a = b.
    Spheroid {
        /// Centre (m).
        centre: Vec3,
        /// Unit vector of the symmetry axis.
        axis: Vec3,
        /// Semi-axis along `axis` (m).
        a: f64,
        /// Semi-axis across `axis` (m).
        b: f64,
    },
    /// A finite circular cylinder of `radius` whose total length, tip to tip along `axis` (end
    /// caps included), is `length` (m).
    Cylinder {
        /// Centre (m).
        centre: Vec3,
        /// Unit vector of the cylinder's axis.
        axis: Vec3,
        /// Radius (m).
        radius: f64,
        /// Total length along the axis, caps included (m).
        length: f64,
        /// Flat or hemispherical ends.
        ends: Ends,
    },
}

/// Checks an axis and returns it normalised: refused (at `field`) when not finite or of zero
/// length.
pub fn unit_axis(axis: Vec3, field: &str) -> Result<Vec3, CoreError> {
    let n = axis.norm();
    if !(n.is_finite() && n > 1e-12) {
        return Err(CoreError::invalid(
            field,
            format!("({}, {}, {})", axis.x, axis.y, axis.z),
            "a finite direction of non-zero length",
        ));
    }
    Ok(axis / n)
}

fn positive(field: &str, v: f64) -> Result<(), CoreError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(CoreError::invalid(field, v, "a finite length > 0 (m)"))
    }
}

impl Inclusion {
    /// A spheroid (semi-axes `a` along `axis`, `b` across, m); refusals name `field`.
    pub fn spheroid(centre: Vec3, axis: Vec3, a: f64, b: f64, field: &str) -> Result<Self, CoreError> {
        positive(&format!("{field}.a"), a)?;
        positive(&format!("{field}.b"), b)?;
        Ok(Self::Spheroid {
            centre: finite_point(centre, &format!("{field}.centre"))?,
            axis: unit_axis(axis, &format!("{field}.axis"))?,
            a,
            b,
        })
    }

    /// A cylinder (`radius`, total `length` along `axis`, m); a round-ended one needs
    /// `length ≥ 2 radius`. Refusals name `field`.
    pub fn cylinder(
        centre: Vec3,
        axis: Vec3,
        radius: f64,
        length: f64,
        ends: Ends,
        field: &str,
    ) -> Result<Self, CoreError> {
        positive(&format!("{field}.radius"), radius)?;
        positive(&format!("{field}.length"), length)?;
        if ends == Ends::Round && length < 2.0 * radius {
            return Err(CoreError::invalid(
                format!("{field}.length"),
                length,
                format!(
                    "a round-ended cylinder is at least its diameter long (≥ {:e} m)",
                    2.0 * radius
                ),
            ));
        }
        Ok(Self::Cylinder {
            centre: finite_point(centre, &format!("{field}.centre"))?,
            axis: unit_axis(axis, &format!("{field}.axis"))?,
            radius,
            length,
            ends,
        })
    }

    /// Centre (m).
    pub fn centre(&self) -> Vec3 {
        match self {
            Self::Spheroid { centre, .. } | Self::Cylinder { centre, .. } => *centre,
        }
    }

    /// Unit axis.
    pub fn axis(&self) -> Vec3 {
        match self {
            Self::Spheroid { axis, .. } | Self::Cylinder { axis, .. } => *axis,
        }
    }

    /// The same shape moved by `shift` (m).
    pub fn translated(&self, shift: Vec3) -> Self {
        let mut s = *self;
        match &mut s {
            Self::Spheroid { centre, .. } | Self::Cylinder { centre, .. } => *centre += shift,
        }
        s
    }

    /// The same shape grown by `t` (m) normal to its surface where that keeps the shape's kind
    /// exactly (cylinders: radius and length), and for a spheroid its semi-axes by `t`, which
    /// contains the true offset surface (a spheroid's parallel surface is not a spheroid).
    pub fn grown(&self, t: f64) -> Self {
        let mut s = *self;
        match &mut s {
            Self::Spheroid { a, b, .. } => {
                *a += t;
                *b += t;
            }
            Self::Cylinder { radius, length, .. } => {
                *radius += t;
                *length += 2.0 * t;
            }
        }
        s
    }

    /// Surface area (m²), exact.
    pub fn area(&self) -> f64 {
        use std::f64::consts::PI;
        match *self {
            Self::Spheroid { a, b, .. } if (a - b).abs() <= 1e-9 * b => 4.0 * PI * b * b,
            Self::Spheroid { a, b, .. } if a > b => {
                let e = (1.0 - (b / a).powi(2)).sqrt();
                2.0 * PI * b * b * (1.0 + a / (b * e) * e.asin())
            }
            Self::Spheroid { a, b, .. } => {
                let e = (1.0 - (a / b).powi(2)).sqrt();
                2.0 * PI * b * b + PI * a * a / e * ((1.0 + e) / (1.0 - e)).ln()
            }
            Self::Cylinder {
                radius,
                length,
                ends: Ends::Flat,
                ..
            } => 2.0 * PI * radius * (radius + length),
            Self::Cylinder { radius, length, .. } => 2.0 * PI * radius * length,
        }
    }

    /// Volume (m³), exact.
    pub fn volume(&self) -> f64 {
        use std::f64::consts::PI;
        match *self {
            Self::Spheroid { a, b, .. } => 4.0 / 3.0 * PI * a * b * b,
            Self::Cylinder {
                radius,
                length,
                ends: Ends::Flat,
                ..
            } => PI * radius * radius * length,
            Self::Cylinder {
                radius,
                length,
                ends: Ends::Round,
                ..
            } => PI * radius * radius * (length - 2.0 * radius) + 4.0 / 3.0 * PI * radius.powi(3),
        }
    }

    /// The smallest axis-aligned box that contains the shape (m), exact.
    pub fn bounds(&self) -> Aabb {
        let (c, u) = (self.centre(), self.axis());
        let half = Vec3::from_fn(|k, _| {
            let along = u[k].abs();
            let across = (1.0 - u[k] * u[k]).max(0.0).sqrt();
            match *self {
                Self::Spheroid { a, b, .. } => (a * a * u[k] * u[k] + b * b * across * across).sqrt(),
                Self::Cylinder {
                    radius,
                    length,
                    ends: Ends::Flat,
                    ..
                } => 0.5 * length * along + radius * across,
                Self::Cylinder {
                    radius,
                    length,
                    ends: Ends::Round,
                    ..
                } => (0.5 * length - radius) * along + radius,
            }
        });
        Aabb {
            min: c - half,
            max: c + half,
        }
    }

    /// The radius of the smallest ball about the centre that holds the shape (m).
    pub fn circumradius(&self) -> f64 {
        match *self {
            Self::Spheroid { a, b, .. } => a.max(b),
            Self::Cylinder {
                radius,
                length,
                ends: Ends::Flat,
                ..
            } => (0.25 * length * length + radius * radius).sqrt(),
            Self::Cylinder { length, .. } => 0.5 * length,
        }
    }

    /// Signed distance (m) from `p` to the surface: negative inside, exact.
    pub fn signed_distance(&self, p: &Vec3) -> f64 {
        let d = p - self.centre();
        let u = self.axis();
        let along = d.dot(&u);
        let radial = (d.norm_squared() - along * along).max(0.0).sqrt();
        match *self {
            Self::Spheroid { a, b, .. } => ellipse_signed_distance(b, a, radial, along),
            Self::Cylinder {
                radius,
                length,
                ends: Ends::Flat,
                ..
            } => {
                let qr = radial - radius;
                let qa = along.abs() - 0.5 * length;
                let outside = (qr.max(0.0).powi(2) + qa.max(0.0).powi(2)).sqrt();
                outside + qr.max(qa).min(0.0)
            }
            Self::Cylinder { radius, length, .. } => {
                let h = 0.5 * length - radius;
                let t = along.clamp(-h, h);
                (radial * radial + (along - t).powi(2)).sqrt() - radius
            }
        }
    }
}

impl Inclusion {
    /// The point of the shape farthest along `d` (m), `d` non-zero.
    pub fn support(&self, d: &Vec3) -> Vec3 {
        let (c, u) = (self.centre(), self.axis());
        let along = d.dot(&u);
        let across = d - along * u;
        let n_across = across.norm();
        let radial = |r: f64| {
            if n_across > 0.0 {
                across * (r / n_across)
            } else {
                Vec3::zeros()
            }
        };
        match *self {
            Self::Spheroid { a, b, .. } => {
                // E² d / √(d·E² d), E² = b² I + (a² − b²) u uᵀ.
                let e2d = b * b * d + (a * a - b * b) * along * u;
                c + e2d / d.dot(&e2d).max(f64::MIN_POSITIVE).sqrt()
            }
            Self::Cylinder {
                radius,
                length,
                ends: Ends::Flat,
                ..
            } => c + 0.5 * length * along.signum() * u + radial(radius),
            Self::Cylinder { radius, length, .. } => {
                c + (0.5 * length - radius) * along.signum() * u + radius * d / d.norm()
            }
        }
    }

    /// The distance between two shapes (m): 0 when they touch or overlap, else the length of
    /// the shortest segment between them: closed form for two round-ended cylinders (segment
    /// to segment), otherwise GJK on the support functions (relative tolerance 1e-10 of the
    /// shapes' size; exact for the segment parts, converging on the curved ones).
    pub fn distance(&self, other: &Inclusion) -> f64 {
        if let (Some((p0, p1, r)), Some((q0, q1, s))) = (self.capsule(), other.capsule()) {
            return (segment_distance(p0, p1, q0, q1) - r - s).max(0.0);
        }
        self.gjk(other, None)
    }

    /// Whether the two shapes are at least `gap` (m) apart and do not touch
    /// ([`Inclusion::distance`] `≥ gap` and `> 0`), stopping GJK as soon as its bounds decide.
    pub fn apart(&self, other: &Inclusion, gap: f64) -> bool {
        let d = if self.capsule().is_some() && other.capsule().is_some() {
            self.distance(other)
        } else {
            self.gjk(other, Some(gap))
        };
        d >= gap && d > 0.0
    }

    /// A round-ended cylinder's axis segment (ends) and radius.
    fn capsule(&self) -> Option<(Vec3, Vec3, f64)> {
        match *self {
            Self::Cylinder {
                centre,
                axis,
                radius,
                length,
                ends: Ends::Round,
            } => {
                let h = (0.5 * length - radius) * axis;
                Some((centre - h, centre + h, radius))
            }
            _ => None,
        }
    }

    /// GJK distance; with `decide`, it returns as soon as the bounds put the distance on one
    /// side of that value (a lower bound ≥ it, or an upper bound below it).
    fn gjk(&self, other: &Inclusion, decide: Option<f64>) -> f64 {
        let support = |d: &Vec3| self.support(&-d) - other.support(d);
        let scale = self.circumradius() + other.circumradius();
        let mut v = self.centre() - other.centre();
        let mut simplex: Vec<Vec3> = Vec::with_capacity(4);
        for _ in 0..128 {
            let vv = v.norm_squared();
            if vv <= (1e-12 * scale).powi(2) {
                return 0.0;
            }
            let w = support(&v);
            // The lower bound v·w/|v| met the upper bound |v|: converged.
            if vv - v.dot(&w) <= 1e-10 * scale * vv.sqrt() {
                return vv.sqrt();
            }
            if let Some(g) = decide {
                let lower = v.dot(&w) / vv.sqrt();
                if lower >= g && lower > 0.0 {
                    return lower;
                }
                if vv.sqrt() < g {
                    return vv.sqrt();
                }
            }
            if simplex
                .iter()
                .any(|p| (p - w).norm_squared() <= (1e-14 * scale).powi(2))
            {
                return vv.sqrt();
            }
            simplex.push(w);
            match closest_on_simplex(&simplex) {
                Some((p, kept)) => {
                    v = p;
                    simplex = kept;
                }
                None => return 0.0, // the origin is inside the tetrahedron
            }
        }
        v.norm()
    }
}

impl Inclusion {
    /// A triangulated surface for drawing (m): the meridian profile cut into about `rings`
    /// pieces (spread by arc length over the caps and the side; rings ≥ 2), revolved in
    /// `2 rings` steps about the axis. Every vertex lies on the surface; a flat cylinder keeps
    /// its rims. Triangles counter-clockwise seen from outside.
    pub fn surface_mesh(&self, rings: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let rings = rings.max(2);
        let around = 2 * rings;
        let (c, u) = (self.centre(), self.axis());
        let helper = if u.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
        let e1 = u.cross(&helper).normalize();
        let e2 = u.cross(&e1);
        let profile = self.meridian(rings);
        let last = profile.len() - 1;
        let mut points = vec![c + profile[0].1 * u];
        for &(rho, z) in &profile[1..last] {
            for j in 0..around {
                let phi = 2.0 * std::f64::consts::PI * j as f64 / around as f64;
                points.push(c + rho * (phi.cos() * e1 + phi.sin() * e2) + z * u);
            }
        }
        points.push(c + profile[last].1 * u);
        let south = (points.len() - 1) as u32;
        let at = |i: usize, j: usize| (1 + (i - 1) * around + j % around) as u32;
        let mut triangles = Vec::with_capacity(2 * around * last);
        for j in 0..around {
            triangles.push([0, at(1, j), at(1, j + 1)]);
            triangles.push([south, at(last - 1, j + 1), at(last - 1, j)]);
        }
        for i in 1..last - 1 {
            for j in 0..around {
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        (points, triangles)
    }

    /// The meridian profile (distance from the axis, position along it; m) from the top pole to
    /// the bottom one: about `rings` pieces, shared among the caps and the side by arc length
    /// (at least one each), with the profile's corners kept.
    fn meridian(&self, rings: usize) -> Vec<(f64, f64)> {
        use std::f64::consts::FRAC_PI_2;
        // Each part: its arc length and its point at t ∈ [0, 1].
        type Part = (f64, Box<dyn Fn(f64) -> (f64, f64)>);
        let parts: Vec<Part> = match *self {
            Self::Spheroid { a, b, .. } => {
                let len = std::f64::consts::PI * (a + b) / 2.0;
                vec![(
                    len,
                    Box::new(move |t: f64| {
                        let th = std::f64::consts::PI * t;
                        (b * th.sin(), a * th.cos())
                    }),
                )]
            }
            Self::Cylinder {
                radius: r,
                length,
                ends: Ends::Round,
                ..
            } => {
                let h = 0.5 * length - r;
                vec![
                    (
                        FRAC_PI_2 * r,
                        Box::new(move |t: f64| {
                            let th = FRAC_PI_2 * t;
                            (r * th.sin(), h + r * th.cos())
                        }),
                    ),
                    (2.0 * h, Box::new(move |t: f64| (r, h - 2.0 * h * t))),
                    (
                        FRAC_PI_2 * r,
                        Box::new(move |t: f64| {
                            let th = FRAC_PI_2 * (1.0 + t);
                            (r * th.sin(), -h + r * th.cos())
                        }),
                    ),
                ]
            }
            Self::Cylinder {
                radius: r, length, ..
            } => {
                let h = 0.5 * length;
                vec![
                    (r, Box::new(move |t: f64| (r * t, h))),
                    (length, Box::new(move |t: f64| (r, h - length * t))),
                    (r, Box::new(move |t: f64| (r * (1.0 - t), -h))),
                ]
            }
        };
        let total: f64 = parts.iter().map(|p| p.0).sum();
        let mut out = vec![(parts[0].1)(0.0)];
        for (len, at) in &parts {
            let n = ((rings as f64 * len / total).round() as usize).max(1);
            out.extend((1..=n).map(|k| at(k as f64 / n as f64)));
        }
        out
    }
}

/// The distance between the segments [p0, p1] and [q0, q1] (m), closed form (the clamped
/// solution of the two-parameter least-squares problem; Ericson, Real-Time Collision Detection,
/// §5.1.9).
fn segment_distance(p0: Vec3, p1: Vec3, q0: Vec3, q1: Vec3) -> f64 {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.dot(&d1), d2.dot(&d2), d2.dot(&r));
    let tiny = 1e-30;
    let (s, t) = if a <= tiny && e <= tiny {
        (0.0, 0.0)
    } else if a <= tiny {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= tiny {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s = if denom > tiny * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    ((p0 + s * d1) - (q0 + t * d2)).norm()
}

/// The point of the simplex (1–4 points) nearest the origin and the smallest face that holds it,
/// by trying every face (15 at most); `None` when a tetrahedron holds the origin.
fn closest_on_simplex(points: &[Vec3]) -> Option<(Vec3, Vec<Vec3>)> {
    let n = points.len();
    if n == 4 && tetrahedron_holds_origin(points) {
        return None;
    }
    let mut best: Option<(f64, Vec3, u32)> = None;
    for mask in 1u32..(1 << n) {
        let face: Vec<Vec3> = (0..n)
            .filter(|k| mask & (1 << k) != 0)
            .map(|k| points[k])
            .collect();
        if face.len() == 4 {
            continue;
        }
        let Some(p) = affine_projection(&face) else {
            continue;
        };
        let d = p.norm_squared();
        if best.is_none_or(|(bd, _, bm)| d < bd || (d == bd && mask.count_ones() < bm.count_ones())) {
            best = Some((d, p, mask));
        }
    }
    let (_, p, mask) = best?;
    Some((
        p,
        (0..n)
            .filter(|k| mask & (1 << k) != 0)
            .map(|k| points[k])
            .collect(),
    ))
}

/// The origin's projection on the affine hull of `face` (1–3 points) when it falls inside the
/// face (barycentric coordinates ≥ 0), else `None`.
fn affine_projection(face: &[Vec3]) -> Option<Vec3> {
    match face {
        [a] => Some(*a),
        [a, b] => {
            let ab = b - a;
            let t = -a.dot(&ab) / ab.norm_squared();
            (ab.norm_squared() > 0.0 && (0.0..=1.0).contains(&t)).then(|| a + t * ab)
        }
        [a, b, c] => {
            let (ab, ac) = (b - a, c - a);
            let (d00, d01, d11) = (ab.dot(&ab), ab.dot(&ac), ac.dot(&ac));
            let (d20, d21) = (-a.dot(&ab), -a.dot(&ac));
            let den = d00 * d11 - d01 * d01;
            if den <= 1e-300 {
                return None;
            }
            let v = (d11 * d20 - d01 * d21) / den;
            let w = (d00 * d21 - d01 * d20) / den;
            (v >= 0.0 && w >= 0.0 && v + w <= 1.0).then(|| a + v * ab + w * ac)
        }
        _ => None,
    }
}

/// Whether the tetrahedron `p` holds the origin (each face's plane leaves it on the side of the
/// opposite vertex).
fn tetrahedron_holds_origin(p: &[Vec3]) -> bool {
    let faces = [(0, 1, 2, 3), (0, 1, 3, 2), (0, 2, 3, 1), (1, 2, 3, 0)];
    faces.iter().all(|&(i, j, k, l)| {
        let n = (p[j] - p[i]).cross(&(p[k] - p[i]));
        let side_origin = n.dot(&-p[i]);
        let side_vertex = n.dot(&(p[l] - p[i]));
        side_origin * side_vertex >= 0.0
    })
}

fn finite_point(p: Vec3, field: &str) -> Result<Vec3, CoreError> {
    if p.iter().all(|v| v.is_finite()) {
        Ok(p)
    } else {
        Err(CoreError::invalid(
            field,
            format!("({}, {}, {})", p.x, p.y, p.z),
            "a finite point (m)",
        ))
    }
}

/// Signed distance from the point (x, y) to the ellipse (x/ex)² + (y/ey)² = 1 (negative
/// inside): the nearest point by Eberly's bisection on the normal-line parameter ("Distance
/// from a Point to an Ellipse, an Ellipsoid, or a Hyperellipsoid", 2013), robust at the axes
/// and for any aspect ratio; exact to round-off.
fn ellipse_signed_distance(ex: f64, ey: f64, x: f64, y: f64) -> f64 {
    let (x, y) = (x.abs(), y.abs());
    // Eberly's routine wants e0 ≥ e1: swap the axes when needed.
    let (e0, e1, y0, y1) = if ex >= ey { (ex, ey, x, y) } else { (ey, ex, y, x) };
    let dist = ellipse_distance_first_quadrant(e0, e1, y0, y1);
    let inside = (y0 / e0).powi(2) + (y1 / e1).powi(2) < 1.0;
    if inside { -dist } else { dist }
}

/// Unsigned distance from (y0, y1) ≥ 0 to the ellipse with semi-axes e0 ≥ e1 > 0.
fn ellipse_distance_first_quadrant(e0: f64, e1: f64, y0: f64, y1: f64) -> f64 {
    if y1 > 0.0 {
        if y0 > 0.0 {
            let z0 = y0 / e0;
            let z1 = y1 / e1;
            let g = z0 * z0 + z1 * z1 - 1.0;
            if g == 0.0 {
                return 0.0;
            }
            let r0 = (e0 / e1).powi(2);
            let s = ellipse_root(r0, z0, z1, g);
            let x0 = r0 * y0 / (s + r0);
            let x1 = y1 / (s + 1.0);
            ((x0 - y0).powi(2) + (x1 - y1).powi(2)).sqrt()
        } else {
            (y1 - e1).abs()
        }
    } else {
        let numer0 = e0 * y0;
        let denom0 = e0 * e0 - e1 * e1;
        if numer0 < denom0 {
            let xde0 = numer0 / denom0;
            let x0 = e0 * xde0;
            let x1 = e1 * (1.0 - xde0 * xde0).max(0.0).sqrt();
            ((x0 - y0).powi(2) + x1 * x1).sqrt()
        } else {
            (y0 - e0).abs()
        }
    }
}

/// The root s of (r0 z0 / (s + r0))² + (z1 / (s + 1))² = 1 by bisection (to the last bit).
fn ellipse_root(r0: f64, z0: f64, z1: f64, g: f64) -> f64 {
    let n0 = r0 * z0;
    let mut s0 = z1 - 1.0;
    let mut s1 = if g < 0.0 { 0.0 } else { n0.hypot(z1) - 1.0 };
    let mut s = 0.0;
    for _ in 0..1100 {
        s = 0.5 * (s0 + s1);
        if s == s0 || s == s1 {
            break;
        }
        let g = (n0 / (s + r0)).powi(2) + (z1 / (s + 1.0)).powi(2) - 1.0;
        if g > 0.0 {
            s0 = s;
        } else if g < 0.0 {
            s1 = s;
        } else {
            break;
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn prolate() -> Inclusion {
        Inclusion::spheroid(Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 1.0, 0.0), 2.0, 0.5, "s").unwrap()
    }

    /// A point on the surface by the parametrisation, its outward normal, for spheroid `s`.
    fn on_surface(a: f64, b: f64, theta: f64) -> (f64, f64, f64, f64) {
        let (r, z) = (b * theta.sin(), a * theta.cos());
        // Outward normal of (r/b)² + (z/a)² = 1 is ∝ (r/b², z/a²).
        let (nr, nz) = (r / (b * b), z / (a * a));
        let n = nr.hypot(nz);
        (r, z, nr / n, nz / n)
    }

    #[test]
    fn spheroid_distance_is_exact_along_normals() {
        for (a, b) in [(2.0, 0.5), (0.3, 1.5), (1.0, 1.0), (20.0, 1.0), (0.05, 1.0)] {
            for k in 0..40 {
                let theta = std::f64::consts::PI * (k as f64 + 0.37) / 40.0;
                let (r, z, nr, nz) = on_surface(a, b, theta);
                assert!(ellipse_signed_distance(b, a, r, z).abs() < 1e-12 * a.max(b));
                // Outside along the normal, the distance is the step (the normal line's nearest
                // point is the foot for any step outside).
                let t = 0.3 * a.min(b);
                assert_relative_eq!(
                    ellipse_signed_distance(b, a, r + t * nr, z + t * nz),
                    t,
                    max_relative = 1e-9
                );
                // Inside, within the smaller radius of curvature the foot is still nearest.
                let rho_min = a.min(b).powi(2) / a.max(b);
                let t = 0.5 * rho_min;
                assert_relative_eq!(
                    ellipse_signed_distance(b, a, r - t * nr, z - t * nz),
                    -t,
                    max_relative = 1e-9
                );
            }
        }
    }

    #[test]
    fn shapes_match_their_sphere_limits_and_rotate_with_their_axis() {
        let c = Vec3::new(0.5, -1.0, 2.0);
        let ball = Inclusion::spheroid(c, Vec3::z(), 1.0, 1.0, "s").unwrap();
        let capsule = Inclusion::cylinder(c, Vec3::x(), 1.0, 2.0, Ends::Round, "c").unwrap();
        for p in [Vec3::new(3.0, 1.0, -2.0), Vec3::new(0.6, -1.1, 2.2), c] {
            let exact = (p - c).norm() - 1.0;
            assert_relative_eq!(ball.signed_distance(&p), exact, epsilon = 1e-12);
            assert_relative_eq!(capsule.signed_distance(&p), exact, epsilon = 1e-12);
        }
        let s = prolate();
        let u = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert_relative_eq!(s.signed_distance(&(s.centre() + 3.0 * u)), 1.0, epsilon = 1e-12);
        assert_relative_eq!(s.signed_distance(&(s.centre() + Vec3::z())), 0.5, epsilon = 1e-12);
        let flat =
            Inclusion::cylinder(Vec3::zeros(), Vec3::new(0.0, 0.0, 2.0), 1.0, 4.0, Ends::Flat, "c").unwrap();
        assert_relative_eq!(flat.signed_distance(&Vec3::new(0.0, 0.0, 3.0)), 1.0);
        assert_relative_eq!(flat.signed_distance(&Vec3::new(0.0, 0.0, 1.5)), -0.5);
        assert_relative_eq!(flat.signed_distance(&Vec3::new(2.0, 0.0, 3.0)), 2f64.sqrt());
    }

    #[test]
    fn bounds_are_tight_and_volumes_agree_with_a_grid_count() {
        let shapes = [
            prolate(),
            Inclusion::spheroid(Vec3::zeros(), Vec3::new(0.2, -0.4, 1.0), 0.2, 1.0, "s").unwrap(),
            Inclusion::cylinder(
                Vec3::zeros(),
                Vec3::new(1.0, 2.0, 3.0),
                0.3,
                3.0,
                Ends::Round,
                "c",
            )
            .unwrap(),
            Inclusion::cylinder(
                Vec3::zeros(),
                Vec3::new(-1.0, 0.5, 0.2),
                0.4,
                2.0,
                Ends::Flat,
                "c",
            )
            .unwrap(),
        ];
        for s in shapes {
            let b = s.bounds();
            let n = 120;
            let h = b.extent() / n as f64;
            let (mut inside, mut lo, mut hi) = (0usize, Vec3::repeat(f64::MAX), Vec3::repeat(f64::MIN));
            for i in 0..n {
                for j in 0..n {
                    for k in 0..n {
                        let p = b.min
                            + Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5).component_mul(&h);
                        if s.signed_distance(&p) <= 0.0 {
                            inside += 1;
                            lo = lo.inf(&p);
                            hi = hi.sup(&p);
                        }
                    }
                }
            }
            let v = inside as f64 * h.x * h.y * h.z;
            assert_relative_eq!(v, s.volume(), max_relative = 0.01);
            // The grid's extreme inside points come within two cells of each face of the box.
            for k in 0..3 {
                assert!(lo[k] - b.min[k] < 2.0 * h[k] && b.max[k] - hi[k] < 2.0 * h[k]);
            }
            assert!(s.circumradius() + 1e-12 >= (b.max - s.centre()).abs().max() - 1e-12);
        }
    }

    /// The distance between two segments' closest points (brute force over a fine grid
    /// refined around the best pair), for the capsule check.
    fn segment_distance(p0: Vec3, p1: Vec3, q0: Vec3, q1: Vec3) -> f64 {
        let (mut best, mut bs, mut bt) = (f64::MAX, 0.0, 0.0);
        let mut span = 1.0;
        for _ in 0..30 {
            let (s0, t0) = (bs, bt);
            for i in -10..=10 {
                for j in -10..=10 {
                    let s = (s0 + span * i as f64 / 10.0).clamp(0.0, 1.0);
                    let t = (t0 + span * j as f64 / 10.0).clamp(0.0, 1.0);
                    let d = (p0 + s * (p1 - p0) - q0 - t * (q1 - q0)).norm();
                    if d < best {
                        (best, bs, bt) = (d, s, t);
                    }
                }
            }
            span *= 0.5;
        }
        best
    }

    #[test]
    fn gjk_distance_matches_exact_distances() {
        // Capsules: segment distance minus the radii.
        let mut rng = 12345u64;
        let mut next = || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..200 {
            let c1 = Vec3::new(next(), next(), next()) * 6.0;
            let c2 = Vec3::new(next(), next(), next()) * 6.0;
            let u1 = Vec3::new(next(), next(), next());
            let u2 = Vec3::new(next(), next(), next());
            let a = Inclusion::cylinder(c1, u1, 0.3, 3.0, Ends::Round, "a").unwrap();
            let b = Inclusion::cylinder(c2, u2, 0.2, 2.0, Ends::Round, "b").unwrap();
            let (ua, ub) = (a.axis(), b.axis());
            let seg = segment_distance(c1 - 1.2 * ua, c1 + 1.2 * ua, c2 - 0.8 * ub, c2 + 0.8 * ub);
            let exact = (seg - 0.5).max(0.0);
            assert!(
                (a.distance(&b) - exact).abs() < 1e-7,
                "{} vs {exact}",
                a.distance(&b)
            );
            assert!((b.distance(&a) - exact).abs() < 1e-7);
            assert!(
                (a.gjk(&b, None) - exact).abs() < 1e-7,
                "{} vs {exact}",
                a.gjk(&b, None)
            );
            for gap in [0.0, 0.1, 0.5] {
                assert_eq!(a.apart(&b, gap), exact >= gap && exact > 0.0);
            }
        }
        // Spheres as spheroids; a spheroid and a point-like ball along its axis and across.
        let s1 = Inclusion::spheroid(Vec3::zeros(), Vec3::x(), 1.0, 1.0, "s").unwrap();
        let s2 = Inclusion::spheroid(Vec3::new(3.0, 4.0, 0.0), Vec3::y(), 1.5, 1.5, "s").unwrap();
        assert_relative_eq!(s1.distance(&s2), 2.5, epsilon = 1e-8);
        let p = prolate();
        let u = p.axis();
        let ball = |at: Vec3| Inclusion::spheroid(at, Vec3::x(), 0.1, 0.1, "b").unwrap();
        assert_relative_eq!(p.distance(&ball(p.centre() + 3.0 * u)), 0.9, epsilon = 1e-8);
        assert_relative_eq!(
            p.distance(&ball(p.centre() + 1.5 * Vec3::z())),
            0.9,
            epsilon = 1e-8
        );
        // Flat cylinders end to end, and side by side.
        let f1 = Inclusion::cylinder(Vec3::zeros(), Vec3::z(), 1.0, 2.0, Ends::Flat, "f").unwrap();
        let f2 = Inclusion::cylinder(Vec3::new(0.5, 0.0, 2.7), Vec3::z(), 1.0, 2.0, Ends::Flat, "f").unwrap();
        assert_relative_eq!(f1.distance(&f2), 0.7, epsilon = 1e-8);
        let f3 = Inclusion::cylinder(Vec3::new(2.5, 0.0, 0.3), Vec3::z(), 1.0, 2.0, Ends::Flat, "f").unwrap();
        assert_relative_eq!(f1.distance(&f3), 0.5, epsilon = 1e-8);
        // Overlap gives 0; so does one inside the other.
        assert_eq!(f1.distance(&ball(Vec3::new(0.2, 0.1, 0.0))), 0.0);
        assert_eq!(p.distance(&ball(p.centre() + 1.5 * u)), 0.0);
        // Against the signed distance for a ball: dist = sd(centre) − r when the ball is outside
        // and the signed distance's foot is the nearest point.
        for k in 0..50 {
            let dir = Vec3::new((k as f64).sin(), (1.3 * k as f64).cos(), 0.3 - 0.01 * k as f64).normalize();
            let at = p.centre() + 4.0 * dir;
            let b = ball(at);
            assert_relative_eq!(p.distance(&b), p.signed_distance(&at) - 0.1, epsilon = 1e-7);
        }
    }

    #[test]
    fn surface_meshes_lie_on_the_surface_and_enclose_nearly_its_volume() {
        for s in [
            prolate(),
            Inclusion::cylinder(
                Vec3::zeros(),
                Vec3::new(1.0, 2.0, 3.0),
                0.3,
                3.0,
                Ends::Round,
                "c",
            )
            .unwrap(),
            Inclusion::cylinder(Vec3::x(), Vec3::new(-1.0, 0.5, 0.2), 0.4, 2.0, Ends::Flat, "c").unwrap(),
            Inclusion::spheroid(Vec3::zeros(), Vec3::new(0.2, -0.4, 1.0), 0.2, 1.0, "s").unwrap(),
        ] {
            let (points, triangles) = s.surface_mesh(24);
            assert!(points.iter().all(|p| s.signed_distance(p).abs() < 1e-9));
            // Divergence theorem: the enclosed volume, within the mesh's chordal error.
            let v: f64 = triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| points[i as usize] - s.centre());
                    a.dot(&b.cross(&c)) / 6.0
                })
                .sum();
            assert!(v > 0.0, "triangles wound inwards");
            assert_relative_eq!(v, s.volume(), max_relative = 0.02);
        }
    }

    #[test]
    fn bad_sizes_and_axes_are_refused_by_field() {
        let e =
            Inclusion::spheroid(Vec3::zeros(), Vec3::zeros(), 1.0, 1.0, "phases[0].shapes[3]").unwrap_err();
        assert!(e.to_string().contains("phases[0].shapes[3].axis"), "{e}");
        let e = Inclusion::spheroid(Vec3::zeros(), Vec3::x(), -1.0, 1.0, "s").unwrap_err();
        assert!(e.to_string().contains("s.a"), "{e}");
        let e = Inclusion::cylinder(Vec3::zeros(), Vec3::x(), 1.0, 1.0, Ends::Round, "f").unwrap_err();
        assert!(e.to_string().contains("f.length"), "{e}");
        let e = Inclusion::cylinder(
            Vec3::new(f64::NAN, 0.0, 0.0),
            Vec3::x(),
            1.0,
            3.0,
            Ends::Flat,
            "f",
        )
        .unwrap_err();
        assert!(e.to_string().contains("f.centre"), "{e}");
    }
}
