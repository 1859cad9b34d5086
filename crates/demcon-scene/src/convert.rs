//! Conversion of file-facing `…Config` types into the lower crates' plain types, with the
//! field path in every error.

use demcon_core::{Axis, Container, CoreError, Face, Material, MaterialTable, Region, Selector, Vec3};

use crate::config::*;
use crate::error::SceneError;

fn v3(t: (f64, f64, f64)) -> Vec3 {
    Vec3::new(t.0, t.1, t.2)
}

fn finite3(field: &str, t: (f64, f64, f64)) -> Result<Vec3, SceneError> {
    if [t.0, t.1, t.2].iter().all(|v| v.is_finite()) {
        Ok(v3(t))
    } else {
        Err(SceneError::invalid(
            field,
            format!("{t:?}"),
            "coordinates must be finite (m)",
        ))
    }
}

fn positive(field: &str, v: f64) -> Result<f64, SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(SceneError::invalid(field, v, "must be a finite number > 0"))
    }
}

/// The container of a `ContainerConfig`, validated.
pub fn container(c: &ContainerConfig, field: &str) -> Result<Container, SceneError> {
    let out = match *c {
        ContainerConfig::Box { size } => Container::Box {
            size: [size.0, size.1, size.2],
        },
        ContainerConfig::Cylinder { radius, length } => Container::Cylinder { radius, length },
        ContainerConfig::Sphere { radius } => Container::Sphere { radius },
        ContainerConfig::Periodic { size } => Container::Periodic {
            size: [size.0, size.1, size.2],
        },
    };
    out.validate().map_err(|e| SceneError::at(field, e))?;
    Ok(out)
}

/// The axis.
pub fn axis(a: AxisConfig) -> Axis {
    match a {
        AxisConfig::X => Axis::X,
        AxisConfig::Y => Axis::Y,
        AxisConfig::Z => Axis::Z,
    }
}

/// The face.
pub fn face(f: FaceConfig) -> Face {
    match f {
        FaceConfig::XMin => Face::XMin,
        FaceConfig::XMax => Face::XMax,
        FaceConfig::YMin => Face::YMin,
        FaceConfig::YMax => Face::YMax,
        FaceConfig::ZMin => Face::ZMin,
        FaceConfig::ZMax => Face::ZMax,
        FaceConfig::Outer => Face::Outer,
    }
}

/// The region, validated (positive radii and lengths, min < max).
pub fn region(r: &RegionConfig, field: &str) -> Result<Region, SceneError> {
    Ok(match r {
        RegionConfig::Box { min, max } => {
            let (a, b) = (
                finite3(&format!("{field}.min"), *min)?,
                finite3(&format!("{field}.max"), *max)?,
            );
            if (0..3).any(|k| a[k] >= b[k]) {
                return Err(SceneError::invalid(
                    &format!("{field}.max"),
                    format!("{max:?}"),
                    format!("must exceed min = {min:?} on every axis"),
                ));
            }
            Region::Box { min: a, max: b }
        }
        RegionConfig::Cylinder {
            base,
            axis: ax,
            radius,
            length,
        } => Region::Cylinder {
            base: finite3(&format!("{field}.base"), *base)?,
            axis: axis(*ax),
            radius: positive(&format!("{field}.radius"), *radius)?,
            length: positive(&format!("{field}.length"), *length)?,
        },
        RegionConfig::Sphere { centre, radius } => Region::Sphere {
            centre: finite3(&format!("{field}.centre"), *centre)?,
            radius: positive(&format!("{field}.radius"), *radius)?,
        },
        RegionConfig::Difference(a, b) => Region::Difference(
            Box::new(region(a, &format!("{field}.Difference.0"))?),
            Box::new(region(b, &format!("{field}.Difference.1"))?),
        ),
        RegionConfig::Union(rs) => Region::Union(
            rs.iter()
                .enumerate()
                .map(|(i, r)| region(r, &format!("{field}.Union[{i}]")))
                .collect::<Result<_, _>>()?,
        ),
        RegionConfig::Intersection(rs) => Region::Intersection(
            rs.iter()
                .enumerate()
                .map(|(i, r)| region(r, &format!("{field}.Intersection[{i}]")))
                .collect::<Result<_, _>>()?,
        ),
    })
}

/// The selector; material names are resolved to phase ids.
pub fn selector(s: &SelectorConfig, materials: &MaterialTable, field: &str) -> Result<Selector, SceneError> {
    Ok(match s {
        SelectorConfig::All => Selector::All,
        SelectorConfig::Face(f) => Selector::Face(face(*f)),
        SelectorConfig::Region(r) => Selector::Region(region(r, &format!("{field}.Region"))?),
        SelectorConfig::Material(name) => {
            Selector::Phase(materials.phase_of(name).map_err(|e| SceneError::at(field, e))?)
        }
        SelectorConfig::Particles(ids) => Selector::Particles(ids.clone()),
    })
}

/// The material table, validated; names must be unique.
pub fn materials(ms: &[MaterialConfig]) -> Result<MaterialTable, SceneError> {
    for (i, m) in ms.iter().enumerate() {
        if ms[..i].iter().any(|o| o.name == m.name) {
            return Err(SceneError::invalid(
                &format!("materials[{i}].name"),
                &m.name,
                "material names must be unique",
            ));
        }
    }
    let table = MaterialTable::new(
        ms.iter()
            .map(|m| Material {
                name: m.name.clone(),
                conductivity: m.conductivity,
                density: m.density,
                specific_heat: m.specific_heat,
                resistivity: m.resistivity,
                resistivity_temp_coeff: m.resistivity_temp_coeff,
                resistivity_ref_temp: m.resistivity_ref_temp,
            })
            .collect(),
    )
    .map_err(|e: CoreError| SceneError::at("materials", e))?;
    Ok(table)
}
