//! The world's clock: the time after each step, and the length of the next one.
//!
//! A world steps by its `dt`, the time after k steps computed by multiplication from an
//! anchor (t = t₀ + (k − k₀)·h), so that it does not drift as a running sum would. A run that
//! records frames at exact times t₀ + k/fps plans each frame's steps ([`Clock::land`]): the
//! next n steps are of length h = (t₁ − t)/n ≤ dt and the n-th ends at t₁ exactly, after which
//! the clock goes on by dt from there (the frame is the new anchor). That is how Blender and
//! Houdini step a frame, by a whole number of substeps; `World.run` chooses n =
//! ⌈1/(fps·dt)⌉, so no step is longer than the dt asked.

use crate::error::Error;

/// A stretch's share per step within this fraction of dt counts as dt (1/(fps·dt) is a whole
/// number but for the rounding of its parts: 1/(50 · 0.001) = 20.000000000000004).
const DIVIDES: f64 = 1e-9;

/// The anchor (k₀ steps at t₀, s) and the step h (s) of the time after k ≥ k₀ steps,
/// t₀ + (k − k₀)·h; with a landing, after k₁ steps the time is t₁ exactly and steps are dt
/// from there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clock {
    /// Steps at the anchor.
    pub k0: u64,
    /// The time at the anchor, s.
    pub t0: f64,
    /// The length of the steps from the anchor, s.
    pub h: f64,
    /// A planned landing (k₁ steps, t₁ s): the time after k₁ steps, exactly.
    pub landing: Option<(u64, f64)>,
}

impl Clock {
    /// The clock of a new world: t = k·dt.
    pub fn new(dt: f64) -> Clock {
        Clock {
            k0: 0,
            t0: 0.0,
            h: dt,
            landing: None,
        }
    }

    /// The time after `k` steps (k ≥ k₀), s, for a world whose step is `dt` (s) after a
    /// landing.
    pub fn time_after(&self, k: u64, dt: f64) -> f64 {
        match self.landing {
            Some((k1, t1)) if k >= k1 => t1 + (k - k1) as f64 * dt,
            _ => self.t0 + (k - self.k0) as f64 * self.h,
        }
    }

    /// The length of the step that starts after `k` steps, s.
    pub fn step_after(&self, k: u64, dt: f64) -> f64 {
        match self.landing {
            Some((k1, _)) if k >= k1 => dt,
            _ => self.h,
        }
    }

    /// After `k` steps: a landing reached becomes the anchor, with steps of `dt` from it (an
    /// event-driven advance past it keeps t₁ + (k − k₁)·dt).
    pub fn reached(&mut self, k: u64, dt: f64) {
        if let Some((k1, t1)) = self.landing {
            if k >= k1 {
                *self = Clock {
                    k0: k1,
                    t0: t1,
                    h: dt,
                    landing: None,
                };
            }
        }
    }

    /// Plans the next `n` steps from `k` steps at time `t` (s) to end at `t1` (s) exactly:
    /// each of length (t₁ − t)/n, which must be > 0 and at most `dt` (the caller chose
    /// n ≥ (t₁ − t)/dt); dt itself when that is dt to a rounding ([`DIVIDES`]).
    pub fn land(&mut self, k: u64, t: f64, t1: f64, n: u64, dt: f64) -> Result<(), Error> {
        if n == 0 {
            return Err(Error::invalid("steps", n, "a landing takes at least 1 step"));
        }
        // (dt itself where it divides the stretch, to a rounding: the steps are the world's
        // own, bit for bit, and only the time is set to t₁ at the end)
        let share = (t1 - t) / n as f64;
        let h = if (share - dt).abs() <= DIVIDES * dt { dt } else { share };
        if !(t1.is_finite() && h > 0.0) {
            return Err(Error::invalid(
                "time",
                t1,
                format!("a landing time must be finite and after the world's time t = {t} s"),
            ));
        }
        if h > dt {
            return Err(Error::invalid(
                "steps",
                n,
                format!(
                    "{n} steps from t = {t} s to {t1} s would each be {h} s, longer than dt = {dt} s: \
                     give at least {} steps",
                    ((t1 - t) / dt).ceil()
                ),
            ));
        }
        *self = Clock {
            k0: k,
            t0: t,
            h,
            landing: Some((k + n, t1)),
        };
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_landing_ends_its_steps_at_its_time_exactly_and_the_clock_goes_on_by_dt() {
        let dt = 1e-3;
        let mut c = Clock::new(dt);
        assert_eq!(c.time_after(7, dt), 7.0 * dt);
        // a frame of 1/30 s in 34 steps from step 7
        let (t, t1) = (c.time_after(7, dt), 7.0 * dt + 1.0 / 30.0);
        c.land(7, t, t1, 34, dt).unwrap();
        assert_eq!(c.step_after(7, dt), (t1 - t) / 34.0);
        assert!(c.step_after(7, dt) <= dt);
        assert_eq!(c.time_after(41, dt), t1);
        assert_eq!(c.step_after(41, dt), dt);
        c.reached(41, dt);
        assert_eq!((c.k0, c.t0, c.h, c.landing), (41, t1, dt, None));
        assert_eq!(c.time_after(43, dt), t1 + 2.0 * dt);
        // refused: too few steps, a time before now
        assert!(c.land(41, t1, t1 + 1.0 / 30.0, 33, dt).is_err());
        assert!(c.land(41, t1, t1, 1, dt).is_err());
        // a stretch that dt divides but for a rounding: steps of dt, the time landed
        let t2 = t1 + 0.02;
        c.land(41, t1, t2, 20, dt).unwrap();
        assert_eq!(c.step_after(41, dt), dt);
        assert_eq!(c.time_after(61, dt), t2);
    }
}
