//! Shaped-inclusion phases of a scene: the listed shapes and the lines of a shapes file into
//! [`Inclusion`]s, and a `RandomShapes` entry into the placement the model runs; every
//! refusal names the field or the file and line.

use std::path::Path;

use demcon_core::{Container, Ends, Inclusion, Vec3};
use demcon_packing::{Orientation, RadiusDistribution, ShapeKind, ShapeParams};
use nalgebra::Matrix3;

use crate::config::{EndsConfig, OrientationConfig, PhaseConfig, ShapeConfig, ShapeKindConfig};
use crate::error::SceneError;

fn v3(t: (f64, f64, f64)) -> Vec3 {
    Vec3::new(t.0, t.1, t.2)
}

fn ends(e: EndsConfig) -> Ends {
    match e {
        EndsConfig::Flat => Ends::Flat,
        EndsConfig::Round => Ends::Round,
    }
}

/// One shape of a `RandomShapes` entry's kind, `aspect` (length over diameter) and `radius`
/// (m), at the origin along z; `None` for sizes a shape cannot have.
pub(crate) fn one_shape(kind: ShapeKindConfig, aspect: f64, radius: f64) -> Option<Inclusion> {
    let (c, z) = (demcon_core::Vec3::zeros(), demcon_core::Vec3::z());
    match kind {
        ShapeKindConfig::Spheroid => Inclusion::spheroid(c, z, aspect * radius, radius, "shape").ok(),
        ShapeKindConfig::Cylinder { ends: e } => {
            Inclusion::cylinder(c, z, radius, 2.0 * aspect * radius, ends(e), "shape").ok()
        }
    }
}

/// One listed shape, checked (refusals name `field`).
pub(crate) fn shape(s: &ShapeConfig, field: &str) -> Result<Inclusion, SceneError> {
    Ok(match *s {
        ShapeConfig::Spheroid { centre, axis, a, b } => {
            Inclusion::spheroid(v3(centre), v3(axis), a, b, field)?
        }
        ShapeConfig::Cylinder {
            centre,
            axis,
            radius,
            length,
            ends: e,
        } => Inclusion::cylinder(v3(centre), v3(axis), radius, length, ends(e), field)?,
    })
}

/// The shapes of a `Shapes` entry at `field`: those listed, then those of `file` (relative to
/// `base_dir`). At least one in all.
pub fn shape_list(
    field: &str,
    listed: &[ShapeConfig],
    file: Option<&str>,
    base_dir: &Path,
) -> Result<Vec<Inclusion>, SceneError> {
    let mut out = listed
        .iter()
        .enumerate()
        .map(|(k, s)| shape(s, &format!("{field}.shapes[{k}]")))
        .collect::<Result<Vec<_>, _>>()?;
    if let Some(f) = file {
        out.extend(read_shapes(&base_dir.join(f), &format!("{field}.file"))?);
    }
    if out.is_empty() {
        return Err(SceneError::invalid(
            &format!("{field}.shapes"),
            "[] and no file",
            "list at least one shape, or give `file`",
        ));
    }
    Ok(out)
}

/// `shapes` as a shapes file [`read_shapes`] reads back bit for bit (shortest round-trip
/// decimals), under a `#` header line `about`.
pub fn format_shapes(shapes: &[Inclusion], about: &str) -> String {
    let mut out = format!("# {about}\n");
    for s in shapes {
        let (c, u) = (s.centre(), s.axis());
        let line = match s {
            Inclusion::Spheroid { a, b, .. } => {
                format!("spheroid {} {} {} {} {} {} {a} {b}", c.x, c.y, c.z, u.x, u.y, u.z)
            }
            Inclusion::Cylinder {
                radius, length, ends, ..
            } => format!(
                "cylinder {} {} {} {} {} {} {radius} {length} {}",
                c.x,
                c.y,
                c.z,
                u.x,
                u.y,
                u.z,
                if *ends == Ends::Round { "round" } else { "flat" }
            ),
        };
        out.push_str(&line);
        out.push('\n');
    }
    out
}

/// Reads a shapes file: one shape per line, whitespace- or comma-separated, `#` comments:
/// `spheroid x y z ux uy uz a b` or `cylinder x y z ux uy uz radius length flat|round` (m).
/// Refusals name `field`, the file and the line.
pub fn read_shapes(path: &Path, field: &str) -> Result<Vec<Inclusion>, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let body = line.split('#').next().unwrap_or("").trim();
        if body.is_empty() {
            continue;
        }
        let at = format!("{}:{}", path.display(), i + 1);
        let words: Vec<&str> = body
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|w| !w.is_empty())
            .collect();
        let bad = |why: &str| SceneError::invalid(field, format!("{at}: {body:?}"), why.to_string());
        let numbers = |from: usize, count: usize| -> Result<Vec<f64>, SceneError> {
            words
                .get(from..from + count)
                .ok_or_else(|| bad("too few values"))?
                .iter()
                .map(|w| {
                    w.parse::<f64>()
                        .map_err(|_| bad(&format!("`{w}` is not a number")))
                })
                .collect()
        };
        let shape = match words[0].to_ascii_lowercase().as_str() {
            "spheroid" if words.len() == 9 => {
                let v = numbers(1, 8)?;
                Inclusion::spheroid(
                    Vec3::new(v[0], v[1], v[2]),
                    Vec3::new(v[3], v[4], v[5]),
                    v[6],
                    v[7],
                    &at,
                )?
            }
            "cylinder" if words.len() == 10 => {
                let v = numbers(1, 8)?;
                let e = match words[9].to_ascii_lowercase().as_str() {
                    "flat" => Ends::Flat,
                    "round" => Ends::Round,
                    _ => return Err(bad("the ends of a cylinder are `flat` or `round`")),
                };
                Inclusion::cylinder(
                    Vec3::new(v[0], v[1], v[2]),
                    Vec3::new(v[3], v[4], v[5]),
                    v[6],
                    v[7],
                    e,
                    &at,
                )?
            }
            _ => {
                return Err(bad(
                    "each line is `spheroid x y z ux uy uz a b` or `cylinder x y z ux uy uz radius length flat|round` \
                     (m)",
                ));
            }
        };
        out.push(shape);
    }
    Ok(out)
}

/// The placement of a `RandomShapes` entry `ph` (the model puts in its container; checked here
/// so that a bad value is refused before packing: refusals name `{field}.…`). `None` for
/// another kind of entry.
pub fn random_shape_params(field: &str, ph: &PhaseConfig) -> Result<Option<ShapeParams>, SceneError> {
    let PhaseConfig::RandomShapes {
        shape,
        aspect,
        radius,
        radius_cov,
        fraction,
        min_gap,
        orientation,
        ..
    } = *ph
    else {
        return Ok(None);
    };
    let kind = match shape {
        ShapeKindConfig::Spheroid => ShapeKind::Spheroid,
        ShapeKindConfig::Cylinder { ends } => ShapeKind::Cylinder {
            round: ends == EndsConfig::Round,
        },
    };
    let orientation = match orientation {
        OrientationConfig::Isotropic => Orientation::Isotropic,
        OrientationConfig::Aligned(u) => Orientation::Aligned(v3(u)),
        OrientationConfig::Tensor((a, b, c)) => {
            Orientation::Tensor(Matrix3::new(a.0, a.1, a.2, b.0, b.1, b.2, c.0, c.1, c.2))
        }
    };
    let p = ShapeParams {
        sizes: RadiusDistribution::gaussian(radius_cov),
        min_gap,
        orientation,
        // The model's container replaces this one.
        ..ShapeParams::new(
            Container::Periodic { size: [1.0; 3] },
            kind,
            aspect,
            radius,
            fraction,
        )
    };
    p.validate().map_err(|e| match e {
        demcon_core::CoreError::InvalidParameter {
            field: f,
            value,
            allowed,
        } => {
            let f = if f.starts_with("radius-") {
                "radius_cov"
            } else {
                f.as_str()
            };
            SceneError::invalid(&format!("{field}.{f}"), value, allowed)
        }
        other => SceneError::at(field, other),
    })?;
    Ok(Some(p))
}
