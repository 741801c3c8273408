//! Contact shadows on the 3D floors: each particle above a floor (a plane facing up, a
//! box's bottom, a mesh's upward triangle) darkens a soft disc of it straight below
//! ([`shadows`]; [`super::paint`] calls it after the scenery).

use super::clip::clip_polygon_halfspace;
use super::frame3::{tangents, Persp3, FLOOR_NZ};
use super::mesh_paint::MeshFloors;
use super::prim::Prim;
use crate::collide::Collider;
use crate::vec3::{add, dot, norm, scale, sub};

/// Contact shadows on 3D floors ([`shadows`]): this colour at up to [`SHADOW_ALPHA`].
pub const SHADOW_COLOR: [u8; 3] = [30, 30, 38];
/// Opacity of the core of the shadow of a particle resting on a floor.
pub const SHADOW_ALPHA: f32 = 0.55;

/// A floor a particle can stand over: a plane whose normal points up (n_z ≥ [`FLOOR_NZ`] of
/// its length), or a box's closed bottom face (only over the box's xy extent). (A mesh's
/// floors are its triangles, [`MeshFloors`].)
struct Floor {
    point: [f64; 3],
    /// Unit normal, pointing into the free side.
    n: [f64; 3],
    /// The xy rectangle it covers (a box's bottom), else unbounded.
    xy: Option<([f64; 2], [f64; 2])>,
}

/// The floor a particle's shadow falls on: the drop t (m) along −z from its centre to it,
/// the centre's distance d ≥ 0 from the floor's plane, its unit normal n (into the free
/// side), a point of it, and the plane or box (none: a mesh's triangle).
#[derive(Clone, Copy)]
struct Below<'a> {
    t: f64,
    d: f64,
    n: [f64; 3],
    point: [f64; 3],
    floor: Option<&'a Floor>,
}

/// Contact shadows: each particle above a floor darkens a soft disc of that floor straight
/// below it (along −z, kinema's gravity), on the first floor the vertical through its centre
/// meets. With h the gap between the particle (radius r) and the floor, the disc's radius is
/// r + h/2 and the opacity of its core [`SHADOW_ALPHA`]·exp(−h / 2r): a ball resting on the
/// floor sits on a dark patch, one a few radii up casts a wide faint one, and one higher
/// than about 7 radii none. The soft edge is six concentric discs (24-gons in the floor
/// plane) of equal opacity, spread more widely the higher the particle, each cut to its
/// floor (a box's bottom face; a plane's part on the free side of the other planes). On a
/// plane or a box the shadow is drawn after the scenery and before every particle (particles
/// stand above their floors, so nothing a shadow could cover is in front of it). On a
/// mesh's triangle (the bottom of a bowl; uncut: a fine mesh curves away from the disc by
/// less than it can show) it joins the depth order just behind its particle, so that the
/// mesh's facets behind it are drawn under it and those in front over it. Floors seen from
/// below (the eye on their solid side) get none.
pub(super) fn shadows(
    p3: &Persp3,
    colliders: &[Collider],
    eye: [f64; 3],
    particles: (&[f64], &[f64]),
    (background, ordered): (&mut Vec<Prim>, &mut Vec<(f64, Prim)>),
) {
    let (positions, radius) = particles;
    if radius.is_empty() {
        return;
    }
    let (floors, meshes) = floors_of(colliders);
    if floors.is_empty() && meshes.is_empty() {
        return;
    }
    // Each shadow is cut to its floor: a box's bottom face, or the part of a plane on the
    // free side of the other planes (a facet of a bowl), as the floor is drawn.
    let planes: Vec<([f64; 3], [f64; 3])> = floors.iter().filter(|f| f.xy.is_none()).map(|f| (f.point, f.n)).collect();
    let mut on_mesh = Vec::new();
    for (c, &r) in positions.chunks_exact(3).zip(radius) {
        let c = [c[0], c[1], c[2]];
        if !(r > 0.0) {
            continue;
        }
        let Some(below) = floor_below(c, &floors, &meshes) else {
            continue;
        };
        if dot(sub(eye, below.point), below.n) <= 0.0 {
            continue; // the floor is seen from below
        }
        let layer = if below.floor.is_some() {
            &mut *background
        } else {
            &mut on_mesh
        };
        shadow_rings(p3, (c, r), &below, &planes, layer);
        // Just behind the particle in the depth order (its depth, one step further: the same
        // zc as its sprite's), after every facet behind it.
        let behind = p3.proj.camera_coords(c)[2].next_up();
        ordered.extend(on_mesh.drain(..).map(|p| (behind, p)));
    }
}

/// The floors of `colliders` that take shadows: the planes facing up and the boxes' closed
/// bottoms, and the meshes' upward triangles.
fn floors_of(colliders: &[Collider]) -> (Vec<Floor>, Vec<MeshFloors<'_>>) {
    let mut floors = Vec::new();
    let mut meshes = Vec::new();
    for c in colliders {
        match c {
            Collider::Plane(p) => {
                let n = scale(1.0 / norm(p.normal()), p.normal());
                if n[2] >= FLOOR_NZ {
                    floors.push(Floor {
                        point: p.point(),
                        n,
                        xy: None,
                    });
                }
            }
            Collider::Box(b) => {
                let (lo, hi) = (b.lo(), b.hi());
                if lo[2].is_finite() {
                    floors.push(Floor {
                        point: [0.0, 0.0, lo[2]],
                        n: [0.0, 0.0, 1.0],
                        xy: Some(([lo[0], lo[1]], [hi[0], hi[1]])),
                    });
                }
            }
            Collider::Mesh(m) => meshes.extend(MeshFloors::new(m)),
            Collider::Sphere(_) => {}
        }
    }
    (floors, meshes)
}

/// The first floor below the centre `c` along −z: the least drop t = d / n_z.
fn floor_below<'f>(c: [f64; 3], floors: &'f [Floor], meshes: &[MeshFloors<'_>]) -> Option<Below<'f>> {
    let mut best: Option<Below> = None;
    for f in floors {
        if let Some((lo, hi)) = f.xy {
            if c[0] < lo[0] || c[0] > hi[0] || c[1] < lo[1] || c[1] > hi[1] {
                continue;
            }
        }
        let d = dot(sub(c, f.point), f.n);
        if d < 0.0 {
            continue;
        }
        let t = d / f.n[2];
        if best.as_ref().is_none_or(|b| t < b.t) {
            best = Some(Below {
                t,
                d,
                n: f.n,
                point: f.point,
                floor: Some(f),
            });
        }
    }
    for m in meshes {
        if let Some((t, n, q)) = m.below(c) {
            if best.as_ref().is_none_or(|b| t < b.t) {
                best = Some(Below {
                    t,
                    d: t * n[2],
                    n,
                    point: q,
                    floor: None,
                });
            }
        }
    }
    best
}

/// The shadow of the particle (centre c, radius r) on the floor `below`, into `layer`: its
/// rings, each cut to the floor (`planes`: the planes' (point, normal), which cut a plane's
/// shadow to its facet); nothing when too faint.
fn shadow_rings(p3: &Persp3, (c, r): ([f64; 3], f64), below: &Below<'_>, planes: &[([f64; 3], [f64; 3])], layer: &mut Vec<Prim>) {
    const SIDES: usize = 24;
    const RINGS: usize = 6;
    let Below { t, d, n, point, floor } = *below;
    let h = (d - r).max(0.0);
    let alpha = SHADOW_ALPHA * (-h / (2.0 * r)).exp() as f32;
    if alpha < 0.01 {
        return;
    }
    let foot = [c[0], c[1], c[2] - t];
    let rs = r + 0.5 * h;
    // The soft edge: rings from (1 − b) to (1 + b) of rs, b from 0.3 (resting) to 0.7.
    let b = 0.3 + 0.4 * h / (h + r);
    let ring_alpha = 1.0 - (1.0 - alpha).powf(1.0 / RINGS as f32);
    let (t1, t2) = tangents(n);
    for ring in 0..RINGS {
        let rr = rs * (1.0 - b + 2.0 * b * ring as f64 / (RINGS - 1) as f64);
        let mut poly: Vec<[f64; 3]> = (0..SIDES)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / SIDES as f64;
                add(foot, add(scale(rr * a.cos(), t1), scale(rr * a.sin(), t2)))
            })
            .collect();
        match floor.map(|f| f.xy) {
            Some(Some((lo, hi))) => {
                for (q, m) in [
                    ([lo[0], 0.0, 0.0], [1.0, 0.0, 0.0]),
                    ([hi[0], 0.0, 0.0], [-1.0, 0.0, 0.0]),
                    ([0.0, lo[1], 0.0], [0.0, 1.0, 0.0]),
                    ([0.0, hi[1], 0.0], [0.0, -1.0, 0.0]),
                ] {
                    if q.iter().all(|v| v.is_finite()) {
                        poly = clip_polygon_halfspace(&poly, q, m);
                    }
                }
            }
            Some(None) => {
                for &(q, m) in planes {
                    if (q, m) != (point, n) {
                        poly = clip_polygon_halfspace(&poly, q, m);
                    }
                }
            }
            None => {}
        }
        if poly.len() >= 3 {
            p3.polygon(layer, &poly, SHADOW_COLOR, ring_alpha);
        }
    }
}
