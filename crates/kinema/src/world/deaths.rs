//! Deaths the engine applies between steps: particles whose time of death has come
//! and particles inside a kill volume are removed after each step of [`World::advance`], so a
//! world with lifetimes or kill volumes advances any number of steps in one call. Births stay
//! with the caller (Python's emitters draw them from their own random streams, at step
//! boundaries it can compute ahead).
//!
//! A particle dies at the first step boundary t with t ≥ its time of death, or at the first
//! one where its centre is inside a kill volume (Houdini's POP Kill by bounding region): the
//! tests are those of `kinema.emitter`'s `KillBox`, `KillSphere` and `KillPlane`, in the same
//! floating-point operations. Its removal is [`World::remove_particles`]'s, and its id is
//! kept for the caller ([`World::take_removed_ids`]), which drops what it holds for it.

use super::World;
use crate::error::Error;

/// A region whose particles die (their centres: the tests below, boundaries included where
/// the Python classes include them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum KillVolume {
    /// The axis-aligned box lo ≤ x ≤ hi (every axis).
    Box {
        /// Lower corner, m.
        lo: [f64; 3],
        /// Upper corner, m.
        hi: [f64; 3],
    },
    /// The ball |x − center|² ≤ radius².
    Sphere {
        /// Centre, m.
        center: [f64; 3],
        /// Radius, m.
        radius: f64,
    },
    /// Behind the plane: (x − point)·normal < 0.
    Plane {
        /// A point of the plane, m.
        point: [f64; 3],
        /// Its normal, pointing to the side that lives (any length > 0).
        normal: [f64; 3],
    },
}

impl KillVolume {
    /// Checks the volume: finite numbers, lo ≤ hi, a radius > 0, a non-zero normal.
    pub fn validate(&self) -> Result<(), Error> {
        let finite = |name: &str, p: &[f64]| -> Result<(), Error> {
            match p.iter().find(|c| !c.is_finite()) {
                Some(c) => Err(Error::invalid(name, c, "a kill volume's coordinates must be finite")),
                None => Ok(()),
            }
        };
        match self {
            KillVolume::Box { lo, hi } => {
                finite("lo", lo)?;
                finite("hi", hi)?;
                if let Some(k) = (0..3).find(|&k| hi[k] < lo[k]) {
                    return Err(Error::invalid(
                        format!("hi[{k}]"),
                        hi[k],
                        format!("must be >= lo[{k}] = {}", lo[k]),
                    ));
                }
            }
            KillVolume::Sphere { center, radius } => {
                finite("center", center)?;
                if !(radius.is_finite() && *radius > 0.0) {
                    return Err(Error::invalid(
                        "radius",
                        radius,
                        "a kill sphere's radius must be a finite number > 0 m",
                    ));
                }
            }
            KillVolume::Plane { point, normal } => {
                finite("point", point)?;
                finite("normal", normal)?;
                if normal.iter().all(|&c| c == 0.0) {
                    return Err(Error::invalid(
                        "normal",
                        "[0, 0, 0]",
                        "a kill plane's normal must be a non-zero vector",
                    ));
                }
            }
        }
        Ok(())
    }

    /// Whether the centre `x` (m) is inside.
    pub fn contains(&self, x: [f64; 3]) -> bool {
        match self {
            KillVolume::Box { lo, hi } => (0..3).all(|k| x[k] >= lo[k] && x[k] <= hi[k]),
            KillVolume::Sphere { center, radius } => {
                let d = [x[0] - center[0], x[1] - center[1], x[2] - center[2]];
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= radius * radius
            }
            KillVolume::Plane { point, normal } => {
                (x[0] - point[0]) * normal[0] + (x[1] - point[1]) * normal[1] + (x[2] - point[2]) * normal[2] < 0.0
            }
        }
    }
}

/// What the engine removes between steps: each particle's time of death (s; +∞: none) and
/// the kill volumes.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct Deaths {
    /// One per particle, in the particles' current order (empty: nobody dies of age).
    pub time: Vec<f64>,
    pub kills: Vec<KillVolume>,
}

impl Deaths {
    pub(super) fn any(&self) -> bool {
        !self.time.is_empty() || !self.kills.is_empty()
    }

    /// Whether particle i, at positions `x` (m), dies at time t (s).
    fn dead(&self, t: f64, x: &[f64], i: usize) -> bool {
        self.time.get(i).is_some_and(|&d| d <= t) || self.kills.iter().any(|k| k.contains([x[3 * i], x[3 * i + 1], x[3 * i + 2]]))
    }
}

impl World {
    /// Sets the deaths the engine applies after each step: `time_of_death` (s, one per
    /// particle, in the user's order; +∞ or NaN-free values only, `None`: nobody dies of age)
    /// and the kill volumes. Particles added later live forever unless set again.
    pub fn set_deaths(&mut self, time_of_death: Option<Vec<f64>>, kills: Vec<KillVolume>) -> Result<(), Error> {
        let n = self.particles.len();
        if let Some(t) = &time_of_death {
            if t.len() != n {
                return Err(Error::invalid(
                    "time_of_death",
                    format!("{} values", t.len()),
                    format!("one per particle ({n})"),
                ));
            }
            if let Some(i) = t.iter().position(|t| t.is_nan()) {
                return Err(Error::invalid(
                    format!("time_of_death[{i}]"),
                    "NaN",
                    "a time in s, or inf for none",
                ));
            }
        }
        for k in &kills {
            k.validate()?;
        }
        // (in the engine's order, where it keeps one: the particles stay where they are)
        let time = time_of_death.map(|t| match self.user_of() {
            Some(user_of) => user_of.iter().map(|&u| t[u as usize]).collect(),
            None => t,
        });
        self.deaths = Deaths {
            time: time.unwrap_or_default(),
            kills,
        };
        Ok(())
    }

    /// Sets the times of death (s; +∞: never) of the particles `start..start + times.len()`
    /// (the user's order; the particles stay in the engine's where it keeps one): the world
    /// keeps them, with the particles, from here on (a
    /// birth adds +∞, a removal or a death drops its own, the sort moves them). While no
    /// particle has one, none is kept (no memory per particle).
    pub fn set_times_of_death(&mut self, start: usize, times: &[f64]) -> Result<(), Error> {
        let n = self.particles.len();
        if start + times.len() > n {
            return Err(Error::invalid(
                "time_of_death",
                format!("{} values from particle {start}", times.len()),
                format!("particles that exist (0..{n})"),
            ));
        }
        if let Some(i) = times.iter().position(|t| t.is_nan()) {
            return Err(Error::invalid(
                format!("time_of_death[{}]", start + i),
                "NaN",
                "a time in s, or inf for none",
            ));
        }
        if self.deaths.time.is_empty() && times.iter().all(|t| *t == f64::INFINITY) {
            return Ok(());
        }
        let mut time = std::mem::take(&mut self.deaths.time);
        time.resize(n, f64::INFINITY);
        // (in the engine's order, where it keeps one: the particles stay where they are)
        match self.user_of() {
            Some(user_of) => {
                for (engine, &user) in user_of.iter().enumerate() {
                    if let Some(t) = (user as usize).checked_sub(start).and_then(|k| times.get(k)) {
                        time[engine] = *t;
                    }
                }
            }
            None => time[start..start + times.len()].copy_from_slice(times),
        }
        self.deaths.time = time;
        Ok(())
    }

    /// Each particle's time of death (s; +∞: never), in the user's order; empty while no
    /// particle has one.
    pub fn times_of_death(&self) -> Vec<f64> {
        match self.user_of() {
            Some(user_of) if !self.deaths.time.is_empty() => {
                let mut t = vec![f64::INFINITY; self.deaths.time.len()];
                for (engine, &user) in user_of.iter().enumerate() {
                    t[user as usize] = self.deaths.time[engine];
                }
                t
            }
            _ => self.deaths.time.clone(),
        }
    }

    /// Whether some particle has a time of death yet to come or past (a finite one).
    pub fn has_times_of_death(&self) -> bool {
        self.deaths.time.iter().any(|t| t.is_finite())
    }

    /// Sets the kill volumes (each checked); the times of death stay.
    pub fn set_kill_volumes(&mut self, kills: Vec<KillVolume>) -> Result<(), Error> {
        for k in &kills {
            k.validate()?;
        }
        self.deaths.kills = kills;
        Ok(())
    }

    /// The ids of the particles the engine removed since the last call, in the order they died.
    pub fn take_removed_ids(&mut self) -> Vec<u64> {
        std::mem::take(&mut self.removed_ids)
    }

    /// Removes the particles whose death has come at the current time (see the module doc);
    /// called after each step.
    pub(super) fn apply_deaths(&mut self) -> Result<(), Error> {
        if !self.deaths.any() || self.particles.is_empty() {
            return Ok(());
        }
        let t = self.time;
        let x = &self.particles.x;
        if !(0..self.particles.len()).any(|i| self.deaths.dead(t, x, i)) {
            return Ok(());
        }
        // (rare: the user's order again, and the indices of the dead in it)
        self.restore_user_order();
        let x = &self.particles.x;
        let gone: Vec<usize> = (0..self.particles.len()).filter(|&i| self.deaths.dead(t, x, i)).collect();
        let ids: Vec<u64> = gone.iter().map(|&i| self.particles.id[i]).collect();
        self.remove_particles(&gone)?;
        self.removed_ids.extend(ids);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::WorldParams;

    #[test]
    fn the_volumes_contain_their_boundaries_as_the_python_classes_do() {
        let b = KillVolume::Box {
            lo: [0.0; 3],
            hi: [1.0; 3],
        };
        assert!(b.contains([1.0, 0.0, 0.5]) && !b.contains([1.0 + 1e-15, 0.0, 0.5]));
        let s = KillVolume::Sphere {
            center: [0.0; 3],
            radius: 2.0,
        };
        assert!(s.contains([2.0, 0.0, 0.0]) && !s.contains([2.0, 1e-7, 0.0]));
        let p = KillVolume::Plane {
            point: [0.0, 0.0, 1.0],
            normal: [0.0, 0.0, 3.0],
        };
        assert!(!p.contains([5.0, 5.0, 1.0]), "on the plane: alive (< 0 only)");
        assert!(p.contains([5.0, 5.0, 1.0 - 1e-12]));
    }

    #[test]
    fn the_dead_are_removed_after_the_step_their_time_comes_and_their_ids_kept() {
        // Three particles at rest (no forces): 0 dies of age at t = 0.0025 (after step 3 of
        // dt = 1 ms), 2 sits in a kill sphere (removed after the first step), 1 lives.
        let mut w = World::new(WorldParams::default()).unwrap();
        let x = [0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 20.0, 0.0, 0.0];
        w.add_particles(&x, &[0.0; 9], &[1.0; 3], &[0.1; 3], &[false; 3]).unwrap();
        let kills = vec![KillVolume::Sphere {
            center: [20.0, 0.0, 0.0],
            radius: 0.5,
        }];
        w.set_deaths(Some(vec![0.0025, f64::INFINITY, f64::INFINITY]), kills).unwrap();
        w.advance(1).unwrap();
        assert_eq!(w.particles().id, vec![0, 1]);
        assert_eq!(w.take_removed_ids(), vec![2]);
        w.advance(1).unwrap();
        assert_eq!(w.particles().len(), 2, "t = 0.002 < 0.0025");
        w.advance(5).unwrap();
        assert_eq!(w.particles().id, vec![1]);
        assert_eq!(w.take_removed_ids(), vec![0]);
        assert!(w.take_removed_ids().is_empty(), "taken once");
        assert_eq!(w.steps(), 7);
        // added later: lives until set again
        w.add_particles(&[0.0; 3], &[0.0; 3], &[1.0], &[0.1], &[false]).unwrap();
        w.advance(3).unwrap();
        assert_eq!(w.particles().id, vec![1, 3]);
        assert!(w.set_deaths(Some(vec![1.0]), Vec::new()).is_err(), "one per particle");
    }
}
