//! Faces that exchange heat with their surroundings: convection h (T_f − T∞) and radiation
//! ε σ (T_f⁴ − T_s⁴) (kelvin), alone or together on one face; and faces held at a temperature
//! that follows a time table. Every temperature here may follow a table ([`TimeValue`]).
//!
//! Each such face is one wall of [`WallContacts`]: a node held at a reference temperature
//! (the value at t = 0 of the held temperature, else of T∞ when the face convects, else of
//! T_s), linked to every particle (Laguerre cell) on the face. A link to a node at T_ref with
//! a source g (V(t) − T_ref) on the particle is exactly a link to V(t): so the tables enter as
//! sources, re-evaluated every step, and the matrix never changes.
//! Per link the face's surface temperature T_f is the centre of a star with three arms: the
//! particle's half-bond G = λ A / h to T_p (the wall link's own conductance, defects applied),
//! the film H_c = h A to T∞, and the radiation R(T_f) = ε σ A (T_f⁴ − T_s⁴) leaving, A the
//! link's exposed area (the cell's facet on the face; without cells, the particle's share of
//! the face by projected area, as `HeatFlux` shares it). With R linearised about T* as
//! H_r (T_f − T_s) + c (H_r = 4 ε σ A T*³, c = R(T*) − H_r (T* − T_s)), T_f is eliminated
//! exactly (star–mesh): the particle sees a link of conductance G (H_c + H_r)/Σ to the
//! reference node, Σ = G + H_c + H_r, and a source G/Σ [H_c (T∞ − T_ref) + H_r (T_s − T_ref)
//! − c]. Convection alone is therefore exact and linear (the finite-volume Robin condition).
//!
//! Radiation is nonlinear:
//! - a steady solve iterates (Newton on the reduced system): solve, find each link's T_f
//!   exactly from its particle's temperature (a scalar root, [`face_temperature`]),
//!   re-linearise at it, solve again, until T_f moves by less than [`NEWTON_TOLERANCE`]
//!   (relative, kelvin);
//! - a transient keeps H_r of the initial state in the matrix and, after every step, puts the
//!   rest of the law (c at the current T_f) in the sources: radiation lagged by one step
//!   (first order in time), the standard semi-implicit treatment.

use demcon_core::{Face, ParticleSet, TimeValue, Vec3};
use demcon_graph::WallContacts;
use serde::Serialize;

use crate::error::ModelError;

/// Stefan–Boltzmann constant σ (W/(m²·K⁴)), CODATA 2018 (exact in the SI).
pub const STEFAN_BOLTZMANN: f64 = 5.670_374_419e-8;

/// 0 °C in kelvin.
pub const KELVIN: f64 = 273.15;

/// Relative change of the face temperatures (kelvin) at which the steady radiation iteration
/// stops.
pub const NEWTON_TOLERANCE: f64 = 1e-11;

/// Most steady radiation iterations before the solve is refused as not converging.
pub const NEWTON_MAX_ITERATIONS: usize = 50;

/// The laws of one face exchanging heat with its surroundings, or held at a tabled
/// temperature.
#[derive(Debug, Clone, PartialEq)]
pub struct Exchange {
    /// The face.
    pub face: Face,
    /// Its wall in [`WallContacts`].
    pub wall: usize,
    /// Held at a temperature (°C) that follows a table (`WallTemperature`).
    pub held: Option<TimeValue>,
    /// Convection: film coefficient h (W/(m²·K)) and fluid temperature T∞ (°C).
    pub convection: Option<(f64, TimeValue)>,
    /// Radiation: emissivity ε (in [0, 1]) and surroundings' temperature T_s (°C).
    pub radiation: Option<(f64, TimeValue)>,
}

impl Exchange {
    /// The temperature the face's wall node is held at (°C): at t = 0, the held temperature,
    /// else T∞ when the face convects, else T_s.
    pub fn reference(&self) -> f64 {
        self.held
            .as_ref()
            .or(self.convection.as_ref().map(|c| &c.1))
            .or(self.radiation.as_ref().map(|r| &r.1))
            .map_or(0.0, |v| v.at(0.0))
    }

    /// Whether a temperature of the face changes in time.
    pub fn varies(&self) -> bool {
        [
            self.held.as_ref(),
            self.convection.as_ref().map(|c| &c.1),
            self.radiation.as_ref().map(|r| &r.1),
        ]
        .into_iter()
        .flatten()
        .any(|v| !v.is_constant())
    }

    /// The face's temperatures at time `t` (s).
    fn now(&self, t: f64) -> Now {
        Now {
            held: self.held.as_ref().map(|v| v.at(t)),
            t_inf: self.convection.as_ref().map_or(0.0, |c| c.1.at(t)),
            t_s: self.radiation.as_ref().map_or(0.0, |r| r.1.at(t)),
            t_ref: self.reference(),
        }
    }

    /// The per-link laws of an exposed area `area` (m²) behind a half-bond `half` (W/K), the
    /// face being `x`-th.
    fn link(&self, x: usize, half: f64, area: f64) -> Link {
        Link {
            area,
            half,
            h_c: self.convection.as_ref().map_or(0.0, |c| c.0 * area),
            e: self
                .radiation
                .as_ref()
                .map_or(0.0, |r| r.0 * STEFAN_BOLTZMANN * area),
            face: x,
            held: self.held.is_some(),
            now: Now::default(),
        }
    }
}

/// A face's temperatures at one time (°C): held, T∞, T_s, and the wall node's T_ref.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Now {
    held: Option<f64>,
    t_inf: f64,
    t_s: f64,
    t_ref: f64,
}

/// One link's star: exposed area A (m²), half-bond G (W/K), film H_c (W/K), radiation ε σ A
/// (W/K⁴), its face, whether the face is held, and the face's temperatures in force.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Link {
    area: f64,
    half: f64,
    h_c: f64,
    e: f64,
    face: usize,
    held: bool,
    now: Now,
}

impl Link {
    /// Net radiated power R(T_f) = ε σ A (T_f⁴ − T_s⁴) (W), temperatures in °C.
    fn radiated(&self, t_f: f64) -> f64 {
        self.e * ((t_f + KELVIN).powi(4) - (self.now.t_s + KELVIN).powi(4))
    }

    /// H_r = 4 ε σ A T*³ (W/K) at T* (°C).
    fn h_r(&self, t_star: f64) -> f64 {
        4.0 * self.e * (t_star + KELVIN).max(0.0).powi(3)
    }

    /// The rest of the radiation law beyond H_r (T_f − T_s) at T_f (W).
    fn rest(&self, h_r: f64, t_f: f64) -> f64 {
        self.radiated(t_f) - h_r * (t_f - self.now.t_s)
    }

    /// The link's conductance to the wall node with radiation linearised by `h_r` (W/K).
    fn conductance(&self, h_r: f64) -> f64 {
        if self.held {
            return self.half;
        }
        let sum = self.half + self.h_c + h_r;
        if sum > 0.0 {
            self.half * (self.h_c + h_r) / sum
        } else {
            0.0
        }
    }

    /// The source the link puts on its particle (W) with radiation `h_r` (W/K) and `rest` (W).
    fn source(&self, h_r: f64, rest: f64) -> f64 {
        let n = &self.now;
        if let Some(v) = n.held {
            return self.half * (v - n.t_ref);
        }
        let sum = self.half + self.h_c + h_r;
        if sum > 0.0 {
            self.half / sum * (self.h_c * (n.t_inf - n.t_ref) + h_r * (n.t_s - n.t_ref) - rest)
        } else {
            0.0
        }
    }
}

/// The surface temperature T_f (°C) of a star: the root of G (T_p − T_f) + H_c (T∞ − T_f) =
/// ε σ A ((T_f + 273.15)⁴ − (T_s + 273.15)⁴), by Newton from the largest of T_p, T∞, T_s
/// (the left side falls and the right rises in T_f, the right convex: from above, Newton
/// descends monotonically onto the root). Without radiation the root is the weighted mean.
fn face_temperature(l: &Link, t_p: f64) -> f64 {
    let (lin, n) = (l.half + l.h_c, &l.now);
    if let Some(v) = n.held {
        return v;
    }
    if l.e == 0.0 {
        return if lin > 0.0 {
            (l.half * t_p + l.h_c * n.t_inf) / lin
        } else {
            t_p
        };
    }
    let mut t = t_p.max(n.t_inf).max(n.t_s);
    for _ in 0..100 {
        let f = l.half * (t_p - t) + l.h_c * (n.t_inf - t) - l.radiated(t);
        let df = -lin - l.h_r(t);
        let next = t - f / df;
        let done = (next - t).abs() <= 1e-15 * (t + KELVIN).abs().max(1.0);
        t = next;
        if done {
            break;
        }
    }
    t
}

/// The faces exchanging heat with their surroundings (or held at a tabled temperature), and
/// the state of their links.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Surroundings {
    /// The faces, in the order of the boundary conditions that name them first.
    pub faces: Vec<Exchange>,
    /// Per face: the field paths of the boundary conditions on it (`thermal.bcs[i]`).
    pub bcs: Vec<Vec<String>>,
    /// Per link of the faces' walls (indices `k` of [`WallContacts`]): its star.
    links: Vec<(usize, Link)>,
    /// Per entry of `links`: the surface temperature the radiation is linearised at (°C).
    t_star: Vec<f64>,
}

/// One face's exchange in a solved state, for `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExchangeReport {
    /// The boundary conditions on the face (`thermal.bcs[i]`).
    pub bcs: Vec<String>,
    /// The face.
    pub face: String,
    /// Heat leaving the body through a held face, Σ G (T_p − T_w) (W).
    pub held_w: f64,
    /// Heat leaving the body through the face by convection, Σ h A (T_f − T∞) (W).
    pub convection_w: f64,
    /// Heat leaving the body through the face by radiation, Σ ε σ A (T_f⁴ − T_s⁴) (W).
    pub radiation_w: f64,
    /// Exposed area of the face (m²).
    pub area_m2: f64,
    /// Lowest and highest surface temperature T_f on the face (°C).
    pub surface_temperature: [f64; 2],
}

impl Surroundings {
    /// The stars of `faces`' links: `half` the links' half-bond conductances (W/K, defects
    /// applied, in link order), the exposed areas from the Laguerre facets or, without cells,
    /// each particle's share of the face by projected area (`face_area`: the face's area,
    /// m²). The radiation is linearised at the surface temperature of particles at `t_guess`
    /// (°C) at t = 0.
    pub fn new(
        faces: Vec<Exchange>,
        bcs: Vec<Vec<String>>,
        walls: &WallContacts,
        half: &[f64],
        particles: &ParticleSet,
        face_area: impl Fn(Face) -> Option<f64>,
        t_guess: f64,
    ) -> Result<Self, ModelError> {
        let mut links = Vec::new();
        for (xi, x) in faces.iter().enumerate() {
            let range = walls.links(x.wall);
            let areas: Vec<f64> = if walls.facet_area.is_empty() {
                let ids: Vec<u32> = range.clone().map(|k| walls.particle[k]).collect();
                let total = face_area(x.face).unwrap_or(0.0);
                let share = demcon_thermal::face_flux_sources(particles, &ids, total).map_err(|e| {
                    let field = bcs[xi].first().map_or("bcs", String::as_str);
                    ModelError::invalid(field, x.face.name(), e.to_string())
                })?;
                ids.iter().map(|&p| share[p as usize]).collect()
            } else {
                range.clone().map(|k| walls.facet_area[k]).collect()
            };
            for (k, a) in range.zip(areas) {
                links.push((k, x.link(xi, half[k], a)));
            }
        }
        let mut s = Surroundings {
            faces,
            bcs,
            links,
            t_star: Vec::new(),
        };
        s.t_star = s.at(0.0).map(|(_, l)| face_temperature(&l, t_guess)).collect();
        Ok(s)
    }

    /// No face exchanges heat with its surroundings.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// Whether the sources change with the state or the time: some face radiates (the
    /// problem is then nonlinear) or follows a table.
    pub fn varies(&self) -> bool {
        self.radiates() || self.faces.iter().any(Exchange::varies)
    }

    /// Whether some face radiates.
    pub fn radiates(&self) -> bool {
        self.links.iter().any(|(_, l)| l.e > 0.0)
    }

    /// Whether some face's temperature follows a table.
    pub fn tabled(&self) -> bool {
        self.faces.iter().any(Exchange::varies)
    }

    /// The links with their faces' temperatures at time `t` (s).
    fn at(&self, t: f64) -> impl Iterator<Item = (usize, Link)> + '_ {
        let now: Vec<Now> = self.faces.iter().map(|x| x.now(t)).collect();
        self.links.iter().map(move |&(k, l)| {
            (
                k,
                Link {
                    now: now[l.face],
                    ..l
                },
            )
        })
    }

    /// New half-bond conductances of the links (W/K, per wall link in link order: λ(T) moved
    /// them).
    pub fn set_half(&mut self, half: &[f64]) {
        for (k, l) in &mut self.links {
            l.half = half[*k];
        }
    }

    /// The face walls' link conductances (W/K) written into `g`, the wall links' conductances
    /// in link order.
    pub fn set_conductances(&self, g: &mut [f64]) {
        for ((k, l), &t) in self.links.iter().zip(&self.t_star) {
            g[*k] = l.conductance(l.h_r(t));
        }
    }

    /// The surface temperature of every link (°C) at time `t` (s) for the particle
    /// temperatures `temps`.
    fn surface_temperatures(&self, walls: &WallContacts, t: f64, temps: &[f64]) -> Vec<f64> {
        self.at(t)
            .map(|(k, l)| face_temperature(&l, temps[walls.particle[k] as usize]))
            .collect()
    }

    /// Adds to `sources` (W per node) what the links put on their particles at time `t` (s):
    /// the tabled temperatures, the radiation in the matrix as it stands and the rest of its
    /// law at the surface temperatures of `temps` (°C per node, particles first).
    pub fn add_sources(&self, walls: &WallContacts, t: f64, temps: &[f64], sources: &mut [f64]) {
        let t_f = self.surface_temperatures(walls, t, temps);
        for (((k, l), &t_star), &tf) in self.at(t).zip(&self.t_star).zip(&t_f) {
            let h_r = l.h_r(t_star);
            sources[walls.particle[k] as usize] += l.source(h_r, l.rest(h_r, tf));
        }
    }

    /// Re-linearises the radiation at the surface temperatures of `temps` (°C per node) at
    /// time `t` (s) and returns the largest change of a surface temperature since the last
    /// linearisation, relative to its value in kelvin.
    pub fn relinearise(&mut self, walls: &WallContacts, t: f64, temps: &[f64]) -> f64 {
        let t_f = self.surface_temperatures(walls, t, temps);
        let mut change = 0.0f64;
        for (((_, l), t_star), &tf) in self.links.iter().zip(&mut self.t_star).zip(&t_f) {
            if l.e > 0.0 {
                change = change.max((tf - *t_star).abs() / (tf + KELVIN).abs().max(1.0));
            }
            *t_star = tf;
        }
        change
    }

    /// The flow into each link's particle (W) at time `t` (s) and the particle temperatures
    /// of `temps`, minus what the network's link (conductance `g`, wall node at T_ref)
    /// carries: the part of a link's heat that the sources carry, for the flux dipoles.
    fn source_flows(&self, walls: &WallContacts, t: f64, g: &[f64], temps: &[f64]) -> Vec<(usize, f64)> {
        let t_f = self.surface_temperatures(walls, t, temps);
        self.at(t)
            .zip(&t_f)
            .map(|((k, l), &tf)| {
                let t_p = temps[walls.particle[k] as usize];
                (k, l.half * (tf - t_p) - g[k] * (l.now.t_ref - t_p))
            })
            .collect()
    }

    /// Adds the sources' part of each link's heat at time `t` (s) to the flux dipoles (W·m):
    /// 2 q ℓ, ℓ where the link acts ([`WallContacts::add_dipoles`] adds the network link's
    /// part).
    pub fn add_dipoles(&self, walls: &WallContacts, t: f64, g: &[f64], temps: &[f64], dipoles: &mut [Vec3]) {
        for (k, q) in self.source_flows(walls, t, g, temps) {
            dipoles[walls.particle[k] as usize] += 2.0 * q * walls.lever(k);
        }
    }

    /// What each face exchanges at time `t` (s) and the particle temperatures `temps` (°C per
    /// node), with the exact laws at the exact surface temperatures.
    pub fn report(&self, walls: &WallContacts, t: f64, temps: &[f64]) -> Vec<ExchangeReport> {
        let t_f = self.surface_temperatures(walls, t, temps);
        let links: Vec<(usize, Link)> = self.at(t).collect();
        self.faces
            .iter()
            .zip(&self.bcs)
            .map(|(x, bcs)| {
                let mut r = ExchangeReport {
                    bcs: bcs.clone(),
                    face: x.face.name().to_string(),
                    held_w: 0.0,
                    convection_w: 0.0,
                    radiation_w: 0.0,
                    area_m2: 0.0,
                    surface_temperature: [f64::INFINITY, f64::NEG_INFINITY],
                };
                let range = walls.links(x.wall);
                for ((k, l), &tf) in links.iter().zip(&t_f) {
                    if !range.contains(k) {
                        continue;
                    }
                    if l.held {
                        r.held_w += l.half * (temps[walls.particle[*k] as usize] - tf);
                    }
                    r.convection_w += l.h_c * (tf - l.now.t_inf);
                    r.radiation_w += l.radiated(tf);
                    r.area_m2 += l.area;
                    r.surface_temperature =
                        [r.surface_temperature[0].min(tf), r.surface_temperature[1].max(tf)];
                }
                r
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn link(half: f64, h_c: f64, e: f64) -> Link {
        Link {
            area: 1.0,
            half,
            h_c,
            e,
            face: 0,
            held: false,
            now: Now {
                held: None,
                t_inf: 20.0,
                t_s: -10.0,
                t_ref: 20.0,
            },
        }
    }

    #[test]
    fn the_surface_temperature_balances_the_three_arms() {
        for l in [link(3.0, 0.5, 2e-9), link(3.0, 0.0, 2e-9), link(3.0, 0.5, 0.0)] {
            for t_p in [-50.0, 20.0, 400.0] {
                let t = face_temperature(&l, t_p);
                let residual = l.half * (t_p - t) + l.h_c * (l.now.t_inf - t) - l.radiated(t);
                assert!(
                    residual.abs() < 1e-12 * l.half * 400.0,
                    "{l:?} at {t_p}: {residual}"
                );
            }
        }
    }

    #[test]
    fn the_eliminated_star_carries_the_particles_heat_exactly_at_the_linearisation_point() {
        // Linearised at the true surface temperature, link + source = G (T_f − T_p).
        let l = link(3.0, 0.5, 2e-9);
        let t_p = 300.0;
        let t = face_temperature(&l, t_p);
        let h_r = l.h_r(t);
        let network = l.conductance(h_r) * (l.now.t_ref - t_p) + l.source(h_r, l.rest(h_r, t));
        let exact = l.half * (t - t_p);
        assert!(
            (network - exact).abs() < 1e-12 * exact.abs(),
            "{network} vs {exact}"
        );
    }
}
