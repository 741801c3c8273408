//! Collision groups: which particle pairs, and which particles and colliders, collide
//! (Box2D's category and mask bits, Bullet's collision filter groups).
//!
//! Each particle is in one group g ∈ 0..[`GROUPS`] (`Particles::group`; empty while every
//! particle is in group 0), its category bit 1 << g. The world keeps one mask per group,
//! `masks[g]`, bit h set when groups g and h collide: a symmetric 32 × 32 matrix, all set by
//! default, kept symmetric by [`GroupMasks::set`] (setting (a, b) sets (b, a)). Particles i and
//! j collide iff `masks[g_i]` has bit g_j, and `CollisionParams::self_collisions` (false: no
//! particle pair collides, whatever the matrix; the colliders still do). Each collider has a
//! mask of the groups it collides with (all by default).
//!
//! The filter is applied where the candidate pairs are made, once: the neighbour lists
//! (`neighbour_list.rs`: a filtered pair or particle–collider pair is never listed, so neither
//! continuous detection, the end-of-step contacts, the islands, the force models' pair pass nor
//! `World::contacts` ever see it, and costs nothing after the build), the placement check, and
//! the event-driven search. With nothing filtered ([`Filter::of`] gives `None`) those paths run
//! exactly as without groups. A change of groups, of the matrix or of a collider's mask makes the
//! world forget its lists.

/// The number of collision groups: a group is a bit of a `u32` mask.
pub const GROUPS: usize = 32;

/// Every group's bit.
pub const ALL: u32 = u32::MAX;

/// The group matrix as one mask per group: bit h of `masks[g]` set when groups g and h collide.
/// Symmetric; all set by default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroupMasks {
    masks: [u32; GROUPS],
}

impl Default for GroupMasks {
    fn default() -> Self {
        GroupMasks { masks: [ALL; GROUPS] }
    }
}

impl GroupMasks {
    /// The masks from 32 rows, checked symmetric; the error names the first pair that is not.
    pub fn from_rows(masks: [u32; GROUPS]) -> Result<Self, crate::error::Error> {
        for a in 0..GROUPS {
            for b in a + 1..GROUPS {
                if (masks[a] >> b & 1) != (masks[b] >> a & 1) {
                    return Err(crate::error::Error::invalid(
                        format!("collision_matrix[{a}][{b}]"),
                        masks[a] >> b & 1 == 1,
                        format!(
                            "a symmetric matrix: collision_matrix[{b}][{a}] is {}; groups {a} and {b} collide or not both ways",
                            masks[b] >> a & 1 == 1
                        ),
                    ));
                }
            }
        }
        Ok(GroupMasks { masks })
    }

    /// Sets whether groups `a` and `b` collide (both ways).
    pub fn set(&mut self, a: usize, b: usize, collide: bool) -> Result<(), crate::error::Error> {
        for (name, g) in [("a", a), ("b", b)] {
            check_group(name, g as u64)?;
        }
        if collide {
            self.masks[a] |= 1 << b;
            self.masks[b] |= 1 << a;
        } else {
            self.masks[a] &= !(1 << b);
            self.masks[b] &= !(1 << a);
        }
        Ok(())
    }

    /// Whether groups `a` and `b` collide.
    pub fn collide(&self, a: usize, b: usize) -> bool {
        self.masks[a] >> b & 1 == 1
    }

    /// The masks, one per group.
    pub fn rows(&self) -> [u32; GROUPS] {
        self.masks
    }

    /// Whether every pair of groups collides (the default).
    pub fn all(&self) -> bool {
        self.masks.iter().all(|&m| m == ALL)
    }
}

/// Refuses a group outside 0..[`GROUPS`]; the error names `name`.
pub fn check_group(name: &str, g: u64) -> Result<(), crate::error::Error> {
    if g >= GROUPS as u64 {
        return Err(crate::error::Error::invalid(
            name,
            g,
            format!(
                "a collision group is an integer in 0..{} (a bit of a 32-bit mask)",
                GROUPS - 1
            ),
        ));
    }
    Ok(())
}

/// What the contact searches read of the groups, when something is filtered: each particle's
/// group, the masks in effect (all 0 without self collisions) and each collider's mask.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Filter<'a> {
    /// Each particle's group (empty: all in group 0).
    groups: &'a [u8],
    masks: [u32; GROUPS],
    /// Each collider's mask (a collider past the end collides with every group).
    colliders: &'a [u32],
}

impl<'a> Filter<'a> {
    /// The filter of particles in `groups` under `masks` (with `self_collisions`) and colliders
    /// of `colliders` masks; `None` when nothing is filtered, so that the searches run
    /// unchanged.
    pub fn of(groups: &'a [u8], masks: &GroupMasks, self_collisions: bool, colliders: &'a [u32]) -> Option<Self> {
        if self_collisions && masks.all() && colliders.iter().all(|&m| m == ALL) {
            return None;
        }
        Some(Filter {
            groups,
            masks: if self_collisions { masks.masks } else { [0; GROUPS] },
            colliders,
        })
    }

    /// Particle i's group.
    #[inline]
    pub fn group(&self, i: usize) -> usize {
        self.groups.get(i).map_or(0, |&g| g as usize)
    }

    /// The groups particle i collides with (a mask).
    #[inline]
    pub fn mask(&self, i: usize) -> u32 {
        self.masks[self.group(i)]
    }

    /// Whether particles i and j collide.
    #[inline]
    pub fn pair(&self, i: usize, j: usize) -> bool {
        self.mask(i) >> self.group(j) & 1 == 1
    }

    /// Whether particle i and collider k collide.
    #[inline]
    pub fn wall(&self, i: usize, k: usize) -> bool {
        self.colliders.get(k).is_none_or(|m| m >> self.group(i) & 1 == 1)
    }

    /// Collider k's mask.
    pub fn collider_mask(&self, k: usize) -> u32 {
        self.colliders.get(k).copied().unwrap_or(ALL)
    }

    /// The masks in effect, one per group.
    pub fn masks(&self) -> [u32; GROUPS] {
        self.masks
    }

    /// Whether no particle pair collides at all (the pair search can be skipped).
    pub fn no_pairs(&self) -> bool {
        self.masks.iter().all(|&m| m == 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn setting_a_pair_sets_both_ways_and_the_filter_reads_it() {
        let mut m = GroupMasks::default();
        m.set(0, 1, false).unwrap();
        assert!(!m.collide(0, 1) && !m.collide(1, 0) && m.collide(0, 0) && m.collide(1, 1));
        assert!(GroupMasks::from_rows(m.rows()).is_ok());
        let groups = [0u8, 1, 0];
        let colliders = [ALL, 0b01];
        let f = Filter::of(&groups, &m, true, &colliders).unwrap();
        assert!(!f.pair(0, 1) && !f.pair(1, 0) && f.pair(0, 2));
        assert!(f.wall(1, 0) && !f.wall(1, 1) && f.wall(0, 1) && f.wall(2, 5));
        let off = Filter::of(&groups, &GroupMasks::default(), false, &[]).unwrap();
        assert!(off.no_pairs() && !off.pair(0, 2) && off.wall(1, 0));
        assert!(Filter::of(&groups, &GroupMasks::default(), true, &[ALL]).is_none());
    }

    #[test]
    fn an_asymmetric_matrix_and_a_group_out_of_range_are_refused() {
        let mut rows = [ALL; GROUPS];
        rows[3] &= !(1 << 5);
        let e = GroupMasks::from_rows(rows).unwrap_err().to_string();
        assert!(e.contains("collision_matrix[3][5]") && e.contains("symmetric"), "{e}");
        let e = GroupMasks::default().set(0, 32, true).unwrap_err().to_string();
        assert!(e.contains("b") && e.contains("0..31"), "{e}");
    }
}
