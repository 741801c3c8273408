//! The lines a frame draws besides the scenery's: the springs between particles and the
//! particles' trails, as pixel-space primitives with their depths ([`super::raster`] orders
//! and draws them with the particles).

use super::camera::{Camera, Projector};
use super::clip::{clip_segment_near, near_depth};
use super::frame::{Frame, RenderParams};
use super::paint::LINE_COLOR;
use super::prim::{line, Prim};

/// The springs as pixel-space lines with the depth of their midpoints (0 in 2D): each cut at
/// the near distance (3D), then shortened at an end by the drawn radius of the particle
/// there (an end cut off by the near distance has no particle in view), so that it runs
/// from rim to rim; none where the rims meet.
pub(super) fn spring_lines(camera: &Camera, projector: &Projector, frame: &Frame, params: &RenderParams) -> Vec<(f64, Prim)> {
    let Frame {
        positions,
        radius,
        springs,
        ..
    } = *frame;
    let (w, h) = (params.width as f64, params.height as f64);
    // The same cut as the scenery's: pixel coordinates stay bounded.
    let zn = near_depth(camera, projector);
    let at = |i: usize| [positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]];
    let drawn_radius = |i: usize| {
        projector
            .project(at(i), radius[i])
            .map_or(0.0, |q| q.r.max(params.min_radius_px))
    };
    let mut out = Vec::new();
    for &[i, j] in springs {
        if i == j {
            continue;
        }
        let (ci, cj) = (projector.camera_coords(at(i)), projector.camera_coords(at(j)));
        let Some((qi, qj)) = segment_in_front(camera, ci, cj, zn) else {
            continue;
        };
        let ri = if qi == ci { drawn_radius(i) } else { 0.0 };
        let rj = if qj == cj { drawn_radius(j) } else { 0.0 };
        let (a, b) = (projector.camera_to_pixel(qi), projector.camera_to_pixel(qj));
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
        if len.partial_cmp(&(ri + rj)) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        let u = [d[0] / len, d[1] / len];
        let a = [a[0] + ri * u[0], a[1] + ri * u[1]];
        let b = [b[0] - rj * u[0], b[1] - rj * u[1]];
        let depth = if camera.is_3d() { 0.5 * (qi[2] + qj[2]) } else { 0.0 };
        if let Some(line) = line(a, b, params.spring_width_px, LINE_COLOR, 1.0, w, h) {
            out.push((depth, line));
        }
    }
    out
}

/// The part of the segment ab (camera coordinates) that can be projected: in 3D cut at the
/// near distance `zn` (none when wholly behind it), in 2D all of it.
fn segment_in_front(camera: &Camera, a: [f64; 3], b: [f64; 3], zn: f64) -> Option<([f64; 3], [f64; 3])> {
    if camera.is_3d() {
        clip_segment_near(a, b, zn)
    } else {
        Some((a, b))
    }
}

/// The trails as pixel-space segments with the depth of their midpoints (0 in 2D), each cut
/// at the near distance (3D), coloured by age (see [`render_frame`](super::render_frame)).
pub(super) fn trail_lines(camera: &Camera, projector: &Projector, frame: &Frame, params: &RenderParams) -> Vec<(f64, Prim)> {
    let (trails, len, colors) = (frame.trails, frame.trail_len, frame.colors);
    let mut out = Vec::new();
    if trails.is_empty() {
        return out;
    }
    let (w, h) = (params.width as f64, params.height as f64);
    let zn = near_depth(camera, projector);
    let bg = params.background.map(|c| c as f64);
    let segments = (len - 1) as f64;
    for (i, path) in trails.chunks_exact(3 * len).enumerate() {
        let c = [colors[3 * i], colors[3 * i + 1], colors[3 * i + 2]].map(|c| c as f64);
        // The particle's disc on screen: the trail stops at its rim, as a spring does.
        let p = &frame.positions[3 * i..3 * i + 3];
        let disc = projector
            .project([p[0], p[1], p[2]], frame.radius[i])
            .map(|q| ([q.x, q.y], q.r.max(params.min_radius_px)));
        for k in 0..len - 1 {
            let (a, b) = (&path[3 * k..3 * k + 3], &path[3 * k + 3..3 * k + 6]);
            if !a.iter().chain(b).all(|v| v.is_finite()) || a == b {
                continue;
            }
            let (ca, cb) = (
                projector.camera_coords([a[0], a[1], a[2]]),
                projector.camera_coords([b[0], b[1], b[2]]),
            );
            let Some((qa, qb)) = segment_in_front(camera, ca, cb, zn) else {
                continue;
            };
            let f = (k + 1) as f64 / segments;
            let colour: [u8; 3] = std::array::from_fn(|j| (bg[j] + f * (c[j] - bg[j])).round() as u8);
            let (pa, pb) = (projector.camera_to_pixel(qa), projector.camera_to_pixel(qb));
            let depth = if camera.is_3d() { 0.5 * (qa[2] + qb[2]) } else { 0.0 };
            for (sa, sb) in outside_disc(pa, pb, disc) {
                let at = |s: f64| [pa[0] + s * (pb[0] - pa[0]), pa[1] + s * (pb[1] - pa[1])];
                if let Some(line) = line(at(sa), at(sb), params.trail_width_px, colour, 1.0, w, h) {
                    out.push((depth, line));
                }
            }
        }
    }
    out
}

/// The parts [s0, s1] ⊂ [0, 1] of the pixel segment a + s·(b − a) outside the disc (centre,
/// radius) (all of it without a disc): none, one or two.
fn outside_disc(a: [f64; 2], b: [f64; 2], disc: Option<([f64; 2], f64)>) -> Vec<(f64, f64)> {
    let Some((c, r)) = disc else {
        return vec![(0.0, 1.0)];
    };
    // |a − c + s·d|² = r²: s² |d|² + 2 s (a − c)·d + |a − c|² − r² = 0.
    let d = [b[0] - a[0], b[1] - a[1]];
    let e = [a[0] - c[0], a[1] - c[1]];
    let (qa, qb, qc) = (
        d[0] * d[0] + d[1] * d[1],
        e[0] * d[0] + e[1] * d[1],
        e[0] * e[0] + e[1] * e[1] - r * r,
    );
    let disc2 = qb * qb - qa * qc;
    if !(qa > 0.0 && disc2 > 0.0) {
        // A point, or a line that misses the circle: all outside or all inside, as a is.
        return if qc > 0.0 { vec![(0.0, 1.0)] } else { vec![] };
    }
    let root = disc2.sqrt();
    let (s0, s1) = ((-qb - root) / qa, (-qb + root) / qa);
    [(0.0, s0.min(1.0)), (s1.max(0.0), 1.0)]
        .into_iter()
        .filter(|(x, y)| y > x)
        .collect()
}
