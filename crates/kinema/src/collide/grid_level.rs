//! One level of the broad phase's grid (`broad_phase::Grid`): a uniform grid over the
//! particles of one size class, its axes laid out over their bounding box (or the periodic
//! box) and its cells filled by a counting sort; the cells around a point, visited slot by
//! slot, for the pair searches.

use rayon::prelude::*;

use super::domain::Domain;
use crate::vec3;

/// From this many particles on, a level's build finds their cells on all threads (below, a
/// parallel pass costs more than it saves).
const PARALLEL_CELLS: usize = 1 << 14;

/// Particles per task of that parallel pass.
const CELL_CHUNK: usize = 4096;

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
    /// An unbounded axis over the bounding box of the level's particles.
    #[default]
    Open,
    /// A periodic axis: cells wrap around, cell n − 1 neighbours cell 0.
    Periodic,
}

/// One uniform grid: the particles of one size class sorted into cells by a counting sort.
#[derive(Debug, Clone, Default)]
pub(super) struct Level {
    axes: [Axis; 3],
    /// Cells per axis.
    pub(super) dims: [usize; 3],
    /// Cell widths per axis, m.
    pub(super) width: [f64; 3],
    /// Lower corner of cell (0, 0, 0), m.
    origin: [f64; 3],
    /// Largest radius of the level's particles, m.
    pub(super) r_max: f64,
    /// The level's particles in ascending order (unused when there is one level: all are).
    pub(super) members: Vec<u32>,
    /// First slot of each cell in `order` (one more entry than cells).
    pub(super) start: Vec<u32>,
    /// Particle indices sorted by cell.
    pub(super) order: Vec<u32>,
}

/// What [`Level::build`] sorts and how: the level's particles (`members`, or all when None)
/// and the least cell width `reach`, m.
#[derive(Debug, Clone, Copy)]
pub(super) struct LevelSort<'a> {
    pub members: Option<&'a [u32]>,
    pub reach: f64,
}

/// The slots [`Level::append_particles`] copies at once from a run of cells (8 particles'
/// indices, 32 bytes).
const RUN: usize = 8;

impl Level {
    /// Lays the level out for cells at least `reach` wide and sorts its particles (`members`,
    /// or all when None) into them; writes each one's cell into `cell_of`.
    pub(super) fn build(&mut self, x: &[f64], radius: &[f64], domain: &Domain, sort: LevelSort<'_>, cell_of: &mut [u32]) {
        let LevelSort { members, reach } = sort;
        let count = members.map_or(radius.len(), |m| m.len());
        let member = |k: usize| members.map_or(k, |m| m[k] as usize);
        self.layout(x, count, member, domain, reach);

        // Counting sort:
        //   cell_of[i]  = cell index of particle i                      (one pass)
        //   start[c+1] += 1 for each particle in c, then prefix sums   → start[c] = first slot
        //   order[start[cell_of[i]]++] = i, for i ascending            → particles by cell
        let total = self.dims.iter().product::<usize>();
        self.start.clear();
        self.start.resize(total + 1, 0);
        if members.is_none() && count >= PARALLEL_CELLS {
            // every particle: the cells (a division and a wrap per axis) on all threads,
            // each particle's alone; the counting below reads them in order
            let level = &*self;
            cell_of[..count].par_chunks_mut(CELL_CHUNK).enumerate().for_each(|(c, out)| {
                for (l, o) in out.iter_mut().enumerate() {
                    *o = level.flatten(level.cell_at(vec3::get(x, c * CELL_CHUNK + l), domain)) as u32;
                }
            });
            for &c in &cell_of[..count] {
                self.start[c as usize + 1] += 1;
            }
        } else {
            for k in 0..count {
                let i = member(k);
                let c = self.flatten(self.cell_at(vec3::get(x, i), domain));
                cell_of[i] = c as u32;
                self.start[c + 1] += 1;
            }
        }
        for c in 1..=total {
            self.start[c] += self.start[c - 1];
        }
        // Placing i at start[c]++ leaves start[c] at the first slot of cell c + 1; shifting the
        // array right by one restores the first slots without a second buffer.
        self.order.clear();
        self.order.resize(count, 0);
        for k in 0..count {
            let i = member(k);
            let c = cell_of[i] as usize;
            self.order[self.start[c] as usize] = i as u32;
            self.start[c] += 1;
        }
        for c in (1..=total).rev() {
            self.start[c] = self.start[c - 1];
        }
        self.start[0] = 0;
    }

    /// Chooses the axes' modes, origins, cell counts and widths for cells at least `reach`
    /// wide, over the `count` particles `member(0..count)`.
    fn layout(&mut self, x: &[f64], count: usize, member: impl Fn(usize) -> usize, domain: &Domain, reach: f64) {
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
                    let (lo, hi) = (0..count)
                        .map(|m| x[3 * member(m) + k])
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| (lo.min(c), hi.max(c)));
                    self.origin[k] = lo;
                    *ext = hi - lo;
                }
            }
        }

        // Cells along each axis for a width w (as f64: a tiny w over a wide box must not
        // overflow usize before the budget has coarsened it).
        // `max` also turns the NaN of an infinite extent over an infinite width into 1.
        let cells_along = |axis: Axis, extent: f64, w: f64| match axis {
            Axis::Flat => 1.0,
            Axis::Open => ((extent / w).floor() + 1.0).max(1.0),
            Axis::Periodic => (extent / w).floor().max(1.0),
        };
        let total = |w: f64| (0..3).map(|k| cells_along(self.axes[k], extent[k], w)).product::<f64>();
        let budget = 2.0 * count as f64 + 16.0;
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
            let cells = cells_along(self.axes[k], ext, w) as usize;
            self.dims[k] = cells;
            self.width[k] = match self.axes[k] {
                Axis::Flat => 0.0,
                Axis::Open => w,
                Axis::Periodic => ext / cells as f64,
            };
        }
    }

    /// The cell (per axis) of a point: wrapped into the box along periodic axes, clamped to
    /// the grid along open axes. A point outside an open level's bounding box goes to the
    /// edge cell, whose neighbours still hold every particle within one cell width of it.
    #[inline]
    pub(super) fn cell_at(&self, p: [f64; 3], domain: &Domain) -> [usize; 3] {
        let mut at = [0usize; 3];
        for k in 0..3 {
            if self.axes[k] == Axis::Flat {
                continue;
            }
            let c = match (self.axes[k], domain.periodic_box()) {
                (Axis::Periodic, Some(b)) => b.wrap_coordinate(k, p[k]),
                _ => p[k],
            };
            // ⌊t⌋ for t = (c − origin) / w: `as usize` truncates, which is the floor for
            // t ≥ 0 (inside the grid, up to rounding), and saturates at 0 below it (and at
            // usize::MAX far above it), as clamping ⌊t⌋ would. (No call to `floor`, which
            // is a library call on baseline x86-64.)
            let t = ((c - self.origin[k]) / self.width[k]) as usize;
            at[k] = t.min(self.dims[k] - 1);
        }
        at
    }

    #[inline]
    fn flatten(&self, at: [usize; 3]) -> usize {
        at[0] + self.dims[0] * (at[1] + self.dims[1] * at[2])
    }

    #[inline]
    pub(super) fn unflatten(&self, cell: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims;
        [cell % nx, (cell / nx) % ny, cell / (nx * ny)]
    }

    /// The particles of the cells within `span[k]` cells of `at` along each axis k, each
    /// cell once (a periodic axis wraps, and gives each of its cells once even when the span
    /// covers it all), appended to `out`: the cells of a run along x are one run of
    /// consecutive slots, copied whole.
    #[inline]
    pub(super) fn append_particles(&self, at: [usize; 3], span: [usize; 3], out: &mut Vec<u32>) {
        let [nx, ny, _] = self.dims;
        let (xs, xn) = self.runs(0, at[0], span[0]);
        let (ys, yn) = self.runs(1, at[1], span[1]);
        let (zs, zn) = self.runs(2, at[2], span[2]);
        for &(z0, z1) in &zs[..zn] {
            for z in z0..=z1 {
                for &(y0, y1) in &ys[..yn] {
                    for y in y0..=y1 {
                        let row = nx * (y + ny * z);
                        for &(x0, x1) in &xs[..xn] {
                            let (a, b) = (self.start[row + x0] as usize, self.start[row + x1 + 1] as usize);
                            // A run of a gas holds a few particles: RUN of them copied at once
                            // (a copy of known length, no call, no loop to end) and the
                            // surplus cut, where the run and the order have that many.
                            if b - a <= RUN && a + RUN <= self.order.len() {
                                let at = out.len();
                                out.extend_from_slice(&self.order[a..a + RUN]);
                                out.truncate(at + (b - a));
                            } else {
                                out.extend_from_slice(&self.order[a..b]);
                            }
                        }
                    }
                }
            }
        }
    }

    /// The cells along axis `k` within `span` of cell `c`, as up to two runs of consecutive
    /// cells (first, last): one run on an open axis (clamped to the grid), two where a
    /// periodic axis wraps.
    #[inline]
    fn runs(&self, k: usize, c: usize, span: usize) -> ([(usize, usize); 2], usize) {
        let n = self.dims[k];
        match self.axes[k] {
            Axis::Flat => ([(0, 0); 2], 1),
            Axis::Periodic if 2 * span + 1 >= n => ([(0, n - 1), (0, 0)], 1),
            Axis::Periodic => {
                let (lo, hi) = ((c + n - span) % n, (c + span) % n);
                if lo <= hi {
                    ([(lo, hi), (0, 0)], 1)
                } else {
                    ([(lo, n - 1), (0, hi)], 2)
                }
            }
            Axis::Open => ([(c.saturating_sub(span), (c + span).min(n - 1)), (0, 0)], 1),
        }
    }
}
