//! Conversion of file-facing `…Config` types into the lower crates' plain types, with the
//! field path in every error: [`problem`] turns a whole scene into one [`Problem`] (what to
//! build, the thermal and electric physics, the post-processing). Value checks live in
//! `validate.rs`; this file only translates.

use std::path::Path;

use demcon_core::{
    Axis, Container, CoreError, Face, Material, MaterialTable, Region, Selector, TimeValue, Vec3,
};
use demcon_graph::{ContactParams, CrackShape, InterfaceRule, LaguerreParams};
use demcon_model::{
    CarveRule, Crack, CtSpec, Damage, DefectSpec, ElectricProblem, Electrode, ElectrodeAt, FieldNames,
    GrainBoundary, InterfaceResistance, ModelParams, PhaseRule, PhaseSpec, SurfaceSpec, ThermalBc,
    ThermalProblem, ThermalSolver, TimeStepSpec, VolumeSource,
};
use demcon_network::{FloatingPolicy, Method, SolveParams};
use demcon_post::{HaloParams, HaloPhases, Line, ProbeMethod};
use demcon_thermal::{CheckpointEvery, Scheme};

use crate::config::*;
use crate::error::SceneError;

/// Where each part of the model's input sits in a scene file: the model names a refused value
/// by these paths.
pub const SCENE_FIELDS: FieldNames = FieldNames {
    bcs: "thermal.bcs",
    sources: "thermal.sources",
    solver: "thermal.solver",
    electrodes: "electric.electrodes",
    electric_homogenize: "electric.homogenize",
    recouple_tolerance: "electric.recouple_tolerance",
    checkpoint: "checkpoint",
    surface: "surface",
    phases: "phases",
    inclusions: "phases.Inclusions",
    phase_rule: "phase_rule",
    carve: "carve",
    contacts: "contacts",
    defects: "defects",
    interfaces: "interfaces",
    grain_boundaries: "grain_boundaries",
    cracks: "cracks",
    damage: "damage",
    cut_contacts: "cut_contacts",
    etc_axis: "outputs.etc_axis",
};

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

/// The scene's words for a container (the inverse of [`container`]).
pub fn container_config(c: &Container) -> ContainerConfig {
    match *c {
        Container::Box { size } => ContainerConfig::Box {
            size: (size[0], size[1], size[2]),
        },
        Container::Periodic { size } => ContainerConfig::Periodic {
            size: (size[0], size[1], size[2]),
        },
        Container::Cylinder { radius, length } => ContainerConfig::Cylinder { radius, length },
        Container::Sphere { radius } => ContainerConfig::Sphere { radius },
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
        FaceConfig::Carved => Face::Carved,
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
            .map(|m| {
                Ok(Material {
                    name: m.name.clone(),
                    conductivity: m.conductivity,
                    conductivity_temp_coeff: m.conductivity_temp_coeff,
                    conductivity_ref_temp: m.conductivity_ref_temp,
                    conductivity_tensor: m.conductivity_tensor.map(tensor),
                    tensor_in_shape_frame: m.tensor_in_shape_frame,
                    conductivity_table: m
                        .conductivity_table
                        .clone()
                        .map(|points| {
                            TimeValue::table(points, &format!("materials[{}].conductivity_table", m.name))
                        })
                        .transpose()?,
                    density: m.density,
                    specific_heat: m.specific_heat,
                    resistivity: m.resistivity,
                    resistivity_temp_coeff: m.resistivity_temp_coeff,
                    resistivity_ref_temp: m.resistivity_ref_temp,
                })
            })
            .collect::<Result<Vec<_>, CoreError>>()
            .map_err(|e| SceneError::at("materials", e))?,
    )
    .map_err(|e: CoreError| SceneError::at("materials", e))?;
    Ok(table)
}

/// The surface model's specification.
pub fn surface(s: &SurfaceConfig) -> SurfaceSpec {
    match s {
        SurfaceConfig::TerrerosAlpha => SurfaceSpec::TerrerosAlpha,
        SurfaceConfig::Laguerre => SurfaceSpec::Laguerre,
        SurfaceConfig::Calibrated { c_t: CtConfig::Auto } => SurfaceSpec::Calibrated(CtSpec::Auto),
        SurfaceConfig::Calibrated {
            c_t: CtConfig::Value(v),
        } => SurfaceSpec::Calibrated(CtSpec::Value(*v)),
    }
}

/// The interface rule.
pub fn interface(i: InterfaceConfig) -> InterfaceRule {
    match i {
        InterfaceConfig::Harmonic => InterfaceRule::HarmonicMean,
        InterfaceConfig::Arithmetic => InterfaceRule::ArithmeticMean,
    }
}

/// The floating-cluster policy.
pub fn floating(f: FloatingConfig) -> FloatingPolicy {
    match f {
        FloatingConfig::Exclude => FloatingPolicy::Exclude,
        FloatingConfig::Fail => FloatingPolicy::Fail,
    }
}

/// The scene's phase rule: its own, or by default `Segment` with an image (conforming cells
/// follow only coarse voxel faces), `Conforming` when every network is the Laguerre cells'
/// and `Centre` otherwise.
pub fn phase_rule_of(cfg: &SceneConfig) -> PhaseRuleConfig {
    cfg.phase_rule.unwrap_or(if has_image(cfg) {
        PhaseRuleConfig::Segment
    } else if only_laguerre(cfg) {
        PhaseRuleConfig::Conforming
    } else {
        PhaseRuleConfig::Centre
    })
}

/// Whether a phase entry is read from an image: its surfaces are a level set through the voxel
/// faces, so the default phase rule is then `Segment`.
pub fn has_image(cfg: &SceneConfig) -> bool {
    cfg.phases.iter().any(|p| matches!(p, PhaseConfig::Image { .. }))
}

/// The phase rule.
pub fn phase_rule(r: PhaseRuleConfig) -> PhaseRule {
    match r {
        PhaseRuleConfig::Centre => PhaseRule::Centre,
        PhaseRuleConfig::Laminate => PhaseRule::Laminate,
        PhaseRuleConfig::Segment => PhaseRule::Segment,
        PhaseRuleConfig::Conforming => PhaseRule::Conforming,
    }
}

/// Contact parameters: a target coordination (7.5 by default) or a relative gap tolerance.
pub fn contact_params(c: &ContactsConfig) -> Result<ContactParams, SceneError> {
    match (c.coordination, c.tolerance) {
        (Some(_), Some(_)) => Err(SceneError::invalid(
            "contacts",
            "both coordination and tolerance",
            "give one of `coordination` (target mean Z) or `tolerance` (relative gap)",
        )),
        (None, Some(t)) => Ok(ContactParams::relative(t)),
        (Some(z), None) => Ok(ContactParams::target(z)),
        (None, None) => Ok(ContactParams::target(7.5)),
    }
}

/// What to build on the packed particles: materials, carving, phases, contacts.
pub fn model_params(cfg: &SceneConfig, base_dir: &Path) -> Result<ModelParams, SceneError> {
    let materials = materials(&cfg.materials)?;
    let carve = match &cfg.carve {
        Some(r) => Some((
            region(r, "carve")?,
            match cfg.carve_rule {
                CarveRuleConfig::WholeSphere => CarveRule::WholeSphere,
                CarveRuleConfig::Centre => CarveRule::Centre,
            },
        )),
        None => None,
    };
    let mut phases = Vec::with_capacity(cfg.phases.len());
    for (i, ph) in cfg.phases.iter().enumerate() {
        let field = format!("phases[{i}]");
        if let PhaseConfig::Image {
            path,
            voxel,
            origin,
            labels,
            dims,
            dtype,
        } = ph
        {
            let mut map = Vec::with_capacity(labels.len());
            for (k, (label, name)) in labels.iter().enumerate() {
                let phase = materials
                    .phase_of(name)
                    .map_err(|e| SceneError::at(&format!("{field}.labels[{k}]"), e))?;
                map.push((*label, phase));
            }
            if !(voxel.is_finite() && *voxel > 0.0) {
                return Err(SceneError::invalid(
                    &format!("{field}.voxel"),
                    voxel,
                    "a finite size > 0 (m)",
                ));
            }
            let image = crate::image::read_image(&base_dir.join(path), *dims, dtype.as_deref(), &field)?;
            let periodic = matches!(
                known_container(cfg, base_dir),
                Ok(Some(Container::Periodic { .. }))
            );
            let labels = crate::image::label_regions(&image, *voxel, v3(*origin), &map, periodic, &field)?;
            phases.push(PhaseSpec::Image { labels });
            continue;
        }
        let material = ph.materials()[0];
        let phase = materials
            .phase_of(material)
            .map_err(|e| SceneError::at(&format!("{field}.material"), e))?;
        phases.push(match ph {
            PhaseConfig::Region { region: r, .. } => PhaseSpec::Region {
                phase,
                region: region(r, &format!("{field}.region"))?,
            },
            PhaseConfig::Inclusions {
                fraction, size_ratio, ..
            } => PhaseSpec::Inclusions {
                phase,
                fraction: *fraction,
                size_ratio: *size_ratio,
            },
            PhaseConfig::Spheres { radius, centres, .. } => {
                check_spheres(&field, *radius, centres)?;
                PhaseSpec::Spheres {
                    phase,
                    radius: *radius,
                    centres: centres.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect(),
                }
            }
            PhaseConfig::Shapes { shapes, file, .. } => PhaseSpec::Shapes {
                phase,
                shapes: crate::shapes::shape_list(&field, shapes, file.as_deref(), base_dir)?,
            },
            PhaseConfig::Image { .. } => unreachable!("converted above"),
            PhaseConfig::RandomShapes { .. } => PhaseSpec::RandomShapes {
                phase,
                placement: crate::shapes::random_shape_params(&field, ph)?
                    .expect("a RandomShapes entry has a placement"),
                placed: None,
            },
        });
    }
    let defects = defect_spec(cfg, &materials)?;
    Ok(ModelParams {
        materials,
        carve,
        phases,
        phase_rule: phase_rule(phase_rule_of(cfg)),
        contacts: contact_params(&cfg.contacts)?,
        laguerre: uses_laguerre(cfg).then(LaguerreParams::default),
        defects,
        seed: cfg.seed,
        fields: SCENE_FIELDS,
    })
}

/// The phase of a material named at `field`: `interfaces[0].between[1]: unknown material
/// "epoxi"; known: epoxy, silica`.
fn named_phase(materials: &MaterialTable, name: &str, field: &str) -> Result<u16, SceneError> {
    materials.phase_of(name).map_err(|_| {
        let names: Vec<&str> = materials.materials.iter().map(|m| m.name.as_str()).collect();
        SceneError::invalid(
            field,
            format!("\"{name}\""),
            format!("unknown material; known: {}", names.join(", ")),
        )
    })
}

/// Interfaces, cracks and damage regions of the scene (the broken bonds of `cut_contacts` are
/// read from their file by the build). Values are checked by [`DefectSpec::validate`] in
/// `validate.rs`; this only resolves names and converts.
pub fn defect_spec(cfg: &SceneConfig, materials: &MaterialTable) -> Result<DefectSpec, SceneError> {
    let mut interfaces = Vec::with_capacity(cfg.interfaces.len());
    for (i, it) in cfg.interfaces.iter().enumerate() {
        let a = named_phase(materials, &it.between.0, &format!("interfaces[{i}].between[0]"))?;
        let b = named_phase(materials, &it.between.1, &format!("interfaces[{i}].between[1]"))?;
        interfaces.push(InterfaceResistance {
            phases: [a, b],
            conductance: it.conductance,
            electric_resistance: it.electric_resistance,
        });
    }
    let grain_boundaries = cfg
        .grain_boundaries
        .iter()
        .enumerate()
        .map(|(i, gb)| {
            Ok(GrainBoundary {
                phase: named_phase(
                    materials,
                    &gb.material,
                    &format!("grain_boundaries[{i}].material"),
                )?,
                conductance: gb.conductance,
                electric_resistance: gb.electric_resistance,
                spread: gb.spread,
                seed: cfg.seed,
            })
        })
        .collect::<Result<Vec<_>, SceneError>>()?;
    let cracks = cfg
        .cracks
        .iter()
        .map(|c| match c {
            CrackConfig::Disc {
                centre,
                normal,
                radius,
                gap_conductance,
                gap_electric_resistance,
            } => Crack {
                shape: CrackShape::Disc {
                    centre: v3(*centre),
                    normal: v3(*normal),
                    radius: *radius,
                },
                gap_conductance: *gap_conductance,
                gap_electric_resistance: *gap_electric_resistance,
            },
            CrackConfig::Polygon {
                points,
                gap_conductance,
                gap_electric_resistance,
            } => Crack {
                shape: CrackShape::Polygon {
                    points: points.iter().map(|&p| v3(p)).collect(),
                },
                gap_conductance: *gap_conductance,
                gap_electric_resistance: *gap_electric_resistance,
            },
        })
        .collect();
    let mut damage = Vec::with_capacity(cfg.damage.len());
    for (i, d) in cfg.damage.iter().enumerate() {
        damage.push(Damage {
            region: region(&d.region, &format!("damage[{i}].region"))?,
            factor: d.factor,
        });
    }
    Ok(DefectSpec {
        interfaces,
        grain_boundaries,
        cracks,
        damage,
        cut_pairs: Vec::new(),
        whole_facet_cuts: false,
    })
}

/// The values of a `Spheres` phase: a finite radius > 0, at least one centre, finite centres.
fn check_spheres(field: &str, radius: f64, centres: &[(f64, f64, f64)]) -> Result<(), SceneError> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(SceneError::invalid(
            &format!("{field}.radius"),
            radius,
            "must be a finite number > 0 (m)",
        ));
    }
    if centres.is_empty() {
        return Err(SceneError::invalid(
            &format!("{field}.centres"),
            "[]",
            "give at least one centre (m)",
        ));
    }
    if let Some(k) = centres
        .iter()
        .position(|c| !(c.0.is_finite() && c.1.is_finite() && c.2.is_finite()))
    {
        return Err(SceneError::invalid(
            &format!("{field}.centres[{k}]"),
            format!("{:?}", centres[k]),
            "must be finite (m)",
        ));
    }
    Ok(())
}

/// Whether the scene's network is the Laguerre tessellation: a physics it runs asks for the
/// Laguerre surface (validation refuses a scene whose two physics disagree).
pub fn uses_laguerre(cfg: &SceneConfig) -> bool {
    let thermal = cfg.thermal.is_some() && matches!(cfg.surface, SurfaceConfig::Laguerre);
    let electric = cfg
        .electric
        .as_ref()
        .is_some_and(|e| matches!(electric_surface(cfg, e), SurfaceConfig::Laguerre));
    thermal || electric
}

/// Whether the scene has a network and every network is the Laguerre cells' (the conforming
/// seeds are sites of the one model both physics share).
pub fn only_laguerre(cfg: &SceneConfig) -> bool {
    let thermal = cfg.thermal.is_none() || matches!(cfg.surface, SurfaceConfig::Laguerre);
    let electric = cfg
        .electric
        .as_ref()
        .is_none_or(|e| matches!(electric_surface(cfg, e), SurfaceConfig::Laguerre));
    uses_laguerre(cfg) && thermal && electric
}

/// The electric network's surface model: its own, or the thermal network's `surface` when it
/// sets none.
pub fn electric_surface(cfg: &SceneConfig, e: &ElectricConfig) -> SurfaceConfig {
    e.surface.unwrap_or(cfg.surface)
}

/// The tensor (W/(m·K), rows) of a conductivity tensor: λ⊥ I + (λ∥ − λ⊥) a aᵀ for a
/// transversely isotropic one (a the unit axis; a zero axis gives NaN, refused by the
/// material's check).
pub fn tensor(t: ConductivityTensorConfig) -> [[f64; 3]; 3] {
    match t {
        ConductivityTensorConfig::Transverse { axis, along, across } => {
            let a = v3(axis);
            let a = a / a.norm();
            std::array::from_fn(|i| {
                std::array::from_fn(|j| if i == j { across } else { 0.0 } + (along - across) * a[i] * a[j])
            })
        }
        ConductivityTensorConfig::Full((r0, r1, r2)) => {
            [[r0.0, r0.1, r0.2], [r1.0, r1.1, r1.2], [r2.0, r2.1, r2.2]]
        }
    }
}

/// A value of the scene that may follow a time table, checked ([`TimeValue::table`]).
pub fn timed(v: &TimedConfig, field: &str) -> Result<TimeValue, SceneError> {
    Ok(match v {
        TimedConfig::Constant(c) => TimeValue::Constant(*c),
        TimedConfig::Table(points) => TimeValue::table(points.clone(), field)?,
    })
}

/// The thermal values of the scene that follow a time table, with their fields.
pub fn thermal_tables(t: &ThermalConfig) -> Vec<(String, &TimedConfig)> {
    let mut out = Vec::new();
    for (i, bc) in t.bcs.iter().enumerate() {
        let (what, v) = match bc {
            ThermalBcConfig::WallTemperature { value, .. } => ("value", value),
            ThermalBcConfig::HeatFlux { flux, .. } => ("flux", flux),
            ThermalBcConfig::Convection { t_inf, .. } => ("t_inf", t_inf),
            ThermalBcConfig::Radiation { t_surroundings, .. } => ("t_surroundings", t_surroundings),
            ThermalBcConfig::FixedTemperature { .. } => continue,
        };
        out.push((format!("thermal.bcs[{i}].{what}"), v));
    }
    for (i, s) in t.sources.iter().enumerate() {
        out.push((format!("thermal.sources[{i}].power_density"), &s.power_density));
    }
    out.retain(|(_, v)| matches!(v, TimedConfig::Table(_)));
    out
}

/// The thermal problem of the scene.
pub fn thermal_problem(
    cfg: &SceneConfig,
    t: &ThermalConfig,
    materials: &MaterialTable,
) -> Result<ThermalProblem, SceneError> {
    let mut bcs = Vec::with_capacity(t.bcs.len());
    for (i, bc) in t.bcs.iter().enumerate() {
        bcs.push(match bc {
            ThermalBcConfig::FixedTemperature { select, value } => ThermalBc::FixedTemperature {
                select: selector(select, materials, &format!("thermal.bcs[{i}].select"))?,
                value: *value,
            },
            ThermalBcConfig::WallTemperature { face: f, value } => ThermalBc::WallTemperature {
                face: face(*f),
                value: timed(value, &format!("thermal.bcs[{i}].value"))?,
            },
            ThermalBcConfig::HeatFlux { face: f, flux } => ThermalBc::HeatFlux {
                face: face(*f),
                flux: timed(flux, &format!("thermal.bcs[{i}].flux"))?,
            },
            ThermalBcConfig::Convection { face: f, h, t_inf } => ThermalBc::Convection {
                face: face(*f),
                h: *h,
                t_inf: timed(t_inf, &format!("thermal.bcs[{i}].t_inf"))?,
            },
            ThermalBcConfig::Radiation {
                face: f,
                emissivity,
                t_surroundings,
            } => ThermalBc::Radiation {
                face: face(*f),
                emissivity: *emissivity,
                t_surroundings: timed(t_surroundings, &format!("thermal.bcs[{i}].t_surroundings"))?,
            },
        });
    }
    let sources: Vec<VolumeSource> = t
        .sources
        .iter()
        .enumerate()
        .map(|(i, s)| {
            Ok(VolumeSource {
                select: selector(&s.select, materials, &format!("thermal.sources[{i}].select"))?,
                power_density: timed(&s.power_density, &format!("thermal.sources[{i}].power_density"))?,
            })
        })
        .collect::<Result<_, SceneError>>()?;
    let solver = match t.solver {
        ThermalSolverConfig::Explicit { t_end, dt } => ThermalSolver::Explicit {
            t_end,
            dt: match dt {
                TimeStepConfig::Auto { safety } => TimeStepSpec::Auto { safety },
                TimeStepConfig::Fixed { dt, allow_unstable } => TimeStepSpec::Fixed { dt, allow_unstable },
                TimeStepConfig::Paper { allow_unstable } => TimeStepSpec::Paper { allow_unstable },
            },
        },
        ThermalSolverConfig::Implicit { t_end, dt, scheme } => ThermalSolver::Implicit {
            t_end,
            dt,
            scheme: match scheme {
                ImplicitSchemeConfig::BackwardEuler => Scheme::BackwardEuler,
                ImplicitSchemeConfig::CrankNicolson => Scheme::CrankNicolson,
            },
        },
        ThermalSolverConfig::Steady => ThermalSolver::Steady,
        ThermalSolverConfig::Homogenize => {
            return Err(SceneError::invalid(
                "thermal.solver",
                "Homogenize",
                "a homogenisation is not a thermal problem with boundary conditions (see `homogenize_plan`)",
            ));
        }
    };
    let mut breakpoints = bcs_and_sources_breakpoints(&bcs, &sources);
    for (i, el) in cfg.electric.iter().flat_map(|e| e.electrodes.iter()).enumerate() {
        breakpoints
            .extend(timed(&el.potential, &format!("electric.electrodes[{i}].potential"))?.breakpoints());
    }
    let output_times = output_times(cfg, t, &breakpoints);
    Ok(ThermalProblem {
        surface: surface(&cfg.surface),
        interface: interface(cfg.interface),
        bcs,
        sources,
        solver,
        initial_temperature: t.initial_temperature,
        output_times,
        floating: floating(cfg.floating),
        solve: solve_params(&cfg.linear_solver),
        progress: None,
    })
}

/// The breakpoints (s) of the time tables among `bcs` and `sources`.
fn bcs_and_sources_breakpoints(bcs: &[ThermalBc], sources: &[VolumeSource]) -> Vec<f64> {
    let mut t = Vec::new();
    for bc in bcs {
        match bc {
            ThermalBc::WallTemperature { value: v, .. }
            | ThermalBc::HeatFlux { flux: v, .. }
            | ThermalBc::Convection { t_inf: v, .. }
            | ThermalBc::Radiation {
                t_surroundings: v, ..
            } => t.extend(v.breakpoints()),
            ThermalBc::FixedTemperature { .. } => {}
        }
    }
    for s in sources {
        t.extend(s.power_density.breakpoints());
    }
    t
}

/// The output times of a transient: `outputs.times`, with the tables' `breakpoints` inside
/// (0, t_end) when `outputs.times_at_breakpoints` asks, in order, each once.
fn output_times(cfg: &SceneConfig, t: &ThermalConfig, breakpoints: &[f64]) -> Vec<f64> {
    let mut times = cfg.outputs.times.clone();
    let t_end = match t.solver {
        ThermalSolverConfig::Explicit { t_end, .. } | ThermalSolverConfig::Implicit { t_end, .. } => t_end,
        _ => return times,
    };
    if cfg.outputs.times_at_breakpoints {
        times.extend(breakpoints.iter().filter(|&&b| b > 0.0 && b < t_end));
        times.sort_by(f64::total_cmp);
        times.dedup();
    }
    times
}

/// The checkpoint schedule of a transient scene (`thermal.checkpoint`), if any.
pub fn checkpoint_every(cfg: &SceneConfig) -> Option<CheckpointEvery> {
    let ck = cfg.thermal.as_ref()?.checkpoint?;
    Some(CheckpointEvery {
        steps: ck.every_steps,
        seconds: ck.every_seconds,
    })
}

/// The electric problem of the scene.
pub fn electric_problem(
    cfg: &SceneConfig,
    e: &ElectricConfig,
    materials: &MaterialTable,
) -> Result<ElectricProblem, SceneError> {
    let mut electrodes = Vec::with_capacity(e.electrodes.len());
    for (i, el) in e.electrodes.iter().enumerate() {
        let at = match (&el.select, &el.face) {
            (Some(sel), None) => ElectrodeAt::Particles(selector(
                sel,
                materials,
                &format!("electric.electrodes[{i}].select"),
            )?),
            (None, Some(f)) => ElectrodeAt::Face(face(*f)),
            (sel, _) => {
                return Err(SceneError::invalid(
                    &format!("electric.electrodes[{i}]"),
                    if sel.is_some() {
                        "both select and face"
                    } else {
                        "neither select nor face"
                    },
                    "give exactly one of `select` (particles held at the potential) or `face` (the container face held at it)",
                ));
            }
        };
        electrodes.push(Electrode {
            at,
            potential: timed(&el.potential, &format!("electric.electrodes[{i}].potential"))?,
        });
    }
    Ok(ElectricProblem {
        surface: surface(&electric_surface(cfg, e)),
        interface: interface(cfg.interface),
        electrodes,
        eta: e.eta,
        floating: floating(cfg.floating),
        recouple_tolerance: e.recouple_tolerance,
        current: e.current,
        solve: solve_params(&cfg.linear_solver),
    })
}

/// The linear solver's parameters.
pub fn solve_params(l: &LinearSolverConfig) -> SolveParams {
    let method = match l.method {
        LinearMethodConfig::Auto => Method::Auto,
        LinearMethodConfig::Multigrid => Method::AmgCg,
        LinearMethodConfig::Mic => Method::IcCg,
        LinearMethodConfig::Jacobi => Method::Cg,
        LinearMethodConfig::Cholesky => Method::Cholesky,
        LinearMethodConfig::Distributed => Method::Distributed,
    };
    SolveParams::new(method, l.rel_tol, l.max_iter)
}

/// How a probe reads a field.
pub fn probe_method(m: ProbeMethodConfig) -> ProbeMethod {
    match m {
        ProbeMethodConfig::Nearest => ProbeMethod::Nearest,
        ProbeMethodConfig::Ball(r) => ProbeMethod::BallAverage { radius: r },
    }
}

/// A probe point.
#[derive(Debug, Clone)]
pub struct Probe {
    /// Name.
    pub name: String,
    /// Point (m).
    pub point: Vec3,
    /// Method.
    pub method: ProbeMethod,
}

/// A profile.
#[derive(Debug, Clone)]
pub struct Profile {
    /// Name.
    pub name: String,
    /// The sampled segment.
    pub line: Line,
    /// Method.
    pub method: ProbeMethod,
}

/// What the post-processing computes.
#[derive(Debug, Clone)]
pub struct PostPlan {
    /// Probes.
    pub probes: Vec<Probe>,
    /// Profiles.
    pub profiles: Vec<Profile>,
    /// Per-particle flux.
    pub flux: bool,
    /// Halo smoothing of the flux.
    pub halo: Option<HaloParams>,
    /// Effective conductivity along this axis.
    pub etc_axis: Option<Axis>,
    /// The fields of a transient at every output time, for the VTK time series (the flux and
    /// its Halo recomputed there when asked for).
    pub series: bool,
    /// The Laguerre cells as polyhedra (`cells.vtu`).
    pub cells: bool,
}

/// The post-processing of the scene.
pub fn post_plan(o: &OutputsConfig) -> PostPlan {
    PostPlan {
        probes: o
            .probes
            .iter()
            .map(|p| Probe {
                name: p.name.clone(),
                point: v3(p.point),
                method: probe_method(p.method),
            })
            .collect(),
        profiles: o
            .profiles
            .iter()
            .map(|p| Profile {
                name: p.name.clone(),
                line: Line {
                    from: v3(p.from),
                    to: v3(p.to),
                    n_points: p.points,
                },
                method: probe_method(p.method),
            })
            .collect(),
        flux: o.flux || o.halo.is_some(),
        halo: o.halo.map(|k| HaloParams {
            ratio: k,
            phases: match o.halo_phases.unwrap_or_default() {
                HaloPhasesConfig::Same => HaloPhases::Same,
                HaloPhasesConfig::All => HaloPhases::All,
            },
            ..HaloParams::default()
        }),
        etc_axis: o.etc_axis.map(axis),
        series: o.vtk || o.contacts_vtk,
        cells: o.cells_vtk,
    }
}

/// The whole scene on plain types: what to build, the physics, the post-processing.
#[derive(Debug, Clone)]
pub struct Problem {
    /// What to build on the packed particles.
    pub model: ModelParams,
    /// The thermal physics.
    pub thermal: Option<ThermalProblem>,
    /// The electric physics.
    pub electric: Option<ElectricProblem>,
    /// Periodic homogenisation (then `thermal` and `electric` are `None`).
    pub homogenize: Option<HomogenizePlan>,
    /// Post-processing.
    pub post: PostPlan,
}

/// What a periodic homogenisation computes: the thermal tensor, the electric one, or both.
#[derive(Debug, Clone, PartialEq)]
pub struct HomogenizePlan {
    /// Thermal surface model and interface rule, when `thermal.solver` is `Homogenize`.
    pub thermal: Option<(SurfaceSpec, InterfaceRule)>,
    /// Electric surface model and interface rule, when `electric.homogenize` is set.
    pub electric: Option<(SurfaceSpec, InterfaceRule)>,
    /// The linear solver.
    pub solve: SolveParams,
}

/// Whether the scene is a periodic homogenisation (thermal `Homogenize` or electric
/// `homogenize: true`).
pub fn is_homogenization(cfg: &SceneConfig) -> bool {
    cfg.thermal
        .as_ref()
        .is_some_and(|t| matches!(t.solver, ThermalSolverConfig::Homogenize))
        || cfg.electric.as_ref().is_some_and(|e| e.homogenize)
}

/// The homogenisation of a scene, when it is one.
pub fn homogenize_plan(cfg: &SceneConfig) -> Option<HomogenizePlan> {
    is_homogenization(cfg).then(|| HomogenizePlan {
        thermal: cfg
            .thermal
            .as_ref()
            .filter(|t| matches!(t.solver, ThermalSolverConfig::Homogenize))
            .map(|_| (surface(&cfg.surface), interface(cfg.interface))),
        electric: cfg
            .electric
            .as_ref()
            .filter(|e| e.homogenize)
            .map(|e| (surface(&electric_surface(cfg, e)), interface(cfg.interface))),
        solve: solve_params(&cfg.linear_solver),
    })
}

/// Converts the whole scene (every conversion error names its field).
pub fn problem(cfg: &SceneConfig, base_dir: &Path) -> Result<Problem, SceneError> {
    let model = model_params(cfg, base_dir)?;
    let homogenize = homogenize_plan(cfg);
    let (thermal, electric) = match (&homogenize, &cfg.thermal, &cfg.electric) {
        (Some(_), _, _) => (None, None),
        (None, t, e) => (
            t.as_ref()
                .map(|t| thermal_problem(cfg, t, &model.materials))
                .transpose()?,
            e.as_ref()
                .map(|e| electric_problem(cfg, e, &model.materials))
                .transpose()?,
        ),
    };
    Ok(Problem {
        model,
        thermal,
        electric,
        homogenize,
        post: post_plan(&cfg.outputs),
    })
}

/// The container, when it is known before packing: a generated packing's, the one the scene
/// gives a file, or the one in the file's header (read alone; a file that cannot be read is
/// reported by the build, as the first thing it does); a tiling's is its packing's, copied.
pub fn known_container(c: &SceneConfig, base_dir: &Path) -> Result<Option<Container>, SceneError> {
    container_of(&c.packing, "packing", base_dir)
}

/// The container of one packing section, when it is known before packing (see
/// [`known_container`]); refusals name `field`.
pub fn container_of(
    p: &PackingConfig,
    field: &str,
    base_dir: &Path,
) -> Result<Option<Container>, SceneError> {
    Ok(match p {
        PackingConfig::Generate { container, .. } | PackingConfig::Given { container, .. } => {
            Some(self::container(container, &format!("{field}.container"))?)
        }
        PackingConfig::File {
            container: Some(container),
            ..
        } => Some(self::container(container, &format!("{field}.container"))?),
        PackingConfig::File {
            path,
            container: None,
        } => demcon_packing::read_xyzr_container(&base_dir.join(path))
            .ok()
            .flatten(),
        PackingConfig::Tile {
            packing,
            repeat,
            walls,
        } => {
            let inner_field = format!("{field}.packing");
            let inner = container_of(packing, &inner_field, base_dir)?;
            let repeat = [repeat.0, repeat.1, repeat.2];
            demcon_packing::tiled_count(1, repeat, &format!("{field}.repeat"))?;
            match inner {
                Some(Container::Periodic { size }) => {
                    let size = [0, 1, 2].map(|k| size[k] * repeat[k] as f64);
                    Some(if *walls {
                        Container::Box { size }
                    } else {
                        Container::Periodic { size }
                    })
                }
                Some(other) => {
                    return Err(SceneError::invalid(
                        &format!("{inner_field}.container"),
                        other.kind(),
                        "only a periodic packing can be tiled: copies of a walled packing would meet at its \
                         walls, with the gaps and layering of a wall between them (pack a Periodic box, and \
                         carve it to shape with `carve` if walls are wanted)",
                    ));
                }
                None => None,
            }
        }
    })
}
