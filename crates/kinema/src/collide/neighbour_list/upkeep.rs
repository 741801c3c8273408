//! The neighbour list kept through changes of the particles without a new build: a
//! renumbering (the world's sort along space), a removal (deaths), a birth (newborns
//! admitted one by one).

use rayon::prelude::*;

use super::{active_walls, NeighbourList, Rows, CHUNK};
use crate::collide::groups::Filter;
use crate::collide::{Collider, Domain};

impl NeighbourList {
    /// No list until the next build (which reads nothing of the old one: its rows' room is
    /// kept for it).
    pub(crate) fn expire(&mut self) {
        self.verified = None;
        self.built_at.clear();
    }

    /// Follows a renumbering of the particles, `new_of_old[i]` the new index of particle i:
    /// rows, partners, walls and the build's positions move with their particles (the list
    /// stays the same list, in the new numbering).
    pub(crate) fn renumber(&mut self, new_of_old: &[u32], old_of_new: &[u32]) {
        self.verified = None;
        if self.built_at.is_empty() {
            return;
        }
        let old = std::mem::take(&mut self.rows);
        if self.half {
            self.rows = reoriented(&old, new_of_old);
        } else {
            self.rows = renumbered(&old, new_of_old, old_of_new);
        }
        for w in &mut self.walls {
            w.0 = new_of_old[w.0] as usize;
        }
        self.walls.sort_unstable();
        // the build's positions in the new order: a gather, on all threads
        let mut built = vec![0.0; self.built_at.len()];
        let from = &self.built_at;
        built
            .par_chunks_mut(3)
            .zip(old_of_new.par_iter())
            .with_min_len(CHUNK)
            .for_each(|(b, &o)| b.copy_from_slice(&from[3 * o as usize..3 * o as usize + 3]));
        self.built_at = built;
    }

    /// Follows a removal of particles (`new_of_old[i]`: particle i's new index,
    /// [`GONE`](crate::limits::GONE) for a removed one; the survivors keep their order):
    /// the pairs and collider candidates of the survivors stay, renumbered, with the build's
    /// positions. The list still holds what it held: every pair of survivors within reach at
    /// the build is listed (a removal takes pairs away, never adds one), and a half list
    /// stays a half one (the renumbering keeps the order of indices).
    pub(crate) fn retain_survivors(&mut self, new_of_old: &[u32]) {
        use crate::limits::GONE;
        self.verified = None;
        if self.built_at.is_empty() {
            return;
        }
        let old_of_new: Vec<u32> = (0..new_of_old.len() as u32)
            .filter(|&o| new_of_old[o as usize] != GONE)
            .collect();
        let old = std::mem::take(&mut self.rows);
        self.rows = renumbered(&old, new_of_old, &old_of_new);
        self.walls.retain_mut(|w| match new_of_old[w.0] {
            GONE => false,
            k => {
                w.0 = k as usize;
                true
            }
        });
        self.built_at = old_of_new
            .iter()
            .flat_map(|&o| {
                let o = 3 * o as usize;
                [self.built_at[o], self.built_at[o + 1], self.built_at[o + 2]]
            })
            .collect();
    }

    /// The most particles × newborns [`NeighbourList::admit`] tests one by one; more
    /// newborns than that at once are cheaper to find by a new build on the grid.
    pub(crate) const ADMIT_MAX_TESTS: usize = 1 << 24;

    /// Follows a birth: particles `start..` of `x`, `radius` (m) are new, the others are the
    /// list's own. Each newborn k is listed with every particle i that is within
    /// r_i + r_k + s of it, i's position taken where the build saw it (a newborn's: where it
    /// is born), and as a candidate of every collider within s; its build position is where
    /// it is now. That is the build's own criterion against the build's positions, so the
    /// argument of the type's doc holds unchanged: a newborn has moved 0 since its
    /// "build", and a pair left out was at least r_i + r_k + s apart in build positions. The
    /// rounding allowance grows with the scale if the newborns lie farther out. The rows stay
    /// ascending (a newborn's index exceeds every old one), so the contacts are summed in the
    /// order a new build would give.
    ///
    /// Returns false, leaving no list (the next evaluation builds one), when there is none to
    /// extend or the newborns are too many to test one by one ([`Self::ADMIT_MAX_TESTS`]).
    /// With a `filter` the pairs that do not collide are left out, as a build leaves them.
    pub(crate) fn admit(
        &mut self,
        x: &[f64],
        radius: &[f64],
        colliders: &[Collider],
        domain: &Domain,
        filter: Option<Filter<'_>>,
        start: usize,
    ) -> bool {
        self.verified = None;
        let n = radius.len();
        let fresh = n - start;
        if self.built_at.len() != 3 * start || fresh.saturating_mul(n) > Self::ADMIT_MAX_TESTS || n > u32::MAX as usize {
            self.built_at.clear();
            return false;
        }
        if fresh == 0 {
            return true;
        }
        let skin = self.skin;
        self.built_at.extend_from_slice(&x[3 * start..]);
        let at = |i: usize, b: &[f64]| [b[3 * i], b[3 * i + 1], b[3 * i + 2]];
        // The new pairs (i, k), i < k, k a newborn, by the row of i.
        let mut added: Vec<(u32, u32)> = Vec::new();
        for k in start..n {
            let xk = at(k, &self.built_at);
            for i in 0..k {
                let d = domain.displacement(xk, at(i, &self.built_at));
                let reach = radius[i] + radius[k] + skin;
                if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < reach * reach && filter.is_none_or(|f| f.pair(i, k)) {
                    added.push((i as u32, k as u32));
                }
            }
        }
        added.sort_unstable();
        // Each chunk's rows again, with the additions after each particle's old partners.
        self.rows.resize_with(n.div_ceil(CHUNK), Rows::default);
        let mut next = added.iter().peekable();
        for (c, rows) in self.rows.iter_mut().enumerate() {
            let first = c * CHUNK;
            let end = ((c + 1) * CHUNK).min(n);
            if next.peek().is_none_or(|&&(i, _)| i as usize >= end) && rows.len() == end - first {
                continue; // nothing new in this chunk
            }
            let old = std::mem::take(rows);
            rows.begin();
            for i in first..end {
                if i - first < old.len() {
                    rows.partners.extend_from_slice(old.of(i - first));
                }
                while let Some(&&(a, b)) = next.peek() {
                    if a as usize != i {
                        break;
                    }
                    rows.partners.push(b);
                    next.next();
                }
                rows.end_row();
            }
            rows.seal();
        }
        if !colliders.is_empty() {
            let walled: Vec<bool> = active_walls(colliders, domain).iter().map(|a| a.iter().any(|&w| w)).collect();
            for i in start..n {
                for (k, c) in colliders
                    .iter()
                    .enumerate()
                    .filter(|&(k, _)| walled[k] && filter.is_none_or(|f| f.wall(i, k)))
                {
                    let mut near = c.is_moving();
                    if !near {
                        c.for_each_touch(at(i, x), radius[i], skin, |_| near = true);
                    }
                    if near {
                        self.walls.push((i, k));
                    }
                }
            }
        }
        let largest = |a: &[f64]| a.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
        self.extent[0] = self.extent[0].max(largest(&x[3 * start..]));
        self.extent[2] = self.extent[2].max(largest(&radius[start..]));
        self.allowance = self.allowance_now();
        true
    }
}

/// The rows in the new numbering, particle i's being old particle `old_of_new[i]`'s row,
/// renumbered, without the partners that are gone ([`GONE`](crate::limits::GONE) in
/// `new_of_old`), sorted again (a full list after any renumbering; any list after a
/// removal, which keeps the order of indices).
fn renumbered(old: &[Rows], new_of_old: &[u32], old_of_new: &[u32]) -> Vec<Rows> {
    use crate::limits::GONE;
    let n = old_of_new.len();
    let mut rows: Vec<Rows> = Vec::new();
    rows.resize_with(n.div_ceil(CHUNK), Rows::default);
    rows.par_iter_mut().enumerate().for_each(|(c, rows)| {
        rows.begin();
        for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
            let o = old_of_new[i] as usize;
            let first = rows.partners.len();
            let kept = old[o / CHUNK].of(o % CHUNK).iter().map(|&j| new_of_old[j as usize]);
            rows.partners.extend(kept.filter(|&j| j != GONE));
            rows.partners[first..].sort_unstable();
            rows.end_row();
        }
        rows.seal();
    });
    rows
}

/// A half list's rows in the new numbering. A pair (a, b), a < b, sat in a's row; in the new
/// numbering it belongs in the row of the lower of its two new indices, which may be b's: so
/// the rows are made again from the pairs, by a counting sort on that lower index, and each
/// row sorted (the same rows, in the same order, as a build at the same positions would list).
fn reoriented(old: &[Rows], new_of_old: &[u32]) -> Vec<Rows> {
    let n = new_of_old.len();
    let pairs = || {
        old.iter().enumerate().flat_map(move |(c, rows)| {
            (0..rows.len()).flat_map(move |l| {
                let a = new_of_old[c * CHUNK + l];
                rows.of(l).iter().map(move |&b| {
                    let b = new_of_old[b as usize];
                    (a.min(b) as usize, a.max(b))
                })
            })
        })
    };
    let mut count = vec![0u32; n];
    for (lo, _) in pairs() {
        count[lo] += 1;
    }
    // where each particle's partners start in its chunk's `partners`
    let mut rows: Vec<Rows> = Vec::new();
    rows.resize_with(n.div_ceil(CHUNK), Rows::default);
    let mut cursor = vec![0u32; n];
    for (c, rows) in rows.iter_mut().enumerate() {
        rows.start.push(0);
        let mut at = 0;
        for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
            cursor[i] = at;
            at += count[i];
            rows.start.push(at);
        }
        rows.partners.resize(at as usize, 0);
    }
    for (lo, hi) in pairs() {
        rows[lo / CHUNK].partners[cursor[lo] as usize] = hi;
        cursor[lo] += 1;
    }
    rows.par_iter_mut().for_each(|rows| {
        for l in 0..rows.len() {
            let (a, b) = (rows.start[l] as usize, rows.start[l + 1] as usize);
            rows.partners[a..b].sort_unstable();
        }
        rows.seal();
    });
    rows
}
