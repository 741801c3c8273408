//! Painting the scenery: the static colliders of a world — planes, boxes, sphere obstacles,
//! the engine's own [`Collider`]s — drawn with the particles, so that a ball bounces on a
//! floor one can see.
//!
//! | collider | 3D (perspective camera)                                  | 2D (orthographic, xy)                 |
//! |----------|----------------------------------------------------------|---------------------------------------|
//! | plane    | a finite floor patch with a faint grid and an outline,   | the solid side lightly filled and the |
//! |          | under everything (background layer)                      | line itself, thick                    |
//! | box      | its floor face lightly filled and its 12 edges as lines, | its rectangle outline (background)    |
//! |          | under everything (background layer)                      |                                       |
//! | sphere   | a shaded sphere in the particles' far-to-near order      | a filled disc under the particles     |
//! | mesh     | translucent lit triangles and faint rim, crease and      | (2D worlds have no meshes)            |
//! |          | outline edges, in the particles' far-to-near order       |                                       |
//! |          | ([`super::mesh_paint`])                                  |                                       |
//!
//! Everything is in fixed neutral colours ([`FLOOR_COLOR`], [`BOX_FLOOR_COLOR`],
//! [`LINE_COLOR`], [`OBSTACLE_COLOR`], [`super::mesh_paint::MESH_COLOR`]) so that the particles' colours keep
//! their meaning.
//!
//! Geometry is turned into a few pixel-space primitives (`Prim`: a convex polygon, a line
//! segment, a disc) once per frame, in f64, cut at the near depth first (`clip.rs`);
//! each band of the raster stage draws every primitive's rows that fall inside it, in list
//! order, before its particles. A band's pixels still depend only on its own rows, so frames
//! stay byte-identical for any thread count. What is infinite (a plane, an open box face) is
//! sized by the scene's extent ([`super::extent`]).

use super::camera::{invalid, Camera, Projector};
use super::clip::{clip_halfplane, clip_polygon_halfspace, clip_segment_near, dot2, guard_rect, near_depth, GUARD};
use super::extent::{clamp_box, Region};
pub use super::frame3::PLANE_ALPHA;
use super::frame3::{tangents, Persp3};
use super::mesh_paint::paint_mesh;
use super::pixels::Sprite;
use super::prim::{fill, line, push, Prim};
use super::shadows::shadows;
use crate::collide::{Collider, Pose, SurfaceVelocity};
use crate::vec3::{add, dot, norm, scale, sub};
use crate::Error;

/// The scenery of a frame: what to draw besides the particles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scenery {
    /// The colliders, drawn in this order within their layer. The 2D (orthographic) camera
    /// draws their xy part: a plane whose normal is along z has no line there.
    pub colliders: Vec<Collider>,
    /// The region the scene occupies, `(lo, hi)` in m: infinite box bounds are clamped to it,
    /// and a plane's floor patch is centred under its centre and sized from it. `None`: the
    /// particles' bounding box (radii included) joined with the finite parts of the
    /// colliders, in this frame. A video should give one extent for all its frames
    /// ([`super::scene_extent`]), so that the scenery does not move while the particles do.
    pub extent: Option<Region>,
}

impl Scenery {
    /// Checks the extent (the colliders were checked when they were made).
    pub fn validate(&self) -> Result<(), Error> {
        if let Some((lo, hi)) = self.extent {
            if !(0..3).all(|k| lo[k].is_finite() && hi[k].is_finite() && lo[k] <= hi[k]) {
                return Err(invalid("extent", format!("{lo:?}..{hi:?}"), "finite corners with hi >= lo"));
            }
        }
        Ok(())
    }

    /// The same scenery with its colliders where a frame's `poses` (one per collider, in
    /// order) put them, its extent kept: how a video draws moving colliders, one scenery a
    /// frame. A collider whose pose is the identity is kept as it is; the others are displaced
    /// as the engine places a moving collider ([`Collider::posed`]: a box only translated).
    /// The pose of a collider comes from its motion (`kinema.render.descriptions.
    /// collider_poses`, the engine's `Motion::at`), never from here.
    pub fn posed(&self, poses: &[Pose]) -> Result<Scenery, Error> {
        if poses.len() != self.colliders.len() {
            return Err(invalid(
                "poses",
                format!("{} poses", poses.len()),
                &format!("one per collider ({})", self.colliders.len()),
            ));
        }
        let colliders = self
            .colliders
            .iter()
            .zip(poses)
            .map(|(c, pose)| {
                if *pose == Pose::IDENTITY {
                    Ok(c.clone())
                } else {
                    c.posed(pose, SurfaceVelocity::default())
                }
            })
            .collect::<Result<_, _>>()?;
        Ok(Scenery {
            colliders,
            extent: self.extent,
        })
    }
}

/// Floor patches (3D planes, box floors) and the solid side of 2D planes, RGB8.
pub const FLOOR_COLOR: [u8; 3] = [224, 224, 220];
/// A box's floor face, RGB8: a shade darker than [`FLOOR_COLOR`], so that it shows on a floor.
pub const BOX_FLOOR_COLOR: [u8; 3] = [212, 212, 206];
/// Outlines: plane patch borders, grid lines (faint), box edges, 2D plane lines, RGB8.
pub const LINE_COLOR: [u8; 3] = [96, 96, 100];
/// Sphere obstacles, RGB8 (shaded in 3D like the particles).
pub const OBSTACLE_COLOR: [u8; 3] = [176, 178, 184];

/// 3D plane patches: a grey drawn at [`PLANE_ALPHA`], so that what lies behind a plane shows
/// through it; over white one plane reads about as [`FLOOR_COLOR`], two crossing ones darker.
pub const PLANE_COLOR: [u8; 3] = [150, 150, 142];
pub use super::shadows::{SHADOW_ALPHA, SHADOW_COLOR};

/// Line widths, pixels.
const PATCH_OUTLINE_PX: f64 = 1.5;
const GRID_PX: f64 = 1.0;
const BOX_EDGE_PX: f64 = 1.5;
const PLANE_2D_PX: f64 = 3.0;
const BOX_2D_PX: f64 = 2.0;
/// Opacity of the faint grid.
const GRID_ALPHA: f32 = 0.25;

/// The colliders turned into primitives for one frame.
#[derive(Debug, Default)]
pub(crate) struct Painted {
    /// Drawn first, in order, under every particle.
    pub background: Vec<Prim>,
    /// 3D sphere obstacles with their depths, to be ordered with the particles.
    pub spheres: Vec<(f64, Sprite)>,
    /// 3D meshes' facets and edge lines with their depths, to be ordered with the particles.
    pub ordered: Vec<(f64, Prim)>,
}

/// What [`paint`] needs to know about the frame.
pub(crate) struct View<'a> {
    pub camera: &'a Camera,
    pub projector: &'a Projector,
    /// Image size, pixels.
    pub width: usize,
    pub height: usize,
    /// Smallest drawn radius, pixels (2D sphere obstacles and far 3D ones).
    pub min_radius_px: f64,
    /// Unit direction towards the light in camera coordinates (x right, y up, z towards
    /// the viewer), as the spheres are lit: it shades the meshes' facets.
    pub light: [f64; 3],
}

/// Turns the colliders into primitives; `extent` sizes what is infinite (see [`Scenery`]).
/// `particles` (positions and radii) cast contact shadows on the 3D floors ([`shadows`]).
pub(crate) fn paint(colliders: &[Collider], extent: Region, view: &View, particles: (&[f64], &[f64])) -> Painted {
    let mut out = Painted::default();
    if colliders.is_empty() {
        return out;
    }
    match (*view.camera, *view.projector) {
        (Camera::Perspective { eye, up: world_up, .. }, Projector::Persp { .. }) => {
            paint_3d(colliders, extent, view, particles, (eye, world_up), &mut out)
        }
        (_, Projector::Ortho { cx, cy, s }) => paint_2d(colliders, extent, view, (cx, cy, s), &mut out),
        _ => unreachable!("a projector is made from its camera"),
    }
    out
}

/// [`paint`] through a perspective camera at `eye` (with its `world_up`): planes and boxes
/// into the background, meshes' facets and sphere obstacles to order with the particles,
/// the particles' shadows on the floors.
fn paint_3d(
    colliders: &[Collider],
    extent: Region,
    view: &View,
    particles: (&[f64], &[f64]),
    (eye, world_up): ([f64; 3], [f64; 3]),
    out: &mut Painted,
) {
    let (w, h) = (view.width as f64, view.height as f64);
    // Geometry nearer than this along the view axis is cut off before projecting.
    let p3 = Persp3 {
        proj: view.projector,
        zn: near_depth(view.camera, view.projector),
        w,
        h,
    };
    // Each plane is drawn where it bounds the free space: the part of it on the free
    // side of every other plane (a bowl of tilted planes shows its facets, not eight
    // squares running through each other).
    let planes: Vec<([f64; 3], [f64; 3])> = colliders
        .iter()
        .filter_map(|c| match c {
            Collider::Plane(p) => Some((p.point(), p.normal())),
            _ => None,
        })
        .collect();
    // Mesh triangles spanning more depth than the smallest particle's radius (or than
    // 1/64 of the scene's diagonal, whichever is larger: the pieces stay few) are
    // halved, so that their depth order with the particles holds (`mesh_paint`).
    let smallest = particles.1.iter().copied().filter(|&r| r > 0.0).fold(f64::INFINITY, f64::min);
    let split = smallest.max(norm(sub(extent.1, extent.0)) / 64.0);
    let mut k = 0;
    for collider in colliders {
        match collider {
            Collider::Plane(p) => {
                let others: Vec<([f64; 3], [f64; 3])> =
                    planes.iter().enumerate().filter(|&(j, _)| j != k).map(|(_, &q)| q).collect();
                k += 1;
                p3.plane(&mut out.background, p.point(), p.normal(), eye, extent, &others)
            }
            Collider::Box(b) => p3.container(&mut out.background, b.lo(), b.hi(), extent, world_up),
            Collider::Mesh(m) => paint_mesh(&p3, m, eye, view.light, split, &mut out.ordered),
            Collider::Sphere(_) => {}
        }
    }
    shadows(&p3, colliders, eye, particles, (&mut out.background, &mut out.ordered));
    paint_spheres(colliders, eye, view, &mut out.spheres);
}

/// The 3D sphere obstacles, shaded spheres with their depths (none around the eye).
fn paint_spheres(colliders: &[Collider], eye: [f64; 3], view: &View, spheres: &mut Vec<(f64, Sprite)>) {
    for collider in colliders {
        if let Collider::Sphere(sphere) = collider {
            let (center, radius) = (sphere.center(), sphere.radius());
            if norm(sub(eye, center)) <= radius {
                continue; // the eye is inside: the sphere would hide the whole world
            }
            let Some(mut q) = view.projector.project(center, radius) else {
                continue;
            };
            // Obstacles are large, so the exact apparent radius is worth having: a
            // sphere of radius R at depth z seen on the axis spans f·R/√(z² − R²), i.e.
            // the particles' f·R/z times z/√(z² − R²).
            let z2r2 = q.depth * q.depth - radius * radius;
            q.r = if z2r2 > 0.0 { q.r * q.depth / z2r2.sqrt() } else { 1e6 };
            if let Some(s) = Sprite::new(q.x, q.y, q.r.max(view.min_radius_px), OBSTACLE_COLOR, view.width, view.height) {
                spheres.push((q.depth, s));
            }
        }
    }
}

/// [`paint`] through the orthographic camera of the xy-plane (pixel x = cx + s x, y = cy −
/// s y): everything into the background, under the particles.
fn paint_2d(colliders: &[Collider], extent: Region, view: &View, (cx, cy, s): (f64, f64, f64), out: &mut Painted) {
    let (w, h) = (view.width as f64, view.height as f64);
    let to_px = |x: f64, y: f64| [cx + s * x, cy - s * y];
    for collider in colliders {
        match collider {
            Collider::Plane(plane) => {
                let (point, normal) = (plane.point(), plane.normal());
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
            Collider::Box(b) => {
                let (lo, hi) = (b.lo(), b.hi());
                let (l, u) = clamp_box(lo, hi, extent);
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
            Collider::Mesh(_) => {} // a 2D world has no meshes
            Collider::Sphere(sphere) => {
                let center = sphere.center();
                let p = to_px(center[0], center[1]);
                let r = (s * sphere.radius()).max(view.min_radius_px);
                if let Some(sp) = Sprite::new(p[0], p[1], r, OBSTACLE_COLOR, view.width, view.height) {
                    out.background.push(Prim::Disc(sp));
                }
            }
        }
    }
}

/// The plane and box painters (the struct is shared with [`super::mesh_paint`]).
impl Persp3<'_> {
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
    ///
    /// The patch is translucent ([`PLANE_COLOR`] at [`PLANE_ALPHA`]) with a darker outline,
    /// and cut to the free side of the `others` (point, normal): what lies behind a tilted
    /// plane shows through it, and where planes cross the overlap reads darker.
    fn plane(
        &self,
        out: &mut Vec<Prim>,
        point: [f64; 3],
        normal: [f64; 3],
        eye: [f64; 3],
        extent: Region,
        others: &[([f64; 3], [f64; 3])],
    ) {
        let (elo, ehi) = extent;
        let n = scale(1.0 / norm(normal), normal);
        let centre = scale(0.5, add(elo, ehi));
        let r_scene = 0.5 * norm(sub(ehi, elo));
        let c = sub(centre, scale(dot(sub(centre, point), n), n));
        let half = (2.5 * norm(sub(eye, c))).max(2.0 * r_scene).max(1e-9);
        // a horizontal floor gets a grid along the world's x and y
        let (t1, t2) = tangents(n);
        let at = |u: f64, v: f64| add(add(point, scale(u, t1)), scale(v, t2));
        let (uc, vc) = (dot(sub(c, point), t1), dot(sub(c, point), t2));
        let corners = [
            at(uc - half, vc - half),
            at(uc + half, vc - half),
            at(uc + half, vc + half),
            at(uc - half, vc + half),
        ];
        let mut patch = corners.to_vec();
        for &(q, m) in others {
            patch = clip_polygon_halfspace(&patch, q, m);
        }
        if patch.len() < 3 {
            return; // on the solid side of another plane: no free space touches it
        }
        self.polygon(out, &patch, PLANE_COLOR, PLANE_ALPHA);
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
                            if let Some((p, q)) = clip_segment_halfspaces(p, q, others) {
                                self.segment(out, p, q, GRID_PX, alpha);
                            }
                        }
                    }
                    y = y1;
                }
            }
        }
        for i in 0..patch.len() {
            self.segment(out, patch[i], patch[(i + 1) % patch.len()], PATCH_OUTLINE_PX, 1.0);
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
    fn container(&self, out: &mut Vec<Prim>, lo: [f64; 3], hi: [f64; 3], extent: Region, up: [f64; 3]) {
        let (l, u) = clamp_box(lo, hi, extent);
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

/// The part of the segment ab (world) on the free side of every plane (point, normal).
fn clip_segment_halfspaces(a: [f64; 3], b: [f64; 3], planes: &[([f64; 3], [f64; 3])]) -> Option<([f64; 3], [f64; 3])> {
    let (mut s0, mut s1) = (0.0f64, 1.0f64);
    for &(q, n) in planes {
        let (da, db) = (dot(sub(a, q), n), dot(sub(b, q), n));
        if da < 0.0 && db < 0.0 {
            return None;
        }
        if (da < 0.0) != (db < 0.0) {
            let s = da / (da - db);
            if da < 0.0 {
                s0 = s0.max(s);
            } else {
                s1 = s1.min(s);
            }
        }
    }
    (s1 > s0).then(|| (add(a, scale(s0, sub(b, a))), add(a, scale(s1, sub(b, a)))))
}
