//! Rasterizer: projected particles → antialiased discs or shaded spheres in an RGB8 image.

use rayon::prelude::*;

use super::camera::{invalid, Camera, Projector};
use super::extent::{frame_extent, Region};
use super::frame::{Frame, RenderParams, RenderStats, Shading, MARKER_COLOR, MARKER_RIM_COLOR, MARKER_RIM_PX};
use super::lines::{spring_lines, trail_lines};
use super::paint::{paint, Painted, Scenery, View};
use super::pixels::{disc_row, fill_rgb, sphere_row, Light, Sprite};
use super::prim::Prim;
use crate::particles::check_per_particle;
use crate::Error;

/// Rows per band: the unit of parallel work (720 rows give 45 bands).
pub const BAND_ROWS: usize = 16;

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
/// drawn as an antialiased line of [`LINE_COLOR`](super::paint::LINE_COLOR),
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
    let (w, h) = (params.width, params.height);
    let projector = camera.projector(w, h)?;
    let light = check_frame(frame, params, image.len())?;

    // 1. project
    let (mut items, culled) = project_particles(&projector, frame, params)?;
    let drawn = items.len();

    // 1b. project the scenery: planes, boxes (and 2D obstacles) become background primitives,
    //     3D sphere obstacles join the particles, numbered after them.
    let (background, obstacles, mesh_prims) = project_scenery(camera, &projector, frame, params, &light, &mut items);

    // 1c. springs: lines numbered after the obstacles (see `render_frame` for their place),
    //     then the markers and the trails' segments.
    let spheres = camera.is_3d();
    add_lines(camera, &projector, frame, params, (obstacles, mesh_prims), &mut items);

    // 2. order: far to near; the index breaks ties so the order is total and repeatable.
    //    A sphere obstacle sorts by its centre's depth like a particle: cloth on its near
    //    side is drawn over it, particles behind it under it.
    if spheres {
        items.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    }

    // 3. bin: counting sort of (band, draw position) keeps the draw order inside each band.
    let (start, binned) = bin_by_band(&items, h);

    // 4. raster, one band per task.
    raster_bands(image, params, &background, &items, (&start, &binned), spheres, &light);

    Ok(RenderStats { drawn, culled })
}

/// The checks of [`render_frame`]'s arguments besides the camera (`image_len`: the image's
/// bytes), in the order their errors come: the lighting to draw with.
fn check_frame(frame: &Frame, params: &RenderParams, image_len: usize) -> Result<Light, Error> {
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
    let n = radius.len();
    check_per_particle("positions", positions.len(), 3, n, "radii")?;
    check_per_particle("colors", colors.len(), 3, n, "radii")?;
    if image_len != w * h * 3 {
        return Err(invalid(
            "image",
            format!("{} bytes", image_len),
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
    Ok(light)
}

/// Stage 1 of [`render_frame`]: the particles projected into sprites with their depths and
/// indices, and how many were culled (behind the camera or outside the image).
fn project_particles(projector: &Projector, frame: &Frame, params: &RenderParams) -> Result<(Items, usize), Error> {
    let Frame {
        positions,
        radius,
        colors,
        springs,
        ..
    } = *frame;
    let (w, h) = (params.width, params.height);
    let n = radius.len();
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
    Ok((items, culled))
}

/// Stage 1b of [`render_frame`]: the scenery painted; its 3D sphere obstacles added to
/// `items` after the particles. Returns the background primitives, how many obstacles were
/// added, and the meshes' primitives to order with the rest.
fn project_scenery(
    camera: &Camera,
    projector: &Projector,
    frame: &Frame,
    params: &RenderParams,
    light: &Light,
    items: &mut Vec<(f64, usize, Item)>,
) -> (Vec<Prim>, usize, Vec<(f64, Prim)>) {
    let Frame {
        positions,
        radius,
        scenery,
        ..
    } = *frame;
    let (w, h) = (params.width, params.height);
    let n = radius.len();
    let painted = if scenery.colliders.is_empty() {
        Painted::default()
    } else {
        let extent = scenery
            .extent
            .unwrap_or_else(|| frame_extent(&scenery.colliders, bounding_box(positions, radius), camera, w, h));
        let view = View {
            camera,
            projector,
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
    (painted.background, obstacles, painted.ordered)
}

/// Stage 1c of [`render_frame`]: the springs' lines, the markers and the trails' segments
/// added to `items`: in 3D numbered after the `obstacles` (then the meshes' primitives
/// `mesh_prims`), to be ordered by depth; in 2D before every particle, in their order.
fn add_lines(
    camera: &Camera,
    projector: &Projector,
    frame: &Frame,
    params: &RenderParams,
    (obstacles, mesh_prims): (usize, Vec<(f64, Prim)>),
    items: &mut Vec<(f64, usize, Item)>,
) {
    let Frame { radius, markers, .. } = *frame;
    let (w, h) = (params.width, params.height);
    let n = radius.len();
    let spheres = camera.is_3d();
    let mut under: Vec<Item> = Vec::new();
    let mut more: Vec<(f64, Item)> = Vec::new();
    for (depth, line) in trail_lines(camera, projector, frame, params) {
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
    let lines = spring_lines(camera, projector, frame, params);
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
        let particles = std::mem::take(items);
        *items = under.into_iter().enumerate().map(|(k, it)| (0.0, k, it)).collect();
        items.extend(particles);
    }
}

/// Stage 3 of [`render_frame`]: each band's items, in draw order (a counting sort of (band,
/// draw position)): band b draws `binned[start[b]..start[b + 1]]`.
fn bin_by_band(items: &[(f64, usize, Item)], h: usize) -> (Vec<usize>, Vec<u32>) {
    let bands = h.div_ceil(BAND_ROWS);
    let band_of = |row: u32| row as usize / BAND_ROWS;
    let mut start = vec![0usize; bands + 1];
    for (_, _, it) in items {
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
    (start, binned)
}

/// Stage 4 of [`render_frame`]: the bands rasterised, one per task: the background, the
/// `background` primitives, then each band's items (`bins` from [`bin_by_band`]).
fn raster_bands(
    image: &mut [u8],
    params: &RenderParams,
    background: &[Prim],
    items: &[(f64, usize, Item)],
    (start, binned): (&[usize], &[u32]),
    spheres: bool,
    light: &Light,
) {
    let bg = params.background;
    let row_bytes = 3 * params.width;
    image.par_chunks_mut(BAND_ROWS * row_bytes).enumerate().for_each(|(b, band)| {
        fill_rgb(band, bg);
        let band_row0 = (b * BAND_ROWS) as u32;
        let band_row1 = band_row0 + (band.len() / row_bytes) as u32;
        // The background layer: every band walks the same short list in the same order.
        for prim in background {
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
                    Item::Sprite(s) if spheres => sphere_row(row, s, j, light),
                    Item::Sprite(s) => disc_row(row, s, j),
                    Item::Prim(line) => line.draw_row(row, j),
                }
            }
        }
    });
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

/// What the bands draw after their backgrounds, each with its depth and its index (the
/// order's tie-break).
type Items = Vec<(f64, usize, Item)>;

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
