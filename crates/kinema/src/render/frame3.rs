//! What the two 3D scenery painters share ([`super::paint`]: planes, boxes, spheres;
//! [`super::mesh_paint`]: meshes, which `paint` calls): the frame's constants
//! ([`Persp3`], which fills a world polygon), the surfaces' translucency ([`PLANE_ALPHA`]) and the rule for which
//! surfaces are floors that take shadows ([`FLOOR_NZ`]).

use super::camera::Projector;
use super::clip::clip_polygon_near;
use super::prim::{fill, push, Prim};
use crate::vec3::{cross, norm, scale};

/// Opacity of a 3D plane patch, and of a mesh's facets
/// ([`super::mesh_paint::MESH_ALPHA`]): what lies behind a surface shows through it.
pub const PLANE_ALPHA: f32 = 0.3;

/// A plane, or a mesh's triangle, is a floor that takes shadows when its normal's z is at
/// least this fraction of its length (about 72° from level at most).
pub(super) const FLOOR_NZ: f64 = 0.3;

/// A 3D frame's constants: the projector, the clipping depth and the image size.
pub(super) struct Persp3<'a> {
    pub(super) proj: &'a Projector,
    /// Geometry nearer than this along the view axis (m) is cut off before projecting.
    pub(super) zn: f64,
    /// Image width and height, pixels.
    pub(super) w: f64,
    pub(super) h: f64,
}

impl Persp3<'_> {
    /// A planar convex polygon in world coordinates, filled.
    pub(super) fn polygon(&self, out: &mut Vec<Prim>, world: &[[f64; 3]], color: [u8; 3], alpha: f32) {
        let cam: Vec<[f64; 3]> = world.iter().map(|&p| self.proj.camera_coords(p)).collect();
        let front = clip_polygon_near(&cam, self.zn);
        let px: Vec<[f64; 2]> = front.iter().map(|&c| self.proj.camera_to_pixel(c)).collect();
        push(out, fill(px, color, alpha, self.w, self.h));
    }
}

/// Two unit tangents of the unit normal `n`: the world axis least aligned with n, made
/// orthogonal to it, and n × that (a horizontal plane gets the world's x and y).
pub(super) fn tangents(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let k = (0..3).min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(0);
    let mut axis = [0.0; 3];
    axis[k] = 1.0;
    let v = cross(n, axis);
    let t1 = scale(1.0 / norm(v), v);
    (t1, cross(n, t1))
}
