//! Clipping: geometry cut to what can be projected and drawn, before it becomes pixels.
//!
//! Two cuts, both Sutherland–Hodgman (walk the edges; keep the vertices inside, add each
//! edge's crossing of the boundary):
//!
//! - the near cut, in camera coordinates: a perspective camera divides by the depth zc, so
//!   polygons and segments are cut at zc = zn > 0 before they are projected ([`near_depth`],
//!   [`clip_polygon_near`], [`clip_segment_near`]);
//! - the guard rectangle, in pixels: the image widened by [`GUARD`] pixels on every side, so
//!   that what is cut away never touches a pixel and every pixel coordinate stays small
//!   ([`guard_rect`], [`clip_halfplane`]).

use super::camera::{Camera, Projector};
use crate::vec3::{dot, norm, sub};

/// Primitives are clipped to the image widened by this margin (pixels), wider than any
/// line's antialiased reach, so that what is clipped away never touches a pixel and all
/// pixel coordinates stay small.
pub(crate) const GUARD: f64 = 4.0;

/// The depth zn (m, along the view axis) where a perspective frame cuts its geometry: the
/// camera's near distance, or 1e-4 of the eye–target distance where that is larger, which
/// keeps pixel coordinates within ~1e4 focal lengths while losing nothing one could see.
/// −∞ for the orthographic camera, which has no depth to cut.
pub(crate) fn near_depth(camera: &Camera, projector: &Projector) -> f64 {
    match (camera, projector) {
        (Camera::Perspective { eye, target, .. }, Projector::Persp { near, .. }) => near.max(1e-4 * norm(sub(*target, *eye))),
        _ => f64::NEG_INFINITY,
    }
}

/// Sutherland–Hodgman against the half-space zc ≥ zn of camera coordinates.
///
/// The pinhole projection divides by zc: a point behind the eye (zc < 0) would land mirrored
/// through the image centre and one at zc → 0 at infinity, so a plane passing behind the
/// camera must be cut before it is projected. Walking the polygon's edges, a vertex in front
/// is kept, and an edge from A to B that crosses zc = zn contributes its crossing point
/// A + s·(B − A), s = (zn − z_A)/(z_B − z_A), whose depth is zn exactly. Cutting a convex
/// polygon by a plane leaves it convex, and its projection (all of it in front) is convex.
pub(crate) fn clip_polygon_near(poly: &[[f64; 3]], zn: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let a = poly[i];
        let b = poly[(i + 1) % poly.len()];
        let (ina, inb) = (a[2] >= zn, b[2] >= zn);
        if ina {
            out.push(a);
        }
        if ina != inb {
            let s = (zn - a[2]) / (b[2] - a[2]);
            out.push([a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), zn]);
        }
    }
    out
}

/// The part of the segment AB (camera coordinates) with zc ≥ zn (see `clip_polygon_near`).
pub(crate) fn clip_segment_near(a: [f64; 3], b: [f64; 3], zn: f64) -> Option<([f64; 3], [f64; 3])> {
    match (a[2] >= zn, b[2] >= zn) {
        (true, true) => Some((a, b)),
        (false, false) => None,
        (ina, _) => {
            let s = (zn - a[2]) / (b[2] - a[2]);
            let m = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), zn];
            Some(if ina { (a, m) } else { (m, b) })
        }
    }
}

/// a·b of two pixel-space vectors.
pub(crate) fn dot2(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The image widened by [`GUARD`] pixels, counter-clockwise on screen.
pub(crate) fn guard_rect(w: f64, h: f64) -> Vec<[f64; 2]> {
    vec![
        [-GUARD, -GUARD],
        [-GUARD, h + GUARD],
        [w + GUARD, h + GUARD],
        [w + GUARD, -GUARD],
    ]
}

/// The part of a polygon where e[0]·x + e[1]·y + e[2] ≥ 0 (Sutherland–Hodgman, as above).
pub(crate) fn clip_halfplane(poly: &[[f64; 2]], e: [f64; 3]) -> Vec<[f64; 2]> {
    clip_where(poly, |p| e[0] * p[0] + e[1] * p[1] + e[2])
}

/// The part of the convex polygon `poly` (points of N coordinates) where the affine function
/// `side` is ≥ 0 (Sutherland–Hodgman): the vertices inside are kept, and each edge ab that
/// crosses gets the point a + s (b − a), s = side(a) / (side(a) − side(b)), where `side`,
/// linear along the edge, is 0.
pub(crate) fn clip_where<const N: usize>(poly: &[[f64; N]], side: impl Fn([f64; N]) -> f64) -> Vec<[f64; N]> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (da, db) = (side(a), side(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let s = da / (da - db);
            out.push(std::array::from_fn(|k| a[k] + s * (b[k] - a[k])));
        }
    }
    out
}

/// The part of the convex polygon `poly` (world) on the free side n·(x − q) ≥ 0 of a plane.
pub(crate) fn clip_polygon_halfspace(poly: &[[f64; 3]], q: [f64; 3], n: [f64; 3]) -> Vec<[f64; 3]> {
    clip_where(poly, |x| dot(sub(x, q), n))
}
