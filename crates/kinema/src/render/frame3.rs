//! What the two 3D scenery painters share ([`super::paint`]: planes, boxes, spheres;
//! [`super::mesh_paint`]: meshes, which `paint` calls): the frame's constants
//! ([`Persp3`]), the surfaces' translucency ([`PLANE_ALPHA`]) and the rule for which
//! surfaces are floors that take shadows ([`FLOOR_NZ`]).

use super::camera::Projector;

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
