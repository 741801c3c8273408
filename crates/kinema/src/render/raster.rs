//! Rasterizer: projected particles → antialiased discs or shaded spheres in an RGB8 image.

use rayon::prelude::*;

use super::camera::{invalid, Camera, Projector};
use super::clip::{clip_segment_near, near_depth};
use super::extent::{frame_extent, Region};
use super::paint::{paint, Painted, Scenery, View, LINE_COLOR};
use super::pixels::{disc_row, fill_rgb, sphere_row, Light, Sprite};
use super::prim::{line, Prim};
use crate::particles::check_per_particle;
use crate::Error;

/// Rows per band: the unit of parallel work (720 rows give 45 bands).
pub const BAND_ROWS: usize = 16;

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
    /// Width of the lines drawn for springs ([`render_frame`]), pixels, in [1, 1000].
    /// Default 1.5.
    pub spring_width_px: f64,
}

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
    /// Pairs of particle indices, each drawn as a line ([`render_frame`]).
    pub springs: &'a [[usize; 2]],
    /// The colliders drawn with the particles.
    pub scenery: &'a Scenery,
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
        }
    }
}

/// Renders the particles into `image` (RGB8, `width × height × 3` bytes, rows top first).
///
/// `positions` holds x, y, z (m) per particle (3N numbers), `radius` one radius (m) per
/// particle, `colors` RGB8 per particle (3N bytes). The [`Camera::Orthographic`] camera draws
/// flat antialiased discs, [`Camera::Perspective`] shaded spheres, far to near. Errors name
/// the bad parameter (lengths, non-finite positions, negative radii, camera, sizes).
pub fn render(
    camera: &Camera,
    positions: &[f64],
    radius: &[f64],
    colors: &[u8],
    params: &RenderParams,
    image: &mut [u8],
) -> Result<RenderStats, Error> {
    render_frame(camera, &Frame::particles(positions, radius, colors), params, image)
}

/// [`render`] with scenery: the colliders of [`Scenery`] drawn with the particles (see
/// [`super::paint`] for how each looks). The stats count particles only. Errors also name a
/// bad extent.
pub fn render_scene(
    camera: &Camera,
    positions: &[f64],
    radius: &[f64],
    colors: &[u8],
    scenery: &Scenery,
    params: &RenderParams,
    image: &mut [u8],
) -> Result<RenderStats, Error> {
    let frame = Frame {
        scenery,
        ..Frame::particles(positions, radius, colors)
    };
    render_frame(camera, &frame, params, image)
}

/// Renders a [`Frame`]: its particles (as [`render`] does), its scenery (as [`render_scene`]
/// does) and its springs. `springs` holds pairs of particle indices (into `positions`), each
/// drawn as an antialiased line of [`LINE_COLOR`],
/// [`RenderParams::spring_width_px`] wide, from the rim of one particle's disc to the rim of
/// the other's (nothing when the two discs touch on screen). A pair of one particle twice
/// draws nothing; an index ≥ N is an error (`springs[k]`).
///
/// Where the lines go in the drawing order: in 2D, after the background and before every
/// particle, so that a particle always covers the strings under it. In 3D they are ordered
/// with the particles and sphere obstacles, far to near, at the depth of their midpoint: a
/// cloth's springs in front of a sphere obstacle are drawn over it and those behind it are
/// hidden, which lines drawn under everything (like box edges) would get wrong. Since a line
/// stops at its particles' rims, it never paints over its own ends, whichever comes first.
pub fn render_frame(camera: &Camera, frame: &Frame, params: &RenderParams, image: &mut [u8]) -> Result<RenderStats, Error> {
    let Frame {
        positions,
        radius,
        colors,
        springs,
        scenery,
    } = *frame;
    let (w, h) = (params.width, params.height);
    let projector = camera.projector(w, h)?;
    let n = radius.len();
    check_per_particle("positions", positions.len(), 3, n, "radii")?;
    check_per_particle("colors", colors.len(), 3, n, "radii")?;
    if image.len() != w * h * 3 {
        return Err(invalid(
            "image",
            format!("{} bytes", image.len()),
            &format!("width × height × 3 = {}", w * h * 3),
        ));
    }
    if !(params.min_radius_px >= 0.0 && params.min_radius_px < 1e6) {
        return Err(invalid(
            "min_radius_px",
            params.min_radius_px,
            "a number of pixels in [0, 1e6)",
        ));
    }
    if !(params.spring_width_px >= 1.0 && params.spring_width_px <= 1000.0) {
        return Err(invalid(
            "spring_width_px",
            params.spring_width_px,
            "a width in pixels in [1, 1000]",
        ));
    }
    if let Some((k, pair)) = springs.iter().enumerate().find(|(_, p)| p[0] >= n || p[1] >= n) {
        return Err(invalid(
            &format!("springs[{k}]"),
            format!("{pair:?}"),
            &format!("two particle indices < N = {n}"),
        ));
    }
    let light = check_shading(&params.shading)?;
    scenery.validate()?;

    // 1. project
    let mut culled = 0;
    let mut items: Vec<(f64, usize, Item)> = Vec::with_capacity(n + springs.len());
    for i in 0..n {
        let p = [positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]];
        if !p.iter().all(|c| c.is_finite()) {
            return Err(invalid(&format!("positions[{i}]"), format!("{p:?}"), "finite coordinates"));
        }
        if !(radius[i] >= 0.0 && radius[i].is_finite()) {
            return Err(invalid(&format!("radius[{i}]"), radius[i], "a finite radius >= 0"));
        }
        let Some(q) = projector.project(p, radius[i]) else {
            culled += 1;
            continue;
        };
        let r = q.r.max(params.min_radius_px);
        let c = [colors[3 * i], colors[3 * i + 1], colors[3 * i + 2]];
        let Some(sprite) = Sprite::new(q.x, q.y, r, c, w, h) else {
            culled += 1;
            continue;
        };
        items.push((q.depth, i, Item::Sprite(sprite)));
    }
    let drawn = items.len();

    // 1b. project the scenery: planes, boxes (and 2D obstacles) become background primitives,
    //     3D sphere obstacles join the particles, numbered after them.
    let spheres = camera.is_3d();
    let painted = if scenery.colliders.is_empty() {
        Painted::default()
    } else {
        let extent = scenery
            .extent
            .unwrap_or_else(|| frame_extent(&scenery.colliders, bounding_box(positions, radius), camera, w, h));
        let view = View {
            camera,
            projector: &projector,
            width: w,
            height: h,
            min_radius_px: params.min_radius_px,
        };
        paint(&scenery.colliders, extent, &view)
    };
    let obstacles = painted.spheres.len();
    for (k, (depth, s)) in painted.spheres.into_iter().enumerate() {
        items.push((depth, n + k, Item::Sprite(s)));
    }
    let background = painted.background;

    // 1c. springs: lines numbered after the obstacles (see `render_frame` for their place).
    let lines = spring_lines(camera, &projector, frame, params);
    if spheres {
        for (k, (depth, line)) in lines.into_iter().enumerate() {
            items.push((depth, n + obstacles + k, Item::Line(line)));
        }
    } else {
        // 2D: before every particle, in their own order.
        let particles = std::mem::take(&mut items);
        items = lines
            .into_iter()
            .enumerate()
            .map(|(k, (d, l))| (d, k, Item::Line(l)))
            .collect();
        items.extend(particles);
    }

    // 2. order: far to near; the index breaks ties so the order is total and repeatable.
    //    A sphere obstacle sorts by its centre's depth like a particle: cloth on its near
    //    side is drawn over it, particles behind it under it.
    if spheres {
        items.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    }

    // 3. bin: counting sort of (band, draw position) keeps the draw order inside each band.
    let bands = h.div_ceil(BAND_ROWS);
    let band_of = |row: u32| row as usize / BAND_ROWS;
    let mut start = vec![0usize; bands + 1];
    for (_, _, it) in &items {
        let (r0, r1) = it.rows();
        for b in band_of(r0)..=band_of(r1 - 1) {
            start[b + 1] += 1;
        }
    }
    for b in 0..bands {
        start[b + 1] += start[b];
    }
    let mut fill = start.clone();
    let mut binned = vec![0u32; start[bands]];
    for (k, (_, _, it)) in items.iter().enumerate() {
        let (r0, r1) = it.rows();
        for b in band_of(r0)..=band_of(r1 - 1) {
            binned[fill[b]] = k as u32;
            fill[b] += 1;
        }
    }

    // 4. raster, one band per task.
    let bg = params.background;
    let row_bytes = 3 * w;
    image.par_chunks_mut(BAND_ROWS * row_bytes).enumerate().for_each(|(b, band)| {
        fill_rgb(band, bg);
        let band_row0 = (b * BAND_ROWS) as u32;
        let band_row1 = band_row0 + (band.len() / row_bytes) as u32;
        // The background layer: every band walks the same short list in the same order.
        for prim in &background {
            let (r0, r1) = prim.rows();
            for j in r0.max(band_row0)..r1.min(band_row1) {
                let off = (j - band_row0) as usize * row_bytes;
                prim.draw_row(&mut band[off..off + row_bytes], j);
            }
        }
        for &k in &binned[start[b]..start[b + 1]] {
            let it = &items[k as usize].2;
            let (r0, r1) = it.rows();
            for j in r0.max(band_row0)..r1.min(band_row1) {
                let off = (j - band_row0) as usize * row_bytes;
                let row = &mut band[off..off + row_bytes];
                match it {
                    Item::Sprite(s) if spheres => sphere_row(row, s, j, &light),
                    Item::Sprite(s) => disc_row(row, s, j),
                    Item::Line(line) => line.draw_row(row, j),
                }
            }
        }
    });

    Ok(RenderStats { drawn, culled })
}

/// The particles' bounding box, radii included (positions are checked finite); `None`
/// without particles.
fn bounding_box(positions: &[f64], radius: &[f64]) -> Option<Region> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (p, &r) in positions.chunks_exact(3).zip(radius) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k] - r);
            hi[k] = hi[k].max(p[k] + r);
        }
    }
    (!radius.is_empty()).then_some((lo, hi))
}

/// What a band draws after its background: a particle or obstacle, or a spring's line.
enum Item {
    Sprite(Sprite),
    Line(Prim),
}

impl Item {
    fn rows(&self) -> (u32, u32) {
        match self {
            Item::Sprite(s) => (s.row0, s.row1),
            Item::Line(p) => p.rows(),
        }
    }
}

/// The springs as pixel-space lines with the depth of their midpoints (0 in 2D): each cut at
/// the near distance (3D), then shortened at an end by the drawn radius of the particle
/// there (an end cut off by the near distance has no particle in view), so that it runs
/// from rim to rim; none where the rims meet.
fn spring_lines(camera: &Camera, projector: &Projector, frame: &Frame, params: &RenderParams) -> Vec<(f64, Prim)> {
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
        let (qi, qj) = if camera.is_3d() {
            match clip_segment_near(ci, cj, zn) {
                Some(pair) => pair,
                None => continue,
            }
        } else {
            (ci, cj)
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

fn check_shading(s: &Shading) -> Result<Light, Error> {
    let n = s.light_dir.iter().map(|c| c * c).sum::<f64>().sqrt();
    if !(n > 0.0 && n.is_finite()) {
        return Err(invalid(
            "light_dir",
            format!("{:?}", s.light_dir),
            "a finite non-zero direction",
        ));
    }
    if !(0.0..=1.0).contains(&s.ambient) {
        return Err(invalid("ambient", s.ambient, "a fraction in [0, 1]"));
    }
    if !(0.0..=1.0).contains(&s.specular) {
        return Err(invalid("specular", s.specular, "a fraction in [0, 1]"));
    }
    if !(1..=1024).contains(&s.shininess) {
        return Err(invalid("shininess", s.shininess, "an exponent in 1 ..= 1024"));
    }
    let l = s.light_dir.map(|c| c / n);
    // Blinn–Phong half vector between the light and the viewer, who looks along −z, i.e.
    // sees along +z from the surface: h = (l + ẑ) / |l + ẑ|.
    let hv = [l[0], l[1], l[2] + 1.0];
    let hn = hv.iter().map(|c| c * c).sum::<f64>().sqrt().max(1e-12);
    Ok(Light {
        l: l.map(|c| c as f32),
        h: hv.map(|c| (c / hn) as f32),
        ambient: s.ambient as f32,
        specular: s.specular as f32,
        shininess: s.shininess,
    })
}
