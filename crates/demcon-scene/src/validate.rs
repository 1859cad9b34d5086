//! Every value check of a scene, run before any heavy work (packing, contacts, solves), so a
//! typo does not surface after a long packing. Errors name the field path, the value and what
//! is allowed. Conversions that can fail (regions, selectors, materials) are checked by
//! running them ([`crate::convert::problem`]).

use std::path::Path;

use demcon_core::{Container, Face, Vec3};

use crate::config::*;
use crate::convert;
use crate::error::SceneError;
use demcon_model::surroundings::KELVIN;

/// The refusals of a scene, gathered so that one run reports them all.
#[derive(Default)]
struct Refusals(Vec<SceneError>);

impl Refusals {
    /// Keeps the error of a check.
    fn check<T>(&mut self, r: Result<T, SceneError>) -> Option<T> {
        r.map_err(|e| self.push(e)).ok()
    }

    /// Keeps a refusal (each of several), once: two checks that meet the same bad value
    /// report it once.
    fn push(&mut self, e: SceneError) {
        let errors = match e {
            SceneError::Several(v) => v,
            e => vec![e],
        };
        for e in errors {
            let text = e.to_string();
            if !self.0.iter().any(|k| k.to_string() == text) {
                self.0.push(e);
            }
        }
    }
}

/// Checks the whole scene and returns its plain plan ([`convert::Problem`], the scene's one
/// conversion); relative paths resolve against `base_dir`. Every refusal is reported at once
/// ([`SceneError::Several`] when there are more than one), each check group naming its first
/// bad value.
pub fn validate(c: &SceneConfig, base_dir: &Path) -> Result<convert::Problem, SceneError> {
    let mut r = Refusals::default();
    // Materials, contacts, carving, phases, selectors, electrodes' select/face: by conversion.
    let mut problem = r.check(convert::problem(c, base_dir));
    let container = r.check(convert::known_container(c, base_dir)).flatten();
    if let Some(Some(n)) = r.check(known_count(&c.packing, "packing")) {
        let field = match c.packing {
            PackingConfig::Tile { .. } => "packing.repeat",
            _ => "packing.count",
        };
        r.check(check_run_memory(n, c, container.as_ref(), field));
    }
    r.check(check_contacts(&c.contacts));
    r.check(check_defects(c, base_dir));
    r.check(check_linear_solver(&c.linear_solver));
    r.check(check_probes(c, container.as_ref()));
    if c.thermal.is_none() && c.electric.is_none() {
        r.push(SceneError::invalid(
            "thermal",
            "none",
            "a scene needs `thermal`, `electric` or both",
        ));
    }
    r.check(check_surface("surface", &c.surface));
    if c.phase_rule == Some(PhaseRuleConfig::Conforming) && !convert::only_laguerre(c) {
        r.push(SceneError::invalid(
            "phase_rule",
            "Conforming",
            "conforming seeds shape the Laguerre cells, and both physics share them: set `surface: \
             Laguerre` (the default) for every network, or use `Centre`, `Segment` or `Laminate` with \
             the contact models",
        ));
    }
    r.check(check_tile_walls(c));
    if let Some(k) = container.as_ref() {
        r.check(check_sphere_centres(c, k));
    }
    if let Some(p) = problem.as_mut() {
        r.check(check_shapes(c, &mut p.model, container.as_ref()));
    }
    if convert::is_homogenization(c) {
        check_homogenization(c, container.as_ref(), &mut r);
    }
    if let (Some(_), Some(e)) = (&c.thermal, &c.electric)
        && let Some(es) = e.surface
        && matches!(c.surface, SurfaceConfig::Laguerre) != matches!(es, SurfaceConfig::Laguerre)
    {
        r.push(SceneError::invalid(
            "electric.surface",
            format!("{es:?} (thermal `surface`: {:?})", c.surface),
            "Laguerre cells replace the contacts, so both physics must use them or neither: set `surface` and \
             `electric.surface` both to Laguerre, or both to contact models (or leave `electric.surface` out: \
             it then follows `surface`)",
        ));
    }
    if let Some(t) = &c.thermal {
        r.check(check_thermal(c, t, container.as_ref()));
        check_thermal_conflicts(t, &mut r);
    }
    if let Some(e) = &c.electric {
        r.check(check_electric(c, e, container.as_ref()));
    }
    r.check(check_outputs(c, container.as_ref()));
    check_names(c, &mut r);
    check_shape_frames(c, &mut r);
    SceneError::all(r.0)?;
    problem.ok_or_else(|| SceneError::invalid("scene", "", "could not be converted"))
}

/// Warns of shapes thinner than 1.5 mean site spacings h (known before packing for a generated
/// count): the cells then resolve them poorly. Measured under conforming cells on aligned
/// fibres (`shapes-aligned`): 0.7 % at 1.75 h across, 1.6 % at 1.2 h, 4.3 % at 0.8 h.
fn thin_shapes(c: &SceneConfig, w: &mut Vec<String>) {
    let (PackingConfig::Generate { count, .. }, Ok(Some(k))) = (
        &c.packing,
        convert::container_of(&c.packing, "packing", Path::new("")),
    ) else {
        return;
    };
    if *count == 0 {
        return;
    }
    let h = (k.volume() / *count as f64).cbrt();
    let thickness = |s: &demcon_core::Inclusion| match *s {
        demcon_core::Inclusion::Spheroid { a, b, .. } => 2.0 * a.min(b),
        demcon_core::Inclusion::Cylinder { radius, length, .. } => (2.0 * radius).min(length),
    };
    for (i, ph) in c.phases.iter().enumerate() {
        let thinnest = match ph {
            PhaseConfig::Shapes { shapes, .. } => shapes
                .iter()
                .filter_map(|s| crate::shapes::shape(s, "phase").ok())
                .map(|s| thickness(&s))
                .fold(f64::INFINITY, f64::min),
            PhaseConfig::RandomShapes {
                shape,
                aspect,
                radius,
                radius_cov,
                ..
            } => crate::shapes::one_shape(*shape, *aspect, radius * (1.0 - 2.5 * radius_cov).max(0.0))
                .map_or(f64::INFINITY, |s| thickness(&s)),
            _ => f64::INFINITY,
        };
        if thinnest < 1.5 * h {
            w.push(format!(
                "phases[{i}]: the thinnest shape is {thinnest:.3e} m across, {:.2} mean site spacings (h = {h:.3e} m at \
                 this count): the cells resolve it poorly and its conductivity may be off by a few % (aligned fibres: \
                 1.6 % at 1.2 h across, 4.3 % at 0.8 h); use more particles (h falls as N^(-1/3)) for shapes at least \
                 1.5 h across",
                thinnest / h
            ));
        }
    }
}

/// What a scene asks for that is allowed but probably not meant: warnings for
/// `summary.json`'s `diagnostics` (and the terminal), found without packing.
pub fn scene_warnings(c: &SceneConfig) -> Vec<String> {
    let mut w = Vec::new();
    let mut used = vec![false; c.materials.len()];
    if let Some(u) = used.first_mut() {
        *u = true; // the matrix: every particle no phase claims
    }
    let mut mark = |name: &str| {
        if let Some(k) = c.materials.iter().position(|m| m.name == name) {
            used[k] = true;
        }
    };
    for ph in &c.phases {
        ph.materials().into_iter().for_each(&mut mark);
    }
    for (k, m) in c.materials.iter().enumerate() {
        if !used[k] {
            w.push(format!(
                "materials[{k}] (`{}`) is used by no phase: only the first material and those `phases` name \
                 are in the body",
                m.name
            ));
        }
    }
    thin_shapes(c, &mut w);
    for (i, it) in c.interfaces.iter().enumerate() {
        for name in [&it.between.0, &it.between.1] {
            if let Some(k) = c.materials.iter().position(|m| &m.name == name)
                && !used[k]
            {
                w.push(format!(
                    "interfaces[{i}]: material `{name}` is used by no phase, so this interface is never met"
                ));
            }
        }
    }
    if c.thermal
        .as_ref()
        .is_some_and(|t| matches!(t.solver, ThermalSolverConfig::Homogenize))
    {
        for (k, m) in c.materials.iter().enumerate() {
            if m.conductivity_temp_coeff != 0.0 {
                w.push(format!(
                    "materials[{k}].conductivity_temp_coeff: a homogenisation has no temperature field; its tensor \
                     uses `{}`'s λ at conductivity_ref_temp = {} °C",
                    m.name, m.conductivity_ref_temp
                ));
            }
        }
    }
    for (i, gb) in c.grain_boundaries.iter().enumerate() {
        if let Some(k) = c.materials.iter().position(|m| m.name == gb.material)
            && !used[k]
        {
            w.push(format!(
                "grain_boundaries[{i}]: material `{}` is used by no phase, so these boundaries are never met",
                gb.material
            ));
        }
    }
    w
}

/// A tensor read in each shape's frame belongs to a material that shapes are made of.
fn check_shape_frames(c: &SceneConfig, r: &mut Refusals) {
    for (k, m) in c.materials.iter().enumerate() {
        let shaped = c.phases.iter().any(|ph| {
            matches!(ph, PhaseConfig::Shapes { material, .. } | PhaseConfig::RandomShapes { material, .. }
                if *material == m.name)
        });
        if m.tensor_in_shape_frame && !shaped {
            r.push(SceneError::invalid(
                &format!("materials[{k}].tensor_in_shape_frame"),
                true,
                format!(
                    "the material of a `Shapes` or `RandomShapes` phase (no such phase is made of `{}`, so its \
                     particles have no shape's frame)",
                    m.name
                ),
            ));
        }
    }
}

/// Two probes or two profiles with one name: their rows could not be told apart.
fn check_names(c: &SceneConfig, r: &mut Refusals) {
    let o = &c.outputs;
    let groups: [(&str, Vec<&str>); 2] = [
        (
            "outputs.probes",
            o.probes.iter().map(|p| p.name.as_str()).collect(),
        ),
        (
            "outputs.profiles",
            o.profiles.iter().map(|p| p.name.as_str()).collect(),
        ),
    ];
    for (field, names) in groups {
        for (i, n) in names.iter().enumerate() {
            if let Some(j) = names[..i].iter().position(|m| m == n) {
                r.push(SceneError::invalid(
                    &format!("{field}[{i}].name"),
                    format!("{n:?}"),
                    format!("{field}[{j}] has this name already: give each a name of its own"),
                ));
            }
        }
    }
}

/// Boundary conditions that contradict each other: two conditions on one face (two held
/// temperatures, a flux and a temperature, two fluxes — counting `FixedTemperature` on the
/// particles of a face as a condition on that face), except a `Convection` and a `Radiation`,
/// which together are one face's exchange with its surroundings.
fn check_thermal_conflicts(t: &ThermalConfig, r: &mut Refusals) {
    let face_of = |bc: &ThermalBcConfig| match bc {
        ThermalBcConfig::WallTemperature { face, .. }
        | ThermalBcConfig::HeatFlux { face, .. }
        | ThermalBcConfig::Convection { face, .. }
        | ThermalBcConfig::Radiation { face, .. } => Some(convert::face(*face)),
        ThermalBcConfig::FixedTemperature {
            select: SelectorConfig::Face(face),
            ..
        } => Some(convert::face(*face)),
        ThermalBcConfig::FixedTemperature { .. } => None,
    };
    let kind = |bc: &ThermalBcConfig| match bc {
        ThermalBcConfig::WallTemperature { .. } => "WallTemperature",
        ThermalBcConfig::HeatFlux { .. } => "HeatFlux",
        ThermalBcConfig::FixedTemperature { .. } => "FixedTemperature",
        ThermalBcConfig::Convection { .. } => "Convection",
        ThermalBcConfig::Radiation { .. } => "Radiation",
    };
    let exchange = |bc: &ThermalBcConfig| {
        matches!(
            bc,
            ThermalBcConfig::Convection { .. } | ThermalBcConfig::Radiation { .. }
        )
    };
    for (i, bc) in t.bcs.iter().enumerate() {
        let Some(f) = face_of(bc) else { continue };
        let clash = |o: &ThermalBcConfig| {
            face_of(o) == Some(f) && !(exchange(bc) && exchange(o) && kind(bc) != kind(o))
        };
        if let Some(j) = t.bcs[..i].iter().position(clash) {
            r.push(SceneError::invalid(
                &format!("thermal.bcs[{i}]"),
                format!("{} on {}", kind(bc), f.name()),
                format!(
                    "thermal.bcs[{j}] ({}) is already on face {}: one face takes one condition (merge them, or \
                     move one to another face; a Convection and a Radiation may share a face)",
                    kind(&t.bcs[j]),
                    f.name()
                ),
            ));
        }
    }
}

/// A tiling cut to walls leaves spheres across the faces: only Laguerre cells (clipped at the
/// faces) model that; a contact model would see spheres poking through its walls.
fn check_tile_walls(c: &SceneConfig) -> Result<(), SceneError> {
    if let PackingConfig::Tile { walls: true, .. } = c.packing
        && !matches!(c.surface, SurfaceConfig::Laguerre)
    {
        return Err(SceneError::invalid(
            "packing.walls",
            "true",
            format!(
                "walls cut the tiled spheres at the faces, which only `surface: Laguerre` models (the cells are \
                 clipped there); with `surface: {:?}` keep the tiling periodic (walls: false) or pack a walled \
                 container",
                c.surface
            ),
        ));
    }
    Ok(())
}

/// Number of particles the packing section will give, when it is known before packing
/// (a generated packing, or a tiling of one); errors on a tiling beyond 32-bit ids.
fn known_count(p: &PackingConfig, field: &str) -> Result<Option<usize>, SceneError> {
    Ok(match p {
        PackingConfig::Generate { count, .. } | PackingConfig::Given { count, .. } => Some(*count),
        PackingConfig::File { .. } => None,
        PackingConfig::Tile { packing, repeat, .. } => {
            match known_count(packing, &format!("{field}.packing"))? {
                Some(n) => Some(demcon_packing::tiled_count(
                    n,
                    [repeat.0, repeat.1, repeat.2],
                    &format!("{field}.repeat"),
                )?),
                None => None,
            }
        }
    })
}

/// Memory a run needs per particle (bytes): the peak resident size of whole steady runs with
/// Halo over their particle count, rounded up with a margin for the allocator's state (which
/// moved the same run's peak by 3 %) (`docs/performance.md` §5, 2026-11-24): 1400 B at 10⁶
/// with Laguerre cells (the facet graph with its cells' data; 1863 B and 1829 B at 8·10⁶
/// before the `mem` branch), 1196 B at 2·10⁵ with a contact model (Terreros α, measured
/// before the `mem` branch, which lowered it too: kept as an upper bound).
pub fn run_bytes_per_particle(c: &SceneConfig) -> u64 {
    if matches!(c.surface, SurfaceConfig::Laguerre) {
        RUN_BYTES_PER_PARTICLE_LAGUERRE
    } else {
        RUN_BYTES_PER_PARTICLE_CONTACTS
    }
}

/// See [`run_bytes_per_particle`].
pub const RUN_BYTES_PER_PARTICLE_LAGUERRE: u64 = 1450;
/// See [`run_bytes_per_particle`].
pub const RUN_BYTES_PER_PARTICLE_CONTACTS: u64 = 1300;

/// The sites the conforming cells add to a packing of `n` particles in `container` (0 under
/// another phase rule): ≈ 1.6 A / h² for followed surfaces of area A (m²) and the mean site
/// spacing h = (V/n)^{1/3} — 2 seeds per sample of area 0.55 h², less the particles they
/// replace within ~1 h of the surface (measured 1.12·10⁵ for 1.10·10⁵ estimated on the f = 0.5
/// composite at 2·10⁵, docs/performance.md §6). Surfaces: listed and placed spheres, sphere
/// regions, box regions' faces, cracks, listed and random shapes (not those of a shapes file).
pub fn conforming_extra_sites(n: usize, c: &SceneConfig, container: &Container) -> usize {
    if convert::phase_rule_of(c) != PhaseRuleConfig::Conforming || n == 0 {
        return 0;
    }
    let b = container.bounds();
    let e = b.max - b.min;
    let volume = container.volume();
    let sphere = |r: f64| 4.0 * std::f64::consts::PI * r * r;
    let region_area = |r: &RegionConfig| match r {
        RegionConfig::Sphere { radius, .. } => sphere(*radius),
        RegionConfig::Box { min, max } => {
            let d = [0, 1, 2].map(|k| {
                let (lo, hi) = ([min.0, min.1, min.2][k], [max.0, max.1, max.2][k]);
                (hi.min(b.max[k]) - lo.max(b.min[k])).max(0.0)
            });
            2.0 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0])
        }
        _ => 0.0,
    };
    let mut area: f64 = c
        .phases
        .iter()
        .map(|ph| match ph {
            PhaseConfig::Spheres { radius, centres, .. } => centres.len() as f64 * sphere(*radius),
            // f V of spheres of radius r: area 3 f V / r.
            PhaseConfig::Inclusions {
                fraction, size_ratio, ..
            } => 3.0 * fraction * volume / (0.5 * e.x.min(e.y).min(e.z) / size_ratio),
            PhaseConfig::Region { region, .. } => region_area(region),
            PhaseConfig::Shapes { shapes, .. } => shapes
                .iter()
                .filter_map(|s| crate::shapes::shape(s, "phase").ok())
                .map(|s| s.area())
                .sum(),
            // f V of shapes of one size: f V times one shape's area over its volume.
            PhaseConfig::RandomShapes {
                shape,
                aspect,
                radius,
                fraction,
                ..
            } => crate::shapes::one_shape(*shape, *aspect, *radius)
                .map_or(0.0, |s| fraction * volume * s.area() / s.volume()),
            // Followed only where its faces are coarser than the sites.
            PhaseConfig::Image { .. } => 0.0,
        })
        .sum();
    area += c
        .cracks
        .iter()
        .map(|k| match k {
            CrackConfig::Disc { radius, .. } => std::f64::consts::PI * radius * radius,
            CrackConfig::Polygon { points, .. } => {
                let p: Vec<Vec3> = points.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
                let twice: Vec3 = (0..p.len()).map(|i| p[i].cross(&p[(i + 1) % p.len()])).sum();
                0.5 * twice.norm()
            }
        })
        .sum::<f64>();
    let per_area = (n as f64 / volume).powf(2.0 / 3.0);
    (1.6 * area * per_area).min(4.0 * n as f64) as usize
}

/// Refuses a run of `n` particles (and the conforming seeds they get, [`conforming_extra_sites`])
/// whose memory estimate ([`run_bytes_per_particle`]) exceeds the memory available now
/// (`MemAvailable`; no check where it is unknown). `field` names what set the count.
pub fn check_run_memory(
    n: usize,
    c: &SceneConfig,
    container: Option<&Container>,
    field: &str,
) -> Result<(), SceneError> {
    let Some(available) = demcon_core::available_memory_bound() else {
        return Ok(());
    };
    let per = run_bytes_per_particle(c);
    let seeds = container.map_or(0, |k| conforming_extra_sites(n, c, k));
    let need = (n as u64).saturating_add(seeds as u64).saturating_mul(per);
    if need > available.bytes {
        let with_seeds = if seeds > 0 {
            format!(" and ~{seeds} conforming seeds")
        } else {
            String::new()
        };
        return Err(SceneError::invalid(
            field,
            format!("{n} particles"),
            format!(
                "a run needs about {per} bytes per particle ({:.1} GB for {n} particles{with_seeds}), but only \
                 {:.1} GB is left: the {}: at most ~{} particles",
                need as f64 / 1e9,
                available.bytes as f64 / 1e9,
                available.bound,
                available.bytes / per
            ),
        ));
    }
    Ok(())
}

/// Largest target coordination accepted: a random packing of spheres has at most ~14
/// neighbours within a few percent of a gap, and the contact search's largest relative gap
/// (1) is reached long before a mean of 20.
pub const MAX_COORDINATION: f64 = 20.0;
/// Smallest target coordination accepted: below 2 most particles have at most one contact,
/// the network falls apart into a dust of pairs and rattlers.
pub const MIN_COORDINATION: f64 = 2.0;

/// Contact parameters: a target coordination in [2, 20], or a relative gap in (0, 1].
fn check_contacts(c: &ContactsConfig) -> Result<(), SceneError> {
    if let Some(z) = c.coordination
        && !(MIN_COORDINATION..=MAX_COORDINATION).contains(&z)
    {
        return Err(SceneError::invalid(
            "contacts.coordination",
            z,
            format!(
                "the target mean coordination must lie in [{MIN_COORDINATION}, {MAX_COORDINATION}] (the papers use 7.5)"
            ),
        ));
    }
    if let Some(t) = c.tolerance
        && !(1e-9..=1.0).contains(&t)
    {
        return Err(SceneError::invalid(
            "contacts.tolerance",
            t,
            "the relative gap tolerance must lie in [1e-9, 1] (a gap up to t·(R_p + R_q); below 1e-9 it is \
             round-off)",
        ));
    }
    Ok(())
}

/// Linear solver: a tolerance the arithmetic can honour and a finite iteration budget.
fn check_linear_solver(l: &LinearSolverConfig) -> Result<(), SceneError> {
    if !(1e-15..=1e-2).contains(&l.rel_tol) {
        return Err(SceneError::invalid(
            "linear_solver.rel_tol",
            l.rel_tol,
            "the relative residual must lie in [1e-15, 1e-2] (below 1e-15 is under round-off)",
        ));
    }
    if !(1..=10_000_000).contains(&l.max_iter) {
        return Err(SceneError::invalid(
            "linear_solver.max_iter",
            l.max_iter,
            "must lie in [1, 10⁷]",
        ));
    }
    Ok(())
}

/// Probes must lie in the domain, when it is known before packing.
fn check_probes(c: &SceneConfig, container: Option<&Container>) -> Result<(), SceneError> {
    let domain = match (&c.carve, container) {
        (Some(r), _) => Some(convert::region(r, "carve")?),
        (None, Some(container)) => Some(container.region()),
        _ => None,
    };
    if let Some(d) = domain {
        for (i, p) in c.outputs.probes.iter().enumerate() {
            let x = Vec3::new(p.point.0, p.point.1, p.point.2);
            if !d.contains_point(&x) {
                return Err(SceneError::invalid(
                    &format!("outputs.probes[{i}].point ({})", p.name),
                    format!("{:?}", p.point),
                    "the probe point must lie inside the domain (container or carved region) (m)",
                ));
            }
        }
    }
    Ok(())
}

fn check_surface(field: &str, s: &SurfaceConfig) -> Result<(), SceneError> {
    if let SurfaceConfig::Calibrated {
        c_t: CtConfig::Value(v),
    } = s
        && !(v.is_finite() && *v > 0.0)
    {
        return Err(SceneError::invalid(
            &format!("{field}.c_t"),
            v,
            "must be a finite number > 0",
        ));
    }
    Ok(())
}

fn finite(field: &str, v: f64, what: &str) -> Result<(), SceneError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(SceneError::invalid(field, v, format!("must be finite ({what})")))
    }
}

/// A value that may follow a time table: finite (`what` it is), at least `min` when given
/// (−273.15 °C: a temperature in kelvin ≥ 0); a table well formed ([`TimeValue::table`]),
/// refused in a steady solve, and covering [0, t_end] in a transient.
fn check_timed(
    field: &str,
    v: &TimedConfig,
    what: &str,
    min: Option<f64>,
    solver: &ThermalSolverConfig,
) -> Result<(), SceneError> {
    let value = convert::timed(v, field)?;
    let (lo, hi) = value.range();
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(SceneError::invalid(field, lo, format!("must be finite ({what})")));
    }
    if let Some(m) = min
        && lo < m
    {
        return Err(SceneError::invalid(
            field,
            lo,
            format!("{what} at or above absolute zero, −273.15 °C"),
        ));
    }
    if value.is_constant() {
        return Ok(());
    }
    match *solver {
        ThermalSolverConfig::Explicit { t_end, .. } | ThermalSolverConfig::Implicit { t_end, .. } => {
            value.check_covers(t_end, field)?;
            Ok(())
        }
        _ => Err(SceneError::invalid(
            field,
            "a time table",
            "a constant in a steady solve or a homogenisation (a table needs a transient solver)",
        )),
    }
}

fn positive_time(field: &str, v: f64) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(field, v, "must be a finite time > 0 (s)"))
    }
}

/// A face used by a boundary condition must exist on the container (when it is known).
fn check_face(
    field: &str,
    f: FaceConfig,
    c: &SceneConfig,
    container: Option<&Container>,
) -> Result<(), SceneError> {
    let face = convert::face(f);
    if face == Face::Carved {
        return match (&c.carve, &c.surface) {
            (Some(_), SurfaceConfig::Laguerre) => Ok(()),
            (None, _) => Err(SceneError::invalid(
                field,
                face.name(),
                "the surface of a carving region: set `carve` (the body is then cut from the container by it)",
            )),
            _ => Err(SceneError::invalid(
                field,
                face.name(),
                "the carved surface is a wall only under Laguerre cells (`surface: Laguerre`), whose facets \
                 on it it is made of",
            )),
        };
    }
    match container {
        Some(c) if !c.faces().contains(&face) => Err(SceneError::invalid(
            field,
            face.name(),
            format!("a {} container has the faces {}", c.kind(), face_list(c.faces())),
        )),
        _ => Ok(()),
    }
}

fn face_list(faces: &[Face]) -> String {
    if faces.is_empty() {
        "[] (none)".into()
    } else {
        faces.iter().map(|f| f.name()).collect::<Vec<_>>().join(", ")
    }
}

fn check_thermal(
    c: &SceneConfig,
    t: &ThermalConfig,
    container: Option<&Container>,
) -> Result<(), SceneError> {
    finite(
        "thermal.initial_temperature",
        t.initial_temperature,
        "a temperature (°C)",
    )?;
    let mut fixed = 0;
    for (i, bc) in t.bcs.iter().enumerate() {
        check_thermal_bc(&format!("thermal.bcs[{i}]"), bc, c, &t.solver, container)?;
        fixed += usize::from(!matches!(bc, ThermalBcConfig::HeatFlux { .. }));
    }
    for (i, s) in t.sources.iter().enumerate() {
        check_timed(
            &format!("thermal.sources[{i}].power_density"),
            &s.power_density,
            "a power density (W/m³)",
            None,
            &t.solver,
        )?;
    }
    check_thermal_solver(c, &t.solver, fixed)?;
    if let Some(ck) = &t.checkpoint {
        check_checkpoint(ck, &t.solver)?;
    }
    Ok(())
}

/// One thermal boundary condition at `field` (`thermal.bcs[i]`).
fn check_thermal_bc(
    field: &str,
    bc: &ThermalBcConfig,
    c: &SceneConfig,
    solver: &ThermalSolverConfig,
    container: Option<&Container>,
) -> Result<(), SceneError> {
    match bc {
        ThermalBcConfig::FixedTemperature { value, .. } => {
            finite(&format!("{field}.value"), *value, "a temperature (°C)")?;
        }
        ThermalBcConfig::WallTemperature { face, value } => {
            check_timed(
                &format!("{field}.value"),
                value,
                "a temperature (°C)",
                None,
                solver,
            )?;
            check_face(&format!("{field}.face"), *face, c, container)?;
        }
        ThermalBcConfig::HeatFlux { face, flux } => {
            check_timed(
                &format!("{field}.flux"),
                flux,
                "a flux density (W/m²)",
                None,
                solver,
            )?;
            check_face(&format!("{field}.face"), *face, c, container)?;
        }
        ThermalBcConfig::Convection { face, h, t_inf } => {
            if !(h.is_finite() && *h > 0.0) {
                return Err(SceneError::invalid(
                    &format!("{field}.h"),
                    h,
                    "a film coefficient > 0 (W/(m²·K)); an adiabatic face needs no condition",
                ));
            }
            check_timed(
                &format!("{field}.t_inf"),
                t_inf,
                "a temperature (°C)",
                Some(-KELVIN),
                solver,
            )?;
            check_face(&format!("{field}.face"), *face, c, container)?;
        }
        ThermalBcConfig::Radiation {
            face,
            emissivity,
            t_surroundings,
        } => {
            if !(*emissivity > 0.0 && *emissivity <= 1.0) {
                return Err(SceneError::invalid(
                    &format!("{field}.emissivity"),
                    emissivity,
                    "an emissivity in (0, 1]; a face that does not radiate needs no condition",
                ));
            }
            check_timed(
                &format!("{field}.t_surroundings"),
                t_surroundings,
                "a temperature (°C)",
                Some(-KELVIN),
                solver,
            )?;
            check_face(&format!("{field}.face"), *face, c, container)?;
        }
    }
    Ok(())
}

/// The thermal solver; `fixed`: the boundary conditions that hold or exchange a temperature.
fn check_thermal_solver(
    c: &SceneConfig,
    solver: &ThermalSolverConfig,
    fixed: usize,
) -> Result<(), SceneError> {
    match *solver {
        ThermalSolverConfig::Explicit { t_end, dt } => {
            positive_time("thermal.solver.t_end", t_end)?;
            match dt {
                TimeStepConfig::Auto { safety } if !(safety > 0.0 && safety <= 1.0) => {
                    return Err(SceneError::invalid(
                        "thermal.solver.dt.safety",
                        safety,
                        "must be in (0, 1]",
                    ));
                }
                TimeStepConfig::Fixed { dt, .. } => positive_time("thermal.solver.dt.dt", dt)?,
                TimeStepConfig::Paper { .. } if !matches!(c.surface, SurfaceConfig::Calibrated { .. }) => {
                    return Err(SceneError::invalid(
                        "thermal.solver.dt",
                        "Paper",
                        "the paper's estimate needs the Calibrated surface model",
                    ));
                }
                _ => {}
            }
        }
        ThermalSolverConfig::Implicit { t_end, dt, .. } => {
            positive_time("thermal.solver.t_end", t_end)?;
            positive_time("thermal.solver.dt", dt)?;
        }
        ThermalSolverConfig::Homogenize => {}
        ThermalSolverConfig::Steady => {
            if fixed == 0 {
                return Err(SceneError::invalid(
                    "thermal.bcs",
                    "no FixedTemperature, WallTemperature, Convection or Radiation",
                    "a steady thermal solve needs at least one fixed temperature or a face exchanging heat with \
                     its surroundings",
                ));
            }
        }
    }
    Ok(())
}

/// Shaped-inclusion and image phases: listed shapes where they may lie
/// and random ones in a `Box` or `Periodic` container (when the container is known before
/// packing).
fn check_shapes(
    c: &SceneConfig,
    model: &mut demcon_model::ModelParams,
    container: Option<&Container>,
) -> Result<(), SceneError> {
    let mut errors = Vec::new();
    for (i, ph) in model.phases.iter_mut().enumerate() {
        let field = format!("phases[{i}]");
        match (ph, container) {
            (demcon_model::PhaseSpec::Shapes { shapes, .. }, Some(k)) => {
                if let Err(e) = demcon_model::shapes::check_placement(k, shapes, &field) {
                    errors.push(e.into());
                }
                let disjoint = matches!(c.phases.get(i), Some(PhaseConfig::Shapes { disjoint: true, .. }));
                if let (true, Some((a, b))) = (disjoint, demcon_packing::first_overlap(shapes, k)) {
                    errors.push(SceneError::invalid(
                        &format!("{field}.shapes[{b}]"),
                        format!("touches or overlaps {field}.shapes[{a}]"),
                        "`disjoint: true` asks that no two shapes touch or overlap (shapes from `file` count after \
                         the listed ones)",
                    ));
                }
            }
            (demcon_model::PhaseSpec::Image { labels }, Some(k)) => {
                if let Some((_, v)) = labels.first()
                    && let Err(e) = crate::image::check_covers(&v.image_box(), k, &field)
                {
                    errors.push(e);
                }
                // Conforming cells on the voxel faces: their steps must not be finer than the
                // site spacing (known here for a generated count; the model checks again).
                if convert::phase_rule_of(c) == PhaseRuleConfig::Conforming
                    && let Ok(Some(n)) = known_count(&c.packing, "packing")
                    && n > 0
                {
                    let h = (k.volume() / n as f64).cbrt();
                    if let Err(e) =
                        demcon_model::check_image_conformable(labels, k, h, ("phase_rule", &field))
                    {
                        errors.push(e.into());
                    }
                }
            }
            (demcon_model::PhaseSpec::RandomShapes { .. }, Some(k))
                if !matches!(k, Container::Box { .. } | Container::Periodic { .. }) =>
            {
                errors.push(SceneError::invalid(
                    &field,
                    format!("RandomShapes in a {} container", k.kind()),
                    "random shapes are placed in a Box or a Periodic container",
                ));
            }
            // Placed now, before packing: an unreachable fraction is refused before the heavy
            // work, and the model reuses the shapes.
            (
                demcon_model::PhaseSpec::RandomShapes {
                    placement, placed, ..
                },
                Some(k),
            ) => match demcon_model::shapes::random_shapes(k, placement, c.seed, &field) {
                Ok((shapes, report)) => *placed = Some(Box::new((*k, shapes, report))),
                Err(e) => errors.push(e.into()),
            },
            _ => {}
        }
    }
    SceneError::all(errors)
}

/// `Spheres` phases: every centre inside the container's bounding box.
fn check_sphere_centres(c: &SceneConfig, container: &Container) -> Result<(), SceneError> {
    for (i, ph) in c.phases.iter().enumerate() {
        if let PhaseConfig::Spheres { radius, centres, .. } = ph {
            let centres: Vec<Vec3> = centres.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
            demcon_model::spheres_region(
                container,
                *radius,
                &centres,
                0.0,
                &format!("{}[{i}]", convert::SCENE_FIELDS.phases),
            )?;
        }
    }
    Ok(())
}

/// A periodic homogenisation: a periodic container, no boundary conditions, sources or
/// electrodes, both physics homogenised (or one absent), and no output that needs a field
/// under boundary conditions.
fn check_homogenization(c: &SceneConfig, container: Option<&Container>, r: &mut Refusals) {
    let thermal_h = c
        .thermal
        .as_ref()
        .map(|t| matches!(t.solver, ThermalSolverConfig::Homogenize));
    let electric_h = c.electric.as_ref().map(|e| e.homogenize);
    let field = if thermal_h == Some(true) {
        "thermal.solver"
    } else {
        "electric.homogenize"
    };
    if let Some(k) = container
        && k.period().is_none()
    {
        r.push(SceneError::invalid(
            field,
            if thermal_h == Some(true) {
                "Homogenize"
            } else {
                "true"
            },
            format!(
                "periodic homogenisation needs a `Periodic` container; this packing's is a {} (for an effective \
                 conductivity along one axis use `solver: Steady` with two walls and `outputs.etc_axis`)",
                k.kind()
            ),
        ));
    }
    match (thermal_h, electric_h) {
        (Some(false), Some(true)) => {
            r.push(SceneError::invalid(
                "thermal.solver",
                "not Homogenize",
                "`electric.homogenize: true` homogenises the whole scene: give `thermal.solver: Homogenize` too, \
                 or remove `thermal`",
            ));
        }
        (Some(true), Some(false)) => {
            r.push(SceneError::invalid(
                "electric.homogenize",
                "false",
                "`thermal.solver: Homogenize` homogenises the whole scene: set `electric.homogenize: true` too, \
                 or remove `electric`",
            ));
        }
        _ => {}
    }
    if let Some(t) = &c.thermal {
        if !t.bcs.is_empty() {
            r.push(SceneError::invalid(
                "thermal.bcs",
                format!("{} boundary condition(s)", t.bcs.len()),
                "a homogenisation imposes mean gradients on a periodic cell: give `bcs: []`",
            ));
        }
        if !t.sources.is_empty() {
            r.push(SceneError::invalid(
                "thermal.sources",
                format!("{} source(s)", t.sources.len()),
                "a homogenisation has no sources: give `sources: []`",
            ));
        }
        if t.checkpoint.is_some() {
            r.push(SceneError::invalid(
                "thermal.checkpoint",
                "Some(..)",
                "a homogenisation has nothing to checkpoint",
            ));
        }
    }
    if let Some(e) = &c.electric
        && !e.electrodes.is_empty()
    {
        r.push(SceneError::invalid(
            "electric.electrodes",
            format!("{} electrode(s)", e.electrodes.len()),
            "a homogenisation imposes mean gradients on a periodic cell: give `electrodes: []`",
        ));
    }
    let o = &c.outputs;
    let refused = [
        ("outputs.etc_axis", o.etc_axis.is_some()),
        ("outputs.halo", o.halo.is_some()),
        ("outputs.probes", !o.probes.is_empty()),
        ("outputs.profiles", !o.profiles.is_empty()),
        ("outputs.times", !o.times.is_empty()),
        ("outputs.flux", o.flux),
        ("outputs.contacts_vtk", o.contacts_vtk),
        // Its plots would have nothing to draw: no probes, profiles, temperature or potential.
        ("outputs.plots", o.plots),
    ];
    for (f, _) in refused.iter().filter(|(_, set)| *set) {
        r.push(SceneError::invalid(
            f,
            "set",
            "a homogenisation gives the tensor (`etc_tensor`, `conductivity_tensor` in summary.json) and the \
             fluctuation fields (vtk, particles_csv), not fields under boundary conditions: remove it",
        ));
    }
}

/// Checkpoints: of a transient only, with at least one period, each valid.
fn check_checkpoint(ck: &CheckpointConfig, solver: &ThermalSolverConfig) -> Result<(), SceneError> {
    if matches!(solver, ThermalSolverConfig::Steady) {
        return Err(SceneError::invalid(
            "thermal.checkpoint",
            "Some(..)",
            "a steady solve has nothing to checkpoint: checkpoints need `solver: Explicit(..)` or \
             `Implicit(..)`",
        ));
    }
    if ck.every_steps.is_none() && ck.every_seconds.is_none() {
        return Err(SceneError::invalid(
            "thermal.checkpoint",
            "(every_steps: None, every_seconds: None)",
            "give every_steps (≥ 1), every_seconds (> 0) or both",
        ));
    }
    if ck.every_steps == Some(0) {
        return Err(SceneError::invalid(
            "thermal.checkpoint.every_steps",
            0,
            "must be ≥ 1 (steps between two checkpoints)",
        ));
    }
    if let Some(s) = ck.every_seconds
        && !(s.is_finite() && s > 0.0)
    {
        return Err(SceneError::invalid(
            "thermal.checkpoint.every_seconds",
            s,
            "must be a finite time > 0 (s of wall time between two checkpoints)",
        ));
    }
    Ok(())
}

fn check_electric(
    c: &SceneConfig,
    e: &ElectricConfig,
    container: Option<&Container>,
) -> Result<(), SceneError> {
    if !(0.0..=1.0).contains(&e.eta) {
        return Err(SceneError::invalid("electric.eta", e.eta, "must be in [0, 1]"));
    }
    if let Some(es) = &e.surface {
        check_surface("electric.surface", es)?;
    }
    if let Some(tol) = e.recouple_tolerance {
        if !(tol.is_finite() && tol > 0.0) {
            return Err(SceneError::invalid(
                "electric.recouple_tolerance",
                tol,
                "must be a finite temperature change > 0 (K)",
            ));
        }
        if c.thermal.is_none() {
            return Err(SceneError::invalid(
                "electric.recouple_tolerance",
                tol,
                "re-solving with ρ_e(T) needs `thermal` physics to give the temperatures",
            ));
        }
    }
    if let Some(i) = e.current {
        if !i.is_finite() {
            return Err(SceneError::invalid("electric.current", i, "a finite current (A)"));
        }
        if e.homogenize || e.electrodes.len() != 2 {
            return Err(SceneError::invalid(
                "electric.current",
                i,
                format!(
                    "exactly two electrodes to drive it between (it enters by electrodes[0], leaves by \
                     electrodes[1]); this scene has {}{}",
                    e.electrodes.len(),
                    if e.homogenize { " and homogenises" } else { "" }
                ),
            ));
        }
    }
    if e.homogenize {
        // Checked with the homogenisation.
    } else if e.electrodes.len() < 2 {
        return Err(SceneError::invalid(
            "electric.electrodes",
            format!("{} electrode(s)", e.electrodes.len()),
            "at least two fixed potentials are needed for a current to flow",
        ));
    }
    for (i, m) in c.materials.iter().enumerate() {
        if m.resistivity.is_none() {
            return Err(SceneError::invalid(
                &format!("materials[{i}].resistivity"),
                "none",
                format!(
                    "material `{}` needs a resistivity (Ω·m) in an electric scene",
                    m.name
                ),
            ));
        }
    }
    for (i, el) in e.electrodes.iter().enumerate() {
        if let Some(f) = el.face {
            check_face(&format!("electric.electrodes[{i}].face"), f, c, container)?;
        }
        // One electrode per face: a face electrode and another electrode on the same face
        // (a face electrode or the particles touching it) would short the face.
        let face_of = |el: &ElectrodeConfig| match (&el.face, &el.select) {
            (Some(f), _) | (None, Some(SelectorConfig::Face(f))) => Some(convert::face(*f)),
            _ => None,
        };
        if let Some(f) = face_of(el)
            && let Some(j) = e.electrodes[..i].iter().position(|o| face_of(o) == Some(f))
            && (el.face.is_some() || e.electrodes[j].face.is_some())
        {
            return Err(SceneError::invalid(
                &format!("electric.electrodes[{i}]"),
                f.name(),
                format!(
                    "electric.electrodes[{j}] already holds face {}: give each face one electrode",
                    f.name()
                ),
            ));
        }
        let field = format!("electric.electrodes[{i}].potential");
        let tabled = matches!(el.potential, TimedConfig::Table(_));
        if tabled && e.current.is_some() {
            return Err(SceneError::invalid(
                &field,
                "a time table",
                "a number under `electric.current` (the current sets the potentials)",
            ));
        }
        let solver = c
            .thermal
            .as_ref()
            .map_or(ThermalSolverConfig::Steady, |t| t.solver);
        check_timed(&field, &el.potential, "a potential (V)", None, &solver)?;
    }
    Ok(())
}

fn check_outputs(c: &SceneConfig, container: Option<&Container>) -> Result<(), SceneError> {
    let o = &c.outputs;
    if o.cells_vtk && !convert::uses_laguerre(c) {
        return Err(SceneError::invalid(
            "outputs.cells_vtk",
            "true",
            format!(
                "cells are drawn from the Laguerre tessellation, which `surface: {:?}` does not build: set \
                 `surface: Laguerre` or remove cells_vtk (contacts_vtk draws the contact network of any model)",
                c.surface
            ),
        ));
    }
    if let Some(k) = o.halo
        && !(k.is_finite() && k > 0.0)
    {
        return Err(SceneError::invalid(
            "outputs.halo",
            k,
            "the Halo/particle radius ratio must be > 0",
        ));
    }
    if let (Some(ph), None) = (o.halo_phases, o.halo) {
        return Err(SceneError::invalid(
            "outputs.halo_phases",
            format!("{ph:?}"),
            "only meaningful with a Halo: give `halo: Some(k)` too, or remove halo_phases",
        ));
    }
    let methods = o
        .probes
        .iter()
        .enumerate()
        .map(|(i, p)| (format!("outputs.probes[{i}].method"), p.method))
        .chain(
            o.profiles
                .iter()
                .enumerate()
                .map(|(i, p)| (format!("outputs.profiles[{i}].method"), p.method)),
        );
    for (field, m) in methods {
        if let ProbeMethodConfig::Ball(r) = m
            && !(r.is_finite() && r > 0.0)
        {
            return Err(SceneError::invalid(&field, r, "the ball radius must be > 0 (m)"));
        }
    }
    if let Some(t) = &c.thermal
        && matches!(t.solver, ThermalSolverConfig::Steady)
        && !o.times.is_empty()
    {
        return Err(SceneError::invalid(
            "outputs.times",
            format!("{:?}", o.times),
            "a steady solve has no time: output times belong to a transient (`Explicit` or `Implicit`); \
             remove them",
        ));
    }
    if let Some(ax) = o.etc_axis
        && !convert::is_homogenization(c)
    {
        check_etc(c, convert::axis(ax), container)?;
    }
    Ok(())
}

/// `outputs.etc_axis`: λ_e needs a steady run between exactly two held sets at different
/// temperatures facing each other along the axis, with no heat entering elsewhere (no flux,
/// source or Joule heat), in a walled container (docs/scenes.md, "Effective conductivity").
fn check_etc(
    c: &SceneConfig,
    axis: demcon_core::Axis,
    container: Option<&Container>,
) -> Result<(), SceneError> {
    let ax = format!("{axis:?}");
    let refuse = |why: String| Err(SceneError::invalid("outputs.etc_axis", &ax, why));
    let Some(t) = &c.thermal else {
        return refuse("the effective conductivity is a thermal figure: the scene has no `thermal`".into());
    };
    if !matches!(t.solver, ThermalSolverConfig::Steady) {
        return refuse(
            "the effective conductivity needs a steady state: use `solver: Steady` (a transient's boundary flow \
             is not λ_e ΔT A / L until it has settled)"
                .into(),
        );
    }
    if let Some(k) = container
        && k.period().is_some()
    {
        return refuse(
            "a periodic box conducts round its period as well as between held sets, so no λ_e along one axis \
             follows from them: use `thermal.solver: Homogenize` (with `bcs: []`) for the effective tensor"
                .into(),
        );
    }
    if let Some((i, _)) = t.bcs.iter().enumerate().find(|(_, b)| {
        matches!(
            b,
            ThermalBcConfig::Convection { .. } | ThermalBcConfig::Radiation { .. }
        )
    }) {
        return refuse(format!(
            "thermal.bcs[{i}] exchanges heat with the surroundings: heat then leaves elsewhere than through the two \
             held sets and no single λ_e describes the body; an ETC run holds two faces and nothing else"
        ));
    }
    if let Some((i, _)) = t
        .bcs
        .iter()
        .enumerate()
        .find(|(_, b)| matches!(b, ThermalBcConfig::HeatFlux { .. }))
    {
        return refuse(format!(
            "thermal.bcs[{i}] imposes a heat flux: heat then enters elsewhere than through the two held sets and \
             no single λ_e describes the body; an ETC run holds two faces and nothing else"
        ));
    }
    if !t.sources.is_empty() {
        return refuse(format!(
            "thermal.sources adds heat inside the body ({} source(s)): the heat through the two held sets then \
             differs and no single λ_e describes it; remove the sources for an ETC run",
            t.sources.len()
        ));
    }
    if let Some(e) = &c.electric
        && e.eta > 0.0
    {
        return refuse(format!(
            "Joule heating (electric.eta = {}) adds heat inside the body: the heat through the two held sets \
             then differs; set `electric.eta: 0.0` or drop `etc_axis`",
            e.eta
        ));
    }
    let held: Vec<(usize, f64)> = t
        .bcs
        .iter()
        .enumerate()
        .filter_map(|(i, b)| match b {
            ThermalBcConfig::FixedTemperature { value, .. } => Some((i, *value)),
            ThermalBcConfig::WallTemperature { value, .. } => {
                Some((i, convert::timed(value, "").ok()?.at(0.0)))
            }
            ThermalBcConfig::HeatFlux { .. }
            | ThermalBcConfig::Convection { .. }
            | ThermalBcConfig::Radiation { .. } => None,
        })
        .collect();
    let [(i, a), (j, b)] = held[..] else {
        return refuse(format!(
            "ETC needs exactly two fixed-temperature sets (found {}): the body between two held faces",
            held.len()
        ));
    };
    if a == b {
        return refuse(format!(
            "thermal.bcs[{i}] and thermal.bcs[{j}] hold the same temperature ({a} °C): λ_e needs a difference"
        ));
    }
    for (i, b) in t.bcs.iter().enumerate() {
        let face = match b {
            ThermalBcConfig::WallTemperature { face, .. }
            | ThermalBcConfig::FixedTemperature {
                select: SelectorConfig::Face(face),
                ..
            } => convert::face(*face),
            _ => continue,
        };
        if face.axis() != Some(axis) {
            return refuse(format!(
                "thermal.bcs[{i}] holds face {}, which is not normal to {ax}: the held sets face each other along \
                 another axis; set `etc_axis` to theirs",
                face.name()
            ));
        }
    }
    if let Some(cont) = container
        && cont.section_and_length(axis).is_none()
    {
        return refuse("the container has no flat faces normal to this axis".into());
    }
    Ok(())
}

/// Interfaces, cracks, damage and the broken-bond file: every value (field paths from
/// [`demcon_model::DefectSpec::validate`]), an interface pair listed twice, a filled crack
/// without its electric resistance in an electric scene, and the file of `cut_contacts` read
/// and its indices checked against the packing's count when it is known.
fn check_defects(c: &SceneConfig, base_dir: &Path) -> Result<(), SceneError> {
    let materials = convert::materials(&c.materials)?;
    let spec = convert::defect_spec(c, &materials)?;
    spec.validate(materials.materials.len(), &convert::SCENE_FIELDS)?;
    for (i, it) in spec.interfaces.iter().enumerate() {
        let same = |o: &demcon_model::InterfaceResistance| {
            o.phases == it.phases || o.phases == [it.phases[1], it.phases[0]]
        };
        if let Some(j) = spec.interfaces[..i].iter().position(same) {
            return Err(SceneError::invalid(
                &format!("interfaces[{i}].between"),
                format!(
                    "({:?}, {:?})",
                    c.interfaces[i].between.0, c.interfaces[i].between.1
                ),
                format!("each pair of materials once (already listed as interfaces[{j}])"),
            ));
        }
    }
    if c.electric.is_some()
        && let Some(i) = spec
            .cracks
            .iter()
            .position(|k| k.gap_conductance.is_some() && k.gap_electric_resistance.is_none())
    {
        return Err(SceneError::invalid(
            &format!("cracks[{i}].gap_electric_resistance"),
            "None",
            "a filled crack (gap_conductance) in an electric scene needs its electric resistance per area \
             (Ω·m², ≥ 0); leave gap_conductance None for an open, insulating crack",
        ));
    }
    if let Some(CutContactsConfig::File(path)) = &c.cut_contacts {
        let pairs = crate::build::read_cut_pairs(&base_dir.join(path))?;
        if let Some(n) = known_count(&c.packing, "packing")?
            && let Some((k, j, x)) = pairs
                .iter()
                .enumerate()
                .flat_map(|(k, p)| [(k, 0, p[0]), (k, 1, p[1])])
                .find(|&(_, _, x)| x as usize >= n)
        {
            return Err(SceneError::invalid(
                &format!("cut_contacts[{k}][{j}]"),
                x,
                format!(
                    "a particle index of the packing (0..{n}) (pair {} of {path})",
                    k + 1
                ),
            ));
        }
    }
    Ok(())
}
