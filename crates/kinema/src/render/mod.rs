//! Off-screen rendering: particles → RGB8 frames (2D antialiased discs, 3D shaded spheres).
//!
//! The stages of a frame, in order:
//!
//! 1. project   positions (m) and radii (m) → pixel centres, pixel radii, depths ([`Camera`]);
//!    particles behind the camera are dropped.
//! 2. order     3D: far to near (painter's algorithm, ties broken by index); 2D: index order —
//!    later particles are drawn over earlier ones.
//! 3. bin       each particle is listed, in draw order, in every horizontal band of
//!    [`BAND_ROWS`] rows it overlaps.
//! 4. raster    the bands are filled in parallel (rayon); each band clears to the background
//!    and draws its list in order. A band's pixels depend only on its list, never on which
//!    thread ran it or when, so frames are byte-identical for every thread count.
//!
//! Colours come per particle as RGB8 ([`colormap`] turns values or ids into them), and
//! [`text::draw_text`] stamps a label (e.g. the time) onto a finished frame; [`yuv`] converts
//! frames for the H.264 encoder.

mod camera;
pub mod colormap;
mod raster;
pub mod text;
pub mod yuv;

pub use camera::{Camera, Projected};
pub use colormap::{categorical, Colormap, COLORMAP_NAMES};
pub use raster::{render, RenderParams, RenderStats, Shading, BAND_ROWS};
