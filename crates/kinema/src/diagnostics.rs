//! Diagnostics of a particle state: kinetic and potential energy, linear and angular momentum.

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

impl Diagnostics {
    /// Measures the state `s` under `forces`.
    pub fn measure(s: &State, forces: &[&dyn Force]) -> Self {
        let mut kinetic = 0.0;
        let mut p = [0.0; 3];
        let mut l = [0.0; 3];
        let mut tensor = [0.0; 9];
        for i in 0..s.len() {
            let m = s.mass[i];
            let x = &s.x[3 * i..3 * i + 3];
            let v = &s.v[3 * i..3 * i + 3];
            kinetic += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            for k in 0..3 {
                p[k] += m * v[k];
            }
            // x × v
            l[0] += m * (x[1] * v[2] - x[2] * v[1]);
            l[1] += m * (x[2] * v[0] - x[0] * v[2]);
            l[2] += m * (x[0] * v[1] - x[1] * v[0]);
            // m v ⊗ v: the upper triangle, mirrored below
            for (r, c) in [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)] {
                tensor[3 * r + c] += m * v[r] * v[c];
            }
        }
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
}
