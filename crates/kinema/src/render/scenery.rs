//! Scenery: the static colliders of a world — planes, boxes, sphere obstacles — drawn with the
//! particles, so that a ball bounces on a floor one can see.
//!
//! | item   | 3D (perspective camera)                                  | 2D (orthographic, xy)                 |
//! |--------|----------------------------------------------------------|---------------------------------------|
//! | plane  | a finite floor patch with a faint grid and an outline,   | the solid side lightly filled and the |
//! |        | under everything (background layer)                      | line itself, thick                    |
//! | box    | its floor face lightly filled and its 12 edges as lines, | its rectangle outline (background)    |
//! |        | under everything (background layer)                      |                                       |
//! | sphere | a shaded sphere in the particles' far-to-near order       | a filled disc under the particles     |
//!
//! Everything is in fixed neutral colours ([`FLOOR_COLOR`], [`BOX_FLOOR_COLOR`],
//! [`LINE_COLOR`], [`OBSTACLE_COLOR`]) so that the particles' colours keep their meaning.
//!
//! Geometry is turned into a few pixel-space primitives ([`Prim`]: a convex polygon, a line
//! segment, a disc) once per frame, in f64; each band of the raster stage draws every
//! primitive's rows that fall inside it, in list order, before its particles. A band's pixels
//! still depend only on its own rows, so frames stay byte-identical for any thread count.

use super::camera::{invalid, Camera, Projector};
use super::raster::{blend, disc_row, fill_rgb, Sprite};
use crate::vec3::{add, cross, dot, norm, scale, sub};
use crate::Error;

/// A static collider to draw. Lengths in m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SceneryItem {
    /// The plane through `point` with `normal` (non-zero; any length): the free side is the
    /// one the normal points to.
    Plane {
        /// A point of the plane, m.
        point: [f64; 3],
        /// Normal, towards the free side.
        normal: [f64; 3],
    },
    /// The axis-aligned container `[lo, hi]`; a bound may be infinite (−∞ for `lo`, +∞ for
    /// `hi`): that face is open and not drawn, and the walls along it are drawn up to the
    /// scene's extent ([`Scenery::extent`]).
    Box {
        /// Lower corner, m.
        lo: [f64; 3],
        /// Upper corner, m (hi > lo along every axis).
        hi: [f64; 3],
    },
    /// A fixed sphere (a circle in 2D; z is ignored there).
    Sphere {
        /// Centre, m.
        center: [f64; 3],
        /// Radius, m (≥ 0).
        radius: f64,
    },
}

/// The scenery of a frame: what to draw besides the particles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scenery {
    /// The colliders, drawn in this order within their layer.
    pub items: Vec<SceneryItem>,
    /// The region the scene occupies, `(lo, hi)` in m: infinite box bounds are clamped to it,
    /// and a plane's floor patch is centred under its centre and sized from it. `None`: the
    /// particles' bounding box (radii included) joined with the finite parts of the items, in
    /// this frame. A video should give one extent for all its frames, so that the scenery
    /// does not move while the particles do.
    pub extent: Option<([f64; 3], [f64; 3])>,
}

/// Floor patches (3D planes, box floors) and the solid side of 2D planes, RGB8.
pub const FLOOR_COLOR: [u8; 3] = [224, 224, 220];
/// A box's floor face, RGB8: a shade darker than [`FLOOR_COLOR`], so that it shows on a floor.
pub const BOX_FLOOR_COLOR: [u8; 3] = [212, 212, 206];
/// Outlines: plane patch borders, grid lines (faint), box edges, 2D plane lines, RGB8.
pub const LINE_COLOR: [u8; 3] = [96, 96, 100];
/// Sphere obstacles, RGB8 (shaded in 3D like the particles).
pub const OBSTACLE_COLOR: [u8; 3] = [176, 178, 184];

/// Line widths, pixels.
const PATCH_OUTLINE_PX: f64 = 1.5;
const GRID_PX: f64 = 1.0;
const BOX_EDGE_PX: f64 = 1.5;
const PLANE_2D_PX: f64 = 3.0;
const BOX_2D_PX: f64 = 2.0;
/// Opacity of the faint grid.
const GRID_ALPHA: f32 = 0.25;
/// Primitives are clipped to the image widened by this margin (pixels), wider than any
/// line's antialiased reach, so that what is clipped away never touches a pixel and all
/// pixel coordinates stay small.
const GUARD: f64 = 4.0;

impl SceneryItem {
    /// Checks the item; `k` is its index, used in the error's parameter name
    /// (`scenery[k].normal`).
    pub fn validate(&self, k: usize) -> Result<(), Error> {
        let name = |field: &str| format!("scenery[{k}].{field}");
        let finite = |v: [f64; 3]| v.iter().all(|c| c.is_finite());
        match *self {
            SceneryItem::Plane { point, normal } => {
                if !finite(point) {
                    return Err(invalid(&name("point"), format!("{point:?}"), "finite coordinates"));
                }
                let n = norm(normal);
                if !(n > 0.0 && n.is_finite()) {
                    return Err(invalid(&name("normal"), format!("{normal:?}"), "a finite non-zero direction"));
                }
            }
            SceneryItem::Box { lo, hi } => {
                for k in 0..3 {
                    // lo may be −∞ and hi +∞ (an open face); never NaN, never +∞ for lo.
                    if !(lo[k] < hi[k] && lo[k] < f64::INFINITY && hi[k] > f64::NEG_INFINITY) {
                        return Err(invalid(
                            &name("lo"),
                            format!("{lo:?} with hi = {hi:?}"),
                            "lo < hi along every axis (lo may be -inf and hi +inf: an open face; no NaN)",
                        ));
                    }
                }
            }
            SceneryItem::Sphere { center, radius } => {
                if !finite(center) {
                    return Err(invalid(&name("center"), format!("{center:?}"), "finite coordinates"));
                }
                if !(radius >= 0.0 && radius.is_finite()) {
                    return Err(invalid(&name("radius"), radius, "a finite radius >= 0"));
                }
            }
        }
        Ok(())
    }
}

impl Scenery {
    /// Checks every item and the extent.
    pub fn validate(&self) -> Result<(), Error> {
        for (k, item) in self.items.iter().enumerate() {
            item.validate(k)?;
        }
        if let Some((lo, hi)) = self.extent {
            if !(0..3).all(|k| lo[k].is_finite() && hi[k].is_finite() && lo[k] <= hi[k]) {
                return Err(invalid("extent", format!("{lo:?}..{hi:?}"), "finite corners with hi >= lo"));
            }
        }
        Ok(())
    }
}

/// A background primitive in pixel coordinates (x to the right, y down), drawn row by row.
#[derive(Clone, Debug)]
pub(crate) enum Prim {
    /// A convex polygon, filled: each edge as (a, b, c) with a·x + b·y + c the signed
    /// distance in pixels, positive inside.
    Fill {
        edges: Vec<[f64; 3]>,
        color: [f32; 3],
        alpha: f32,
        rows: (u32, u32),
    },
    /// A segment from `a` of direction `u` (unit) and length `len`, `half` its half width.
    Line {
        a: [f64; 2],
        u: [f64; 2],
        len: f64,
        half: f64,
        color: [f32; 3],
        alpha: f32,
        rows: (u32, u32),
    },
    /// A flat disc (2D sphere obstacles).
    Disc(Sprite),
}

/// The scenery turned into primitives for one frame.
#[derive(Debug, Default)]
pub(crate) struct Built {
    /// Drawn first, in order, under every particle.
    pub background: Vec<Prim>,
    /// 3D sphere obstacles with their depths, to be ordered with the particles.
    pub spheres: Vec<(f64, Sprite)>,
}

/// What `build` needs to know about the frame.
pub(crate) struct Frame<'a> {
    pub camera: &'a Camera,
    pub projector: &'a Projector,
    pub width: usize,
    pub height: usize,
    pub min_radius_px: f64,
    /// The particles' bounding box with radii, `None` when there are none.
    pub particles: Option<([f64; 3], [f64; 3])>,
}

/// Turns the (validated) scenery into primitives.
pub(crate) fn build(scenery: &Scenery, fr: &Frame) -> Built {
    let mut out = Built::default();
    if scenery.items.is_empty() {
        return out;
    }
    let (elo, ehi) = scenery.extent.unwrap_or_else(|| default_extent(scenery, fr));
    let (w, h) = (fr.width as f64, fr.height as f64);
    match (*fr.camera, *fr.projector) {
        (
            Camera::Perspective {
                eye,
                target,
                up: world_up,
                ..
            },
            Projector::Persp { near, .. },
        ) => {
            // Geometry nearer than this along the view axis is cut off before projecting (see
            // `clip_polygon_near`); 1e-4 of the eye–target distance keeps pixel coordinates
            // within ~1e4 focal lengths while losing nothing one could see.
            let zn = near.max(1e-4 * norm(sub(target, eye)));
            let p3 = Persp3 {
                proj: fr.projector,
                zn,
                w,
                h,
            };
            for item in &scenery.items {
                match *item {
                    SceneryItem::Plane { point, normal } => p3.plane(&mut out.background, point, normal, eye, elo, ehi),
                    SceneryItem::Box { lo, hi } => p3.container(&mut out.background, lo, hi, elo, ehi, world_up),
                    SceneryItem::Sphere { .. } => {}
                }
            }
            for item in &scenery.items {
                if let SceneryItem::Sphere { center, radius } = *item {
                    if norm(sub(eye, center)) <= radius {
                        continue; // the eye is inside: the sphere would hide the whole world
                    }
                    let Some(mut q) = fr.projector.project(center, radius) else {
                        continue;
                    };
                    // Obstacles are large, so the exact apparent radius is worth having: a
                    // sphere of radius R at depth z seen on the axis spans f·R/√(z² − R²), i.e.
                    // the particles' f·R/z times z/√(z² − R²).
                    let z2r2 = q.depth * q.depth - radius * radius;
                    q.r = if z2r2 > 0.0 { q.r * q.depth / z2r2.sqrt() } else { 1e6 };
                    if let Some(s) = Sprite::new(q.x, q.y, q.r.max(fr.min_radius_px), OBSTACLE_COLOR, fr.width, fr.height) {
                        out.spheres.push((q.depth, s));
                    }
                }
            }
        }
        (_, Projector::Ortho { cx, cy, s }) => {
            let to_px = |x: f64, y: f64| [cx + s * x, cy - s * y];
            for item in &scenery.items {
                match *item {
                    SceneryItem::Plane { point, normal } => {
                        // In the xy view a plane is the line n·(x − p) = 0 of its normal's xy
                        // part; a plane parallel to the view (normal along z) has no line.
                        let nxy = (normal[0] * normal[0] + normal[1] * normal[1]).sqrt();
                        if nxy <= 1e-9 * norm(normal) {
                            continue;
                        }
                        // Pixel y runs down: the pixel-space normal is (nx, −ny).
                        let n = [normal[0] / nxy, -normal[1] / nxy];
                        let p = to_px(point[0], point[1]);
                        // The solid side n·(q − p) ≤ 0 of the guard rectangle, filled.
                        let mut poly = guard_rect(w, h);
                        poly = clip_halfplane(&poly, [-n[0], -n[1], dot2(n, p)]);
                        push(&mut out.background, fill(poly, FLOOR_COLOR, 1.0, w, h));
                        // The line: the foot of the image centre on it, ± more than the guard
                        // rectangle's diagonal along its direction t = (−n_y, n_x).
                        let t = [-n[1], n[0]];
                        let c = [0.5 * w, 0.5 * h];
                        let along = dot2(t, [c[0] - p[0], c[1] - p[1]]);
                        let foot = [p[0] + along * t[0], p[1] + along * t[1]];
                        let reach = 2.0 * (w + h + 4.0 * GUARD);
                        let a = [foot[0] - reach * t[0], foot[1] - reach * t[1]];
                        let b = [foot[0] + reach * t[0], foot[1] + reach * t[1]];
                        push(&mut out.background, line(a, b, PLANE_2D_PX, LINE_COLOR, 1.0, w, h));
                    }
                    SceneryItem::Box { lo, hi } => {
                        let (l, u) = clamp_box(lo, hi, elo, ehi);
                        // Each side is drawn when its own bound is finite: no lid on an open top.
                        let sides = [
                            (lo[0].is_finite(), [l[0], l[1]], [l[0], u[1]]),
                            (hi[0].is_finite(), [u[0], l[1]], [u[0], u[1]]),
                            (lo[1].is_finite(), [l[0], l[1]], [u[0], l[1]]),
                            (hi[1].is_finite(), [l[0], u[1]], [u[0], u[1]]),
                        ];
                        for (finite, a, b) in sides {
                            if finite {
                                let (a, b) = (to_px(a[0], a[1]), to_px(b[0], b[1]));
                                push(&mut out.background, line(a, b, BOX_2D_PX, LINE_COLOR, 1.0, w, h));
                            }
                        }
                    }
                    SceneryItem::Sphere { center, radius } => {
                        let p = to_px(center[0], center[1]);
                        let r = (s * radius).max(fr.min_radius_px);
                        if let Some(sp) = Sprite::new(p[0], p[1], r, OBSTACLE_COLOR, fr.width, fr.height) {
                            out.background.push(Prim::Disc(sp));
                        }
                    }
                }
            }
        }
        _ => unreachable!("a projector is made from its camera"),
    }
    out
}

/// The particles' box joined with the finite parts of the items; without either, a region
/// around what the camera looks at.
fn default_extent(scenery: &Scenery, fr: &Frame) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut grow = |k: usize, v: f64| {
        if v.is_finite() {
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    };
    if let Some((a, b)) = fr.particles {
        for k in 0..3 {
            grow(k, a[k]);
            grow(k, b[k]);
        }
    }
    for item in &scenery.items {
        match *item {
            SceneryItem::Plane { .. } => {}
            SceneryItem::Box { lo: a, hi: b } => {
                for k in 0..3 {
                    grow(k, a[k]);
                    grow(k, b[k]);
                }
            }
            SceneryItem::Sphere { center, radius } => {
                for (k, c) in center.into_iter().enumerate() {
                    grow(k, c - radius);
                    grow(k, c + radius);
                }
            }
        }
    }
    let fallback = match *fr.camera {
        Camera::Perspective { eye, target, .. } => {
            let r = 0.25 * norm(sub(target, eye));
            (sub(target, [r; 3]), add(target, [r; 3]))
        }
        Camera::Orthographic { center, pixels_per_unit } => {
            let (hw, hh) = (
                0.5 * fr.width as f64 / pixels_per_unit,
                0.5 * fr.height as f64 / pixels_per_unit,
            );
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

/// The box with its infinite bounds replaced by the extent's (never past the other bound).
fn clamp_box(lo: [f64; 3], hi: [f64; 3], elo: [f64; 3], ehi: [f64; 3]) -> ([f64; 3], [f64; 3]) {
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

/// A 3D frame's constants: the projector, the clipping depth and the image size.
struct Persp3<'a> {
    proj: &'a Projector,
    zn: f64,
    w: f64,
    h: f64,
}

impl Persp3<'_> {
    /// A planar convex polygon in world coordinates, filled.
    fn polygon(&self, out: &mut Vec<Prim>, world: &[[f64; 3]], color: [u8; 3], alpha: f32) {
        let cam: Vec<[f64; 3]> = world.iter().map(|&p| self.proj.camera_coords(p)).collect();
        let front = clip_polygon_near(&cam, self.zn);
        let px: Vec<[f64; 2]> = front.iter().map(|&c| self.proj.camera_to_pixel(c)).collect();
        push(out, fill(px, color, alpha, self.w, self.h));
    }

    /// A world segment, drawn as a line `width` pixels wide.
    fn segment(&self, out: &mut Vec<Prim>, a: [f64; 3], b: [f64; 3], width: f64, alpha: f32) {
        let (a, b) = (self.proj.camera_coords(a), self.proj.camera_coords(b));
        if let Some((a, b)) = clip_segment_near(a, b, self.zn) {
            let (a, b) = (self.proj.camera_to_pixel(a), self.proj.camera_to_pixel(b));
            push(out, line(a, b, width, LINE_COLOR, alpha, self.w, self.h));
        }
    }

    /// A plane as a square floor patch: filled, a faint grid around the scene, an outline.
    ///
    /// The patch is centred at the foot c of the scene's centre on the plane, and its half
    /// side is 2.5 times the eye's distance from c (at least the scene's diameter): a camera
    /// framing the scene sees the floor run under and well beyond it, into the distance,
    /// with its far border in view as a horizon.
    fn plane(&self, out: &mut Vec<Prim>, point: [f64; 3], normal: [f64; 3], eye: [f64; 3], elo: [f64; 3], ehi: [f64; 3]) {
        let n = scale(1.0 / norm(normal), normal);
        let centre = scale(0.5, add(elo, ehi));
        let r_scene = 0.5 * norm(sub(ehi, elo));
        let c = sub(centre, scale(dot(sub(centre, point), n), n));
        let half = (2.5 * norm(sub(eye, c))).max(2.0 * r_scene).max(1e-9);
        // Tangents: the world axis least aligned with n, made orthogonal to it, and n × that;
        // a horizontal floor gets a grid along the world's x and y.
        let k = (0..3).min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(0);
        let mut axis = [0.0; 3];
        axis[k] = 1.0;
        let t1 = {
            let v = cross(n, axis);
            scale(1.0 / norm(v), v)
        };
        let t2 = cross(n, t1);
        let at = |u: f64, v: f64| add(add(point, scale(u, t1)), scale(v, t2));
        let (uc, vc) = (dot(sub(c, point), t1), dot(sub(c, point), t2));
        let corners = [
            at(uc - half, vc - half),
            at(uc + half, vc - half),
            at(uc + half, vc + half),
            at(uc - half, vc + half),
        ];
        self.polygon(out, &corners, FLOOR_COLOR, 1.0);
        // Grid: a mat of radius R = 3× the scene's radius around c (within the patch), its
        // lines on multiples of a 1-2-5 step of at least R/12 counted from `point`, so that
        // they stay put from frame to frame (at most ~24 lines each way: the lines' pixels
        // are what a floor costs). Each line is drawn cell by cell, each piece faded out
        // towards the mat's rim and where the lines crowd together on screen (towards the
        // horizon, where they would merge into a dark band).
        let radius = (3.0 * r_scene).max(0.12 * half).min(half);
        let step = nice_step(radius / 12.0);
        let grid = |a: f64| {
            let first = ((a - radius) / step).ceil() as i64;
            let last = ((a + radius) / step).floor() as i64;
            (first..=last).map(|i| i as f64 * step)
        };
        for along_v in [true, false] {
            // Lines of constant u (running along t2), then of constant v (along t1).
            let (lines, mid, other) = if along_v { (grid(uc), vc, uc) } else { (grid(vc), uc, vc) };
            for x in lines {
                let point_at = |s: f64, t: f64| if along_v { at(s, t) } else { at(t, s) };
                let mut y = ((mid - radius) / step).floor() * step;
                while y < mid + radius {
                    let y1 = y + step;
                    let ym = 0.5 * (y + y1);
                    // Full inside 0.6 R of c, nothing beyond R.
                    let rho = ((x - other).powi(2) + (ym - mid).powi(2)).sqrt();
                    let rim = ((radius - rho) / (0.4 * radius)).clamp(0.0, 1.0) as f32;
                    if rim > 0.0 {
                        let (p, q) = (point_at(x, y), point_at(x, y1));
                        let alpha = GRID_ALPHA * rim * self.grid_fade(p, q, point_at(x, ym), point_at(x + step, ym));
                        if alpha > 0.0 {
                            self.segment(out, p, q, GRID_PX, alpha);
                        }
                    }
                    y = y1;
                }
            }
        }
        for i in 0..4 {
            self.segment(out, corners[i], corners[(i + 1) % 4], PATCH_OUTLINE_PX, 1.0);
        }
    }

    /// Opacity factor in [0, 1] of the grid piece p–q whose neighbouring line passes through
    /// `next` (its midpoint `m` moved one step across): the on-screen distance between the
    /// two lines is |(P(next) − P(m)) × d|, d the piece's unit direction on screen; it fades
    /// from 1 at 12 px apart to 0 at 3 px, where 1 px lines would cover a third of the floor.
    fn grid_fade(&self, p: [f64; 3], q: [f64; 3], m: [f64; 3], next: [f64; 3]) -> f32 {
        let cams = [p, q, m, next].map(|w| self.proj.camera_coords(w));
        if cams.iter().any(|c| c[2] <= self.zn) {
            return 1.0; // crosses the near distance: close to the eye, the lines are far apart
        }
        let [pp, pq, pm, pn] = cams.map(|c| self.proj.camera_to_pixel(c));
        let d = [pq[0] - pp[0], pq[1] - pp[1]];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
        if len < 1e-9 {
            return 0.0; // seen end on: a dot
        }
        let gap = ((pn[0] - pm[0]) * d[1] - (pn[1] - pm[1]) * d[0]).abs() / len;
        (((gap - 3.0) / 9.0).clamp(0.0, 1.0)) as f32
    }

    /// A box container: its floor face lightly filled and its 12 edges.
    ///
    /// Both are background: they are drawn before every particle, so the edges in front of
    /// the particles are drawn under them too — a painter's approximation that keeps the
    /// container from hiding what it contains.
    fn container(&self, out: &mut Vec<Prim>, lo: [f64; 3], hi: [f64; 3], elo: [f64; 3], ehi: [f64; 3], up: [f64; 3]) {
        let (l, u) = clamp_box(lo, hi, elo, ehi);
        let corner = |sx: bool, sy: bool, sz: bool| {
            [
                if sx { u[0] } else { l[0] },
                if sy { u[1] } else { l[1] },
                if sz { u[2] } else { l[2] },
            ]
        };
        // The floor: the face whose outward normal points most against the camera's up
        // (the lo z face for a z-up camera), when that face is closed.
        let mut best: Option<(f64, usize, bool)> = None;
        for (axis, up_axis) in up.into_iter().enumerate() {
            for high in [false, true] {
                let d = if high { up_axis } else { -up_axis };
                if best.is_none_or(|(bd, _, _)| d < bd) {
                    best = Some((d, axis, high));
                }
            }
        }
        if let Some((d, axis, high)) = best {
            let closed = if high { hi[axis].is_finite() } else { lo[axis].is_finite() };
            if d < 0.0 && closed {
                let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
                let face: Vec<[f64; 3]> = [(false, false), (true, false), (true, true), (false, true)]
                    .iter()
                    .map(|&(sb, sc)| {
                        let mut s = [false; 3];
                        s[axis] = high;
                        s[b] = sb;
                        s[c] = sc;
                        corner(s[0], s[1], s[2])
                    })
                    .collect();
                // Opaque: a span copy per row, where blending would cost per pixel.
                self.polygon(out, &face, BOX_FLOOR_COLOR, 1.0);
            }
        }
        // An edge along `axis` sits on two faces; it is drawn when both are closed (an open
        // top has no rim, its walls rise to the extent).
        for axis in 0..3 {
            let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
            for (sb, sc) in [(false, false), (true, false), (false, true), (true, true)] {
                let bound = |k: usize, high: bool| if high { hi[k] } else { lo[k] };
                if !(bound(b, sb).is_finite() && bound(c, sc).is_finite()) {
                    continue;
                }
                let mut s0 = [false; 3];
                s0[b] = sb;
                s0[c] = sc;
                let mut s1 = s0;
                s1[axis] = true;
                self.segment(
                    out,
                    corner(s0[0], s0[1], s0[2]),
                    corner(s1[0], s1[1], s1[2]),
                    BOX_EDGE_PX,
                    1.0,
                );
            }
        }
    }
}

/// The smallest of 1, 2, 5 × 10^k not below x (x > 0).
fn nice_step(x: f64) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    let m = x / p;
    p * if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
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
fn clip_polygon_near(poly: &[[f64; 3]], zn: f64) -> Vec<[f64; 3]> {
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

fn dot2(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The image widened by [`GUARD`] pixels, counter-clockwise on screen.
fn guard_rect(w: f64, h: f64) -> Vec<[f64; 2]> {
    vec![
        [-GUARD, -GUARD],
        [-GUARD, h + GUARD],
        [w + GUARD, h + GUARD],
        [w + GUARD, -GUARD],
    ]
}

/// The part of a polygon where e[0]·x + e[1]·y + e[2] ≥ 0 (Sutherland–Hodgman, as above).
fn clip_halfplane(poly: &[[f64; 2]], e: [f64; 3]) -> Vec<[f64; 2]> {
    let side = |p: [f64; 2]| e[0] * p[0] + e[1] * p[1] + e[2];
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (da, db) = (side(a), side(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let s = da / (da - db);
            out.push([a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])]);
        }
    }
    out
}

fn push(out: &mut Vec<Prim>, p: Option<Prim>) {
    if let Some(p) = p {
        out.push(p);
    }
}

/// Pixel rows [row0, row1) whose centres j + ½ lie in [y0, y1].
fn rows_of(y0: f64, y1: f64, h: f64) -> (u32, u32) {
    let r0 = (y0 - 0.5).ceil().clamp(0.0, h) as u32;
    let r1 = ((y1 - 0.5).floor() + 1.0).clamp(0.0, h) as u32;
    (r0, r1)
}

fn color_f32(c: [u8; 3]) -> [f32; 3] {
    c.map(|v| v as f32)
}

/// A convex polygon (pixels) as a fill: clipped to the guard rectangle, its edges as inward
/// signed-distance equations. `None` when nothing of it is in view.
fn fill(poly: Vec<[f64; 2]>, color: [u8; 3], alpha: f32, w: f64, h: f64) -> Option<Prim> {
    let mut poly = poly;
    // Guard rectangle: x ≥ −G, x ≤ w + G, y ≥ −G, y ≤ h + G.
    for e in [
        [1.0, 0.0, GUARD],
        [-1.0, 0.0, w + GUARD],
        [0.0, 1.0, GUARD],
        [0.0, -1.0, h + GUARD],
    ] {
        if poly.len() < 3 {
            return None;
        }
        poly = clip_halfplane(&poly, e);
    }
    if poly.len() < 3 {
        return None;
    }
    let m = poly.len() as f64;
    let centroid = poly.iter().fold([0.0, 0.0], |s, p| [s[0] + p[0] / m, s[1] + p[1] / m]);
    let mut edges = Vec::with_capacity(poly.len());
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let d = [b[0] - a[0], b[1] - a[1]];
        let l = (d[0] * d[0] + d[1] * d[1]).sqrt();
        if l < 1e-9 {
            continue;
        }
        // The unit normal of the edge's line; flipped to point at the centroid (inside).
        let mut n = [-d[1] / l, d[0] / l];
        if dot2(n, [centroid[0] - a[0], centroid[1] - a[1]]) < 0.0 {
            n = [-n[0], -n[1]];
        }
        edges.push([n[0], n[1], -dot2(n, a)]);
    }
    if edges.len() < 3 || edges.len() > MAX_EDGES {
        return None;
    }
    let (y0, y1) = poly
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[1]), hi.max(p[1])));
    let rows = rows_of(y0 - 0.5, y1 + 0.5, h);
    (rows.0 < rows.1).then(|| Prim::Fill {
        edges,
        color: color_f32(color),
        alpha,
        rows,
    })
}

/// A quad cut by the near plane and four guard sides has at most 9 edges.
const MAX_EDGES: usize = 16;

/// A segment (pixels) `width` pixels wide, clipped to the guard rectangle (Liang–Barsky).
pub(crate) fn line(a: [f64; 2], b: [f64; 2], width: f64, color: [u8; 3], alpha: f32, w: f64, h: f64) -> Option<Prim> {
    let d = [b[0] - a[0], b[1] - a[1]];
    // a + s·d for s in [s0, s1], kept inside each of the four sides.
    let (mut s0, mut s1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d[0], a[0] + GUARD),
        (d[0], w + GUARD - a[0]),
        (-d[1], a[1] + GUARD),
        (d[1], h + GUARD - a[1]),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let s = q / p;
            if p < 0.0 {
                s0 = s0.max(s);
            } else {
                s1 = s1.min(s);
            }
        }
    }
    if s0 > s1 {
        return None;
    }
    let p0 = [a[0] + s0 * d[0], a[1] + s0 * d[1]];
    let p1 = [a[0] + s1 * d[0], a[1] + s1 * d[1]];
    let v = [p1[0] - p0[0], p1[1] - p0[1]];
    let len = (v[0] * v[0] + v[1] * v[1]).sqrt();
    let u = if len > 1e-12 { [v[0] / len, v[1] / len] } else { [1.0, 0.0] };
    let half = 0.5 * width;
    let reach = half + 0.5;
    let rows = rows_of(p0[1].min(p1[1]) - reach, p0[1].max(p1[1]) + reach, h);
    (rows.0 < rows.1).then(|| Prim::Line {
        a: p0,
        u,
        len,
        half,
        color: color_f32(color),
        alpha,
        rows,
    })
}

/// The x range where lo ≤ c·x + k ≤ hi (all of it, or none, when c = 0).
#[inline]
fn slab(c: f64, k: f64, lo: f64, hi: f64) -> (f64, f64) {
    if c.abs() < 1e-12 {
        if (lo..=hi).contains(&k) {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (f64::INFINITY, f64::NEG_INFINITY)
        }
    } else {
        let (x0, x1) = ((lo - k) / c, (hi - k) / c);
        (x0.min(x1), x0.max(x1))
    }
}

/// Pixel columns [i0, i1) whose centres i + ½ lie in [x0, x1].
#[inline]
fn cols_of(x0: f64, x1: f64, width: usize) -> (usize, usize) {
    let wf = width as f64;
    let i0 = (x0 - 0.5).ceil().clamp(0.0, wf) as usize;
    let i1 = ((x1 - 0.5).floor() + 1.0).clamp(0.0, wf) as usize;
    (i0, i1)
}

impl Prim {
    /// Rows [row0, row1) the primitive can touch.
    pub(crate) fn rows(&self) -> (u32, u32) {
        match self {
            Prim::Fill { rows, .. } | Prim::Line { rows, .. } => *rows,
            Prim::Disc(s) => (s.row0, s.row1),
        }
    }

    /// Draws row `j` of the primitive into `row` (RGB8, the image's width).
    pub(crate) fn draw_row(&self, row: &mut [u8], j: u32) {
        let width = row.len() / 3;
        let y = j as f64 + 0.5;
        match self {
            Prim::Fill { edges, color, alpha, .. } => {
                // Each edge's signed distance along this row is d_e(x) = a·x + k_e with
                // k_e = b·y + c. A pixel whose centre is at distance d inside a straight edge
                // is covered clamp(d + ½, 0, 1) (the edge sweeps the unit pixel over a
                // one-pixel band of d); inside a convex polygon the nearest edge decides:
                // coverage ≈ clamp(min_e d_e + ½, 0, 1). So the touched pixels have every
                // d_e > −½ and the fully covered ones every d_e ≥ ½: two x ranges per edge.
                let mut k = [0.0f64; MAX_EDGES];
                let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
                let (mut f0, mut f1) = (f64::NEG_INFINITY, f64::INFINITY);
                for (e, ke) in edges.iter().zip(k.iter_mut()) {
                    *ke = e[1] * y + e[2];
                    if e[0].abs() < 1e-12 {
                        if *ke <= -0.5 {
                            return;
                        }
                        if *ke < 0.5 {
                            f0 = f64::INFINITY; // no pixel of this row is fully inside
                        }
                    } else {
                        let (xt, xf) = ((-0.5 - *ke) / e[0], (0.5 - *ke) / e[0]);
                        if e[0] > 0.0 {
                            t0 = t0.max(xt);
                            f0 = f0.max(xf);
                        } else {
                            t1 = t1.min(xt);
                            f1 = f1.min(xf);
                        }
                    }
                }
                let (i0, i1) = cols_of(t0, t1, width);
                if i0 >= i1 {
                    return;
                }
                let (fi0, fi1) = if f0 <= f1 { cols_of(f0, f1, width) } else { (i0, i0) };
                let (fi0, fi1) = (fi0.clamp(i0, i1), fi1.clamp(i0, i1).max(fi0.clamp(i0, i1)));
                let k = &k[..edges.len()];
                let partial = |px: &mut [u8], i: usize| {
                    let x = i as f64 + 0.5;
                    let d = edges.iter().zip(k).fold(f64::INFINITY, |m, (e, ke)| m.min(e[0] * x + ke));
                    let a = (d + 0.5).clamp(0.0, 1.0) as f32 * alpha;
                    if a > 0.0 {
                        blend(px, *color, a);
                    }
                };
                for i in (i0..fi0).chain(fi1..i1) {
                    partial(&mut row[3 * i..3 * i + 3], i);
                }
                if *alpha >= 1.0 {
                    fill_rgb(&mut row[3 * fi0..3 * fi1], color.map(|c| c as u8));
                } else {
                    for px in row[3 * fi0..3 * fi1].chunks_exact_mut(3) {
                        blend(px, *color, *alpha);
                    }
                }
            }
            Prim::Line {
                a,
                u,
                len,
                half,
                color,
                alpha,
                ..
            } => {
                // Coverage of a pixel by a line of width w whose centre line passes at distance
                // d from the pixel centre: each of the line's two borders is a straight edge,
                // the near one at signed distance w/2 − d inside, which covers
                // clamp(w/2 − d + ½, 0, 1) of the pixel (as for the fill above); for w ≥ 1
                // the far border (at w/2 + d ≥ ½) leaves it alone, so
                // coverage = clamp(w/2 + ½ − d, 0, 1). d is the distance to the segment, so
                // the ends are round caps.
                let reach = half + 0.5;
                let n = [-u[1], u[0]];
                // The pixels within reach: |n·(p − a)| ≤ reach and −reach ≤ u·(p − a) ≤ len + reach.
                let (x0, x1) = slab(n[0], n[1] * (y - a[1]) - n[0] * a[0], -reach, reach);
                let (x2, x3) = slab(u[0], u[1] * (y - a[1]) - u[0] * a[0], -reach, len + reach);
                let (i0, i1) = cols_of(x0.max(x2), x1.min(x3), width);
                for i in i0..i1 {
                    let p = [i as f64 + 0.5 - a[0], y - a[1]];
                    let t = dot2(p, *u).clamp(0.0, *len);
                    let (dx, dy) = (p[0] - t * u[0], p[1] - t * u[1]);
                    let d = (dx * dx + dy * dy).sqrt();
                    let cov = (half + 0.5 - d).clamp(0.0, 1.0) as f32 * alpha;
                    if cov > 0.0 {
                        blend(&mut row[3 * i..3 * i + 3], *color, cov);
                    }
                }
            }
            Prim::Disc(s) => disc_row(row, s, j),
        }
    }
}
