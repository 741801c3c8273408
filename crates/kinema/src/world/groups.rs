//! The collision groups as the world holds them (`collide/groups.rs`): each particle's group,
//! the groups' matrix of which collide, and each collider's mask.

use super::{CollisionParams, World};
use crate::collide::GroupMasks;
use crate::error::Error;

impl World {
    /// Puts particles `start..start + group.len()` into the collision groups `group` (0..32,
    /// `collide/groups.rs`); the contact lists start over. Groups are kept with collisions off.
    pub fn set_particle_groups(&mut self, start: usize, group: &[u32]) -> Result<(), Error> {
        let n = self.particles.len();
        if start + group.len() > n {
            return Err(Error::invalid(
                "group",
                format!("{} values from particle {start}", group.len()),
                format!("one collision group per particle, within the {n} particles"),
            ));
        }
        super::contents::check_groups(group, group.len())?;
        let p = &mut self.particles;
        if p.group.is_empty() && group.iter().all(|&g| g == 0) {
            return Ok(());
        }
        p.group.resize(n, 0);
        for (k, &g) in group.iter().enumerate() {
            p.group[start + k] = g as u8;
        }
        if p.group.iter().all(|&g| g == 0) {
            p.group.clear();
        }
        // (a pair that collides now may overlap: the placement check looks at them again)
        self.check_placement_from(start);
        self.contacts_changed();
        Ok(())
    }

    /// Each particle's collision group (all 0 unless set).
    pub fn particle_groups(&self) -> Vec<u32> {
        let p = &self.particles;
        (0..p.len()).map(|i| p.group.get(i).map_or(0, |&g| g as u32)).collect()
    }

    /// Sets whether collision groups `a` and `b` collide (both ways: the matrix stays
    /// symmetric); turns collisions on if they are off.
    pub fn set_group_collisions(&mut self, a: usize, b: usize, collide: bool) -> Result<(), Error> {
        let mut masks = self.group_masks();
        masks.set(a, b, collide)?;
        self.set_group_masks(masks)
    }

    /// The collision groups' matrix, as one mask per group (all set while collisions are off).
    pub fn group_masks(&self) -> GroupMasks {
        self.collide_stage.as_ref().map(|c| c.group_masks).unwrap_or_default()
    }

    /// Sets the collision groups' matrix; turns collisions on if they are off.
    pub fn set_group_masks(&mut self, masks: GroupMasks) -> Result<(), Error> {
        if self.collide_stage.is_none() {
            self.set_collisions(CollisionParams::default())?;
        }
        let stage = self.collide_stage.as_mut().expect("collisions are on");
        if stage.group_masks != masks {
            stage.group_masks = masks;
            self.contacts_changed();
        }
        Ok(())
    }

    /// Sets the groups collider `k` collides with (`mask`: bit g for group g).
    pub fn set_collider_mask(&mut self, k: usize, mask: u32) -> Result<(), Error> {
        let Some(stage) = self.collide_stage.as_mut().filter(|s| k < s.colliders.len()) else {
            let n = self.collide_stage.as_ref().map_or(0, |s| s.colliders.len());
            return Err(Error::invalid(
                "collider",
                k,
                format!("an index below the number of colliders ({n})"),
            ));
        };
        stage
            .collider_masks
            .resize(stage.colliders.len(), crate::collide::groups::ALL);
        if stage.collider_masks[k] != mask {
            stage.collider_masks[k] = mask;
            self.check_placement_from(0);
            self.contacts_changed();
        }
        Ok(())
    }

    /// Each collider's mask of the groups it collides with, in the order added.
    pub fn collider_masks(&self) -> Vec<u32> {
        self.collide_stage.as_ref().map_or_else(Vec::new, |s| {
            (0..s.colliders.len())
                .map(|k| s.collider_masks.get(k).copied().unwrap_or(crate::collide::groups::ALL))
                .collect()
        })
    }
}
