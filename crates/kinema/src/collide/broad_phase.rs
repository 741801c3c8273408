//! Broad phase: candidate pairs from a uniform grid, rebuilt each call by a counting sort.
//!
//! A pair (i, j) is a candidate when |x_i − x_j| < r_i + r_j + margin (minimum image along
//! periodic axes). With cells at least s = 2 r_max + margin wide, such a pair is never more
//! than one cell apart along any axis, so searching a particle's own cell and its neighbours
//! (27 in 3D, 9 in 2D) finds all of its partners, whatever the mix of radii.
//!
//! The grid is rebuilt from scratch each call, in O(N):
//!
//! ```text
//!   cell_of[i]  = cell index of particle i                      (one pass)
//!   start[c+1] += 1 for each particle in c, then prefix sums   → start[c] = first slot of c
//!   order[start[cell_of[i]]++] = i, for i ascending            → particles sorted by cell
//! ```
//!
//! The search then runs cell by cell over copies of the positions and radii stored in that
//! order, so that a cell's neighbours are read from nearby memory; the pairs it finds are put
//! in (i, j) order by a second counting sort, by i.

use super::domain::Domain;
use super::vec3;
use crate::error::Error;

/// A candidate pair (i, j) of particle indices, i < j.
pub type Pair = (usize, usize);

/// Relative widening of the cells beyond s = 2 r_max + margin.
///
/// A cell coordinate t = (x − origin) / w is computed with an absolute rounding error of at
/// most about ε·t ≤ ε·T, with T the number of cells along the axis (≤ the cell budget, far
/// below 2³³); two coordinates a distance d < s apart then differ by less than
/// s / w + 2 ε T ≤ 1 / (1 + 10⁻⁶) + 2·2⁻⁵²·2³³ < 1 cell, so they are never two cells apart.
const CELL_SLACK: f64 = 1e-6;

/// How an axis is divided into cells.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
enum Axis {
    /// A single cell (the z axis of a 2D domain).
    Flat,
    /// An unbounded axis over the bounding box of the particles.
    #[default]
    Open,
    /// A periodic axis: cells wrap around, cell n − 1 neighbours cell 0.
    Periodic,
}

/// The uniform grid of the broad phase. It keeps its buffers between calls: once warm, a
/// call allocates nothing unless the number of particles or of found pairs grows.
///
/// The cell width is at least the largest diameter plus the margin (a little more, see the
/// module doc); it grows further where that would give more than 2N + 16 cells (a few
/// particles spread far apart), which keeps the memory O(N) at the cost of fuller cells.
#[derive(Debug, Clone, Default)]
pub struct Grid {
    axes: [Axis; 3],
    /// Cells per axis.
    dims: [usize; 3],
    /// Cell widths per axis, m.
    width: [f64; 3],
    /// Lower corner of cell (0, 0, 0), m.
    origin: [f64; 3],
    /// Cell index of each particle.
    cell_of: Vec<usize>,
    /// First slot of each cell in `order` (one more entry than cells).
    start: Vec<usize>,
    /// Particle indices sorted by cell.
    order: Vec<usize>,
    /// Positions, m, and radii, m, in the order of `order`.
    pos: Vec<[f64; 3]>,
    rad: Vec<f64>,
    /// Pairs in the order found, and per-particle counts for sorting them.
    scratch: Vec<Pair>,
    count: Vec<usize>,
}

impl Grid {
    /// An empty grid; its buffers grow on the first call.
    pub fn new() -> Self {
        Grid::default()
    }

    /// Cells per axis of the last call (1 along a 2D domain's z).
    pub fn cells(&self) -> [usize; 3] {
        self.dims
    }

    /// Cell widths of the last call along each axis, m (0 along a single-cell axis).
    pub fn cell_width(&self) -> [f64; 3] {
        self.width
    }

    /// Writes into `pairs` (cleared first) every pair (i, j), i < j, with
    /// |x_i − x_j| < r_i + r_j + `margin`, the distance being the minimum image along the
    /// domain's periodic axes; sorted by i, then j.
    ///
    /// `x`: positions, m (3 per particle, finite); `radius`: radii, m (≥ 0, finite, one per
    /// particle); `margin`: m (≥ 0, finite; 0 for contacts now, the distance both can travel
    /// within the step for continuous detection). Zero-radius particles never pair with each
    /// other unless `margin` > 0 (the test is strict: a distance < 0 is impossible).
    ///
    /// The result is exactly [`all_pairs`]'s, in O(N + pairs) time when the particles fill
    /// their bounding box (or the periodic box) roughly evenly.
    pub fn find_pairs(
        &mut self,
        x: &[f64],
        radius: &[f64],
        domain: &Domain,
        margin: f64,
        pairs: &mut Vec<Pair>,
    ) -> Result<(), Error> {
        check_inputs(x, radius, margin)?;
        pairs.clear();
        let n = radius.len();
        let reach = 2.0 * radius.iter().fold(0.0, |m: f64, r| m.max(*r)) + margin;
        if n < 2 || reach == 0.0 {
            // nothing can pair: one cell holds everything
            self.dims = [1; 3];
            self.width = [0.0; 3];
            return Ok(());
        }
        self.layout(x, domain, reach);
        self.sort_into_cells(x, radius, domain);

        // Cell by cell, so that neighbouring cells (and the copies of their particles'
        // positions, stored in cell order) are read from memory close together.
        let mut found = std::mem::take(&mut self.scratch);
        found.clear();
        let [nx, ny, nz] = self.dims;
        for cz in 0..nz {
            for cy in 0..ny {
                for cx in 0..nx {
                    self.pairs_from_cell([cx, cy, cz], domain, margin, &mut found);
                }
            }
        }
        self.scratch = found;
        self.sort_pairs(n, pairs);
        Ok(())
    }

    /// Sorts the particles into cells at least 2 r_max + `margin` wide for [`Grid::partners`]
    /// (same arguments, checks and cell layout as [`Grid::find_pairs`]). Returns false when
    /// nothing can pair (fewer than two particles, or zero reach): every particle has no
    /// partner then.
    pub fn prepare(&mut self, x: &[f64], radius: &[f64], domain: &Domain, margin: f64) -> Result<bool, Error> {
        check_inputs(x, radius, margin)?;
        let reach = 2.0 * radius.iter().fold(0.0, |m: f64, r| m.max(*r)) + margin;
        if radius.len() < 2 || reach == 0.0 {
            self.dims = [1; 3];
            self.width = [0.0; 3];
            return Ok(false);
        }
        self.layout(x, domain, reach);
        self.sort_into_cells(x, radius, domain);
        Ok(true)
    }

    /// Particle i's partners in the grid of the last [`Grid::prepare`] (same positions `x`
    /// and `radius`): every j ≠ i with |x_i − x_j| < r_i + r_j + `margin` (the pair test of
    /// [`Grid::find_pairs`], with j's stored copy of its position), appended to `out` in
    /// ascending order of j. Reads the grid only, so particles can be searched in parallel:
    /// each pair is found twice, once from each side (a full neighbour list).
    pub fn partners(&self, i: usize, xi: [f64; 3], ri: f64, domain: &Domain, margin: f64, out: &mut Vec<u32>) {
        let first = out.len();
        let [nx, ny, _] = self.dims;
        let cell = self.cell_of[i];
        let at = [cell % nx, (cell / nx) % ny, cell / (nx * ny)];
        let (xs, xn) = self.neighbours(0, at[0]);
        let (ys, yn) = self.neighbours(1, at[1]);
        let (zs, zn) = self.neighbours(2, at[2]);
        for &z in &zs[..zn] {
            for &y in &ys[..yn] {
                let row = nx * (y + ny * z);
                let mut k = 0;
                while k < xn {
                    let run = xs[k];
                    while k + 1 < xn && xs[k + 1] == xs[k] + 1 {
                        k += 1;
                    }
                    for b in self.start[row + run]..self.start[row + xs[k] + 1] {
                        let j = self.order[b];
                        if j != i && touches(domain, xi, self.pos[b], ri, self.rad[b], margin) {
                            out.push(j as u32);
                        }
                    }
                    k += 1;
                }
            }
        }
        out[first..].sort_unstable();
    }

    /// Appends to `found` each pair (i, j), j > i, of a particle i in cell `at` with a
    /// particle j in the same or a neighbouring cell that passes the pair test.
    fn pairs_from_cell(&self, at: [usize; 3], domain: &Domain, margin: f64, found: &mut Vec<Pair>) {
        let [nx, ny, _] = self.dims;
        let cell = at[0] + nx * (at[1] + ny * at[2]);
        let (xs, xn) = self.neighbours(0, at[0]);
        let (ys, yn) = self.neighbours(1, at[1]);
        let (zs, zn) = self.neighbours(2, at[2]);
        for a in self.start[cell]..self.start[cell + 1] {
            let (i, xi, ri) = (self.order[a], self.pos[a], self.rad[a]);
            for &z in &zs[..zn] {
                for &y in &ys[..yn] {
                    let row = nx * (y + ny * z);
                    // neighbouring cells along x with consecutive indices form one run of slots
                    let mut k = 0;
                    while k < xn {
                        let first = xs[k];
                        while k + 1 < xn && xs[k + 1] == xs[k] + 1 {
                            k += 1;
                        }
                        for b in self.start[row + first]..self.start[row + xs[k] + 1] {
                            let j = self.order[b];
                            if j > i && touches(domain, xi, self.pos[b], ri, self.rad[b], margin) {
                                found.push((i, j));
                            }
                        }
                        k += 1;
                    }
                }
            }
        }
    }

    /// Chooses the axes' modes, origins, cell counts and widths for cells at least `reach` wide.
    fn layout(&mut self, x: &[f64], domain: &Domain, reach: f64) {
        let periodic = domain.periodic_box();
        let mut extent = [0.0; 3];
        for (k, ext) in extent.iter_mut().enumerate() {
            self.axes[k] = if k == 2 && domain.dim() == 2 {
                Axis::Flat
            } else if periodic.is_some_and(|p| p.axes()[k]) {
                Axis::Periodic
            } else {
                Axis::Open
            };
            match self.axes[k] {
                Axis::Flat => {
                    self.origin[k] = 0.0;
                }
                Axis::Periodic => {
                    let p = periodic.expect("a periodic axis has a box");
                    self.origin[k] = p.lo()[k];
                    *ext = p.period(k);
                }
                Axis::Open => {
                    let (lo, hi) = x
                        .iter()
                        .skip(k)
                        .step_by(3)
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| (lo.min(*c), hi.max(*c)));
                    self.origin[k] = lo;
                    *ext = hi - lo;
                }
            }
        }

        // Cells along each axis for a width w (as f64: a tiny w over a wide box must not
        // overflow usize before the budget has coarsened it).
        // `max` also turns the NaN of an infinite extent over an infinite width into 1.
        let count = |axis: Axis, extent: f64, w: f64| match axis {
            Axis::Flat => 1.0,
            Axis::Open => ((extent / w).floor() + 1.0).max(1.0),
            Axis::Periodic => (extent / w).floor().max(1.0),
        };
        let total = |w: f64| (0..3).map(|k| count(self.axes[k], extent[k], w)).product::<f64>();
        let budget = 2.0 * (x.len() / 3) as f64 + 16.0;
        let mut w = reach * (1.0 + CELL_SLACK);
        if total(w) > budget {
            // Jump close to the width that fits the budget, then grow in steps: the box's
            // volume (area in 2D) over the budget is the volume of one cell.
            let active: Vec<f64> = (0..3).filter(|&k| self.axes[k] != Axis::Flat).map(|k| extent[k]).collect();
            let volume: f64 = active.iter().product();
            w = w.max((volume / budget).powf(1.0 / active.len() as f64));
            while total(w) > budget {
                w *= 1.25;
            }
        }
        for (k, &ext) in extent.iter().enumerate() {
            let cells = count(self.axes[k], ext, w) as usize;
            self.dims[k] = cells;
            self.width[k] = match self.axes[k] {
                Axis::Flat => 0.0,
                Axis::Open => w,
                Axis::Periodic => ext / cells as f64,
            };
        }
    }

    /// Counting sort of the particles by cell: fills `cell_of`, `start`, `order`, and the
    /// positions and radii in that order.
    fn sort_into_cells(&mut self, x: &[f64], radius: &[f64], domain: &Domain) {
        let n = x.len() / 3;
        let [nx, ny, nz] = self.dims;
        let total = nx * ny * nz;
        self.cell_of.clear();
        for i in 0..n {
            let p = vec3::get(x, i);
            let mut coord = [0usize; 3];
            for k in 0..3 {
                if self.axes[k] == Axis::Flat {
                    continue;
                }
                let c = match (self.axes[k], domain.periodic_box()) {
                    (Axis::Periodic, Some(b)) => b.wrap_coordinate(k, p[k]),
                    _ => p[k],
                };
                // ≥ 0 by construction up to rounding; `as usize` saturates at 0 below it.
                let t = ((c - self.origin[k]) / self.width[k]).floor() as usize;
                coord[k] = t.min(self.dims[k] - 1);
            }
            self.cell_of.push(coord[0] + nx * (coord[1] + ny * coord[2]));
        }

        self.start.clear();
        self.start.resize(total + 1, 0);
        for &c in &self.cell_of {
            self.start[c + 1] += 1;
        }
        for c in 1..=total {
            self.start[c] += self.start[c - 1];
        }
        // Placing i at start[c]++ leaves start[c] at the first slot of cell c + 1; shifting the
        // array right by one restores the first slots without a second buffer.
        self.order.clear();
        self.order.resize(n, 0);
        for (i, &c) in self.cell_of.iter().enumerate() {
            self.order[self.start[c]] = i;
            self.start[c] += 1;
        }
        for c in (1..=total).rev() {
            self.start[c] = self.start[c - 1];
        }
        self.start[0] = 0;
        self.pos.clear();
        self.pos.extend(self.order.iter().map(|&i| vec3::get(x, i)));
        self.rad.clear();
        self.rad.extend(self.order.iter().map(|&i| radius[i]));
    }

    /// Moves the pairs found (in cell order) from `scratch` into `pairs`, sorted by i, then
    /// j: a counting sort by i (O(N + pairs)), then each particle's few partners sorted.
    fn sort_pairs(&mut self, n: usize, pairs: &mut Vec<Pair>) {
        self.count.clear();
        self.count.resize(n + 1, 0);
        for &(i, _) in &self.scratch {
            self.count[i + 1] += 1;
        }
        for i in 1..=n {
            self.count[i] += self.count[i - 1];
        }
        pairs.clear();
        pairs.resize(self.scratch.len(), (0, 0));
        for &pair in &self.scratch {
            pairs[self.count[pair.0]] = pair;
            self.count[pair.0] += 1;
        }
        // count[i] is now the end of i's run, which starts where i − 1's ends
        let mut begin = 0;
        for i in 0..n {
            pairs[begin..self.count[i]].sort_unstable();
            begin = self.count[i];
        }
    }

    /// The distinct cells along axis `k` that neighbour (or are) cell `c`: up to 3, each once
    /// even on a periodic axis of fewer than 3 cells, where c − 1 and c + 1 coincide.
    fn neighbours(&self, k: usize, c: usize) -> ([usize; 3], usize) {
        let n = self.dims[k];
        match self.axes[k] {
            Axis::Flat => ([0, 0, 0], 1),
            Axis::Periodic if n >= 3 => ([(c + n - 1) % n, c, (c + 1) % n], 3),
            Axis::Periodic => ([0, 1, 2], n),
            Axis::Open => {
                let lo = c.saturating_sub(1);
                let hi = (c + 1).min(n - 1);
                ([lo, lo + 1, lo + 2], hi - lo + 1)
            }
        }
    }
}

/// The O(N²) reference for [`Grid::find_pairs`]: the same pairs, by testing every pair.
/// Same arguments and the same errors.
pub fn all_pairs(x: &[f64], radius: &[f64], domain: &Domain, margin: f64, pairs: &mut Vec<Pair>) -> Result<(), Error> {
    check_inputs(x, radius, margin)?;
    pairs.clear();
    let n = radius.len();
    for i in 0..n {
        for j in i + 1..n {
            if touches(domain, vec3::get(x, i), vec3::get(x, j), radius[i], radius[j], margin) {
                pairs.push((i, j));
            }
        }
    }
    Ok(())
}

/// The pair test of both searches, the same floating-point operations in both:
/// |d|² < (r_i + r_j + margin)², d = x_i − x_j as its minimum image.
#[inline]
fn touches(domain: &Domain, xi: [f64; 3], xj: [f64; 3], ri: f64, rj: f64, margin: f64) -> bool {
    let d = domain.displacement(xi, xj);
    let reach = ri + rj + margin;
    vec3::dot(d, d) < reach * reach
}

fn check_inputs(x: &[f64], radius: &[f64], margin: f64) -> Result<(), Error> {
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
mod tests {
    use super::super::domain::Periodic;
    use super::*;

    fn both(x: &[f64], radius: &[f64], domain: &Domain, margin: f64) -> (Vec<Pair>, Vec<Pair>) {
        let (mut fast, mut slow) = (Vec::new(), Vec::new());
        Grid::new().find_pairs(x, radius, domain, margin, &mut fast).unwrap();
        all_pairs(x, radius, domain, margin, &mut slow).unwrap();
        (fast, slow)
    }

    #[test]
    fn a_small_line_by_hand() {
        // centres 0, 1, 2.5, 2.875 on x, radii 0.5, 0.5, 0.125, 0.25 (all exact in binary):
        // 0–1 touch at exactly 1.0 (not < 1.0), 1–2 are 1.5 apart (reach 0.625), 2–3 are
        // 0.375 apart (reach 0.375, not <). A margin of 1.25 adds 1–2 (1.5 < 1.875) and 1–3
        // (1.875 < 2.0), not 0–2 (2.5 ≥ 1.875) nor 0–3 (2.875 ≥ 2.0).
        let x = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.5, 0.0, 0.0, 2.875, 0.0, 0.0];
        let r = [0.5, 0.5, 0.125, 0.25];
        let d = Domain::open(3).unwrap();
        assert_eq!(both(&x, &r, &d, 0.0), (vec![], vec![]));
        let (fast, slow) = both(&x, &r, &d, 0.01);
        assert_eq!(fast, vec![(0, 1), (2, 3)]);
        assert_eq!(fast, slow);
        let (fast, _) = both(&x, &r, &d, 1.25);
        assert_eq!(fast, vec![(0, 1), (1, 2), (1, 3), (2, 3)]);
    }

    #[test]
    fn pairs_across_a_periodic_boundary_once_even_in_a_two_cell_box() {
        // period 2.0 along x with cells ≥ 1.0 wide: 2 cells, whose −1 and +1 neighbours are
        // the same cell. 0.05 and 1.95 are 0.1 apart through the boundary.
        let p = Periodic::new([0.0; 3], [2.0, 1.0, 1.0], [true, false, false]).unwrap();
        let d = Domain::periodic(2, p).unwrap();
        let x = [0.05, 0.5, 0.0, 1.95, 0.5, 0.0, 1.0, 0.5, 0.0];
        let r = [0.45, 0.45, 0.45];
        let (fast, slow) = both(&x, &r, &d, 0.0);
        assert_eq!(fast, vec![(0, 1)]);
        assert_eq!(fast, slow);
        let mut g = Grid::new();
        let mut pairs = Vec::new();
        g.find_pairs(&x, &r, &d, 0.12, &mut pairs).unwrap();
        assert_eq!(g.cells(), [1, 1, 1]);
        assert_eq!(pairs, vec![(0, 1), (0, 2), (1, 2)]);
    }

    #[test]
    fn a_chain_just_inside_contact_distance_is_found_link_by_link() {
        // Equal radii, neighbours a hair closer than 2r along a line (axis-aligned and
        // diagonal): every link is a pair, and links cross cell boundaries all along. Cells
        // even slightly narrower than 2r would put some neighbours two cells apart.
        let (n, r) = (2000, 0.05);
        for dir in [[1.0, 0.0, 0.0], [0.6, 0.0, 0.8], [0.48, 0.6, 0.64]] {
            for gap in [1e-3, 1e-9, 1e-15] {
                let step = 2.0 * r * (1.0 - gap);
                let x: Vec<f64> = (0..n).flat_map(|k| dir.map(|c| 1.7 + c * step * k as f64)).collect();
                let (fast, slow) = both(&x, &vec![r; n], &Domain::open(3).unwrap(), 0.0);
                assert!(
                    fast == slow,
                    "direction {dir:?}, gap {gap}: {} pairs, {} expected",
                    fast.len(),
                    slow.len()
                );
                // at a relative gap of 1e-15 the rounding of the positions decides each link
                if gap > 1e-12 {
                    assert_eq!(fast.len(), n - 1, "direction {dir:?}, gap {gap}");
                }
            }
        }
    }

    #[test]
    fn sparse_particles_coarsen_the_grid_instead_of_allocating_it() {
        // 3 tiny particles 1e6 m apart would need 1e18 cells of 2e-3 m.
        let x = [0.0, 0.0, 0.0, 1e6, 1e6, 1e6, 1e6, 1e6, 1e6 + 1e-3];
        let r = [1e-3; 3];
        let mut g = Grid::new();
        let mut pairs = Vec::new();
        g.find_pairs(&x, &r, &Domain::open(3).unwrap(), 0.0, &mut pairs).unwrap();
        assert_eq!(pairs, vec![(1, 2)]);
        assert!(g.cells().iter().product::<usize>() <= 2 * 3 + 16, "{:?}", g.cells());
    }

    #[test]
    fn zero_radii_pair_only_through_the_margin() {
        let x = [0.0; 6];
        let d = Domain::open(2).unwrap();
        assert_eq!(both(&x, &[0.0, 0.0], &d, 0.0).0, vec![]);
        assert_eq!(both(&x, &[0.0, 0.0], &d, 1e-9).0, vec![(0, 1)]);
    }

    #[test]
    fn buffers_are_kept_between_calls() {
        let x: Vec<f64> = (0..300).map(|k| (k as f64 * 0.37).sin() * 3.0).collect();
        let r = vec![0.2; 100];
        let d = Domain::open(3).unwrap();
        let mut g = Grid::new();
        let mut pairs = Vec::new();
        g.find_pairs(&x, &r, &d, 0.0, &mut pairs).unwrap();
        let caps = (g.cell_of.capacity(), g.start.capacity(), g.order.capacity(), pairs.capacity());
        let first = pairs.clone();
        g.find_pairs(&x, &r, &d, 0.0, &mut pairs).unwrap();
        assert_eq!(pairs, first);
        assert_eq!(
            caps,
            (g.cell_of.capacity(), g.start.capacity(), g.order.capacity(), pairs.capacity())
        );
    }

    #[test]
    fn bad_input_is_named() {
        let d = Domain::open(3).unwrap();
        let mut pairs = Vec::new();
        let mut g = Grid::new();
        let e = g
            .find_pairs(&[0.0; 5], &[1.0; 2], &d, 0.0, &mut pairs)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("x = 5 values is invalid"), "{e}");
        let e = g
            .find_pairs(&[0.0, 0.0, 0.0, 0.0, f64::INFINITY, 0.0], &[1.0; 2], &d, 0.0, &mut pairs)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("x[1][1] = inf is invalid"), "{e}");
        let e = all_pairs(&[0.0; 6], &[1.0, -1.0], &d, 0.0, &mut pairs)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("radius[1] = -1 is invalid"), "{e}");
        let e = all_pairs(&[0.0; 6], &[1.0; 2], &d, f64::NAN, &mut pairs)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("margin = NaN is invalid"), "{e}");
    }
}
