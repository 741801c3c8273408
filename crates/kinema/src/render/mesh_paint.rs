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
//! meet). Every vertex is projected once per frame (both triangles of an edge need the same
//! pixel coordinates), and a triangle with no vertex in front of the near depth, or no pixel
//! centre of the image inside it, costs nothing more.
//!
//! **Order.** A facet sorts at the depth of its centroid, a line at its midpoint's, far to
//! near with the particles and obstacles (painter's algorithm, no depth buffer): a ball in a
//! bowl is drawn over the far wall and under the near one, which tints it; a ball behind a
//! closed mesh is seen through two layers of it; where a closed mesh overlaps itself on screen
//! the nearer face is drawn last. For a fine mesh the centroid is a good stand-in for the
//! depth of every pixel of the triangle; a coarse one can tint a ball that touches it.
//!
//! **Lines.** An edge is drawn (opaque [`MESH_EDGE_COLOR`], a lighter [`super::paint::LINE_COLOR`]: a rim
//! of many short segments drawn translucent would darken at every joint, where two round
//! caps overlap, and read as a dotted line) where the surface ends (one
//! triangle: a bowl's rim), folds (the two normals more than [`FEATURE_ANGLE_DEG`] apart: a
//! cube's edges, not the diagonals of its faces) or turns away from the eye (one triangle
//! facing it, the other not: the outline of a smooth bowl, found anew each frame). Edges of
//! three or more triangles are drawn too. Finding them sorts the 3F edge keys, O(F log F).

use super::clip::clip_segment_near;
use super::paint::{Persp3, MESH_COLOR, MESH_EDGE_COLOR};
use super::prim::{line, Facet, Prim};
use crate::collide::TriangleMesh;
use crate::vec3::{add, dot, scale, sub};

/// Opacity of a mesh's facets.
pub const MESH_ALPHA: f32 = super::paint::PLANE_ALPHA;
/// The shade of a facet turned away from the light, as a fraction of [`MESH_COLOR`].
pub const MESH_AMBIENT: f64 = 0.45;
/// An edge whose two triangles' normals differ by more than this (degrees) is a crease, drawn.
pub const FEATURE_ANGLE_DEG: f64 = 30.0;
/// Width of those lines, pixels.
const EDGE_PX: f64 = 1.2;

/// Appends the mesh's facets and lines, each with its depth (m along the view axis), to
/// `out`. `eye` is the camera's position and `light` the unit direction towards the light
/// in the spheres' camera coordinates (x right, y up, z towards the viewer).
pub(super) fn paint_mesh(p3: &Persp3, mesh: &TriangleMesh, eye: [f64; 3], light: [f64; 3], out: &mut Vec<(f64, Prim)>) {
    let (vertices, faces) = (mesh.vertices(), mesh.faces());
    let proj = p3.proj;
    let cam: Vec<[f64; 3]> = vertices.iter().map(|&v| proj.camera_coords(v)).collect();
    let px: Vec<[f64; 2]> = cam
        .iter()
        .map(|&c| {
            if c[2] >= p3.zn {
                proj.camera_to_pixel(c)
            } else {
                [f64::NAN; 2]
            }
        })
        .collect();
    // Where edge ij crosses the near depth, from its endpoints in index order, so that the
    // two triangles of the edge get the same point.
    let crossing = |i: usize, j: usize| {
        let (a, b) = (cam[i.min(j)], cam[i.max(j)]);
        let s = (p3.zn - a[2]) / (b[2] - a[2]);
        proj.camera_to_pixel([a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), p3.zn])
    };
    // The camera axes as a rotation: camera_coords(d) − camera_coords(0) = (d·right, d·up,
    // d·forward); the spheres' z points back at the viewer.
    let origin = proj.camera_coords([0.0; 3]);
    let shade_of = |n: [f64; 3]| {
        let c = sub(proj.camera_coords(n), origin);
        let ndl = (c[0] * light[0] + c[1] * light[1] - c[2] * light[2]).max(0.0);
        MESH_AMBIENT + (1.0 - MESH_AMBIENT) * ndl
    };
    for (t, face) in faces.iter().enumerate() {
        let [a, b, c] = face.map(|k| k as usize);
        let front = [a, b, c].map(|k| cam[k][2] >= p3.zn);
        if !front.contains(&true) {
            continue;
        }
        let mut poly = [[0.0; 2]; 4];
        let mut m = 0;
        if front == [true; 3] {
            poly[..3].copy_from_slice(&[px[a], px[b], px[c]]);
            m = 3;
        } else {
            // Sutherland–Hodgman against the near depth (as `clip::clip_polygon_near`), with
            // the crossings computed once per edge direction.
            for (k, (i, j)) in [(a, b), (b, c), (c, a)].into_iter().enumerate() {
                let fj = front[(k + 1) % 3];
                if front[k] {
                    poly[m] = px[i];
                    m += 1;
                }
                if front[k] != fj {
                    poly[m] = crossing(i, j);
                    m += 1;
                }
            }
        }
        let mut n = mesh.face_normal(t);
        let centroid = scale(1.0 / 3.0, add(add(vertices[a], vertices[b]), vertices[c]));
        if dot(n, sub(eye, centroid)) < 0.0 {
            n = scale(-1.0, n);
        }
        let shade = shade_of(n);
        let color = MESH_COLOR.map(|v| (v as f64 * shade).round().min(255.0) as u8);
        if let Some(f) = Facet::new(&poly[..m], color, MESH_ALPHA, p3.w, p3.h) {
            let depth = (cam[a][2] + cam[b][2] + cam[c][2]) / 3.0;
            out.push((depth, Prim::Facet(f)));
        }
    }
    for (i, j) in outline_edges(mesh, eye) {
        if let Some((ca, cb)) = clip_segment_near(cam[i], cam[j], p3.zn) {
            let (pa, pb) = (proj.camera_to_pixel(ca), proj.camera_to_pixel(cb));
            if let Some(l) = line(pa, pb, EDGE_PX, MESH_EDGE_COLOR, 1.0, p3.w, p3.h) {
                out.push((0.5 * (ca[2] + cb[2]), l));
            }
        }
    }
}

/// The edges (vertex index pairs) drawn as lines from `eye`: boundary, crease, silhouette
/// and non-manifold edges (see the module's comment), in a fixed order.
fn outline_edges(mesh: &TriangleMesh, eye: [f64; 3]) -> Vec<(usize, usize)> {
    let (vertices, faces) = (mesh.vertices(), mesh.faces());
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
                let n1 = mesh.face_normal(t1 as usize);
                let mut n2 = mesh.face_normal(t2 as usize);
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
