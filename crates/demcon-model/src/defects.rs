//! Imperfect interfaces, cracks, damage and broken bonds: what a discrete model is for.
//!
//! - **Interface resistance** between two phases ([`InterfaceResistance`]): a contact (or
//!   Laguerre facet) whose centre-to-centre segment crosses the interface between phases a and
//!   b gets the extra series resistance 1/(h S) thermally (h in W/(m²·K)) and r_c/S
//!   electrically (r_c in Ω·m²), S its transmission surface:
//!   1/G = h_p/(λ_p S) + h_q/(λ_q S) + 1/(h S). The phase rule decides where the segment
//!   crosses: by centre, when p and q differ; with the segment rule, wherever a half-bond
//!   crosses its particle's interface plane (so a contact between two particles of the same
//!   phase, one of them cut, may cross it, and a wall link may too). The path along the
//!   segment is read as four phases — p's centre, the end of p's half-bond, the end of q's,
//!   q's centre — and every change adds one interface resistance. Its position along the
//!   segment does not change a series conductance; whether (and how often) it is crossed does,
//!   and so does its orientation: a crossing inside a cut particle (segment rule) is divided
//!   by |e·n| (e the branch, n the interface normal of the particle's plane), which makes a
//!   Laguerre network exact for plane interfaces wherever they cut the cells
//!   (`path_resistance`); a change at the facet (by centre, or a crossing the segment rule's
//!   sphere test missed) takes n from the phases themselves: the facets between the phases
//!   around p and q form a staircase whose Σ S e is the interface's area times its normal
//!   (`phase_normals`). The laminate rule has no position on the segment: it is read by
//!   centre. Unlisted pairs stay perfect.
//! - **Cracks** ([`Crack`]): every contact whose segment crosses the crack's surface
//!   ([`demcon_graph::CrackShape`], minimum-image segment and periodic images in a periodic
//!   box) is cut — removed from the graph and the network, in both physics. On a Laguerre
//!   graph an open crack cuts by the part of each facet it covers
//!   ([`demcon_graph::blocked_contacts`]: the facet's disc projected along the branch onto the
//!   crack's plane): a facet covered wholly is cut, one covered in part keeps the open part of
//!   its conductances ([`MARK_PARTLY_CUT`]), so the crack's edge is not rounded to whole
//!   facets (`whole_facet_cuts` restores the segment rule). A filled crack
//!   (`gap_conductance`) is an interface on a surface: on the part of each facet it covers (the
//!   same covered part) the contact gets the series resistance 1/(h_gap S |e·n|) (and
//!   r_gap/(S |e·n|) electrically, which a filled crack must give when the scene is electric),
//!   n the crack's normal — the term of an interface crossing (`crossing_resistance`), which
//!   makes a crack across a section of a Laguerre bar exact. Wall links whose segment (centre
//!   to face) a crack crosses are cut by an open crack, given the gap of a filled one (divided
//!   by |e·n| too, e the face's normal), whole (the segment rule), and count as the crack's
//!   hits. A cluster that a crack separates from every boundary value is a floating cluster
//!   like any other (excluded and reported, or refused, by the scene's `floating` policy).
//! - **Damage** ([`Damage`]): the conductances (both physics) of the contacts whose branch
//!   midpoint lies in the region are multiplied by the factor, in (0, 1]; overlapping regions
//!   multiply. A contact is "in" a region by its midpoint (the minimum-image midpoint, wrapped
//!   into the cell, in a periodic box): the one point of a contact that belongs to neither
//!   particle. A wall link is in it by the midpoint of its half-bond.
//! - **Broken bonds** (`cut_pairs`): particle index pairs (0-based, in the order of the
//!   packing before carving: the order of an imported file) cut like an open crack, e.g. the
//!   broken bonds of a mechanical DEM run. Pairs that are not contacts of the graph are counted
//!   in the report; an index out of range is an error.
//!
//! Per-contact marks ([`Defects::marks`], bits [`MARK_INTERFACE`], [`MARK_DAMAGED`],
//! [`MARK_FILLED_CRACK`], [`MARK_PARTLY_CUT`]) and the cut contacts ([`Defects::cut`]) are
//! kept for the output writers; [`Defects::crack_face`] lists the particles on a crack face
//! (the ends of a contact an open crack cuts or covers in part, or a filled crack crosses).

use std::collections::HashMap;

use demcon_core::{Container, ParticleSet, Region, Vec3};
use demcon_graph::{
    ContactGraph, CrackShape, HalfBond, Laminates, Mix, WallContacts, blocked_contacts, first_crossing,
};
use serde::Serialize;

use crate::error::{FieldNames, ModelError};

/// A contact crossing the interface between the two phases.
pub const MARK_INTERFACE: u8 = 1;
/// A contact whose conductances a damage region scales.
pub const MARK_DAMAGED: u8 = 2;
/// A contact crossed by a filled crack (kept, with the gap's series resistance).
pub const MARK_FILLED_CRACK: u8 = 4;
/// A Laguerre facet an open crack covers in part (kept, its conductances scaled by the open
/// part).
pub const MARK_PARTLY_CUT: u8 = 8;

/// The interface between two phases, with its conductances.
#[derive(Debug, Clone, PartialEq)]
pub struct InterfaceResistance {
    /// The two phases (indices into the material table; order does not matter).
    pub phases: [u16; 2],
    /// Thermal interface conductance h (W/(m²·K)), > 0.
    pub conductance: f64,
    /// Electric interface resistance r_c (Ω·m²), ≥ 0; `None`: electrically perfect.
    pub electric_resistance: Option<f64>,
}

/// A boundary resistance on every facet (contact) between two particles of one material —
/// each particle a grain — in series like an interface's: 1/(h S) thermal, r/S electric.
#[derive(Debug, Clone, PartialEq)]
pub struct GrainBoundary {
    /// The material (index into the material table).
    pub phase: u16,
    /// Thermal boundary (Kapitza) conductance h (W/(m²·K)), > 0.
    pub conductance: f64,
    /// Electric boundary resistance r (Ω·m²), ≥ 0; `None`: electrically perfect.
    pub electric_resistance: Option<f64>,
    /// Spread of h over the facets: the coefficient of variation of a log-normal factor of
    /// mean 1 drawn per facet (from `seed` and the facet's two particles, so the same for any
    /// thread count); the electric resistance takes the inverse factor. `None` or 0: none.
    pub spread: Option<f64>,
    /// Seed of the spread.
    pub seed: u64,
}

impl GrainBoundary {
    /// The factor on h of the facet between particles `p` < `q`: log-normal of mean 1 and
    /// coefficient of variation `spread`, or 1.
    fn factor(&self, p: u32, q: u32) -> f64 {
        let cv = self.spread.unwrap_or(0.0);
        if cv <= 0.0 {
            return 1.0;
        }
        use rand::SeedableRng;
        use rand_distr::Distribution;
        // One stream per facet: the seed mixed with the pair (SplitMix64's finaliser).
        let mut z = self.seed ^ ((p as u64) << 32 | q as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(z ^ (z >> 31));
        rand_distr::LogNormal::from_mean_cv(1.0, cv)
            .map(|d| d.sample(&mut rng))
            .unwrap_or(1.0)
    }
}

/// A crack surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Crack {
    /// Its surface.
    pub shape: CrackShape,
    /// `None`: an open crack (insulating, the contacts are cut). `Some(h)`: a filled crack of
    /// conductance h per area (W/(m²·K)), > 0.
    pub gap_conductance: Option<f64>,
    /// The filled crack's electric resistance per area (Ω·m²), ≥ 0; needed by an electric
    /// solve when `gap_conductance` is set.
    pub gap_electric_resistance: Option<f64>,
}

/// Conductances scaled in a region.
#[derive(Debug, Clone, PartialEq)]
pub struct Damage {
    /// The region (a contact is in it by its branch midpoint).
    pub region: Region,
    /// Factor on the conductances, in (0, 1].
    pub factor: f64,
}

/// Interfaces, cracks, damage and broken bonds to apply to a model.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DefectSpec {
    /// Interface resistances between phase pairs.
    pub interfaces: Vec<InterfaceResistance>,
    /// Boundary resistances between the grains (particles) of one material.
    pub grain_boundaries: Vec<GrainBoundary>,
    /// Crack surfaces.
    pub cracks: Vec<Crack>,
    /// Damage regions.
    pub damage: Vec<Damage>,
    /// Broken bonds: particle index pairs (before carving).
    pub cut_pairs: Vec<[u32; 2]>,
    /// Cracks take a Laguerre facet only where its segment crosses them, whole
    /// or not at all (the segment rule of the contact models), instead of by the covered part
    /// of the facet: an open crack cuts it, a filled one puts its gap on all of it. For
    /// comparisons; `false` by default.
    pub whole_facet_cuts: bool,
}

impl DefectSpec {
    /// Nothing to apply.
    pub fn is_empty(&self) -> bool {
        self.interfaces.is_empty()
            && self.grain_boundaries.is_empty()
            && self.cracks.is_empty()
            && self.damage.is_empty()
            && self.cut_pairs.is_empty()
    }

    /// Checks every value; errors name the caller's fields (`{interfaces}[i]…`,
    /// `{cracks}[i]…`, `{damage}[i].factor` of `fields`). `n_phases` is the number of materials.
    pub fn validate(&self, n_phases: usize, fields: &FieldNames) -> Result<(), ModelError> {
        let FieldNames {
            interfaces,
            grain_boundaries,
            cracks,
            damage,
            ..
        } = fields;
        for (i, gb) in self.grain_boundaries.iter().enumerate() {
            if gb.phase as usize >= n_phases {
                return Err(ModelError::invalid(
                    &format!("{grain_boundaries}[{i}].material"),
                    gb.phase,
                    format!("a phase of the material table (0..{n_phases})"),
                ));
            }
            if let Some(j) = self.grain_boundaries[..i]
                .iter()
                .position(|o| o.phase == gb.phase)
            {
                return Err(ModelError::invalid(
                    &format!("{grain_boundaries}[{i}].material"),
                    gb.phase,
                    format!("each material once (already listed as {grain_boundaries}[{j}])"),
                ));
            }
            positive(
                &format!("{grain_boundaries}[{i}].conductance"),
                gb.conductance,
                "W/(m²·K)",
            )?;
            if let Some(r) = gb.electric_resistance {
                non_negative(&format!("{grain_boundaries}[{i}].electric_resistance"), r, "Ω·m²")?;
            }
            if let Some(c) = gb.spread {
                non_negative(
                    &format!("{grain_boundaries}[{i}].spread"),
                    c,
                    "a coefficient of variation",
                )?;
            }
        }
        for (i, it) in self.interfaces.iter().enumerate() {
            for (j, &ph) in it.phases.iter().enumerate() {
                if ph as usize >= n_phases {
                    return Err(ModelError::invalid(
                        &format!("{interfaces}[{i}].between[{j}]"),
                        ph,
                        format!("a phase of the material table (0..{n_phases})"),
                    ));
                }
            }
            if it.phases[0] == it.phases[1] {
                return Err(ModelError::invalid(
                    &format!("{interfaces}[{i}].between"),
                    format!("({}, {})", it.phases[0], it.phases[1]),
                    "two different materials",
                ));
            }
            positive(
                &format!("{interfaces}[{i}].conductance"),
                it.conductance,
                "W/(m²·K)",
            )?;
            if let Some(r) = it.electric_resistance {
                non_negative(&format!("{interfaces}[{i}].electric_resistance"), r, "Ω·m²")?;
            }
        }
        for (i, c) in self.cracks.iter().enumerate() {
            c.shape.validate(&format!("{cracks}[{i}]")).map_err(|e| match e {
                demcon_core::CoreError::InvalidParameter {
                    field,
                    value,
                    allowed,
                } => ModelError::Invalid {
                    field,
                    value,
                    allowed,
                },
                other => ModelError::at(&format!("{cracks}[{i}]"), other),
            })?;
            if let Some(h) = c.gap_conductance {
                positive(&format!("{cracks}[{i}].gap_conductance"), h, "W/(m²·K)")?;
            }
            if let Some(r) = c.gap_electric_resistance {
                non_negative(&format!("{cracks}[{i}].gap_electric_resistance"), r, "Ω·m²")?;
            }
        }
        for (i, d) in self.damage.iter().enumerate() {
            if !(d.factor.is_finite() && d.factor > 0.0 && d.factor <= 1.0) {
                return Err(ModelError::invalid(
                    &format!("{damage}[{i}].factor"),
                    d.factor,
                    "a factor in (0, 1] (0 would cut the contacts: use a crack or cut_contacts)",
                ));
            }
        }
        Ok(())
    }

    /// The interface resistances (thermal m²·K/W, electric Ω·m²) per phase pair, row-major
    /// over `n_phases` × `n_phases`.
    fn table(&self, n_phases: usize) -> Vec<Option<(f64, f64)>> {
        let mut t = vec![None; n_phases * n_phases];
        for it in &self.interfaces {
            let [a, b] = it.phases.map(usize::from);
            let r = (1.0 / it.conductance, it.electric_resistance.unwrap_or(0.0));
            t[a * n_phases + b] = Some(r);
            t[b * n_phases + a] = Some(r);
        }
        t
    }
}

fn positive(field: &str, v: f64, unit: &str) -> Result<(), ModelError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ModelError::invalid(
            field,
            v,
            format!("a finite number > 0 ({unit})"),
        ))
    }
}

fn non_negative(field: &str, v: f64, unit: &str) -> Result<(), ModelError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(ModelError::invalid(
            field,
            v,
            format!("a finite number ≥ 0 ({unit})"),
        ))
    }
}

/// Why a contact was cut.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum CutCause {
    /// An open crack (index into the spec's cracks) crosses its segment at `point` (m).
    Crack {
        /// The crack.
        crack: u32,
        /// Where the segment crosses it (m).
        point: [f64; 3],
    },
    /// A broken bond of the `cut_pairs` list.
    Broken,
}

/// A contact removed from the model's graph.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CutContact {
    /// The two particles (current ids, p < q).
    pub pair: [u32; 2],
    /// Why.
    pub cause: CutCause,
}

/// What applying the defects did.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct DefectReport {
    /// Contacts cut by open cracks.
    pub cut_by_cracks: usize,
    /// Laguerre facets open cracks cover in part (kept, scaled by the open part).
    pub partly_cut_by_cracks: usize,
    /// Contacts crossed by filled cracks (kept with the gap resistance).
    pub filled_crack_contacts: usize,
    /// Wall links (to any face of the container) whose segment a crack crosses: cut by an open
    /// crack, given a filled crack's gap, when their face is held at a value.
    pub crack_wall_links: usize,
    /// Broken bonds cut (pairs of `cut_pairs` that were contacts).
    pub broken_bonds: usize,
    /// Pairs of `cut_pairs` that are not contacts of the graph (or lost a particle to carving).
    pub broken_not_contacts: usize,
    /// Contacts in a damage region.
    pub damaged_contacts: usize,
    /// Contacts crossing a listed interface (at build time; re-phasing updates it).
    pub interface_contacts: usize,
    /// Of those, contacts between two spheres that nearly touch, whose branch reads the
    /// interface twice ([`PhaseBridge`]).
    pub bridged_contacts: usize,
    /// Particles on a crack face (an end of a contact crossed by a crack).
    pub crack_face_particles: usize,
    /// Connected components of the graph once the contacts are cut.
    pub components_after_cuts: usize,
    /// Findings for the user (a crack that crosses no contact: outside the domain?).
    pub warnings: Vec<String>,
}

/// The defects applied to a model: the spec, per-contact values and marks, the cut contacts.
#[derive(Debug, Clone, Default)]
pub struct Defects {
    /// What was asked for.
    pub spec: DefectSpec,
    /// Per contact of the model's graph: [`MARK_INTERFACE`] | [`MARK_DAMAGED`] |
    /// [`MARK_FILLED_CRACK`] | [`MARK_PARTLY_CUT`] bits (0 for a plain contact).
    pub marks: Vec<u8>,
    /// Per contact: the factor on its conductances, the damage regions' factors times the open
    /// part of a facet an open crack covers in part (empty when neither: all 1).
    pub damage: Vec<f64>,
    /// Per contact: the thermal series resistance per area of the filled cracks it crosses,
    /// each divided by |e·n| (e the branch, n the crack's normal, as an interface crossing is)
    /// (m²·K/W; empty when none).
    pub gap_thermal: Vec<f64>,
    /// Per contact: the electric series resistance per area of the filled cracks it crosses
    /// (Ω·m², each divided by |e·n| like `gap_thermal`; empty when none).
    pub gap_electric: Vec<f64>,
    /// Per contact: the part of its facet the filled cracks cover, in [0, 1] (1 without cells;
    /// the largest of the cracks'), on which `gap_thermal` and `gap_electric` apply (empty when
    /// no filled crack crosses a contact).
    pub gap_cover: Vec<f64>,
    /// Contacts removed from the graph (open cracks, broken bonds).
    pub cut: Vec<CutContact>,
    /// Particles on a crack face, ascending.
    pub crack_face: Vec<u32>,
    /// What was done.
    pub report: DefectReport,
}

impl Defects {
    /// Whether the segment a → b (m) crosses a crack (open or filled; periodic images in a
    /// periodic `container`): the Halo does not average across it.
    pub fn crack_between(&self, a: &Vec3, b: &Vec3, container: &Container) -> bool {
        self.spec
            .cracks
            .iter()
            .any(|c| c.shape.crossing_periodic(a, b, container.period()).is_some())
    }

    /// Any crack at all?
    pub fn has_cracks(&self) -> bool {
        !self.spec.cracks.is_empty()
    }
}

/// How the particle ids of `cut_pairs` map to the model's: `kept_ids[k]` is the id before
/// carving of the model's particle k (`None`: no carving), `n_before` the particle count
/// before carving (the range of `cut_pairs`); `fields` the caller's names for its defects.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Numbering<'a> {
    pub kept_ids: Option<&'a [u32]>,
    pub n_before: usize,
    pub fields: &'a FieldNames,
}

/// Applies `spec` to a freshly built graph: cuts the contacts crossed by open cracks and the
/// broken bonds, records the filled cracks' gaps, the damage factors and the marks.
/// `numbering` maps the ids of `cut_pairs`, `n_phases` is the number of materials.
pub(crate) fn apply_defects(
    graph: ContactGraph,
    particles: &ParticleSet,
    container: &Container,
    mixes: &[Mix],
    spec: &DefectSpec,
    numbering: Numbering<'_>,
    n_phases: usize,
) -> Result<(ContactGraph, Defects), ModelError> {
    let m = graph.len();
    let mut c = Cutting {
        remove: vec![false; m],
        cause: vec![None; m],
        marks: vec![0u8; m],
        face: vec![false; particles.len()],
        crack_hits: vec![0usize; spec.cracks.len()],
        open_part: Vec::new(),
        gap_thermal: Vec::new(),
        gap_electric: Vec::new(),
        gap_cover: Vec::new(),
        report: DefectReport::default(),
    };
    if !spec.cut_pairs.is_empty() {
        c.break_bonds(&graph, spec, numbering)?;
    }
    let cracks = numbering.fields.cracks;
    c.open_cracks(&graph, particles, container, spec);
    c.filled_cracks(&graph, particles, container, spec);
    // Wall links (of every face the container has) count as hits too: a crack lying between
    // a face and the centres next to it crosses no contact but cuts (or fills) those links.
    for (i, n) in wall_links_crossed(&graph, particles, container, &spec.cracks)
        .into_iter()
        .enumerate()
    {
        c.crack_hits[i] += n;
        c.report.crack_wall_links += n;
    }
    for (i, &hits) in c.crack_hits.iter().enumerate() {
        if hits == 0 {
            c.report.warnings.push(format!(
                "{cracks}[{i}] crosses no contact or wall link (outside the domain, or smaller than a \
                 particle)"
            ));
        }
    }
    let damage = c.damage(&graph, particles, container, spec);
    c.finish(graph, particles, mixes, spec, damage, n_phases)
}

/// The contacts' defects as they are found, one per contact before any is removed.
struct Cutting {
    /// Contacts to remove (broken bonds, open cracks) and why.
    remove: Vec<bool>,
    cause: Vec<Option<CutCause>>,
    marks: Vec<u8>,
    /// Particles on a crack's face.
    face: Vec<bool>,
    /// Contacts and wall links each crack crosses.
    crack_hits: Vec<usize>,
    /// The open part of each facet an open crack covers in part (empty when none).
    open_part: Vec<f64>,
    /// Filled cracks' gap resistances per contact (thermal, electric) and covered fraction
    /// (empty when none).
    gap_thermal: Vec<f64>,
    gap_electric: Vec<f64>,
    gap_cover: Vec<f64>,
    report: DefectReport,
}

impl Cutting {
    /// Broken bonds, mapped to current ids.
    fn break_bonds(
        &mut self,
        graph: &ContactGraph,
        spec: &DefectSpec,
        numbering: Numbering<'_>,
    ) -> Result<(), ModelError> {
        let Numbering {
            kept_ids,
            n_before,
            fields,
        } = numbering;
        let mut new_id = vec![u32::MAX; n_before];
        match kept_ids {
            Some(ids) => ids
                .iter()
                .enumerate()
                .for_each(|(k, &i)| new_id[i as usize] = k as u32),
            None => new_id.iter_mut().enumerate().for_each(|(k, v)| *v = k as u32),
        }
        let index: HashMap<[u32; 2], usize> =
            graph.pairs.iter().enumerate().map(|(k, &pq)| (pq, k)).collect();
        for (i, &[a, b]) in spec.cut_pairs.iter().enumerate() {
            for (j, x) in [a, b].into_iter().enumerate() {
                if x as usize >= n_before {
                    return Err(ModelError::invalid(
                        &format!("{}[{i}][{j}]", fields.cut_contacts),
                        x,
                        format!("a particle index of the packing (0..{n_before})"),
                    ));
                }
            }
            let (p, q) = (new_id[a as usize], new_id[b as usize]);
            let key = [p.min(q), p.max(q)];
            match index.get(&key) {
                Some(&k) if p != u32::MAX && q != u32::MAX && p != q => {
                    if !self.remove[k] {
                        self.report.broken_bonds += 1;
                    }
                    self.remove[k] = true;
                    self.cause[k] = Some(CutCause::Broken);
                }
                _ => self.report.broken_not_contacts += 1,
            }
        }
        Ok(())
    }

    /// Open cracks cut the contacts they cover (the first that a segment crosses is named);
    /// a facet covered in part keeps its open part.
    fn open_cracks(
        &mut self,
        graph: &ContactGraph,
        particles: &ParticleSet,
        container: &Container,
        spec: &DefectSpec,
    ) {
        let m = graph.len();
        let open: Vec<usize> = (0..spec.cracks.len())
            .filter(|&i| spec.cracks[i].gap_conductance.is_none())
            .collect();
        let shapes: Vec<CrackShape> = open.iter().map(|&i| spec.cracks[i].shape.clone()).collect();
        let covers = blocked_contacts(graph, particles, container, &shapes, spec.whole_facet_cuts);
        for (k, x) in covers.iter().enumerate() {
            let Some(x) = x else { continue };
            let crack = open[x.crack as usize];
            self.crack_hits[crack] += 1;
            let [p, q] = graph.pairs[k];
            self.face[p as usize] = true;
            self.face[q as usize] = true;
            if x.fraction < 1.0 {
                if self.open_part.is_empty() {
                    self.open_part = vec![1.0; m];
                }
                self.open_part[k] = 1.0 - x.fraction;
                self.marks[k] |= MARK_PARTLY_CUT;
                self.report.partly_cut_by_cracks += 1;
                continue;
            }
            if !self.remove[k] {
                self.report.cut_by_cracks += 1;
            }
            self.remove[k] = true;
            self.cause[k].get_or_insert(CutCause::Crack {
                crack: crack as u32,
                point: [x.point.x, x.point.y, x.point.z],
            });
        }
    }

    /// Filled cracks: an interface on a surface. On the part of a facet it covers (the whole
    /// contact without cells), each adds its gap's resistance per area divided by |e·n| (n the
    /// crack's normal, e the branch), the term an interface crossing gets
    /// (`crossing_resistance`). A segment crossing an open crack is cut whatever filled cracks
    /// it also crosses; two filled cracks add up.
    fn filled_cracks(
        &mut self,
        graph: &ContactGraph,
        particles: &ParticleSet,
        container: &Container,
        spec: &DefectSpec,
    ) {
        let m = graph.len();
        for (i, crack) in spec.cracks.iter().enumerate() {
            let Some(h) = crack.gap_conductance else { continue };
            let (_, normal) = crack.shape.plane();
            let covers = blocked_contacts(
                graph,
                particles,
                container,
                std::slice::from_ref(&crack.shape),
                spec.whole_facet_cuts,
            );
            for (k, x) in covers.iter().enumerate() {
                let Some(x) = x else { continue };
                self.crack_hits[i] += 1;
                let [p, q] = graph.pairs[k];
                self.face[p as usize] = true;
                self.face[q as usize] = true;
                if self.remove[k] {
                    continue;
                }
                if self.gap_thermal.is_empty() {
                    self.gap_thermal = vec![0.0; m];
                    self.gap_electric = vec![0.0; m];
                    self.gap_cover = vec![0.0; m];
                }
                let cos = graph.geometry[k].normal.dot(&normal).abs();
                self.gap_thermal[k] += crossing_resistance(1.0 / h, cos);
                self.gap_electric[k] +=
                    crossing_resistance(crack.gap_electric_resistance.unwrap_or(0.0), cos);
                self.gap_cover[k] = f64::max(self.gap_cover[k], x.fraction);
                if self.marks[k] & MARK_FILLED_CRACK == 0 {
                    self.report.filled_crack_contacts += 1;
                }
                self.marks[k] |= MARK_FILLED_CRACK;
            }
        }
    }

    /// Damage, by the branch midpoint; the open part of partly cut facets scales the same way
    /// (empty when neither).
    fn damage(
        &mut self,
        graph: &ContactGraph,
        particles: &ParticleSet,
        container: &Container,
        spec: &DefectSpec,
    ) -> Vec<f64> {
        let m = graph.len();
        let mut damage = std::mem::take(&mut self.open_part);
        if !spec.damage.is_empty() {
            if damage.is_empty() {
                damage = vec![1.0; m];
            }
            for (k, dk) in damage.iter_mut().enumerate() {
                let p = graph.pairs[k][0] as usize;
                let mid = wrap(container, particles.centres[p] + 0.5 * graph.branch(k));
                for d in &spec.damage {
                    if d.region.contains_point(&mid) {
                        *dk *= d.factor;
                        self.marks[k] |= MARK_DAMAGED;
                    }
                }
            }
            self.report.damaged_contacts = self.marks.iter().filter(|&&b| b & MARK_DAMAGED != 0).count();
        }
        damage
    }

    /// Removes the cut contacts from the graph and the per-contact vectors, and marks the
    /// interfaces.
    fn finish(
        self,
        graph: ContactGraph,
        particles: &ParticleSet,
        mixes: &[Mix],
        spec: &DefectSpec,
        damage: Vec<f64>,
        n_phases: usize,
    ) -> Result<(ContactGraph, Defects), ModelError> {
        let Cutting {
            remove,
            cause,
            marks,
            face,
            gap_thermal,
            gap_electric,
            gap_cover,
            mut report,
            ..
        } = self;
        let m = graph.len();
        let cut: Vec<CutContact> = (0..m)
            .filter(|&k| remove[k])
            .map(|k| CutContact {
                pair: graph.pairs[k],
                cause: cause[k].unwrap_or(CutCause::Broken),
            })
            .collect();
        let keep = |v: Vec<f64>| -> Vec<f64> {
            if v.is_empty() {
                v
            } else {
                (0..m).filter(|&k| !remove[k]).map(|k| v[k]).collect()
            }
        };
        let (gap_thermal, gap_electric, gap_cover, damage) = (
            keep(gap_thermal),
            keep(gap_electric),
            keep(gap_cover),
            keep(damage),
        );
        let marks: Vec<u8> = (0..m).filter(|&k| !remove[k]).map(|k| marks[k]).collect();
        let graph = if cut.is_empty() {
            graph
        } else {
            graph.without(&remove, &particles.radii)?
        };
        report.components_after_cuts = graph.report.n_components;
        let crack_face: Vec<u32> = (0..face.len() as u32).filter(|&p| face[p as usize]).collect();
        report.crack_face_particles = crack_face.len();
        let mut defects = Defects {
            spec: spec.clone(),
            marks,
            damage,
            gap_thermal,
            gap_electric,
            gap_cover,
            cut,
            crack_face,
            report,
        };
        update_interface_marks(&mut defects, &graph, &particles.phases, mixes, &[], n_phases);
        Ok((graph, defects))
    }
}

/// A point wrapped into a periodic container's cell (unchanged otherwise).
fn wrap(container: &Container, x: Vec3) -> Vec3 {
    match container.period() {
        None => x,
        Some(l) => {
            let min = container.bounds().min;
            Vec3::from_fn(|i, _| min[i] + (x[i] - min[i]).rem_euclid(l[i]))
        }
    }
}

/// Smallest |e·n| an interface crossing is divided by (a branch almost along the interface).
const MIN_CROSSING_COSINE: f64 = 1e-3;

/// The series term, per area of the branch's transmission surface S, of a surface of
/// resistance `r` per area (an interface: 1/h in m²·K/W or r_c in Ω·m²; a filled crack's gap)
/// that a branch crosses at |e·n| = `cos` (e the branch, n the surface's normal): r / |e·n|,
/// so that the branch's resistance gains r/(S |e·n|) (|e·n| floored at
/// [`MIN_CROSSING_COSINE`]).
///
/// Why |e·n|: across a plane surface carrying the flux q, the continuum has the jump q r and
/// passes q (e·n) S through a facet of normal e. A branch reproduces both only if its surface
/// term is r/(S |e·n|); with the series rule for the bulk parts its flow is then exactly
/// q·(S e), and Σ S e = 0 per closed cell makes the piecewise-linear continuum field an exact
/// solution of the Laguerre network, wherever the plane cuts the cells. The one code path for
/// interfaces (phase changes along a branch, [`path_resistance`]) and filled cracks (a
/// surface the branch crosses, [`apply_defects`]).
fn crossing_resistance(r: f64, cos: f64) -> f64 {
    r / cos.max(MIN_CROSSING_COSINE)
}

/// A conductance `g` (W/K or S) in series with the resistance per area `r` (m²·K/W or Ω·m²)
/// over the surface `area` (m²): 1/(1/g + r/S); `g` unchanged when any of them is not > 0.
fn in_series(g: f64, r: f64, area: f64) -> f64 {
    if r > 0.0 && g > 0.0 && area > 0.0 {
        1.0 / (1.0 / g + r / area)
    } else {
        g
    }
}

/// A conductance `g` (W/K or S) whose surface `area` (m²) a filled crack covers in the part
/// `cover` (in [0, 1]) with the gap resistance per area `gap` (m²·K/W or Ω·m², |e·n|
/// included): the covered part in series with the gap, the rest as it was, in parallel —
/// (1 − f) g + f / (1/g + r/S), which is 1/(1/g + r/S) for a facet covered wholly.
fn with_gap(g: f64, gap: f64, cover: f64, area: f64) -> f64 {
    if cover >= 1.0 {
        in_series(g, gap, area)
    } else {
        (1.0 - cover) * g + cover * in_series(g, gap, area)
    }
}

/// For each of `cracks`, the wall links it crosses (the segment from a particle's centre to
/// its face, [`CrackShape::crossing_periodic`]) among the links every face of the container
/// could have ([`WallContacts::for_graph`] per face; a face no particle touches has none).
fn wall_links_crossed(
    graph: &ContactGraph,
    particles: &ParticleSet,
    container: &Container,
    cracks: &[Crack],
) -> Vec<usize> {
    let mut hits = vec![0; cracks.len()];
    if cracks.is_empty() {
        return hits;
    }
    let period = container.period();
    for &face in container.faces() {
        let Ok(walls) = WallContacts::for_graph(graph, particles, container, &[face], "cracks") else {
            continue;
        };
        for k in 0..walls.len() {
            let a = particles.centres[walls.particle[k] as usize];
            let b = a + walls.half_length[k] * walls.normal[k];
            for (i, c) in cracks.iter().enumerate() {
                if c.shape.crossing_periodic(&a, &b, period).is_some() {
                    hits[i] += 1;
                }
            }
        }
    }
    hits
}

/// The phase at the end of particle `p`'s half-bond along the unit vector `e` over `length`
/// (m), and |e·n| of the interface plane it crosses: the other phase when the segment rule
/// sees it cross the particle's interface plane (one of its two planes: the one whose part
/// beyond is longer, as [`Mix::segment_fraction`] reads it), else the phase of its centre
/// (and 1).
fn end_phase(lam: &Laminates<'_>, phases: &[u16], p: usize, e: &Vec3, length: f64) -> (u16, f64) {
    match lam.get(p) {
        Some(m) if m.half_bond == HalfBond::Segment && m.segment_fraction(e, length) > 0.0 => {
            let beyond = |n: &Vec3, offset: f64| {
                let k = e.dot(n);
                if k <= 0.0 {
                    0.0
                } else {
                    (1.0 - offset / (k * length)).clamp(0.0, 1.0)
                }
            };
            let normal = match &m.second {
                Some((n, off)) if beyond(n, *off) > beyond(&m.normal, m.offset) => *n,
                _ => m.normal,
            };
            (m.other_phase, e.dot(&normal).abs())
        }
        _ => (phases[p], 1.0),
    }
}

/// Sum of the interface resistances (thermal m²·K/W, electric Ω·m²) over the steps (from
/// phase, to phase, |e·n| of the crossing) of a path, each divided by its |e·n|
/// ([`crossing_resistance`]), and the number of listed interfaces crossed. A crossing inside a
/// cut particle (segment rule) takes n from the particle's plane; by centre, the facet between
/// two cells is the interface.
fn path_resistance(table: &[Option<(f64, f64)>], n: usize, steps: &[(u16, u16, f64)]) -> (f64, f64, u32) {
    let mut r = (0.0, 0.0, 0);
    for &(a, b, cos) in steps {
        if a != b
            && let Some(Some((t, e))) = table.get(a as usize * n + b as usize)
        {
            r.0 += crossing_resistance(*t, cos);
            r.1 += crossing_resistance(*e, cos);
            r.2 += 1;
        }
    }
    r
}

/// The interface normal read from the phases by centre, per particle: u_p = Σ S e over its
/// contacts to particles of another phase (e from p towards them, S the transmission surface,
/// m²). Over a plane interface the facets between the phases form a staircase whose Σ S e is
/// the plane's area times its normal (the closure of the cells on one side), so u_p − u_q
/// estimates the interface normal at a contact (p, q) between the phases.
fn phase_normals(graph: &ContactGraph, phases: &[u16], areas: &[f64]) -> Vec<Vec3> {
    let mut u = vec![Vec3::zeros(); phases.len()];
    for (k, &[p, q]) in graph.pairs.iter().enumerate() {
        let (p, q) = (p as usize, q as usize);
        if phases[p] != phases[q] {
            let v = areas[k] * graph.geometry[k].normal;
            u[p] += v;
            u[q] -= v;
        }
    }
    u
}

/// The interface resistances of contact `k` (thermal m²·K/W, electric Ω·m², count), `table`
/// the interfaces between each pair of the `n` phases. `normals` ([`phase_normals`]) give the
/// |e·n| of a crossing at the facet (the centre reading); without them it is 1. A contact with a
/// `bridge` reads its two crossings instead.
fn contact_interface(
    graph: &ContactGraph,
    phases: &[u16],
    lam: &Laminates<'_>,
    (table, n): (&[Option<(f64, f64)>], usize),
    k: usize,
    normals: Option<&[Vec3]>,
    bridge: Option<&PhaseBridge>,
) -> (f64, f64, u32) {
    if let Some(b) = bridge {
        let [p, q] = b.pair.map(|x| phases[x as usize]);
        return path_resistance(
            table,
            n,
            &[(p, b.gap_phase, b.cos_exit), (b.gap_phase, q, b.cos_entry)],
        );
    }
    let [p, q] = graph.pairs[k].map(|x| x as usize);
    let g = &graph.geometry[k];
    let w = graph.split(k);
    let (end_p, cos_p) = end_phase(lam, phases, p, &g.normal, w * g.distance);
    let (end_q, cos_q) = end_phase(lam, phases, q, &(-g.normal), (1.0 - w) * g.distance);
    let cos_facet = match normals {
        Some(u) if end_p != end_q => {
            let v = u[p] - u[q];
            let norm = v.norm();
            if norm > 0.0 {
                (g.normal.dot(&v) / norm).abs()
            } else {
                1.0
            }
        }
        _ => 1.0,
    };
    // p's half-bond, the facet (the interface itself when the phases change there), q's.
    let steps = [
        (phases[p], end_p, cos_p),
        (end_p, end_q, cos_facet),
        (end_q, phases[q], cos_q),
    ];
    if phases[p] != end_p && end_p != end_q && end_q != phases[q] {
        // Both half-bonds cross their own particle's plane and the phases change at the facet
        // too (a → b → a → b): two tangent planes of a curved interface, each placing the one
        // crossing in its own half. One crossing, with their mean cosine.
        return path_resistance(table, n, &[(phases[p], phases[q], 0.5 * (cos_p + cos_q))]);
    }
    path_resistance(table, n, &steps)
}

/// Sets the [`MARK_INTERFACE`] bits (and the report's count) from the current phases.
pub(crate) fn update_interface_marks(
    defects: &mut Defects,
    graph: &ContactGraph,
    phases: &[u16],
    mixes: &[Mix],
    bridges: &[PhaseBridge],
    n_phases: usize,
) {
    if defects.marks.len() != graph.len() {
        defects.marks = vec![0; graph.len()];
    }
    let table = defects.spec.table(n_phases);
    let lam = Laminates::new(phases.len(), mixes);
    let mut count = 0;
    for (k, bridge) in bridge_of(graph, bridges).enumerate() {
        let crossed = !defects.spec.interfaces.is_empty()
            && contact_interface(graph, phases, &lam, (&table, n_phases), k, None, bridge).2 > 0;
        if crossed {
            defects.marks[k] |= MARK_INTERFACE;
            count += 1;
        } else {
            defects.marks[k] &= !MARK_INTERFACE;
        }
    }
    defects.report.interface_contacts = count;
}

/// A branch that leaves one sphere and enters another across a gap: conforming cells where two
/// spheres nearly touch, closer than the seed pairs can follow, or, by centre, two particles of
/// two spheres in contact (both ends of one phase, the surfaces between them on no facet). Its
/// path reads two crossings —
/// out of p's sphere into the gap's phase, out of the gap into q's sphere — each with its own
/// |e·n| ([`crossing_resistance`]), instead of the phases at its ends (none). The bulk
/// conductance keeps p's and q's phases along the whole branch (the gap, under ~0.2 × the
/// seed offset, is not in it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PhaseBridge {
    /// The contact's particles `[p, q]`, p < q (as in the graph).
    pub pair: [u32; 2],
    /// The phase of the gap between the spheres.
    pub gap_phase: u16,
    /// |e·n| where the branch leaves p's sphere (e from p to q, n the sphere's normal).
    pub cos_exit: f64,
    /// |e·n| where it enters q's sphere.
    pub cos_entry: f64,
}

/// For each contact of `graph` in order, its bridge among `bridges` (sorted by pair, as the
/// graph's pairs are), or `None`.
fn bridge_of<'b>(
    graph: &'b ContactGraph,
    bridges: &'b [PhaseBridge],
) -> impl Iterator<Item = Option<&'b PhaseBridge>> + 'b {
    let mut j = 0;
    graph.pairs.iter().map(move |pq| {
        while j < bridges.len() && bridges[j].pair < *pq {
            j += 1;
        }
        bridges.get(j).filter(|b| b.pair == *pq)
    })
}

/// Which network a conductance belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Physics {
    /// Heat: interface 1/h, gap 1/h_gap.
    Thermal,
    /// Current: interface r_c, gap r_gap.
    Electric,
}

/// What the conductances of a built model read of its defects (a model's
/// [`crate::Model::defect_view`]): the defects, the graph, the particles and their cut parts,
/// the container, the number of phases and the bridges.
pub(crate) struct DefectView<'a> {
    pub(crate) defects: &'a Defects,
    pub(crate) graph: &'a ContactGraph,
    pub(crate) particles: &'a ParticleSet,
    pub(crate) container: &'a Container,
    pub(crate) mixes: &'a [Mix],
    pub(crate) n_phases: usize,
    pub(crate) bridges: &'a [PhaseBridge],
}

/// Adds the interface and filled-crack series resistances per area to contact conductances
/// `g` (W/K or S) of surfaces `areas` (m²) and applies the damage factors:
/// G = f / (1/G₀ + (Σ r_interface + r_gap)/S) on a facet a filled crack covers wholly (each
/// r already divided by its |e·n|), G = f ((1 − c) G₁ + c / (1/G₁ + r_gap/S)) with
/// G₁ = 1/(1/G₀ + Σ r_interface/S) on one it covers in the part c ([`with_gap`]).
pub(crate) fn apply_to_contacts(view: &DefectView<'_>, areas: &[f64], g: &mut [f64], physics: Physics) {
    let (defects, graph, phases, mixes, n_phases) = (
        view.defects,
        view.graph,
        &view.particles.phases,
        view.mixes,
        view.n_phases,
    );
    if defects.spec.interfaces.is_empty()
        && defects.spec.grain_boundaries.is_empty()
        && defects.gap_thermal.is_empty()
        && defects.damage.is_empty()
    {
        return;
    }
    let grains = grain_table(&defects.spec.grain_boundaries, n_phases);
    let table = defects.spec.table(n_phases);
    let lam = Laminates::new(phases.len(), mixes);
    let gap = match physics {
        Physics::Thermal => &defects.gap_thermal,
        Physics::Electric => &defects.gap_electric,
    };
    let interfaces = !defects.spec.interfaces.is_empty();
    let normals = interfaces.then(|| phase_normals(graph, phases, areas));
    for (k, bridge) in bridge_of(graph, view.bridges).enumerate().take(g.len()) {
        let mut r = 0.0;
        if interfaces {
            let (t, e, _) = contact_interface(
                graph,
                phases,
                &lam,
                (&table, n_phases),
                k,
                normals.as_deref(),
                bridge,
            );
            r = match physics {
                Physics::Thermal => t,
                Physics::Electric => e,
            };
        }
        if let Some(gb) = grain_boundary(&grains, graph, phases, &lam, k, bridge) {
            let [p, q] = graph.pairs[k];
            let f = gb.factor(p, q);
            r += match physics {
                Physics::Thermal => 1.0 / (gb.conductance * f),
                Physics::Electric => gb.electric_resistance.unwrap_or(0.0) / f,
            };
        }
        let r_gap = gap.get(k).copied().unwrap_or(0.0);
        let cover = defects.gap_cover.get(k).copied().unwrap_or(1.0);
        g[k] = if cover >= 1.0 {
            in_series(g[k], r + r_gap, areas[k])
        } else {
            with_gap(in_series(g[k], r, areas[k]), r_gap, cover, areas[k])
        };
        if let Some(f) = defects.damage.get(k) {
            g[k] *= f;
        }
    }
}

/// The grain boundary of each phase, if any (indexed by phase).
fn grain_table(gbs: &[GrainBoundary], n_phases: usize) -> Vec<Option<&GrainBoundary>> {
    let mut t = vec![None; n_phases];
    for gb in gbs {
        if let Some(slot) = t.get_mut(gb.phase as usize) {
            *slot = Some(gb);
        }
    }
    t
}

/// The grain boundary on contact `k`: both particles wholly of one phase that has one (no
/// cut particle, no bridge across a gap of another phase).
fn grain_boundary<'g>(
    grains: &[Option<&'g GrainBoundary>],
    graph: &ContactGraph,
    phases: &[u16],
    lam: &Laminates<'_>,
    k: usize,
    bridge: Option<&PhaseBridge>,
) -> Option<&'g GrainBoundary> {
    if grains.iter().all(Option::is_none) || bridge.is_some() {
        return None;
    }
    let [p, q] = graph.pairs[k].map(|x| x as usize);
    if phases[p] != phases[q] || lam.get(p).is_some() || lam.get(q).is_some() {
        return None;
    }
    grains.get(phases[p] as usize).copied().flatten()
}

/// Drops the wall links an open crack cuts (segment from the centre to the face).
pub(crate) fn cut_wall_links(
    defects: &Defects,
    walls: &mut WallContacts,
    particles: &ParticleSet,
    container: &Container,
) {
    let open: Vec<CrackShape> = defects
        .spec
        .cracks
        .iter()
        .filter(|c| c.gap_conductance.is_none())
        .map(|c| c.shape.clone())
        .collect();
    if open.is_empty() {
        return;
    }
    let period = container.period();
    let cut: Vec<bool> = (0..walls.len())
        .map(|k| {
            let a = particles.centres[walls.particle[k] as usize];
            let b = a + walls.half_length[k] * walls.normal[k];
            first_crossing(&open, &a, &b, period).is_some()
        })
        .collect();
    walls.retain_links(|k| !cut[k]);
}

/// The wall-link counterpart of [`apply_to_contacts`]: the interface a half-bond crosses
/// inside its particle (segment rule), filled cracks on the link's segment (each gap divided
/// by |e·n|, e the face's normal), damage by the half-bond's midpoint.
pub(crate) fn apply_to_walls(
    view: &DefectView<'_>,
    walls: &WallContacts,
    surfaces: &[f64],
    g: &mut [f64],
    physics: Physics,
) {
    let (defects, particles, container, mixes, n_phases) = (
        view.defects,
        view.particles,
        view.container,
        view.mixes,
        view.n_phases,
    );
    let spec = &defects.spec;
    if spec.interfaces.is_empty() && spec.cracks.is_empty() && spec.damage.is_empty() {
        return;
    }
    let table = spec.table(n_phases);
    let lam = Laminates::new(particles.len(), mixes);
    let period = container.period();
    for k in 0..walls.len() {
        let p = walls.particle[k] as usize;
        let (n, h) = (walls.normal[k], walls.half_length[k]);
        let a = particles.centres[p];
        let b = a + h * n;
        let (end, cos) = end_phase(&lam, &particles.phases, p, &n, h);
        let (t, e, _) = path_resistance(&table, n_phases, &[(particles.phases[p], end, cos)]);
        let r = match physics {
            Physics::Thermal => t,
            Physics::Electric => e,
        };
        // A filled crack on the link's segment (the segment rule, as open cracks cut links):
        // its gap over the link's surface, divided by |e·n| with e the face's normal.
        let mut r_gap = 0.0;
        for c in &spec.cracks {
            if let Some(hg) = c.gap_conductance
                && c.shape.crossing_periodic(&a, &b, period).is_some()
            {
                let gap = match physics {
                    Physics::Thermal => 1.0 / hg,
                    Physics::Electric => c.gap_electric_resistance.unwrap_or(0.0),
                };
                r_gap += crossing_resistance(gap, n.dot(&c.shape.plane().1).abs());
            }
        }
        g[k] = in_series(g[k], r + r_gap, surfaces[k]);
        let mid = wrap(container, a + 0.5 * h * n);
        for d in &spec.damage {
            if d.region.contains_point(&mid) {
                g[k] *= d.factor;
            }
        }
    }
}
