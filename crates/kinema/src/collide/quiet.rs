//! Quiet particles: which particles continuous detection must look at in a step of a
//! force-free world.
//!
//! Without forces every particle moves on a straight line between impulses, and a line does
//! not change from one step to the next. So each particle gets a *meeting time*: the first
//! time its line meets (or touches) a list partner's line or a collider, computed when its
//! line last changed. A step then starts its impact search only from the particles whose
//! meeting time falls in it; every other one is quiet, and is read only as the partner of a
//! particle being looked at. Within the step nothing else changes: an impact's two
//! particles look for their next impacts over all their partners, quiet or not, as before.
//!
//! **Why that finds every impact.** Take a pair i, j whose lines meet at time T. Of the
//! two meeting times, the one computed later was computed while both lines were already the
//! current ones, and saw the meeting: it is at most T, so that particle is looked at in
//! the step of T (or earlier: a stale meeting time, made with a partner's old line, only makes
//! a particle due for nothing). A particle's meeting time is recomputed after every step in which
//! it was looked at or its line changed (an impact, the end-of-step solve), from the state
//! at the step's end, and all of them are recomputed whenever the neighbour list is rebuilt.
//! Times are absolute (the world's clock), and a particle is due with a margin of a
//! thousandth of a step: the world's positions advance by x + h v each step, the lines from
//! one point, and the two differ by roundings.
//!
//! **How long the list holds.** Without a pass over all particles each step, the list's
//! validity comes from a bound: no particle moves faster than `vmax`, the largest speed any
//! particle had since the list was built (raised by every impact and every end-of-step
//! velocity change), so none is farther than `reach` from its build position, where `reach`
//! grows by h·vmax each step (plus what the end-of-step solve moved positions by). Two
//! particles then close by at most 2·reach, and the list holds while that is less than its
//! skin. Meetings are searched up to the time the bound says the list expires; the rebuild
//! at that time computes every meeting time again.
//!
//! This is the "lazy" half of event-driven MD (Alder & Wainwright; DynamO, Smallenburg):
//! a particle is touched only when something happens to it. The step's work is O(k log N)
//! for k particles due, plus the integrator's pass.

use super::events::Timetable;

/// A meeting time is due in a step ending at `end` when it is at most end + DUE_MARGIN h.
const DUE_MARGIN: f64 = 1e-3;

/// The meeting times and the list's validity bound (see the module doc).
#[derive(Debug, Default)]
pub(crate) struct Meetings {
    /// Each particle's meeting time, s of the world's clock (none: nothing until the list's
    /// rebuild).
    pub table: Timetable,
    /// Whether the meeting times hold for the current state; false: the next step looks at
    /// every particle, and computes them all again at its end.
    pub valid: bool,
    /// No particle is farther than this from its position at the list's build, m (at the
    /// last step's end).
    pub reach: f64,
    /// No particle moved faster than this since the list's build, m/s.
    pub vmax: f64,
}

impl Meetings {
    /// The bound on any particle's distance from its build position after another step of
    /// h s, m.
    pub fn reach_after(&self, h: f64) -> f64 {
        self.reach + h * self.vmax
    }

    /// Time from now (s) until two particles may have closed by the list's `allowance` (m):
    /// how far ahead meetings must be searched (a large finite number when nothing moves).
    pub fn horizon(&self, allowance: f64) -> f64 {
        let left = (0.5 * allowance - self.reach).max(0.0);
        if self.vmax > 0.0 {
            (left / self.vmax).min(f64::MAX)
        } else {
            f64::MAX
        }
    }

    /// The particles due in a step of h s ending at `end` (world clock, s), ascending; their
    /// meeting times are taken (recompute them at the step's end).
    pub fn due(&mut self, end: f64, h: f64) -> Vec<usize> {
        let mut due = Vec::new();
        while let Some((i, _)) = self.table.pop_until(end + DUE_MARGIN * h) {
            due.push(i);
        }
        due.sort_unstable();
        due
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn due_takes_the_times_in_the_step_and_its_margin_only_once() {
        let mut w = Meetings::default();
        w.table.fill(4, [(0, 1.0005), (1, 0.5), (2, 1.002), (3, 2.0)].into_iter());
        // a step of 0.1 s ending at 1.0: margin 1e-4 s
        assert_eq!(w.due(1.0, 0.1), vec![1]);
        assert_eq!(w.due(1.001, 0.1), vec![0]);
        assert!(w.due(1.001, 0.1).is_empty(), "taken times are gone");
        w.table.set(3, Some(0.1)); // a new time replaces the old one
        assert_eq!(w.due(1.1, 0.1), vec![2, 3]);
        assert!(w.due(10.0, 0.1).is_empty());
    }

    #[test]
    fn the_bound_grows_with_the_fastest_speed() {
        let w = Meetings {
            reach: 0.05,
            vmax: 2.0,
            ..Meetings::default()
        };
        assert_eq!(w.reach_after(0.01), 0.07);
        // the list of skin 0.3 holds while 2 reach < 0.3: (0.15 − 0.05) / 2 s from now
        assert!((w.horizon(0.3) - 0.05).abs() < 1e-15);
        assert_eq!(Meetings::default().horizon(0.3), f64::MAX);
    }
}
