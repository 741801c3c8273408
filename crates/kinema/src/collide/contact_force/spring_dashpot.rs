//! The linear spring–dashpot (DEM) normal force, damped for a restitution.
//!
//! Instead of an impulse, overlapping bodies feel a force along the normal while they
//! overlap, and the integrator (stage 1 of a step) moves them apart:
//!
//! ```text
//!   F_n = k_n δ + c_n δ' = k_n δ − m_eff γ_n u_n          (on i along n; −F_n n on j)
//! ```
//!
//! with δ the overlap, δ' = −u_n (the overlap grows while they approach), m_eff = 1 / (w_i + w_j)
//! the reduced mass and c_n = m_eff γ_n. Along the normal the overlap then obeys the damped
//! oscillator
//!
//! ```text
//!   m_eff δ'' = −F_n   ⇔   δ'' + γ_n δ' + ω₀² δ = 0,    ω₀² = k_n / m_eff,  γ_n = 2 ζ ω₀
//! ```
//!
//! Contact starts at δ = 0 with δ'(0) = −u_n⁻ > 0. For ζ < 1 the solution is
//! δ(t) = δ'(0)/ω_d · e^{−ζ ω₀ t} sin(ω_d t), ω_d = ω₀ √(1 − ζ²): the overlap is back to zero
//! after half a damped period t_c = π / ω_d, with δ'(t_c) = −δ'(0) e^{−ζ ω₀ t_c}. So
//!
//! ```text
//!   e = −u_n⁺ / u_n⁻ = exp(−ζ π / √(1 − ζ²))   ⇔   ζ = −ln e / √(π² + ln² e)
//! ```
//!
//! (square ln e = −ζπ/√(1 − ζ²) and solve for ζ²), independent of k_n and of the masses: the
//! damping scales with m_eff so that every pair bounces back with the same e.
//!
//! Limits: e = 1 gives ζ = 0, no damping. e → 0 gives ζ → 1, critical damping, where the
//! overlap decays to zero without ever reaching it (t_c → ∞): the pair ends at rest relative
//! to each other, the limit e = 0, and [`damping_ratio`] returns ζ = 1 for it.
//!
//! The force is not clamped at zero. Near the end of a contact the dashpot pulls (δ → 0 while
//! separating gives F_n = −m_eff γ_n u_n < 0); cutting that pull off would end the contact
//! early and bounce back faster than the e asked for, which the formula above would no
//! longer give.

use crate::error::Error;

/// The damping ratio ζ of the contact oscillator that bounces back with restitution `e`
/// (in [0, 1]): ζ = −ln e / √(π² + ln² e); 0 for e = 1, 1 (critical) for e = 0.
pub fn damping_ratio(restitution: f64) -> Result<f64, Error> {
    if !(0.0..=1.0).contains(&restitution) {
        return Err(Error::invalid(
            "restitution",
            restitution,
            "the coefficient of restitution must be in [0, 1]",
        ));
    }
    if restitution == 0.0 {
        return Ok(1.0);
    }
    // ln e ≤ 0; its magnitude keeps e = 1 at +0 rather than −0.
    let l = restitution.ln().abs();
    Ok(l / (std::f64::consts::PI * std::f64::consts::PI + l * l).sqrt())
}

/// The spring–dashpot law itself, F_n = k_n δ − c_n u_n (N, > 0 pushes the pair apart):
/// stiffness k_n (N/m), dashpot coefficient c_n (kg/s), overlap δ (m) and normal velocity u_n
/// (m/s, < 0 approaching). Every spring–dashpot contact in kinema is this function: the
/// world's contact force calls it for each contact (`contact_force/law.rs`), and so does the
/// tests' `SpringDashpotLaw` (`oracles.rs`), whose restitution they measure.
#[inline]
pub fn spring_dashpot_force(stiffness: f64, dashpot: f64, overlap: f64, u_n: f64) -> f64 {
    stiffness * overlap - dashpot * u_n
}

/// c_n = m_eff γ_n = 2 ζ √(k_n m_eff) = 2 ζ √(k_n / w), kg/s: the dashpot that gives damping
/// ratio ζ to a contact of stiffness k_n (N/m) and inverse-mass sum w = w_i + w_j (1/kg, > 0).
#[inline]
pub fn dashpot_coefficient(stiffness: f64, zeta: f64, inverse_mass_sum: f64) -> f64 {
    2.0 * zeta * (stiffness / inverse_mass_sum).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::contact::{Contact, Partner};
    use crate::collide::oracles::{restitution_of_damping, SpringDashpotLaw};

    #[test]
    fn damping_ratio_closed_forms() {
        assert_eq!(damping_ratio(1.0).unwrap(), 0.0);
        assert!(damping_ratio(1.0).unwrap().is_sign_positive());
        assert_eq!(damping_ratio(0.0).unwrap(), 1.0);
        // ζ = 1/2: e = exp(−(π/2)/√(3/4)) = exp(−π/√3)
        let e = (-std::f64::consts::PI / 3f64.sqrt()).exp();
        assert!((damping_ratio(e).unwrap() - 0.5).abs() < 1e-15);
        for e in [1e-6, 0.1, 0.5, 0.9, 0.999] {
            let back = restitution_of_damping(damping_ratio(e).unwrap());
            assert!((back - e).abs() < 1e-14 * e.max(1e-2), "{e} → {back}");
        }
        // ζ grows as e falls
        assert!(damping_ratio(0.1).unwrap() > damping_ratio(0.5).unwrap());
        let e = damping_ratio(1.5).unwrap_err().to_string();
        assert!(e.starts_with("restitution = 1.5 is invalid"), "{e}");
        let e = SpringDashpotLaw::new(0.0, 0.5).unwrap_err().to_string();
        assert!(e.starts_with("stiffness = 0 is invalid"), "{e}");
    }

    #[test]
    fn forces_are_equal_and_opposite_and_match_the_law() {
        let law = SpringDashpotLaw::new(1e4, 0.5).unwrap();
        let inv_mass = [0.5, 0.25, 0.0];
        let contacts = [
            Contact {
                i: 0,
                other: Partner::Particle(1),
                normal: [0.6, 0.0, 0.8],
                overlap: 1e-3,
                u_n: -0.7,
                wall_velocity: [0.0; 3],
            },
            Contact {
                i: 1,
                other: Partner::Collider(0),
                normal: [0.0, 0.0, 1.0],
                overlap: 2e-3,
                u_n: 0.1,
                wall_velocity: [0.0; 3],
            },
            // a gap within the tolerance: no force
            Contact {
                i: 2,
                other: Partner::Particle(0),
                normal: [1.0, 0.0, 0.0],
                overlap: -1e-3,
                u_n: -5.0,
                wall_velocity: [0.0; 3],
            },
        ];
        let mut f = [0.0; 9];
        law.accumulate(&contacts, &inv_mass, &mut f).unwrap();
        let m_eff = 1.0 / 0.75;
        let f0 = law.normal_force(1e-3, -0.7, m_eff);
        // k δ + 2 ζ √(k m_eff) |u_n|
        let expect = 1e4 * 1e-3 + 2.0 * law.damping_ratio() * (1e4 * m_eff).sqrt() * 0.7;
        assert!((f0 - expect).abs() < 1e-12 * expect);
        let f1 = law.normal_force(2e-3, 0.1, 4.0);
        let want = [0.6 * f0, 0.0, 0.8 * f0 - 0.0, -0.6 * f0, 0.0, -0.8 * f0 + f1, 0.0, 0.0, 0.0];
        for k in 0..9 {
            assert!((f[k] - want[k]).abs() < 1e-12 * expect, "f[{k}] = {} vs {}", f[k], want[k]);
        }
        assert_eq!(law.contact_omega_squared(&contacts[0], &inv_mass), 1e4 * 0.75);
        assert_eq!(law.max_omega_squared(&contacts, &inv_mass), 1e4 * 0.75);
    }
}
