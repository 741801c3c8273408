//! Adhesion of Hertz's contacts: the JKR contact (Johnson, Kendall and Roberts 1971; LAMMPS
//! GRANULAR's `jkr`), its contact radius, force, energy and pull-off distance. (DMT's constant
//! pull is a term of `law.rs`.)
//!
//! Two elastic spheres of reduced radius R* and effective modulus E* = E / (2 (1 − ν²)) with
//! surface energy γ (work of adhesion w = 2γ) touch over a disc of radius a, with (Johnson,
//! Contact Mechanics, §5.5)
//!
//! ```text
//!   δ(a) = a²/R* − 2 √(π γ a / E*)                       the overlap, m
//!   F(a) = 4 E* a³ / (3 R*) − 4 √(π γ E* a³)             the normal force, N (> 0 pushes)
//! ```
//!
//! (Hertz's law less the adhesive term; γ = 0 gives a = √(R* δ), F = 4/3 E* √R* δ^(3/2).)
//! The force is least, −F_po = −3π γ R* (−3/2 π w R*), at a_f = (9π γ R*² / (4 E*))^(1/3),
//! δ_f = −a_f² / (3 R*) = −(3π² γ² R* / (16 E*²))^(1/3): under a pull the contact lets go
//! there. The contact is hysteretic: bodies approaching touch at δ = 0 (they snap to a
//! disc of radius a_0 = (4π γ R*² / E*)^(1/3) and feel F(a_0) = −8/9 F_po at once), but
//! once touching they hold on beyond it, to δ_f, where the contact ends (LAMMPS's `touch`
//! flag, kept per contact; here the contacts' memory, `history.rs`).
//!
//! The energy stored in a contact at overlap δ is U(δ) = ∫₀^δ F dδ' along the curve, a
//! polynomial in √a (`Jkr::energy`): 0 at the first touch, U(δ_f) > 0 when it lets go. That
//! U(δ_f) is lost at every separation, whatever the dashpot: the work of pulling apart the
//! adhesive neck, which the approach did not give back (Thornton and Ning 1998). A body
//! whose kinetic energy of approach (m* u²/2) is less stays stuck: the sticking speed
//! u_s = √(2 U(δ_f) / m*) with no dashpot.

use std::f64::consts::PI;

use crate::error::Error;

/// Adhesion between touching bodies of Hertz's model, by the surface energy γ, J/m² (≥ 0;
/// w = 2γ the work of adhesion), as LAMMPS GRANULAR's `dmt` and `jkr` normal models have it
/// (`cohesion.rs` here).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cohesion {
    /// Derjaguin–Muller–Toporov (1975): Hertz's force less a constant pull F_po = 4π γ R*
    /// (2π w R*) while the bodies overlap; the contact ends at δ = 0.
    Dmt {
        /// γ, J/m².
        surface_energy: f64,
    },
    /// Johnson–Kendall–Roberts (1971): the contact radius a and the force from the overlap
    /// by the JKR relations; a contact, once made, holds beyond δ = 0 until the pull reaches
    /// F_po = 3π γ R* (3/2 π w R*), at δ = −(3π² γ² R* / (16 E*²))^(1/3).
    Jkr {
        /// γ, J/m².
        surface_energy: f64,
    },
}

impl Cohesion {
    /// The names, as the binding and the scene files spell them.
    pub const NAMES: [&'static str; 2] = ["dmt", "jkr"];

    /// The model named `name` with surface energy γ (J/m²).
    pub fn from_name(name: &str, surface_energy: f64) -> Result<Cohesion, Error> {
        match name {
            "dmt" => Ok(Cohesion::Dmt { surface_energy }),
            "jkr" => Ok(Cohesion::Jkr { surface_energy }),
            other => Err(Error::invalid(
                "cohesion",
                format!("'{other}'"),
                "the cohesion model must be 'dmt' (Derjaguin–Muller–Toporov) or 'jkr' \
                 (Johnson–Kendall–Roberts), with model='hertz', or None",
            )),
        }
    }

    /// Its name.
    pub fn name(&self) -> &'static str {
        match self {
            Cohesion::Dmt { .. } => Self::NAMES[0],
            Cohesion::Jkr { .. } => Self::NAMES[1],
        }
    }

    /// γ, J/m².
    pub fn surface_energy(&self) -> f64 {
        match *self {
            Cohesion::Dmt { surface_energy } | Cohesion::Jkr { surface_energy } => surface_energy,
        }
    }
}

/// The JKR contact of bodies with effective modulus E* (Pa) and surface energy γ (J/m²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Jkr {
    /// E*, Pa.
    pub e_star: f64,
    /// γ, J/m².
    pub gamma: f64,
}

impl Jkr {
    /// F_po = 3π γ R*, N: the largest pull the contact of reduced radius `r` (m) takes.
    pub fn pull_off_force(&self, r: f64) -> f64 {
        3.0 * PI * self.gamma * r
    }

    /// |δ_f| = (3π² γ² R* / (16 E*²))^(1/3), m: how far apart (past touching) a contact of
    /// reduced radius `r` holds (LAMMPS's `pulloff_distance`).
    pub fn pull_off_distance(&self, r: f64) -> f64 {
        (3.0 * PI * PI * self.gamma * self.gamma * r / (16.0 * self.e_star * self.e_star)).cbrt()
    }

    /// The contact radius a, m, at overlap `delta` (m; ≥ δ_f) for reduced radius `r`: the
    /// largest root of δ = a²/R* − 2 √(π γ a / E*).
    ///
    /// With s = √a that is s⁴ − b s − c = 0, b = 2 R* √(π γ / E*), c = R* δ: g(s) = s⁴ − b s − c
    /// is convex, least at s* = (b/4)^(1/3), and increasing past it. Newton's method from
    /// s₀ = b^(1/3) + max(c, 0)^(1/4), where g(s₀) ≥ 0 ((x + y)⁴ ≥ x³(x + y) + y⁴), descends
    /// to the largest root without overshooting, so it stops when a step no longer lowers s
    /// (the last bit): the same result on every machine. (Beyond the curve's end, below
    /// g(s*) = 0, it gives s* itself.)
    pub fn contact_radius(&self, r: f64, delta: f64) -> f64 {
        let b = 2.0 * r * (PI * self.gamma / self.e_star).sqrt();
        let c = r * delta;
        let floor = (0.25 * b).cbrt();
        let mut s = b.cbrt() + c.max(0.0).sqrt().sqrt();
        for _ in 0..100 {
            let s2 = s * s;
            let g = s2 * s2 - b * s - c;
            let slope = 4.0 * s2 * s - b;
            if slope <= 0.0 {
                break;
            }
            let next = s - g / slope;
            // (no lower: the root, to the last bit; NaN stops too)
            if next.partial_cmp(&s) != Some(std::cmp::Ordering::Less) {
                break;
            }
            s = next.max(floor);
            if s == floor {
                break;
            }
        }
        s * s
    }

    /// F(a) = 4 E* a³ / (3 R*) − 4 √(π γ E* a³), N, at contact radius `a` (m), reduced radius
    /// `r` (m).
    pub fn force(&self, r: f64, a: f64) -> f64 {
        let a3 = a * a * a;
        4.0 * self.e_star * a3 / (3.0 * r) - 4.0 * (PI * self.gamma * self.e_star * a3).sqrt()
    }

    /// U = ∫₀^δ F dδ', J, the energy stored in the contact at contact radius `a` (m): with
    /// dδ/da = 2a/R* − √(π γ / (E* a)) and q = √(π γ E*),
    ///
    /// ```text
    ///   F dδ/da = 8 E* a⁴/(3 R*²) − 28 q a^(5/2) / (3 R*) + 4π γ a
    ///   G(a)    = 8 E* a⁵ / (15 R*²) − 8 q a^(7/2) / (3 R*) + 2π γ a²,    U = G(a) − G(a₀)
    /// ```
    ///
    /// a₀ = (4π γ R*² / E*)^(1/3) the radius at δ = 0. (γ = 0: 8/15 E* √R* δ^(5/2), Hertz's
    /// 2/5 F δ.)
    pub fn energy(&self, r: f64, a: f64) -> f64 {
        self.primitive(r, a) - self.primitive(r, self.touch_radius(r))
    }

    /// U(δ_f), J: the energy a contact of reduced radius `r` (m) loses when it lets go.
    pub fn separation_energy(&self, r: f64) -> f64 {
        let a_f = (9.0 * PI * self.gamma * r * r / (4.0 * self.e_star)).cbrt();
        self.energy(r, a_f)
    }

    /// a₀ = (4π γ R*² / E*)^(1/3), m: the contact radius at δ = 0.
    fn touch_radius(&self, r: f64) -> f64 {
        (4.0 * PI * self.gamma * r * r / self.e_star).cbrt()
    }

    /// G(a) of [`Jkr::energy`], J.
    fn primitive(&self, r: f64, a: f64) -> f64 {
        let q = (PI * self.gamma * self.e_star).sqrt();
        let a2 = a * a;
        8.0 * self.e_star * a2 * a2 * a / (15.0 * r * r) - 8.0 * q * a2 * a.sqrt() * a / (3.0 * r) + 2.0 * PI * self.gamma * a2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const JKR: Jkr = Jkr {
        e_star: 5.0e6,
        gamma: 0.05,
    };

    fn overlap(r: f64, a: f64) -> f64 {
        a * a / r - 2.0 * (PI * JKR.gamma * a / JKR.e_star).sqrt()
    }

    #[test]
    fn the_contact_radius_inverts_the_jkr_overlap() {
        let r = 1e-3;
        let a_f = (9.0 * PI * JKR.gamma * r * r / (4.0 * JKR.e_star)).cbrt();
        for a in [a_f, 1.5 * a_f, 3.0 * a_f, 10.0 * a_f, 100.0 * a_f] {
            let got = JKR.contact_radius(r, overlap(r, a));
            assert!((got - a).abs() <= 1e-12 * a, "a = {a}: {got}");
        }
    }

    #[test]
    fn the_force_is_least_at_the_pull_off_and_the_pull_off_distance_is_where() {
        let r = 2e-3;
        let d_f = JKR.pull_off_distance(r);
        let a_f = JKR.contact_radius(r, -d_f);
        let f_po = JKR.pull_off_force(r);
        // F(δ_f) = −3π γ R*, and F is larger on either side
        assert!((JKR.force(r, a_f) + f_po).abs() < 1e-9 * f_po);
        for k in [0.9, 1.1] {
            assert!(JKR.force(r, k * a_f) > -f_po);
        }
        // at δ = 0 the snap-in force −8/9 F_po
        let a0 = JKR.contact_radius(r, 0.0);
        assert!((JKR.force(r, a0) + 8.0 / 9.0 * f_po).abs() < 1e-9 * f_po);
    }

    #[test]
    fn the_energy_is_the_integral_of_the_force_over_the_overlap() {
        // trapezoid rule over δ from 0 to δ_f (negative) and to a compression
        let r = 1e-3;
        for end in [-JKR.pull_off_distance(r), 5.0 * JKR.pull_off_distance(r)] {
            let n = 200_000;
            let mut sum = 0.0;
            let f = |d: f64| JKR.force(r, JKR.contact_radius(r, d));
            for k in 0..n {
                let (d0, d1) = (end * k as f64 / n as f64, end * (k + 1) as f64 / n as f64);
                sum += 0.5 * (f(d0) + f(d1)) * (d1 - d0);
            }
            let exact = JKR.energy(r, JKR.contact_radius(r, end));
            assert!((sum - exact).abs() < 1e-6 * exact.abs(), "{sum} vs {exact}");
        }
        assert!(JKR.separation_energy(r) > 0.0);
    }

    #[test]
    fn without_adhesion_it_is_hertz() {
        let h = Jkr { e_star: 1e7, gamma: 0.0 };
        let (r, d) = (1e-3, 1e-6);
        let a = h.contact_radius(r, d);
        assert!((a - (r * d).sqrt()).abs() < 1e-15);
        let hertz = 4.0 / 3.0 * h.e_star * r.sqrt() * d.powf(1.5);
        assert!((h.force(r, a) - hertz).abs() < 1e-12 * hertz);
        assert!((h.energy(r, a) - 0.4 * hertz * d).abs() < 1e-12 * hertz * d);
    }
}
