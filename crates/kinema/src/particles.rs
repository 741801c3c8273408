//! Particles: struct of arrays — positions, velocities, masses, radii, ids.

use crate::collide::GEOMETRY_LIMIT;
use crate::error::Error;

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
    /// Stable identifiers, in the order of creation.
    pub id: Vec<u64>,
}

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
        for (name, values) in [("position", x), ("velocity", v)] {
            if let Some(i) = values.iter().position(|c| !c.is_finite()) {
                return Err(Error::invalid(
                    format!("{name}[{}][{}]", i / 3, i % 3),
                    values[i],
                    "coordinates must be finite",
                ));
            }
        }
        if let Some(i) = mass.iter().position(|m| !(m.is_finite() && *m > 0.0)) {
            return Err(Error::invalid(
                format!("mass[{i}]"),
                mass[i],
                "masses must be finite and > 0 kg (pin a particle to make it immovable)",
            ));
        }
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
        let first_id = self.id.last().map_or(0, |l| l + 1);
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
        Ok(start..start + n)
    }

    /// Whether particle i is pinned.
    pub fn is_pinned(&self, i: usize) -> bool {
        self.inv_mass[i] == 0.0
    }
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
