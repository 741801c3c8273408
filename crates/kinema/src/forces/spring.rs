//! Springs: Hooke springs with a dashpot along each, many in one force from index arrays.
//!
//! Spring s joins particles i and j. With d = x_j − x_i, L = |d|, n = d / L (unit, from i
//! toward j) and u = v_j − v_i,
//!
//! ```text
//!   F_i = [ k (L − L₀) + c (u·n) ] n,     F_j = −F_i
//! ```
//!
//! A stretched spring (L > L₀) pulls i toward j; separating ends (u·n > 0) are held back by
//! the dashpot. F_i is computed once and added to i and subtracted from j, so action equals
//! minus reaction to the last bit and the springs change no total momentum. The elastic part
//! has the potential ½ k (L − L₀)²; the dashpot's power is −c (u·n)² ≤ 0, it only dissipates.
//!
//! Coincident ends (L = 0) give no direction: such a spring adds no force. For L₀ = 0 this is
//! exact (the force k d vanishes with d); for L₀ > 0 the force is discontinuous there and
//! zero is the choice that adds no energy.

use rayon::prelude::*;
use std::sync::{Arc, Mutex};

use super::spring_pass::{Scratch, SpringArrays};
use super::{check_buffers, each_chunk, ChunkWork, EnergyClass, Force, Linearized, Properties, Rates, State};
use crate::error::{CallbackError, Error};
use crate::limits::GONE;
use crate::particles::retain_rows;
use crate::vec3::dot;

/// A set of damped springs between pairs of particles.
///
/// Spring s joins particles `i[s]` and `j[s]` (distinct) with stiffness `k[s]` (N/m, > 0),
/// rest length `rest_length[s]` (m, ≥ 0) and dashpot coefficient `damping[s]` (N·s/m = kg/s,
/// ≥ 0), all finite. The force on i is F_i = [k (L − L₀) + c (v_j − v_i)·n] n, N,
/// with n the unit vector from i to j and L their distance; F_j = −F_i. Potential energy
/// U = Σ ½ k (L − L₀)², J (the elastic part; the dashpot has none). Internal: the springs
/// change no total momentum.
#[derive(Debug, Clone, PartialEq)]
pub struct Springs {
    i: Vec<usize>,
    j: Vec<usize>,
    k: Vec<f64>,
    rest_length: Vec<f64>,
    damping: Vec<f64>,
    /// 1 + the largest index, the fewest particles the springs need (0 without springs).
    min_particles: usize,
    /// Buffers of the parallel force pass (not part of the springs' value).
    scratch: Scratch,
    /// The room of the Jacobian's blocks between linearisations (not part of the value).
    blocks: BlockRoom,
}

/// The room of the springs' Jacobian blocks, lent to each [`LinearizedSprings`] and given back
/// when it is dropped: an implicit step linearises the springs anew, and a cloth of 59,000
/// springs made 5 MB at each, which the system mapped and faulted in anew each time (blocks
/// that large get a mapping of their own: `kinema-py`'s `memory.rs`), 14 % of the step.
#[derive(Debug, Default)]
struct BlockRoom(Arc<Mutex<Vec<SpringBlock>>>);

impl BlockRoom {
    /// The room, empty (an empty one if another holds it).
    fn lend(&self) -> Vec<SpringBlock> {
        let mut blocks = self.0.lock().map(|mut room| std::mem::take(&mut *room)).unwrap_or_default();
        blocks.clear();
        blocks
    }
}

impl Clone for BlockRoom {
    /// A room of its own (a clone's linearisations do not wait on the original's).
    fn clone(&self) -> Self {
        BlockRoom::default()
    }
}

impl PartialEq for BlockRoom {
    fn eq(&self, _: &Self) -> bool {
        true // a buffer, not data
    }
}

impl Springs {
    /// Memory a spring takes, bytes: its ends and values (40), the force pass's buffers (an
    /// optional tension, 32; two end entries, 8; the springs placed by their lower end, 40),
    /// its block of the Jacobian when the step advice or an implicit method linearises the
    /// springs (a `SpringBlock`, 88) and the copies made while springs are added (the arrays
    /// handed over, 40): 248, rounded up.
    pub const BYTES_PER_SPRING: usize = 256;

    /// Whether the machine can give `count` springs their memory
    /// ([`Springs::BYTES_PER_SPRING`] each), tried once: [`Error::OutOfMemory`] where it
    /// cannot, before anything is built (a step would abort on it otherwise).
    pub fn room(count: usize) -> Result<(), Error> {
        let bytes = count.saturating_mul(Self::BYTES_PER_SPRING);
        match Vec::<u8>::new().try_reserve_exact(bytes) {
            Ok(()) => Ok(()),
            Err(_) => Err(Error::out_of_memory(format!("{count} springs"), bytes)),
        }
    }

    /// Springs from per-spring arrays (all of the same length): ends `i`, `j` (particle
    /// indices, i ≠ j), stiffness `k` (N/m, > 0), rest length `rest_length` (m, ≥ 0) and
    /// dashpot coefficient `damping` (N·s/m, ≥ 0), all finite. Errors name the array, the
    /// spring and the value. Indices are checked against the particles by
    /// [`Force::validate`].
    pub fn new(i: Vec<usize>, j: Vec<usize>, k: Vec<f64>, rest_length: Vec<f64>, damping: Vec<f64>) -> Result<Self, Error> {
        let count = i.len();
        for (name, len) in [
            ("j", j.len()),
            ("k", k.len()),
            ("rest_length", rest_length.len()),
            ("damping", damping.len()),
        ] {
            if len != count {
                return Err(Error::invalid(
                    name,
                    format!("{len} values"),
                    format!("one per spring ({count}, the length of i)"),
                ));
            }
        }
        for s in 0..count {
            if i[s] == j[s] {
                return Err(Error::invalid(
                    format!("j[{s}]"),
                    j[s],
                    format!(
                        "spring {s} joins particle {} to itself; its ends i[{s}] and j[{s}] must differ",
                        i[s]
                    ),
                ));
            }
            if !(k[s].is_finite() && k[s] > 0.0) {
                return Err(Error::invalid(
                    format!("k[{s}]"),
                    k[s],
                    "spring stiffness must be finite and > 0 N/m",
                ));
            }
            if !(rest_length[s].is_finite() && rest_length[s] >= 0.0) {
                return Err(Error::invalid(
                    format!("rest_length[{s}]"),
                    rest_length[s],
                    "rest lengths must be finite and >= 0 m",
                ));
            }
            if !(damping[s].is_finite() && damping[s] >= 0.0) {
                return Err(Error::invalid(
                    format!("damping[{s}]"),
                    damping[s],
                    "dashpot coefficients must be finite and >= 0 N·s/m",
                ));
            }
        }
        let min_particles = i.iter().chain(&j).map(|p| p + 1).max().unwrap_or(0);
        Ok(Springs {
            i,
            j,
            k,
            rest_length,
            damping,
            min_particles,
            scratch: Scratch::default(),
            blocks: BlockRoom::default(),
        })
    }

    /// Springs joining `i[s]` to `j[s]`, all with the same stiffness `k` (N/m, > 0), rest
    /// length `rest_length` (m, ≥ 0) and dashpot coefficient `damping` (N·s/m, ≥ 0).
    pub fn uniform(i: Vec<usize>, j: Vec<usize>, k: f64, rest_length: f64, damping: f64) -> Result<Self, Error> {
        let count = i.len();
        Springs::new(i, j, vec![k; count], vec![rest_length; count], vec![damping; count])
    }

    /// Springs at rest in the configuration `x` (m, 3 per particle): each rest length is the
    /// current distance |x_j − x_i|. Stiffness `k` (N/m, > 0) and dashpot coefficient
    /// `damping` (N·s/m, ≥ 0) are the same for all springs; indices must be < the number of
    /// particles in `x`.
    pub fn with_rest_from_positions(i: Vec<usize>, j: Vec<usize>, k: f64, damping: f64, x: &[f64]) -> Result<Self, Error> {
        if x.len() % 3 != 0 {
            return Err(Error::invalid(
                "x",
                format!("{} values", x.len()),
                "3 coordinates per particle",
            ));
        }
        if let Some(p) = x.iter().position(|c| !c.is_finite()) {
            return Err(Error::invalid(
                format!("x[{}][{}]", p / 3, p % 3),
                x[p],
                "coordinates must be finite",
            ));
        }
        let mut springs = Springs::uniform(i, j, k, 0.0, damping)?;
        springs.validate(x.len() / 3)?;
        for s in 0..springs.len() {
            springs.rest_length[s] = distance(x, springs.i[s], springs.j[s]);
        }
        Ok(springs)
    }

    /// Number of springs.
    pub fn len(&self) -> usize {
        self.i.len()
    }

    /// Whether there are no springs.
    pub fn is_empty(&self) -> bool {
        self.i.is_empty()
    }

    /// First ends (particle indices).
    pub fn i(&self) -> &[usize] {
        &self.i
    }

    /// Second ends (particle indices).
    pub fn j(&self) -> &[usize] {
        &self.j
    }

    /// Stiffnesses, N/m.
    pub fn stiffness(&self) -> &[f64] {
        &self.k
    }

    /// Rest lengths, m.
    pub fn rest_length(&self) -> &[f64] {
        &self.rest_length
    }

    /// Dashpot coefficients, N·s/m.
    pub fn damping(&self) -> &[f64] {
        &self.damping
    }

    /// Per spring, ω² = k (w_i + w_j) (1/s²) and γ = c (w_i + w_j) (1/s), with `inv_mass` the
    /// particles' inverse masses w (1/kg; 0 for a pinned particle, which counts as infinitely
    /// heavy). See [`Springs::max_rates`] for the motion they describe.
    ///
    /// These are exact for an isolated spring's motion along its axis (and bound the motion
    /// across it while the spring is longer than half its rest length: the transverse
    /// stiffness is k (1 − L₀/L), below k in magnitude there). In a network a particle shared
    /// by several springs moves faster than any one spring says (a uniform chain reaches
    /// ω² → 4k/m, twice the 2k/m of each spring): use [`Springs::max_rates`] for a step bound.
    pub fn stiffness_bounds(&self, inv_mass: &[f64]) -> Result<Vec<Rates>, Error> {
        self.validate(inv_mass.len())?;
        Ok((0..self.len())
            .map(|s| {
                let w = inv_mass[self.i[s]] + inv_mass[self.j[s]];
                Rates {
                    omega_squared: self.k[s] * w,
                    damping_rate: self.damping[s] * w,
                    standby: None,
                }
            })
            .collect())
    }

    /// Upper bounds for the whole network on ω²_max (1/s²), the largest eigenvalue of M⁻¹K,
    /// and on γ_max (1/s), the largest of M⁻¹C, with K and C the springs' stiffness and damping
    /// matrices; `inv_mass` as in [`Springs::stiffness_bounds`]. Zero without springs.
    ///
    /// Block Gershgorin on M⁻¹K: row block p holds w_p K_s on the diagonal and −w_p K_s
    /// off it for each spring s at p, with |K_s| = k_s max(1, |1 − L₀/L|) = k_s while the spring
    /// is longer than L₀/2. Every eigenvalue is then within Σ_s w_p k_s of a diagonal one, so
    ///
    /// ```text
    ///   ω²_max ≤ max_p 2 w_p Σ_{s at p} k_s,      γ_max ≤ max_p 2 w_p Σ_{s at p} c_s
    /// ```
    ///
    /// The bound is reached by the highest mode of a long uniform chain (4k/m).
    ///
    /// For one spring with inverse masses w_i, w_j at its ends, the stretch r = L − L₀ obeys
    /// r'' = −ω² r − γ r' along the spring, with ω² = k (w_i + w_j) and γ = c (w_i + w_j) (the
    /// relative acceleration is w_j F_j − w_i F_i = −(w_i + w_j) F_i). A pinned end has w = 0,
    /// infinite mass. Explicit methods need h ω below their stability limit (2 for symplectic
    /// Euler and Verlet) and h γ below theirs for the damping (2 for forward Euler on r' = −γ r).
    pub fn max_rates(&self, inv_mass: &[f64]) -> Result<Rates, Error> {
        self.validate(inv_mass.len())?;
        let mut k_sum = vec![0.0; inv_mass.len()];
        let mut c_sum = vec![0.0; inv_mass.len()];
        for s in 0..self.len() {
            for p in [self.i[s], self.j[s]] {
                k_sum[p] += self.k[s];
                c_sum[p] += self.damping[s];
            }
        }
        let mut rates = Rates::default();
        for (p, w) in inv_mass.iter().enumerate() {
            rates.omega_squared = rates.omega_squared.max(2.0 * w * k_sum[p]);
            rates.damping_rate = rates.damping_rate.max(2.0 * w * c_sum[p]);
        }
        Ok(rates)
    }

    /// Unit vector n from i to j and the distance L of spring s; `None` for coincident ends.
    #[inline(always)]
    fn axis(&self, x: &[f64], s: usize) -> Option<([f64; 3], f64)> {
        let (a, b) = (3 * self.i[s], 3 * self.j[s]);
        let d = [x[b] - x[a], x[b + 1] - x[a + 1], x[b + 2] - x[a + 2]];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        (len > 0.0).then(|| ([d[0] / len, d[1] / len, d[2] / len], len))
    }

    /// u = v_j − v_i of spring s.
    #[inline(always)]
    fn relative(&self, v: &[f64], s: usize) -> [f64; 3] {
        let (a, b) = (3 * self.i[s], 3 * self.j[s]);
        [v[b] - v[a], v[b + 1] - v[a + 1], v[b + 2] - v[a + 2]]
    }

    /// Errors (naming the first bad spring) unless every index is below `n`.
    fn check_indices(&self, n: usize) -> Result<(), Error> {
        if self.min_particles <= n {
            return Ok(());
        }
        for s in 0..self.len() {
            for (name, p) in [("i", self.i[s]), ("j", self.j[s])] {
                if p >= n {
                    return Err(Error::invalid(
                        format!("{name}[{s}]"),
                        p,
                        format!("spring {s}'s ends must be indices of the {n} particles (< {n})"),
                    ));
                }
            }
        }
        unreachable!("min_particles is 1 + the largest index")
    }
}

/// One spring's Jacobian blocks at a state: with e = dx_j − dx_i, w = dv_j − dv_i and
/// P e = e − (n·e) n, the product on i is (k n·e + turn·P e + c n·w) n + transverse P e.
#[derive(Debug, Clone, Copy)]
struct SpringBlock {
    i: usize,
    j: usize,
    n: [f64; 3],
    k: f64,
    c: f64,
    transverse: f64,
    /// c u / L, the dashpot's turning-axis term ((P u)·e = u·(P e)); 0 when definite.
    turn: [f64; 3],
}

/// Springs linearised at one state (see [`Force::linearize`]); its blocks' room goes back to
/// the springs' [`BlockRoom`] when it is dropped.
struct LinearizedSprings {
    blocks: Vec<SpringBlock>,
    home: Arc<Mutex<Vec<SpringBlock>>>,
}

impl Drop for LinearizedSprings {
    fn drop(&mut self) {
        if let Ok(mut room) = self.home.lock() {
            *room = std::mem::take(&mut self.blocks);
        }
    }
}

impl Linearized for LinearizedSprings {
    /// Adds each spring's blocks (see [`Springs::linearize`]) times (dx, dv).
    fn apply(&self, _s: &State, dx: &[f64], dv: &[f64], out: &mut [f64]) {
        for b in &self.blocks {
            let (a, c) = (3 * b.i, 3 * b.j);
            let e = [dx[c] - dx[a], dx[c + 1] - dx[a + 1], dx[c + 2] - dx[a + 2]];
            let w = [dv[c] - dv[a], dv[c + 1] - dv[a + 1], dv[c + 2] - dv[a + 2]];
            let ne = dot(b.n, e);
            let pe = [e[0] - ne * b.n[0], e[1] - ne * b.n[1], e[2] - ne * b.n[2]];
            let axial = b.k * ne + dot(b.turn, pe) + b.c * dot(b.n, w);
            for q in 0..3 {
                let g = axial * b.n[q] + b.transverse * pe[q];
                out[a + q] += g;
                out[c + q] -= g;
            }
        }
    }

    /// Adds c_x·diag(∂F/∂x) + c_v·diag(∂F/∂v): each end of a spring has the diagonal blocks
    /// −(k n nᵀ + k_t P + n (P t)ᵀ) and −c n nᵀ (k_t the transverse coefficient, t the
    /// turning-axis term), whose q-th diagonal entries are
    /// −(k n_q² + k_t (1 − n_q²) + n_q (t_q − n_q t·n)) and −c n_q². For coincident ends
    /// (n = 0) that is −c_x k_t, with k_t = k for rest length 0 and 0 otherwise. The
    /// implicit solve asks for it from the definite linearisation, where t = 0 and
    /// k_t = k max(0, 1 − L₀/L).
    fn add_diagonal(&self, _s: &State, cx: f64, cv: f64, out: &mut [f64]) {
        for b in &self.blocks {
            let tn = dot(b.turn, b.n);
            let mut diag = [0.0; 3];
            for q in 0..3 {
                let nn = b.n[q] * b.n[q];
                let turning = b.n[q] * (b.turn[q] - b.n[q] * tn);
                diag[q] = -cx * (b.k * nn + b.transverse * (1.0 - nn) + turning) - cv * b.c * nn;
            }
            for p in [b.i, b.j] {
                for q in 0..3 {
                    out[3 * p + q] += diag[q];
                }
            }
        }
    }
}

impl Springs {
    /// The force pass (`spring_pass.rs`) into `f`, with `each` called on each chunk of
    /// particles once summed ([`Force::accumulate_then`]); the buffers and indices checked
    /// first.
    fn pass(&mut self, s: &State, f: &mut [f64], each: Option<&ChunkWork>) -> Result<(), CallbackError> {
        check_buffers(self.name(), s, &[("f", f.len())])?;
        self.check_indices(s.len())?;
        let springs = SpringArrays {
            i: &self.i,
            j: &self.j,
            k: &self.k,
            rest_length: &self.rest_length,
            damping: &self.damping,
        };
        self.scratch.accumulate(&springs, s.x, s.v, f, each);
        Ok(())
    }
}

fn distance(x: &[f64], i: usize, j: usize) -> f64 {
    let (a, b) = (3 * i, 3 * j);
    ((x[b] - x[a]).powi(2) + (x[b + 1] - x[a + 1]).powi(2) + (x[b + 2] - x[a + 2]).powi(2)).sqrt()
}

impl Force for Springs {
    fn name(&self) -> &str {
        "spring"
    }

    /// Adds F_i = [k (L − L₀) + c (u·n)] n to each spring's first end and −F_i to its second.
    /// Two passes on all threads (`spring_pass.rs`): each spring's force (chunks of springs),
    /// then each particle's sum over the springs it ends, in spring order (chunks of
    /// particles): the same additions in the same order as one loop over the springs that
    /// adds the force to end i and subtracts it from end j, so the result is the same for any
    /// number of threads.
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        self.pass(s, f, None)
    }

    /// [`Force::accumulate`] with `each` called from the sum pass on each chunk of particles
    /// as soon as its sums are done, where `chunk` is the pass's own chunk (else the
    /// default: all the sums, then the chunks).
    fn accumulate_then(&mut self, s: &State, f: &mut [f64], chunk: usize, each: &ChunkWork) -> Result<(), CallbackError> {
        if chunk != Scratch::SUM_CHUNK {
            self.accumulate(s, f)?;
            each_chunk(f, chunk, each);
            return Ok(());
        }
        self.pass(s, f, Some(each))
    }

    /// Checks that every index is below `n`; the error names the spring and the index.
    fn validate(&self, n: usize) -> Result<(), Error> {
        self.check_indices(n)
    }

    /// U = Σ ½ k (L − L₀)², J: the elastic energy. The dashpot is dissipative and has no
    /// potential, so for damped springs F ≠ −∇U while the ends move; the total energy then
    /// decays by the dashpot's work. `None` if an index is out of range.
    ///
    /// Summed by chunks of a fixed number of springs on all threads, the chunks' sums then
    /// added in order: the same bits for any number of threads (and for springs that fit one
    /// chunk, the bits of one loop). The world asks for it at every runaway check (every
    /// tenth step): one loop over a cloth's 59k springs, on one thread, was a twentieth of
    /// its two threads' steps.
    fn potential_energy(&self, s: &State) -> Option<f64> {
        if self.check_indices(s.len()).is_err() || s.x.len() != 3 * s.len() {
            return None;
        }
        const CHUNK: usize = super::PARALLEL_CHUNK;
        let sums: Vec<f64> = self
            .i
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let springs = c * CHUNK..c * CHUNK + chunk.len();
                springs
                    .map(|sp| {
                        let stretch = distance(s.x, self.i[sp], self.j[sp]) - self.rest_length[sp];
                        0.5 * self.k[sp] * stretch * stretch
                    })
                    .sum::<f64>()
            })
            .collect();
        Some(sums.into_iter().sum())
    }

    /// Internal (each spring pulls its ends equally and oppositely); conservative without
    /// dashpots, dissipative with some (the dashpot's power −c (u·n)² ≤ 0, the elastic work
    /// is −ΔU); a function of the velocities when some spring has a dashpot (c > 0). Each
    /// spring's ends follow their particles ([`Force::reindex`]).
    fn properties(&self) -> Properties {
        let damped = self.damping.iter().any(|c| *c != 0.0);
        Properties {
            energy: if damped {
                EnergyClass::Dissipative
            } else {
                EnergyClass::Conservative
            },
            depends_on_position: true,
            depends_on_velocity: damped,
            internal: true,
            renumbers: true,
            per_particle: false,
        }
    }

    /// A spring with a removed end dies with it; the others keep their order and their ends
    /// follow their particles.
    fn reindex(&mut self, new_of_old: &[u32]) {
        self.scratch = Scratch::default();
        if new_of_old.contains(&GONE) {
            let keep: Vec<bool> = self
                .i
                .iter()
                .zip(&self.j)
                .map(|(&a, &b)| new_of_old[a] != GONE && new_of_old[b] != GONE)
                .collect();
            for v in [&mut self.i, &mut self.j] {
                retain_rows(v, 1, &keep);
            }
            for v in [&mut self.k, &mut self.rest_length, &mut self.damping] {
                retain_rows(v, 1, &keep);
            }
        }
        for end in self.i.iter_mut().chain(self.j.iter_mut()) {
            *end = new_of_old[*end] as usize;
        }
        self.min_particles = self.i.iter().chain(&self.j).map(|p| p + 1).max().unwrap_or(0);
    }

    /// The Jacobian as each spring's blocks, with the axis n, the transverse coefficient and
    /// the dashpot's turning-axis term computed once (P = I − n nᵀ, the projector
    /// across the spring; ∂n/∂d = P / L; ∂L/∂d = nᵀ):
    ///
    /// ```text
    ///   elastic   ∂[k (L − L₀) n]/∂d = k [ n nᵀ + (1 − L₀/L) P ]
    ///   dashpot   ∂[c (u·n) n]/∂d    = c [ (u·n) P + n (P u)ᵀ ] / L
    ///             ∂[c (u·n) n]/∂u    = c n nᵀ
    /// ```
    ///
    /// Since d = x_j − x_i and u = v_j − v_i, with K the sum of the first two blocks,
    /// δF_i = K (dx_j − dx_i) + c n nᵀ (dv_j − dv_i) and δF_j = −δF_i. K is not symmetric
    /// when the ends move (the n (P u)ᵀ term): the dashpot's axis turns with the spring.
    ///
    /// At L = 0 (coincident ends, no force, see the module doc) a spring of rest length 0
    /// adds k (dx_j − dx_i), the exact derivative of its force k d; any other adds nothing.
    /// `None` if a buffer's length or an index does not fit `s`.
    ///
    /// With `definite`, the definite part of the Jacobian: each spring's transverse
    /// stiffness k (1 − L₀/L) is clamped at 0 (a compressed spring would otherwise make
    /// M − h²∂F/∂x indefinite for large h; Choi & Ko 2002), and the dashpot keeps only its
    /// symmetric c n nᵀ (the terms from the turning axis are dropped). What is left is
    /// −(k n nᵀ + k max(0, 1 − L₀/L) P) and −c n nᵀ per spring: negative semi-definite.
    fn linearize(&self, s: &State, definite: bool) -> Option<Box<dyn Linearized>> {
        if check_buffers(self.name(), s, &[]).is_err() || self.check_indices(s.len()).is_err() {
            return None;
        }
        let mut blocks = self.blocks.lend();
        blocks.reserve(self.len());
        for sp in 0..self.len() {
            let (k, rest, c) = (self.k[sp], self.rest_length[sp], self.damping[sp]);
            let block = match self.axis(s.x, sp) {
                // Coincident ends: k I for rest length 0, nothing otherwise (module doc).
                None => SpringBlock {
                    i: self.i[sp],
                    j: self.j[sp],
                    n: [0.0; 3],
                    k: 0.0,
                    c: 0.0,
                    transverse: if rest == 0.0 { k } else { 0.0 },
                    turn: [0.0; 3],
                },
                Some((n, len)) => {
                    let (transverse, turn) = if definite {
                        (k * (1.0 - rest / len).max(0.0), [0.0; 3])
                    } else {
                        let u = self.relative(s.v, sp);
                        let scale = c / len;
                        (
                            k * (1.0 - rest / len) + c * dot(u, n) / len,
                            [scale * u[0], scale * u[1], scale * u[2]],
                        )
                    };
                    SpringBlock {
                        i: self.i[sp],
                        j: self.j[sp],
                        n,
                        k,
                        c,
                        transverse,
                        turn,
                    }
                }
            };
            blocks.push(block);
        }
        Some(Box::new(LinearizedSprings {
            blocks,
            home: Arc::clone(&self.blocks.0),
        }))
    }

    /// The network's Gershgorin bounds, [`Springs::max_rates`].
    fn rates(&self, _s: &State, inv_mass: &[f64]) -> Option<Rates> {
        self.max_rates(inv_mass).ok()
    }
}

#[cfg(test)]
#[path = "tests/spring.rs"]
mod tests;
