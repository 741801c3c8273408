//! Stages 2–4 of a world step with the impulse model: detect collisions (continuously inside
//! the step, then as contacts at its end), respond by Newton's restitution law, distribute each
//! impulse onto both particles.

use crate::collide::{
    apply_impulse, collider_contacts, resolve, separate, sphere_contacts, toi_plane, toi_sphere_obstacle, toi_spheres, Collider,
    Contact, Domain, Grid, Material, MaterialTable, Pair, Partner, Periodic, Plane, ResolveParams, SeparateParams,
};
use crate::error::Error;

/// The contact model: how a collision changes the motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactModel {
    /// Newton's restitution law by impulses after integration (stages 2–4), the seed's model.
    Impulse,
    /// A spring–dashpot force while bodies overlap (the DEM way), integrated with the other
    /// forces in stage 1: F_n = k_n δ − m_eff γ_n u_n with γ_n from the requested e by the
    /// damped oscillator's closed form ([`crate::collide::PenaltyLaw`]), or given.
    SpringDashpot {
        /// Normal stiffness k_n, N/m (> 0).
        stiffness: f64,
        /// Damping rate γ_n, 1/s (≥ 0), instead of the one the restitution implies.
        damping: Option<f64>,
    },
}

/// How collisions between particles, and with colliders, are handled. Units SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CollisionParams {
    /// The contact model. Default [`ContactModel::Impulse`].
    pub model: ContactModel,
    /// Coefficient of restitution e ∈ [0, 1] of every particle without its own (1: elastic,
    /// 0: plastic). Default 1.
    pub restitution: f64,
    /// Coulomb friction coefficient μ ≥ 0 of every particle without its own. Default 0.
    pub friction: f64,
    /// Continuous detection: impacts are found at their time inside the step and resolved
    /// in time order, so nothing passes through a particle or a wall however fast. Default
    /// true.
    pub ccd: bool,
    /// Approach speeds below this use e = 0, m/s, so that resting contacts do not bounce in
    /// place. `None` (default): twice the largest speed change the forces gave a particle in
    /// the step (a body resting under gravity approaches at g·dt each step).
    pub restitution_threshold: Option<f64>,
}

impl Default for CollisionParams {
    fn default() -> Self {
        CollisionParams {
            model: ContactModel::Impulse,
            restitution: 1.0,
            friction: 0.0,
            ccd: true,
            restitution_threshold: None,
        }
    }
}

impl CollisionParams {
    /// Checks the values; the error names the parameter.
    pub fn check(&self) -> Result<Material, Error> {
        if let ContactModel::SpringDashpot { stiffness, damping } = self.model {
            if !(stiffness.is_finite() && stiffness > 0.0) {
                return Err(Error::invalid(
                    "stiffness",
                    stiffness,
                    "the contact stiffness must be finite and > 0 N/m",
                ));
            }
            if let Some(g) = damping {
                if !(g.is_finite() && g >= 0.0) {
                    return Err(Error::invalid(
                        "damping",
                        g,
                        "the contact damping rate must be finite and >= 0 1/s",
                    ));
                }
            }
        }
        if let Some(t) = self.restitution_threshold {
            if !(t.is_finite() && t >= 0.0) {
                return Err(Error::invalid(
                    "restitution_threshold",
                    t,
                    "the restitution threshold must be finite and >= 0 m/s (or None for automatic)",
                ));
            }
        }
        Material::new(self.restitution, self.friction)
    }
}

/// What the collision stages did, over one step or summed over many.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CollisionStats {
    /// Contacts at the end of the step (touching or overlapping pairs and particle–collider
    /// contacts).
    pub contacts: usize,
    /// Impacts found by continuous detection inside the step, each resolved at its time.
    pub impacts: usize,
    /// Impulses applied (impacts and end-of-step contacts).
    pub impulses: usize,
    /// Σ m Δv of all particles over the collision stages minus the impulses that colliders
    /// and pinned particles gave them, N·s: the sum of all impulses between movable
    /// particles, zero by action and reaction up to rounding.
    pub impulse_balance: [f64; 3],
    /// Kinetic energy removed by the collisions, J (≥ 0; 0 for e = 1 without friction).
    pub energy_lost: f64,
    /// The largest overlap left after the step, m.
    pub max_overlap: f64,
}

impl CollisionStats {
    /// Adds another step's figures (contacts: the latest).
    pub fn accumulate(&mut self, step: &CollisionStats) {
        self.contacts = step.contacts;
        self.impacts += step.impacts;
        self.impulses += step.impulses;
        for k in 0..3 {
            self.impulse_balance[k] += step.impulse_balance[k];
        }
        self.energy_lost += step.energy_lost;
        self.max_overlap = step.max_overlap;
    }
}

/// A time of impact inside the step: particle `i` meets `partner` at time `time` (s from the
/// start of the step); `wall` picks the wall of a box. `versions` are the two particles'
/// path versions when it was computed: a later impact of either makes it stale.
#[derive(Debug, Clone, Copy)]
struct Event {
    time: f64,
    i: usize,
    partner: Partner,
    wall: usize,
    versions: (u32, u32),
}

/// The collision stages of a world, with their settings, colliders and buffers.
#[derive(Debug, Clone)]
pub(crate) struct CollisionStage {
    pub params: CollisionParams,
    material: Material,
    /// Per-particle restitution and friction where set (`None`: the global value); empty
    /// until some particle gets its own (32 B per particle otherwise spent on nothing).
    pub own: Vec<(Option<f64>, Option<f64>)>,
    /// The materials of all particles, built from `own` and the global value when some
    /// particle has its own.
    particle_materials: Option<Vec<Material>>,
    pub colliders: Vec<Collider>,
    pub domain: Domain,
    grid: Grid,
    pairs: Vec<Pair>,
    contacts: Vec<Contact>,
    /// The end-of-step contacts as detected (overlap and u_n before the response).
    pub detected: Vec<Contact>,
    /// Scratch: collider contacts, and the velocities before the stage (for the impulse balance).
    walls: Vec<Contact>,
    v_before: Vec<f64>,
    // Continuous detection: each particle moves on x(τ) = x_ref + v_ref (τ − t_ref) + ½ a (τ − t_ref)²
    accel: Vec<f64>,
    t_ref: Vec<f64>,
    x_ref: Vec<f64>,
    v_ref: Vec<f64>,
    version: Vec<u32>,
    events: Vec<Event>,
    /// Candidate pairs of each particle (indices into `pairs`), CSR.
    adjacency_start: Vec<usize>,
    adjacency: Vec<usize>,
    pub total: CollisionStats,
    pub last: CollisionStats,
}

/// Whether contact `c` is with a wall of a box collider along a periodic axis of `domain`:
/// such walls do not exist (a particle leaving one side comes back on the other). Box walls
/// have axis-aligned normals.
pub(crate) fn on_periodic_wall(c: &Contact, colliders: &[Collider], domain: &Domain) -> bool {
    let in_box = matches!(c.other, Partner::Collider(k) if matches!(colliders[k], Collider::Box(_)));
    in_box
        && domain
            .periodic_box()
            .is_some_and(|p| (0..3).any(|k| p.axes()[k] && c.normal[k] != 0.0))
}

fn get(a: &[f64], i: usize) -> [f64; 3] {
    [a[3 * i], a[3 * i + 1], a[3 * i + 2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

impl CollisionStage {
    pub fn new(params: CollisionParams, dim: usize) -> Result<Self, Error> {
        let material = params.check()?;
        Ok(CollisionStage {
            params,
            material,
            own: Vec::new(),
            particle_materials: None,
            colliders: Vec::new(),
            domain: Domain::open(dim)?,
            grid: Grid::new(),
            pairs: Vec::new(),
            contacts: Vec::new(),
            detected: Vec::new(),
            walls: Vec::new(),
            v_before: Vec::new(),
            accel: Vec::new(),
            t_ref: Vec::new(),
            x_ref: Vec::new(),
            v_ref: Vec::new(),
            version: Vec::new(),
            events: Vec::new(),
            adjacency_start: Vec::new(),
            adjacency: Vec::new(),
            total: CollisionStats::default(),
            last: CollisionStats::default(),
        })
    }

    /// Changes the settings, keeping colliders and buffers.
    pub fn set_params(&mut self, params: CollisionParams) -> Result<(), Error> {
        self.material = params.check()?;
        self.params = params;
        self.refresh_materials()
    }

    /// Forgets the last step's contacts and figures (a step of the spring–dashpot model).
    pub fn clear_step(&mut self) {
        self.detected.clear();
        self.last = CollisionStats::default();
    }

    /// The global material and the per-particle ones (if any particle has its own).
    pub fn materials_parts(&self) -> (Material, Option<Vec<Material>>) {
        (self.material, self.particle_materials.clone())
    }

    /// Rebuilds the per-particle materials from `own` and the global value.
    pub fn refresh_materials(&mut self) -> Result<(), Error> {
        if self.own.iter().all(|(e, m)| e.is_none() && m.is_none()) {
            self.particle_materials = None;
            return Ok(());
        }
        let global = self.material;
        self.particle_materials = Some(
            self.own
                .iter()
                .map(|(e, m)| Material::new(e.unwrap_or(global.restitution()), m.unwrap_or(global.friction())))
                .collect::<Result<_, _>>()?,
        );
        Ok(())
    }

    /// Makes the axes `axes` periodic with the cell [lo, hi) (m); the walls of a box
    /// collider along those axes are removed (particles leaving one side come back on the
    /// other). `None` makes space open again.
    pub fn set_periodic(&mut self, periodic: Option<Periodic>) -> Result<(), Error> {
        let dim = self.domain.dim();
        self.domain = match periodic {
            Some(p) => Domain::periodic(dim, p)?,
            None => Domain::open(dim)?,
        };
        Ok(())
    }

    fn materials(&self) -> MaterialTable<'_> {
        let table = MaterialTable::uniform(self.material).with_colliders(&self.colliders);
        match &self.particle_materials {
            Some(m) => table.with_particles(m),
            None => table,
        }
    }

    /// The walls of collider `k` that are active: a box's walls along periodic axes are not.
    fn wall_active(&self, plane: &Plane) -> bool {
        match self.domain.periodic_box() {
            Some(p) => {
                let n = plane.normal();
                !(0..3).any(|k| p.axes()[k] && n[k] != 0.0)
            }
            None => true,
        }
    }

    /// Stages 2–4 on the step from (x0, v0) to the integrated (x1, v1), over `h` s: impacts
    /// inside the step in time order (with `ccd`), then the contacts at the end: Newton's
    /// restitution by sequential impulses and the removal of overlap. (x1, v1) are updated
    /// in place; returns whether anything changed.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &mut self,
        x0: &[f64],
        v0: &[f64],
        x1: &mut [f64],
        v1: &mut [f64],
        radius: &[f64],
        inv_mass: &[f64],
        mass: &[f64],
        h: f64,
    ) -> Result<bool, Error> {
        let n = radius.len();
        let mut stats = CollisionStats::default();
        // Automatic threshold: twice the largest speed change the forces made in this step.
        let threshold = self.params.restitution_threshold.unwrap_or_else(|| {
            let dv = (0..n)
                .map(|i| {
                    norm([
                        v1[3 * i] - v0[3 * i],
                        v1[3 * i + 1] - v0[3 * i + 1],
                        v1[3 * i + 2] - v0[3 * i + 2],
                    ])
                })
                .fold(0.0, f64::max);
            2.0 * dv
        });
        self.v_before.clear();
        self.v_before.extend_from_slice(v1);
        let mut external = [0.0; 3];
        let mut changed = false;

        if self.params.ccd {
            changed |= self.sweep(x0, v0, x1, v1, radius, inv_mass, h, threshold, &mut stats, &mut external)?;
        }

        // Stage 2 at the end of the step: pairs (broad phase) → contacts (narrow phase), then
        // the colliders.
        self.grid.find_pairs(x1, radius, &self.domain, 0.0, &mut self.pairs)?;
        sphere_contacts(x1, v1, radius, &self.pairs, &self.domain, 0.0, &mut self.contacts)?;
        self.walls.clear();
        collider_contacts(&self.colliders, x1, v1, radius, 0.0, &mut self.walls)?;
        // Box walls along periodic axes do not exist (their normals are along the axes).
        let (colliders, domain) = (&self.colliders, &self.domain);
        self.contacts
            .extend(self.walls.iter().filter(|c| !on_periodic_wall(c, colliders, domain)));
        stats.contacts = self.contacts.len();

        // Stages 3–4: the impulse j = −(1 + e) u_n / (1/m_i + 1/m_j) of each approaching contact,
        // +j n / m_i on i and −j n / m_j on j, by sequential impulses.
        let resolve_params = ResolveParams {
            restitution_threshold: threshold,
            ..ResolveParams::default()
        };
        let r = resolve(&self.contacts, v1, inv_mass, &self.materials(), &resolve_params)?;
        stats.impulses += r.impulses;
        stats.energy_lost += r.kinetic_energy_lost;
        for (k, e) in external.iter_mut().enumerate() {
            *e += r.collider_impulse_sum[k] + r.pinned_impulse_sum[k];
        }
        if r.impulses > 0 {
            changed = true;
        }
        // Overlap left by discrete detection is removed by moving positions, not velocities.
        self.detected.clone_from(&self.contacts);
        let s = separate(&mut self.contacts, x1, inv_mass, &SeparateParams::default())?;
        stats.max_overlap = s.max_overlap_after;
        if s.max_overlap_before > 0.0 {
            changed = true;
        }
        if let Some(p) = self.domain.periodic_box() {
            p.wrap_positions(x1);
        }

        // The impulse balance: Σ m Δv minus what colliders and pinned particles gave.
        for i in 0..n {
            if inv_mass[i] > 0.0 {
                for k in 0..3 {
                    stats.impulse_balance[k] += mass[i] * (v1[3 * i + k] - self.v_before[3 * i + k]);
                }
            }
        }
        for (b, e) in stats.impulse_balance.iter_mut().zip(external) {
            *b -= e;
        }
        self.last = stats;
        self.total.accumulate(&stats);
        Ok(changed)
    }

    /// Continuous detection: finds the impacts inside the step in time order and resolves
    /// each at its time. Returns whether any impulse was applied.
    ///
    /// Each particle moves on the parabola with the constant acceleration that takes it from
    /// (x0, v0) to the integrated x1 in h: a = 2 (x1 − x0 − v0 h) / h², exact for uniform
    /// fields such as gravity (and then the relative motion of two particles is a straight
    /// line). At an impact at τ the two particles' velocities there, v(τ) = v_ref + a (τ −
    /// t_ref), get the restitution impulse and each continues on a new parabola from τ. At
    /// the end a particle that was hit is at its parabola's point at h, with velocity
    /// v(h) + (v1 − (v0 + a h)) (the integrator's velocity beyond the parabola's is kept).
    #[allow(clippy::too_many_arguments)]
    fn sweep(
        &mut self,
        x0: &[f64],
        v0: &[f64],
        x1: &mut [f64],
        v1: &mut [f64],
        radius: &[f64],
        inv_mass: &[f64],
        h: f64,
        threshold: f64,
        stats: &mut CollisionStats,
        external: &mut [f64; 3],
    ) -> Result<bool, Error> {
        let n = radius.len();
        self.accel.clear();
        self.accel
            .extend((0..3 * n).map(|c| 2.0 * (x1[c] - x0[c] - v0[c] * h) / (h * h)));
        self.t_ref.clear();
        self.t_ref.resize(n, 0.0);
        self.x_ref.clear();
        self.x_ref.extend_from_slice(x0);
        self.v_ref.clear();
        self.v_ref.extend_from_slice(v0);
        self.version.clear();
        self.version.resize(n, 0);

        // Candidates: pairs that can close their gap within the step. Two parabolas come at
        // most (|v_i| + |v_j|) h + ½ (|a_i| + |a_j|) h² closer.
        let reach = (0..n)
            .map(|i| norm(get(v0, i)) * h + 0.5 * norm(get(&self.accel, i)) * h * h)
            .fold(0.0, f64::max);
        self.grid.find_pairs(x0, radius, &self.domain, 2.0 * reach, &mut self.pairs)?;
        self.adjacency_start.clear();
        self.adjacency_start.resize(n + 1, 0);
        for &(i, j) in &self.pairs {
            self.adjacency_start[i + 1] += 1;
            self.adjacency_start[j + 1] += 1;
        }
        for i in 0..n {
            self.adjacency_start[i + 1] += self.adjacency_start[i];
        }
        self.adjacency.clear();
        self.adjacency.resize(2 * self.pairs.len(), 0);
        let mut fill = self.adjacency_start.clone();
        for (p, &(i, j)) in self.pairs.iter().enumerate() {
            for q in [i, j] {
                self.adjacency[fill[q]] = p;
                fill[q] += 1;
            }
        }

        self.events.clear();
        for p in 0..self.pairs.len() {
            let (i, j) = self.pairs[p];
            if let Some(e) = self.pair_event(i, j, radius, h, 0.0) {
                self.events.push(e);
            }
        }
        for i in 0..n {
            self.collider_events(i, radius, h, 0.0);
        }

        // Impacts in time order. Each one changes two paths at most; the events of those
        // particles are recomputed and older ones become stale. A cap keeps a pathological
        // case (a particle wedged between two others) from looping: what is left is resolved
        // at the end of the step.
        let cap = 100 * (n + self.pairs.len()) + 1000;
        let mut processed = 0;
        let mut any = false;
        while processed < cap {
            let Some((k, event)) = self
                .events
                .iter()
                .enumerate()
                .filter(|(_, e)| self.is_current(e))
                .min_by(|a, b| a.1.time.total_cmp(&b.1.time).then(a.1.i.cmp(&b.1.i)))
                .map(|(k, e)| (k, *e))
            else {
                break;
            };
            self.events.swap_remove(k);
            processed += 1;
            if self.events.len() > 64 * (n + self.pairs.len()) {
                let version = &self.version;
                self.events.retain(|e| {
                    let vj = match e.partner {
                        Partner::Particle(j) => version[j],
                        Partner::Collider(_) => 0,
                    };
                    (version[e.i], vj) == e.versions
                });
            }
            let t = event.time;
            // Move the particles involved to the impact.
            let mut movers = vec![event.i];
            if let Partner::Particle(j) = event.partner {
                movers.push(j);
            }
            for &q in &movers {
                self.advance(q, t);
            }
            let Some(contact) = self.contact_at(&event) else { continue };
            // Touching pairs that approach slower than the resolve tolerance (rounding after an
            // earlier impulse) are not impacts; the end-of-step stage sees them if they close.
            let vi = get(&self.v_ref, event.i);
            let vj = contact.partner_particle().map_or([0.0; 3], |j| get(&self.v_ref, j));
            let u_n = dot([vi[0] - vj[0], vi[1] - vj[1], vi[2] - vj[2]], contact.normal);
            if u_n >= -ResolveParams::default().tolerance {
                continue;
            }
            let material = self.materials().pair(&contact);
            let Some(impulse) = apply_impulse(&contact, &mut self.v_ref, inv_mass, material, threshold) else {
                continue;
            };
            any = true;
            stats.impacts += 1;
            stats.impulses += 1;
            stats.energy_lost += impulse.energy_lost;
            let external_partner = match event.partner {
                Partner::Collider(_) => true,
                Partner::Particle(j) => inv_mass[j] == 0.0,
            };
            // What the movable side got from a collider or a pinned particle is external.
            let sign = match event.partner {
                _ if external_partner && inv_mass[event.i] > 0.0 => 1.0,
                Partner::Particle(j) if inv_mass[event.i] == 0.0 && inv_mass[j] > 0.0 => -1.0,
                _ => 0.0,
            };
            for (e, j) in external.iter_mut().zip(impulse.vector) {
                *e += sign * j;
            }
            for &q in &movers {
                self.version[q] += 1;
            }
            for &q in &movers {
                for a in self.adjacency_start[q]..self.adjacency_start[q + 1] {
                    let (i, j) = self.pairs[self.adjacency[a]];
                    if let Some(e) = self.pair_event(i, j, radius, h, t) {
                        self.events.push(e);
                    }
                }
                self.collider_events(q, radius, h, t);
            }
        }

        // The particles that were hit end on their last parabola.
        for i in 0..n {
            if self.version[i] == 0 {
                continue;
            }
            let dt = h - self.t_ref[i];
            for k in 0..3 {
                let c = 3 * i + k;
                let drift = v1[c] - (v0[c] + self.accel[c] * h);
                x1[c] = self.x_ref[c] + self.v_ref[c] * dt + 0.5 * self.accel[c] * dt * dt;
                v1[c] = self.v_ref[c] + self.accel[c] * dt + drift;
            }
        }
        Ok(any)
    }

    fn is_current(&self, e: &Event) -> bool {
        let vj = match e.partner {
            Partner::Particle(j) => self.version[j],
            Partner::Collider(_) => 0,
        };
        (self.version[e.i], vj) == e.versions
    }

    /// Moves particle q along its parabola to time t and makes that its reference.
    fn advance(&mut self, q: usize, t: f64) {
        let dt = t - self.t_ref[q];
        for k in 0..3 {
            let c = 3 * q + k;
            self.x_ref[c] += self.v_ref[c] * dt + 0.5 * self.accel[c] * dt * dt;
            self.v_ref[c] += self.accel[c] * dt;
        }
        self.t_ref[q] = t;
    }

    /// Position and velocity of particle q at time t on its current parabola.
    fn state_at(&self, q: usize, t: f64) -> ([f64; 3], [f64; 3]) {
        let dt = t - self.t_ref[q];
        let mut x = [0.0; 3];
        let mut v = [0.0; 3];
        for k in 0..3 {
            let c = 3 * q + k;
            x[k] = self.x_ref[c] + self.v_ref[c] * dt + 0.5 * self.accel[c] * dt * dt;
            v[k] = self.v_ref[c] + self.accel[c] * dt;
        }
        (x, v)
    }

    /// The first impact of particles i and j after time `now` within the step.
    ///
    /// Their separation d(τ) = d₀ + u τ + ½ Δa τ² is a straight line when Δa = 0 (uniform
    /// fields), and [`toi_spheres`] solves |d| = r_i + r_j exactly. Otherwise the chord of
    /// the remaining step (u + ½ Δa (h − now)) gives a first root, refined by Newton's method
    /// on |d(τ)|² − R².
    fn pair_event(&self, i: usize, j: usize, radius: &[f64], h: f64, now: f64) -> Option<Event> {
        let (xi, vi) = self.state_at(i, now);
        let (xj, vj) = self.state_at(j, now);
        let d0 = self.domain.displacement(xi, xj);
        let u = [vi[0] - vj[0], vi[1] - vj[1], vi[2] - vj[2]];
        let da = [
            self.accel[3 * i] - self.accel[3 * j],
            self.accel[3 * i + 1] - self.accel[3 * j + 1],
            self.accel[3 * i + 2] - self.accel[3 * j + 2],
        ];
        let big_r = radius[i] + radius[j];
        let rest = h - now;
        let tau = if da == [0.0; 3] {
            toi_spheres(d0, u, big_r, rest)?
        } else {
            let chord = [
                u[0] + 0.5 * da[0] * rest,
                u[1] + 0.5 * da[1] * rest,
                u[2] + 0.5 * da[2] * rest,
            ];
            let mut tau = toi_spheres(d0, chord, big_r, rest)?;
            for _ in 0..8 {
                let d = [0, 1, 2].map(|k| d0[k] + u[k] * tau + 0.5 * da[k] * tau * tau);
                let dd = [0, 1, 2].map(|k| u[k] + da[k] * tau);
                let g = dot(d, d) - big_r * big_r;
                let dg = 2.0 * dot(d, dd);
                if dg == 0.0 {
                    break;
                }
                let next = (tau - g / dg).clamp(0.0, rest);
                if (next - tau).abs() <= 1e-15 * rest {
                    tau = next;
                    break;
                }
                tau = next;
            }
            tau
        };
        if tau == 0.0 {
            // Touching already (and approaching): a resting contact, or one that an impact of
            // this step just pressed together. It is left to the end-of-step stage, whose
            // sequential impulses settle whole stacks at once; as events at one instant they
            // would cascade through a pile one impulse at a time.
            return None;
        }
        Some(Event {
            time: now + tau,
            i,
            partner: Partner::Particle(j),
            wall: 0,
            versions: (self.version[i], self.version[j]),
        })
    }

    /// Pushes the first impact of particle i with each collider after `now`.
    fn collider_events(&mut self, i: usize, radius: &[f64], h: f64, now: f64) {
        let (x, v) = self.state_at(i, now);
        let a = get(&self.accel, i);
        let rest = h - now;
        let mut found = Vec::new();
        for (k, collider) in self.colliders.iter().enumerate() {
            match collider {
                Collider::Plane(p) => {
                    if let Some(t) = toi_plane(x, v, a, radius[i], p, rest) {
                        found.push((t, k, 0));
                    }
                }
                Collider::Box(b) => {
                    for (w, wall) in b.walls().iter().enumerate() {
                        if self.wall_active(wall) {
                            if let Some(t) = toi_plane(x, v, a, radius[i], wall, rest) {
                                found.push((t, k, w));
                            }
                        }
                    }
                }
                Collider::Sphere(s) => {
                    let chord = [v[0] + 0.5 * a[0] * rest, v[1] + 0.5 * a[1] * rest, v[2] + 0.5 * a[2] * rest];
                    if let Some(t) = toi_sphere_obstacle(x, chord, radius[i], s, rest) {
                        found.push((t, k, 0));
                    }
                }
            }
        }
        for (t, k, w) in found.into_iter().filter(|f| f.0 > 0.0) {
            // (t = 0: touching already, left to the end-of-step stage as for pairs)
            self.events.push(Event {
                time: now + t,
                i,
                partner: Partner::Collider(k),
                wall: w,
                versions: (self.version[i], 0),
            });
        }
    }

    /// The contact of an event at its time (the particles already moved there).
    fn contact_at(&self, e: &Event) -> Option<Contact> {
        let xi = get(&self.x_ref, e.i);
        let normal = match e.partner {
            Partner::Particle(j) => {
                let d = self.domain.displacement(xi, get(&self.x_ref, j));
                let len = norm(d);
                if len == 0.0 {
                    return None;
                }
                [d[0] / len, d[1] / len, d[2] / len]
            }
            Partner::Collider(k) => match &self.colliders[k] {
                Collider::Plane(p) => p.normal(),
                Collider::Box(b) => b.walls()[e.wall].normal(),
                Collider::Sphere(s) => {
                    let c = s.center();
                    let d = [xi[0] - c[0], xi[1] - c[1], xi[2] - c[2]];
                    let len = norm(d);
                    if len == 0.0 {
                        return None;
                    }
                    [d[0] / len, d[1] / len, d[2] / len]
                }
            },
        };
        Some(Contact {
            i: e.i,
            other: e.partner,
            normal,
            overlap: 0.0,
            u_n: 0.0,
        })
    }
}
