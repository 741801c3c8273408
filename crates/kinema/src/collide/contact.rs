//! Contact: what the narrow phase and the colliders hand to the response — one touching pair.

/// What particle `i` of a [`Contact`] touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Partner {
    /// Another particle, by index (for particle pairs from the narrow phase, always > `i`).
    Particle(usize),
    /// A static collider, by its index in the caller's collider list.
    Collider(usize),
}

/// One contact between particle `i` and its partner, as seen at the positions and velocities
/// it was computed from.
///
/// The normal points from the partner towards particle `i`, so that an impulse `+j n` on `i`
/// (and `−j n` on a particle partner) pushes the two apart for j > 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// The particle, by index.
    pub i: usize,
    /// What it touches.
    pub other: Partner,
    /// Unit normal n, from the partner towards particle `i`.
    pub normal: [f64; 3],
    /// Penetration depth δ, m: > 0 when the two overlap (for two spheres δ = r_i + r_j − |x_i − x_j|),
    /// < 0 for a gap that is still within the contact tolerance that found it.
    pub overlap: f64,
    /// Relative normal velocity u_n = (v_i − v_j)·n, m/s (v_j the partner particle's
    /// velocity, or a collider's surface velocity at the contact): < 0 while they approach,
    /// > 0 while they separate.
    pub u_n: f64,
    /// A collider partner's surface velocity at the contact point, m/s (0 for a still
    /// collider and for a particle partner).
    pub wall_velocity: [f64; 3],
}

/// A contact's figures, for output (`World::contact_report`): the contact, its point,
/// and the force on particle i split along and across n (the force models' at the state;
/// the impulse model's step impulse over dt, its mean force), and whether it slides.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactReport {
    /// The contact as detected (at the step's end).
    pub contact: Contact,
    /// The contact point, m: on the line of centres, where the two surfaces' overlap is
    /// split in the ratio of the radii (ρ_i = d r_i/(r_i + r_j) from i); on a collider's
    /// surface.
    pub point: [f64; 3],
    /// The normal force on i, N (along n; −it on a partner particle).
    pub force_n: [f64; 3],
    /// The tangential (friction) force on i, N (⊥ n).
    pub force_t: [f64; 3],
    /// With the impulse model, the step's impulse on i (N·s, normal then tangential part);
    /// zeros with the force models.
    pub impulse: [[f64; 3]; 2],
    /// Whether the contact slides: its tangential force at the Coulomb bound μ |F_n|.
    pub sliding: bool,
}

impl ContactReport {
    /// The contact point of `c` for particle i at `xi` (m) of radius `ri` and a partner
    /// particle of radius `rj` (`None`: a collider), m.
    pub fn point_of(c: &Contact, xi: [f64; 3], ri: f64, rj: Option<f64>) -> [f64; 3] {
        let arm = match rj {
            Some(rj) if ri + rj > 0.0 => (ri + rj - c.overlap) * ri / (ri + rj),
            Some(_) => 0.0,
            None => ri - c.overlap,
        };
        crate::vec3::sub(xi, crate::vec3::scale(arm, c.normal))
    }
}

impl Contact {
    /// The partner particle's index, or `None` for a collider.
    pub fn partner_particle(&self) -> Option<usize> {
        match self.other {
            Partner::Particle(j) => Some(j),
            Partner::Collider(_) => None,
        }
    }

    /// Whether the two approach (u_n < 0).
    pub fn is_approaching(&self) -> bool {
        self.u_n < 0.0
    }
}

/// Action and reaction, the one place a pair's impulse meets both sides: `+k_i p` onto
/// particle i's entry and `−k_j p` onto its partner j's (none for a collider) in `a`, a flat
/// array of 3 values per particle. With velocities and k the inverse masses (1/kg) it is an
/// impulse p (N·s) applied to a pair; with angular velocities and k the inverse inertias
/// times the lever arms, the turn it gives them (`collide/spin.rs`).
#[inline]
pub(crate) fn action_reaction(a: &mut [f64], i: usize, j: Option<usize>, (k_i, k_j): (f64, f64), p: [f64; 3]) {
    for d in 0..3 {
        a[3 * i + d] += k_i * p[d];
    }
    if let Some(j) = j {
        for d in 0..3 {
            a[3 * j + d] -= k_j * p[d];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partner_and_approach() {
        let c = Contact {
            i: 0,
            other: Partner::Particle(3),
            normal: [1.0, 0.0, 0.0],
            overlap: 0.1,
            u_n: -2.0,
            wall_velocity: [0.0; 3],
        };
        assert_eq!(c.partner_particle(), Some(3));
        assert!(c.is_approaching());
        let w = Contact {
            other: Partner::Collider(1),
            u_n: 0.0,
            ..c
        };
        assert_eq!(w.partner_particle(), None);
        assert!(!w.is_approaching());
    }
}
