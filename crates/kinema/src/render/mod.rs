//! Off-screen rendering: particles → RGB8 frames (2D antialiased discs, 3D shaded spheres),
//! with optional scenery: the static colliders (planes, boxes, sphere obstacles, triangle
//! meshes; [`Scenery`]).
//!
//! The stages of a frame, in order:
//!
//! 1. project   positions (m) and radii (m) → pixel centres, pixel radii, depths ([`Camera`]);
//!    particles behind the camera are dropped. The scenery is projected too ([`paint`]):
//!    planes, boxes and 2D obstacles become a short list of background primitives (convex
//!    fills and antialiased lines in pixels, cut at the camera's near distance first),
//!    3D sphere obstacles become sprites like the particles, numbered after them, and mesh
//!    colliders translucent facets and edge lines, each with its depth. Springs
//!    (pairs of particles, [`render_frame`]) become antialiased lines from rim to rim, cut at
//!    the near distance, numbered after the obstacles; trails (each particle's recent path)
//!    become antialiased segments faded by age, and markers (attractors) discs.
//! 2. order     3D: far to near (painter's algorithm, ties broken by index), sphere obstacles,
//!    springs (at their midpoints' depth) and mesh facets (at their centroids') included; 2D: springs first, then the particles
//!    in index order — later particles are drawn over earlier ones.
//! 3. bin       each sprite or line is listed, in draw order, in every horizontal band of
//!    [`BAND_ROWS`] rows it overlaps. (The few background primitives are not binned: every
//!    band walks all of them and draws the rows it owns.)
//! 4. raster    the bands are filled in parallel (rayon); each band clears to the background,
//!    draws the background primitives in order, then its list in order. A band's pixels
//!    depend only on its lists, never on which thread ran it or when, so frames are
//!    byte-identical for every thread count.
//!
//! Colours come per particle as RGB8 ([`colormap`] turns values or ids into them), and
//! [`text::draw_text`] stamps a label (e.g. the time) onto a finished frame; [`yuv`] converts
//! frames for the H.264 encoder.
//!
//! The modules, each using only those listed before it (besides the camera): `camera`;
//! `pixels` (sprites and the row painters); `clip` (the near cut and the guard rectangle);
//! `prim` (pixel-space fills, lines and mesh facets); [`extent`] (the region infinite
//! scenery is drawn in); `frame3` (what the 3D scenery painters share: a frame's
//! constants, the surfaces' opacity, the floor rule); [`mesh_paint`] (mesh colliders →
//! facets and lines); `shadows` (the particles' contact shadows on the 3D floors); [`paint`]
//! (colliders → primitives and sprites, meshes through `mesh_paint`, shadows through
//! `shadows`); `frame` (what a frame shows, the render parameters and stats); `lines`
//! (springs and trails → lines); `raster` (the four stages).

mod camera;
mod clip;
pub mod colormap;
pub mod extent;
mod frame;
mod frame3;
mod lines;
pub mod mesh_paint;
pub mod paint;
mod pixels;
mod prim;
mod raster;
mod shadows;
pub mod text;
pub mod yuv;

pub use camera::{Camera, Projected, FRAME_MARGIN};
pub use colormap::{categorical, Colormap, COLORMAP_NAMES};
pub use extent::{collider_boxes, scene_extent, Region};
pub use frame::{Frame, RenderParams, RenderStats, Shading, MARKER_COLOR, MARKER_RIM_COLOR, MARKER_RIM_PX};
pub use paint::Scenery;
pub use raster::{render, render_frame, render_scene, BAND_ROWS};
