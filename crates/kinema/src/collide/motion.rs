//! Prescribed motion of a collider: a rigid displacement of its rest placement as a function
//! of time, and the velocity field of its surface.
//!
//! A collider moves as a rigid body that nothing pushes back (infinite mass): its motion is
//! given, and the particles feel it through its position and its surface velocity. At time t
//! a point x₀ of the collider as it was added is at
//!
//! ```text
//!   x(t) = R(t) (x₀ − c) + c + T(t)
//! ```
//!
//! with c the pivot (the point the rotation turns about, in the rest placement), R(t) a
//! rotation and T(t) a translation; the surface's velocity at a point x is then
//!
//! ```text
//!   u(x) = Ṫ + ω × (x − c − T)
//! ```
//!
//! with ω the angular velocity (Ṙ Rᵀ = [ω]×). Two kinds ([`Motion`]): steady (constant
//! velocity V and angular velocity ω: T = V t, R = exp(t [ω]×), Rodrigues' formula), and
//! keyframes (times t_k, translations T_k and rotations R_k: T linear between keys, R by
//! spherical linear interpolation of unit quaternions, which turns at a constant ω between
//! two keys; before the first key and after the last the collider rests at them).
//!
//! A steady rotation about a collider's own axis of symmetry (a drum about its axis, a
//! sphere about its centre) moves no surface point: only the surface velocity changes the
//! contacts, as for LAMMPS's `fix wall/gran ... rotate`.

use crate::error::Error;
use crate::vec3;

/// A rigid displacement: x ↦ R (x − c) + c + T.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Rotation matrix R, rows.
    pub rotation: [[f64; 3]; 3],
    /// The pivot c, m.
    pub pivot: [f64; 3],
    /// Translation T, m.
    pub translation: [f64; 3],
}

impl Pose {
    /// No displacement.
    pub const IDENTITY: Pose = Pose {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        pivot: [0.0; 3],
        translation: [0.0; 3],
    };

    /// Where a point `x` of the rest placement is, m.
    pub fn point(&self, x: [f64; 3]) -> [f64; 3] {
        vec3::add(vec3::add(self.vector(vec3::sub(x, self.pivot)), self.pivot), self.translation)
    }

    /// A direction (normal) `d` of the rest placement, turned: R d.
    pub fn vector(&self, d: [f64; 3]) -> [f64; 3] {
        self.rotation.map(|row| vec3::dot(row, d))
    }

    /// The rest placement's point that is now at `x`: Rᵀ (x − c − T) + c.
    pub fn point_back(&self, x: [f64; 3]) -> [f64; 3] {
        vec3::add(
            self.vector_back(vec3::sub(vec3::sub(x, self.pivot), self.translation)),
            self.pivot,
        )
    }

    /// Rᵀ d.
    pub fn vector_back(&self, d: [f64; 3]) -> [f64; 3] {
        let r = &self.rotation;
        [0, 1, 2].map(|k| r[0][k] * d[0] + r[1][k] * d[1] + r[2][k] * d[2])
    }

    /// Whether it turns anything (R ≠ I).
    pub fn rotates(&self) -> bool {
        self.rotation != Pose::IDENTITY.rotation
    }
}

/// The velocity field of a rigid surface: u(x) = `linear` + `angular` × (x − `center`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SurfaceVelocity {
    /// Velocity of the point `center`, m/s.
    pub linear: [f64; 3],
    /// Angular velocity ω, rad/s.
    pub angular: [f64; 3],
    /// The point the rotation turns about now, m.
    pub center: [f64; 3],
}

impl SurfaceVelocity {
    /// The surface's velocity at point `x` (m), m/s.
    pub fn at(&self, x: [f64; 3]) -> [f64; 3] {
        vec3::add(self.linear, vec3::cross(self.angular, vec3::sub(x, self.center)))
    }

    /// Where a point `x` (m) near the surface `back` s before it reaches this placement is
    /// seen from this placement: the surface's motion over those `back` s, steady at this
    /// field, applied to x. A translation adds V back; a turn also turns x by ω back about
    /// the centre where it was then, c − V back:
    ///
    /// ```text
    ///   x' = c + R(ω back) (x − c + V back)
    /// ```
    ///
    /// (for a point of the surface itself, where that point is now: the continuous detection
    /// sees a particle's path from the collider placed at the step's end through this map).
    pub fn moved_with(&self, x: [f64; 3], back: f64) -> [f64; 3] {
        if self.angular == [0.0; 3] {
            return vec3::add(x, vec3::scale(back, self.at(x)));
        }
        let turn = rotation_of_vector(vec3::scale(back, self.angular));
        let d = vec3::add(vec3::sub(x, self.center), vec3::scale(back, self.linear));
        vec3::add(self.center, turn.map(|row| vec3::dot(row, d)))
    }

    /// Whether the surface is still.
    pub fn is_still(&self) -> bool {
        self.linear == [0.0; 3] && self.angular == [0.0; 3]
    }
}

/// A prescribed motion (see the module's doc).
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// Constant velocity V (m/s) and angular velocity ω (rad/s) about `pivot` (m), from the
    /// time `start` (s, on the world's clock) on; before it the collider rests where it
    /// was added: T = V (t − t_s), R = exp((t − t_s) [ω]×) for t ≥ t_s.
    Steady {
        /// V, m/s.
        velocity: [f64; 3],
        /// ω, rad/s.
        angular_velocity: [f64; 3],
        /// c, m.
        pivot: [f64; 3],
        /// t_s, s.
        start: f64,
    },
    /// Keyframes: at `times[k]` (s, increasing) the collider is displaced by `translations[k]`
    /// (m) and turned by the unit quaternion `rotations[k]` (w, x, y, z) about `pivot` (m).
    Keyframes {
        /// t_k, s.
        times: Vec<f64>,
        /// T_k, m.
        translations: Vec<[f64; 3]>,
        /// R_k as unit quaternions (w, x, y, z), each on the same hemisphere as the one
        /// before it (the shorter way round).
        rotations: Vec<[f64; 4]>,
        /// c, m.
        pivot: [f64; 3],
    },
}

impl Motion {
    /// A steady motion; the values must be finite.
    pub fn steady(velocity: [f64; 3], angular_velocity: [f64; 3], pivot: [f64; 3]) -> Result<Motion, Error> {
        for (name, v) in [
            ("velocity", velocity),
            ("angular_velocity", angular_velocity),
            ("pivot", pivot),
        ] {
            if let Some((k, value)) = vec3::first_non_finite(&v) {
                return Err(Error::invalid(
                    format!("{name}[{k}]"),
                    value,
                    "a collider's motion must be finite",
                ));
            }
        }
        Ok(Motion::Steady {
            velocity,
            angular_velocity,
            pivot,
            start: 0.0,
        })
    }

    /// This steady motion started at `start` (s, finite) instead of the world's time 0: the
    /// collider rests where it was added until then (keyframes keep their own times: refused).
    pub fn starting_at(self, start: f64) -> Result<Motion, Error> {
        if !start.is_finite() {
            return Err(Error::invalid("start", start, "a motion's start must be a finite time, s"));
        }
        match self {
            Motion::Steady {
                velocity,
                angular_velocity,
                pivot,
                ..
            } => Ok(Motion::Steady {
                velocity,
                angular_velocity,
                pivot,
                start,
            }),
            Motion::Keyframes { .. } => Err(Error::invalid(
                "start",
                start,
                "keyframes start at their first time: shift the times instead",
            )),
        }
    }

    /// Keyframes at `times` (s, finite, strictly increasing, at least one) of `translations`
    /// (m) and `rotations` (quaternions w, x, y, z, non-zero; normalised here) about `pivot`.
    pub fn keyframes(
        times: Vec<f64>,
        translations: Vec<[f64; 3]>,
        rotations: Vec<[f64; 4]>,
        pivot: [f64; 3],
    ) -> Result<Motion, Error> {
        let n = times.len();
        if n == 0 {
            return Err(Error::invalid("times", "[]", "keyframes need at least one time"));
        }
        for (name, len) in [("translations", translations.len()), ("rotations", rotations.len())] {
            if len != n {
                return Err(Error::invalid(
                    name,
                    format!("{len} values"),
                    format!("one per keyframe time ({n})"),
                ));
            }
        }
        for (k, &t) in times.iter().enumerate() {
            if !t.is_finite() || (k > 0 && t <= times[k - 1]) {
                return Err(Error::invalid(
                    format!("times[{k}]"),
                    t,
                    "keyframe times must be finite and strictly increasing, s",
                ));
            }
        }
        for (k, p) in translations.iter().enumerate() {
            if let Some((c, value)) = vec3::first_non_finite(p) {
                return Err(Error::invalid(format!("translations[{k}][{c}]"), value, "must be finite, m"));
            }
        }
        if let Some((k, value)) = vec3::first_non_finite(&pivot) {
            return Err(Error::invalid(format!("pivot[{k}]"), value, "must be finite, m"));
        }
        let mut unit: Vec<[f64; 4]> = Vec::with_capacity(n);
        for (k, q) in rotations.iter().enumerate() {
            let len = q.iter().map(|c| c * c).sum::<f64>().sqrt();
            if !(len.is_finite() && len > 0.0) {
                return Err(Error::invalid(
                    format!("rotations[{k}]"),
                    format!("{q:?}"),
                    "a rotation is a finite, non-zero quaternion (w, x, y, z)",
                ));
            }
            let mut u = q.map(|c| c / len);
            if let Some(prev) = unit.last() {
                if prev.iter().zip(&u).map(|(a, b)| a * b).sum::<f64>() < 0.0 {
                    u = u.map(|c| -c);
                }
            }
            unit.push(u);
        }
        Ok(Motion::Keyframes {
            times,
            translations,
            rotations: unit,
            pivot,
        })
    }

    /// Whether the collider moves at some time within [t0, t1] (s): a steady motion with a
    /// velocity or an angular velocity always, keyframes between their first key and their
    /// last (before the first and after the last the collider rests at them).
    pub fn moves_within(&self, t0: f64, t1: f64) -> bool {
        match self {
            Motion::Steady {
                velocity,
                angular_velocity,
                start,
                ..
            } => (*velocity != [0.0; 3] || *angular_velocity != [0.0; 3]) && t1 > *start,
            Motion::Keyframes { times, .. } => t1 > times[0] && t0 < times[times.len() - 1],
        }
    }

    /// The displacement at the step's end `t1` (s) and the surface's velocity field over the
    /// step from `t0`: a steady motion's own (once started); for keyframes, and a steady
    /// motion that starts within the step, the steady field that moves the
    /// collider from where it is at t0 to where it is at t1 (its chord: V = (T₁ − T₀)/h, ω
    /// the turn R₁ R₀ᵀ over h), so that a key inside the step, or a jump of many metres
    /// between two keys within it, is swept as the displacement it makes, not as the
    /// velocity it has at t1 (none once the last key is passed).
    pub fn over(&self, t0: f64, t1: f64) -> (Pose, SurfaceVelocity) {
        let (pose, velocity) = self.at(t1);
        let h = t1 - t0;
        let steady_through = matches!(self, Motion::Steady { start, .. } if t0 >= *start);
        if steady_through || h.is_nan() || h <= 0.0 || !self.moves_within(t0, t1) {
            return (pose, velocity);
        }
        let (start, _) = self.at(t0);
        let linear = vec3::scale(1.0 / h, vec3::sub(pose.translation, start.translation));
        let turn = turn_vector(relative_rotation(start.rotation, pose.rotation));
        let field = SurfaceVelocity {
            linear,
            angular: vec3::scale(1.0 / h, turn),
            center: velocity.center,
        };
        (pose, field)
    }

    /// The displacement at time `t` (s) and the surface's velocity field then.
    pub fn at(&self, t: f64) -> (Pose, SurfaceVelocity) {
        match self {
            Motion::Steady {
                velocity,
                angular_velocity,
                pivot,
                start,
            } => {
                if t < *start {
                    let rest = SurfaceVelocity {
                        center: *pivot,
                        ..SurfaceVelocity::default()
                    };
                    return (
                        Pose {
                            pivot: *pivot,
                            ..Pose::IDENTITY
                        },
                        rest,
                    );
                }
                // (t − 0.0 is t: a motion from the world's time 0 keeps its bits)
                let t = t - *start;
                let translation = vec3::scale(t, *velocity);
                let pose = Pose {
                    rotation: rotation_of_vector(vec3::scale(t, *angular_velocity)),
                    pivot: *pivot,
                    translation,
                };
                let velocity = SurfaceVelocity {
                    linear: *velocity,
                    angular: *angular_velocity,
                    center: vec3::add(*pivot, translation),
                };
                (pose, velocity)
            }
            Motion::Keyframes {
                times,
                translations,
                rotations,
                pivot,
            } => {
                let n = times.len();
                let still = |k: usize| {
                    let pose = Pose {
                        rotation: rotation_of_quaternion(rotations[k]),
                        pivot: *pivot,
                        translation: translations[k],
                    };
                    (
                        pose,
                        SurfaceVelocity {
                            center: vec3::add(*pivot, translations[k]),
                            ..SurfaceVelocity::default()
                        },
                    )
                };
                if t <= times[0] {
                    return still(0);
                }
                if t >= times[n - 1] {
                    return still(n - 1);
                }
                let k = times.partition_point(|&tk| tk <= t) - 1;
                let span = times[k + 1] - times[k];
                let s = (t - times[k]) / span;
                let (t0, t1) = (translations[k], translations[k + 1]);
                let translation = [0, 1, 2].map(|c| t0[c] + s * (t1[c] - t0[c]));
                let linear = [0, 1, 2].map(|c| (t1[c] - t0[c]) / span);
                // slerp: q(s) = q0 (q0⁻¹ q1)^s; the relative rotation q0⁻¹ q1 = (cos ½θ, sin ½θ a)
                // turns by θ about a, so ω = R0 a θ / span (in the world frame)
                let (q0, q1) = (rotations[k], rotations[k + 1]);
                let rel = quat_mul(quat_conj(q0), q1);
                let half = rel[1..].iter().map(|c| c * c).sum::<f64>().sqrt().atan2(rel[0]);
                let axis_sin = [rel[1], rel[2], rel[3]];
                let sin_half = vec3::norm(axis_sin);
                let (q, angular) = if sin_half > 0.0 {
                    let axis = vec3::scale(1.0 / sin_half, axis_sin);
                    let (sin, cos) = (s * half).sin_cos();
                    let part = [cos, axis[0] * sin, axis[1] * sin, axis[2] * sin];
                    let r0 = rotation_of_quaternion(q0);
                    let w_body = vec3::scale(2.0 * half / span, axis);
                    (quat_mul(q0, part), r0.map(|row| vec3::dot(row, w_body)))
                } else {
                    (q0, [0.0; 3])
                };
                let pose = Pose {
                    rotation: rotation_of_quaternion(q),
                    pivot: *pivot,
                    translation,
                };
                let velocity = SurfaceVelocity {
                    linear,
                    angular,
                    center: vec3::add(*pivot, translation),
                };
                (pose, velocity)
            }
        }
    }

    /// Whether it ever turns the collider.
    pub fn rotates(&self) -> bool {
        match self {
            Motion::Steady { angular_velocity, .. } => *angular_velocity != [0.0; 3],
            Motion::Keyframes { rotations, .. } => rotations.iter().any(|q| q[1] != 0.0 || q[2] != 0.0 || q[3] != 0.0),
        }
    }
}

/// R₁ R₀ᵀ: the turn from rotation R₀ to R₁ (rows).
fn relative_rotation(r0: [[f64; 3]; 3], r1: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    // (R₁ R₀ᵀ)_ij = Σ_k R₁_ik R₀_jk = row i of R₁ · row j of R₀
    r1.map(|row| [0, 1, 2].map(|j| vec3::dot(row, r0[j])))
}

/// The rotation vector θ (rad: the axis times the angle, in [0, π)) of a rotation matrix:
/// sin|θ| â from its skew part, cos|θ| from its trace.
fn turn_vector(r: [[f64; 3]; 3]) -> [f64; 3] {
    let w = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]];
    let sin = 0.5 * vec3::norm(w);
    if sin == 0.0 {
        return [0.0; 3];
    }
    let cos = 0.5 * (r[0][0] + r[1][1] + r[2][2] - 1.0);
    vec3::scale(sin.atan2(cos) / (2.0 * sin), w)
}

/// The rotation by the angle |θ| about θ/|θ| (Rodrigues: R = I + sin|θ| K + (1 − cos|θ|) K²,
/// K = [θ/|θ|]×).
pub fn rotation_of_vector(theta: [f64; 3]) -> [[f64; 3]; 3] {
    let angle = vec3::norm(theta);
    if angle == 0.0 {
        return Pose::IDENTITY.rotation;
    }
    let (s, c) = ((0.5 * angle).sin(), (0.5 * angle).cos());
    let a = vec3::scale(s / angle, theta);
    rotation_of_quaternion([c, a[0], a[1], a[2]])
}

/// The rotation matrix of the unit quaternion (w, x, y, z).
pub fn rotation_of_quaternion(q: [f64; 4]) -> [[f64; 3]; 3] {
    let [w, x, y, z] = q;
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

fn quat_mul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

fn quat_conj(q: [f64; 4]) -> [f64; 4] {
    [q[0], -q[1], -q[2], -q[3]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_steady_turn_moves_points_on_circles_at_omega_r() {
        // ω = 2 rad/s about z through (1, 0, 0): the point (2, 0, 0) at t = π/4 has turned by
        // π/2 to (1, 1, 0), and its speed is ω r = 2 m/s along +y at the start.
        let m = Motion::steady([0.0; 3], [0.0, 0.0, 2.0], [1.0, 0.0, 0.0]).unwrap();
        let (pose, vel) = m.at(std::f64::consts::FRAC_PI_4);
        let p = pose.point([2.0, 0.0, 0.0]);
        assert!(
            (p[0] - 1.0).abs() < 1e-15 && (p[1] - 1.0).abs() < 1e-15 && p[2] == 0.0,
            "{p:?}"
        );
        assert_eq!(m.at(0.0).1.at([2.0, 0.0, 0.0]), [0.0, 2.0, 0.0]);
        // the velocity at the turned point is tangent to its circle: (−2, 0, 0)
        let u = vel.at(p);
        assert!((u[0] + 2.0).abs() < 1e-15 && u[1].abs() < 1e-15, "{u:?}");
        // back and forth
        let back = pose.point_back(p);
        assert!((back[0] - 2.0).abs() < 1e-15 && back[1].abs() < 1e-15, "{back:?}");
    }

    #[test]
    fn keyframes_interpolate_and_hold() {
        // 0 s: at rest; 2 s: moved by (2, 0, 0) and turned 90° about z (q = (cos 45°, 0, 0, sin 45°))
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let m = Motion::keyframes(
            vec![0.0, 2.0],
            vec![[0.0; 3], [2.0, 0.0, 0.0]],
            vec![[1.0, 0.0, 0.0, 0.0], [h, 0.0, 0.0, h]],
            [0.0; 3],
        )
        .unwrap();
        let (pose, vel) = m.at(1.0);
        assert_eq!(pose.translation, [1.0, 0.0, 0.0]);
        // half way: 45° about z, at the constant ω = (π/2)/2 s
        let p = pose.vector([1.0, 0.0, 0.0]);
        assert!((p[0] - h).abs() < 1e-15 && (p[1] - h).abs() < 1e-15, "{p:?}");
        assert_eq!(vel.linear, [1.0, 0.0, 0.0]);
        assert!(
            (vel.angular[2] - std::f64::consts::FRAC_PI_4).abs() < 1e-15,
            "{:?}",
            vel.angular
        );
        // before and after: held, still
        assert_eq!(m.at(-1.0).0, Pose::IDENTITY);
        assert!(m.at(5.0).1.is_still());
        assert_eq!(m.at(5.0).0.translation, [2.0, 0.0, 0.0]);
        let e = Motion::keyframes(vec![0.0, 0.0], vec![[0.0; 3]; 2], vec![[1.0, 0.0, 0.0, 0.0]; 2], [0.0; 3])
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("times[1] = 0 is invalid"), "{e}");
    }
}
