//! Contact detection: from a packing to the contact graph with each contact's geometry
//! (d_pq, unit normal p→q; the gap and R_m follow from the radii), the tolerance used and a
//! report.

use std::borrow::Cow;
use std::time::Instant;

use demcon_core::{Components, Container, CoreError, ParticleSet, Vec3};
use rayon::prelude::*;

use crate::error::{GraphError, positive};
use crate::laguerre::Cells;
use crate::search::{Candidates, NeighbourSearch, candidates, separation, wrap};

/// Which pairs count as contacts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactTolerance {
    /// Contact iff gap g_pq = d_pq − R_p − R_q ≤ ε·(R_p + R_q); ε is dimensionless, > 0.
    Relative(f64),
    /// The smallest ε for which the mean coordination number Z = 2·contacts/N reaches this
    /// target (contacts per particle, > 0). The paper's value is 7.5.
    TargetCoordination(f64),
}

impl Default for ContactTolerance {
    fn default() -> Self {
        Self::TargetCoordination(7.5)
    }
}

/// Inputs of [`detect_contacts`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// The contact rule. Default: target coordination 7.5.
    pub tolerance: ContactTolerance,
    /// With a target coordination: how far above the target the reached Z may be (contacts
    /// per particle) before a [`Diagnostic::CoordinationOvershoot`] is reported. Z can only
    /// overshoot when several pairs share the selected gap (lattices). Default 0.01.
    pub coordination_tolerance: f64,
    /// With a target coordination: the first relative tolerance searched (dimensionless);
    /// it doubles until the target is reached or `max_epsilon` is passed. Default 0.1.
    pub initial_epsilon: f64,
    /// With a target coordination: the largest relative tolerance tried (dimensionless).
    /// Default 1.0.
    pub max_epsilon: f64,
    /// The neighbour-search structure. Default: cell grid.
    pub search: NeighbourSearch,
}

impl Default for ContactParams {
    fn default() -> Self {
        Self {
            tolerance: ContactTolerance::default(),
            coordination_tolerance: 0.01,
            initial_epsilon: 0.1,
            max_epsilon: 1.0,
            search: NeighbourSearch::default(),
        }
    }
}

impl ContactParams {
    /// Default parameters with a fixed relative tolerance ε (dimensionless).
    pub fn relative(epsilon: f64) -> Self {
        Self {
            tolerance: ContactTolerance::Relative(epsilon),
            ..Self::default()
        }
    }

    /// Default parameters with a target mean coordination number (contacts per particle).
    pub fn target(coordination: f64) -> Self {
        Self {
            tolerance: ContactTolerance::TargetCoordination(coordination),
            ..Self::default()
        }
    }

    /// Checks every field; the error names it.
    pub fn validate(&self) -> Result<(), GraphError> {
        match self.tolerance {
            ContactTolerance::Relative(e) => {
                positive("tolerance.relative", e)?;
            }
            ContactTolerance::TargetCoordination(z) => {
                positive("tolerance.target_coordination", z)?;
            }
        }
        positive("coordination_tolerance", self.coordination_tolerance)?;
        positive("initial_epsilon", self.initial_epsilon)?;
        positive("max_epsilon", self.max_epsilon)?;
        Ok(())
    }
}

/// Geometry of one contact, computed once; thermal and electric models only read it.
/// The gap and the mean radius are not stored (a Laguerre graph reads neither, and they cost
/// 16 B per facet, 0.11 kB per particle): [`ContactGraph::gap`] and
/// [`ContactGraph::mean_radius`] compute them from the radii, bit for bit as detection did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactGeometry {
    /// Centre distance d_pq (m), minimum image in a periodic box.
    pub distance: f64,
    /// Unit normal from p to q (dimensionless).
    pub normal: Vec3,
}

/// A non-fatal finding of contact detection (the variants `Rattlers`, `SingleContact`,
/// `Overlaps`, `CoordinationOvershoot`, `Disconnected`), for the user to read.
pub use demcon_core::Diagnostic;

/// What contact detection did and found.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactReport {
    /// Relative tolerance ε used (dimensionless): contact iff gap ≤ ε·(R_p + R_q). With a
    /// target coordination, the midpoint between the last accepted and the first rejected
    /// relative gap, so that the same ε reproduces the same contacts.
    pub epsilon: f64,
    /// The requested coordination, if any (contacts per particle).
    pub target_coordination: Option<f64>,
    /// Mean coordination number reached Z = 2·contacts/N (contacts per particle).
    pub coordination: f64,
    /// Number of contacts.
    pub n_contacts: usize,
    /// Ids of the particles with no contact, ascending.
    pub rattlers: Vec<u32>,
    /// Number of particles with fewer than 2 contacts (rattlers included).
    pub under_two_contacts: usize,
    /// Number of overlapping pairs (gap < 0).
    pub overlaps: usize,
    /// Number of connected components (each rattler is one).
    pub n_components: usize,
    /// Particles in the largest connected component.
    pub largest_component: usize,
    /// Neighbour-search structure used.
    pub search: NeighbourSearch,
    /// Candidate searches run: 1 for a relative tolerance; with a target, one per doubling
    /// of the search tolerance. The tolerance itself is then exact (see [`detect_contacts`]).
    pub search_rounds: u32,
    /// Candidate pairs examined in the last search round (pairs within the search tolerance).
    pub candidates: usize,
    /// Wall time of the whole detection (s).
    pub wall_time_s: f64,
    /// Non-fatal findings.
    pub diagnostics: Vec<Diagnostic>,
}

/// The contact graph of a packing: pairs, their geometry, and the detection report.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactGraph {
    /// Number of particles (graph vertices).
    pub n_particles: usize,
    /// Contacts `[p, q]` with p < q, sorted ascending: deterministic.
    pub pairs: Vec<[u32; 2]>,
    /// Geometry of each contact, same order as `pairs`.
    pub geometry: Vec<ContactGeometry>,
    /// What detection did and found.
    pub report: ContactReport,
    /// The cells, when the graph is the facet graph of a Laguerre tessellation
    /// ([`crate::tessellate`]); `None` for contacts found by a gap tolerance.
    pub cells: Option<Box<Cells>>,
    /// Contacts of each particle removed by [`ContactGraph::without`] (cracks, broken bonds);
    /// empty when none was. [`ContactGraph::surface_degrees`] counts them back.
    pub cut_degrees: Vec<u32>,
}

impl ContactGraph {
    /// Number of contacts of each particle (counted in parallel; integer counts, so the
    /// result does not depend on the thread count).
    pub fn degrees(&self) -> Vec<u32> {
        use std::sync::atomic::{AtomicU32, Ordering::Relaxed};
        let d: Vec<AtomicU32> = (0..self.n_particles).map(|_| AtomicU32::new(0)).collect();
        self.pairs.par_iter().for_each(|&[p, q]| {
            d[p as usize].fetch_add(1, Relaxed);
            d[q as usize].fetch_add(1, Relaxed);
        });
        d.into_iter().map(AtomicU32::into_inner).collect()
    }

    /// The neighbour counts a surface model reads (Terreros α(n)): the contacts of the packing,
    /// those cut by cracks or broken bonds included — a broken bond does not change the share
    /// of its particle's surface each intact contact stands for.
    pub fn surface_degrees(&self) -> Vec<u32> {
        let mut d = self.degrees();
        for (x, c) in d.iter_mut().zip(&self.cut_degrees) {
            *x += c;
        }
        d
    }

    /// Mean coordination number Z = 2·contacts/N (contacts per particle); 0 for no particle.
    pub fn coordination(&self) -> f64 {
        if self.n_particles == 0 {
            0.0
        } else {
            2.0 * self.pairs.len() as f64 / self.n_particles as f64
        }
    }

    /// Connected components: a label per particle (0 = largest), their sizes.
    pub fn components(&self) -> Components {
        Components::from_pairs(self.n_particles, &self.pairs)
    }

    /// Branch vector of contact `k`: d_pq · e_pq, from p to its (minimum-image) neighbour q (m).
    pub fn branch(&self, k: usize) -> Vec3 {
        let g = &self.geometry[k];
        g.normal * g.distance
    }

    /// Gap of contact `k`, g_pq = d_pq − R_p − R_q (m), for the radii of the graph's
    /// particles; negative for overlapping spheres.
    pub fn gap(&self, k: usize, radii: &[f64]) -> f64 {
        let [p, q] = self.pairs[k];
        self.geometry[k].distance - radii[p as usize] - radii[q as usize]
    }

    /// Mean radius of contact `k`, R_m = (R_p + R_q)/2 (m), for the radii of the graph's
    /// particles.
    pub fn mean_radius(&self, k: usize, radii: &[f64]) -> f64 {
        let [p, q] = self.pairs[k];
        0.5 * (radii[p as usize] + radii[q as usize])
    }

    /// Adds each contact's share to the particle dipoles D_p = Σ_q g_pq (u_q − u_p) ℓ_pq (W·m
    /// for heat, A·m for current), ℓ_pq the branch. With Laguerre cells each flow acts at its
    /// facet's centroid a_pq (from p): p receives 2 g (u_q − u_p) a_pq and q receives
    /// 2 g (u_q − u_p) (ℓ_pq − a_pq), which makes −D_p / (2 V_cell,p) exact for a linear field
    /// (Σ_facets S (c_f − x_p) ⊗ n = V_cell I, wall facets included:
    /// [`crate::WallContacts::add_dipoles`]); without cells both ends receive g (u_q − u_p) ℓ_pq.
    /// The construction of `demcon_post::particle_dipoles_levers` and `particle_dipoles`, on
    /// the graph's own arrays. `g` per contact (W/K or S), `values` per node (K or V; the
    /// particles first, as many as the graph has). Sequential in contact order: deterministic.
    pub fn add_dipoles(&self, g: &[f64], values: &[f64], dipoles: &mut [Vec3]) {
        assert!(
            g.len() == self.len() && values.len() >= self.n_particles && dipoles.len() >= self.n_particles
        );
        match self.cells.as_deref() {
            Some(cells) => {
                for (k, &[p, q]) in self.pairs.iter().enumerate() {
                    let (p, q) = (p as usize, q as usize);
                    let flow = 2.0 * g[k] * (values[q] - values[p]);
                    let a = cells.centroid[k];
                    dipoles[p] += flow * a;
                    dipoles[q] += flow * (self.branch(k) - a);
                }
            }
            None => {
                for (k, &[p, q]) in self.pairs.iter().enumerate() {
                    let (p, q) = (p as usize, q as usize);
                    let term = (g[k] * (values[q] - values[p])) * self.branch(k);
                    dipoles[p] += term;
                    dipoles[q] += term;
                }
            }
        }
    }

    /// Where contact `k`'s branch is split between its two particles: h_p/d_pq from p (the
    /// Laguerre facet's position), or 0.5 for contacts without cells.
    pub fn split(&self, k: usize) -> f64 {
        self.cells.as_ref().map_or(0.5, |c| c.split[k])
    }

    /// Number of contacts.
    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    /// Whether there is no contact.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// The graph restricted to the particles `keep` (ascending, unique ids), renumbered
    /// 0, 1, … in that order — the same numbering as [`ParticleSet::retain`] or
    /// [`ParticleSet::permuted`] with these ids. Contacts with a removed end are dropped;
    /// the report is kept, with its counts updated (`radii`: of the graph's particles, for
    /// the overlaps).
    pub fn induced(&self, keep: &[u32], radii: &[f64]) -> Result<ContactGraph, GraphError> {
        crate::error::same_len("radii", radii.len(), self.n_particles, "particle")?;
        if let Some(w) = keep.windows(2).position(|w| w[0] >= w[1]) {
            return Err(CoreError::invalid(
                format!("keep[{}]", w + 1),
                keep[w + 1],
                "particle ids must be strictly ascending",
            )
            .into());
        }
        if let Some(&last) = keep.last()
            && last as usize >= self.n_particles
        {
            return Err(CoreError::invalid(
                format!("keep[{}]", keep.len() - 1),
                last,
                format!("particle ids must be below {}", self.n_particles),
            )
            .into());
        }
        let mut new_id = vec![u32::MAX; self.n_particles];
        for (k, &i) in keep.iter().enumerate() {
            new_id[i as usize] = k as u32;
        }
        let mut pairs = Vec::new();
        let mut geometry = Vec::new();
        for (&[p, q], g) in self.pairs.iter().zip(&self.geometry) {
            let (a, b) = (new_id[p as usize], new_id[q as usize]);
            if a != u32::MAX && b != u32::MAX {
                pairs.push([a, b]);
                geometry.push(*g);
            }
        }
        let cells = self
            .cells
            .as_ref()
            .map(|c| Box::new(c.induced(&self.pairs, keep, &new_id)));
        let mut graph = ContactGraph {
            n_particles: keep.len(),
            pairs,
            geometry,
            report: self.report.clone(),
            cells,
            cut_degrees: if self.cut_degrees.is_empty() {
                Vec::new()
            } else {
                keep.iter().map(|&i| self.cut_degrees[i as usize]).collect()
            },
        };
        let radii: Vec<f64> = keep.iter().map(|&i| radii[i as usize]).collect();
        summarise(&mut graph, &radii);
        Ok(graph)
    }
}

impl ContactGraph {
    /// The graph without the contacts `k` for which `remove[k]` is set (cut by a crack, or
    /// broken bonds): same particles, the other contacts in their order with their geometry
    /// (and facets), the report's counts (components, rattlers) updated.
    ///
    /// `radii`: the particles' (m), for the report.
    ///
    /// Errors: `remove` not one flag per contact, `radii` not one per particle.
    pub fn without(&self, remove: &[bool], radii: &[f64]) -> Result<ContactGraph, GraphError> {
        crate::error::same_len("remove", remove.len(), self.len(), "contact")?;
        crate::error::same_len("radii", radii.len(), self.n_particles, "particle")?;
        let keep = |k: &usize| !remove[*k];
        let pairs = (0..self.len()).filter(keep).map(|k| self.pairs[k]).collect();
        let geometry = (0..self.len()).filter(keep).map(|k| self.geometry[k]).collect();
        let cells = self.cells.as_ref().map(|c| {
            Box::new(Cells {
                facet_area: (0..self.len()).filter(keep).map(|k| c.facet_area[k]).collect(),
                split: (0..self.len()).filter(keep).map(|k| c.split[k]).collect(),
                centroid: (0..self.len()).filter(keep).map(|k| c.centroid[k]).collect(),
                volume: c.volume.clone(),
                walls: c.walls.clone(),
                report: c.report.clone(),
            })
        });
        let mut cut_degrees = if self.cut_degrees.is_empty() {
            vec![0; self.n_particles]
        } else {
            self.cut_degrees.clone()
        };
        for (k, &[p, q]) in self.pairs.iter().enumerate() {
            if remove[k] {
                cut_degrees[p as usize] += 1;
                cut_degrees[q as usize] += 1;
            }
        }
        let mut graph = ContactGraph {
            n_particles: self.n_particles,
            pairs,
            geometry,
            report: self.report.clone(),
            cells,
            cut_degrees,
        };
        summarise(&mut graph, radii);
        Ok(graph)
    }
}

/// Fills the report's counts and diagnostics from the graph (all but the search fields);
/// `radii` of the graph's particles.
pub(crate) fn summarise(graph: &mut ContactGraph, radii: &[f64]) {
    let degrees = graph.degrees();
    let comps = graph.components();
    // Count and largest overlap: integer sums and a maximum, so any reduction order gives
    // the same result.
    let g = &*graph;
    let (overlaps, max_rel) = (0..g.len())
        .into_par_iter()
        .map(|k| (k, g.gap(k, radii)))
        .filter(|&(_, gap)| gap < 0.0)
        .map(|(k, gap)| (1usize, -gap / (2.0 * g.mean_radius(k, radii))))
        .reduce(|| (0, 0.0f64), |a, b| (a.0 + b.0, a.1.max(b.1)));
    let r = &mut graph.report;
    r.coordination = if graph.n_particles == 0 {
        0.0
    } else {
        2.0 * graph.pairs.len() as f64 / graph.n_particles as f64
    };
    r.n_contacts = graph.pairs.len();
    r.rattlers = (0..graph.n_particles as u32)
        .filter(|&i| degrees[i as usize] == 0)
        .collect();
    r.under_two_contacts = degrees.iter().filter(|&&d| d < 2).count();
    let single = degrees.iter().filter(|&&d| d == 1).count();

    r.overlaps = overlaps;
    r.n_components = comps.count();
    r.largest_component = comps.largest();
    r.diagnostics
        .retain(|d| matches!(d, Diagnostic::CoordinationOvershoot { .. }));
    if !r.rattlers.is_empty() {
        r.diagnostics.push(Diagnostic::Rattlers {
            count: r.rattlers.len(),
        });
    }
    if single > 0 {
        r.diagnostics.push(Diagnostic::SingleContact { count: single });
    }
    if overlaps > 0 {
        r.diagnostics.push(Diagnostic::Overlaps {
            count: overlaps,
            max_relative: max_rel,
        });
    }
    if comps.count() > 1 {
        r.diagnostics.push(Diagnostic::Disconnected {
            components: comps.count(),
            largest: comps.largest(),
        });
    }
}

/// Checks the arrays of a particle set (they are public fields, so may disagree).
fn validate_particles(particles: &ParticleSet) -> Result<(), GraphError> {
    let n = particles.centres.len();
    if n == 0 && particles.radii.is_empty() {
        return Err(GraphError::EmptyParticleSet);
    }
    crate::error::same_len("particles.radii", particles.radii.len(), n, "centre")?;
    crate::error::same_len("particles.phases", particles.phases.len(), n, "centre")?;
    if n > u32::MAX as usize {
        return Err(CoreError::invalid("particles", n, "at most 2^32 − 1 particles").into());
    }
    if let Some(i) = particles
        .centres
        .iter()
        .position(|c| !c.iter().all(|v| v.is_finite()))
    {
        return Err(CoreError::invalid(
            format!("particles.centres[{i}]"),
            format!("{:?}", particles.centres[i].as_slice()),
            "must be finite (m)",
        )
        .into());
    }
    if let Some(i) = particles.radii.iter().position(|r| !(r.is_finite() && *r > 0.0)) {
        return Err(CoreError::invalid(
            format!("particles.radii[{i}]"),
            particles.radii[i],
            "must be a finite number > 0 (m)",
        )
        .into());
    }
    Ok(())
}

/// Validated inputs of a search: positions (wrapped into a periodic box), the period, and
/// the largest relative tolerance the period allows.
pub(crate) struct Prepared<'a> {
    pub pos: Cow<'a, [Vec3]>,
    period: Option<[f64; 3]>,
    eps_limit: f64,
}

pub(crate) fn prepare<'a>(
    particles: &'a ParticleSet,
    container: &Container,
) -> Result<Prepared<'a>, GraphError> {
    container.validate()?;
    validate_particles(particles)?;
    let rmax = particles.radii.iter().copied().fold(0.0, f64::max);
    let period = container.period();
    let pos: Cow<[Vec3]> = match period {
        Some(l) => Cow::Owned(
            particles
                .centres
                .par_iter()
                .map(|c| Vec3::new(wrap(c.x, l[0]), wrap(c.y, l[1]), wrap(c.z, l[2])))
                .collect(),
        ),
        None => Cow::Borrowed(&particles.centres),
    };
    // In a periodic box every contact distance, at most 2·R_max·(1 + ε), must stay below half
    // the smallest period so that the minimum image is the only image in contact.
    let eps_limit = match period {
        Some(l) => {
            let lmin = l.iter().copied().fold(f64::INFINITY, f64::min);
            let limit = lmin / (4.0 * rmax) - 1.0;
            if limit <= 0.0 {
                return Err(CoreError::invalid(
                    "container.size",
                    format!("{lmin} (smallest period)"),
                    format!(
                        "each period must exceed 4 × the largest radius ({}) so that every contact has a single minimum image",
                        4.0 * rmax
                    ),
                )
                .into());
            }
            limit * (1.0 - 1e-9)
        }
        None => f64::INFINITY,
    };
    Ok(Prepared {
        pos,
        period,
        eps_limit,
    })
}

/// One point of the coordination-versus-tolerance curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoordinationPoint {
    /// Relative gap tolerance ε (dimensionless).
    pub epsilon: f64,
    /// Mean coordination number Z at ε (contacts per particle).
    pub coordination: f64,
    /// Fraction of particles with fewer than 2 contacts at ε (dimensionless).
    pub under_two_fraction: f64,
}

/// Mean coordination Z(ε) and the fraction of particles with fewer than 2 contacts, for each
/// relative tolerance in `epsilons` (each finite and > 0), from one search at the largest.
/// This is the curve that [`ContactTolerance::TargetCoordination`] inverts.
///
/// Errors: as [`detect_contacts`] with the largest ε.
pub fn coordination_curve(
    particles: &ParticleSet,
    container: &Container,
    epsilons: &[f64],
    search: NeighbourSearch,
) -> Result<Vec<CoordinationPoint>, GraphError> {
    for (k, &e) in epsilons.iter().enumerate() {
        positive(&format!("epsilons[{k}]"), e)?;
    }
    let prepared = prepare(particles, container)?;
    let Some(emax) = epsilons.iter().copied().reduce(f64::max) else {
        return Ok(Vec::new());
    };
    if emax > prepared.eps_limit {
        return Err(CoreError::invalid(
            "epsilons",
            emax,
            format!("at most {:.6} in this periodic box: the largest contact distance 2·R_max·(1 + ε) must stay under half the smallest period", prepared.eps_limit),
        )
        .into());
    }
    let cands = candidates(search, &prepared.pos, &particles.radii, prepared.period, emax)?;
    let n = particles.len();
    Ok(epsilons
        .iter()
        .map(|&eps| {
            let mut degree = vec![0u32; n];
            let mut count = 0usize;
            for c in cands.iter().filter(|c| c.rel_gap <= eps) {
                degree[c.p() as usize] += 1;
                degree[c.q() as usize] += 1;
                count += 1;
            }
            CoordinationPoint {
                epsilon: eps,
                coordination: 2.0 * count as f64 / n as f64,
                under_two_fraction: degree.iter().filter(|&&d| d < 2).count() as f64 / n as f64,
            }
        })
        .collect())
}

/// The `k`-th and the (`k` + 1)-th smallest relative gaps of the candidates (0-based; the
/// second is `None` past the end). Exact: a histogram of the gaps' leading bits (in
/// parallel; counts are integers, so the result does not depend on the thread count) finds
/// the buckets holding both ranks, and only their values are ranked.
fn kth_gaps(cands: &Candidates, k: usize) -> (f64, Option<f64>) {
    const BITS: u32 = 16;
    // Order-preserving map of f64 to u64 (the order of `f64::total_cmp`).
    let key = |x: f64| {
        let b = x.to_bits();
        if b >> 63 == 1 { !b } else { b | (1 << 63) }
    };
    let bucket = |x: f64| (key(x) >> (64 - BITS)) as usize;
    let hist = cands
        .parts
        .par_iter()
        .fold(
            || vec![0usize; 1 << BITS],
            |mut h, part| {
                for c in part {
                    h[bucket(c.rel_gap)] += 1;
                }
                h
            },
        )
        .reduce(
            || vec![0usize; 1 << BITS],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(&b) {
                    *x += y;
                }
                a
            },
        );
    let total: usize = hist.iter().sum();
    // The bucket of rank r, and the number of values in the buckets below it.
    let locate = |r: usize| {
        let mut below = 0;
        for (b, &h) in hist.iter().enumerate() {
            if below + h > r {
                return (b, below);
            }
            below += h;
        }
        unreachable!("rank {r} below the total {total}")
    };
    let (b0, below) = locate(k);
    let b1 = if k + 1 < total { locate(k + 1).0 } else { b0 };
    let mut vals: Vec<f64> = cands
        .parts
        .par_iter()
        .flat_map_iter(|part| {
            part.iter()
                .map(|c| c.rel_gap)
                .filter(|&x| (b0..=b1).contains(&bucket(x)))
        })
        .collect();
    let (_, kth, right) = vals.select_nth_unstable_by(k - below, f64::total_cmp);
    let kth = *kth;
    (kth, right.iter().copied().min_by(f64::total_cmp))
}

/// The pairs of the candidates with relative gap ≤ `epsilon`, in key order: counted per part,
/// then each part writes its own slice, in parallel.
fn accepted_pairs(cands: &Candidates, epsilon: f64) -> Vec<[u32; 2]> {
    let counts: Vec<usize> = cands
        .parts
        .par_iter()
        .map(|part| part.iter().filter(|c| c.rel_gap <= epsilon).count())
        .collect();
    let mut pairs = vec![[0u32; 2]; counts.iter().sum()];
    let mut slices = Vec::with_capacity(counts.len());
    let mut rest = pairs.as_mut_slice();
    for &m in &counts {
        let (head, tail) = rest.split_at_mut(m);
        slices.push(head);
        rest = tail;
    }
    slices.into_par_iter().zip(&cands.parts).for_each(|(out, part)| {
        for (o, c) in out.iter_mut().zip(part.iter().filter(|c| c.rel_gap <= epsilon)) {
            *o = [c.p(), c.q()];
        }
    });
    pairs
}

/// Finds the contacts of a packing.
///
/// A pair (p, q) is a contact when its gap g_pq = d_pq − R_p − R_q is at most ε·(R_p + R_q),
/// with d_pq the centre distance (minimum image in a periodic box). Walls make no contacts.
///
/// With [`ContactTolerance::TargetCoordination`] the candidate pairs within a search
/// tolerance (`initial_epsilon`, doubled up to `max_epsilon` until there are enough) are
/// ranked by relative gap and ε is set exactly: the fewest contacts giving Z ≥ target, i.e.
/// ⌈Z·N/2⌉ contacts, so Z overshoots by less than 2/N unless pairs share the same gap.
/// Z(ε) is a step function known exactly from the candidates, so this selection is the limit
/// of a bisection on ε, without its iterations.
///
/// Errors: invalid parameters or particles (named), an empty set, coincident centres, a
/// periodic box shorter than 4·R_max·(1 + ε) (contacts would have two images), an
/// unreachable target (with the largest Z found).
pub fn detect_contacts(
    particles: &ParticleSet,
    container: &Container,
    params: &ContactParams,
) -> Result<ContactGraph, GraphError> {
    let start = Instant::now();
    params.validate()?;
    let prepared = prepare(particles, container)?;
    let Prepared {
        pos,
        period,
        eps_limit,
    } = &prepared;
    let (period, eps_limit) = (*period, *eps_limit);
    let n = particles.len();
    let radii = &particles.radii;
    let search = |eps: f64| candidates(params.search, pos, radii, period, eps);

    let (cands, epsilon, rounds, target, overshoot): (Candidates, f64, u32, Option<f64>, bool) = match params
        .tolerance
    {
        ContactTolerance::Relative(eps) => {
            if eps > eps_limit {
                return Err(CoreError::invalid(
                        "tolerance.relative",
                        eps,
                        format!(
                            "at most {eps_limit:.6} in this periodic box: the largest contact distance 2·R_max·(1 + ε) must stay under half the smallest period"
                        ),
                    )
                    .into());
            }
            (search(eps)?, eps, 1, None, false)
        }
        ContactTolerance::TargetCoordination(z) => {
            let (cands, epsilon, rounds, overshoot) = target_search(z, n, params, eps_limit, &search)?;
            (cands, epsilon, rounds, Some(z), overshoot)
        }
    };
    let n_candidates = cands.len();
    if let Some(c) = cands.parts.par_iter().find_map_first(|part| {
        part.iter()
            .find(|c| c.rel_gap <= epsilon && c.rel_gap <= -1.0 + 1e-12)
    }) {
        let (p, q) = (c.p(), c.q());
        let d = separation(&pos[p as usize], &pos[q as usize], period.as_ref()).norm();
        return Err(GraphError::CoincidentCentres { p, q, distance: d });
    }
    let per = period.as_ref();
    let pairs = accepted_pairs(&cands, epsilon);
    drop(cands);
    let geometry: Vec<ContactGeometry> = pairs
        .par_iter()
        .map(|&[p, q]| {
            let (p, q) = (p as usize, q as usize);
            let sep = separation(&pos[p], &pos[q], per);
            let distance = sep.norm_squared().sqrt();
            ContactGeometry {
                distance,
                normal: sep / distance,
            }
        })
        .collect();
    let mut diagnostics = Vec::new();
    let mut graph = ContactGraph {
        n_particles: n,
        pairs,
        geometry,
        report: ContactReport {
            epsilon,
            target_coordination: target,
            coordination: 0.0,
            n_contacts: 0,
            rattlers: Vec::new(),
            under_two_contacts: 0,
            overlaps: 0,
            n_components: 0,
            largest_component: 0,
            search: params.search,
            search_rounds: rounds,
            candidates: n_candidates,
            wall_time_s: 0.0,
            diagnostics: Vec::new(),
        },
        cells: None,
        cut_degrees: Vec::new(),
    };
    if overshoot {
        diagnostics.push(Diagnostic::CoordinationOvershoot {
            target: target.unwrap_or(0.0),
            reached: graph.coordination(),
        });
    }
    graph.report.diagnostics = diagnostics;
    summarise(&mut graph, radii);
    graph.report.wall_time_s = start.elapsed().as_secs_f64();
    Ok(graph)
}

/// The search to a target mean coordination `z` over `n` particles: the tolerance doubled from
/// `params.initial_epsilon` (at most `params.max_epsilon` and `eps_limit`) until enough
/// candidates, then set between the gaps of the contact that reaches `z` and the next.
/// Returns the candidates, ε, the rounds and whether the coordination overshoots `z` by more
/// than `params.coordination_tolerance`.
fn target_search(
    z: f64,
    n: usize,
    params: &ContactParams,
    eps_limit: f64,
    search: &dyn Fn(f64) -> Result<Candidates, GraphError>,
) -> Result<(Candidates, f64, u32, bool), GraphError> {
    let need = (z * n as f64 / 2.0).ceil();
    let all_pairs = n as f64 * (n as f64 - 1.0) / 2.0;
    let cap = params.max_epsilon.min(eps_limit);
    let mut eps_s = params.initial_epsilon.min(cap);
    let mut rounds = 0;
    let cands = loop {
        rounds += 1;
        let c = search(eps_s)?;
        if c.len() as f64 >= need {
            break c;
        }
        if eps_s >= cap || c.len() as f64 >= all_pairs {
            return Err(GraphError::UnreachableCoordination {
                target: z,
                max_coordination: 2.0 * c.len() as f64 / n as f64,
                max_epsilon: eps_s,
            });
        }
        eps_s = (2.0 * eps_s).min(cap);
    };
    let (eps_k, next) = kth_gaps(&cands, need as usize - 1);
    let epsilon = match next {
        Some(nx) if nx > eps_k => {
            let mid = 0.5 * (eps_k + nx);
            if mid >= eps_k && mid < nx { mid } else { eps_k }
        }
        _ => eps_k,
    };
    let accepted: usize = cands
        .parts
        .par_iter()
        .map(|part| part.iter().filter(|c| c.rel_gap <= epsilon).count())
        .sum();
    let reached = 2.0 * accepted as f64 / n as f64;
    let overshoot = reached - z > params.coordination_tolerance;
    Ok((cands, epsilon, rounds, overshoot))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::Candidate;

    /// The histogram selection agrees with a full sort, across parts, with negative gaps,
    /// ties, and ranks at the ends.
    #[test]
    fn kth_gaps_agrees_with_a_sort() {
        let mut x = 0x2545f4914f6cdd1du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let parts: Vec<Vec<Candidate>> = (0..7)
            .map(|p| {
                (0..300)
                    .map(|q| Candidate {
                        key: ((p as u64) << 32) | q,
                        rel_gap: if q % 50 == 0 { 0.05 } else { 0.3 * next() - 0.1 },
                    })
                    .collect()
            })
            .collect();
        let cands = Candidates { parts };
        let mut all: Vec<f64> = cands.iter().map(|c| c.rel_gap).collect();
        all.sort_by(f64::total_cmp);
        for k in [0, 1, 17, 500, 1049, 1050, all.len() - 2, all.len() - 1] {
            let (kth, next) = kth_gaps(&cands, k);
            assert_eq!(kth, all[k], "rank {k}");
            assert_eq!(next, all.get(k + 1).copied(), "rank {k} + 1");
        }
    }
}
