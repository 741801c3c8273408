//! What a frame shows and how it is drawn: the particles, springs, trails, markers and
//! scenery of a [`Frame`], the image's [`RenderParams`] (with the spheres' [`Shading`]), and
//! the [`RenderStats`] a render returns.

use super::paint::Scenery;

/// How 3D spheres are lit. Directions are in camera coordinates: x to the right of the
/// image, y up the image, z from the sphere towards the viewer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    /// Direction towards the light (need not be unit). Default (−0.45, 0.6, 0.66): upper left,
    /// in front.
    pub light_dir: [f64; 3],
    /// Ambient fraction of the base colour seen where the light does not reach, in [0, 1].
    /// Default 0.25.
    pub ambient: f64,
    /// Strength of the white specular highlight, in [0, 1]. Default 0.35.
    pub specular: f64,
    /// Blinn–Phong exponent of the highlight (larger is tighter). Default 32.
    pub shininess: i32,
}

impl Default for Shading {
    fn default() -> Self {
        Shading {
            light_dir: [-0.45, 0.6, 0.66],
            ambient: 0.25,
            specular: 0.35,
            shininess: 32,
        }
    }
}

/// Everything about a frame except the particles and the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderParams {
    /// Image width, pixels (1 ..= 32768).
    pub width: usize,
    /// Image height, pixels (1 ..= 32768).
    pub height: usize,
    /// Background colour, RGB8. Default white.
    pub background: [u8; 3],
    /// Smallest drawn radius, pixels, so that distant or tiny particles stay visible.
    /// Default 1.0.
    pub min_radius_px: f64,
    /// Lighting of 3D spheres (the 2D camera draws flat discs and ignores it).
    pub shading: Shading,
    /// Width of the lines drawn for springs ([`render_frame`](super::render_frame)), pixels, in [1, 1000].
    /// Default 1.5.
    pub spring_width_px: f64,
    /// Width of the particles' trails ([`Frame::trails`]), pixels, in [1, 1000]. Default 1.5.
    pub trail_width_px: f64,
    /// Radius of a marker ([`Frame::markers`]), pixels, in [1, 1000]; its dark rim adds
    /// [`MARKER_RIM_PX`]. Default 5.
    pub marker_radius_px: f64,
}

/// The fill of a marker ([`Frame::markers`]: an attractor): amber, a sun.
pub const MARKER_COLOR: [u8; 3] = [245, 170, 40];
/// The rim of a marker, dark grey.
pub const MARKER_RIM_COLOR: [u8; 3] = [50, 50, 54];
/// The width of a marker's rim, pixels.
pub const MARKER_RIM_PX: f64 = 1.5;

impl RenderParams {
    /// A `width × height` frame with the defaults of the other fields.
    pub fn new(width: usize, height: usize) -> Self {
        RenderParams {
            width,
            height,
            background: [255, 255, 255],
            min_radius_px: 1.0,
            shading: Shading::default(),
            spring_width_px: 1.5,
            trail_width_px: 1.5,
            marker_radius_px: 5.0,
        }
    }
}

/// What a frame contained.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderStats {
    /// Particles that touched the image.
    pub drawn: usize,
    /// Particles behind the camera or entirely outside the image.
    pub culled: usize,
}

/// What one frame shows: the particles, the springs between them and the scenery.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// x, y, z (m) per particle: 3N numbers.
    pub positions: &'a [f64],
    /// Radius (m) per particle: N numbers.
    pub radius: &'a [f64],
    /// Colour (RGB8) per particle: 3N bytes.
    pub colors: &'a [u8],
    /// Pairs of particle indices, each drawn as a line ([`render_frame`](super::render_frame)).
    pub springs: &'a [[usize; 2]],
    /// The colliders drawn with the particles.
    pub scenery: &'a Scenery,
    /// Each particle's recent path (its trail), oldest point first: `trail_len` points x, y,
    /// z (m) per particle, N × `trail_len` × 3 numbers, or none (empty). A non-finite point
    /// breaks the path there (the particle was not alive).
    pub trails: &'a [f64],
    /// Points per trail (≥ 2 when there are trails).
    pub trail_len: usize,
    /// Points x, y, z (m) marked with a disc (an attractor's centre): 3M numbers.
    pub markers: &'a [f64],
}

/// No colliders: what [`Frame::particles`] draws besides the particles.
static NO_SCENERY: Scenery = Scenery {
    colliders: Vec::new(),
    extent: None,
};

impl<'a> Frame<'a> {
    /// The particles alone: no springs, no scenery.
    pub fn particles(positions: &'a [f64], radius: &'a [f64], colors: &'a [u8]) -> Self {
        Frame {
            positions,
            radius,
            colors,
            springs: &[],
            scenery: &NO_SCENERY,
            trails: &[],
            trail_len: 0,
            markers: &[],
        }
    }
}
