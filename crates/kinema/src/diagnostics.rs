//! Diagnostics of a particle state: kinetic and potential energy, linear and angular momentum.

use rayon::prelude::*;

use crate::forces::{Force, State};

/// Energies (J) and momenta of one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostics {
    /// Time, s.
    pub t: f64,
    /// Kinetic energy Σ ½ m |v|², J.
    pub kinetic: f64,
    /// Potential energy of each conservative force, J, by force name in the order they were added.
    pub potential: Vec<(String, f64)>,
    /// Linear momentum Σ m v, kg·m/s.
    pub momentum: [f64; 3],
    /// Angular momentum about the origin, kg·m²/s: Σ m x × v, plus with spin each
    /// particle's own, Σ I ω (the sum that impulses at contact points conserve).
    pub angular_momentum: [f64; 3],
    /// With spin: the rotational kinetic energy Σ ½ I |ω|², J (0 without).
    pub rotational: f64,
    /// With spin: the particles' own angular momentum Σ I ω, kg·m²/s (0 without; part of
    /// `angular_momentum`).
    pub spin: [f64; 3],
    /// The kinetic tensor Σ m v ⊗ v, J (row-major 3 × 3): over a volume, the kinetic part of
    /// the pressure tensor (`Trajectory.pressure`); its trace is twice `kinetic`.
    pub kinetic_tensor: [f64; 9],
}

/// Particles per chunk of [`Diagnostics::measure`]'s sums (fixed: the same bits on any number
/// of threads).
const CHUNK: usize = 4096;

/// The sums over particles of one chunk (or of all, added chunk by chunk).
#[derive(Default)]
struct Sums {
    kinetic: f64,
    momentum: [f64; 3],
    angular: [f64; 3],
    /// The upper triangle of Σ m v ⊗ v (mirrored below by the caller).
    tensor: [f64; 9],
}

impl Sums {
    /// The sums over the particles of masses `mass`, positions `x` and velocities `v`.
    fn of(mass: &[f64], x: &[f64], v: &[f64]) -> Self {
        let mut s = Sums::default();
        for ((&m, x), v) in mass.iter().zip(x.chunks_exact(3)).zip(v.chunks_exact(3)) {
            s.kinetic += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            for (pk, vk) in s.momentum.iter_mut().zip(v) {
                *pk += m * vk;
            }
            // x × v
            s.angular[0] += m * (x[1] * v[2] - x[2] * v[1]);
            s.angular[1] += m * (x[2] * v[0] - x[0] * v[2]);
            s.angular[2] += m * (x[0] * v[1] - x[1] * v[0]);
            // m v ⊗ v: the upper triangle, mirrored below
            for (r, c) in [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)] {
                s.tensor[3 * r + c] += m * v[r] * v[c];
            }
        }
        s
    }

    /// Adds another chunk's sums.
    fn add(&mut self, other: &Sums) {
        self.kinetic += other.kinetic;
        let mine = self.momentum.iter_mut().chain(&mut self.angular).chain(&mut self.tensor);
        let theirs = other.momentum.iter().chain(&other.angular).chain(&other.tensor);
        for (a, b) in mine.zip(theirs) {
            *a += b;
        }
    }
}

/// Where [`Diagnostics::measure_copying`] writes the positions (m) and velocities (m/s) it
/// reads, 3 values per particle: particle i at place `place[i]` (a permutation of 0..N: the
/// user's index of the engine's particle i, `world/order.rs`), or at i itself without one.
pub struct StateCopy<'a> {
    /// Positions, m (3 N).
    x: &'a mut [f64],
    /// Velocities, m/s (3 N).
    v: &'a mut [f64],
    /// Each particle's place, a permutation of 0..N; `None`: its own index.
    place: Option<&'a [u32]>,
}

impl<'a> StateCopy<'a> {
    /// Particle i's position and velocity into `x` and `v` at i (3 N values each).
    pub fn new(x: &'a mut [f64], v: &'a mut [f64]) -> Self {
        StateCopy { x, v, place: None }
    }

    /// Particle i's position and velocity into `x` and `v` at `place[i]`. `place` must be a
    /// permutation of 0..N (the copy's chunks write at once, trusting that no two particles
    /// share a place): the world's order (`world/order.rs`) alone makes it.
    pub(crate) fn placed(x: &'a mut [f64], v: &'a mut [f64], place: &'a [u32]) -> Self {
        StateCopy {
            x,
            v,
            place: Some(place),
        }
    }

    /// The copy's rooms as pointers the chunks of `measure_copying` share, for N particles.
    ///
    /// Panics unless both rooms hold 3 N values and `place` (if given) N places (each below N:
    /// checked as it is written, `SharedCopy::put`).
    fn shared(self, n: usize) -> SharedCopy<'a> {
        assert!(
            self.x.len() == 3 * n && self.v.len() == 3 * n,
            "a copy of {n} particles' state needs 3 x {n} values"
        );
        assert!(self.place.is_none_or(|p| p.len() == n), "the places of {n} particles");
        SharedCopy {
            x: self.x.as_mut_ptr(),
            v: self.v.as_mut_ptr(),
            n,
            place: self.place,
            _rooms: std::marker::PhantomData,
        }
    }
}

/// A [`StateCopy`] whose rooms (3 `n` values each) the chunks write at once, each its own
/// particles' places.
struct SharedCopy<'a> {
    x: *mut f64,
    v: *mut f64,
    n: usize,
    place: Option<&'a [u32]>,
    _rooms: std::marker::PhantomData<&'a mut [f64]>,
}

// SAFETY: the chunks write through the pointers only at their own particles' places, each
// below N (`SharedCopy::put` asserts it), and distinct particles have distinct places
// (`place` is a permutation: `StateCopy::placed`), so no two threads write the same value
// and nobody reads the rooms while they are written (they are borrowed mutably for 'a).
unsafe impl Send for SharedCopy<'_> {}
unsafe impl Sync for SharedCopy<'_> {}

impl SharedCopy<'_> {
    /// Writes the chunk of particles from `first` on (positions `x`, velocities `v`, 3 each)
    /// at their places.
    fn put(&self, first: usize, x: &[f64], v: &[f64]) {
        match self.place {
            None => unsafe {
                // (their places are first.., contiguous)
                std::ptr::copy_nonoverlapping(x.as_ptr(), self.x.add(3 * first), x.len());
                std::ptr::copy_nonoverlapping(v.as_ptr(), self.v.add(3 * first), v.len());
            },
            Some(place) => {
                let place = &place[first..first + x.len() / 3];
                for ((&u, x), v) in place.iter().zip(x.chunks_exact(3)).zip(v.chunks_exact(3)) {
                    // (no other chunk has u)
                    assert!((u as usize) < self.n, "place {u} of {} particles", self.n);
                    let u = 3 * u as usize;
                    unsafe {
                        std::ptr::copy_nonoverlapping(x.as_ptr(), self.x.add(u), 3);
                        std::ptr::copy_nonoverlapping(v.as_ptr(), self.v.add(u), 3);
                    }
                }
            }
        }
    }
}

impl Diagnostics {
    /// Measures the state `s` under `forces`.
    ///
    /// The sums over the particles run in chunks of [`CHUNK`] on all threads, each chunk's
    /// sums added in chunk order: the same bits on any number of threads (and one chunk's
    /// serial sums below [`CHUNK`] particles). At 10⁶ particles: 1.4 ms on two threads, 2.9
    /// by the serial loop this replaced (a frame of `World.run` reads them once).
    pub fn measure(s: &State, forces: &[&dyn Force]) -> Self {
        Self::measure_copying(s, forces, None)
    }

    /// [`Diagnostics::measure`], the same bits, with the positions and velocities it reads
    /// written into `copy` on the way (`World.run`'s frame: one pass over the state instead of
    /// the sums' pass and a copy's).
    pub fn measure_copying(s: &State, forces: &[&dyn Force], copy: Option<StateCopy<'_>>) -> Self {
        let n = s.mass.len();
        let copy = copy.map(|c| c.shared(n));
        let mut total = Sums::default();
        for part in s
            .mass
            .par_chunks(CHUNK)
            .zip(s.x.par_chunks(3 * CHUNK))
            .zip(s.v.par_chunks(3 * CHUNK))
            .enumerate()
            .map(|(c, ((mass, x), v))| {
                if let Some(copy) = &copy {
                    copy.put(c * CHUNK, x, v);
                }
                Sums::of(mass, x, v)
            })
            .collect::<Vec<_>>()
        {
            total.add(&part);
        }
        let Sums {
            kinetic,
            momentum: p,
            angular: l,
            mut tensor,
        } = total;
        for (r, c) in [(1, 0), (2, 0), (2, 1)] {
            tensor[3 * r + c] = tensor[3 * c + r];
        }
        let potential = forces
            .iter()
            .filter_map(|f| f.potential_energy(s).map(|u| (f.name().to_string(), u)))
            .collect();
        Self {
            t: s.t,
            kinetic,
            potential,
            momentum: p,
            angular_momentum: l,
            rotational: 0.0,
            spin: [0.0; 3],
            kinetic_tensor: tensor,
        }
    }

    /// Adds the particles' spin: angular velocities `omega` (rad/s, 3 per particle) and
    /// moments of inertia `inertia` (kg·m², one per particle).
    pub fn with_spin(mut self, omega: &[f64], inertia: &[f64]) -> Self {
        for (w, &i) in omega.chunks_exact(3).zip(inertia) {
            self.rotational += 0.5 * i * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            for k in 0..3 {
                self.spin[k] += i * w[k];
            }
        }
        for k in 0..3 {
            self.angular_momentum[k] += self.spin[k];
        }
        self
    }

    /// Total potential energy, J.
    pub fn potential_total(&self) -> f64 {
        self.potential.iter().map(|(_, u)| u).sum()
    }

    /// Kinetic (translational and rotational) plus potential energy, J (the energy conserved
    /// by conservative forces).
    pub fn total_energy(&self) -> f64 {
        self.kinetic + self.rotational + self.potential_total()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kinetic_tensor_is_the_sum_of_m_v_v_and_its_trace_twice_the_kinetic_energy() {
        // m = 1, v = (1, 2, 3) and m = 2, v = (−1, 0, 2): Σ m v_r v_c by hand
        let (x, v, mass) = (vec![0.0; 6], vec![1.0, 2.0, 3.0, -1.0, 0.0, 2.0], vec![1.0, 2.0]);
        let d = Diagnostics::measure(
            &State {
                t: 0.0,
                x: &x,
                v: &v,
                mass: &mass,
            },
            &[],
        );
        let expected = [
            1.0 + 2.0,
            2.0 + 0.0,
            3.0 - 4.0, //
            2.0 + 0.0,
            4.0 + 0.0,
            6.0 + 0.0, //
            3.0 - 4.0,
            6.0 + 0.0,
            9.0 + 8.0,
        ];
        assert_eq!(d.kinetic_tensor, expected);
        assert_eq!(
            d.kinetic_tensor[0] + d.kinetic_tensor[4] + d.kinetic_tensor[8],
            2.0 * d.kinetic
        );
    }

    #[test]
    fn the_sums_in_chunks_are_the_same_bits_on_any_threads_and_the_plain_sums_to_rounding() {
        // 2.5 chunks of particles with masses, positions and velocities of mixed signs and
        // sizes (the chunked order rounds differently from one loop, never by more than a few
        // units in the last place of the sums of magnitudes)
        let n = 2 * CHUNK + CHUNK / 2;
        let value = |k: usize, scale: f64| scale * ((k as f64 * 0.618_033_988_7).fract() - 0.4);
        let mass: Vec<f64> = (0..n).map(|i| 1.0 + value(i, 1.5)).collect();
        let x: Vec<f64> = (0..3 * n).map(|k| value(k + 7, 40.0)).collect();
        let v: Vec<f64> = (0..3 * n).map(|k| value(k + 3, 9.0)).collect();
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &mass,
        };
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| Diagnostics::measure(&s, &[]))
        };
        let one = on(1);
        for threads in [2, 3] {
            assert_eq!(on(threads), one, "{threads} threads");
        }
        // one loop over all particles, as the closed form Σ ½ m |v|², Σ m v, Σ m x × v
        let (mut kinetic, mut p, mut l, mut scale) = (0.0, [0.0; 3], [0.0; 3], [0.0_f64; 3]);
        for i in 0..n {
            let (m, xi, vi) = (mass[i], &x[3 * i..3 * i + 3], &v[3 * i..3 * i + 3]);
            kinetic += 0.5 * m * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
            let cross = [
                xi[1] * vi[2] - xi[2] * vi[1],
                xi[2] * vi[0] - xi[0] * vi[2],
                xi[0] * vi[1] - xi[1] * vi[0],
            ];
            for k in 0..3 {
                p[k] += m * vi[k];
                l[k] += m * cross[k];
                scale[k] += (m * vi[k]).abs() + (m * cross[k]).abs();
            }
        }
        assert!((one.kinetic - kinetic).abs() <= 1e-14 * kinetic);
        for k in 0..3 {
            assert!((one.momentum[k] - p[k]).abs() <= 1e-14 * scale[k], "p[{k}]");
            assert!((one.angular_momentum[k] - l[k]).abs() <= 1e-14 * scale[k], "L[{k}]");
        }
    }
}
