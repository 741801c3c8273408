//! The normal sub-models of the force models, as LAMMPS GRANULAR registers them
//! (`granular_model.cpp`: `normal hooke`, `hertz/material`, `dmt`, `jkr`): one closed
//! choice, [`NormalLaw`], and everything a contact asks of it — the secant stiffness, the
//! contact radius, the pull-off force, the elastic energy and how far apart a contact holds.
//!
//! A new normal law is one variant here and its arm in each method below (every match names
//! every law, so the compiler lists them), its row in the table of sub-models
//! (`sub_models.rs`), and its setting (`stage/settings.rs`: `ContactModel`, its name,
//! `force_model_of`); the pair pass, the damping (`law.rs`), the
//! tangential part (`tangent.rs`) and the rates (`force.rs`) read it only through these
//! methods. (Checked by adding a toy law F = k δ² and taking it out: `docs/architecture.md`,
//! "How to add".)
//!
//! Each method takes R*, the contact's reduced radius, as a closure: Hooke's law never needs
//! it, and the pair pass must not pay for it there.

use std::f64::consts::PI;

use super::cohesion::{Cohesion, Jkr};

/// The 4/3 of Hertz's law F = 4/3 E* √R* δ^(3/2).
pub(super) const HERTZ: f64 = 4.0 / 3.0;

/// √5 / 2: Hertz's dashpot against the linear one of the same e (`law.rs`'s `dashpot_at`).
const HERTZ_DAMPING: f64 = 1.118_033_988_749_895;

/// The elastic normal force of a contact of overlap δ (m) and reduced radius R* (m), N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum NormalLaw {
    /// Hooke's spring F = k_n δ (`spring_dashpot`; LAMMPS's `hooke`), k_n in N/m.
    Hooke { stiffness: f64 },
    /// Hertz's elastic spheres F = 4/3 E* √R* δ^(3/2) (`hertz`; LAMMPS's `hertz/material`),
    /// E* = E / (2 (1 − ν²)) in Pa (Johnson, Contact Mechanics, §4.2).
    Hertz { e_star: f64 },
    /// Derjaguin–Muller–Toporov (1975): Hertz's force less the constant pull F_po = 4π γ R*
    /// while the bodies overlap (LAMMPS's `dmt`); `pull_off` = 4π γ, N/m.
    Dmt { e_star: f64, pull_off: f64 },
    /// Johnson–Kendall–Roberts (1971, `cohesion.rs`): the force at the contact radius a of
    /// the overlap, holding past touching down to δ = −|δ_f| (LAMMPS's `jkr`).
    Jkr(Jkr),
}

impl NormalLaw {
    /// The names of its variants, as `name` gives them (`sub_models.rs`).
    pub const NAMES: [&'static str; 4] = ["hooke", "hertz", "dmt", "jkr"];

    /// Its name (LAMMPS's, but `hertz` for its `hertz/material`).
    pub fn name(&self) -> &'static str {
        match self {
            NormalLaw::Hooke { .. } => Self::NAMES[0],
            NormalLaw::Hertz { .. } => Self::NAMES[1],
            NormalLaw::Dmt { .. } => Self::NAMES[2],
            NormalLaw::Jkr(_) => Self::NAMES[3],
        }
    }

    /// Hertz's law of effective modulus `e_star` (Pa) with the adhesion `cohesion` (none
    /// where its surface energy is 0).
    pub fn hertz(e_star: f64, cohesion: Option<Cohesion>) -> Self {
        match cohesion.filter(|c| c.surface_energy() > 0.0) {
            None => NormalLaw::Hertz { e_star },
            Some(Cohesion::Dmt { surface_energy }) => NormalLaw::Dmt {
                e_star,
                pull_off: 4.0 * PI * surface_energy,
            },
            Some(Cohesion::Jkr { surface_energy }) => NormalLaw::Jkr(Jkr {
                e_star,
                gamma: surface_energy,
            }),
        }
    }

    /// JKR's contact, the one law whose contacts hold past touching.
    #[inline(always)]
    pub fn jkr(&self) -> Option<Jkr> {
        match *self {
            NormalLaw::Jkr(jkr) => Some(jkr),
            NormalLaw::Hooke { .. } | NormalLaw::Hertz { .. } | NormalLaw::Dmt { .. } => None,
        }
    }

    /// The radius of the contact disc, m: √(R* δ) (Hertz), JKR's a with its adhesion.
    #[inline]
    pub fn contact_radius(&self, overlap: f64, r_star: impl Fn() -> f64) -> f64 {
        match self {
            NormalLaw::Jkr(jkr) => jkr.contact_radius(r_star(), overlap),
            NormalLaw::Hooke { .. } | NormalLaw::Hertz { .. } | NormalLaw::Dmt { .. } => (r_star() * overlap).sqrt(),
        }
    }

    /// The secant stiffness F_el/δ at overlap δ > 0, N/m: k_n with Hooke's law; with Hertz's,
    /// 4/3 E* a, a the contact radius (F = 4/3 E* √R* δ^(3/2), a = √(R* δ); JKR's a with its
    /// adhesion).
    #[inline(always)]
    pub fn secant_stiffness(&self, overlap: f64, r_star: impl Fn() -> f64) -> f64 {
        match *self {
            NormalLaw::Hooke { stiffness } => stiffness,
            NormalLaw::Hertz { e_star } | NormalLaw::Dmt { e_star, .. } => HERTZ * e_star * self.contact_radius(overlap, r_star),
            NormalLaw::Jkr(jkr) => HERTZ * jkr.e_star * self.contact_radius(overlap, r_star),
        }
    }

    /// dF/dδ over the secant stiffness: 1 for Hooke's δ, 3/2 for Hertz's δ^(3/2).
    pub fn tangent_of_secant(&self, secant: f64) -> f64 {
        match self {
            NormalLaw::Hooke { .. } => secant,
            NormalLaw::Hertz { .. } | NormalLaw::Dmt { .. } | NormalLaw::Jkr(_) => 1.5 * secant,
        }
    }

    /// The tangent stiffness a contact reaches in an elastic impact, N/m, at approach speed
    /// `u` (m/s) between bodies of inverse masses summing to `w` (1/kg), `r` the largest
    /// radius (m; the stiffest R*): Hooke's k_n at any speed; Hertz's 3/2 k_n at the deepest
    /// overlap δ_max = (5 m_eff u² / (4 k_h))^(2/5), k_h = 4/3 E* √R* (energy: ½ m_eff u² = 2/5
    /// k_h δ^(5/2)); `None` while nothing moves.
    pub fn impact_stiffness(&self, u: impl Fn() -> f64, r: impl Fn() -> f64, w: f64) -> Option<f64> {
        let e_star = match *self {
            NormalLaw::Hooke { stiffness } => return Some(stiffness),
            NormalLaw::Hertz { e_star } | NormalLaw::Dmt { e_star, .. } => e_star,
            NormalLaw::Jkr(jkr) => jkr.e_star,
        };
        let (u, r) = (u(), r());
        let k_h = HERTZ * e_star * r.sqrt();
        if !(u > 0.0 && k_h > 0.0) {
            return None;
        }
        let deepest = (5.0 * u * u / (4.0 * k_h * w)).powf(0.4);
        Some(1.5 * k_h * deepest.sqrt())
    }

    /// The pull-off force, N: DMT's 4π γ R*, JKR's 3π γ R* (0 without adhesion).
    #[inline(always)]
    pub fn pull_off(&self, r_star: impl Fn() -> f64) -> f64 {
        match *self {
            NormalLaw::Dmt { pull_off, .. } => pull_off * r_star(),
            NormalLaw::Jkr(jkr) => jkr.pull_off_force(r_star()),
            NormalLaw::Hooke { .. } | NormalLaw::Hertz { .. } => 0.0,
        }
    }

    /// The dashpot of the law given the linear one of the same e, kg/s: Hertz's contacts
    /// take √5/2 of it at the current secant stiffness (Tsuji et al. 1992; LAMMPS's `damping
    /// coeff_restitution` for Hertzian contacts).
    #[inline(always)]
    pub fn restitution_dashpot(&self, linear: f64) -> f64 {
        match self {
            NormalLaw::Hooke { .. } => linear,
            NormalLaw::Hertz { .. } | NormalLaw::Dmt { .. } | NormalLaw::Jkr(_) => HERTZ_DAMPING * linear,
        }
    }

    /// The elastic force and the dashpot of a contact of overlap δ (m) approaching at u_n
    /// (m/s), N and kg/s, or `None` where it exerts none (apart, or past JKR's pull-off
    /// distance); `dashpot(k)` is the dashpot at secant stiffness k.
    ///
    /// With DMT the pull-off F_po is taken off while the bodies overlap: F_n = 4/3 E* √R*
    /// δ^(3/2) − c_n u_n − F_po. The contact ends at δ = 0, so a body held by it comes free
    /// under a pull above F_po (at rest, δ → 0⁺ leaves −F_po). With JKR's the force is F(a) −
    /// c_n u_n at the contact radius a of the overlap, down to δ = −|δ_f|: the caller gives a
    /// contact apart (δ ≤ 0) only if it touched at the last step.
    #[inline(always)]
    pub fn force_parts(
        &self,
        overlap: f64,
        u_n: f64,
        r_star: impl Fn() -> f64,
        dashpot: impl Fn(f64) -> f64,
    ) -> Option<(f64, f64)> {
        match *self {
            // (Hooke's first: the common law, with nothing to pull; the force as it was
            // written before the laws were one choice, bit for bit: F − 0 is F)
            NormalLaw::Hooke { stiffness } => {
                if overlap <= 0.0 {
                    return None;
                }
                let c_n = dashpot(stiffness);
                Some((crate::collide::spring_dashpot_force(stiffness, c_n, overlap, u_n), c_n))
            }
            NormalLaw::Jkr(jkr) => {
                let r = r_star();
                if overlap <= -jkr.pull_off_distance(r) {
                    return None;
                }
                let a = jkr.contact_radius(r, overlap);
                let c_n = dashpot(HERTZ * jkr.e_star * a);
                Some((jkr.force(r, a) - c_n * u_n, c_n))
            }
            NormalLaw::Hertz { .. } | NormalLaw::Dmt { .. } => {
                if overlap <= 0.0 {
                    return None;
                }
                let k = self.secant_stiffness(overlap, &r_star);
                let c_n = dashpot(k);
                let force = crate::collide::spring_dashpot_force(k, c_n, overlap, u_n);
                Some((force - self.pull_off(r_star), c_n))
            }
        }
    }

    /// The elastic energy of a contact of overlap δ (m), J, if it counts (overlapping, or
    /// JKR's held contact): ½ k_n δ² (Hooke), ∫ 4/3 E* √R* δ^(3/2) dδ = 2/5 k_n δ² (Hertz, k_n
    /// the secant stiffness at δ), less F_po δ with DMT adhesion (the work of the constant
    /// pull over the overlap); JKR's ∫₀^δ F dδ' (`cohesion.rs`).
    #[inline]
    pub fn energy(&self, overlap: f64, r_star: impl Fn() -> f64) -> Option<f64> {
        match *self {
            NormalLaw::Jkr(jkr) => {
                let r = r_star();
                (overlap > -jkr.pull_off_distance(r)).then(|| jkr.energy(r, jkr.contact_radius(r, overlap)))
            }
            NormalLaw::Hooke { stiffness } => (overlap > 0.0).then_some(0.5 * stiffness * overlap * overlap),
            NormalLaw::Hertz { .. } | NormalLaw::Dmt { .. } => (overlap > 0.0)
                .then(|| 0.4 * self.secant_stiffness(overlap, &r_star) * overlap * overlap - self.pull_off(&r_star) * overlap),
        }
    }

    /// How far past touching a contact of the largest reduced radius `r_max()` (m) can hold,
    /// m: JKR's pull-off distance, else 0 (without asking `r_max`).
    pub fn reach_past_touching(&self, r_max: impl Fn() -> f64) -> f64 {
        self.jkr().map_or(0.0, |jkr| jkr.pull_off_distance(r_max()))
    }
}
