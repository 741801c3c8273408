//! Particles: struct of arrays — positions, velocities, masses, radii, ids, and with spin
//! their angular velocities and moments of inertia.

use crate::error::Error;
use crate::limits::GEOMETRY_LIMIT;

/// The particles of a world, one entry per particle in each array; vectors are stored
/// flat, x y z per particle (`x[3i..3i+3]`).
///
/// A pinned particle keeps its mass `mass[i]` (for gravity, energies and momenta of the
/// forces acting on it) but has inverse mass `inv_mass[i] = 0`: no force moves it, as if its
/// inertia were infinite.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Particles {
    /// Positions, m (3 per particle).
    pub x: Vec<f64>,
    /// Velocities, m/s (3 per particle).
    pub v: Vec<f64>,
    /// Masses, kg (> 0, finite).
    pub mass: Vec<f64>,
    /// Inverse masses, 1/kg: 1/mass, or 0 for a pinned particle.
    pub inv_mass: Vec<f64>,
    /// Radii, m (≥ 0; 0 for point particles).
    pub radius: Vec<f64>,
    /// Stable identifiers, in the order of creation; never reused, not even after the
    /// particle with the highest one is removed.
    pub id: Vec<u64>,
    /// The id the next particle added gets.
    pub next_id: u64,
    /// With spin ([`Particles::enable_spin`]): angular velocities, rad/s (3 per particle; a
    /// 2D world turns about z only); empty without.
    pub omega: Vec<f64>,
    /// With spin: each particle's orientation, a unit quaternion (w, x, y, z) (4 per
    /// particle), the identity when it was added, turned each step by the step's angular
    /// velocity ([`turn_orientations`]); empty without spin.
    pub orientation: Vec<f64>,
    /// With spin: the angular accelerations at the current state, rad/s² (3 per particle):
    /// velocity Verlet's carry under the contacts' torques (`collide/contact_force/verlet.rs`),
    /// zero where nothing turns them; empty without spin.
    pub alpha: Vec<f64>,
    /// With spin: moments of inertia about the centre, kg·m² (≥ 0, one per particle); empty
    /// without.
    pub inertia: Vec<f64>,
    /// With spin: inverse moments of inertia, 1/(kg·m²): 1/I, or 0 for a pinned particle and
    /// for a particle without inertia (a point: no contact can turn it); empty without.
    pub inv_inertia: Vec<f64>,
    /// With spin: I / (m r²) of a particle added without its own inertia: 2/5 for a solid
    /// sphere (3D), 1/2 for a disc (2D); 0 without spin.
    pub inertia_factor: f64,
    /// Collision groups, 0..32 (`collide/groups.rs`), one per particle; empty while every
    /// particle is in group 0 (no byte spent on them).
    pub group: Vec<u8>,
}

/// In a `new_of_old` map of [`Particles::retain`]: the particle was removed (defined in
/// [`crate::limits`], which the contacts share; kept here under its old name).
pub use crate::limits::GONE;

impl Particles {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.mass.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// About how much memory a world needs per particle (its state, the integrator's
    /// buffers, the neighbour lists), bytes: measured 400–800 with 10⁶ particles.
    pub const BYTES_PER_PARTICLE: usize = 1024;

    /// Appends particles and returns their indices. `x`, `v` hold 3 values per particle;
    /// `mass`, `radius`, `pinned` one each. Errors name the first bad value; room the
    /// machine cannot give ([`Particles::BYTES_PER_PARTICLE`] each) is
    /// [`Error::OutOfMemory`].
    pub fn add(
        &mut self,
        x: &[f64],
        v: &[f64],
        mass: &[f64],
        radius: &[f64],
        pinned: &[bool],
    ) -> Result<std::ops::Range<usize>, Error> {
        let n = mass.len();
        let check_len = |name: &str, got: usize, per: usize| {
            if got == per * n {
                Ok(())
            } else {
                Err(Error::invalid(
                    name,
                    format!("{got} values"),
                    format!("{per} per particle for {n} particles ({} values)", per * n),
                ))
            }
        };
        check_len("position", x.len(), 3)?;
        check_len("velocity", v.len(), 3)?;
        check_len("radius", radius.len(), 1)?;
        check_len("pinned", pinned.len(), 1)?;
        check_state(["position", "velocity", "mass"], x, v, mass, None)?;
        if let Some(i) = radius.iter().position(|r| !(*r >= 0.0 && *r <= GEOMETRY_LIMIT)) {
            return Err(Error::invalid(
                format!("radius[{i}]"),
                radius[i],
                "radii must be finite, >= 0 m and <= 1e150 m (collisions square distances)",
            ));
        }
        // Room first, so that a size the machine cannot hold is an error, not an abort.
        let room = |bytes: usize, ok: bool| -> Result<(), Error> {
            ok.then_some(())
                .ok_or_else(|| Error::out_of_memory(format!("adding {n} particles"), bytes))
        };
        let total = (self.len() + n).saturating_mul(Self::BYTES_PER_PARTICLE);
        room(total, self.x.try_reserve(3 * n).is_ok() && self.v.try_reserve(3 * n).is_ok())?;
        room(
            total,
            self.mass.try_reserve(n).is_ok()
                && self.inv_mass.try_reserve(n).is_ok()
                && self.radius.try_reserve(n).is_ok()
                && self.id.try_reserve(n).is_ok(),
        )?;
        // and the world's working memory for them (integration, neighbour lists, collisions),
        // tried once: the step would abort on it otherwise
        room(total, Vec::<u8>::new().try_reserve_exact(total).is_ok())?;
        let start = self.len();
        let first_id = self.next_id;
        self.next_id += n as u64;
        self.x.extend_from_slice(x);
        self.v.extend(
            v.iter()
                .zip(pinned.iter().flat_map(|p| [*p; 3]))
                .map(|(v, p)| if p { 0.0 } else { *v }),
        );
        self.mass.extend_from_slice(mass);
        self.inv_mass
            .extend(mass.iter().zip(pinned).map(|(m, p)| if *p { 0.0 } else { 1.0 / m }));
        self.radius.extend_from_slice(radius);
        self.id.extend((0..n as u64).map(|k| first_id + k));
        if self.has_spin() {
            // at rest, unturned, with the inertia of a solid sphere (a disc in 2D)
            self.omega.resize(3 * self.len(), 0.0);
            let all = self.len();
            identities(&mut self.orientation, all);
            self.alpha.resize(3 * self.len(), 0.0);
            let f = self.inertia_factor;
            self.inertia.extend(mass.iter().zip(radius).map(|(m, r)| f * m * r * r));
            for q in start..start + n {
                self.inv_inertia
                    .push(Self::inverse_inertia(self.inertia[q], self.inv_mass[q]));
            }
        }
        if !self.group.is_empty() {
            self.group.resize(self.len(), 0);
        }
        Ok(start..start + n)
    }

    /// Whether the particles have spin (angular velocities and moments of inertia).
    pub fn has_spin(&self) -> bool {
        self.inertia_factor > 0.0
    }

    /// Gives every particle, now and later, an angular velocity (0 to start) and a moment of
    /// inertia `factor` m r² (2/5: solid spheres in 3D; 1/2: discs in 2D), or takes them away
    /// (`factor` 0). A no-op if spin is already on with this factor.
    pub fn enable_spin(&mut self, factor: f64) {
        if factor == self.inertia_factor {
            return;
        }
        self.inertia_factor = factor;
        self.omega.clear();
        self.orientation.clear();
        self.alpha.clear();
        self.inertia.clear();
        self.inv_inertia.clear();
        if factor > 0.0 {
            self.omega.resize(3 * self.len(), 0.0);
            let n = self.len();
            identities(&mut self.orientation, n);
            self.alpha.resize(3 * self.len(), 0.0);
            self.inertia
                .extend(self.mass.iter().zip(&self.radius).map(|(m, r)| factor * m * r * r));
            self.inv_inertia.extend(
                self.inertia
                    .iter()
                    .zip(&self.inv_mass)
                    .map(|(&i, &w)| Self::inverse_inertia(i, w)),
            );
        }
    }

    /// 1/I, or 0 for a pinned particle (`inv_mass` 0) or one without inertia.
    fn inverse_inertia(inertia: f64, inv_mass: f64) -> f64 {
        if inv_mass == 0.0 || inertia == 0.0 {
            0.0
        } else {
            1.0 / inertia
        }
    }

    /// Sets the angular velocities (rad/s, 3 per particle) and moments of inertia (kg·m², one
    /// per particle) of the particles `range`, where given; needs spin. A pinned particle
    /// keeps ω = 0. In 2D (`dim` 2) ω turns about z only. Errors name the first bad value.
    pub fn set_spin(
        &mut self,
        range: std::ops::Range<usize>,
        omega: Option<&[f64]>,
        inertia: Option<&[f64]>,
        dim: usize,
    ) -> Result<(), Error> {
        if !self.has_spin() {
            return Err(Error::invalid(
                "angular_velocity",
                "given",
                "a world without spin has none: turn spin on first (World(spin=True), [world] spin = true)",
            ));
        }
        Self::check_spin(range.len(), omega, inertia, dim)?;
        for (k, q) in range.enumerate() {
            if let Some(i) = inertia {
                self.inertia[q] = i[k];
                self.inv_inertia[q] = Self::inverse_inertia(i[k], self.inv_mass[q]);
            }
            if let Some(w) = omega.filter(|_| self.inv_mass[q] > 0.0) {
                self.omega[3 * q..3 * q + 3].copy_from_slice(&w[3 * k..3 * k + 3]);
            }
        }
        Ok(())
    }

    /// The checks of [`Particles::set_spin`] on the values for `n` particles: 3 finite
    /// components each (x, y zero in 2D), inertias finite and ≥ 0.
    pub fn check_spin(n: usize, omega: Option<&[f64]>, inertia: Option<&[f64]>, dim: usize) -> Result<(), Error> {
        if let Some(w) = omega {
            check_per_particle("angular_velocity", w.len(), 3, n, "particles")?;
            if let Some(k) = w.iter().position(|c| !c.is_finite()) {
                return Err(Error::invalid(
                    format!("angular_velocity[{}][{}]", k / 3, k % 3),
                    w[k],
                    "angular velocities must be finite, rad/s",
                ));
            }
            if dim == 2 {
                if let Some(k) = w.chunks(3).position(|c| c[0] != 0.0 || c[1] != 0.0) {
                    return Err(Error::invalid(
                        format!("angular_velocity[{k}]"),
                        format!("{:?}", &w[3 * k..3 * k + 3]),
                        "a 2D world turns about z only: the x and y components must be 0",
                    ));
                }
            }
        }
        if let Some(i) = inertia {
            check_per_particle("inertia", i.len(), 1, n, "particles")?;
            if let Some(k) = i.iter().position(|c| !(c.is_finite() && *c >= 0.0)) {
                return Err(Error::invalid(
                    format!("inertia[{k}]"),
                    i[k],
                    "moments of inertia must be finite and >= 0 kg m^2",
                ));
            }
        }
        Ok(())
    }

    /// Keeps the particles where `keep[i]` holds, in their order, and removes the others;
    /// returns `new_of_old`: each particle's new index, or [`GONE`]. The ids stay with their
    /// particles (and are never given again).
    pub fn retain(&mut self, keep: &[bool]) -> Vec<u32> {
        assert_eq!(keep.len(), self.len(), "one flag per particle");
        let mut next = 0u32;
        let new_of_old: Vec<u32> = keep
            .iter()
            .map(|&k| {
                if k {
                    next += 1;
                    next - 1
                } else {
                    GONE
                }
            })
            .collect();
        for v in [&mut self.x, &mut self.v] {
            retain_rows(v, 3, keep);
        }
        retain_rows(&mut self.omega, 3, keep);
        retain_rows(&mut self.orientation, 4, keep);
        retain_rows(&mut self.alpha, 3, keep);
        for v in [
            &mut self.mass,
            &mut self.inv_mass,
            &mut self.radius,
            &mut self.inertia,
            &mut self.inv_inertia,
        ] {
            retain_rows(v, 1, keep);
        }
        retain_rows(&mut self.id, 1, keep);
        retain_rows(&mut self.group, 1, keep);
        new_of_old
    }

    /// Whether particle i is pinned.
    pub fn is_pinned(&self, i: usize) -> bool {
        self.inv_mass[i] == 0.0
    }
}

/// Keeps the rows (of `width` values each) of `a` where `keep` holds; a buffer not in use
/// (of another length) is left alone.
/// Checks that the flat array `name` (length `len`) holds `per` values for each of `n`
/// particles, `counted` saying what gave n ("radii", "particles", "inverse masses"), so that
/// a kernel can index it without panicking. The error names the array, its length and the
/// length it must have. The one check behind every kernel's per-particle buffers.
pub(crate) fn check_per_particle(name: &str, len: usize, per: usize, n: usize, counted: &str) -> Result<(), Error> {
    if len != per * n {
        return Err(Error::invalid(
            name,
            format!("{len} values"),
            format!("{per} per particle ({} for the {n} {counted})", per * n),
        ));
    }
    Ok(())
}

pub(crate) fn retain_rows<T: Copy>(a: &mut Vec<T>, width: usize, keep: &[bool]) {
    if a.len() != width * keep.len() {
        return;
    }
    let mut row = 0;
    a.retain(|_| {
        let k = keep[row / width];
        row += 1;
        k
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pinned_particles_keep_their_mass_and_lose_their_velocity() {
        let mut p = Particles::default();
        let r = p.add(&[0.0; 6], &[1.0; 6], &[2.0, 3.0], &[0.1, 0.2], &[false, true]).unwrap();
        assert_eq!(r, 0..2);
        assert_eq!(p.inv_mass, vec![0.5, 0.0]);
        assert_eq!(p.mass, vec![2.0, 3.0]);
        assert_eq!(&p.v[3..], &[0.0; 3]);
        assert!(p.is_pinned(1) && !p.is_pinned(0));
        let r = p.add(&[0.0; 3], &[0.0; 3], &[1.0], &[0.0], &[false]).unwrap();
        assert_eq!(r, 2..3);
        assert_eq!(p.id, vec![0, 1, 2]);
    }

    #[test]
    fn removed_particles_take_their_values_and_ids_with_them() {
        let mut p = Particles::default();
        let x: Vec<f64> = (0..9).map(f64::from).collect();
        p.add(&x, &x, &[1.0, 2.0, 3.0], &[0.1, 0.2, 0.3], &[false; 3]).unwrap();
        let new_of_old = p.retain(&[true, false, false]);
        assert_eq!(new_of_old, vec![0, GONE, GONE]);
        assert_eq!(
            (p.x.as_slice(), p.mass.as_slice(), p.id.as_slice()),
            (&x[..3], &[1.0][..], &[0][..])
        );
        // the highest id (2) is gone, and still never given again
        p.add(&[0.0; 3], &[0.0; 3], &[4.0], &[0.4], &[false]).unwrap();
        assert_eq!(p.id, vec![0, 3]);
        assert_eq!(p.retain(&[false, true]), vec![GONE, 0]);
        assert_eq!((p.radius.as_slice(), p.inv_mass.as_slice()), (&[0.4][..], &[0.25][..]));
    }

    #[test]
    fn bad_values_are_named() {
        let mut p = Particles::default();
        let e = p
            .add(&[0.0; 3], &[0.0; 3], &[-1.0], &[0.0], &[false])
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("mass[0] = -1 is invalid"), "{e}");
        let e = p
            .add(&[0.0, f64::NAN, 0.0], &[0.0; 3], &[1.0], &[0.0], &[false])
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("position[0][1] = NaN is invalid"), "{e}");
        assert!(p.is_empty());
    }
}

/// Grows `orientation` (4 per particle) to `n` particles with the identity (1, 0, 0, 0).
fn identities(orientation: &mut Vec<f64>, n: usize) {
    while orientation.len() < 4 * n {
        orientation.extend_from_slice(&[1.0, 0.0, 0.0, 0.0]);
    }
}

/// Turns each orientation q (4 per particle, (w, x, y, z)) by a step of h (s) at the mean of
/// the angular velocities at its start and end, ω̄ = (ω₀ + ω₁)/2 (rad/s, 3 per particle, world
/// frame): q ← (cos x, sin x ω̂) ⊗ q with x = h |ω̄| / 2, the rotation by 2x about ω̂ that
/// a constant ω̄ makes in h (exact for a ball that rolls at a steady spin; second order in h
/// where ω changes).
///
/// It runs for every particle of every step, so it is kept to multiplications: cos x and
/// sin(x)/x come from their Taylor series in x² to x⁶ where x < 0.01 (the first term left
/// out, x⁸/8!, is under 3e-21: exact to rounding; a granular step turns a grain far less),
/// with no square root, else from `sin_cos`; and the product is brought back to unit length
/// by one Newton step, q (3 − |q|²)/2, whose error is the square of the rounding it removes
/// (with the trigonometric functions, a square root and divisions this took a ninth of a
/// spinning Hertz pile's step).
pub fn turn_orientations(orientation: &mut [f64], omega0: &[f64], omega1: &[f64], h: f64) {
    let half = 0.5 * h;
    for (q, (w0, w1)) in orientation
        .chunks_exact_mut(4)
        .zip(omega0.chunks_exact(3).zip(omega1.chunks_exact(3)))
    {
        let w = [0.5 * (w0[0] + w1[0]), 0.5 * (w0[1] + w1[1]), 0.5 * (w0[2] + w1[2])];
        let w2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        if w2 == 0.0 {
            continue;
        }
        let x2 = half * half * w2;
        let (c, s) = if x2 < 1e-4 {
            const C: [f64; 3] = [1.0 / 2.0, 1.0 / 12.0, 1.0 / 30.0];
            const S: [f64; 3] = [1.0 / 6.0, 1.0 / 20.0, 1.0 / 42.0];
            (
                1.0 - x2 * C[0] * (1.0 - x2 * C[1] * (1.0 - x2 * C[2])),
                1.0 - x2 * S[0] * (1.0 - x2 * S[1] * (1.0 - x2 * S[2])),
            )
        } else {
            let x = x2.sqrt();
            let (s, c) = x.sin_cos();
            (c, s / x)
        };
        let s = s * half; // sin(x) ω̂ = (sin x / x) (h/2) ω̄
        let d = [c, s * w[0], s * w[1], s * w[2]];
        // the Hamilton product d ⊗ q
        let t = [
            d[0] * q[0] - d[1] * q[1] - d[2] * q[2] - d[3] * q[3],
            d[0] * q[1] + d[1] * q[0] + d[2] * q[3] - d[3] * q[2],
            d[0] * q[2] - d[1] * q[3] + d[2] * q[0] + d[3] * q[1],
            d[0] * q[3] + d[1] * q[2] - d[2] * q[1] + d[3] * q[0],
        ];
        let scale = 0.5 * (3.0 - (t[0] * t[0] + t[1] * t[1] + t[2] * t[2] + t[3] * t[3]));
        for k in 0..4 {
            q[k] = t[k] * scale;
        }
    }
}

/// The one check of the particles' state as a caller writes it: the coordinates of `x` and
/// `v` (m, m/s; 3 per particle) finite and, in a 2D world (`dim` = `Some(2)`), with z = 0; the
/// masses finite and > 0 kg. `names` are the three as the caller names them (`position`,
/// `velocity`, `mass` for new particles, [`Particles::add`]; `positions`, `velocities`,
/// `masses` for a whole state written back, `World::write_state`), and the error names the
/// first bad value by them. (`dim` `None`: the caller checks z itself.)
pub fn check_state(names: [&str; 3], x: &[f64], v: &[f64], mass: &[f64], dim: Option<usize>) -> Result<(), Error> {
    for (name, values) in [(names[0], x), (names[1], v)] {
        if let Some(i) = values.iter().position(|c| !c.is_finite()) {
            return Err(Error::invalid(
                format!("{name}[{}][{}]", i / 3, i % 3),
                values[i],
                "coordinates must be finite",
            ));
        }
        if dim == Some(2) {
            if let Some(i) = values.chunks(3).position(|c| c.len() == 3 && c[2] != 0.0) {
                return Err(Error::invalid(
                    format!("{name}[{i}][2]"),
                    values[3 * i + 2],
                    "a 2D world keeps z = 0",
                ));
            }
        }
    }
    if let Some(i) = mass.iter().position(|m| !(m.is_finite() && *m > 0.0)) {
        return Err(Error::invalid(
            format!("{}[{i}]", names[2]),
            mass[i],
            "masses must be finite and > 0 kg (pin a particle to make it immovable)",
        ));
    }
    Ok(())
}
