//! The scene's extent: the region a picture's scenery is laid out in.
//!
//! A plane is infinite and an open box face has no wall, so drawing them needs a size: a
//! plane's floor patch is centred under the extent's centre and sized from it, and a box's
//! infinite bounds are drawn up to it (`clamp_box`). Two extents, one rule for the
//! colliders (a box's finite bounds, each along its own axis; a sphere's box; a plane adds
//! nothing):
//!
//! - [`scene_extent`]: a whole video's, from the positions of all its frames, so that the
//!   scenery stays put while the particles move; the default cameras frame it too;
//! - `frame_extent`: one frame's, when it is given none ([`super::Scenery::extent`]).

use super::camera::{invalid, Camera};
use crate::collide::Collider;
use crate::vec3::{add, norm, sub};
use crate::Error;

/// An axis-aligned box `(lo, hi)`, its corners in m.
pub type Region = ([f64; 3], [f64; 3]);

/// Calls `grow(axis, value)` with the finite parts of the colliders: a box's finite bounds,
/// each along its own axis (an open top adds nothing along z), and the faces of a sphere's
/// or a mesh's bounding box (c ± R for a sphere); a plane has none.
fn finite_parts(colliders: &[Collider], mut grow: impl FnMut(usize, f64)) {
    for collider in colliders {
        match collider {
            Collider::Plane(_) => {}
            Collider::Box(b) => {
                for k in 0..3 {
                    for v in [b.lo()[k], b.hi()[k]] {
                        if v.is_finite() {
                            grow(k, v);
                        }
                    }
                }
            }
            Collider::Sphere(s) => {
                for (k, c) in s.center().into_iter().enumerate() {
                    grow(k, c - s.radius());
                    grow(k, c + s.radius());
                }
            }
            Collider::Mesh(m) => {
                let (lo, hi) = m.bounds();
                for k in 0..3 {
                    grow(k, lo[k]);
                    grow(k, hi[k]);
                }
            }
        }
    }
}

/// The extent of a video: the box of every finite point of `positions` (x, y, z in m, 3 per
/// point: all frames' particles, NaN where one is not alive) and of the colliders' finite
/// parts, widened on every side by the largest of `radius` (m, one per particle).
///
/// An axis that nothing reached gets [0, 0] (or [0, 1] when no axis was reached). The margin
/// is at least 1e-3 of the widest side, and a single point without radius gets 0.5 m, so
/// that the extent always has a size a camera can frame. Errors name a radius that is not
/// finite and ≥ 0, or positions that do not come in threes.
pub fn scene_extent(positions: &[f64], radius: &[f64], colliders: &[Collider]) -> Result<Region, Error> {
    if positions.len() % 3 != 0 {
        return Err(invalid(
            "positions",
            format!("{} numbers", positions.len()),
            "x, y, z of each point: a multiple of 3",
        ));
    }
    if let Some((i, r)) = radius.iter().enumerate().find(|(_, r)| !(r.is_finite() && **r >= 0.0)) {
        return Err(invalid(&format!("radius[{i}]"), r, "a finite radius >= 0"));
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut grow = |k: usize, v: f64| {
        lo[k] = lo[k].min(v);
        hi[k] = hi[k].max(v);
    };
    for p in positions.chunks_exact(3) {
        if p.iter().all(|c| c.is_finite()) {
            for (k, &c) in p.iter().enumerate() {
                grow(k, c);
            }
        }
    }
    finite_parts(colliders, &mut grow);
    let known: [bool; 3] = std::array::from_fn(|k| lo[k].is_finite() && hi[k].is_finite());
    let any = known.contains(&true);
    for k in 0..3 {
        if !known[k] {
            lo[k] = 0.0;
            hi[k] = if any { 0.0 } else { 1.0 };
        }
    }
    let span = (0..3).map(|k| hi[k] - lo[k]).fold(f64::NEG_INFINITY, f64::max);
    let largest = radius.iter().copied().fold(0.0, f64::max);
    // A degenerate box (one point, no radius) still gets a view of finite size.
    let pad = if span + largest > 0.0 { largest.max(1e-3 * span) } else { 0.5 };
    Ok((lo.map(|v| v - pad), hi.map(|v| v + pad)))
}

/// The box each collider occupies within `extent`, in the colliders' order: a box with its
/// infinite bounds at the extent's, a sphere's bounding box; planes have none. What the
/// default 3D camera frames besides the particles.
pub fn collider_boxes(colliders: &[Collider], extent: Region) -> Vec<Region> {
    let (elo, ehi) = extent;
    colliders
        .iter()
        .filter_map(|collider| match collider {
            Collider::Plane(_) => None,
            Collider::Box(b) => {
                let (lo, hi) = (b.lo(), b.hi());
                Some((
                    std::array::from_fn(|k| if lo[k].is_finite() { lo[k] } else { elo[k] }),
                    std::array::from_fn(|k| if hi[k].is_finite() { hi[k] } else { ehi[k] }),
                ))
            }
            Collider::Sphere(s) => {
                let (c, r) = (s.center(), s.radius());
                Some((c.map(|v| v - r), c.map(|v| v + r)))
            }
            Collider::Mesh(m) => Some(m.bounds()),
        })
        .collect()
}

/// The extent of a lone frame: `particles` (their bounding box with radii, `None` without
/// any) joined with the colliders' finite parts; an axis that nothing reached takes the
/// region around what the camera looks at in a `width × height` image.
pub(crate) fn frame_extent(
    colliders: &[Collider],
    particles: Option<Region>,
    camera: &Camera,
    width: usize,
    height: usize,
) -> Region {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut grow = |k: usize, v: f64| {
        if v.is_finite() {
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    };
    if let Some((a, b)) = particles {
        for k in 0..3 {
            grow(k, a[k]);
            grow(k, b[k]);
        }
    }
    finite_parts(colliders, &mut grow);
    let fallback = match *camera {
        Camera::Perspective { eye, target, .. } => {
            let r = 0.25 * norm(sub(target, eye));
            (sub(target, [r; 3]), add(target, [r; 3]))
        }
        Camera::Orthographic { center, pixels_per_unit } => {
            let (hw, hh) = (0.5 * width as f64 / pixels_per_unit, 0.5 * height as f64 / pixels_per_unit);
            ([center[0] - hw, center[1] - hh, 0.0], [center[0] + hw, center[1] + hh, 0.0])
        }
    };
    // An axis that nothing finite reached takes the camera's region; one that only a single
    // value reached (an open box's floor, no particles) is widened by it.
    for k in 0..3 {
        if lo[k] > hi[k] {
            lo[k] = fallback.0[k];
            hi[k] = fallback.1[k];
        } else if lo[k] == hi[k] {
            lo[k] = lo[k].min(fallback.0[k]);
            hi[k] = hi[k].max(fallback.1[k]);
        }
    }
    (lo, hi)
}

/// The box `[lo, hi]` with its infinite bounds replaced by the extent's (never past the
/// other bound).
pub(crate) fn clamp_box(lo: [f64; 3], hi: [f64; 3], extent: Region) -> Region {
    let (elo, ehi) = extent;
    let mut l = lo;
    let mut u = hi;
    for k in 0..3 {
        if !lo[k].is_finite() {
            l[k] = if hi[k].is_finite() { elo[k].min(hi[k]) } else { elo[k] };
        }
        if !hi[k].is_finite() {
            u[k] = ehi[k].max(l[k]);
        }
    }
    (l, u)
}
