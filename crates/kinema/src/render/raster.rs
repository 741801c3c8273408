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
    /// Pairs of particle indices, each drawn as a line ([`render_frame`]).
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
///
/// Trails ([`Frame::trails`]) are polylines [`RenderParams::trail_width_px`] wide in their
/// particle's colour, faded towards the background with age: segment k of S (0 the oldest)
/// mixes (k + 1)/S of the colour into the background, so the newest segment has the
/// particle's colour and the path fades out behind it (opaque, so no joint is drawn twice
/// over); like a spring, a trail stops at the rim of its particle's disc. Markers ([`Frame::markers`]) are discs of [`MARKER_COLOR`] with a dark rim,
/// [`RenderParams::marker_radius_px`] whatever their distance. In 2D the order is trails,
/// markers, springs, particles; in 3D trail segments (at their midpoints' depth) and markers
/// are ordered far to near with the rest.
pub fn render_frame(camera: &Camera, frame: &Frame, params: &RenderParams, image: &mut [u8]) -> Result<RenderStats, Error> {
    let Frame {
        positions,
        radius,
        colors,
        springs,
        scenery,
        trails,
        trail_len,
        markers,
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
    for (name, v) in [
        ("trail_width_px", params.trail_width_px),
        ("marker_radius_px", params.marker_radius_px),
    ] {
        if !(v >= 1.0 && v <= 1000.0) {
            return Err(invalid(name, v, "a size in pixels in [1, 1000]"));
        }
    }
    if !trails.is_empty() && (trail_len < 2 || trails.len() != n * trail_len * 3) {
        return Err(invalid(
            "trails",
            format!("{} numbers of {trail_len} points per trail", trails.len()),
            &format!("N × trail_len × 3 = {n} × trail_len × 3 numbers, trail_len >= 2"),
        ));
    }
    if markers.len() % 3 != 0 || !markers.iter().all(|c| c.is_finite()) {
        return Err(invalid(
            "markers",
            format!("{} numbers", markers.len()),
            "finite x, y, z per marker",
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
            light: light.l.map(f64::from),
        };
        paint(&scenery.colliders, extent, &view, (positions, radius))
    };
    let obstacles = painted.spheres.len();
    for (k, (depth, s)) in painted.spheres.into_iter().enumerate() {
        items.push((depth, n + k, Item::Sprite(s)));
    }
    let background = painted.background;
    let mesh_prims = painted.ordered;

    // 1c. springs: lines numbered after the obstacles (see `render_frame` for their place),
    //     then the markers and the trails' segments.
    let mut under: Vec<Item> = Vec::new();
    let mut more: Vec<(f64, Item)> = Vec::new();
    for (depth, line) in trail_lines(camera, &projector, frame, params) {
        more.push((depth, Item::Prim(line)));
    }
    for p in markers.chunks_exact(3) {
        let Some(q) = projector.project([p[0], p[1], p[2]], 0.0) else {
            continue;
        };
        let r = params.marker_radius_px;
        for (rr, c) in [(r + MARKER_RIM_PX, MARKER_RIM_COLOR), (r, MARKER_COLOR)] {
            if let Some(s) = Sprite::new(q.x, q.y, rr, c, w, h) {
                more.push((q.depth, Item::Sprite(s)));
            }
        }
    }
    let lines = spring_lines(camera, &projector, frame, params);
    if spheres {
        let first = n + obstacles + lines.len();
        for (k, (depth, line)) in lines.into_iter().enumerate() {
            items.push((depth, n + obstacles + k, Item::Prim(line)));
        }
        let first_mesh = first + more.len();
        for (k, (depth, it)) in more.into_iter().enumerate() {
            items.push((depth, first + k, it));
        }
        for (k, (depth, p)) in mesh_prims.into_iter().enumerate() {
            items.push((depth, first_mesh + k, Item::Prim(p)));
        }
    } else {
        // 2D: trails and markers, then the springs, before every particle, in their order.
        under.extend(more.into_iter().map(|(_, it)| it));
        under.extend(lines.into_iter().map(|(_, l)| Item::Prim(l)));
        let particles = std::mem::take(&mut items);
        items = under.into_iter().enumerate().map(|(k, it)| (0.0, k, it)).collect();
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
                    Item::Prim(line) => line.draw_row(row, j),
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

/// What a band draws after its background: a particle or obstacle, or a primitive (a
/// spring's or trail's line, a mesh's facet or edge).
enum Item {
    Sprite(Sprite),
    Prim(Prim),
}

impl Item {
    fn rows(&self) -> (u32, u32) {
        match self {
            Item::Sprite(s) => (s.row0, s.row1),
            Item::Prim(p) => p.rows(),
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
        let Some((qi, qj)) = segment_in_front(camera, ci, cj, zn) else {
            continue;
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

/// The part of the segment ab (camera coordinates) that can be projected: in 3D cut at the
/// near distance `zn` (none when wholly behind it), in 2D all of it.
fn segment_in_front(camera: &Camera, a: [f64; 3], b: [f64; 3], zn: f64) -> Option<([f64; 3], [f64; 3])> {
    if camera.is_3d() {
        clip_segment_near(a, b, zn)
    } else {
        Some((a, b))
    }
}

/// The trails as pixel-space segments with the depth of their midpoints (0 in 2D), each cut
/// at the near distance (3D), coloured by age (see [`render_frame`]).
fn trail_lines(camera: &Camera, projector: &Projector, frame: &Frame, params: &RenderParams) -> Vec<(f64, Prim)> {
    let (trails, len, colors) = (frame.trails, frame.trail_len, frame.colors);
    let mut out = Vec::new();
    if trails.is_empty() {
        return out;
    }
    let (w, h) = (params.width as f64, params.height as f64);
    let zn = near_depth(camera, projector);
    let bg = params.background.map(|c| c as f64);
    let segments = (len - 1) as f64;
    for (i, path) in trails.chunks_exact(3 * len).enumerate() {
        let c = [colors[3 * i], colors[3 * i + 1], colors[3 * i + 2]].map(|c| c as f64);
        // The particle's disc on screen: the trail stops at its rim, as a spring does.
        let p = &frame.positions[3 * i..3 * i + 3];
        let disc = projector
            .project([p[0], p[1], p[2]], frame.radius[i])
            .map(|q| ([q.x, q.y], q.r.max(params.min_radius_px)));
        for k in 0..len - 1 {
            let (a, b) = (&path[3 * k..3 * k + 3], &path[3 * k + 3..3 * k + 6]);
            if !a.iter().chain(b).all(|v| v.is_finite()) || a == b {
                continue;
            }
            let (ca, cb) = (
                projector.camera_coords([a[0], a[1], a[2]]),
                projector.camera_coords([b[0], b[1], b[2]]),
            );
            let Some((qa, qb)) = segment_in_front(camera, ca, cb, zn) else {
                continue;
            };
            let f = (k + 1) as f64 / segments;
            let colour: [u8; 3] = std::array::from_fn(|j| (bg[j] + f * (c[j] - bg[j])).round() as u8);
            let (pa, pb) = (projector.camera_to_pixel(qa), projector.camera_to_pixel(qb));
            let depth = if camera.is_3d() { 0.5 * (qa[2] + qb[2]) } else { 0.0 };
            for (sa, sb) in outside_disc(pa, pb, disc) {
                let at = |s: f64| [pa[0] + s * (pb[0] - pa[0]), pa[1] + s * (pb[1] - pa[1])];
                if let Some(line) = line(at(sa), at(sb), params.trail_width_px, colour, 1.0, w, h) {
                    out.push((depth, line));
                }
            }
        }
    }
    out
}

/// The parts [s0, s1] ⊂ [0, 1] of the pixel segment a + s·(b − a) outside the disc (centre,
/// radius) (all of it without a disc): none, one or two.
fn outside_disc(a: [f64; 2], b: [f64; 2], disc: Option<([f64; 2], f64)>) -> Vec<(f64, f64)> {
    let Some((c, r)) = disc else {
        return vec![(0.0, 1.0)];
    };
    // |a − c + s·d|² = r²: s² |d|² + 2 s (a − c)·d + |a − c|² − r² = 0.
    let d = [b[0] - a[0], b[1] - a[1]];
    let e = [a[0] - c[0], a[1] - c[1]];
    let (qa, qb, qc) = (
        d[0] * d[0] + d[1] * d[1],
        e[0] * d[0] + e[1] * d[1],
        e[0] * e[0] + e[1] * e[1] - r * r,
    );
    let disc2 = qb * qb - qa * qc;
    if !(qa > 0.0 && disc2 > 0.0) {
        // A point, or a line that misses the circle: all outside or all inside, as a is.
        return if qc > 0.0 { vec![(0.0, 1.0)] } else { vec![] };
    }
    let root = disc2.sqrt();
    let (s0, s1) = ((-qb - root) / qa, (-qb + root) / qa);
    [(0.0, s0.min(1.0)), (s1.max(0.0), 1.0)]
        .into_iter()
        .filter(|(x, y)| y > x)
        .collect()
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
