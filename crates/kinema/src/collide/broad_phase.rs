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
//! The search then runs cell by cell over copies of the positions and radii stored in that
//! order, so that a cell's neighbours are read from nearby memory; the pairs it finds are put
//! in (i, j) order by a second counting sort, by i.

use super::domain::Domain;
use crate::error::Error;
use crate::vec3;

/// A candidate pair (i, j) of particle indices, i < j.
pub type Pair = (usize, usize);

/// Relative widening of the cells beyond s = 2 r_max + margin.
///
/// A cell coordinate t = (x − origin) / w is computed with an absolute rounding error of at
/// most about ε·t ≤ ε·T, with T the number of cells along the axis (≤ the cell budget, far
/// below 2³³); two coordinates a distance d < s apart then differ by less than
/// s / w + 2 ε T ≤ 1 / (1 + 10⁻⁶) + 2·2⁻⁵²·2³³ < 1 cell, so they are never two cells apart.
const CELL_SLACK: f64 = 1e-6;

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

/// The broad phase's grid: one uniform grid per size class of particles (a hierarchical grid,
/// as MercuryDPM's HGrid). It keeps its buffers between calls: once warm, a call allocates
/// nothing unless the number of particles, of levels or of found pairs grows.
///
/// A uniform grid needs cells as wide as the largest particle, so one boulder among fine
/// grains puts thousands of grains into each cell and the search becomes quadratic. Here each
/// particle is sorted into the grid of its own level, whose cells are as wide as that level's
/// largest reach s = 2 r + margin (a little more, see `CELL_SLACK`); levels' reaches grow by
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
    /// Pairs in the order found, and per-particle counts for sorting them.
    scratch: Vec<Pair>,
    count: Vec<usize>,
}

/// One uniform grid: the particles of one size class sorted into cells by a counting sort.
#[derive(Debug, Clone, Default)]
struct Level {
    axes: [Axis; 3],
    /// Cells per axis.
    dims: [usize; 3],
    /// Cell widths per axis, m.
    width: [f64; 3],
    /// Lower corner of cell (0, 0, 0), m.
    origin: [f64; 3],
    /// Largest radius of the level's particles, m.
    r_max: f64,
    /// The level's particles in ascending order (unused when there is one level: all are).
    members: Vec<u32>,
    /// First slot of each cell in `order` (one more entry than cells).
    start: Vec<u32>,
    /// Particle indices sorted by cell.
    order: Vec<u32>,
    /// Positions, m, and radii, m, in the order of `order` (for [`Grid::find_pairs`] only;
    /// empty after [`Grid::prepare`]).
    pos: Vec<[f64; 3]>,
    rad: Vec<f64>,
}

impl Grid {
    /// An empty grid; its buffers grow on the first call.
    pub fn new() -> Self {
        Grid::default()
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

    /// Writes into `pairs` (cleared first) every pair (i, j), i < j, with
    /// |x_i − x_j| < r_i + r_j + `margin`, the distance being the minimum image along the
    /// domain's periodic axes; sorted by i, then j.
    ///
    /// `x`: positions, m (3 per particle, finite); `radius`: radii, m (≥ 0, finite, one per
    /// particle); `margin`: m (≥ 0, finite; 0 for contacts now, the distance both can travel
    /// within the step for continuous detection). Zero-radius particles never pair with each
    /// other unless `margin` > 0 (the test is strict: a distance < 0 is impossible).
    ///
    /// The result is exactly [`all_pairs`]'s, in O(N + pairs) time when each level's
    /// particles fill their bounding box (or the periodic box) roughly evenly.
    pub fn find_pairs(
        &mut self,
        x: &[f64],
        radius: &[f64],
        domain: &Domain,
        margin: f64,
        pairs: &mut Vec<Pair>,
    ) -> Result<(), Error> {
        pairs.clear();
        if !self.sort(x, radius, domain, margin, true)? {
            return Ok(());
        }
        // Level by level, cell by cell, so that neighbouring cells (and the copies of their
        // particles' positions, stored in cell order) are read from memory close together.
        let mut found = std::mem::take(&mut self.scratch);
        found.clear();
        let levels = &self.levels[..self.used];
        for (l, level) in levels.iter().enumerate() {
            let cells = level.dims.iter().product::<usize>();
            for cell in 0..cells {
                let at = level.unflatten(cell);
                for a in level.start[cell] as usize..level.start[cell + 1] as usize {
                    let (i, xi, ri) = (level.order[a] as usize, level.pos[a], level.rad[a]);
                    // its own level: each pair once, from its lower index
                    level.visit(at, [1; 3], |b| {
                        let j = level.order[b] as usize;
                        if j > i && touches(domain, xi, level.pos[b], ri, level.rad[b], margin) {
                            found.push((i, j));
                        }
                    });
                    // coarser levels: the pair is found from this, the smaller, side only
                    for coarse in &levels[l + 1..] {
                        coarse.visit(coarse.cell_at(xi, domain), [1; 3], |b| {
                            let j = coarse.order[b] as usize;
                            if touches(domain, xi, coarse.pos[b], ri, coarse.rad[b], margin) {
                                found.push((i.min(j), i.max(j)));
                            }
                        });
                    }
                }
            }
        }
        self.scratch = found;
        self.sort_pairs(radius.len(), pairs);
        Ok(())
    }

    /// Sorts the particles into the levels' cells for [`Grid::partners`] (same arguments,
    /// checks and cell layout as [`Grid::find_pairs`]). Returns false when nothing can pair
    /// (fewer than two particles, or zero reach): every particle has no partner then.
    ///
    /// Unlike [`Grid::find_pairs`] it keeps no copies of the positions and radii in cell
    /// order (32 B per particle): its callers sort their particles along space themselves.
    pub fn prepare(&mut self, x: &[f64], radius: &[f64], domain: &Domain, margin: f64) -> Result<bool, Error> {
        self.sort(x, radius, domain, margin, false)
    }

    /// Sorts the particles into the levels' cells, with copies of their positions and radii
    /// in cell order when `copies`. False when nothing can pair.
    fn sort(&mut self, x: &[f64], radius: &[f64], domain: &Domain, margin: f64, copies: bool) -> Result<bool, Error> {
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
            l.build(x, radius, None, domain, reach_max, &mut self.cell_of, copies);
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
            level.build(x, radius, Some(&members), domain, reach, &mut self.cell_of, copies);
            level.members = members;
        }
        Ok(true)
    }

    /// Particle i's partners in the grid of the last [`Grid::prepare`] (same positions `x`,
    /// m, and `radius`, m): every j ≠ i with |x_i − x_j| < r_i + r_j + `margin` (the pair
    /// test of [`Grid::find_pairs`]), appended to `out` in ascending order of j. Reads the
    /// grid only, so particles can be searched in parallel:
    /// each pair is found twice, once from each side (a full neighbour list).
    ///
    /// In its own and the coarser levels i searches the 3 × 3 × 3 cells around it; in a
    /// finer level, whose cells may be much narrower than i, the cells within
    /// r_i + r_max + margin of it (r_max the finer level's largest radius).
    pub fn partners(&self, i: usize, x: &[f64], radius: &[f64], domain: &Domain, margin: f64, out: &mut Vec<u32>) {
        let first = out.len();
        let (xi, ri) = (vec3::get(x, i), radius[i]);
        let own = self.level_of.get(i).map_or(0, |&l| l as usize);
        let mut search = |level: &Level, at: [usize; 3], span: [usize; 3]| {
            level.visit(at, span, |b| {
                let j = level.order[b] as usize;
                if j != i && touches(domain, xi, vec3::get(x, j), ri, radius[j], margin) {
                    out.push(j as u32);
                }
            });
        };
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
        out[first..].sort_unstable();
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
}

impl Level {
    /// Lays the level out for cells at least `reach` wide and sorts its particles (`members`,
    /// or all when None) into them; writes each one's cell into `cell_of`; copies their
    /// positions and radii in cell order when `copies` (else frees the copies).
    #[allow(clippy::too_many_arguments)]
    fn build(
        &mut self,
        x: &[f64],
        radius: &[f64],
        members: Option<&[u32]>,
        domain: &Domain,
        reach: f64,
        cell_of: &mut [u32],
        copies: bool,
    ) {
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
        for k in 0..count {
            let i = member(k);
            let c = self.flatten(self.cell_at(vec3::get(x, i), domain));
            cell_of[i] = c as u32;
            self.start[c + 1] += 1;
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
        if !copies {
            (self.pos, self.rad) = (Vec::new(), Vec::new());
            return;
        }
        self.pos.clear();
        self.pos.extend(self.order.iter().map(|&i| vec3::get(x, i as usize)));
        self.rad.clear();
        self.rad.extend(self.order.iter().map(|&i| radius[i as usize]));
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
    fn cell_at(&self, p: [f64; 3], domain: &Domain) -> [usize; 3] {
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
    fn unflatten(&self, cell: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims;
        [cell % nx, (cell / nx) % ny, cell / (nx * ny)]
    }

    /// Calls `f` with every slot of the cells within `span[k]` cells of `at` along each axis
    /// k, each cell once (a periodic axis wraps, and visits each of its cells once even when
    /// the span covers it all).
    #[inline]
    fn visit(&self, at: [usize; 3], span: [usize; 3], mut f: impl FnMut(usize)) {
        let [nx, ny, _] = self.dims;
        let (xs, xn) = self.runs(0, at[0], span[0]);
        let (ys, yn) = self.runs(1, at[1], span[1]);
        let (zs, zn) = self.runs(2, at[2], span[2]);
        for &(z0, z1) in &zs[..zn] {
            for z in z0..=z1 {
                for &(y0, y1) in &ys[..yn] {
                    for y in y0..=y1 {
                        let row = nx * (y + ny * z);
                        // consecutive cells along x are one run of consecutive slots
                        for &(x0, x1) in &xs[..xn] {
                            for b in self.start[row + x0]..self.start[row + x1 + 1] {
                                f(b as usize);
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
