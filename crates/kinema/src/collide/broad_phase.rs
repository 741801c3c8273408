//! Broad phase: candidate pairs from a hierarchical grid, rebuilt each call by counting sorts.
//!
//! A pair (i, j) is a candidate when |x_i − x_j| < r_i + r_j + margin (minimum image along
//! periodic axes). With cells at least s = 2 r_max + margin wide, such a pair is never more
//! than one cell apart along any axis, so searching a particle's own cell and its neighbours
//! (27 in 3D, 9 in 2D) finds all of its partners.
//!
//! Cells as wide as the largest particle are too wide for the rest when radii differ much
//! (one boulder among grains: every grain would test thousands of others), so the particles
//! are split into levels by reach, each level a uniform grid of its own width (the HGrid of
//! MercuryDPM, Ogarko & Luding 2012); a pair is searched from its smaller particle's side, in
//! its own level and the coarser ones. Radii within a factor 2 make one level.
//!
//! Each level is rebuilt from scratch each call, in O(N):
//!
//! ```text
//!   cell_of[i]  = cell index of particle i                      (one pass)
//!   start[c+1] += 1 for each particle in c, then prefix sums   → start[c] = first slot of c
//!   order[start[cell_of[i]]++] = i, for i ascending            → particles sorted by cell
//! ```
//!
//! A particle's partners are then searched in the cells around it, particle by particle
//! ([`Grid::partners`], [`Grid::partners_from`]): the neighbour lists (`neighbour_list.rs`)
//! are built so, on all threads, and the placement check (`placement.rs`) searches so.
//! The O(N²) search they are tested against is `all_pairs` in `oracles.rs`.

use super::domain::Domain;
use super::grid_level::{Level, LevelSort};
use crate::error::Error;
use crate::vec3;

/// Neighbouring levels' cell widths differ by at most this factor (the level index below is
/// a log₂, so this is 2 and nothing else): a particle goes to level
/// ⌊log₂(s_i / s_min)⌋ of its own reach s_i = 2 r_i + margin, so within a level the reaches
/// span less than 2×, and a particle's cells are never more than twice its reach, as in a
/// grid of equal radii.
const LEVEL_RATIO: f64 = 2.0;

/// At most this many levels: radii spanning more than 2¹⁵ share the coarsest.
const MAX_LEVELS: usize = 16;

/// The most particles the grid indexes (its slots and cells are u32; 2N + 16 cells must fit).
pub const MAX_PARTICLES: usize = (u32::MAX as usize - 16) / 2;

/// The broad phase's grid: one uniform grid per size class of particles (a hierarchical grid,
/// as MercuryDPM's HGrid). It keeps its buffers between calls: once warm, a call allocates
/// nothing unless the number of particles or of levels grows.
///
/// A uniform grid needs cells as wide as the largest particle, so one boulder among fine
/// grains puts thousands of grains into each cell and the search becomes quadratic. Here each
/// particle is sorted into the grid of its own level, whose cells are as wide as that level's
/// largest reach s = 2 r + margin (a little more, see `CELL_SLACK` in grid_level.rs); levels' reaches grow by
/// factors of 2 (`LEVEL_RATIO`), and levels no particle falls into are not built. A pair is
/// found from the side of its smaller particle: i searches its own level and every coarser
/// one in the 3 × 3 × 3 cells around its position there (j's cells are at least as wide as
/// j's reach ≥ r_i + r_j + margin, so j is at most one cell away). With equal radii (or radii
/// within 2×) there is one level and this is the plain uniform grid.
///
/// Each level's cells are at least its reach wide; they grow further where that would give
/// more than 2 N_level + 16 cells (a few particles spread far apart), which keeps the memory
/// O(N) at the cost of fuller cells.
#[derive(Debug, Clone, Default)]
pub struct Grid {
    /// The levels in use, finest first (only `levels[..used]` hold this call's particles).
    levels: Vec<Level>,
    used: usize,
    /// Level of each particle (empty when there is one level).
    level_of: Vec<u8>,
    /// Cell of each particle in its own level's grid.
    cell_of: Vec<u32>,
}

impl Grid {
    /// An empty grid; its buffers grow on the first call.
    pub fn new() -> Self {
        Grid::default()
    }

    /// Gives back the grid's buffers (the next [`Grid::prepare`] makes them again): for a
    /// caller that builds rarely, such as a neighbour list kept over many steps (at 10⁶
    /// particles they are 9 B a particle, idle between builds).
    pub fn release(&mut self) {
        *self = Grid::default();
    }

    /// Cells per axis of the last call's finest level (1 along a 2D domain's z).
    pub fn cells(&self) -> [usize; 3] {
        self.levels.first().filter(|_| self.used > 0).map_or([1; 3], |l| l.dims)
    }

    /// Cells of the last call over all levels.
    pub fn cell_count(&self) -> usize {
        self.levels[..self.used]
            .iter()
            .map(|l| l.dims.iter().product::<usize>())
            .sum()
    }

    /// Levels of the last call (0 when nothing could pair).
    pub fn level_count(&self) -> usize {
        self.used
    }

    /// Cell widths of the last call's finest level along each axis, m (0 along a
    /// single-cell axis).
    pub fn cell_width(&self) -> [f64; 3] {
        self.levels.first().filter(|_| self.used > 0).map_or([0.0; 3], |l| l.width)
    }

    /// Sorts the particles into the levels' cells for [`Grid::partners`], for the pairs
    /// (i, j) with |x_i − x_j| < r_i + r_j + `margin`, the distance being the minimum image
    /// along the domain's periodic axes. Returns false when nothing can pair (fewer than two
    /// particles, or zero reach): every particle has no partner then.
    ///
    /// `x`: positions, m (3 per particle, finite); `radius`: radii, m (≥ 0, finite, one per
    /// particle); `margin`: m (≥ 0, finite; the skin of a neighbour list, 0 for contacts now).
    /// Zero-radius particles never pair with each other unless `margin` > 0 (the test is
    /// strict: a distance < 0 is impossible).
    ///
    /// It keeps no copies of the positions and radii in cell order: its callers sort their
    /// particles along space themselves. The search is O(N + pairs) when each level's
    /// particles fill their bounding box (or the periodic box) roughly evenly.
    pub fn prepare(&mut self, x: &[f64], radius: &[f64], domain: &Domain, margin: f64) -> Result<bool, Error> {
        check_inputs(x, radius, margin)?;
        let n = radius.len();
        let (r_min, r_max) = radius
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), &r| (lo.min(r), hi.max(r)));
        let reach_max = 2.0 * r_max + margin;
        if n < 2 || reach_max == 0.0 {
            self.used = 0;
            return Ok(false);
        }
        // Level ⌊log₂(s_i / base)⌋ of each reach s_i (levels 0 ..= MAX_LEVELS − 1; the
        // base is raised so that the largest reach falls into the last level at most).
        let base = (2.0 * r_min + margin).max(reach_max * LEVEL_RATIO.powi(1 - MAX_LEVELS as i32));
        let level = |r: f64| -> usize {
            let s = 2.0 * r + margin;
            if s <= base {
                0
            } else {
                ((s / base).log2().floor() as usize).min(MAX_LEVELS - 1)
            }
        };
        self.cell_of.clear();
        self.cell_of.resize(n, 0);
        if level(r_max) == 0 {
            // radii within 2× of each other: one uniform grid over all particles
            self.level_of.clear();
            self.used = 1;
            if self.levels.is_empty() {
                self.levels.push(Level::default());
            }
            let l = &mut self.levels[0];
            l.r_max = r_max;
            let sort = LevelSort {
                members: None,
                reach: reach_max,
            };
            l.build(x, radius, domain, sort, &mut self.cell_of);
            return Ok(true);
        }
        // Several levels: number the non-empty ones in order, finest first.
        let mut occupied = [false; MAX_LEVELS];
        self.level_of.clear();
        self.level_of.extend(radius.iter().map(|&r| level(r) as u8));
        for &l in &self.level_of {
            occupied[l as usize] = true;
        }
        let mut index = [0u8; MAX_LEVELS];
        let mut used = 0;
        for (l, &o) in occupied.iter().enumerate() {
            index[l] = used as u8;
            used += o as usize;
        }
        for l in self.level_of.iter_mut() {
            *l = index[*l as usize];
        }
        self.used = used;
        if self.levels.len() < used {
            self.levels.resize_with(used, Level::default);
        }
        for level in &mut self.levels[..used] {
            level.members.clear();
            level.r_max = 0.0;
        }
        for (i, &l) in self.level_of.iter().enumerate() {
            let level = &mut self.levels[l as usize];
            level.members.push(i as u32);
            level.r_max = level.r_max.max(radius[i]);
        }
        for level in &mut self.levels[..used] {
            let members = std::mem::take(&mut level.members);
            // (at least `base` > 0: a level of points with no margin pairs with nothing of
            // its own, but its cells need a width)
            let reach = (2.0 * level.r_max + margin).max(base);
            let sort = LevelSort {
                members: Some(&members),
                reach,
            };
            level.build(x, radius, domain, sort, &mut self.cell_of);
            level.members = members;
        }
        Ok(true)
    }

    /// Particle i's partners in the grid of the last [`Grid::prepare`] (same positions `x`,
    /// m, and `radius`, m, and `margin`, m): every j ≠ i with |x_i − x_j| < r_i + r_j +
    /// `margin` (minimum image), appended to `out` in ascending order of j. Reads the
    /// grid only, so particles can be searched in parallel:
    /// each pair is found twice, once from each side (a full neighbour list).
    ///
    /// In its own and the coarser levels i searches the 3 × 3 × 3 cells around it; in a
    /// finer level, whose cells may be much narrower than i, the cells within
    /// r_i + r_max + margin of it (r_max the finer level's largest radius).
    pub fn partners(&self, i: usize, x: &[f64], radius: &[f64], domain: &Domain, margin: f64, out: &mut Vec<u32>) {
        self.partners_from(i, 0, x, radius, domain, margin, out);
    }

    /// [`Grid::partners`] among the particles j ≥ `lowest` only (`lowest` = i + 1: each pair
    /// found once, from its lower index, for a half neighbour list); the others are passed
    /// over before the distance test.
    #[allow(clippy::too_many_arguments)]
    pub fn partners_from(
        &self,
        i: usize,
        lowest: usize,
        x: &[f64],
        radius: &[f64],
        domain: &Domain,
        margin: f64,
        out: &mut Vec<u32>,
    ) {
        let first = out.len();
        let (xi, ri) = (vec3::get(x, i), radius[i]);
        let own = self.level_of.get(i).map_or(0, |&l| l as usize);
        // The candidates (the particles of the cells searched) first, appended to `out` a
        // run of cells at a time; then tested below.
        let mut search = |level: &Level, at: [usize; 3], span: [usize; 3]| level.append_particles(at, span, out);
        let levels = &self.levels[..self.used];
        search(&levels[own], levels[own].unflatten(self.cell_of[i] as usize), [1; 3]);
        for (l, level) in levels.iter().enumerate() {
            if l < own {
                // |x_i − x_j| < ρ = r_i + r_max + margin is less than ρ / w (+ rounding,
                // far below 10⁻⁵) cells along each axis: within ⌈ρ / w + 10⁻⁵⌉ cells.
                let rho = ri + level.r_max + margin;
                let mut span = [0; 3];
                for k in 0..3 {
                    if level.width[k] > 0.0 {
                        // (as usize saturates; more than the grid's cells visits them all)
                        span[k] = ((rho / level.width[k] + 1e-5).ceil() as usize).min(level.dims[k]);
                    }
                }
                search(level, level.cell_at(xi, domain), span);
            } else if l > own {
                search(level, level.cell_at(xi, domain), [1; 3]);
            }
        }
        // The candidates' test in a loop without a branch but where one passes (in the gas
        // of `benchmarks/granular_gas.py`, about one candidate in fifteen): j ≠ i, j ≥
        // `lowest` and the distance test are joined as booleans (half the candidates of a
        // half list are j < i, unforeseeable to a branch), and those that pass are moved down
        // in place. A particle's candidates were visited cell by cell before, each cell's
        // loop ending at a branch as unforeseeable.
        let mut kept = first;
        for k in first..out.len() {
            let j = out[k] as usize;
            let pass = (j != i) & (j >= lowest) & touches(domain, xi, vec3::get(x, j), ri, radius[j], margin);
            out[kept] = j as u32;
            kept += usize::from(pass);
        }
        out.truncate(kept);
        out[first..].sort_unstable();
    }
}

/// The pair test of the grid's search and of the O(N²) one the tests check it against
/// (`all_pairs` in `oracles.rs`), the same floating-point operations in both:
/// |d|² < (r_i + r_j + margin)², d = x_i − x_j as its minimum image.
#[inline]
pub(crate) fn touches(domain: &Domain, xi: [f64; 3], xj: [f64; 3], ri: f64, rj: f64, margin: f64) -> bool {
    let d = domain.displacement(xi, xj);
    let reach = ri + rj + margin;
    vec3::dot(d, d) < reach * reach
}

/// The checks of [`Grid::prepare`]'s arguments (and of the O(N²) search's).
pub(crate) fn check_inputs(x: &[f64], radius: &[f64], margin: f64) -> Result<(), Error> {
    if radius.len() > MAX_PARTICLES {
        return Err(Error::invalid(
            "particles",
            radius.len(),
            format!("at most {MAX_PARTICLES} in the broad phase's grid"),
        ));
    }
    if x.len() != 3 * radius.len() {
        return Err(Error::invalid(
            "x",
            format!("{} values", x.len()),
            format!("3 per particle ({} for the {} radii)", 3 * radius.len(), radius.len()),
        ));
    }
    if let Some((p, value)) = vec3::first_non_finite(x) {
        return Err(Error::invalid(
            format!("x[{}][{}]", p / 3, p % 3),
            value,
            "positions must be finite",
        ));
    }
    if let Some(i) = radius.iter().position(|r| !(r.is_finite() && *r >= 0.0)) {
        return Err(Error::invalid(
            format!("radius[{i}]"),
            radius[i],
            "radii must be finite and >= 0 m",
        ));
    }
    if !(margin.is_finite() && margin >= 0.0) {
        return Err(Error::invalid("margin", margin, "the pair margin must be finite and >= 0 m"));
    }
    Ok(())
}

#[cfg(test)]
#[path = "tests/broad_phase.rs"]
mod tests;
