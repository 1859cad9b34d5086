//! The Lubachevsky–Stillinger packing: event-driven hard-sphere dynamics with radii
//! growing in proportion.
//!
//! Scheme (single-event, after Smallenburg 2022): every particle holds exactly one
//! scheduled event, the earliest of (a) a collision with a neighbour, (b) a wall hit,
//! (c) leaving its neighbour-list bounding sphere. Events are popped in `(time, id)` order
//! from a queue that keeps the near future in a small heap and the rest in a calendar of time
//! buckets (`queue.rs`). A collision event stores its partner's collision counter and is discarded
//! as stale when the partner has collided since. Particles are advanced lazily (each keeps
//! its own time stamp). Neighbour lists: each particle owns a bounding sphere (its radius
//! plus a skin) fixed in space until it would leave it; two particles are neighbours iff
//! their bounding spheres overlap, found through a cell grid on the sphere centres. All
//! radii follow `R_i(t) = a_i s(t)` with `s(t) = s0 + g t`, so the distribution is kept;
//! `s = 1` is the target. A velocity-rescaling thermostat keeps the growth rate relative
//! to the thermal speed fixed (growth injects kinetic energy). The collision virial gives
//! the reduced pressure that detects jamming. Up to `compression_phi` the radii grow at the
//! faster `compression_growth_rate` (the structure of the dilute start does not survive),
//! then at the set rate.

pub(crate) mod grid;
pub(crate) mod nblist;
pub mod predict;
pub(crate) mod queue;

use std::time::Instant;

use demcon_core::{Container, ParticleSet, Vec3, morton_order};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::error::PackingError;
use crate::params::{PackProgress, PackingParams, StopReason};
use crate::radius::jamming_estimate;
use crate::report::{PackingReport, summarize};
use demcon_core::mem::{huge_filled, huge_vec};
use grid::{PlacedGrid, SphereGrid};
use nblist::NbLists;
use predict::{collide_pair, collide_wall, inside_ball_delay, pair_delay_coef, plane_delay};
use queue::EventQueue;

/// Largest overlap (relative to the smaller radius) accepted in a finished packing before
/// it is reported as a numerical failure.
pub const MAX_OVERLAP: f64 = 1e-9;

/// Reduced pressure at which the fast compression stage ends early (dimensionless): well
/// above the equilibrium fluid at φ = 0.5 (p* ≈ 13), far below jamming.
const COMPRESSION_MAX_PRESSURE: f64 = 100.0;

/// Wall index of the radial wall of a cylinder or sphere (box walls are `2k` and `2k + 1`).
const RADIAL: u8 = 6;

/// Kind of a scheduled event.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Ev {
    Pair { j: u32, cj: u32 },
    Wall(u8),
    Exit,
}

/// State of one particle, one cache line: position `x` (m) at its own time `t`, velocity
/// `v` (m per time unit), radius `a` at s = 1, i.e. at the target (m).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct P {
    x: Vec3,
    t: f64,
    v: Vec3,
    a: f64,
}

struct Engine {
    container: Container,
    period: Option<Vec3>,
    p: Vec<P>,
    a_mean: f64,
    /// Largest radius at the target (m).
    a_max: f64,
    s0: f64,
    g: f64,
    /// Growth rate after the fast compression stage (equal to `g` once it is over).
    g_final: f64,
    /// Scale `s` at which the fast compression stage ends (`f64::INFINITY` when none).
    s_switch: f64,
    count: Vec<u32>,
    queue: EventQueue,
    /// Bounding spheres and neighbour lists.
    nb: NbLists,
    grid: SphereGrid,
    skin: f64,
    /// Scratch list for rebuilds.
    scratch: Vec<u32>,
    ke: f64,
    ke_target: f64,
    // statistics
    collisions: u64,
    wall_collisions: u64,
    rebuilds: u64,
    stale: u64,
    rescales: u64,
    virial: f64,
}

/// Packs `params.count` spheres by the Lubachevsky–Stillinger algorithm.
///
/// Returns the packing renumbered along a Morton curve (absolute radii and centres, m) and
/// the report. Deterministic: the same parameters and seed give the same packing, bit for
/// bit. `progress` is called about five times a second. A run that stops short of the
/// target (jamming, budgets) is not an error: check [`PackingReport::stop`].
///
/// Errors: bad parameters ([`PackingError::Invalid`]), a container that cannot hold the
/// particles, a failed initial placement, or overlaps left by round-off
/// ([`PackingError::Overlap`], above [`MAX_OVERLAP`]).
pub fn pack(
    params: &PackingParams,
    seed: u64,
    progress: Option<&dyn Fn(&PackProgress)>,
) -> Result<(ParticleSet, PackingReport), PackingError> {
    let start = Instant::now();
    params.validate()?;
    let n = params.count;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let rel = params.radii.sample(n, &mut rng);
    let vol = params.container.volume();
    let rel_vol: f64 = rel.iter().map(|r| r.powi(3)).sum::<f64>() * 4.0 / 3.0 * std::f64::consts::PI;
    let scale = (params.target_phi * vol / rel_vol).cbrt();
    let a: Vec<f64> = rel.iter().map(|r| r * scale).collect();
    let a_max = a.iter().copied().fold(0.0, f64::max);
    let a_mean = a.iter().sum::<f64>() / n as f64;
    check_fits(params, a_max, a_mean)?;

    let mut eng = Engine::start(params, a, a_mean, &mut rng)?;
    let loop_start = Instant::now();
    let (stop, p_red) = eng.run(params, &start, progress);
    let loop_s = loop_start.elapsed().as_secs_f64();

    let (s_final, now) = match stop {
        StopReason::TargetReached => (1.0, (1.0 - eng.s0) / eng.g),
        _ => {
            let now = eng.latest_time();
            (eng.s(now), now)
        }
    };
    for i in 0..n {
        eng.advance(i, now);
    }
    let radii: Vec<f64> = eng.p.iter().map(|p| p.a * s_final).collect();
    let raw = ParticleSet::new(eng.p.iter().map(|p| p.x).collect(), radii)?;
    let order = morton_order(&raw.centres, &params.container.bounds());
    let particles = raw.permuted(&order);

    let packing = summarize(&particles, &params.container, params.bulk_margin_diameters);
    if packing.max_overlap > MAX_OVERLAP {
        return Err(PackingError::Overlap {
            overlap: packing.max_overlap,
            allowed: MAX_OVERLAP,
        });
    }
    let events = eng.collisions + eng.wall_collisions + eng.rebuilds;
    let report = PackingReport {
        packing,
        target_phi: params.target_phi,
        jamming_estimate: jamming_estimate(&params.radii),
        stop,
        events,
        collisions: eng.collisions,
        wall_collisions: eng.wall_collisions,
        stale_events: eng.stale,
        thermostat_rescales: eng.rescales,
        reduced_pressure: p_red,
        events_per_s: events as f64 / loop_s.max(1e-9),
        wall_s: start.elapsed().as_secs_f64(),
        growth_rate: params.growth_rate,
        seed,
    };
    Ok((particles, report))
}

/// Rejects containers that cannot hold the largest particle, and periodic boxes too small
/// for the nearest-image convention of the neighbour lists.
fn check_fits(params: &PackingParams, a_max: f64, a_mean: f64) -> Result<(), PackingError> {
    let c = &params.container;
    if a_max >= c.inradius() {
        return Err(PackingError::ContainerTooSmall {
            reason: format!(
                "at φ = {} the largest of the {} particles has radius {a_max:.4e} m, but the {} \
                 only fits spheres of radius below {:.4e} m; use more particles or a larger container",
                params.target_phi,
                params.count,
                c.kind(),
                c.inradius()
            ),
        });
    }
    if let Some(p) = c.period() {
        let reach = 4.0 * (a_max + params.neighbour_skin * a_mean);
        let lmin = p.iter().copied().fold(f64::INFINITY, f64::min);
        if reach >= lmin {
            return Err(PackingError::ContainerTooSmall {
                reason: format!(
                    "a periodic box needs each period above 4 × (largest radius + neighbour skin) \
                     = {reach:.4e} m, but the smallest is {lmin:.4e} m with {} particles at φ = {}; \
                     use more particles",
                    params.count, params.target_phi
                ),
            });
        }
    }
    Ok(())
}

/// Uniform random point at which a sphere of radius `r` lies inside the container.
fn random_point(c: &Container, r: f64, rng: &mut ChaCha8Rng) -> Vec3 {
    let b = c.bounds();
    loop {
        let u = Vec3::new(rng.random(), rng.random(), rng.random());
        let p = match c {
            Container::Periodic { .. } => b.min + u.component_mul(&b.extent()),
            _ => {
                let lo = b.min + Vec3::repeat(r);
                lo + u.component_mul(&(b.extent() - Vec3::repeat(2.0 * r)))
            }
        };
        if matches!(c, Container::Periodic { .. }) || c.wall_distance(&p) >= r {
            return p;
        }
    }
}

/// Gaussian velocities of scale `a_mean` for `n` particles, the mean drift removed and the
/// kinetic energy set to its target 3/2 n a_mean² (returned beside them).
fn initial_velocities(n: usize, a_mean: f64, rng: &mut ChaCha8Rng) -> (Vec<Vec3>, f64) {
    let mut v: Vec<Vec3> = (0..n)
        .map(|_| {
            Vec3::new(
                StandardNormal.sample(rng),
                StandardNormal.sample(rng),
                StandardNormal.sample(rng),
            ) * a_mean
        })
        .collect();
    let drift = v.iter().sum::<Vec3>() / n as f64;
    if n > 1 {
        v.iter_mut().for_each(|vi| *vi -= drift);
    }
    let ke_target = 1.5 * n as f64 * a_mean * a_mean;
    let ke = 0.5 * v.iter().map(|v| v.norm_squared()).sum::<f64>();
    let scale = if ke > 0.0 { (ke_target / ke).sqrt() } else { 1.0 };
    v.iter_mut().for_each(|vi| *vi *= scale);
    (v, ke_target)
}

impl Engine {
    /// Random sequential placement at a low volume fraction, velocities, lists, events.
    fn start(
        params: &PackingParams,
        a: Vec<f64>,
        a_mean: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Self, PackingError> {
        let n = a.len();
        let c = params.container;
        let period = c.period().map(|p| Vec3::new(p[0], p[1], p[2]));
        let a_max = a.iter().copied().fold(0.0, f64::max);
        let mut phi0 = params.initial_phi.min(0.9 * params.target_phi);
        // Largest first; ties by id.
        let mut by_size: Vec<u32> = (0..n as u32).collect();
        by_size.sort_by(|&i, &j| a[j as usize].total_cmp(&a[i as usize]).then(i.cmp(&j)));
        let x = 'attempt: loop {
            let s0 = (phi0 / params.target_phi).cbrt();
            let mut grid = PlacedGrid::new(&c.bounds(), 2.0 * a_max * s0, period.is_some(), n, 4 * n + 64);
            let mut x = vec![Vec3::zeros(); n];
            for &i in &by_size {
                let i = i as usize;
                let ri = a[i] * s0;
                let mut placed = false;
                for _ in 0..20_000 {
                    let p = random_point(&c, ri, rng);
                    if !grid.overlaps(&p, ri, |d| min_image(period, d)) {
                        x[i] = p;
                        grid.insert(&p, ri);
                        placed = true;
                        break;
                    }
                }
                if !placed {
                    phi0 *= 0.7;
                    if phi0 < 1e-3 {
                        return Err(PackingError::Placement {
                            count: n,
                            phi: phi0 / 0.7,
                        });
                    }
                    continue 'attempt;
                }
            }
            break x;
        };
        let s0 = (phi0 / params.target_phi).cbrt();
        // Renumber along a Morton curve: neighbours in space become neighbours in memory.
        let order = morton_order(&x, &c.bounds());
        let x: Vec<Vec3> = order.iter().map(|&i| x[i as usize]).collect();
        let a: Vec<f64> = order.iter().map(|&i| a[i as usize]).collect();
        let (v, ke_target) = initial_velocities(n, a_mean, rng);

        let skin = params.neighbour_skin;
        let cell = 2.0 * (a_max + skin * a_mean);
        let grid = SphereGrid::new(&c.bounds(), cell, period.is_some(), n, 2 * n + 64);
        let mut eng = Engine {
            container: c,
            period,
            p: huge_vec((0..n).map(|i| P {
                x: x[i],
                t: 0.0,
                v: v[i],
                a: a[i],
            })),
            a_mean,
            a_max,
            s0,
            g: params.growth_rate,
            g_final: params.growth_rate,
            s_switch: f64::INFINITY,
            count: huge_filled(n, 0),
            queue: EventQueue::new(vec![f64::INFINITY; n]),
            nb: NbLists::new(n),
            grid,
            skin,
            scratch: Vec::new(),
            ke: ke_target,
            ke_target,
            collisions: 0,
            wall_collisions: 0,
            rebuilds: 0,
            stale: 0,
            rescales: 0,
            virial: 0.0,
        };
        for i in 0..n {
            let (c, rad) = (eng.p[i].x, eng.bounding_radius(i, s0));
            eng.nb.set_sphere(i, c, rad);
            eng.grid.insert(i, c, rad);
        }
        // Symmetric lists: the list of i already holds the neighbours k < i (pushed while k
        // was processed); add those above i to both sides. (Taking the list of i as the
        // scratch list, as an earlier version did, dropped the k < i entries: the lists were
        // one-sided until each particle's first rebuild, and collisions were missed.)
        let mut list = Vec::new();
        for i in 0..n {
            eng.find_neighbours(i, &mut list);
            list.retain(|&j| j as usize > i);
            for &j in &list {
                eng.nb.push(j as usize, i as u32);
                eng.nb.push(i, j);
            }
        }
        let s_switch = (params.compression_phi / params.target_phi).cbrt();
        if params.compression_growth_rate > params.growth_rate && s_switch > s0 && s_switch < 1.0 {
            eng.g = params.compression_growth_rate;
            eng.s_switch = s_switch;
        }
        eng.predict_all(0.0);
        Ok(eng)
    }

    #[inline]
    fn s(&self, t: f64) -> f64 {
        self.s0 + self.g * t
    }

    /// Time of the latest processed event (the clock of the most recently updated particle).
    fn latest_time(&self) -> f64 {
        self.p.iter().map(|p| p.t).fold(0.0, f64::max)
    }

    #[inline]
    fn advance(&mut self, i: usize, now: f64) {
        let mut p = self.p[i].x + self.p[i].v * (now - self.p[i].t);
        if let Some(l) = self.period {
            for k in 0..3 {
                if p[k] >= l[k] {
                    p[k] -= l[k];
                } else if p[k] < 0.0 {
                    p[k] += l[k];
                }
            }
        }
        self.p[i].x = p;
        self.p[i].t = now;
    }

    /// Particles whose bounding spheres overlap that of `i` (written into `out`).
    fn find_neighbours(&self, i: usize, out: &mut Vec<u32>) {
        out.clear();
        let (ci, ri) = self.nb.sphere(i);
        let slack = self.grid.slack();
        self.grid.for_each_near(&ci, |c, rad, id| {
            let d = min_image(self.period, c - ci);
            let s = ri + rad + slack;
            if d.norm_squared() < s * s && id as usize != i {
                out.push(id);
            }
        });
    }

    /// Radius of a new bounding sphere of `i` at scale `s` (m): its radius plus the skin,
    /// `a_i s + skin ā + a_max (1 − s)`. At the target (`s = 1`) the skin is `skin ā`; below it
    /// the skin takes up the room the largest sphere has not grown into yet, so the spheres
    /// of the fast, dilute start (which travel far) rebuild their lists less often, while every
    /// bounding sphere still fits the grid cell (`2 (a_max + skin ā)`).
    #[inline]
    fn bounding_radius(&self, i: usize, s: f64) -> f64 {
        self.p[i].a * s + self.skin * self.a_mean + self.a_max * (1.0 - s).max(0.0)
    }

    /// New bounding sphere and neighbour list for `i` (synchronised at `now`).
    fn rebuild(&mut self, i: usize, now: f64) {
        let mut list = std::mem::take(&mut self.scratch);
        self.nb.take(i, &mut list);
        // Each old neighbour's block is edited: start loading them all at once.
        for &j in &list {
            self.nb.prefetch(j as usize);
        }
        for &j in &list {
            self.nb.remove(j as usize, i as u32);
        }
        self.grid.remove(i);
        let (c, rad) = (self.p[i].x, self.bounding_radius(i, self.s(now)));
        self.nb.set_sphere(i, c, rad);
        self.grid.insert(i, c, rad);
        self.find_neighbours(i, &mut list);
        for &j in &list {
            self.nb.push(j as usize, i as u32);
        }
        self.nb.set(i, &list);
        self.scratch = list;
        self.rebuilds += 1;
    }

    /// The earliest event of particle `i` (synchronised at `now`): time and kind.
    #[inline]
    fn next_event(&self, i: usize, now: f64) -> (f64, Ev) {
        let P {
            x: xi, v: vi, a: ai, ..
        } = self.p[i];
        let s = self.s(now);
        let ri = ai * s;
        let gi = ai * self.g;
        // Leaving the bounding sphere.
        let (bc, brad) = self.nb.sphere(i);
        let p = min_image(self.period, xi - bc);
        let room = brad - ri;
        let mut best = if room - p.norm() <= 0.0 {
            0.0
        } else {
            inside_ball_delay(&p, &vi, room, gi)
        };
        let mut kind = Ev::Exit;
        // Walls.
        let mut wall = |d: f64, w: u8| {
            if d < best {
                best = d;
                kind = Ev::Wall(w);
            }
        };
        match self.container {
            Container::Box { size } => {
                for k in 0..3 {
                    wall(plane_delay(xi[k] - ri, vi[k], gi), 2 * k as u8);
                    wall(plane_delay(size[k] - xi[k] - ri, -vi[k], gi), 2 * k as u8 + 1);
                }
            }
            Container::Cylinder { radius, length } => {
                wall(plane_delay(xi.z - ri, vi.z, gi), 4);
                wall(plane_delay(length - xi.z - ri, -vi.z, gi), 5);
                let pr = Vec3::new(xi.x, xi.y, 0.0);
                let vr = Vec3::new(vi.x, vi.y, 0.0);
                wall(inside_ball_delay(&pr, &vr, radius - ri, gi), RADIAL);
            }
            Container::Sphere { radius } => {
                wall(inside_ball_delay(&xi, &vi, radius - ri, gi), RADIAL);
            }
            Container::Periodic { .. } => {}
        }
        // Neighbours, in two passes over chunks of the list: the first only loads and does
        // arithmetic (no branches), so the loads of all neighbours are in flight at once; the
        // second decides. A pair whose gap polynomial f(τ) = aτ² + 2bτ + c is still positive
        // at the current best delay, and decreasing up to it, cannot collide earlier: skip
        // the square root.
        let (inline, spilled) = self.nb.get(i);
        for list in [inline, spilled] {
            for chunk in list.chunks(nblist::INLINE) {
                let mut coef = [[0.0; 6]; nblist::INLINE];
                for (q, &j) in coef.iter_mut().zip(chunk) {
                    let pj = &self.p[j as usize];
                    let r = min_image(self.period, pj.x + pj.v * (now - pj.t) - xi);
                    let v = pj.v - vi;
                    let sa = ai + pj.a;
                    let (sigma, gamma) = (sa * s, sa * self.g);
                    let rv = r.dot(&v);
                    let r2 = r.norm_squared();
                    *q = [
                        v.norm_squared() - gamma * gamma,
                        rv - sigma * gamma,
                        r2 - sigma * sigma,
                        rv,
                        r2,
                        gamma,
                    ];
                }
                for (&[a, b, c, rv, r2, gamma], &j) in coef.iter().zip(chunk) {
                    if c > 0.0
                        && ((b >= 0.0 && a >= 0.0)
                            || ((a * best + 2.0 * b) * best + c > 0.0 && (a <= 0.0 || -b >= a * best)))
                    {
                        continue;
                    }
                    let d = pair_delay_coef(a, b, c, rv, r2, gamma);
                    if d < best {
                        best = d;
                        kind = Ev::Pair {
                            j,
                            cj: self.count[j as usize],
                        };
                    }
                }
            }
        }
        (now + best, kind)
    }

    /// Starts loading what the event of `k` (most likely the next one) will read: the
    /// particles of `k`'s neighbour list (its prediction) and, for a collision, the partner's
    /// particle and block. `k`'s own block was prefetched at the start of the current event
    /// and has usually arrived. Only cache hints: nothing is changed.
    #[inline]
    fn prefetch_event(&self, k: usize) {
        self.prefetch_neighbours(k);
        if let Ev::Pair { j, .. } = self.nb.event(k) {
            demcon_core::mem::prefetch(&self.p[j as usize]);
            self.nb.prefetch(j as usize);
        }
    }

    /// Starts loading the particles of `k`'s neighbour list (those held in its block).
    #[inline]
    fn prefetch_neighbours(&self, k: usize) {
        for &j in self.nb.inline_ids(k) {
            demcon_core::mem::prefetch(&self.p[j as usize]);
        }
    }

    #[inline]
    fn predict(&mut self, i: usize, now: f64) {
        let (t, kind) = self.next_event(i, now);
        self.nb.set_event(i, kind);
        self.queue.update(i, t);
    }

    /// Recomputes every particle's event (all synchronised at `now`) and rebuilds the queue.
    fn predict_all(&mut self, now: f64) {
        let n = self.p.len();
        let mut times = Vec::with_capacity(n);
        for i in 0..n {
            let (t, kind) = self.next_event(i, now);
            self.nb.set_event(i, kind);
            times.push(t);
        }
        self.queue = EventQueue::new(times);
    }

    /// Inward unit normal of wall `w` at the position of particle `i`.
    fn wall_normal(&self, i: usize, w: u8) -> Vec3 {
        if w == RADIAL {
            let mut p = self.p[i].x;
            if matches!(self.container, Container::Cylinder { .. }) {
                p.z = 0.0;
            }
            let n = p.norm();
            if n > 0.0 { -p / n } else { Vec3::zeros() }
        } else {
            let k = (w / 2) as usize;
            let mut e = Vec3::zeros();
            e[k] = if w.is_multiple_of(2) { 1.0 } else { -1.0 };
            e
        }
    }

    /// Synchronises everyone at `now`, restarts the clock at 0 and rescales the velocities to
    /// the target kinetic energy; continues with growth rate `g`; recomputes all events.
    fn thermostat(&mut self, now: f64, g: f64) {
        let n = self.p.len();
        for i in 0..n {
            self.advance(i, now);
            self.p[i].t = 0.0;
        }
        self.s0 = self.s(now);
        self.g = g;
        let ke = 0.5 * self.p.iter().map(|p| p.v.norm_squared()).sum::<f64>();
        if ke > 0.0 {
            let f = (self.ke_target / ke).sqrt();
            self.p.iter_mut().for_each(|p| p.v *= f);
        }
        self.ke = self.ke_target;
        self.rescales += 1;
        self.predict_all(0.0);
    }

    /// Ends the fast compression stage at `now`: rescale, final growth rate, new events.
    fn end_compression(&mut self, now: f64) {
        self.s_switch = f64::INFINITY;
        self.thermostat(now, self.g_final);
    }

    /// The budgets, checked every 1024 events: the stop reason when the events or the wall time
    /// are spent; else a progress report at most every 0.2 s (`last_progress`, s).
    fn budget_spent(
        &self,
        params: &PackingParams,
        start: &Instant,
        progress: Option<&dyn Fn(&PackProgress)>,
        last_progress: &mut f64,
        p_red: f64,
    ) -> Option<StopReason> {
        let events = self.collisions + self.wall_collisions + self.rebuilds;
        if events >= params.max_events {
            return Some(StopReason::EventBudget);
        }
        let wall = start.elapsed().as_secs_f64();
        if wall >= params.max_wall_s {
            return Some(StopReason::TimeBudget);
        }
        if let Some(cb) = progress
            && wall - *last_progress >= 0.2
        {
            *last_progress = wall;
            let s = self.s(self.queue.top().1.min((1.0 - self.s0) / self.g));
            cb(&PackProgress {
                phi: params.target_phi * s * s * s,
                target_phi: params.target_phi,
                events,
                wall_s: wall,
                reduced_pressure: p_red,
            });
        }
        None
    }

    /// The collision of particles `i` and `j` at time `te` when `j` has not moved since the
    /// event was predicted (its count is still `cj`; else `i` alone is advanced and predicted
    /// again, and `false` returned). `ru`: the runner-up event's particle, whose memory is
    /// prefetched between the two predictions.
    #[inline(always)]
    fn pair_event(&mut self, i: usize, j: usize, cj: u32, te: f64, ru: Option<usize>) -> bool {
        if self.count[j] != cj {
            self.stale += 1;
            self.advance(i, te);
            if let Some(k) = ru {
                self.prefetch_event(k);
            }
            self.predict(i, te);
            return false;
        }
        self.advance(i, te);
        self.advance(j, te);
        let r = min_image(self.period, self.p[j].x - self.p[i].x);
        let dist = r.norm();
        let nrm = r / dist;
        let gamma = (self.p[i].a + self.p[j].a) * self.g;
        let (mut vi, mut vj) = (self.p[i].v, self.p[j].v);
        let imp = collide_pair(&mut vi, &mut vj, &nrm, gamma);
        self.p[i].v = vi;
        self.p[j].v = vj;
        self.ke += imp * gamma;
        self.virial += imp * dist;
        self.count[i] += 1;
        self.count[j] += 1;
        self.collisions += 1;
        self.predict(i, te);
        if let Some(k) = ru {
            self.prefetch_event(k);
        }
        self.predict(j, te);
        if let Some(k) = ru
            && let Ev::Pair { j: m, .. } = self.nb.event(k)
        {
            self.prefetch_neighbours(m as usize);
        }
        true
    }

    /// The event loop. Returns the stop reason and the last reduced pressure.
    fn run(
        &mut self,
        params: &PackingParams,
        start: &Instant,
        progress: Option<&dyn Fn(&PackProgress)>,
    ) -> (StopReason, f64) {
        let n = self.p.len();
        let ke_limit = |e: &Engine| e.ke_target * (1.0 + params.thermostat_tolerance);
        // Pressure window: time accumulated before the last clock restart (time units).
        let mut win_elapsed_before = 0.0;
        let mut win_collisions = 0u64;
        let mut p_red = 0.0;
        let mut last_progress = 0.0;
        let mut checks = 0u64;
        loop {
            checks += 1;
            if checks.is_multiple_of(1024)
                && let Some(stop) = self.budget_spent(params, start, progress, &mut last_progress, p_red)
            {
                return (stop, p_red);
            }
            let (i, te) = self.queue.top();
            let t_target = (1.0 - self.s0) / self.g;
            if te >= t_target.min((self.s_switch - self.s0) / self.g) {
                if te >= t_target {
                    return (StopReason::TargetReached, p_red);
                }
                // End of the fast compression stage: no event before it, so everyone can be
                // advanced to it; the pressure window restarts with the final growth rate.
                let ts = (self.s_switch - self.s0) / self.g;
                self.end_compression(ts);
                (win_elapsed_before, win_collisions, self.virial) = (0.0, 0, 0.0);
                continue;
            }
            // The next event is most likely the runner-up's: start loading its particle and
            // block now, so that they arrive while this event is processed. Once its block
            // is in (after this event's first prediction), its neighbours and partner follow
            // (`prefetch_event`), and after the second its partner's neighbours. Events wait
            // on memory at random places; these hints keep several loads in flight.
            let ru = self.queue.runner_up();
            if let Some(k) = ru {
                demcon_core::mem::prefetch(&self.p[k]);
                self.nb.prefetch(k);
            }
            match self.nb.event(i) {
                Ev::Pair { j, cj } => {
                    if !self.pair_event(i, j as usize, cj, te, ru) {
                        // A stale event: `i` predicted again, nothing collided.
                        continue;
                    }
                    win_collisions += 1;
                }
                Ev::Wall(w) => {
                    self.advance(i, te);
                    let nrm = self.wall_normal(i, w);
                    let w0 = self.p[i].v.dot(&nrm);
                    let mut vi = self.p[i].v;
                    let dw = collide_wall(&mut vi, &nrm, self.p[i].a * self.g);
                    self.p[i].v = vi;
                    self.ke += dw * w0 + 0.5 * dw * dw;
                    self.count[i] += 1;
                    self.wall_collisions += 1;
                    if let Some(k) = ru {
                        self.prefetch_event(k);
                    }
                    self.predict(i, te);
                }
                Ev::Exit => {
                    self.advance(i, te);
                    self.rebuild(i, te);
                    self.predict(i, te);
                }
            }
            if self.ke > ke_limit(self) {
                // Pressure over the window (the clock restarts at 0 at every rescale), with
                // the mean temperature between rescales.
                let kt = (self.ke + self.ke_target) / (3.0 * n as f64);
                let dt = win_elapsed_before + te;
                if win_collisions >= n as u64 && dt > 0.0 {
                    p_red = 1.0 + self.virial / (3.0 * n as f64 * kt * dt);
                    self.virial = 0.0;
                    win_collisions = 0;
                    win_elapsed_before = 0.0;
                } else {
                    win_elapsed_before = dt;
                }
                if self.s_switch.is_finite() && p_red >= COMPRESSION_MAX_PRESSURE {
                    // Fast growth is near its own (looser) jamming point: slow down now.
                    self.end_compression(te);
                    (win_elapsed_before, win_collisions, self.virial) = (0.0, 0, 0.0);
                    continue;
                }
                self.thermostat(te, self.g);
                if p_red >= params.jam_pressure {
                    return (StopReason::Jammed, p_red);
                }
            }
        }
    }
}

/// Nearest periodic image of a difference vector (unchanged without a period).
#[inline]
fn min_image(period: Option<Vec3>, mut d: Vec3) -> Vec3 {
    if let Some(l) = period {
        for k in 0..3 {
            let h = 0.5 * l[k];
            if d[k] > h {
                d[k] -= l[k];
            } else if d[k] < -h {
                d[k] += l[k];
            }
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::radius::RadiusDistribution;

    /// The root cause of the overlaps at budget stops: every neighbour list must hold both
    /// sides of each pair from the start.
    #[test]
    fn neighbour_lists_are_symmetric_from_the_start() {
        let params = PackingParams::new(
            Container::Box { size: [0.01; 3] },
            400,
            0.6,
            RadiusDistribution::gaussian(0.3),
        );
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let a = params.radii.sample(400, &mut rng);
        let scale = (0.6 * params.container.volume()
            / (a.iter().map(|r| r.powi(3)).sum::<f64>() * 4.0 / 3.0 * std::f64::consts::PI))
            .cbrt();
        let a: Vec<f64> = a.iter().map(|r| r * scale).collect();
        let a_mean = a.iter().sum::<f64>() / 400.0;
        let eng = Engine::start(&params, a, a_mean, &mut rng).unwrap();
        let mut pairs = 0;
        for i in 0..400 {
            let (a, b) = eng.nb.get(i);
            for &j in a.iter().chain(b) {
                let (c, d) = eng.nb.get(j as usize);
                assert!(
                    c.contains(&(i as u32)) || d.contains(&(i as u32)),
                    "{i} lists {j}, not the reverse"
                );
                pairs += 1;
            }
        }
        assert!(pairs > 400);
    }
}
