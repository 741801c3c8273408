//! Shock propagation (Guendelman, Bridson & Fedkiw 2003, "Nonconvex rigid bodies with
//! stacking", §7): the order in which the soft step's shock stages (`collide/soft_step.rs`,
//! the `animation` accuracy) visit an island's supports, bottom up, and which side of each
//! they hold still.
//!
//! Projected Gauss–Seidel moves a load one contact per pass, so a pile n contacts deep
//! needs of the order of n² passes to bring its weight down to the floor; cut off earlier,
//! each layer sinks into the one below by what the passes left unresolved, and a deep pile
//! at a large step never rests (a 60-deep column at 60 Hz: 20 % of r after 5 s, the passes
//! at their cap of 100 in 293 of 300 steps). Shock propagation takes the pile as levels:
//! level 0 the particles only a collider (or a pinned particle) holds up, and each other
//! particle one level above the highest of its supports. Visiting the levels bottom up, each
//! particle's supports held still (infinite mass), a particle is stopped on its supports in
//! one pass whatever the depth: what a level needs of the one below is already there.
//!
//! "Holds up" is read from the forces: partner p supports particle q across a touching
//! contact of normal n (on q) when n points against q's acceleration a_q by more than
//! [`SUPPORT_COSINE`] of |a_q| (under gravity: a contact within about 75° of vertical, q
//! above). Side contacts hold nothing up and are left to the passes, and a particle no chain
//! of supports from the ground reaches (a ball in flight) takes no part.
//!
//! The shock only pushes: each contact's push starts at 0 and stays ≥ 0 along n, with no
//! friction, so it stops what sinks and nothing else. Holding the sides of a pile still as
//! well (Guendelman's levels over every contact) over-constrains a packed pile: a grain wedged
//! between its supports cannot also be pushed sideways, the passes of a level never
//! converged, and a 2D pour still overlapped by 41 % of r at 60 Hz.
//!
//! What it costs in physics: a support held still does not feel the reaction of the particle
//! it stops, so the shock's pushes conserve no momentum (the ground takes it up), and the
//! collider books do not see them; the energy lost does (it is measured from the states).
//! It is the `animation` accuracy's part, not the `physics` grade's.

use crate::error::Error;

/// Where the impulse model's end-of-step solve sits on the work–precision curve
/// (docs/collisions.md, "The accuracy setting"). The step is the other half of the setting.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Accuracy {
    /// `physics`: momentum exchanged by action and reaction only, up to 100 passes of the
    /// solve and 30 of the relax a step; at 1 ms piles rest at 0.2–0.3 % of r.
    #[default]
    Physics,
    /// `animation`: shock propagation (`collide/shock.rs`: the pile's levels resolved bottom
    /// up, each on the still levels below it), and up to 10 passes of the solve (30 of the
    /// relax, as `Physics`). Deep piles at rest at 120 Hz within about 1 % of r, several times faster; the
    /// shock's pushes are taken up by the ground, not by the particles below.
    Animation,
}

impl Accuracy {
    /// The names, as the binding and the scene files spell them.
    pub const NAMES: [&'static str; 2] = ["physics", "animation"];

    /// The setting named `name`.
    pub fn from_name(name: &str) -> Result<Self, Error> {
        match name {
            "physics" => Ok(Accuracy::Physics),
            "animation" => Ok(Accuracy::Animation),
            other => Err(Error::invalid(
                "accuracy",
                format!("'{other}'"),
                "the accuracy must be 'physics' or 'animation'",
            )),
        }
    }

    /// Its name.
    pub fn name(&self) -> &'static str {
        match self {
            Accuracy::Physics => Self::NAMES[0],
            Accuracy::Animation => Self::NAMES[1],
        }
    }
}

/// The least cosine between a contact's normal and the particle's deceleration for the
/// contact to hold the particle up: about 75° from the vertical under gravity.
pub(crate) const SUPPORT_COSINE: f64 = 0.25;

/// A particle no support reaches.
pub(crate) const UNREACHED: u32 = u32::MAX;

/// The level of each of `n` particles: 0 for a `grounded` one none of whose supports is a
/// particle, else one more than the highest level among its supports (`edges`: (support,
/// supported)) that the ground holds up; [`UNREACHED`] if no chain of supports leads to the
/// ground (a ball in flight), or if it lies on a loop of supports (which no order takes
/// bottom up). The longest chain, so that each particle's supports are all of lower levels
/// (Kahn's topological order), over the supports the ground holds up (a loose grain a
/// particle touches from above does not hold it out of the order).
pub(crate) fn levels(n: usize, grounded: &[usize], edges: &[(usize, usize)]) -> Vec<u32> {
    // the supported particles of each particle, as a compressed row list
    let above = |edges: &[(usize, usize)]| {
        let mut starts = vec![0usize; n + 1];
        for &(p, _) in edges {
            starts[p + 1] += 1;
        }
        for k in 0..n {
            starts[k + 1] += starts[k];
        }
        let mut fill = starts.clone();
        let mut list = vec![0usize; edges.len()];
        for &(p, q) in edges {
            list[fill[p]] = q;
            fill[p] += 1;
        }
        (starts, list)
    };
    // the particles some chain of supports leads to from the ground
    let (starts, list) = above(edges);
    let mut rooted = vec![false; n];
    let mut work: Vec<usize> = grounded.to_vec();
    for &q in grounded {
        rooted[q] = true;
    }
    while let Some(p) = work.pop() {
        for &q in &list[starts[p]..starts[p + 1]] {
            if !rooted[q] {
                rooted[q] = true;
                work.push(q);
            }
        }
    }
    // the longest chain over the rooted supports
    let held: Vec<(usize, usize)> = edges.iter().copied().filter(|&(p, _)| rooted[p]).collect();
    let (starts, list) = above(&held);
    let mut below = vec![0u32; n];
    for &(_, q) in &held {
        below[q] += 1;
    }
    let mut level = vec![UNREACHED; n];
    let mut ready: Vec<usize> = (0..n).filter(|&q| rooted[q] && below[q] == 0).collect();
    for &q in &ready {
        level[q] = 0;
    }
    let mut settled = vec![false; n];
    while let Some(p) = ready.pop() {
        settled[p] = true;
        for &q in &list[starts[p]..starts[p + 1]] {
            level[q] = if level[q] == UNREACHED {
                level[p] + 1
            } else {
                level[q].max(level[p] + 1)
            };
            below[q] -= 1;
            if below[q] == 0 {
                ready.push(q);
            }
        }
    }
    for (l, s) in level.iter_mut().zip(settled) {
        if !s {
            *l = UNREACHED;
        }
    }
    level
}

/// Which side of a contact a shock stage holds still.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Held {
    /// Neither: a collider or an immovable particle holds the other side up.
    Neither,
    /// Particle i, the support.
    I,
    /// Particle j, the support.
    J,
}

/// The shock stages' visits: contacts (indices), each with the side held still, level by
/// level bottom up (`starts[l]..starts[l + 1]` the visits of level l).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct ShockOrder {
    pub visits: Vec<(usize, Held)>,
    pub starts: Vec<usize>,
}

/// The order of the support contacts: each contact that holds a particle up, with the level
/// of the particle it holds up and the side held still (`None`: not a support, or the
/// particle held up is [`UNREACHED`]). By level, within a level in list order.
pub(crate) fn order(supports: impl Iterator<Item = Option<(u32, Held)>>) -> ShockOrder {
    let mut keyed: Vec<(u32, usize, Held)> = supports
        .enumerate()
        .filter_map(|(k, s)| s.filter(|&(l, _)| l != UNREACHED).map(|(l, h)| (l, k, h)))
        .collect();
    keyed.sort_by_key(|&(l, k, _)| (l, k));
    let top = keyed.last().map_or(0, |&(l, _, _)| l as usize + 1);
    let mut starts = vec![0usize; top + 1];
    for &(l, _, _) in &keyed {
        starts[l as usize + 1] += 1;
    }
    for l in 0..top {
        starts[l + 1] += starts[l];
    }
    ShockOrder {
        visits: keyed.into_iter().map(|(_, k, h)| (k, h)).collect(),
        starts,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_particle_is_above_all_its_supports_and_a_loop_is_unreached() {
        // 0 on the ground, 1 on 0, 2 on 1; 3 rests on 0 and 2 (level 3: above both); 4 rests
        // on nothing; 5 and 6 hold each other up (a loop) over 8, on the ground; 7 rests on 6;
        // 9 rests on 1 and on 4, which the ground does not hold up.
        let edges = [(0, 1), (1, 2), (0, 3), (2, 3), (8, 5), (5, 6), (6, 5), (6, 7), (1, 9), (4, 9)];
        let level = levels(10, &[0, 8], &edges);
        let u = UNREACHED;
        assert_eq!(level, vec![0, 1, 2, 3, u, u, u, u, 0, 2]);
    }

    #[test]
    fn the_order_goes_bottom_up() {
        let supports = vec![
            Some((1, Held::J)),
            Some((0, Held::Neither)),
            None,
            Some((UNREACHED, Held::I)),
            Some((1, Held::I)),
        ];
        let o = order(supports.into_iter());
        assert_eq!(o.visits, vec![(1, Held::Neither), (0, Held::J), (4, Held::I)]);
        assert_eq!(o.starts, vec![0, 1, 3]);
    }
}
