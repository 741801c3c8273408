//! Event-driven dynamics of the impulse model, for particles that fly free between impacts
//! (no forces): from one frame to the next the world jumps from impact to impact instead of
//! stepping (`CollisionParams::event_driven`; `World::advance` calls [`EventDriven::advance`]).
//!
//! Between impacts a particle moves on a straight line, x(t) = x_i + v_i (t − t_i), so each
//! particle keeps its own time t_i (the time its stored position is for) and is only moved
//! when something happens to it. What can happen is an *event*:
//!
//! - **impact** of i and j: the first root of |d + u τ| = r_i + r_j, d = x_i − x_j and
//!   u = v_i − v_j taken at a common time (the minimum image when periodic):
//!
//!   ```text
//!     b = d·u < 0 (approaching),  c = |d|² − (r_i + r_j)²,  disc = b² − |u|² c ≥ 0
//!     τ = c / (−b + √disc)        (the smaller root, written without cancellation)
//!   ```
//!
//!   (c ≤ 0 with b < 0: an overlap that still approaches, τ = 0). It is answered by the same
//!   rule as the stepped model's impacts, [`restitution_impulse`](super::restitution_impulse)
//!   (Newton's u_n⁺ = −e u_n⁻, Coulomb friction), each impulse onto both particles
//!   (`impacts.rs`);
//! - **a wall**: a plane (or a box collider's wall) at distance s = (x − p)·n − r, reached at
//!   τ = s / (−v·n) when v·n < 0, answered by the same rule;
//! - **leaving the shell**: the particle's neighbour list expires (`shells.rs`), and is made
//!   again around a new centre a little ahead of it on its way ([`AHEAD`]).
//!
//! **One event per particle** (Smallenburg, EPJE 45:22 (2022)): a particle keeps only its
//! earliest event, in a bucketed calendar (`calendar.rs`). After an impact of i and j only
//! their events are found again. A third particle k whose event was an impact with i is not
//! touched: its event holds the *path* i had (the count of i's impacts), and when it comes
//! up with a path that is no longer i's, k's event is found again from that time. That is
//! enough: k's other partners met k no sooner than that stale event (it was k's earliest),
//! and an earlier impact of k with i's new path is i's own earliest-event search's business.
//! Making a list again changes no path, so it stales nothing.
//!
//! Everything is found from the present: an event's search moves no particle, it reads each
//! position at the event's time. Between calls the state is kept (the world drops it when
//! particles, colliders or settings change), so a run of many frames builds the lists once.

mod calendar;
mod impacts;
mod shells;

use super::books::ColliderBooks;
use super::colliders::Collider;
use super::groups::Filter;
use super::impulse::CollisionStats;
use super::morton::morton_order;
use super::response::MaterialTable;
use super::roots::toi_half_space;
use super::{Domain, Periodic};
use crate::error::Error;
use crate::interrupt::Interrupt;
use crate::particles::Particles;
use crate::vec3;
use calendar::{Calendar, Entry};
use shells::Shells;

/// The shell δ as a fraction of the mean diameter. A thin shell is left often (a particle
/// whose flights between impacts are λ long leaves a shell of radius δ/2 after about
/// (δ/2λ)² of them), a thick one holds many partners to look at after each event; on the hard-sphere gas of `benchmarks/hard_sphere_gas.py` (φ = 0.25) the cost per
/// collision was lowest and flat from 0.6 to 0.8 (0.3: 1.3× slower, 1.3: 1.4×).
pub const SHELL: f64 = 0.7;

/// Where a particle's new shell is centred: AHEAD · δ/2 ahead of it along its velocity, not
/// where it is. It then crosses the shell's middle on its way instead of starting there: its
/// first flight after leaving is mostly spent, not lost, and it leaves the new shell later (on
/// the gas of `benchmarks/hard_sphere_gas.py`, 27 % fewer shell events at 0.8 than at 0, at
/// the same impacts). The centre stays inside the shell (AHEAD < 1): the particle is within
/// δ/2 of it, all the lists' bound needs.
const AHEAD: f64 = 0.75;

/// Events between two asks of the interrupt (Ctrl-C) check.
const POLL_EVERY: u64 = 1 << 14;

/// A particle: where it is at its own time, how it moves, and its counts (64 bytes: one
/// cache line, everything an event reads of a particle but its radius).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct Body {
    /// Position at time `t`, m.
    x: [f64; 3],
    /// The particle's own time, s.
    t: f64,
    /// Velocity, m/s.
    v: [f64; 3],
    /// Its path: its impacts so far.
    path: u32,
    /// Its schedule: how often its event was found (the calendar's live entry holds the
    /// latest).
    schedule: u32,
}

impl Body {
    /// Where the particle is at time `at`, s, under the uniform field `g` (m/s²):
    /// x + v Δt + ½ g Δt² (with g = 0 the straight line, to the bit).
    #[inline]
    fn at(&self, at: f64, g: [f64; 3]) -> [f64; 3] {
        let dt = at - self.t;
        let h = 0.5 * dt * dt;
        [0, 1, 2].map(|k| self.x[k] + self.v[k] * dt + g[k] * h)
    }

    /// Where the particle is at time `at`, s, without a field: x + v Δt.
    #[inline]
    fn line(&self, at: f64) -> [f64; 3] {
        let dt = at - self.t;
        [0, 1, 2].map(|k| self.x[k] + self.v[k] * dt)
    }

    /// Its velocity at time `at`, s: v + g Δt.
    #[inline]
    fn velocity(&self, at: f64, g: [f64; 3]) -> [f64; 3] {
        let dt = at - self.t;
        [0, 1, 2].map(|k| self.v[k] + g[k] * dt)
    }

    /// Moves it to time `at`, s (position wrapped into the periodic cell when `wrap`).
    #[inline(always)]
    fn move_to(&mut self, at: f64, g: [f64; 3], domain: Option<&Domain>) {
        let x = self.at(at, g);
        self.x = match domain.and_then(|d| d.periodic_box()) {
            Some(c) => c.wrap(x),
            None => x,
        };
        self.v = self.velocity(at, g);
        self.t = at;
    }
}

/// What a particle's next event is.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    /// An impact with particle `j` while j is on path `path` (its impacts so far).
    Pair { j: u32, path: u32 },
    /// An impact with wall `k` of `EventDriven::walls`.
    Wall(u32),
    /// Leaving its shell: its neighbour list is made again.
    Shell,
    /// Nothing ever (at rest, alone).
    Nothing,
}

/// A flat wall: a plane collider, or a box collider's wall (not along a periodic axis).
#[derive(Debug, Clone, Copy)]
struct Wall {
    point: [f64; 3],
    /// Unit normal, towards the particles' side.
    normal: [f64; 3],
    /// The collider it belongs to.
    collider: usize,
    /// The groups it collides with (its collider's mask, `collide/groups.rs`).
    mask: u32,
}

/// The event-driven state of a world's particles (module doc).
pub(crate) struct EventDriven {
    /// The particles in our own order (`order[k]`: the world's index of our particle k).
    bodies: Vec<Body>,
    order: Vec<u32>,
    /// Radii in our order, m.
    radius: Vec<f64>,
    shells: Shells,
    /// Each particle's next event (its time and kind).
    calendar: Calendar<Kind>,
    walls: Vec<Wall>,
    /// Particles' own times are all this, s, between calls.
    time: f64,
    /// The uniform field, m/s²: the particles' acceleration between impacts.
    g: [f64; 3],
    /// With collision groups (`collide/groups.rs`): each particle's group in our order and
    /// the groups' masks in effect; `None` when every pair collides.
    groups: Option<(Vec<u8>, [u32; crate::collide::GROUPS])>,
}

/// What the event-driven path cannot do, or `None`: a collider other than a still plane or
/// box (spheres and meshes are not walls).
pub(crate) fn unsupported_collider(colliders: &[Collider]) -> Option<(usize, &'static str)> {
    colliders.iter().enumerate().find_map(|(k, c)| match c {
        Collider::Plane(_) | Collider::Box(_) => None,
        Collider::Sphere(_) => Some((k, "a sphere obstacle")),
        Collider::Mesh(_) => Some((k, "a triangle mesh")),
    })
}

/// The cells' range: the periodic cell along its axes, the bodies' extent elsewhere (the
/// origin without bodies).
fn cells_range(bodies: &[Body], cell: Option<&Periodic>) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for b in bodies {
        for k in 0..3 {
            lo[k] = lo[k].min(b.x[k]);
            hi[k] = hi[k].max(b.x[k]);
        }
    }
    if let Some(c) = cell {
        for k in (0..3).filter(|&k| c.axes()[k]) {
            lo[k] = c.lo()[k];
            hi[k] = c.hi()[k];
        }
    }
    if bodies.is_empty() {
        lo = [0.0; 3];
        hi = [0.0; 3];
    }
    (lo, hi)
}

/// The neighbour lists' shell δ (m) of `n` particles filling the cells' range `lo..hi` of a
/// `dim`-dimensional domain, with mean and largest radii `radii` and the periodic `cell`.
fn shell_width(
    (lo, hi): ([f64; 3], [f64; 3]),
    n: usize,
    dim: usize,
    (r_mean, r_max): (f64, f64),
    cell: Option<&Periodic>,
) -> f64 {
    // (at least half the mean spacing of the particles in the space they fill: point
    // particles, or ones far smaller than their spacing, would otherwise leave a shell of
    // almost nothing at every move, and a step never end; the hard-sphere gas of the
    // benchmark, φ = 0.25, has 0.64 σ there, under its 0.7 σ)
    let room: f64 = (0..dim).map(|k| (hi[k] - lo[k]).max(0.0)).product();
    let spacing = if n > 0 {
        (room / n as f64).powf(1.0 / dim as f64)
    } else {
        0.0
    };
    let mut delta = (SHELL * 2.0 * r_mean).max(0.5 * spacing);
    // the minimum image must find every partner within reach: 2 r_max + δ < L/2
    if let Some(c) = cell {
        for k in (0..3).filter(|&k| c.axes()[k]) {
            delta = delta.min(0.9 * (0.5 * c.period(k) - 2.0 * r_max));
        }
    }
    if delta.is_nan() || delta <= 0.0 {
        delta = f64::MIN_POSITIVE; // point particles: the list holds touching pairs only
    }
    delta
}

/// What [`EventDriven::advance`] takes besides the state, handed whole to its loop.
type AdvanceArgs<'a, 'm> = (
    &'a mut Particles,
    &'a MaterialTable<'m>,
    f64,
    &'a Domain,
    f64,
    &'a mut [ColliderBooks],
    &'a mut Interrupt,
);

impl EventDriven {
    /// The state of particles `p` at time `t0` (s): positions wrapped into the periodic cell,
    /// every neighbour list made, every particle's first event scheduled. The colliders must
    /// be planes and boxes ([`unsupported_collider`]); the radii must suit the domain
    /// ([`Domain::check_radii`]).
    pub fn new(p: &Particles, colliders: &[Collider], domain: &Domain, filter: Option<Filter<'_>>, t0: f64, g: [f64; 3]) -> Self {
        let n = p.len();
        let cell = domain.periodic_box().copied();
        let r_max = p.radius.iter().cloned().fold(0.0, f64::max);
        let r_mean = if n > 0 { p.radius.iter().sum::<f64>() / n as f64 } else { 0.0 };
        // Our own order, along a Morton curve of cells about a list's reach wide: the partners
        // an event reads then mostly sit in nearby memory (the state is larger than a core's
        // cache from ~10⁴ particles on, and an event is a chain of such reads).
        let lowest = (0..3).map(|k| (0..n).map(|i| p.x[3 * i + k]).fold(f64::INFINITY, f64::min));
        let origin: Vec<f64> = lowest.map(|v| if v.is_finite() { v } else { 0.0 }).collect();
        let order = morton_order(
            &p.x,
            [origin[0], origin[1], origin[2]],
            (2.0 * r_max).max(f64::MIN_POSITIVE) * (1.0 + SHELL),
        );
        let bodies: Vec<Body> = order
            .iter()
            .map(|&i| {
                let i = i as usize;
                let x = vec3::get(&p.x, i);
                Body {
                    x: cell.map_or(x, |c| c.wrap(x)),
                    t: t0,
                    v: vec3::get(&p.v, i),
                    path: 0,
                    schedule: 0,
                }
            })
            .collect();
        let radius: Vec<f64> = order.iter().map(|&i| p.radius[i as usize]).collect();
        let mut walls = collect_walls(colliders, domain);
        let groups = filter.map(|f| {
            for w in &mut walls {
                w.mask = f.collider_mask(w.collider);
            }
            let ours: Vec<u8> = order.iter().map(|&i| f.group(i as usize) as u8).collect();
            (ours, f.masks())
        });

        // The cells' range: the periodic cell along its axes, the particles' extent elsewhere.
        let (lo, hi) = cells_range(&bodies, cell.as_ref());
        let delta = shell_width((lo, hi), n, domain.dim(), (r_mean, r_max), cell.as_ref());
        let centres: Vec<[f64; 3]> = bodies.iter().map(|b| b.x).collect();
        let shells = Shells::new(&centres, &radius, domain, lo, hi, delta);
        let mut state = EventDriven {
            bodies,
            order,
            radius,
            shells,
            calendar: Calendar::new(t0, 1.0, 1),
            walls,
            time: t0,
            g,
            groups,
        };
        state.schedule_first(t0, domain);
        state
    }

    /// Every particle's first event at `t0` (s), then a calendar sized for them.
    fn schedule_first(&mut self, t0: f64, domain: &Domain) {
        let n = self.bodies.len();
        let first: Vec<(f64, Kind)> = (0..n).map(|i| self.find(i, t0, domain)).collect();
        let waits: Vec<f64> = first.iter().map(|e| e.0 - t0).filter(|w| w.is_finite()).collect();
        let mean_wait = if waits.is_empty() {
            1.0
        } else {
            waits.iter().sum::<f64>() / waits.len() as f64
        };
        let width = Calendar::<Kind>::width_for(waits.len(), mean_wait);
        self.calendar = Calendar::new(t0, width, n.next_power_of_two().clamp(64, 1 << 20));
        for (i, e) in first.into_iter().enumerate() {
            self.enter(i, e);
        }
    }

    /// Whether the state is for `n` particles at time `t` (s): what the world checks before
    /// going on with it.
    pub fn is_at(&self, n: usize, t: f64, g: [f64; 3]) -> bool {
        self.bodies.len() == n && self.time == t && self.g == g
    }

    /// Runs every event up to time `t1` (s), then moves every particle to t1 and writes
    /// positions (wrapped into the periodic cell) and velocities into `p`. Returns the books of
    /// the impacts (impacts, impulses, energy lost, impulse balance) and adds what the walls
    /// took to `walls_books` (one per collider). Stops with the interrupt's error, leaving the
    /// particles as they were at the call (the state is then of no further use).
    ///
    /// The loop runs on x86-64-v3's instructions where the CPU has them (`simd.rs`: the
    /// same bits as the baseline's).
    #[allow(clippy::too_many_arguments)]
    pub fn advance(
        &mut self,
        p: &mut Particles,
        materials: &MaterialTable<'_>,
        restitution_threshold: f64,
        domain: &Domain,
        t1: f64,
        walls_books: &mut [ColliderBooks],
        interrupt: &mut Interrupt,
    ) -> Result<CollisionStats, Error> {
        let args = (p, materials, restitution_threshold, domain, t1, walls_books, interrupt);
        #[cfg(target_arch = "x86_64")]
        if crate::simd::v3() {
            // SAFETY: the CPU has every feature `advance_v3` is compiled for (`simd::v3`).
            return unsafe { self.advance_v3(args) };
        }
        self.advance_baseline(args)
    }

    /// [`EventDriven::advance`] on the baseline instruction set.
    fn advance_baseline(&mut self, args: AdvanceArgs<'_, '_>) -> Result<CollisionStats, Error> {
        self.advance_loop(args)
    }

    /// [`EventDriven::advance`] on x86-64-v3's instructions.
    ///
    /// # Safety
    /// Only where the CPU has them ([`crate::simd::v3`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2")]
    unsafe fn advance_v3(&mut self, args: AdvanceArgs<'_, '_>) -> Result<CollisionStats, Error> {
        self.advance_loop(args)
    }

    /// The event loop of [`EventDriven::advance`], inlined into each instruction set's
    /// version with everything it calls on every event.
    #[inline(always)]
    fn advance_loop(
        &mut self,
        (p, materials, restitution_threshold, domain, t1, walls_books, interrupt): AdvanceArgs<'_, '_>,
    ) -> Result<CollisionStats, Error> {
        let mut stats = CollisionStats::default();
        let mut events = 0u64;
        loop {
            events += 1;
            if events % POLL_EVERY == 0 {
                interrupt.poll()?;
            }
            let bodies = &self.bodies;
            let Some(entry) = self
                .calendar
                .pop_until(t1, |e| e.version == bodies[e.particle as usize].schedule)
            else {
                break;
            };
            let (i, now) = (entry.particle as usize, entry.time);
            match entry.what {
                Kind::Pair { j, path } if self.bodies[j as usize].path != path => {
                    // j changed course since: i's event is found again from now
                    self.reschedule(i, now, domain);
                }
                Kind::Pair { j, .. } => {
                    let j = j as usize;
                    self.impact_pair(i, j, now, p, materials, restitution_threshold, domain, &mut stats);
                    self.reschedule(i, now, domain);
                    self.reschedule(j, now, domain);
                }
                Kind::Wall(k) => {
                    let k = k as usize;
                    let bounced = self.impact_wall(i, k, now, p, materials, restitution_threshold, &mut stats, walls_books);
                    let n = self.walls[k].normal;
                    if !bounced && vec3::dot(self.g, n) < 0.0 && vec3::dot(self.bodies[i].v, n) >= 0.0 {
                        // at rest on the wall with the field pressing it there: its next
                        // event would be this one again, forever
                        return Err(Error::invalid(
                            "event_driven",
                            "True",
                            format!(
                                "particle {} rests on collider {} under the field, a contact that events cannot hold (event_driven=False steps it)",
                                self.order[i], self.walls[k].collider
                            ),
                        ));
                    }
                    self.reschedule(i, now, domain);
                }
                Kind::Shell => {
                    let b = &mut self.bodies[i];
                    b.move_to(now, self.g, Some(domain));
                    // the new shell's centre lies ahead on its way (module doc)
                    let speed = vec3::norm(b.v);
                    let c = if speed > 0.0 {
                        vec3::add(b.x, vec3::scale(AHEAD * 0.5 * self.shells.delta / speed, b.v))
                    } else {
                        b.x
                    };
                    let c = domain.periodic_box().map_or(c, |p| p.wrap(c));
                    self.shells.remake(i, c, &self.radius, domain);
                    self.reschedule(i, now, domain);
                }
                Kind::Nothing => {}
            }
        }
        // Every particle where it is at t1, into the world's arrays. The bodies themselves stay
        // at their own times: moved to t1 (rounded there), the next call would go on from other
        // bits than one call over both spans, and how a run is cut into calls would change it.
        for (b, &i) in self.bodies.iter().zip(&self.order) {
            let mut now = *b;
            now.move_to(t1, self.g, Some(domain));
            let i = i as usize;
            p.x[3 * i..3 * i + 3].copy_from_slice(&now.x);
            p.v[3 * i..3 * i + 3].copy_from_slice(&now.v);
        }
        self.time = t1;
        Ok(stats)
    }

    /// Finds particle i's event from time `now` again and schedules it.
    #[inline(always)]
    fn reschedule(&mut self, i: usize, now: f64, domain: &Domain) {
        let next = self.find(i, now, domain);
        self.enter(i, next);
    }

    /// Enters particle i's event (its time, s, and kind) into the calendar (a new schedule:
    /// older entries go stale).
    #[inline(always)]
    fn enter(&mut self, i: usize, (time, what): (f64, Kind)) {
        let b = &mut self.bodies[i];
        b.schedule = b.schedule.wrapping_add(1);
        if time.is_finite() {
            self.calendar.push(Entry {
                time,
                particle: i as u32,
                version: b.schedule,
                what,
            });
        }
    }

    /// Particle i's earliest event after `now` (s): an impact with a partner of its list or a
    /// wall, or leaving its shell (module doc).
    #[inline(always)]
    fn find(&self, i: usize, now: f64, domain: &Domain) -> (f64, Kind) {
        if self.g == [0.0; 3] {
            self.find_in::<false>(i, now, domain)
        } else {
            self.find_in::<true>(i, now, domain)
        }
    }

    /// [`EventDriven::find`] with (`FIELD`) or without a field: the force-free search skips
    /// the field's terms, which are 0 there (its results are the same to the bit).
    #[inline(always)]
    fn find_in<const FIELD: bool>(&self, i: usize, now: f64, domain: &Domain) -> (f64, Kind) {
        let g = if FIELD { self.g } else { [0.0; 3] };
        let bi = self.bodies[i];
        let ri = self.radius[i];
        let (xi, vi) = if FIELD {
            (bi.at(now, g), bi.velocity(now, g))
        } else {
            (bi.line(now), bi.v)
        };
        // leaving the shell: |d + v τ| = δ/2 with d = x − c inside (|d| ≤ δ/2); under a field
        // |d + v τ + ½ g τ²| ≤ |d| + |v| τ + ½ |g| τ², whose reaching δ/2 comes no later
        let half = 0.5 * self.shells.delta;
        let d = domain.displacement(xi, self.shells.centre[i]);
        let a = vec3::dot(vi, vi);
        let mut best = (f64::INFINITY, Kind::Nothing);
        if !FIELD {
            if a > 0.0 {
                let b = vec3::dot(d, vi);
                let c = vec3::dot(d, d) - half * half;
                let tau = if c >= 0.0 { 0.0 } else { (-b + (b * b - a * c).sqrt()) / a };
                best = (now + tau, Kind::Shell);
            }
        } else {
            // ½|g| τ² + |v| τ − (δ/2 − |d|) = 0, its positive root written without cancellation
            let room = (half - vec3::norm(d)).max(0.0);
            let (speed, pull) = (a.sqrt(), 0.5 * vec3::norm(g));
            let tau = 2.0 * room / (speed + (speed * speed + 4.0 * pull * room).sqrt());
            best = (now + tau, Kind::Shell);
        }
        // (with collision groups: i's group, and the groups i collides with)
        let (gi, mi) = self.groups.as_ref().map_or((0, u32::MAX), |(g, m)| (g[i], m[g[i] as usize]));
        // its partners' bodies asked of the cache all at once, before the first is read: the
        // loop below waits on each one's line otherwise (1 thread, the 32,000-sphere gas of
        // `benchmarks/hard_sphere_gas.py`: 2–11 % more collisions per CPU-second in 7 pairs)
        for &j in self.shells.of(i) {
            crate::simd::prefetch(&self.bodies[j as usize]);
        }
        for &j in self.shells.of(i) {
            if let Some((g, _)) = &self.groups {
                if mi >> g[j as usize] & 1 == 0 {
                    continue; // a pair that does not collide
                }
            }
            let bj = &self.bodies[j as usize];
            // the field moves both alike: their relative motion is a straight line
            let (xj, vj) = if FIELD {
                (bj.at(now, g), bj.velocity(now, g))
            } else {
                (bj.line(now), bj.v)
            };
            let d = domain.displacement(xi, xj);
            let u = vec3::sub(vi, vj);
            let b = vec3::dot(d, u);
            if b >= 0.0 {
                continue; // apart or parting
            }
            let reach = ri + self.radius[j as usize];
            let c = vec3::dot(d, d) - reach * reach;
            let tau = if c <= 0.0 {
                0.0
            } else {
                let uu = vec3::dot(u, u);
                let disc = b * b - uu * c;
                if disc < 0.0 {
                    continue; // passes by
                }
                c / (-b + disc.sqrt())
            };
            if now + tau < best.0 {
                best = (now + tau, Kind::Pair { j, path: bj.path });
            }
        }
        for (k, w) in self.walls.iter().enumerate() {
            if w.mask >> gi & 1 == 0 {
                continue; // a wall that lets i's group through
            }
            let tau = if !FIELD {
                let u = vec3::dot(vi, w.normal);
                if u >= 0.0 {
                    continue;
                }
                let s = vec3::dot(vec3::sub(xi, w.point), w.normal) - ri;
                s.max(0.0) / -u
            } else {
                // the parabola's first touch of the wall's half-space
                match toi_half_space(xi, vi, g, ri, w.point, w.normal, f64::INFINITY) {
                    Some(tau) => tau,
                    None => continue,
                }
            };
            if now + tau < best.0 {
                best = (now + tau, Kind::Wall(k as u32));
            }
        }
        best
    }
}

/// The walls of the colliders: every plane, and every box wall not along a periodic axis.
fn collect_walls(colliders: &[Collider], domain: &Domain) -> Vec<Wall> {
    let periodic = domain.periodic_box().map_or([false; 3], |p| p.axes());
    let mut walls = Vec::new();
    for (k, c) in colliders.iter().enumerate() {
        match c {
            Collider::Plane(plane) => walls.push(Wall {
                point: plane.point(),
                normal: plane.normal(),
                collider: k,
                mask: u32::MAX,
            }),
            Collider::Box(b) => {
                for plane in b.walls() {
                    let n = plane.normal();
                    if (0..3).any(|a| periodic[a] && n[a] != 0.0) {
                        continue;
                    }
                    walls.push(Wall {
                        point: plane.point(),
                        normal: n,
                        collider: k,
                        mask: u32::MAX,
                    });
                }
            }
            _ => {}
        }
    }
    walls
}

#[cfg(test)]
mod tests;
