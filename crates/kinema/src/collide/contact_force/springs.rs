//! What the three laws of a contact's tangential side share (`tangent.rs`: the sliding
//! spring; `rolling.rs`, `twisting.rs`): the contact as they see it ([`Touch`]), its two
//! sides' relative spin ([`Spins`]), a spring turned into the tangent plane as the contact
//! rolls round ([`into_plane`]), and the spring–dashpot–slider of the sliding and rolling
//! springs ([`slider`]; the twist is its scalar kind, in `twisting.rs`).
//! The derivations are in `tangent.rs`'s module doc.

use crate::vec3;

/// The relative angular velocity ω_i − ω_j of a contact's two sides (ω_j = 0 at a
/// collider), rad/s: now (the dashpots') and over the step (what stretches the springs).
pub(super) struct Spins {
    pub now: [f64; 3],
    pub over_step: [f64; 3],
}

/// One contact as the tangential law sees it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Touch {
    /// n, from the partner towards i.
    pub normal: [f64; 3],
    /// a, m: the radius of the contact disc (√(R* δ) with Hertz's law, JKR's with its
    /// adhesion: `cohesion.rs`).
    pub contact_radius: f64,
    /// R*, m.
    pub reduced_radius: f64,
    /// u = v_i − v_j (or v_i − w), m/s.
    pub u: [f64; 3],
    /// ω_i and ω_j (0 at a collider), rad/s.
    pub omega: [[f64; 3]; 2],
    /// With a step: u and ω over it, (x(t + h) − x(t))/h (Verlet's v + h/2 a, the mean of the
    /// velocities at the step's start and its predictor), which stretch the springs, so that
    /// ξ is the contact point's displacement to rounding; `None`: `u`, `omega`.
    pub moved: Option<([f64; 3], [[f64; 3]; 2])>,
    /// ρ_i, ρ_j, m.
    pub arms: (f64, f64),
    /// |F_n|, N: the normal force, dashpot included (LAMMPS's Fncrit).
    pub normal_force: f64,
    /// c_n, kg/s.
    pub dashpot: f64,
    /// μ of the pair's material.
    pub friction: f64,
}

/// ξ turned into the plane ⊥ n, its length kept (a spring of zero length stays so).
#[inline]
pub(super) fn into_plane(xi: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let along = vec3::dot(xi, n);
    if along == 0.0 {
        return xi;
    }
    let before = vec3::norm(xi);
    let flat = vec3::sub(xi, vec3::scale(along, n));
    let after = vec3::norm(flat);
    if after > 0.0 {
        vec3::scale(before / after, flat)
    } else {
        [0.0; 3]
    }
}

/// A spring–dashpot slider, F = −k ξ − γ v with |F| ≤ cap: the force, and the stretch after
/// a slide (set to where the force stays at the cap).
#[inline]
pub(super) fn slider(xi: [f64; 3], v: [f64; 3], k: f64, gamma: f64, cap: f64) -> ([f64; 3], [f64; 3], bool) {
    let f = [
        -k * xi[0] - gamma * v[0],
        -k * xi[1] - gamma * v[1],
        -k * xi[2] - gamma * v[2],
    ];
    let size = vec3::norm(f);
    if size <= cap {
        return (f, xi, false);
    }
    if vec3::norm(xi) == 0.0 || k == 0.0 {
        // no stretch to hold the cap with (LAMMPS: no force)
        return ([0.0; 3], xi, true);
    }
    let s = cap / size;
    let f = vec3::scale(s, f);
    let xi = [
        -(f[0] + gamma * v[0]) / k,
        -(f[1] + gamma * v[1]) / k,
        -(f[2] + gamma * v[2]) / k,
    ];
    (f, xi, true)
}
