//! Pixels: particles and sphere obstacles as sprites, and the row painters every layer uses
//! (span fill, "over" blending, antialiased discs, shaded spheres).
//!
//! Everything here works on one image row at a time (RGB8, the image's width), so that a
//! band of the raster stage can draw its own rows and nothing else.

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

/// Lighting constants in f32, the light and half vectors normalised.
pub(crate) struct Light {
    /// Towards the light, unit, camera coordinates.
    pub(crate) l: [f32; 3],
    /// The Blinn–Phong half vector, unit.
    pub(crate) h: [f32; 3],
    pub(crate) ambient: f32,
    pub(crate) specular: f32,
    pub(crate) shininess: i32,
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
pub(crate) fn sphere_row(row: &mut [u8], s: &Sprite, j: u32, light: &Light) {
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
