//! Rasterizer: projected particles → antialiased discs or shaded spheres in an RGB8 image.

use rayon::prelude::*;

use super::camera::{invalid, Camera, Projector};
use super::scenery::{self, Prim, Scenery, LINE_COLOR};
use crate::vec3::{norm, sub};
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

/// A particle (or a sphere obstacle) ready to rasterize, in pixels; f32 is ample for image
/// coordinates.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sprite {
    pub(crate) x: f32,
    pub(crate) y: f32,
    pub(crate) r: f32,
    pub(crate) color: [f32; 3],
    /// Rows [row0, row1) that the antialiased outline can touch.
    pub(crate) row0: u32,
    pub(crate) row1: u32,
}

impl Sprite {
    /// The disc of centre (x, y) and radius r (pixels) in a `w × h` image; `None` when it
    /// touches no pixel (or r is not finite).
    #[inline]
    pub(crate) fn new(x: f64, y: f64, r: f64, color: [u8; 3], w: usize, h: usize) -> Option<Sprite> {
        // The antialiased outline reaches half a pixel beyond the radius (see `coverage`).
        let reach = r + 0.5;
        if x + reach < 0.0 || x - reach > w as f64 || y + reach < 0.0 || y - reach > h as f64 || !r.is_finite() {
            return None;
        }
        // Pixel row j is drawn when its centre j + 0.5 is within the reach of the centre.
        let row0 = (y - reach - 0.5).ceil().max(0.0) as u32;
        let row1 = ((y + reach - 0.5).floor() + 1.0).clamp(0.0, h as f64) as u32;
        if row0 >= row1 {
            return None;
        }
        Some(Sprite {
            x: x as f32,
            y: y as f32,
            // A sphere filling the screen a million times over draws like one filling it once.
            r: r.min(1e6) as f32,
            color: color.map(|c| c as f32),
            row0,
            row1,
        })
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
    render_scene(camera, positions, radius, colors, &Scenery::default(), params, image)
}

/// [`render`] with scenery: the colliders of [`Scenery`] drawn with the particles (see
/// [`super::scenery`] for how each looks). The stats count particles only. Errors also name
/// a bad scenery item (`scenery[2].radius`) or extent.
pub fn render_scene(
    camera: &Camera,
    positions: &[f64],
    radius: &[f64],
    colors: &[u8],
    scenery: &Scenery,
    params: &RenderParams,
    image: &mut [u8],
) -> Result<RenderStats, Error> {
    render_frame(camera, positions, radius, colors, &[], scenery, params, image)
}

/// [`render_scene`] with springs: `springs` holds pairs of particle indices (into
/// `positions`), each drawn as an antialiased line of [`LINE_COLOR`],
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
#[allow(clippy::too_many_arguments)]
pub fn render_frame(
    camera: &Camera,
    positions: &[f64],
    radius: &[f64],
    colors: &[u8],
    springs: &[[usize; 2]],
    scenery: &Scenery,
    params: &RenderParams,
    image: &mut [u8],
) -> Result<RenderStats, Error> {
    let (w, h) = (params.width, params.height);
    let projector = camera.projector(w, h)?;
    let n = radius.len();
    if positions.len() != 3 * n {
        return Err(invalid(
            "positions",
            format!("{} numbers", positions.len()),
            &format!("3 per particle (N = {n} from radius)"),
        ));
    }
    if colors.len() != 3 * n {
        return Err(invalid(
            "colors",
            format!("{} bytes", colors.len()),
            &format!("3 per particle (N = {n} from radius)"),
        ));
    }
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
    let built = if scenery.items.is_empty() {
        scenery::Built::default()
    } else {
        let frame = scenery::Frame {
            camera,
            projector: &projector,
            width: w,
            height: h,
            min_radius_px: params.min_radius_px,
            particles: bounding_box(positions, radius),
        };
        scenery::build(scenery, &frame)
    };
    let obstacles = built.spheres.len();
    for (k, (depth, s)) in built.spheres.into_iter().enumerate() {
        items.push((depth, n + k, Item::Sprite(s)));
    }
    let background = built.background;

    // 1c. springs: lines numbered after the obstacles (see `render_frame` for their place).
    let lines = spring_lines(camera, &projector, positions, radius, springs, params);
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
fn bounding_box(positions: &[f64], radius: &[f64]) -> Option<([f64; 3], [f64; 3])> {
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
fn spring_lines(
    camera: &Camera,
    projector: &Projector,
    positions: &[f64],
    radius: &[f64],
    springs: &[[usize; 2]],
    params: &RenderParams,
) -> Vec<(f64, Prim)> {
    let (w, h) = (params.width as f64, params.height as f64);
    // The same cut as the scenery's (`scenery::build`): pixel coordinates stay bounded.
    let zn = match (camera, projector) {
        (Camera::Perspective { eye, target, .. }, Projector::Persp { near, .. }) => near.max(1e-4 * norm(sub(*target, *eye))),
        _ => f64::NEG_INFINITY,
    };
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
            match scenery::clip_segment_near(ci, cj, zn) {
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
        if let Some(line) = scenery::line(a, b, params.spring_width_px, LINE_COLOR, 1.0, w, h) {
            out.push((depth, line));
        }
    }
    out
}

/// Lighting constants in f32, the light and half vectors normalised.
struct Light {
    l: [f32; 3],
    h: [f32; 3],
    ambient: f32,
    specular: f32,
    shininess: i32,
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

/// Pixel columns [i0, i1) of row `j` whose centres are within the antialiased reach of `s`,
/// with dy, the centre's vertical offset.
#[inline]
fn span(row_len: usize, s: &Sprite, j: u32) -> Option<(usize, usize, f32)> {
    let dy = j as f32 + 0.5 - s.y;
    let reach = s.r + 0.5;
    let q = reach * reach - dy * dy;
    if q <= 0.0 {
        return None;
    }
    let half = q.sqrt();
    let width = (row_len / 3) as f32;
    let i0 = (s.x - half - 0.5).ceil().clamp(0.0, width) as usize;
    let i1 = ((s.x + half - 0.5).floor() + 1.0).clamp(0.0, width) as usize;
    (i0 < i1).then_some((i0, i1, dy))
}

/// Coverage of a pixel by a disc of radius r whose centre is at distance d from the pixel
/// centre. The signed distance from the pixel centre to the edge is r − d (positive inside);
/// a pixel is a unit square, so as the edge sweeps across it the covered fraction goes from
/// 0 to 1 over a one-pixel-wide band of that distance: coverage ≈ clamp(r − d + ½, 0, 1)
/// (exact for a straight edge parallel to a pixel side; the edge's curvature, 1/r, is small).
#[inline]
fn coverage(r: f32, d2: f32) -> f32 {
    (r + 0.5 - d2.sqrt()).clamp(0.0, 1.0)
}

/// Sets every pixel of `dst` (RGB8) to `c`: one pixel, then copies of what is done, doubling
/// (a few memcpy calls instead of one small copy per pixel).
#[inline]
pub(crate) fn fill_rgb(dst: &mut [u8], c: [u8; 3]) {
    if dst.len() < 3 {
        return;
    }
    dst[..3].copy_from_slice(&c);
    let mut done = 3;
    while done < dst.len() {
        let n = done.min(dst.len() - done);
        dst.copy_within(0..n, done);
        done += n;
    }
}

/// `dst ← dst + a·(src − dst)`, rounded: the "over" operator with coverage as alpha.
#[inline]
pub(crate) fn blend(dst: &mut [u8], src: [f32; 3], a: f32) {
    for k in 0..3 {
        let d = dst[k] as f32;
        dst[k] = (d + a * (src[k] - d) + 0.5) as u8;
    }
}

/// One row of a flat 2D disc.
#[inline]
pub(crate) fn disc_row(row: &mut [u8], s: &Sprite, j: u32) {
    let Some((i0, i1, dy)) = span(row.len(), s, j) else { return };
    // Pixels with d ≤ r − ½ are fully covered and need neither sqrt nor blending.
    let inner = (s.r - 0.5).max(0.0);
    let inner2 = inner * inner;
    let full = s.color.map(|c| c as u8);
    for i in i0..i1 {
        let dx = i as f32 + 0.5 - s.x;
        let d2 = dx * dx + dy * dy;
        let px = &mut row[3 * i..3 * i + 3];
        if d2 <= inner2 {
            px.copy_from_slice(&full);
        } else {
            let a = coverage(s.r, d2);
            if a > 0.0 {
                blend(px, s.color, a);
            }
        }
    }
}

/// One row of a shaded sphere.
///
/// The sphere seen from far away projects to a disc; at the pixel offset (dx, dy) from the
/// centre, in units of the radius u = dx/r, v = −dy/r (y up), the visible surface point has
/// the unit normal n = (u, v, √(1 − u² − v²)) in camera coordinates. Its colour is
/// base · (ambient + (1 − ambient)·max(n·l, 0)) + 255 · specular · max(n·h, 0)^shininess
/// (Lambert diffuse plus a Blinn–Phong highlight), clamped to 255.
#[inline]
fn sphere_row(row: &mut [u8], s: &Sprite, j: u32, light: &Light) {
    let Some((i0, i1, dy)) = span(row.len(), s, j) else { return };
    let inner = (s.r - 0.5).max(0.0);
    let inner2 = inner * inner;
    let inv_r = 1.0 / s.r;
    let v = -dy * inv_r;
    let kd = 1.0 - light.ambient;
    for i in i0..i1 {
        let dx = i as f32 + 0.5 - s.x;
        let d2 = dx * dx + dy * dy;
        let a = if d2 <= inner2 { 1.0 } else { coverage(s.r, d2) };
        if a <= 0.0 {
            continue;
        }
        let u = dx * inv_r;
        // On the antialiased rim u² + v² slightly exceeds 1: the normal lies in the image plane.
        let w = (1.0 - u * u - v * v).max(0.0).sqrt();
        let ndl = (u * light.l[0] + v * light.l[1] + w * light.l[2]).max(0.0);
        let ndh = (u * light.h[0] + v * light.h[1] + w * light.h[2]).max(0.0);
        let shade = light.ambient + kd * ndl;
        let spec = 255.0 * light.specular * powi(ndh, light.shininess);
        let c = [
            (s.color[0] * shade + spec).min(255.0),
            (s.color[1] * shade + spec).min(255.0),
            (s.color[2] * shade + spec).min(255.0),
        ];
        let px = &mut row[3 * i..3 * i + 3];
        if a >= 1.0 {
            for k in 0..3 {
                px[k] = (c[k] + 0.5) as u8;
            }
        } else {
            blend(px, c, a);
        }
    }
}

/// x^n by squaring (n ≥ 1), the same on every platform unlike a libm `powf`.
#[inline]
fn powi(mut x: f32, mut n: i32) -> f32 {
    let mut acc = 1.0;
    while n > 0 {
        if n & 1 == 1 {
            acc *= x;
        }
        x *= x;
        n >>= 1;
    }
    acc
}
