//! A contact's row of the soft step: its masses, friction, normal and spin arms, and the
//! visit that updates its impulses and its particles' velocities (the solve's innermost
//! step, inlined into each pass).

use super::Target;
use crate::collide::contact::Contact;
use crate::collide::shock::Held;
use crate::collide::spin::Rotation;
use crate::vec3;

/// A contact's rolling resistance (module doc): the inverse inertias k_i, k_j (1/(kg·m²)),
/// the angular effective mass 1/(k_i + k_j) (kg·m²), the cap μ_r R* (m; the angular
/// impulse's bound per unit normal impulse) and R* (m). Without: all 0.
#[derive(Clone, Copy, Default)]
struct Roll {
    k: [f64; 2],
    mass: f64,
    cap: f64,
    r_star: f64,
}

/// A contact of [`soft_step`]: its inverse masses w (1/kg), effective mass 1/(w_i + w_j)
/// (kg) along n and 1/w_t across (the same without spin), friction μ, normal n, whether its
/// partner is a particle, and with spin `turn` = [ρ_i, ρ_j, k_i ρ_i, k_j ρ_j] (m, m and
/// 1/(kg·m); `collide/spin.rs`) and its rolling resistance.
#[derive(Clone, Copy)]
pub(super) struct Row {
    wi: f64,
    wj: f64,
    mass: f64,
    mass_t: f64,
    turn: [f64; 4],
    roll: Roll,
    mu: f64,
    pub(super) n: [f64; 3],
    has_j: bool,
}

impl Row {
    /// The row of contact `c` with its targets, among particles of these inverse masses
    /// (1/kg), with spin `rotation`, rolling resistance μ_r `rolling` and friction μ `mu`.
    #[inline]
    pub(super) fn new(
        c: &Contact,
        target: &Target,
        inv_mass: &[f64],
        rotation: Option<Rotation<'_>>,
        rolling: f64,
        mu: f64,
    ) -> Row {
        let (wi, wj) = (inv_mass[c.i], c.partner_particle().map_or(0.0, |j| inv_mass[j]));
        let w = wi + wj;
        let mass = if w > 0.0 { 1.0 / w } else { 0.0 };
        // with spin: the arms, the turn per unit of n × p, and the tangential mass
        let (turn, mass_t, roll) = match rotation {
            Some(r) => {
                let ((rho_i, rho_j), (ki, kj)) = (r.arms(c, target.rest), r.inverse_inertias(c));
                let w_t = w + ki * rho_i * rho_i + kj * rho_j * rho_j;
                let ri = r.radius[c.i];
                let r_star = c.partner_particle().map_or(ri, |j| ri * r.radius[j] / (ri + r.radius[j]));
                let roll = Roll {
                    k: [ki, kj],
                    mass: if ki + kj > 0.0 { 1.0 / (ki + kj) } else { 0.0 },
                    cap: rolling * r_star,
                    r_star,
                };
                (
                    [rho_i, rho_j, ki * rho_i, kj * rho_j],
                    if w_t > 0.0 { 1.0 / w_t } else { 0.0 },
                    roll,
                )
            }
            None => ([0.0; 4], mass, Roll::default()),
        };
        Row {
            wi,
            wj,
            mass,
            mass_t,
            turn,
            roll,
            mu,
            n: c.normal,
            has_j: c.partner_particle().is_some(),
        }
    }

    /// The row with one side held still (`collide/shock.rs`): its inverse mass and inertia
    /// taken as 0, the effective masses those of the other side alone.
    #[inline]
    pub(super) fn held(&self, held: Held) -> Row {
        let mut r = *self;
        match held {
            Held::Neither => return r,
            Held::I => (r.wi, r.turn[2], r.roll.k[0]) = (0.0, 0.0, 0.0),
            Held::J => (r.wj, r.turn[3], r.roll.k[1]) = (0.0, 0.0, 0.0),
        }
        let inverse = |w: f64| if w > 0.0 { 1.0 / w } else { 0.0 };
        let w = r.wi + r.wj;
        r.mass = inverse(w);
        r.mass_t = inverse(w + r.turn[2] * r.turn[0] + r.turn[3] * r.turn[1]);
        r.roll.mass = inverse(r.roll.k[0] + r.roll.k[1]);
        r
    }

    /// The velocity of i's contact point relative to j's: v_i − v_j, less
    /// (ρ_i ω_i + ρ_j ω_j) × n with spin (N = 6).
    #[inline(always)]
    pub(super) fn relative<const N: usize>(&self, vi: &[f64; N], vj: &[f64; N]) -> [f64; 3] {
        let u = [vi[0] - vj[0], vi[1] - vj[1], vi[2] - vj[2]];
        if N == 6 {
            let w = std::array::from_fn(|k| self.turn[0] * vi[3 + k] + self.turn[1] * vj[3 + k]);
            vec3::sub(u, vec3::cross(w, self.n))
        } else {
            u
        }
    }

    /// The impulse p on i and −p on j, at their contact points: v_i += w_i p, v_j −= w_j p,
    /// and with spin ω_i −= k_i ρ_i n × p, ω_j −= k_j ρ_j n × p.
    #[inline(always)]
    pub(super) fn apply<const N: usize>(&self, vi: &mut [f64; N], vj: &mut [f64; N], p: [f64; 3]) {
        for k in 0..3 {
            vi[k] += self.wi * p[k];
        }
        if self.has_j {
            for k in 0..3 {
                vj[k] -= self.wj * p[k];
            }
        }
        if N == 6 {
            let np = vec3::cross(self.n, p);
            for k in 0..3 {
                vi[3 + k] -= self.turn[2] * np[k];
            }
            if self.has_j {
                for k in 0..3 {
                    vj[3 + k] -= self.turn[3] * np[k];
                }
            }
        }
    }

    /// A tangential total clamped to the cone |t| ≤ μ λ.
    #[inline(always)]
    pub(super) fn clamp(&self, t: [f64; 3], lambda: f64) -> [f64; 3] {
        let (len, cap) = (vec3::norm(t), self.mu * lambda);
        if len > cap {
            vec3::scale(if len > 0.0 { cap / len } else { 0.0 }, t)
        } else {
            t
        }
    }

    /// One visit with the totals (λ, t): the normal total that brings u_n to at least `b_n`
    /// (clamped at 0), then, with `b_t`, the tangential total that brings the tangential
    /// velocity to `b_t` within the cone. Returns the largest change, as a velocity (m/s).
    #[inline(always)]
    pub(super) fn visit<const N: usize>(
        &self,
        vi: &mut [f64; N],
        vj: &mut [f64; N],
        (normal, tangent, roll): &mut (f64, [f64; 3], [f64; 3]),
        b_n: f64,
        b_t: Option<[f64; 3]>,
    ) -> f64 {
        let mut change: f64 = 0.0;
        let u_n = vec3::dot(self.relative(vi, vj), self.n);
        let total = (*normal - (u_n - b_n) * self.mass).max(0.0);
        let dn = total - *normal;
        *normal = total;
        if dn != 0.0 {
            change = change.max(dn.abs() / self.mass);
            self.apply(vi, vj, vec3::scale(dn, self.n));
        }
        if let Some(b_t) = b_t {
            if self.mu > 0.0 {
                let u = self.relative(vi, vj);
                let u_t = vec3::sub(u, vec3::scale(vec3::dot(u, self.n), self.n));
                let old = *tangent;
                let t = self.clamp(vec3::sub(old, vec3::scale(self.mass_t, vec3::sub(u_t, b_t))), total);
                let dt = vec3::sub(t, old);
                if dt != [0.0; 3] {
                    change = change.max(vec3::norm(dt) / self.mass_t);
                    *tangent = t;
                    self.apply(vi, vj, dt);
                }
            }
        } else if *tangent != [0.0; 3] {
            // the restitution stage keeps the friction within the cone of a shrinking λ
            let t = self.clamp(*tangent, total);
            let dt = vec3::sub(t, *tangent);
            if dt != [0.0; 3] {
                *tangent = t;
                self.apply(vi, vj, dt);
            }
        }
        if N == 6 && self.roll.cap > 0.0 {
            let change_roll = self.visit_roll(vi, vj, roll, total, b_t.is_some());
            change = change.max(change_roll);
        }
        change
    }

    /// The rolling (and twisting) resistance's part of a visit: with `hold`, the angular
    /// impulse M that brings the relative turning to 0 within |M| ≤ μ_r R* λ; without (the
    /// restitution stage), M kept within the cone of a shrinking λ. Returns the change as a
    /// velocity at R*, m/s.
    #[inline(always)]
    fn visit_roll<const N: usize>(
        &self,
        vi: &mut [f64; N],
        vj: &mut [f64; N],
        roll: &mut [f64; 3],
        lambda: f64,
        hold: bool,
    ) -> f64 {
        let r = self.roll;
        let old = *roll;
        let wanted = if hold {
            let w: [f64; 3] = std::array::from_fn(|k| vi[3 + k] - vj[3 + k]);
            vec3::sub(old, vec3::scale(r.mass, w))
        } else {
            old
        };
        let (len, cap) = (vec3::norm(wanted), r.cap * lambda);
        let m = if len > cap {
            vec3::scale(if len > 0.0 { cap / len } else { 0.0 }, wanted)
        } else {
            wanted
        };
        let dm = vec3::sub(m, old);
        if dm == [0.0; 3] {
            return 0.0;
        }
        *roll = m;
        for k in 0..3 {
            vi[3 + k] += r.k[0] * dm[k];
        }
        if self.has_j {
            for k in 0..3 {
                vj[3 + k] -= r.k[1] * dm[k];
            }
        }
        vec3::norm(dm) / r.mass.max(f64::MIN_POSITIVE) * r.r_star
    }
}
