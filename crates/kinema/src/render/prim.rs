//! Pixel-space primitives: convex fills and antialiased lines (and flat discs), each turned
//! into signed-distance equations once per frame and drawn row by row; and facets, the
//! triangles of a mesh, filled where they cover pixel centres so that neighbours tile.
//!
//! The painters of the scenery ([`super::paint`]) and of springs (the raster stage) build
//! them in f64 from points already projected (and cut at the near depth, [`super::clip`]);
//! each is clipped to the guard rectangle here, so that its pixel coordinates stay small. A
//! band of the raster stage draws the rows of a primitive that fall inside it, and a row's
//! pixels depend on nothing else, so frames stay byte-identical for any thread count.

use super::clip::{clip_halfplane, dot2, GUARD};
use super::pixels::{blend, disc_row, fill_rgb, Sprite};

/// A background primitive in pixel coordinates (x to the right, y down), drawn row by row.
#[derive(Clone, Debug)]
pub(crate) enum Prim {
    /// A convex polygon, filled: each edge as (a, b, c) with a·x + b·y + c the signed
    /// distance in pixels, positive inside.
    Fill {
        edges: Vec<[f64; 3]>,
        color: [f32; 3],
        alpha: f32,
        rows: (u32, u32),
    },
    /// A segment from `a` of direction `u` (unit) and length `len`, `half` its half width.
    Line {
        a: [f64; 2],
        u: [f64; 2],
        len: f64,
        half: f64,
        color: [f32; 3],
        alpha: f32,
        rows: (u32, u32),
    },
    /// A flat disc (2D sphere obstacles).
    Disc(Sprite),
    /// A mesh's triangle (or the quad left of it by the near cut), not antialiased.
    Facet(Facet),
}

/// A convex polygon of three or four vertices (pixels) that paints exactly the pixels whose
/// centres it covers, with no antialiased rim: the triangles of a mesh, drawn translucent.
///
/// Antialiased fills ([`Prim::Fill`]) would blend twice along every edge two triangles share
/// (and under-cover their corners), a lattice of seams over a fine mesh; sampled at pixel
/// centres, triangles that share an edge share its pixels out exactly: a translucent surface
/// reads as one layer. Exactness takes two things. Both triangles hold the shared vertices'
/// pixel coordinates bit for bit (the painter projects each vertex once), and each computes
/// the edge's crossing of a row from its endpoints in one canonical order (the lower
/// (y, x) first), so both get the same x_e; the triangle on its left takes the centres
/// x < x_e and the one on its right x ≥ x_e. A row y crosses the edges with y0 ≤ y < y1 (half
/// open, so a row through a shared vertex or along a horizontal edge belongs to one side).
/// The outline of the surface is jagged; the mesh's painter draws its rim and silhouette as
/// antialiased lines over it.
#[derive(Clone, Debug)]
pub(crate) struct Facet {
    pts: [[f64; 2]; 4],
    n: usize,
    color: [f32; 3],
    alpha: f32,
    rows: (u32, u32),
}

impl Facet {
    /// The facet of the convex polygon `poly` (3 or 4 vertices, pixels) in a `w × h` image;
    /// `None` when it covers no pixel centre of the image's rows and columns (outside the
    /// view, or a sliver between two rows or two columns of centres).
    pub(crate) fn new(poly: &[[f64; 2]], color: [u8; 3], alpha: f32, w: f64, h: f64) -> Option<Facet> {
        if !(3..=4).contains(&poly.len()) {
            return None;
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in poly {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        // Centres c = i + ½ with lo ≤ c < hi: i in [⌈lo − ½⌉, ⌈hi − ½⌉).
        let centres = |lo: f64, hi: f64, n: f64| ((lo - 0.5).ceil().clamp(0.0, n), (hi - 0.5).ceil().clamp(0.0, n));
        let (c0, c1) = centres(lo[0], hi[0], w);
        let (r0, r1) = centres(lo[1], hi[1], h);
        if !(c0 < c1 && r0 < r1) {
            return None;
        }
        let mut pts = [[0.0; 2]; 4];
        pts[..poly.len()].copy_from_slice(poly);
        Some(Facet {
            pts,
            n: poly.len(),
            color: color_f32(color),
            alpha,
            rows: (r0 as u32, r1 as u32),
        })
    }

    /// Row `j`: the centres between the two edges crossing it (see [`Facet`]).
    fn draw_row(&self, row: &mut [u8], j: u32) {
        let y = j as f64 + 0.5;
        let (mut xl, mut xr, mut crossings) = (f64::INFINITY, f64::NEG_INFINITY, 0);
        for k in 0..self.n {
            let (a, b) = (self.pts[k], self.pts[(k + 1) % self.n]);
            let (p, q) = if (a[1], a[0]) <= (b[1], b[0]) { (a, b) } else { (b, a) };
            if p[1] <= y && y < q[1] {
                let x = p[0] + (y - p[1]) * (q[0] - p[0]) / (q[1] - p[1]);
                xl = xl.min(x);
                xr = xr.max(x);
                crossings += 1;
            }
        }
        if crossings < 2 {
            return;
        }
        let width = (row.len() / 3) as f64;
        let i0 = (xl - 0.5).ceil().clamp(0.0, width) as usize;
        let i1 = (xr - 0.5).ceil().clamp(0.0, width) as usize;
        if i0 >= i1 {
            return;
        }
        if self.alpha >= 1.0 {
            fill_rgb(&mut row[3 * i0..3 * i1], self.color.map(|c| c as u8));
        } else {
            for px in row[3 * i0..3 * i1].chunks_exact_mut(3) {
                blend(px, self.color, self.alpha);
            }
        }
    }
}

/// Appends `p` when there is one (a primitive that is entirely out of view is `None`).
pub(crate) fn push(out: &mut Vec<Prim>, p: Option<Prim>) {
    if let Some(p) = p {
        out.push(p);
    }
}

/// Pixel rows [row0, row1) whose centres j + ½ lie in [y0, y1].
fn rows_of(y0: f64, y1: f64, h: f64) -> (u32, u32) {
    let r0 = (y0 - 0.5).ceil().clamp(0.0, h) as u32;
    let r1 = ((y1 - 0.5).floor() + 1.0).clamp(0.0, h) as u32;
    (r0, r1)
}

fn color_f32(c: [u8; 3]) -> [f32; 3] {
    c.map(|v| v as f32)
}

/// A convex polygon (pixels) as a fill: clipped to the guard rectangle, its edges as inward
/// signed-distance equations. `None` when nothing of it is in view.
pub(crate) fn fill(poly: Vec<[f64; 2]>, color: [u8; 3], alpha: f32, w: f64, h: f64) -> Option<Prim> {
    let mut poly = poly;
    // Guard rectangle: x ≥ −G, x ≤ w + G, y ≥ −G, y ≤ h + G.
    for e in [
        [1.0, 0.0, GUARD],
        [-1.0, 0.0, w + GUARD],
        [0.0, 1.0, GUARD],
        [0.0, -1.0, h + GUARD],
    ] {
        if poly.len() < 3 {
            return None;
        }
        poly = clip_halfplane(&poly, e);
    }
    if poly.len() < 3 {
        return None;
    }
    let m = poly.len() as f64;
    let centroid = poly.iter().fold([0.0, 0.0], |s, p| [s[0] + p[0] / m, s[1] + p[1] / m]);
    let mut edges = Vec::with_capacity(poly.len());
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let d = [b[0] - a[0], b[1] - a[1]];
        let l = (d[0] * d[0] + d[1] * d[1]).sqrt();
        if l < 1e-9 {
            continue;
        }
        // The unit normal of the edge's line; flipped to point at the centroid (inside).
        let mut n = [-d[1] / l, d[0] / l];
        if dot2(n, [centroid[0] - a[0], centroid[1] - a[1]]) < 0.0 {
            n = [-n[0], -n[1]];
        }
        edges.push([n[0], n[1], -dot2(n, a)]);
    }
    if edges.len() < 3 || edges.len() > MAX_EDGES {
        return None;
    }
    let (y0, y1) = poly
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[1]), hi.max(p[1])));
    let rows = rows_of(y0 - 0.5, y1 + 0.5, h);
    (rows.0 < rows.1).then(|| Prim::Fill {
        edges,
        color: color_f32(color),
        alpha,
        rows,
    })
}

/// A quad cut by the near plane, four guard sides and up to a dozen other planes (a faceted
/// bowl), or a shadow's 16-gon cut by the near plane and the guard sides, fits.
const MAX_EDGES: usize = 32;

/// A segment (pixels) `width` pixels wide, clipped to the guard rectangle (Liang–Barsky).
pub(crate) fn line(a: [f64; 2], b: [f64; 2], width: f64, color: [u8; 3], alpha: f32, w: f64, h: f64) -> Option<Prim> {
    let d = [b[0] - a[0], b[1] - a[1]];
    // a + s·d for s in [s0, s1], kept inside each of the four sides.
    let (mut s0, mut s1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d[0], a[0] + GUARD),
        (d[0], w + GUARD - a[0]),
        (-d[1], a[1] + GUARD),
        (d[1], h + GUARD - a[1]),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let s = q / p;
            if p < 0.0 {
                s0 = s0.max(s);
            } else {
                s1 = s1.min(s);
            }
        }
    }
    if s0 > s1 {
        return None;
    }
    let p0 = [a[0] + s0 * d[0], a[1] + s0 * d[1]];
    let p1 = [a[0] + s1 * d[0], a[1] + s1 * d[1]];
    let v = [p1[0] - p0[0], p1[1] - p0[1]];
    let len = (v[0] * v[0] + v[1] * v[1]).sqrt();
    let u = if len > 1e-12 { [v[0] / len, v[1] / len] } else { [1.0, 0.0] };
    let half = 0.5 * width;
    let reach = half + 0.5;
    let rows = rows_of(p0[1].min(p1[1]) - reach, p0[1].max(p1[1]) + reach, h);
    (rows.0 < rows.1).then(|| Prim::Line {
        a: p0,
        u,
        len,
        half,
        color: color_f32(color),
        alpha,
        rows,
    })
}

/// The x range where lo ≤ c·x + k ≤ hi (all of it, or none, when c = 0).
#[inline]
fn slab(c: f64, k: f64, lo: f64, hi: f64) -> (f64, f64) {
    if c.abs() < 1e-12 {
        if (lo..=hi).contains(&k) {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (f64::INFINITY, f64::NEG_INFINITY)
        }
    } else {
        let (x0, x1) = ((lo - k) / c, (hi - k) / c);
        (x0.min(x1), x0.max(x1))
    }
}

/// Pixel columns [i0, i1) whose centres i + ½ lie in [x0, x1].
#[inline]
fn cols_of(x0: f64, x1: f64, width: usize) -> (usize, usize) {
    let wf = width as f64;
    let i0 = (x0 - 0.5).ceil().clamp(0.0, wf) as usize;
    let i1 = ((x1 - 0.5).floor() + 1.0).clamp(0.0, wf) as usize;
    (i0, i1)
}

impl Prim {
    /// Rows [row0, row1) the primitive can touch.
    pub(crate) fn rows(&self) -> (u32, u32) {
        match self {
            Prim::Fill { rows, .. } | Prim::Line { rows, .. } => *rows,
            Prim::Disc(s) => (s.row0, s.row1),
            Prim::Facet(f) => f.rows,
        }
    }

    /// Draws row `j` of the primitive into `row` (RGB8, the image's width).
    pub(crate) fn draw_row(&self, row: &mut [u8], j: u32) {
        let width = row.len() / 3;
        let y = j as f64 + 0.5;
        match self {
            Prim::Fill { edges, color, alpha, .. } => {
                // Each edge's signed distance along this row is d_e(x) = a·x + k_e with
                // k_e = b·y + c. A pixel whose centre is at distance d inside a straight edge
                // is covered clamp(d + ½, 0, 1) (the edge sweeps the unit pixel over a
                // one-pixel band of d); inside a convex polygon the nearest edge decides:
                // coverage ≈ clamp(min_e d_e + ½, 0, 1). So the touched pixels have every
                // d_e > −½ and the fully covered ones every d_e ≥ ½: two x ranges per edge.
                let mut k = [0.0f64; MAX_EDGES];
                let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
                let (mut f0, mut f1) = (f64::NEG_INFINITY, f64::INFINITY);
                for (e, ke) in edges.iter().zip(k.iter_mut()) {
                    *ke = e[1] * y + e[2];
                    if e[0].abs() < 1e-12 {
                        if *ke <= -0.5 {
                            return;
                        }
                        if *ke < 0.5 {
                            f0 = f64::INFINITY; // no pixel of this row is fully inside
                        }
                    } else {
                        let (xt, xf) = ((-0.5 - *ke) / e[0], (0.5 - *ke) / e[0]);
                        if e[0] > 0.0 {
                            t0 = t0.max(xt);
                            f0 = f0.max(xf);
                        } else {
                            t1 = t1.min(xt);
                            f1 = f1.min(xf);
                        }
                    }
                }
                let (i0, i1) = cols_of(t0, t1, width);
                if i0 >= i1 {
                    return;
                }
                let (fi0, fi1) = if f0 <= f1 { cols_of(f0, f1, width) } else { (i0, i0) };
                let (fi0, fi1) = (fi0.clamp(i0, i1), fi1.clamp(i0, i1).max(fi0.clamp(i0, i1)));
                let k = &k[..edges.len()];
                let partial = |px: &mut [u8], i: usize| {
                    let x = i as f64 + 0.5;
                    let d = edges.iter().zip(k).fold(f64::INFINITY, |m, (e, ke)| m.min(e[0] * x + ke));
                    let a = (d + 0.5).clamp(0.0, 1.0) as f32 * alpha;
                    if a > 0.0 {
                        blend(px, *color, a);
                    }
                };
                for i in (i0..fi0).chain(fi1..i1) {
                    partial(&mut row[3 * i..3 * i + 3], i);
                }
                if *alpha >= 1.0 {
                    fill_rgb(&mut row[3 * fi0..3 * fi1], color.map(|c| c as u8));
                } else {
                    for px in row[3 * fi0..3 * fi1].chunks_exact_mut(3) {
                        blend(px, *color, *alpha);
                    }
                }
            }
            Prim::Line {
                a,
                u,
                len,
                half,
                color,
                alpha,
                ..
            } => {
                // Coverage of a pixel by a line of width w whose centre line passes at distance
                // d from the pixel centre: each of the line's two borders is a straight edge,
                // the near one at signed distance w/2 − d inside, which covers
                // clamp(w/2 − d + ½, 0, 1) of the pixel (as for the fill above); for w ≥ 1
                // the far border (at w/2 + d ≥ ½) leaves it alone, so
                // coverage = clamp(w/2 + ½ − d, 0, 1). d is the distance to the segment, so
                // the ends are round caps.
                let reach = half + 0.5;
                let n = [-u[1], u[0]];
                // The pixels within reach: |n·(p − a)| ≤ reach and −reach ≤ u·(p − a) ≤ len + reach.
                let (x0, x1) = slab(n[0], n[1] * (y - a[1]) - n[0] * a[0], -reach, reach);
                let (x2, x3) = slab(u[0], u[1] * (y - a[1]) - u[0] * a[0], -reach, len + reach);
                let (i0, i1) = cols_of(x0.max(x2), x1.min(x3), width);
                for i in i0..i1 {
                    let p = [i as f64 + 0.5 - a[0], y - a[1]];
                    let t = dot2(p, *u).clamp(0.0, *len);
                    let (dx, dy) = (p[0] - t * u[0], p[1] - t * u[1]);
                    let d = (dx * dx + dy * dy).sqrt();
                    let cov = (half + 0.5 - d).clamp(0.0, 1.0) as f32 * alpha;
                    if cov > 0.0 {
                        blend(&mut row[3 * i..3 * i + 3], *color, cov);
                    }
                }
            }
            Prim::Disc(s) => disc_row(row, s, j),
            Prim::Facet(f) => f.draw_row(row, j),
        }
    }
}
