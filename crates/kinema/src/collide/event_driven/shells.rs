//! Neighbour lists with a shell, kept per particle (Smallenburg, EPJE 45:22 (2022), §2.2).
//!
//! Particle i's list is made at some time with i at its *centre* c_i; it holds every j with
//!
//! ```text
//!   |c_i − c_j| < r_i + r_max + δ        (δ: the shell, m; the minimum image when periodic)
//! ```
//!
//! and i keeps it while it stays within δ/2 of c_i (its *shell*; leaving it is an event, after
//! which the list is made again around the new place). While both i and j stay in their
//! shells, a pair outside each other's lists is at least |c_i − c_j| − δ/2 − δ/2 ≥ r_i + r_j
//! apart: it cannot touch. The lists are symmetric (j in i's list exactly when i is in j's), so
//! that making i's list again can drop i from the lists of those it leaves and add it to those
//! it meets; a pair's distance is always taken between one new centre and one older one,
//! which is what the bound above needs.
//!
//! The centres are found through cells of edge ≥ 2 r_max + δ filed by centre (not by the
//! particle's present place): a particle changes cell only when its list is made again, so
//! there is no cell-crossing event. A cell keeps its members' centres rounded to f32 in blocks
//! of four (x, y, z and the particles, 64 bytes: one cache line), so that the test of a
//! block's four against the reach is a few vector instructions; the reach is widened by the
//! rounding (`Cells::scan`), so the search finds every partner the exact centres would and
//! perhaps a few more, which is harmless: a list may hold extra particles, never lack one. Along an axis that is not periodic the cells cover the
//! range given at construction, and a centre outside it is filed in the nearest end cell
//! (filing by a clamped index keeps two centres closer than one edge in the same or adjacent
//! cells: the search stays exact, it only slows for particles far outside).

use crate::collide::domain::floor;
use crate::collide::Domain;

/// Per-particle neighbour lists (flat, `cap` slots a particle) and the cells of the centres.
pub(super) struct Shells {
    /// The shell δ, m.
    pub delta: f64,
    /// The largest radius, m.
    r_max: f64,
    /// Each particle's list centre (m; wrapped into the periodic cell).
    pub centre: Vec<[f64; 3]>,
    /// Slots per particle in `list`; doubled when a list would overflow.
    cap: usize,
    list: Vec<u32>,
    count: Vec<u32>,
    cells: Cells,
    /// A buffer for `remake`.
    scratch: Vec<u32>,
    /// `remake`'s marks, one per particle: `stamp` on a particle found around the new
    /// centre, `stamp + 1` once it is also found in the old list (older values: neither).
    mark: Vec<u32>,
    stamp: u32,
}

/// The particle of an empty lane.
const EMPTY: u32 = u32::MAX;

/// Four members of a cell: their centres (m, rounded to f32) and indices. An empty lane has
/// an infinite centre (no reach takes it in) and the index `EMPTY`; a cell's members fill
/// its first lanes.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct Block {
    x: [f32; 4],
    y: [f32; 4],
    z: [f32; 4],
    id: [u32; 4],
}

impl Block {
    const EMPTY: Block = Block {
        x: [f32::INFINITY; 4],
        y: [f32::INFINITY; 4],
        z: [f32::INFINITY; 4],
        id: [EMPTY; 4],
    };

    fn set(&mut self, lane: usize, c: [f64; 3], id: u32) {
        self.x[lane] = c[0] as f32;
        self.y[lane] = c[1] as f32;
        self.z[lane] = c[2] as f32;
        self.id[lane] = id;
    }

    fn take(&self, lane: usize) -> ([f32; 3], u32) {
        ([self.x[lane], self.y[lane], self.z[lane]], self.id[lane])
    }

    fn put(&mut self, lane: usize, (c, id): ([f32; 3], u32)) {
        self.x[lane] = c[0];
        self.y[lane] = c[1];
        self.z[lane] = c[2];
        self.id[lane] = id;
    }
}

/// One cell of [`Cells::around`] along one axis: its coordinate, the shift of its members'
/// images (m) and its gap to the point (m).
#[derive(Debug, Clone, Copy, Default)]
struct Span {
    cell: usize,
    shift: f64,
    gap: f64,
}

impl Span {
    fn new(cell: usize, shift: f64, gap: f64) -> Self {
        Span { cell, shift, gap }
    }
}

/// Cells of edge ≥ `edge` over [lo, lo + n·edge) along each axis. Each cell is `blocks`
/// consecutive [`Block`]s of one flat array (x-neighbouring cells are adjacent).
struct Cells {
    lo: [f64; 3],
    /// The cells' edge along each axis (m) and its inverse.
    edge: [f64; 3],
    inv_edge: [f64; 3],
    n: [usize; 3],
    /// The period along each periodic axis (0 along the others), m.
    period: [f64; 3],
    /// Blocks per cell; doubled when a cell would overflow.
    blocks: usize,
    block: Vec<Block>,
    filled: Vec<u32>,
    /// The cell each particle is filed in (`u32::MAX`: none yet), and its lane there.
    cell_of: Vec<u32>,
    lane_of: Vec<u32>,
}

impl Cells {
    /// Cells over [lo, hi] (m, finite, hi ≥ lo) of edge at least `edge` (m, > 0) along each
    /// axis (one cell along an axis shorter than that); periodic axes (`period` > 0) wrap.
    fn new(lo: [f64; 3], hi: [f64; 3], edge: f64, period: [f64; 3], particles: usize) -> Self {
        let mut n = [1usize; 3];
        let mut inv_edge = [0.0; 3];
        let mut edges = [0.0; 3];
        for k in 0..3 {
            let span = hi[k] - lo[k];
            // at most ~8 cells a particle along all axes together: no more are useful
            let most = ((particles.max(1) as f64) * 8.0).cbrt().ceil().max(1.0);
            n[k] = ((span / edge).floor()).clamp(1.0, most) as usize;
            inv_edge[k] = if span > 0.0 { n[k] as f64 / span } else { 0.0 };
            edges[k] = span / n[k] as f64;
        }
        let cells = n[0] * n[1] * n[2];
        Cells {
            lo,
            edge: edges,
            inv_edge,
            n,
            period,
            blocks: 1,
            block: vec![Block::EMPTY; cells],
            filled: vec![0; cells],
            cell_of: vec![u32::MAX; particles],
            lane_of: vec![0; particles],
        }
    }

    /// The cell coordinates of point `p` (clamped into the grid).
    #[inline(always)]
    fn coords(&self, p: [f64; 3]) -> [usize; 3] {
        [0, 1, 2].map(|k| {
            let c = floor((p[k] - self.lo[k]) * self.inv_edge[k]);
            c.clamp(0.0, (self.n[k] - 1) as f64) as usize
        })
    }

    #[inline(always)]
    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.n[1] + c[1]) * self.n[0] + c[0]
    }

    /// Files particle i at centre `p`, taking it out of its old cell.
    #[inline(always)]
    fn file(&mut self, i: usize, p: [f64; 3]) {
        let cell = self.index(self.coords(p));
        let old = self.cell_of[i];
        if old as usize == cell {
            let lane = self.lane_of[i] as usize;
            self.block[cell * self.blocks + lane / 4].set(lane % 4, p, i as u32);
            return;
        }
        if old != u32::MAX {
            // the cell's last member takes i's lane
            let (old, lane) = (old as usize, self.lane_of[i] as usize);
            let last = self.filled[old] as usize - 1;
            let base = old * self.blocks;
            let moved = self.block[base + last / 4].take(last % 4);
            self.block[base + lane / 4].put(lane % 4, moved);
            self.lane_of[moved.1 as usize] = lane as u32;
            self.block[base + last / 4].put(last % 4, Block::EMPTY.take(0));
            self.filled[old] -= 1;
        }
        if self.filled[cell] as usize == 4 * self.blocks {
            self.grow();
        }
        let lane = self.filled[cell] as usize;
        self.block[cell * self.blocks + lane / 4].set(lane % 4, p, i as u32);
        self.filled[cell] += 1;
        self.cell_of[i] = cell as u32;
        self.lane_of[i] = lane as u32;
    }

    /// Doubles every cell's room.
    fn grow(&mut self) {
        let (old, blocks) = (self.blocks, 2 * self.blocks);
        let mut block = vec![Block::EMPTY; blocks * self.filled.len()];
        for c in 0..self.filled.len() {
            block[c * blocks..c * blocks + old].copy_from_slice(&self.block[c * old..(c + 1) * old]);
        }
        self.block = block;
        self.blocks = blocks;
    }

    /// The cells around the cell of `p` (its own and the adjacent ones, each once) with, along
    /// each axis, the shift s (m) that makes c + s a member's image nearest to `p` when the
    /// axis wraps (0 otherwise) and the gap (m) between p and the cell along the axis (0 for
    /// p's own; no member of the cell is nearer than that along it, up to the rounding of
    /// the cell's bounds): per axis up to 3 [`Span`]s. `exact`: false when a periodic axis
    /// has fewer than 3 cells (then the shifts are not the minimum image and the caller must
    /// take it pair by pair).
    #[inline(always)]
    fn around(&self, p: [f64; 3]) -> ([[Span; 3]; 3], [usize; 3], bool) {
        let c = self.coords(p);
        let mut span = [[Span::default(); 3]; 3];
        let mut count = [0usize; 3];
        let mut exact = true;
        for k in 0..3 {
            let n = self.n[k];
            let l = self.period[k];
            // p's distances to its own cell's lower and upper faces (a member of a lower cell
            // lies below the lower face, of a higher one above the upper: clamped end cells
            // hold members beyond the range only on their outer side)
            let below = (p[k] - (self.lo[k] + c[k] as f64 * self.edge[k])).max(0.0);
            let above = (self.lo[k] + (c[k] + 1) as f64 * self.edge[k] - p[k]).max(0.0);
            let own = Span::new(c[k], 0.0, 0.0);
            if l > 0.0 && n >= 3 {
                let left = if c[k] == 0 { (n - 1, -l) } else { (c[k] - 1, 0.0) };
                let right = if c[k] == n - 1 { (0, l) } else { (c[k] + 1, 0.0) };
                span[k] = [Span::new(left.0, left.1, below), own, Span::new(right.0, right.1, above)];
                count[k] = 3;
            } else if l > 0.0 {
                exact = false;
                for (m, s) in span[k].iter_mut().enumerate().take(n) {
                    *s = Span::new(m, 0.0, 0.0);
                }
                count[k] = n;
            } else {
                let first = c[k].saturating_sub(1);
                let last = (c[k] + 1).min(n - 1);
                for (m, s) in (first..=last).enumerate() {
                    let gap = match s.cmp(&c[k]) {
                        std::cmp::Ordering::Less => below,
                        std::cmp::Ordering::Equal => 0.0,
                        std::cmp::Ordering::Greater => above,
                    };
                    span[k][m] = Span::new(s, 0.0, gap);
                }
                count[k] = last - first + 1;
            }
        }
        (span, count, exact)
    }

    /// Pushes onto `out` every particle filed in the cells around `p` (m) whose centre may be
    /// within `reach` (m) of p: the rounded centres are tested against the reach widened by
    /// their rounding (module doc). `None` where this test cannot be exact (a periodic axis of
    /// fewer than 3 cells, or coordinates beyond 10³⁰ m): the caller tests exactly.
    #[inline(always)]
    fn scan(&self, p: [f64; 3], reach: f64, out: &mut Vec<u32>) -> Option<()> {
        let (span, count, exact) = self.around(p);
        let big = p.iter().fold(0.0f64, |m, c| m.max(c.abs())) + self.period.iter().fold(0.0f64, |m, &l| m.max(l));
        if !exact || big > 1e30 {
            return None;
        }
        // The f32 test's error: each of the centre, p − s and the difference rounds once at
        // ≤ 2⁻²⁴ of magnitudes ≤ big + 2 reach, and the squared length's three products and two
        // sums at ≤ 2⁻²⁴ each of |d|² ≤ (reach)²: 2⁻¹⁹ (big + 2 reach) covers them with room.
        let slack = 2f64.powi(-19) * (big + 2.0 * reach);
        let widened = (reach + slack) as f32 * (1.0 + 1e-6);
        let r2 = widened * widened;
        // The cells that may hold a member the test below takes in: those whose gap to p is
        // within the widened reach and the f32 test's error (a corner cell of the 27 lies
        // beyond it about half the time, an edge cell a fifth), each with p − s, its first
        // block asked of the cache before the first is read (the scan waits on each block's
        // line otherwise: the cells outgrow a core's cache)
        let far = (widened as f64 + 2.0 * slack) * (widened as f64 + 2.0 * slack);
        let mut visit = [(0usize, [0.0f32; 3]); 27];
        let mut visits = 0;
        for sz in &span[2][..count[2]] {
            for sy in &span[1][..count[1]] {
                for sx in &span[0][..count[0]] {
                    if sx.gap * sx.gap + sy.gap * sy.gap + sz.gap * sz.gap > far {
                        continue;
                    }
                    let cell = self.index([sx.cell, sy.cell, sz.cell]);
                    crate::simd::prefetch(&self.block[cell * self.blocks]);
                    // the members' images are at c + s: p − (c + s) = (p − s) − c
                    let q = [(p[0] - sx.shift) as f32, (p[1] - sy.shift) as f32, (p[2] - sz.shift) as f32];
                    visit[visits] = (cell, q);
                    visits += 1;
                }
            }
        }
        for &(cell, q) in &visit[..visits] {
            for b in &self.block[cell * self.blocks..(cell + 1) * self.blocks] {
                let mut near = [false; 4];
                for l in 0..4 {
                    let (dx, dy, dz) = (q[0] - b.x[l], q[1] - b.y[l], q[2] - b.z[l]);
                    near[l] = dx * dx + dy * dy + dz * dz < r2;
                }
                // the near lanes' ids kept in order without a branch per lane: each
                // written at the end, the end moved past it only if near
                let start = out.len();
                out.extend_from_slice(&b.id);
                let mut kept = start;
                for l in 0..4 {
                    out[kept] = b.id[l];
                    kept += near[l] as usize;
                }
                out.truncate(kept);
                if b.id[3] == EMPTY {
                    break; // the cell's members end in this block
                }
            }
        }
        Some(())
    }

    /// Every particle filed in the cells around `p`, for the caller's exact test.
    fn members_around(&self, p: [f64; 3], out: &mut Vec<u32>) {
        let (span, count, _) = self.around(p);
        for sz in &span[2][..count[2]] {
            for sy in &span[1][..count[1]] {
                for sx in &span[0][..count[0]] {
                    let cell = self.index([sx.cell, sy.cell, sz.cell]);
                    for b in &self.block[cell * self.blocks..(cell + 1) * self.blocks] {
                        out.extend(b.id.iter().copied().filter(|&j| j != EMPTY));
                    }
                }
            }
        }
    }
}

impl Shells {
    /// Lists for every particle, each centred at its position `x[i]` (already wrapped), with
    /// shell `delta` (m), cells over [lo, hi] (m).
    pub fn new(x: &[[f64; 3]], radius: &[f64], domain: &Domain, lo: [f64; 3], hi: [f64; 3], delta: f64) -> Self {
        let n = x.len();
        let r_max = radius.iter().cloned().fold(0.0, f64::max);
        let period = domain
            .periodic_box()
            .map_or([0.0; 3], |p| [0, 1, 2].map(|k| if p.axes()[k] { p.period(k) } else { 0.0 }));
        let cells = Cells::new(lo, hi, 2.0 * r_max + delta, period, n);
        let mut shells = Shells {
            delta,
            r_max,
            centre: x.to_vec(),
            cap: 16,
            list: vec![0; 16 * n],
            count: vec![0; n],
            cells,
            scratch: Vec::new(),
            mark: vec![0; n],
            stamp: 0,
        };
        for (i, &p) in x.iter().enumerate() {
            shells.cells.file(i, p);
        }
        // every pair once, from its lower index's side, into both lists: the lists are
        // symmetric (and stay so: `remake` adds and removes both ways)
        let mut found = Vec::new();
        for i in 0..n {
            shells.find_near(i, shells.centre[i], radius[i], domain, &mut found);
            for &j in found.iter().filter(|&&j| j as usize > i) {
                shells.append(i, j);
                shells.append(j as usize, i as u32);
            }
        }
        shells
    }

    /// Into `found`: the particles other than i whose centres may be within r_i + r_max + δ
    /// of `at` (every partner of i centred there; module doc).
    #[inline(always)]
    fn find_near(&self, i: usize, at: [f64; 3], r_i: f64, domain: &Domain, found: &mut Vec<u32>) {
        found.clear();
        let reach = r_i + self.r_max + self.delta;
        if self.cells.scan(at, reach, found).is_none() {
            found.clear();
            self.cells.members_around(at, found);
            found.retain(|&j| {
                let d = domain.displacement(at, self.centre[j as usize]);
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < reach * reach
            });
        }
        found.retain(|&j| j as usize != i);
    }

    /// Particle i's list.
    #[inline]
    pub fn of(&self, i: usize) -> &[u32] {
        &self.list[i * self.cap..i * self.cap + self.count[i] as usize]
    }

    /// Adds j to i's list, doubling every list's room when i's is full.
    #[inline(always)]
    fn append(&mut self, i: usize, j: u32) {
        if self.count[i] as usize == self.cap {
            let (old, cap) = (self.cap, 2 * self.cap);
            let mut list = vec![0; cap * self.count.len()];
            for (k, &c) in self.count.iter().enumerate() {
                list[k * cap..k * cap + c as usize].copy_from_slice(&self.list[k * old..k * old + c as usize]);
            }
            self.list = list;
            self.cap = cap;
        }
        self.list[i * self.cap + self.count[i] as usize] = j;
        self.count[i] += 1;
    }

    /// Takes j out of i's list (if there).
    #[inline(always)]
    fn remove(&mut self, i: usize, j: u32) {
        let start = i * self.cap;
        let c = self.count[i] as usize;
        if let Some(k) = self.list[start..start + c].iter().position(|&m| m == j) {
            self.list[start + k] = self.list[start + c - 1];
            self.count[i] -= 1;
        }
    }

    /// Makes particle i's list again around `at` (m, wrapped): i leaves the lists of the old
    /// partners it no longer reaches and joins those of the new ones (module doc); the lists
    /// of partners it keeps (most: it moved only δ/2) are not touched.
    #[inline(always)]
    pub fn remake(&mut self, i: usize, at: [f64; 3], radius: &[f64], domain: &Domain) {
        let mut found = std::mem::take(&mut self.scratch);
        // the old partners' lists, of which those i leaves lose it below, asked of the cache
        // while the cells are searched
        for &j in self.of(i) {
            crate::simd::prefetch(&self.list[j as usize * self.cap]);
        }
        self.centre[i] = at;
        self.cells.file(i, at);
        self.find_near(i, at, radius[i], domain, &mut found);
        // old partners not found again leave; found ones not there before join (found ones
        // marked, then those of the old list marked again: a pass over each instead of a
        // search of one list for each member of the other)
        self.stamp = self.stamp.wrapping_add(2);
        if self.stamp < 2 {
            self.mark.fill(0); // the stamps wrapped: no old mark may equal a new one
            self.stamp = 2;
        }
        let (found_now, listed_too) = (self.stamp, self.stamp + 1);
        for &j in &found {
            self.mark[j as usize] = found_now;
        }
        let start = i * self.cap;
        let mut k = 0;
        while k < self.count[i] as usize {
            let j = self.list[start + k];
            if self.mark[j as usize] == found_now {
                self.mark[j as usize] = listed_too;
                k += 1;
            } else {
                self.remove(j as usize, i as u32);
                self.count[i] -= 1;
                self.list[start + k] = self.list[start + self.count[i] as usize];
            }
        }
        for &j in &found {
            if self.mark[j as usize] == found_now {
                self.append(i, j);
                self.append(j as usize, i as u32);
            }
        }
        self.scratch = found;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Cells::scan` finds every filed centre within the reach of a point, as the plain test
    /// of every centre does (the minimum image where the axes wrap), though it skips the
    /// cells whose gap to the point is beyond the reach: random centres and points in a
    /// periodic cell, and in an open range with some beyond its ends (filed in the clamped
    /// end cells).
    #[test]
    fn the_scan_finds_every_centre_within_reach() {
        let mut next = super::super::tests::uniform(99);
        let (lo, hi, reach) = ([0.0; 3], [10.0, 8.0, 12.0], 1.7);
        for periodic in [false, true] {
            let period = if periodic { hi } else { [0.0; 3] };
            // (beyond the open range by up to 3 m on either side)
            let spread = if periodic { 0.0 } else { 3.0 };
            let mut point = || [0, 1, 2].map(|k| lo[k] - spread + (hi[k] - lo[k] + 2.0 * spread) * next());
            let centres: Vec<[f64; 3]> = (0..2000).map(|_| point()).collect();
            let mut cells = Cells::new(lo, hi, reach, period, centres.len());
            for (i, &c) in centres.iter().enumerate() {
                cells.file(i, c);
            }
            let mut found = Vec::new();
            let mut within_reach = 0;
            for _ in 0..1000 {
                let p = point();
                found.clear();
                cells.scan(p, reach, &mut found).expect("an exact scan");
                for (j, c) in centres.iter().enumerate() {
                    let d = [0, 1, 2].map(|k| {
                        let d = p[k] - c[k];
                        if period[k] > 0.0 {
                            d - period[k] * (d / period[k]).round()
                        } else {
                            d
                        }
                    });
                    if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < reach * reach {
                        within_reach += 1;
                        assert!(
                            found.contains(&(j as u32)),
                            "centre {j} at {c:?} is within reach of {p:?} but not found (periodic: {periodic})"
                        );
                    }
                }
            }
            assert!(within_reach > 5000, "{within_reach} pairs within reach");
        }
    }
}
