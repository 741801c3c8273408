//! The spring–dashpot contact model as a force of stage 1: contacts found at every force
//! evaluation push overlapping bodies apart with F_n = k_n δ − m_eff γ_n u_n.
//!
//! The contacts come from a Verlet neighbour list ([`NeighbourList`]): the grid's candidate
//! pairs within r_i + r_j + skin (and the particles within the skin of a collider), kept until
//! the particles have moved far enough that something left out could touch. Every evaluation
//! tests what is listed exactly, so the contacts, and the forces, are those of a search at
//! every evaluation, bit for bit.
//!
//! The list is a full one (each pair listed from both sides) kept in chunks of
//! [`CHUNK`] particles, so that the build and the force pass run on all threads with rayon and
//! each particle's force is summed by one thread alone, in a fixed order: the result does not
//! depend on the number of threads.

use std::sync::{Mutex, MutexGuard};

use rayon::prelude::*;

use super::collisions::on_periodic_wall;
pub(crate) use crate::collide::neighbour_list::CHUNK;
use crate::collide::neighbour_list::{collider_scale, NeighbourList, Rows, SKIN_PER_RADIUS};
use crate::collide::{
    damping_ratio, dashpot_coefficient, pair_contact, spring_dashpot_force, Collider, Contact, Domain, Grid, Material, Partner,
    GEOMETRY_LIMIT,
};
use crate::error::{CallbackError, Error};
use crate::forces::{EnergyClass, Force, Properties, Rates, Standby, State};
use crate::particles::GONE;

/// Penalty contacts between particles and with colliders (the DEM way).
///
/// While particle i overlaps its partner by δ > 0, the pair feels F_n n on i and −F_n n on a
/// partner particle (a collider takes the reaction), N, with
///
/// ```text
///   F_n = k_n δ − c_n u_n,      c_n = 2 ζ √(k_n m_eff)   (ζ from e, closed form)
///                               c_n = m_eff γ_n           (γ_n given)
/// ```
///
/// m_eff = 1/(w_i + w_j) the reduced mass and u_n the normal relative velocity. The damping
/// ratio ζ = −ln e / √(π² + ln² e) makes the contact's damped half-oscillation bounce back with
/// exactly the requested e ([`crate::collide::penalty`]); e is the pair's material (global,
/// per particle, per collider, combined as in the impulse model). The spring part is
/// conservative, with U = Σ ½ k_n δ² over overlapping contacts; the dashpot only removes
/// energy. No friction: tangential forces belong to the impulse model.
pub(crate) struct ContactForce {
    stiffness: f64,
    damping: Option<f64>,
    global: Material,
    own: Option<Vec<Material>>,
    /// ζ of the pair materials, worked out once.
    ratios: DampingRatios,
    radius: Vec<f64>,
    inv_mass: Vec<f64>,
    colliders: Vec<Collider>,
    domain: Domain,
    /// The neighbour list's skin, m.
    skin: f64,
    /// The largest |coordinate| of the colliders' points, centres and radii, m (for the
    /// neighbour list's rounding margin).
    collider_scale: f64,
    /// Buffers kept between evaluations (a mutex, not a `RefCell`: the passes share `&self`
    /// across threads).
    scratch: Mutex<Scratch>,
}

#[derive(Default)]
struct Scratch {
    grid: Grid,
    list: NeighbourList,
    /// Each chunk's share of the contact energy, J (kept to allocate nothing per evaluation).
    chunk_energy: Vec<f64>,
}

impl ContactForce {
    /// The force for particles of radii `radius` (m) and inverse masses `inv_mass` (1/kg),
    /// with stiffness k_n (N/m) and optional damping rate γ_n (1/s), the pair materials from
    /// `global` and `own`, the colliders and the domain (2D/3D, periodic axes).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        stiffness: f64,
        damping: Option<f64>,
        global: Material,
        own: Option<Vec<Material>>,
        radius: Vec<f64>,
        inv_mass: Vec<f64>,
        colliders: Vec<Collider>,
        domain: Domain,
    ) -> Self {
        let mean_radius = if radius.is_empty() {
            0.0
        } else {
            radius.iter().sum::<f64>() / radius.len() as f64
        };
        ContactForce {
            stiffness,
            damping,
            ratios: DampingRatios::new(global, own.as_deref(), &colliders),
            global,
            own,
            skin: SKIN_PER_RADIUS * mean_radius,
            collider_scale: colliders.iter().map(collider_scale).fold(0.0, f64::max),
            radius,
            inv_mass,
            colliders,
            domain,
            scratch: Mutex::new(Scratch::default()),
        }
    }

    /// The same force with a neighbour-list skin of `skin` m (≥ 0, finite; 0 searches the
    /// grid at every evaluation).
    #[cfg(test)]
    fn with_skin(mut self, skin: f64) -> Self {
        self.skin = skin;
        self
    }

    /// Whether the neighbour list must be rebuilt before an evaluation at positions `x` (m,
    /// 3 per particle): there is none, or the particles have moved too far since its build.
    ///
    /// The world asks this right before the force evaluation at the same `x`; a yes is
    /// remembered for that buffer, so the evaluation does not check a second time.
    pub fn list_expired(&self, x: &[f64]) -> bool {
        let list = &mut self.scratch().list;
        let holds = list.holds(x, &self.domain);
        list.verified = holds.then_some((x.as_ptr() as usize, x.len()));
        !holds
    }

    /// Forgets what [`ContactForce::list_expired`] found (the world calls this at the end of
    /// each step, so that a buffer reused later is checked again).
    pub fn forget_verified(&self) {
        self.scratch().list.verified = None;
    }

    /// The width of the cells the neighbour list searches, 2 r_max + skin, m.
    pub fn reach(&self) -> f64 {
        2.0 * self.radius.iter().fold(0.0, |m: f64, r| m.max(*r)) + self.skin
    }

    /// The domain (2D/3D, periodic axes).
    pub fn domain(&self) -> &Domain {
        &self.domain
    }

    /// The buffers (a panic in another evaluation leaves them usable: each build starts over).
    fn scratch(&self) -> MutexGuard<'_, Scratch> {
        self.scratch.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// How many times the neighbour list was built so far.
    #[cfg(test)]
    fn list_builds(&self) -> usize {
        self.scratch().list.builds
    }

    /// Calls `each` with every contact at state `s`, in the order of a full search: particle
    /// pairs by (i, j) (those of the neighbour list that touch, each tested exactly as
    /// [`pair_contact`] tests it), then particle by particle, collider by collider, wall by
    /// wall (box walls along periodic axes left out), as
    /// [`collider_contacts`](crate::collide::collider_contacts) lists them.
    fn for_each_contact(&self, s: &State, scratch: &mut Scratch, mut each: impl FnMut(&Contact)) -> Result<(), Error> {
        self.update_list(s, scratch)?;
        let list = &scratch.list;
        let (x, v) = (s.x, s.v);
        for (c, rows) in list.rows.iter().enumerate() {
            for (l, i) in (c * CHUNK..).take(rows.len()).enumerate() {
                for &j in rows.of(l) {
                    if j as usize > i {
                        if let Some(contact) = self.pair(i, j as usize, x, v) {
                            each(&contact);
                        }
                    }
                }
            }
        }
        self.for_each_wall_contact(s, list, each);
        Ok(())
    }

    /// The contact of particles i < j at (x, v), if they overlap: `pair_contact`, after its own
    /// test |d|² < (r_i + r_j + 0)² with the same floating-point operations, inline (most
    /// listed pairs do not touch, and are dropped here without a call).
    #[inline]
    fn pair(&self, i: usize, j: usize, x: &[f64], v: &[f64]) -> Option<Contact> {
        let d = self
            .domain
            .displacement([x[3 * i], x[3 * i + 1], x[3 * i + 2]], [x[3 * j], x[3 * j + 1], x[3 * j + 2]]);
        let reach = self.radius[i] + self.radius[j] + 0.0;
        if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= reach * reach {
            return None;
        }
        pair_contact(i, j, x, v, &self.radius, &self.domain, 0.0)
    }

    /// Calls `each(contact, first)` with the contact of particle i with each listed partner j
    /// it overlaps at (x, v), in the row's order; the contact is computed with the lower index
    /// first (`first`: i is that one), so both sides of a pair see the same numbers.
    #[inline]
    fn for_each_partner_contact(&self, i: usize, partners: &[u32], x: &[f64], v: &[f64], mut each: impl FnMut(&Contact, bool)) {
        let (xi, ri) = ([x[3 * i], x[3 * i + 1], x[3 * i + 2]], self.radius[i]);
        for &j in partners {
            let j = j as usize;
            if !self.overlaps(xi, ri, j, x) {
                continue;
            }
            let (lo, hi) = if i < j { (i, j) } else { (j, i) };
            if let Some(contact) = pair_contact(lo, hi, x, v, &self.radius, &self.domain, 0.0) {
                each(&contact, i == lo);
            }
        }
    }

    /// Whether particles i and j overlap at `x`, tested from i's side with x_i already loaded:
    /// the same operations as [`ContactForce::pair`]'s test of the pair (lower index first),
    /// bit for bit, since x_i − x_j = −(x_j − x_i) exactly, the minimum image is odd and the
    /// squares and r_i + r_j do not care about the order.
    #[inline]
    fn overlaps(&self, xi: [f64; 3], ri: f64, j: usize, x: &[f64]) -> bool {
        let d = self.domain.displacement(xi, [x[3 * j], x[3 * j + 1], x[3 * j + 2]]);
        let reach = ri + self.radius[j] + 0.0;
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < reach * reach
    }

    /// Calls `each` with every contact of a particle with a collider at `s`, particle by
    /// particle, collider by collider (the list must hold at `s`).
    fn for_each_wall_contact(&self, s: &State, list: &NeighbourList, mut each: impl FnMut(&Contact)) {
        for &(i, k) in &list.walls {
            self.wall_contacts(i, k, s.x, s.v, &mut each);
        }
    }

    /// Calls `each` with the contacts of particle i with collider k at (x, v) (a box's walls
    /// along periodic axes left out).
    #[inline]
    fn wall_contacts(&self, i: usize, k: usize, x: &[f64], v: &[f64], mut each: impl FnMut(&Contact)) {
        let (p, vi) = ([x[3 * i], x[3 * i + 1], x[3 * i + 2]], [v[3 * i], v[3 * i + 1], v[3 * i + 2]]);
        self.colliders[k].for_each_touch(p, self.radius[i], 0.0, |t| {
            let c = Contact {
                i,
                other: Partner::Collider(k),
                normal: t.normal,
                overlap: t.overlap,
                u_n: vi[0] * t.normal[0] + vi[1] * t.normal[1] + vi[2] * t.normal[2],
            };
            if !on_periodic_wall(&c, &self.colliders, &self.domain) {
                each(&c);
            }
        });
    }

    /// Velocity Verlet's force evaluation and closing kick fused into one parallel pass over
    /// the particles (see `VerletBuffers` in `world/mod.rs`): for each particle i,
    ///
    /// ```text
    ///   F_i  = other_i + Σ_j contact forces (pairs, then colliders: as `accumulate` sums them)
    ///   a'_i = F_i / m_i           (into `a`, which held a_i: only i reads its own a_i)
    ///   v_i  ← v_i + h/2 (a_i + a'_i)   (into `v_out`)
    /// ```
    ///
    /// at the drifted state `s` (x', and the predictor v' that the dashpot sees), with
    /// `v` the velocities at the step's start, `other` the other forces' sum (N; `None`: none),
    /// `inv_mass` (0 pinned) and `flat` (2D: a_z = 0). Saves the separate passes that clear the
    /// force buffer, turn it into accelerations and kick. Returns the first non-finite
    /// coordinate of x' or of the new velocities, if any.
    #[allow(clippy::too_many_arguments)]
    pub fn verlet_force_and_kick(
        &self,
        s: &State,
        other: Option<&[f64]>,
        inv_mass: &[f64],
        flat: bool,
        h: f64,
        v: &[f64],
        a: &mut [f64],
        v_out: &mut [f64],
    ) -> Result<Option<usize>, Error> {
        let mut scratch = self.scratch();
        self.update_list(s, &mut scratch)?;
        let list = &scratch.list;
        let (x, vp) = (s.x, s.v);
        let bad = a
            .par_chunks_mut(3 * CHUNK)
            .zip(v_out.par_chunks_mut(3 * CHUNK))
            .zip(list.rows.par_iter())
            .enumerate()
            .map(|(c, ((ac, vc), rows))| {
                let first = c * CHUNK;
                // this chunk's wall candidates (sorted by particle)
                let w0 = list.walls.partition_point(|w| w.0 < first);
                let w1 = list.walls.partition_point(|w| w.0 < first + rows.len());
                let mut walls = list.walls[w0..w1].iter().peekable();
                let mut bad = None;
                for (l, i) in (first..).take(rows.len()).enumerate() {
                    let mut f = match other {
                        Some(o) => [o[3 * i], o[3 * i + 1], o[3 * i + 2]],
                        None => [0.0; 3],
                    };
                    self.for_each_partner_contact(i, rows.of(l), x, vp, |contact, first| {
                        if let Some(force) = self.normal_force(contact) {
                            for k in 0..3 {
                                if first {
                                    f[k] += force * contact.normal[k];
                                } else {
                                    f[k] -= force * contact.normal[k];
                                }
                            }
                        }
                    });
                    while let Some(&(_, k)) = walls.next_if(|w| w.0 == i) {
                        self.wall_contacts(i, k, x, vp, |contact| {
                            if let Some(force) = self.normal_force(contact) {
                                for (fk, nk) in f.iter_mut().zip(contact.normal) {
                                    *fk += force * nk;
                                }
                            }
                        });
                    }
                    let w = inv_mass[i];
                    for k in 0..3 {
                        let a_new = if flat && k == 2 { 0.0 } else { f[k] * w };
                        let q = 3 * l + k;
                        vc[q] = v[3 * i + k] + 0.5 * h * (ac[q] + a_new);
                        ac[q] = a_new;
                        if bad.is_none() && !(vc[q].is_finite() && x[3 * i + k].is_finite()) {
                            bad = Some(3 * i + k);
                        }
                    }
                }
                bad
            })
            .flatten() // (Option's own order puts None first: drop the clean chunks)
            .min();
        Ok(bad)
    }

    /// The pair forces at `s` added to `f` (N, 3 per particle), and the pairs' energy
    /// Σ ½ k_n δ² (J). Chunk by chunk in parallel: particle i sums the forces of its listed
    /// partners in ascending order of j, each pair's contact computed with the lower index
    /// first, so i and j get F_n n and −F_n n to the bit; a pair's energy is counted by its
    /// lower index, and the chunks' sums are added in chunk order. Without `f`, the energy only.
    fn pair_pass(&self, s: &State, scratch: &mut Scratch, f: Option<&mut [f64]>) -> f64 {
        let Scratch { list, chunk_energy, .. } = scratch;
        let (x, v) = (s.x, s.v);
        let chunk = |c: usize, rows: &Rows, mut fc: Option<&mut [f64]>| {
            let mut energy = -0.0;
            for (l, i) in (c * CHUNK..).take(rows.len()).enumerate() {
                self.for_each_partner_contact(i, rows.of(l), x, v, |contact, first| {
                    if first {
                        if let Some(u) = self.spring_energy(contact) {
                            energy += u;
                        }
                    }
                    let (Some(fc), Some(force)) = (fc.as_deref_mut(), self.normal_force(contact)) else {
                        return;
                    };
                    for k in 0..3 {
                        if first {
                            fc[3 * l + k] += force * contact.normal[k];
                        } else {
                            fc[3 * l + k] -= force * contact.normal[k];
                        }
                    }
                });
            }
            energy
        };
        match f {
            Some(f) => f
                .par_chunks_mut(3 * CHUNK)
                .zip(list.rows.par_iter())
                .enumerate()
                .map(|(c, (fc, rows))| chunk(c, rows, Some(fc)))
                .collect_into_vec(chunk_energy),
            None => list
                .rows
                .par_iter()
                .enumerate()
                .map(|(c, rows)| chunk(c, rows, None))
                .collect_into_vec(chunk_energy),
        }
        chunk_energy.iter().fold(-0.0, |sum, u| sum + u)
    }

    /// The force of contact `c` along its normal, N (> 0 pushes apart), or `None` when it
    /// exerts none (not overlapping, or both sides immovable).
    #[inline]
    fn normal_force(&self, c: &Contact) -> Option<f64> {
        let w = self.inverse_mass_sum(c);
        if c.overlap.is_nan() || c.overlap <= 0.0 || w == 0.0 {
            return None;
        }
        Some(spring_dashpot_force(self.stiffness, self.dashpot(c, w), c.overlap, c.u_n))
    }

    /// ½ k_n δ² of contact `c` if it counts in the potential energy (overlapping, with a
    /// movable particle), J.
    #[inline]
    fn spring_energy(&self, c: &Contact) -> Option<f64> {
        (c.overlap > 0.0 && self.inverse_mass_sum(c) > 0.0).then_some(0.5 * self.stiffness * c.overlap * c.overlap)
    }

    /// U = Σ ½ k_n δ² at the positions of `s` (J), summed as the force evaluation sums it.
    fn potential_at(&self, s: &State, scratch: &mut Scratch) -> Result<f64, Error> {
        self.update_list(s, scratch)?;
        let mut energy = self.pair_pass(s, scratch, None);
        self.for_each_wall_contact(s, &scratch.list, |c| {
            if let Some(u) = self.spring_energy(c) {
                energy += u;
            }
        });
        Ok(energy)
    }

    /// Checks the state's lengths and makes the neighbour list hold at its positions.
    fn update_list(&self, s: &State, scratch: &mut Scratch) -> Result<(), Error> {
        let n = self.radius.len();
        for (name, len) in [("x", s.x.len()), ("v", s.v.len())] {
            if len != 3 * n {
                return Err(Error::invalid(
                    name,
                    format!("{len} values"),
                    format!("3 per particle ({} for the {n} radii)", 3 * n),
                ));
            }
        }
        let Scratch { grid, list, .. } = scratch;
        list.update(
            grid,
            s.x,
            &self.radius,
            &self.colliders,
            &self.domain,
            self.skin,
            self.collider_scale,
        )
    }

    /// w_i + w_j of a contact.
    fn inverse_mass_sum(&self, c: &Contact) -> f64 {
        self.inv_mass[c.i] + c.partner_particle().map_or(0.0, |j| self.inv_mass[j])
    }

    /// c_n (kg/s) of a contact with w = w_i + w_j > 0.
    fn dashpot(&self, c: &Contact, w: f64) -> f64 {
        match self.damping {
            Some(gamma) => gamma / w,
            None => dashpot_coefficient(self.stiffness, self.ratios.of(c), w),
        }
    }
}

/// The damping ratio ζ = `damping_ratio`(e) of every contact's material, worked out once per
/// particle and collider rather than per contact (a logarithm and a square root each).
///
/// A pair of particles has e = max(e_i, e_j) ([`Material::combine`]), so its ζ is the ζ of
/// the particle with the larger e (either one when they are equal: the same e gives the same
/// ζ), bit for bit what `damping_ratio(max(e_i, e_j))` gives. Against a collider, the
/// collider's own e where it sets one, else the particle's.
struct DampingRatios {
    /// ζ of the global e.
    global: f64,
    /// (e, ζ) of each particle, when particles have their own materials.
    particles: Option<Vec<(f64, f64)>>,
    /// ζ of each collider's own e, where it sets one.
    colliders: Vec<Option<f64>>,
}

impl DampingRatios {
    fn new(global: Material, own: Option<&[Material]>, colliders: &[Collider]) -> Self {
        let zeta = |e: f64| damping_ratio(e).unwrap_or(0.0);
        DampingRatios {
            global: zeta(global.restitution()),
            particles: own.map(|m| m.iter().map(|m| (m.restitution(), zeta(m.restitution()))).collect()),
            colliders: colliders.iter().map(|c| c.surface().restitution().map(zeta)).collect(),
        }
    }

    /// Particle i's (e, ζ), or `None` when every particle has the global material.
    fn particle(&self, i: usize) -> Option<(f64, f64)> {
        self.particles.as_ref().map(|p| p[i])
    }

    /// ζ of contact `c`.
    fn of(&self, c: &Contact) -> f64 {
        match c.other {
            Partner::Collider(k) => self.colliders[k].unwrap_or_else(|| self.particle(c.i).map_or(self.global, |p| p.1)),
            Partner::Particle(j) => match (self.particle(c.i), self.particle(j)) {
                (Some((e_i, z_i)), Some((e_j, z_j))) => {
                    if e_j > e_i {
                        z_j
                    } else {
                        z_i
                    }
                }
                _ => self.global,
            },
        }
    }
}

impl Force for ContactForce {
    fn name(&self) -> &str {
        "contact"
    }

    /// The contact forces at `s`: particle pairs on all threads, then colliders.
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        let mut scratch = std::mem::take(&mut *self.scratch());
        let result = self.update_list(s, &mut scratch);
        if result.is_ok() {
            self.pair_pass(s, &mut scratch, Some(f));
            self.for_each_wall_contact(s, &scratch.list, |c| {
                if let Some(force) = self.normal_force(c) {
                    for k in 0..3 {
                        f[3 * c.i + k] += force * c.normal[k];
                    }
                }
            });
        }
        *self.scratch() = scratch;
        match result {
            Err(Error::InvalidParameter { .. }) if s.x.iter().chain(s.v).any(|c| !(c.abs() <= GEOMETRY_LIMIT)) => {
                // A state that is non-finite, or too large for the contacts' geometry (a
                // stage of rk45, an overflowing step): no contact force exists there. NaN
                // forces let the world stop the step as it stops any non-finite one
                // (SimulationDiverged), instead of an error about the list's internals.
                f.fill(f64::NAN);
                Ok(())
            }
            other => Ok(other?),
        }
    }

    // No `validate`: the world rebuilds this force whenever its particles change.

    /// U = Σ ½ k_n δ² over the overlapping contacts, J.
    fn potential_energy(&self, s: &State) -> Option<f64> {
        self.potential_at(s, &mut self.scratch()).ok()
    }

    /// Dissipative (the spring is conservative and the dashpot dissipative), a function of
    /// positions and velocities, internal when no collider pushes; it follows a renumbering.
    fn properties(&self) -> Properties {
        Properties {
            energy: EnergyClass::Dissipative,
            depends_on_position: true,
            depends_on_velocity: true,
            internal: self.colliders.is_empty(),
            renumbers: true,
        }
    }

    /// Radii, inverse masses, materials and the neighbour list follow their particles. A
    /// removal (some [`GONE`]) is left to the world, which rebuilds this force from the
    /// survivors ([`crate::World::remove_particles`]).
    fn reindex(&mut self, new_of_old: &[u32]) {
        if new_of_old.contains(&GONE) {
            return;
        }
        let mut old_of_new = vec![0u32; new_of_old.len()];
        for (old, &new) in new_of_old.iter().enumerate() {
            old_of_new[new as usize] = old as u32;
        }
        fn gather<T: Copy>(a: &[T], old_of_new: &[u32]) -> Vec<T> {
            old_of_new.iter().map(|&o| a[o as usize]).collect()
        }
        self.radius = gather(&self.radius, &old_of_new);
        self.inv_mass = gather(&self.inv_mass, &old_of_new);
        if let Some(own) = &self.own {
            self.own = Some(gather(own, &old_of_new));
        }
        if let Some(p) = &self.ratios.particles {
            self.ratios.particles = Some(gather(p, &old_of_new));
        }
        self.scratch().list.renumber(new_of_old, &old_of_new);
    }

    /// Gershgorin over the contacts at `s`: a contact adds k_n w_p to particle p's row twice
    /// with a particle partner (diagonal and off-diagonal), once against a collider; the
    /// dashpot likewise with c_n. The standby oscillation is [`ContactForce::standby`].
    fn rates(&self, s: &State, inv_mass: &[f64]) -> Option<Rates> {
        let mut k_row = vec![0.0; inv_mass.len()];
        let mut c_row = vec![0.0; inv_mass.len()];
        self.for_each_contact(s, &mut self.scratch(), |c| {
            let w = self.inverse_mass_sum(c);
            if c.overlap.is_nan() || c.overlap <= 0.0 || w == 0.0 {
                return;
            }
            let times = if c.partner_particle().is_some() { 2.0 } else { 1.0 };
            let dashpot = self.dashpot(c, w);
            for p in std::iter::once(c.i).chain(c.partner_particle()) {
                k_row[p] += times * self.stiffness;
                c_row[p] += times * dashpot;
            }
        })
        .ok()?;
        let mut rates = Rates {
            standby: self.standby(inv_mass),
            ..Rates::default()
        };
        for (p, w) in inv_mass.iter().enumerate() {
            rates.omega_squared = rates.omega_squared.max(w * k_row[p]);
            rates.damping_rate = rates.damping_rate.max(w * c_row[p]);
        }
        Some(rates)
    }
}

impl ContactForce {
    /// A contact that is not touching yet counts as a spring: ω² = k_n (w_i + w_j) for the
    /// two lightest movable particles (or k_n w against a collider), with the ζ of the
    /// largest restitution's opposite, the least damped contact.
    fn standby(&self, inv_mass: &[f64]) -> Option<Standby> {
        let mut lightest = [0.0_f64; 2];
        for w in inv_mass {
            if *w > lightest[0] {
                lightest = [*w, lightest[0]];
            } else if *w > lightest[1] {
                lightest[1] = *w;
            }
        }
        let w = (lightest[0] + lightest[1]).max(if self.colliders.is_empty() { 0.0 } else { lightest[0] });
        if w == 0.0 || (inv_mass.len() < 2 && self.colliders.is_empty()) {
            return None;
        }
        let omega_squared = self.stiffness * w;
        let zeta = match self.damping {
            Some(gamma) => gamma / (2.0 * omega_squared.sqrt()),
            None => {
                let e_max = self
                    .own
                    .iter()
                    .flatten()
                    .map(|m| m.restitution())
                    .chain(self.colliders.iter().filter_map(|c| c.surface().restitution()))
                    .fold(self.global.restitution(), f64::max);
                damping_ratio(e_max).unwrap_or(0.0)
            }
        };
        Some(Standby { omega_squared, zeta })
    }
}

#[cfg(test)]
mod tests {
    //! The neighbour list against a search at every evaluation: the forces and energies of
    //! [`ContactForce`] are compared bit for bit with a reference that finds the contacts with
    //! the O(N²) [`all_pairs`] and the collide kernels at every call and applies the law as
    //! written before the list (the material table and ζ per contact), while the particles
    //! move: through the sides of a periodic cell, at speeds that force rebuilds.

    use super::*;
    use crate::collide::{
        all_pairs, collider_contacts, sphere_contacts, BoxContainer, MaterialTable, Periodic, Plane, SphereObstacle, Surface,
    };
    use crate::forces::testing::Rng;

    /// Forces (N) and U (J) from the contacts of an exhaustive search at `s`, by the law as
    /// it was written before the neighbour list.
    fn reference(force: &ContactForce, s: &State) -> (Vec<f64>, f64) {
        let (mut pairs, mut contacts, mut walls) = (Vec::new(), Vec::new(), Vec::new());
        all_pairs(s.x, &force.radius, &force.domain, 0.0, &mut pairs).unwrap();
        sphere_contacts(s.x, s.v, &force.radius, &pairs, &force.domain, 0.0, &mut contacts).unwrap();
        collider_contacts(&force.colliders, s.x, s.v, &force.radius, 0.0, &mut walls).unwrap();
        contacts.extend(walls.iter().filter(|c| !on_periodic_wall(c, &force.colliders, &force.domain)));
        let table = MaterialTable::uniform(force.global).with_colliders(&force.colliders);
        let table = match &force.own {
            Some(m) => table.with_particles(m),
            None => table,
        };
        let mut f = vec![0.0; s.x.len()];
        for c in &contacts {
            let w = force.inverse_mass_sum(c);
            if c.overlap.is_nan() || c.overlap <= 0.0 || w == 0.0 {
                continue;
            }
            let dashpot = match force.damping {
                Some(gamma) => gamma / w,
                None => 2.0 * damping_ratio(table.pair(c).restitution()).unwrap_or(0.0) * (force.stiffness / w).sqrt(),
            };
            let fn_ = force.stiffness * c.overlap - dashpot * c.u_n;
            for k in 0..3 {
                f[3 * c.i + k] += fn_ * c.normal[k];
                if let Some(j) = c.partner_particle() {
                    f[3 * j + k] -= fn_ * c.normal[k];
                }
            }
        }
        let u = contacts
            .iter()
            .filter(|c| c.overlap > 0.0 && force.inverse_mass_sum(c) > 0.0)
            .map(|c| 0.5 * force.stiffness * c.overlap * c.overlap)
            .sum();
        (f, u)
    }

    fn bits(a: &[f64]) -> Vec<u64> {
        a.iter().map(|c| c.to_bits()).collect()
    }

    struct Scene {
        force: ContactForce,
        x: Vec<f64>,
        v: Vec<f64>,
        mass: Vec<f64>,
        /// A constant acceleration on every particle, m/s².
        g: [f64; 3],
    }

    /// Steps `scene` with symplectic Euler (kick with the contact forces and g, then drift,
    /// then wrap into the periodic cell as the world does) for `steps` steps of `dt`; at every
    /// step the force with the list, the same force rebuilding its list at every call (skin 0)
    /// and the exhaustive reference must give the same forces and energies, bit for bit.
    /// `kicks` gives particles new velocities before some steps (fast movers). Returns the
    /// list's builds and how many times a particle was wrapped through a periodic side.
    fn run(mut scene: Scene, steps: usize, dt: f64, kicks: &[(usize, usize, [f64; 3])]) -> (usize, usize) {
        let n = scene.mass.len();
        let mut every_call = ContactForce::new(
            scene.force.stiffness,
            scene.force.damping,
            scene.force.global,
            scene.force.own.clone(),
            scene.force.radius.clone(),
            scene.force.inv_mass.clone(),
            scene.force.colliders.clone(),
            scene.force.domain,
        )
        .with_skin(0.0);
        let (mut touching, mut wrapped) = (0, 0);
        for step in 0..steps {
            for &(when, i, v) in kicks {
                if when == step {
                    scene.v[3 * i..3 * i + 3].copy_from_slice(&v);
                }
            }
            let s = State {
                t: 0.0,
                x: &scene.x,
                v: &scene.v,
                mass: &scene.mass,
            };
            let (f_ref, u_ref) = reference(&scene.force, &s);
            let mut f = vec![0.0; 3 * n];
            scene.force.accumulate(&s, &mut f).unwrap();
            let mut f0 = vec![0.0; 3 * n];
            every_call.accumulate(&s, &mut f0).unwrap();
            assert_eq!(bits(&f), bits(&f_ref), "step {step}: forces with the list");
            assert_eq!(bits(&f0), bits(&f_ref), "step {step}: forces with a search at every call");
            let u = scene.force.potential_energy(&s).unwrap();
            assert_eq!(u.to_bits(), u_ref.to_bits(), "step {step}: remembered U {u} vs {u_ref}");
            touching += usize::from(u_ref > 0.0);
            for i in 0..n {
                for k in 0..3 {
                    let a = f[3 * i + k] * scene.force.inv_mass[i] + scene.g[k];
                    scene.v[3 * i + k] += dt * a;
                    scene.x[3 * i + k] += dt * scene.v[3 * i + k];
                }
            }
            if let Some(p) = scene.force.domain.periodic_box() {
                let before = scene.x.clone();
                p.wrap_positions(&mut scene.x);
                wrapped += before.iter().zip(&scene.x).filter(|(a, b)| a != b).count();
            }
        }
        assert!(touching > steps / 2, "contacts in only {touching} of {steps} steps");
        assert_eq!(every_call.list_builds(), steps, "skin 0 searches at every call");
        (scene.force.list_builds(), wrapped)
    }

    /// Positions, velocities, radii, masses and inverse masses.
    type Gas = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

    /// `n` particles of radii in [r/2, r] at random in [lo, hi) (3D, or z = 0 in 2D), with
    /// `apart`: not overlapping (drawn again where one would overlap an earlier one; the
    /// minimum image in `domain`), with speeds up to `speed` (m/s) and masses in [0.5, 2] kg, the first one
    /// pinned.
    #[allow(clippy::too_many_arguments)]
    fn gas(rng: &mut Rng, n: usize, r: f64, lo: [f64; 3], hi: [f64; 3], domain: &Domain, apart: bool, speed: f64) -> Gas {
        let dim = domain.dim();
        let radius = rng.vec(n, 0.5 * r, r);
        let (mut x, mut v): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
        for i in 0..n {
            let p = loop {
                let p = [0, 1, 2].map(|k| if k < dim { rng.uniform(lo[k], hi[k]) } else { 0.0 });
                let clear = !apart
                    || (0..i).all(|j| {
                        let d = domain.displacement(p, [x[3 * j], x[3 * j + 1], x[3 * j + 2]]);
                        d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= (radius[i] + radius[j]).powi(2)
                    });
                if clear {
                    break p;
                }
            };
            x.extend(p);
            v.extend([0, 1, 2].map(|k| if k < dim { rng.uniform(-speed, speed) } else { 0.0 }));
        }
        let mass = rng.vec(n, 0.5, 2.0);
        let mut inv_mass: Vec<f64> = mass.iter().map(|m| 1.0 / m).collect();
        inv_mass[0] = 0.0;
        (x, v, radius, mass, inv_mass)
    }

    #[test]
    fn a_periodic_gas_crossing_its_cell_gets_the_forces_of_a_search_at_every_call() {
        // A gas in a periodic unit cube (all three axes), r ≤ 4 cm: at up to 1 m/s and
        // dt = 0.25 ms a particle moves up to 0.25 mm a step against a skin of 0.2 mean radii
        // (6 mm), so the list lasts several steps; particles leave through the sides and are
        // wrapped back (their displacements taken as minimum images). Particles 1 and 2
        // are shot across the cell at 40 and 60 m/s for 20 steps (1–1.5 cm a step: a
        // rebuild at every one of those steps).
        let mut rng = Rng::new(7);
        let (lo, hi) = ([0.0; 3], [1.0; 3]);
        let cell = Periodic::new(lo, hi, [true; 3]).unwrap();
        let domain = Domain::periodic(3, cell).unwrap();
        let (x, v, radius, mass, inv_mass) = gas(&mut rng, 400, 0.04, lo, hi, &domain, true, 1.0);
        let walls = vec![Collider::Box(BoxContainer::new(lo, hi, Surface::default()).unwrap())];
        let material = Material::new(0.5, 0.0).unwrap();
        let force = ContactForce::new(1e4, None, material, None, radius, inv_mass, walls, domain);
        let scene = Scene {
            force,
            x,
            v,
            mass,
            g: [0.0; 3],
        };
        let kicks = [
            (100, 1, [40.0, 10.0, -5.0]),
            (100, 2, [-60.0, 0.0, 30.0]),
            (120, 1, [0.0; 3]),
            (120, 2, [0.0; 3]),
        ];
        let (builds, wrapped) = run(scene, 300, 2.5e-4, &kicks);
        eprintln!("periodic gas: {builds} builds in 300 steps, {wrapped} crossings");
        assert!(
            builds >= 20,
            "the fast particles force a rebuild at every step: {builds} builds"
        );
        assert!(builds < 120, "the list is reused: {builds} builds in 300 steps");
        assert!(wrapped > 10, "{wrapped} crossings of the cell's sides");
    }

    #[test]
    fn a_pile_on_colliders_with_own_materials_gets_the_forces_of_a_search_at_every_call() {
        // Open space, a box open at the top, a tilted plane and a sphere obstacle, gravity:
        // particles fall onto the floor and the obstacle and push each other apart. Particles have
        // their own restitutions (0, 1 and equal values included), colliders their own or
        // none, so ζ comes from every branch of the pair rule. One particle is dropped in at
        // 30 m/s (a rebuild at each step until it stops).
        let mut rng = Rng::new(11);
        let (lo, hi) = ([0.0; 3], [0.6, 0.6, f64::INFINITY]);
        let (x, v, radius, mass, inv_mass) = gas(
            &mut rng,
            300,
            0.05,
            [0.0; 3],
            [0.6, 0.6, 0.8],
            &Domain::open(3).unwrap(),
            true,
            0.3,
        );
        let own: Vec<Material> = (0..300)
            .map(|i| {
                let e = match i % 5 {
                    0 => 0.0,
                    1 => 1.0,
                    2 => 0.5,
                    _ => rng.uniform(0.0, 1.0),
                };
                Material::new(e, 0.0).unwrap()
            })
            .collect();
        let colliders = vec![
            Collider::Box(BoxContainer::new(lo, hi, Surface::new(None, None).unwrap()).unwrap()),
            Collider::Plane(Plane::new([0.0, 0.0, 0.1], [1.0, 0.0, 3.0], Surface::new(Some(0.3), None).unwrap()).unwrap()),
            Collider::Sphere(SphereObstacle::new([0.3, 0.3, 0.3], 0.1, Surface::new(Some(0.9), None).unwrap()).unwrap()),
        ];
        let material = Material::new(0.4, 0.0).unwrap();
        let force = ContactForce::new(
            5e3,
            None,
            material,
            Some(own),
            radius,
            inv_mass,
            colliders,
            Domain::open(3).unwrap(),
        );
        let scene = Scene {
            force,
            x,
            v,
            mass,
            g: [0.0, 0.0, -9.81],
        };
        let (builds, _) = run(scene, 600, 2e-4, &[(50, 5, [0.0, 0.0, -30.0])]);
        eprintln!("pile: {builds} builds in 600 steps");
        assert!(builds < 200, "the list is reused: {builds} builds in 600 steps");
    }

    #[test]
    fn a_2d_strip_periodic_along_x_with_a_given_damping() {
        // Circles in the xy-plane, periodic along x only, the rectangle's walls along y
        // kept (those along x vanish), γ_n given instead of e. Particle 9 runs at 80 m/s
        // (2 cm a step) for 140 steps, through the gas and the cell's sides.
        let mut rng = Rng::new(3);
        let (lo, hi) = ([-1.0, 0.0, 0.0], [1.0, 0.5, 0.0]);
        let cell = Periodic::new(
            [-1.0, 0.0, f64::NEG_INFINITY],
            [1.0, 0.5, f64::INFINITY],
            [true, false, false],
        )
        .unwrap();
        let domain = Domain::periodic(2, cell).unwrap();
        let (x, v, radius, mass, inv_mass) = gas(&mut rng, 200, 0.03, lo, hi, &domain, true, 0.5);
        let rect = BoxContainer::rect([-1.0, 0.0], [1.0, 0.5], Surface::default()).unwrap();
        let material = Material::new(0.7, 0.0).unwrap();
        let force = ContactForce::new(
            1e4,
            Some(30.0),
            material,
            None,
            radius,
            inv_mass,
            vec![Collider::Box(rect)],
            domain,
        );
        let scene = Scene {
            force,
            x,
            v,
            mass,
            g: [0.0, -2.0, 0.0],
        };
        let (builds, wrapped) = run(scene, 400, 2.5e-4, &[(10, 9, [80.0, 5.0, 0.0]), (150, 9, [1.0, 0.0, 0.0])]);
        eprintln!("2D strip: {builds} builds in 400 steps, {wrapped} crossings");
        assert!(wrapped > 3, "{wrapped} crossings of the cell's sides");
        assert!((140..260).contains(&builds), "{builds} builds in 400 steps");
    }

    #[test]
    fn a_head_on_pair_just_outside_the_list_is_caught_before_it_touches() {
        // The worst case of the criterion: two particles (r = 0.1 m, skin s = 0.02 m) start
        // s (1 + 10⁻³) beyond contact, so out of the list, and close head-on at 1 mm each a
        // step. They touch at the 11th step; the two largest moves reach s at the 10th, when
        // the list is rebuilt with them in it. A criterion 30 % looser would miss the touch.
        let x = vec![0.0, 0.0, 0.0, 0.2 + 0.02 * 1.001, 0.0, 0.0, 5.0, 5.0, 5.0];
        let v = vec![1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let force = ContactForce::new(
            10.0,
            None,
            Material::new(0.5, 0.0).unwrap(),
            None,
            vec![0.1; 3],
            vec![1.0; 3],
            vec![],
            Domain::open(3).unwrap(),
        )
        .with_skin(0.02);
        let scene = Scene {
            force,
            x,
            v,
            mass: vec![1.0; 3],
            g: [0.0; 3],
        };
        let (builds, _) = run(scene, 40, 1e-3, &[]);
        assert_eq!(builds, 4, "built at steps 0, 10, 20, 30");
    }

    #[test]
    fn the_energy_is_that_of_the_positions_asked_about() {
        // U at x after a force evaluation there is the reference's; at other positions (a
        // particle of an overlapping pair a micrometre away) it is found again, not the last
        // evaluation's.
        let mut rng = Rng::new(5);
        let (x, v, radius, mass, inv_mass) = gas(&mut rng, 200, 0.06, [0.0; 3], [0.5; 3], &Domain::open(3).unwrap(), false, 1.0);
        let mut force = ContactForce::new(
            1e3,
            None,
            Material::new(0.5, 0.0).unwrap(),
            None,
            radius,
            inv_mass,
            vec![],
            Domain::open(3).unwrap(),
        );
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &mass,
        };
        let mut f = vec![0.0; x.len()];
        force.accumulate(&s, &mut f).unwrap();
        let u = force.potential_energy(&s).unwrap();
        assert!(u > 0.0);
        assert_eq!(u.to_bits(), reference(&force, &s).1.to_bits());
        // a particle of an overlapping pair a micrometre away: found again
        let mut pairs = Vec::new();
        all_pairs(&x, &force.radius, &force.domain, 0.0, &mut pairs).unwrap();
        let (i, _) = pairs[0];
        let mut x2 = x.clone();
        x2[3 * i] += 1e-6;
        let s2 = State { x: &x2, ..s };
        let u2 = force.potential_energy(&s2).unwrap();
        assert_eq!(u2.to_bits(), reference(&force, &s2).1.to_bits());
        assert_ne!(u2.to_bits(), u.to_bits(), "a moved overlap changes U");
        // At NaN positions no force exists: NaN forces (the world then stops the step with
        // SimulationDiverged), and no U
        let mut bad = x.clone();
        bad[4] = f64::NAN;
        let s3 = State { x: &bad, ..s };
        assert!(force.accumulate(&s3, &mut f).is_ok());
        assert!(f.iter().all(|c| c.is_nan()));
        assert_eq!(force.potential_energy(&s3), None);
        // and the rates at s are those of its contacts
        assert!(force.rates(&s, &force.inv_mass.clone()).unwrap().omega_squared > 0.0);
    }

    #[test]
    fn the_allowance_leaves_a_rounding_margin_below_the_skin() {
        // Coordinates 10¹² times the skin leave no room: the list is rebuilt at every call.
        let radius = vec![1e-3; 2];
        let domain = Domain::open(3).unwrap();
        let (mut list, mut grid) = (NeighbourList::default(), Grid::new());
        let x = [0.0, 0.0, 0.0, 1.5e-3, 0.0, 0.0];
        list.update(&mut grid, &x, &radius, &[], &domain, 2e-4, 0.0).unwrap();
        assert!(list.allowance < 2e-4 && list.allowance > 2e-4 * (1.0 - 1e-10));
        assert_eq!(
            (list.rows[0].of(0), list.rows[0].of(1)),
            (&[1][..], &[0][..]),
            "listed from both sides"
        );
        list.update(&mut grid, &x, &radius, &[], &domain, 2e-4, 0.0).unwrap();
        assert_eq!(list.builds, 1, "nothing moved");
        let far = [1e9, 0.0, 0.0, 1e9 + 1.5e-3, 0.0, 0.0];
        list.update(&mut grid, &far, &radius, &[], &domain, 2e-4, 0.0).unwrap();
        assert!(list.allowance < 0.0);
        list.update(&mut grid, &far, &radius, &[], &domain, 2e-4, 0.0).unwrap();
        assert_eq!(list.builds, 3);
        // two particles that together moved the allowance (exactly: half each, along
        // coordinates that were 0): rebuilt; a hair less: kept
        list.update(&mut grid, &x, &radius, &[], &domain, 2e-4, 0.0).unwrap();
        let half = 0.5 * list.allowance;
        assert!(!list.holds(&[-half, 0.0, 0.0, 1.5e-3, half, 0.0], &domain));
        let less = 0.99 * half;
        assert!(list.holds(&[-less, 0.0, 0.0, 1.5e-3, half, 0.0], &domain));
        assert!(!list.holds(&[f64::NAN, 0.0, 0.0, 1.5e-3, 0.0, 0.0], &domain));
    }
}
