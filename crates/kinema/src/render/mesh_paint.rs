//! Painting a triangle-mesh collider in 3D: its triangles as translucent facets lit by a
//! Lambert term, and its rim, creases and silhouette as faint lines, all ordered by depth
//! with the particles.
//!
//! **Facets.** Each triangle is filled in [`MESH_COLOR`] times a Lambert shade at
//! [`MESH_ALPHA`], so that what lies behind or inside the mesh shows through it. The shade
//! is a + (1 − a)·max(n·l, 0) with a = [`MESH_AMBIENT`], l the frame's light (the
//! direction the spheres are lit from, [`super::Shading::light_dir`]) and n the triangle's
//! normal turned towards the eye: the side one sees is the side that is lit, so the
//! curvature of a bowl reads from inside and out. Triangles are cut at the near depth like
//! the other scenery, and sampled at pixel centres ([`Facet`]: no seam where neighbours
//! meet, as both compute their shared vertices and near-depth crossings alike). A triangle
//! wholly behind the near depth or outside a side of the view costs nothing more.
//!
//! **Order.** A facet sorts at the depth of its farthest vertex, a line at its farther end's,
//! far to near with the particles and obstacles (painter's algorithm, no depth buffer): a
//! ball in a bowl is drawn over the far wall and under the near one, which tints it; a ball
//! behind a closed mesh is seen through two layers of it; where a closed mesh overlaps
//! itself on screen the nearer face is drawn last; and the triangles a ball rests on, which
//! reach from behind it to in front of it, are drawn under it. Triangles that span much
//! depth are halved first ([`paint_mesh`]), so that a large one in front of a ball still
//! tints it.
//!
//! **Lines.** An edge is drawn (opaque [`MESH_EDGE_COLOR`], a lighter
//! [`super::paint::LINE_COLOR`]: a rim of many short segments drawn translucent would darken
//! at every joint, where two round caps overlap, and read as a dotted line) where the
//! surface ends (one triangle: a bowl's rim), folds (the two normals more than [`FEATURE_ANGLE_DEG`] apart: a
//! cube's edges, not the diagonals of its faces) or turns away from the eye (one triangle
//! facing it, the other not: the outline of a smooth bowl, found anew each frame). Edges of
//! three or more triangles are drawn too. Finding them sorts the 3F edge keys, O(F log F).
//!
//! **Where.** A moving mesh (one with a pose, [`TriangleMesh::pose`]) is drawn where its
//! pose puts it: its vertices and normals displaced each frame ([`Placed`]); a still one's
//! are used as they are.
//!
//! **Shadows.** A mesh is a floor too ([`MeshFloors`]): a particle over one of its triangles
//! that faces up casts its contact shadow there (the bottom of a bowl), drawn in the depth
//! order just behind the particle, after the facets under it and before those in front.

use std::borrow::Cow;

use super::clip::{clip_segment_near, GUARD};
use super::frame3::{Persp3, FLOOR_NZ, PLANE_ALPHA};
use super::prim::{line, Facet, Prim};
use crate::collide::TriangleMesh;
use crate::vec3::{add, dot, scale, sub};

/// Mesh colliders' triangles, RGB8, lit by [`MESH_AMBIENT`] and the light, and drawn at
/// [`MESH_ALPHA`] like the planes.
pub const MESH_COLOR: [u8; 3] = [150, 150, 142];
/// Mesh colliders' rims, creases and outlines, RGB8: [`super::paint::LINE_COLOR`] at about
/// half strength over white, drawn opaque.
pub const MESH_EDGE_COLOR: [u8; 3] = [140, 140, 146];
/// Opacity of a mesh's facets: the planes' ([`PLANE_ALPHA`]).
pub const MESH_ALPHA: f32 = PLANE_ALPHA;
/// The shade of a facet turned away from the light, as a fraction of [`MESH_COLOR`].
pub const MESH_AMBIENT: f64 = 0.45;
/// An edge whose two triangles' normals differ by more than this (degrees) is a crease, drawn.
pub const FEATURE_ANGLE_DEG: f64 = 30.0;
/// Width of those lines, pixels.
const EDGE_PX: f64 = 1.2;

/// A mesh where it is drawn: its vertices and face normals displaced by its pose (a moving
/// mesh), or borrowed as added (a still one).
struct Placed<'a> {
    mesh: &'a TriangleMesh,
    vertices: Cow<'a, [[f64; 3]]>,
    /// The turned face normals; `None`: the mesh's own.
    normals: Option<Vec<[f64; 3]>>,
}

impl<'a> Placed<'a> {
    fn new(mesh: &'a TriangleMesh) -> Self {
        match mesh.pose() {
            None => Placed {
                mesh,
                vertices: Cow::Borrowed(mesh.vertices()),
                normals: None,
            },
            Some(pose) => Placed {
                mesh,
                vertices: Cow::Owned(mesh.vertices().iter().map(|&v| pose.point(v)).collect()),
                normals: Some((0..mesh.faces().len()).map(|t| pose.vector(mesh.face_normal(t))).collect()),
            },
        }
    }

    fn faces(&self) -> &'a [[u32; 3]] {
        self.mesh.faces()
    }

    /// The unit normal of triangle `t` where it is drawn.
    fn normal(&self, t: usize) -> [f64; 3] {
        self.normals.as_ref().map_or_else(|| self.mesh.face_normal(t), |n| n[t])
    }
}

/// How many times a facet is cut into four at most ([`paint_mesh`]'s `split`): 4^6 =
/// 4096 pieces of a triangle.
const MAX_SPLIT: u32 = 6;

/// Appends the mesh's facets and lines, each with its depth key (m along the view axis), to
/// `out`. `eye` is the camera's position and `light` the unit direction towards the light
/// in the spheres' camera coordinates (x right, y up, z towards the viewer).
///
/// A piece's key is its farthest vertex's depth, so that it is drawn over a particle only
/// when all of it is nearer than the particle's centre: the surface a ball rests on, running
/// from behind it to in front of it, is drawn under it, whatever the size of its triangles.
/// A triangle whose depth spans more than `split` (m) is cut into four at its edges'
/// midpoints (up to [`MAX_SPLIT`] times; infinite: never), so that a large translucent
/// triangle in front of a particle still tints it. Midpoints are halfway in camera
/// coordinates, computed alike from either end, so the pieces of an edge two triangles
/// share are the same on both sides.
pub(super) fn paint_mesh(
    p3: &Persp3,
    mesh: &TriangleMesh,
    eye: [f64; 3],
    light: [f64; 3],
    split: f64,
    out: &mut Vec<(f64, Prim)>,
) {
    let placed = Placed::new(mesh);
    let (vertices, faces) = (&placed.vertices[..], placed.faces());
    let proj = p3.proj;
    let cam: Vec<[f64; 3]> = vertices.iter().map(|&v| proj.camera_coords(v)).collect();
    // The camera axes as a rotation: camera_coords(d) − camera_coords(0) = (d·right, d·up,
    // d·forward); the spheres' z points back at the viewer.
    let origin = proj.camera_coords([0.0; 3]);
    let shade_of = |n: [f64; 3]| {
        let c = sub(proj.camera_coords(n), origin);
        let ndl = (c[0] * light[0] + c[1] * light[1] - c[2] * light[2]).max(0.0);
        MESH_AMBIENT + (1.0 - MESH_AMBIENT) * ndl
    };
    let sides = view_sides(p3);
    for (t, face) in faces.iter().enumerate() {
        let [a, b, c] = face.map(|k| k as usize);
        let tri = [cam[a], cam[b], cam[c]];
        if outside(&sides, &tri, p3.zn) {
            continue;
        }
        let mut n = placed.normal(t);
        let centroid = scale(1.0 / 3.0, add(add(vertices[a], vertices[b]), vertices[c]));
        if dot(n, sub(eye, centroid)) < 0.0 {
            n = scale(-1.0, n);
        }
        let shade = shade_of(n);
        let color = MESH_COLOR.map(|v| (v as f64 * shade).round().min(255.0) as u8);
        facet(p3, &sides, tri, color, split, 0, out);
    }
    for (i, j) in outline_edges(&placed, eye) {
        edge(p3, cam[i], cam[j], out);
    }
}

/// The four sides of the view (left, right, top, bottom) widened by the guard, as planes
/// through the eye in camera coordinates: a point p is outside one when s·p > 0.
fn view_sides(p3: &Persp3) -> [[f64; 3]; 4] {
    // Pixel x = cx + f·x/z, so x > w + G ⇔ f·x − (w + G − cx)·z > 0 (z > 0), and so on; pixel
    // y runs down: y < −G ⇔ f·y − (cy + G)·z > 0.
    let (f, cx, cy) = p3.proj.focal();
    let g = GUARD;
    [
        [-f, 0.0, -(cx + g)],
        [f, 0.0, -(p3.w + g - cx)],
        [0.0, f, -(cy + g)],
        [0.0, -f, -(p3.h + g - cy)],
    ]
}

/// Whether the camera-space polygon lies wholly behind the near depth or wholly outside one
/// side of the view.
fn outside(sides: &[[f64; 3]; 4], pts: &[[f64; 3]], zn: f64) -> bool {
    pts.iter().all(|p| p[2] < zn) || sides.iter().any(|s| pts.iter().all(|p| dot(*s, *p) > 0.0))
}

/// The point halfway between a and b (the same bits whichever comes first).
fn mid(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])]
}

/// A triangle (camera coordinates) as a facet, or as four halves' facets while its depth
/// spans more than `split` (see [`paint_mesh`]).
fn facet(
    p3: &Persp3,
    sides: &[[f64; 3]; 4],
    tri: [[f64; 3]; 3],
    color: [u8; 3],
    split: f64,
    level: u32,
    out: &mut Vec<(f64, Prim)>,
) {
    let zs = tri.map(|p| p[2]);
    let far = zs[0].max(zs[1]).max(zs[2]);
    if far - zs[0].min(zs[1]).min(zs[2]) > split && level < MAX_SPLIT {
        let [a, b, c] = tri;
        let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
        for piece in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
            if !outside(sides, &piece, p3.zn) {
                facet(p3, sides, piece, color, split, level + 1, out);
            }
        }
        return;
    }
    let proj = p3.proj;
    let mut poly = [[0.0; 2]; 4];
    let mut m = 0;
    // Sutherland–Hodgman against the near depth (as `clip::clip_polygon_near`), each edge's
    // crossing computed from its ends in one order (the lesser coordinates first), so that
    // the two triangles of an edge get the same point.
    for k in 0..3 {
        let (a, b) = (tri[k], tri[(k + 1) % 3]);
        let (fa, fb) = (a[2] >= p3.zn, b[2] >= p3.zn);
        if fa {
            poly[m] = proj.camera_to_pixel(a);
            m += 1;
        }
        if fa != fb {
            let (p, q) = if a < b { (a, b) } else { (b, a) };
            let s = (p3.zn - p[2]) / (q[2] - p[2]);
            poly[m] = proj.camera_to_pixel([p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1]), p3.zn]);
            m += 1;
        }
    }
    if let Some(f) = Facet::new(&poly[..m], color, MESH_ALPHA, p3.w, p3.h) {
        out.push((far, Prim::Facet(f)));
    }
}

/// An edge line (camera coordinates), whole: halves would overlap their antialiased ends
/// and darken the joint.
fn edge(p3: &Persp3, a: [f64; 3], b: [f64; 3], out: &mut Vec<(f64, Prim)>) {
    if let Some((ca, cb)) = clip_segment_near(a, b, p3.zn) {
        let (pa, pb) = (p3.proj.camera_to_pixel(ca), p3.proj.camera_to_pixel(cb));
        if let Some(l) = line(pa, pb, EDGE_PX, MESH_EDGE_COLOR, 1.0, p3.w, p3.h) {
            out.push((ca[2].max(cb[2]), l));
        }
    }
}

/// The edges (vertex index pairs) drawn as lines from `eye`: boundary, crease, silhouette
/// and non-manifold edges (see the module's comment), in a fixed order.
fn outline_edges(mesh: &Placed, eye: [f64; 3]) -> Vec<(usize, usize)> {
    let (vertices, faces) = (&mesh.vertices[..], mesh.faces());
    // (lower index << 32 | higher index, triangle, whether the triangle runs lower → higher).
    let mut edges: Vec<(u64, u32, bool)> = Vec::with_capacity(3 * faces.len());
    for (t, f) in faces.iter().enumerate() {
        for (i, j) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
            let key = (u64::from(i.min(j)) << 32) | u64::from(i.max(j));
            edges.push((key, t as u32, i < j));
        }
    }
    edges.sort_unstable();
    let cos_feature = FEATURE_ANGLE_DEG.to_radians().cos();
    let mut out = Vec::new();
    let mut k = 0;
    while k < edges.len() {
        let key = edges[k].0;
        let run = edges[k..].iter().take_while(|e| e.0 == key).count();
        let (i, j) = ((key >> 32) as usize, (key & 0xffff_ffff) as usize);
        let drawn = match run {
            2 => {
                let ((_, t1, up1), (_, t2, up2)) = (edges[k], edges[k + 1]);
                let n1 = mesh.normal(t1 as usize);
                let mut n2 = mesh.normal(t2 as usize);
                // Two triangles that run along the edge the same way disagree on which side
                // is out (an open mesh may): turn one round before comparing.
                if up1 == up2 {
                    n2 = scale(-1.0, n2);
                }
                let to_eye = sub(eye, vertices[i]);
                let crease = dot(n1, n2) < cos_feature;
                let silhouette = (dot(n1, to_eye) > 0.0) != (dot(n2, to_eye) > 0.0);
                crease || silhouette
            }
            _ => true, // the rim (one triangle) or a non-manifold edge
        };
        if drawn {
            out.push((i, j));
        }
        k += run;
    }
    out
}

/// A mesh's floors, for contact shadows ([`super::paint`]'s `shadows`): its triangles that
/// face up or down by at least [`FLOOR_NZ`] (as a plane floor must), binned by their xy
/// boxes on a grid of about one triangle a cell (at most [`FLOOR_GRID`] a side), so that the
/// vertical through a particle's centre is tested against the few triangles over its cell.
/// Built per frame in O(F), only where there are particles to cast shadows.
pub(super) struct MeshFloors<'a> {
    mesh: Placed<'a>,
    lo: [f64; 2],
    /// Cells per metre along x and y.
    per_m: [f64; 2],
    n: [usize; 2],
    /// The triangles of cell k are `tris[start[k]..start[k + 1]]`.
    start: Vec<u32>,
    tris: Vec<u32>,
}

/// The most grid cells a side of [`MeshFloors`].
const FLOOR_GRID: usize = 512;

impl<'a> MeshFloors<'a> {
    /// `None` when no triangle of the mesh is a floor.
    pub(super) fn new(mesh: &'a TriangleMesh) -> Option<Self> {
        let mesh = Placed::new(mesh);
        let faces = mesh.faces();
        let floors: Vec<u32> = (0..faces.len())
            .filter(|&t| mesh.normal(t)[2].abs() >= FLOOR_NZ)
            .map(|t| t as u32)
            .collect();
        if floors.is_empty() {
            return None;
        }
        let (lo, hi) = mesh.mesh.bounds();
        let size = [hi[0] - lo[0], hi[1] - lo[1]];
        let cell = (size[0] * size[1] / floors.len() as f64).sqrt();
        let n: [usize; 2] = std::array::from_fn(|k| {
            if cell > 0.0 {
                ((size[k] / cell).ceil() as usize).clamp(1, FLOOR_GRID)
            } else {
                1
            }
        });
        let per_m: [f64; 2] = std::array::from_fn(|k| if size[k] > 0.0 { n[k] as f64 / size[k] } else { 0.0 });
        let mut grid = MeshFloors {
            mesh,
            lo: [lo[0], lo[1]],
            per_m,
            n,
            start: vec![0; n[0] * n[1] + 1],
            tris: Vec::new(),
        };
        // Counting sort of (cell, triangle): count, prefix sums, fill.
        // The cells under a triangle's xy box: rows j0..=j1 of columns i0..=i1.
        let cells_of = |g: &MeshFloors, t: u32| {
            let f = faces[t as usize].map(|k| g.mesh.vertices[k as usize]);
            let (x0, x1) = (f[0][0].min(f[1][0]).min(f[2][0]), f[0][0].max(f[1][0]).max(f[2][0]));
            let (y0, y1) = (f[0][1].min(f[1][1]).min(f[2][1]), f[0][1].max(f[1][1]).max(f[2][1]));
            let ((i0, j0), (i1, j1)) = (g.cell([x0, y0]), g.cell([x1, y1]));
            let nx = g.n[0];
            (j0..=j1).flat_map(move |j| (i0..=i1).map(move |i| j * nx + i))
        };
        for &t in &floors {
            for k in cells_of(&grid, t) {
                grid.start[k + 1] += 1;
            }
        }
        for k in 0..n[0] * n[1] {
            grid.start[k + 1] += grid.start[k];
        }
        let mut fill = grid.start.clone();
        let mut tris = vec![0u32; grid.start[n[0] * n[1]] as usize];
        for &t in &floors {
            for k in cells_of(&grid, t) {
                tris[fill[k] as usize] = t;
                fill[k] += 1;
            }
        }
        grid.tris = tris;
        Some(grid)
    }

    /// The cell (i, j) holding the point (x, y), clamped to the grid.
    fn cell(&self, p: [f64; 2]) -> (usize, usize) {
        let at = |k: usize| (((p[k] - self.lo[k]) * self.per_m[k]).floor().max(0.0) as usize).min(self.n[k] - 1);
        (at(0), at(1))
    }

    /// The first floor triangle the vertical through `c` meets going down from it: its drop
    /// t = c_z − z ≥ 0, its unit normal turned up, and the point (c_x, c_y, z) where it meets it.
    /// The point is inside a triangle when its barycentric coordinates in the xy projection
    /// are ≥ 0 (edges included, so that no seam between two triangles lets it through).
    pub(super) fn below(&self, c: [f64; 3]) -> Option<(f64, [f64; 3], [f64; 3])> {
        let (lo, hi) = self.mesh.mesh.bounds();
        if c[0] < lo[0] || c[0] > hi[0] || c[1] < lo[1] || c[1] > hi[1] || c[2] < lo[2] {
            return None;
        }
        let (i, j) = self.cell([c[0], c[1]]);
        let k = j * self.n[0] + i;
        let (vertices, faces) = (&self.mesh.vertices[..], self.mesh.faces());
        let mut best: Option<(f64, u32)> = None;
        for &t in &self.tris[self.start[k] as usize..self.start[k + 1] as usize] {
            let [a, b, q] = faces[t as usize].map(|v| vertices[v as usize]);
            let det = (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]);
            if det == 0.0 {
                continue;
            }
            let (px, py) = (c[0] - a[0], c[1] - a[1]);
            let l1 = (px * (q[1] - a[1]) - py * (q[0] - a[0])) / det;
            let l2 = ((b[0] - a[0]) * py - (b[1] - a[1]) * px) / det;
            if l1 < 0.0 || l2 < 0.0 || l1 + l2 > 1.0 {
                continue;
            }
            let z = a[2] + l1 * (b[2] - a[2]) + l2 * (q[2] - a[2]);
            let drop = c[2] - z;
            if drop >= 0.0 && best.is_none_or(|(d, _)| drop < d) {
                best = Some((drop, t));
            }
        }
        let (drop, t) = best?;
        let n = self.mesh.normal(t as usize);
        let n = if n[2] < 0.0 { scale(-1.0, n) } else { n };
        Some((drop, n, [c[0], c[1], c[2] - drop]))
    }
}
