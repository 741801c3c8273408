//! The contacts' memory: each touching contact's tangential and rolling springs (its
//! [`Slip`]), kept from one step to the next by the pair (i, j) it belongs to, not by its
//! place in the neighbour list, so that a rebuild of the list, the particles' sort along
//! space, a birth or a death leaves every contact's memory where it was (LAMMPS keeps it
//! per neighbour in `fix neigh/history` and copies it at each rebuild; the same idea).
//!
//! The store is two sorted vectors: particle pairs by (i, j), i < j, and particle–collider
//! touches by (i, collider), in the order the collider lists its touches, each with the
//! touch's normal (a box touches a particle in a corner with two walls at once: the normal
//! tells them apart). A pass reads the store (old) and writes what the contacts are now into
//! per-chunk outboxes (pending); the step that made them accepted, the world swaps them in
//! ([`Histories::accept`]), so that a refused step leaves the memory as it was.
//!
//! A contact that stops touching is forgotten: the next touch starts with unstretched springs
//! (LAMMPS zeroes a neighbour's history when it stops touching).

use crate::limits::GONE;

/// What a contact remembers: the stretch of its springs (see the fields).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Slip {
    /// ξ_t: the tangential spring's stretch, m, the displacement of i's contact point relative
    /// to the partner's accumulated while they touch (in the tangent plane).
    pub shear: [f64; 3],
    /// ξ_r: the rolling spring's stretch, m, R* Δω × n accumulated (in the tangent plane).
    pub roll: [f64; 3],
    /// θ_tw: the twisting spring's angle, rad, (ω_i − ω_j)·n accumulated.
    pub twist: f64,
}

impl Slip {
    /// The same memory seen from the partner's side (the pair's indices swapped): the
    /// tangential stretch is i's relative to j, so it turns over; the rolling stretch
    /// R* (ω_i − ω_j) × n and the twist (ω_i − ω_j)·n keep their sign, since both factors turn
    /// over with n = (x_i − x_j)/|x_i − x_j|.
    pub fn swapped(self) -> Slip {
        Slip {
            shear: self.shear.map(|c| -c),
            ..self
        }
    }

    /// As 7 numbers: shear, roll, twist (for checkpoints).
    pub fn to_array(self) -> [f64; 7] {
        let [a, b, c] = self.shear;
        let [d, e, f] = self.roll;
        [a, b, c, d, e, f, self.twist]
    }

    /// From 7 numbers ([`Slip::to_array`]).
    pub fn from_array(a: [f64; 7]) -> Slip {
        Slip {
            shear: [a[0], a[1], a[2]],
            roll: [a[3], a[4], a[5]],
            twist: a[6],
        }
    }
}

/// The memory of a touching particle pair i < j.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PairSlip {
    pub i: u32,
    pub j: u32,
    pub slip: Slip,
}

/// The memory of a particle touching a collider.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct WallSlip {
    pub i: u32,
    /// The collider, by index.
    pub k: u32,
    /// The touch's normal when it was last seen (which of the collider's touches it is).
    pub normal: [f64; 3],
    pub slip: Slip,
}

/// The store (see the module doc).
#[derive(Debug, Default)]
pub(crate) struct Histories {
    /// Sorted by (i, j).
    pub pairs: Vec<PairSlip>,
    /// Sorted by (i, k), each particle's touches of a collider in the order it lists them.
    pub walls: Vec<WallSlip>,
    /// What the last pass made, per chunk, until accepted.
    pub(super) pending_pairs: Vec<Vec<PairSlip>>,
    pub(super) pending_walls: Vec<Vec<WallSlip>>,
    /// Whether `pending_*` hold a pass's result not yet accepted.
    pub(super) pending: bool,
}

/// A particle's touches of a collider count as the same touch while their normals agree this
/// well (cos of 60°): a box's walls meet at 90°, a mesh's faces seen by one particle at most
/// as steeply as the mesh bends under it.
const SAME_TOUCH: f64 = 0.5;

impl Histories {
    /// The pending memory becomes the store (the step that made it was accepted).
    pub fn accept(&mut self) {
        if !self.pending {
            return;
        }
        self.pending = false;
        self.pairs.clear();
        for p in &mut self.pending_pairs {
            self.pairs.append(p);
        }
        self.walls.clear();
        for w in &mut self.pending_walls {
            self.walls.append(w);
        }
    }

    /// Forgets everything.
    pub fn clear(&mut self) {
        self.pairs.clear();
        self.walls.clear();
        self.pending = false;
    }

    /// Follows a renumbering of the particles (`new_of_old[i]`: particle i's new index; with a
    /// removal, [`GONE`] for the removed: their contacts are forgotten).
    pub fn renumber(&mut self, new_of_old: &[u32]) {
        self.pending = false;
        self.pairs.retain_mut(|p| {
            let (a, b) = (new_of_old[p.i as usize], new_of_old[p.j as usize]);
            if a == GONE || b == GONE {
                return false;
            }
            if a < b {
                (p.i, p.j) = (a, b);
            } else {
                (p.i, p.j, p.slip) = (b, a, p.slip.swapped());
            }
            true
        });
        self.pairs.sort_unstable_by_key(|p| (p.i, p.j));
        self.walls.retain_mut(|w| match new_of_old[w.i as usize] {
            GONE => false,
            a => {
                w.i = a;
                true
            }
        });
        // (stable: a particle's touches of one collider keep their order)
        self.walls.sort_by_key(|w| (w.i, w.k));
    }
}

/// The memory of pair (i, j) in a chunk's part of the store (sorted), if it touched.
#[inline]
pub(super) fn pair_memory(part: &[PairSlip], i: u32, j: u32) -> Option<Slip> {
    part.binary_search_by_key(&(i, j), |p| (p.i, p.j))
        .ok()
        .map(|at| part[at].slip)
}

/// The memory of particle i's touch of collider k with normal `normal` in a chunk's part of
/// the store, if it touched.
#[inline]
pub(super) fn wall_memory(part: &[WallSlip], i: u32, k: u32, normal: [f64; 3]) -> Option<Slip> {
    touches_of(part, i, k)
        .iter()
        .map(|w| (crate::vec3::dot(w.normal, normal), w.slip))
        .filter(|(cos, _)| *cos > SAME_TOUCH)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, s)| s)
}

/// The touches of collider k by particle i remembered in a chunk's part of the store.
#[inline]
pub(super) fn touches_of(part: &[WallSlip], i: u32, k: u32) -> &[WallSlip] {
    let a = part.partition_point(|w| (w.i, w.k) < (i, k));
    let b = a + part[a..].partition_point(|w| (w.i, w.k) == (i, k));
    &part[a..b]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slip(a: f64) -> Slip {
        Slip {
            shear: [a, 0.0, 0.0],
            roll: [0.0, a, 0.0],
            twist: a,
        }
    }

    #[test]
    fn a_renumbering_keeps_each_pairs_memory_and_turns_the_shear_over_when_the_pair_turns() {
        let mut h = Histories {
            pairs: vec![
                PairSlip {
                    i: 0,
                    j: 1,
                    slip: slip(1.0),
                },
                PairSlip {
                    i: 0,
                    j: 2,
                    slip: slip(2.0),
                },
                PairSlip {
                    i: 1,
                    j: 2,
                    slip: slip(3.0),
                },
            ],
            ..Histories::default()
        };
        // 0 → 2, 1 → 0, 2 → 1
        h.renumber(&[2, 0, 1]);
        let keys: Vec<_> = h.pairs.iter().map(|p| (p.i, p.j)).collect();
        assert_eq!(keys, vec![(0, 1), (0, 2), (1, 2)]);
        // old (1, 2) is new (0, 1): same orientation
        assert_eq!(h.pairs[0].slip, slip(3.0));
        // old (0, 1) is new (2, 0) → (0, 2), turned over
        assert_eq!(h.pairs[1].slip, slip(1.0).swapped());
        assert_eq!(h.pairs[1].slip.shear, [-1.0, 0.0, 0.0]);
        assert_eq!(h.pairs[1].slip.roll, [0.0, 1.0, 0.0]);
        // old (0, 2) is new (2, 1) → (1, 2)
        assert_eq!(h.pairs[2].slip, slip(2.0).swapped());
        // a removal forgets the removed particle's contacts
        h.renumber(&[0, GONE, 1]);
        assert_eq!(h.pairs.len(), 1);
        assert_eq!((h.pairs[0].i, h.pairs[0].j), (0, 1));
        assert_eq!(pair_memory(&h.pairs, 0, 1), Some(slip(1.0).swapped()));
        assert_eq!(pair_memory(&h.pairs, 0, 2), None);
    }

    #[test]
    fn a_collider_touch_is_found_by_its_normal() {
        let part = [
            WallSlip {
                i: 3,
                k: 0,
                normal: [0.0, 0.0, 1.0],
                slip: slip(1.0),
            },
            WallSlip {
                i: 3,
                k: 0,
                normal: [1.0, 0.0, 0.0],
                slip: slip(2.0),
            },
        ];
        assert_eq!(wall_memory(&part, 3, 0, [0.1, 0.0, 0.99]), Some(slip(1.0)));
        assert_eq!(wall_memory(&part, 3, 0, [0.99, 0.0, 0.1]), Some(slip(2.0)));
        assert_eq!(wall_memory(&part, 3, 0, [0.0, 1.0, 0.0]), None);
        assert_eq!(wall_memory(&part, 3, 1, [0.0, 0.0, 1.0]), None);
    }
}
