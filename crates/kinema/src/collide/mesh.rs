//! Triangle-mesh colliders: a static surface of triangles that particles bounce off, with a
//! bounding-volume hierarchy so that a query costs O(log T) for T triangles.
//!
//! **Sides.** An *open* mesh (some edge has one face, or two faces that disagree on its
//! direction) is two-sided: a particle belongs to the side its centre is on, and the normal
//! of a face contact is ±n_face towards it. A *closed* mesh (every edge shared by exactly two
//! faces that run along it in opposite directions) bounds a solid: it knows inside from
//! outside. Its faces are oriented outwards on construction (flipped if its signed volume
//! Σ a·(b × c)/6 is negative), and particles live outside it ([`Side::Outside`], an obstacle)
//! or inside it ([`Side::Inside`], a container such as a drum). A face contact's normal is
//! then the face's normal towards the free side whatever side the centre is on, so that a
//! centre pushed past a face is pushed back out, not through.
//!
//! **Contacts.** A sphere of radius r at p touches every triangle whose closest point q is
//! nearer than r (+ the tolerance). The closest point lies in the face's interior, on an
//! edge or at a vertex (Ericson, *Real-Time Collision Detection* §5.1.5). Neighbouring
//! triangles report the same edge or vertex as their closest point, and a ball resting on a
//! flat patch of two coplanar triangles sees the face of one and the shared edge of the
//! other, tilted: a "ghost" contact that would kick it sideways at every seam. Three rules keep
//! exactly the contacts of the surface's true features:
//!
//! 1. contacts at the same point (the same edge or vertex seen from several triangles) are one;
//! 2. an edge or vertex contact is one of the surface only if every triangle around that edge
//!    or vertex has its nearest point there: the centre then lies in the edge's (vertex's)
//!    Voronoi region of the whole surface, not only of one triangle. A neighbour with a
//!    nearer point (the face a ball rests on, beside the seam or rim the other triangle
//!    reports) makes it no contact.
//!
//! 3. touches whose normals lie within 10° of each other are one, with the deepest overlap
//!    and their mean normal (weighted by depth): a ball in a faceted bowl, or at the apex of a
//!    fan of thin triangles (the pole of a UV sphere, where it is tangent to every spoke),
//!    rests on the smooth surface the facets stand for, not on hundreds of nearly parallel
//!    contacts that the solver would take up one by one.
//!
//! In a concave crease sharper than 10° (a V, a box's inner corner) the ball touches two
//! faces: two face contacts, both kept. On a convex edge it touches the edge: one contact, normal from the
//! edge to the centre. Centred exactly over a seam of a flat patch, both triangles report
//! the seam: one contact, along the patch's normal. At the apex of a fan of thin triangles
//! (the pole of a UV sphere) only the true nearest point remains, not one per spoke. An
//! edge of an open mesh's border belongs to one triangle and needs no neighbour.
//!
//! **Continuous detection.** [`TriangleMesh::toi`] sweeps the sphere along a straight path
//! against each triangle the hierarchy finds near it: the first time its centre comes within r
//! of the face's plane inside the triangle, of an edge's line within the edge, or of a vertex
//! (each the first root of a quadratic, as in `toi.rs`).

use std::collections::HashMap;
use std::sync::Arc;

use super::motion::Pose;
use super::surface::{Surface, Touch};
use crate::error::Error;
use crate::vec3;
use hierarchy::Node;

mod features;
pub use features::NearCache;
mod flat;
mod hierarchy;
mod time_of_impact;

/// Which side of a mesh particles belong to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Either side (an open mesh): the side the particle's centre is on.
    Both,
    /// Outside a closed mesh: it is a solid obstacle.
    Outside,
    /// Inside a closed mesh: it is a container.
    Inside,
}

/// Where on a triangle its closest point to a query point lies: its face, its edge k (from
/// its vertex k to vertex k + 1 mod 3), or its vertex k.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Feature {
    Face,
    Edge(u8),
    Vertex(u8),
}

/// The most memory the engine takes while it builds a mesh, per triangle, bytes (a closed
/// mesh of 4·10⁶ triangles, V ≈ F/2, measured: 93 B peak, 69 B kept; the caller's float64
/// vertices and int64 faces are another 36 B; `docs/collisions.md`. The flat nodes,
/// `mesh/flat.rs`, measured on the whole process: 2 B more at the peak, 6 B more kept):
/// said in the error when a mesh does not fit.
pub const BYTES_PER_TRIANGLE: usize = 100;

/// An empty buffer with room for `n` values of a mesh of `triangles` triangles, or the
/// mesh's out-of-memory error: every buffer whose size the mesh sets is allocated through
/// here (or `try_reserve`d), so that a mesh too large for the machine is an error, never an
/// abort.
pub fn mesh_buffer<T>(n: usize, triangles: usize) -> Result<Vec<T>, Error> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| mesh_too_large(triangles))?;
    Ok(v)
}

/// The error of a mesh of `triangles` triangles that cannot be allocated.
pub fn mesh_too_large(triangles: usize) -> Error {
    Error::out_of_memory(
        format!("a mesh of {triangles} triangles (about {BYTES_PER_TRIANGLE} B each while it is built)"),
        triangles.saturating_mul(BYTES_PER_TRIANGLE),
    )
}

/// The geometry of a mesh, shared by its copies (the stage, the contact force and a picture
/// hold the same one).
#[derive(Debug, PartialEq)]
struct Geometry {
    vertices: Vec<[f64; 3]>,
    faces: Vec<[u32; 3]>,
    /// Unit normal of each face, (b − a) × (c − a) normalised.
    normals: Vec<[f64; 3]>,
    /// The triangles in the order the hierarchy's leaves hold them.
    order: Vec<u32>,
    nodes: Vec<Node>,
    closed: bool,
    /// Largest |coordinate| of a vertex, m.
    scale: f64,
    /// The box around the vertices of the triangles, (lo, hi), m.
    bounds: ([f64; 3], [f64; 3]),
    /// For each triangle, how many triangles share each of its edges (itself included; 1 on
    /// an open mesh's border), at most 255.
    edge_faces: Vec<[u8; 3]>,
    /// How many triangles each vertex belongs to.
    valence: Vec<u32>,
}

/// A static triangle mesh that particles collide with. Cloning is cheap: copies share the
/// geometry.
#[derive(Debug, Clone)]
pub struct TriangleMesh {
    geometry: Arc<Geometry>,
    side: Side,
    surface: Surface,
    /// Where a moving mesh is: its geometry is kept as added, and each query is turned into
    /// that frame (a mesh of 10⁶ triangles moves at the cost of one transform per query).
    pose: Option<Pose>,
}

impl PartialEq for TriangleMesh {
    fn eq(&self, other: &Self) -> bool {
        (Arc::ptr_eq(&self.geometry, &other.geometry) || self.geometry == other.geometry)
            && self.side == other.side
            && self.surface == other.surface
            && self.pose == other.pose
    }
}

impl TriangleMesh {
    /// The mesh of `vertices` (m, finite) and triangles `faces` (three vertex indices each,
    /// counter-clockwise seen from the outside for a closed mesh; any order for an open one).
    /// Triangles of zero area are left out (they have no normal and touch nothing their
    /// neighbours do not). `inside`: for a closed mesh, whether particles live inside it (a
    /// container) rather than outside (an obstacle); an open mesh is two-sided and refuses
    /// `inside = true`.
    ///
    /// Errors name the first bad value: a non-finite vertex, an index out of range, a face
    /// with a repeated vertex, no triangle of non-zero area.
    pub fn new(vertices: Vec<[f64; 3]>, mut faces: Vec<[u32; 3]>, inside: bool, surface: Surface) -> Result<Self, Error> {
        let triangles = faces.len();
        check_indices(&vertices, &faces)?;
        let area = |f: &[u32; 3]| {
            let [a, b, c] = f.map(|k| vertices[k as usize]);
            vec3::cross(vec3::sub(b, a), vec3::sub(c, a))
        };
        faces.retain(|f| vec3::norm(area(f)) > 0.0);
        if faces.is_empty() {
            return Err(Error::invalid(
                "faces",
                "no triangle of non-zero area",
                "a mesh needs at least one triangle with three distinct, non-collinear vertices",
            ));
        }
        let (closed, edge_faces) = adjacency(&faces).ok_or_else(|| mesh_too_large(triangles))?;
        if closed {
            let volume: f64 = faces
                .iter()
                .map(|f| {
                    let [a, b, c] = f.map(|k| vertices[k as usize]);
                    vec3::dot(a, vec3::cross(b, c))
                })
                .sum();
            if volume < 0.0 {
                for f in &mut faces {
                    f.swap(1, 2);
                }
            }
        } else if inside {
            return Err(Error::invalid(
                "inside",
                "true",
                "only a closed mesh has an inside (every edge shared by exactly two faces); this mesh is open, \
                 so it is two-sided: particles stay on the side they start on",
            ));
        }
        let mut normals = mesh_buffer(faces.len(), triangles)?;
        normals.extend(faces.iter().map(|f| {
            let c = area(f);
            vec3::scale(1.0 / vec3::norm(c), c)
        }));
        let scale = vertices.iter().flatten().fold(0.0_f64, |m, c| m.max(c.abs()));
        let valence = vertex_valence(&vertices, &faces, triangles)?;
        let mut geometry = Geometry {
            vertices,
            faces,
            normals,
            order: Vec::new(),
            nodes: Vec::new(),
            closed,
            scale,
            bounds: ([0.0; 3], [0.0; 3]),
            edge_faces,
            valence,
        };
        geometry.build().ok_or_else(|| mesh_too_large(triangles))?;
        geometry.bounds = bounds(&geometry.vertices, &geometry.faces);
        let side = match (closed, inside) {
            (false, _) => Side::Both,
            (true, false) => Side::Outside,
            (true, true) => Side::Inside,
        };
        Ok(TriangleMesh {
            geometry: Arc::new(geometry),
            side,
            surface,
            pose: None,
        })
    }

    /// The vertices, m.
    pub fn vertices(&self) -> &[[f64; 3]] {
        &self.geometry.vertices
    }

    /// The triangles (zero-area ones left out; a closed mesh's oriented outwards).
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.geometry.faces
    }

    /// The unit normal of triangle `t` ((b − a) × (c − a) normalised; outwards on a closed mesh).
    pub fn face_normal(&self, t: usize) -> [f64; 3] {
        self.geometry.normals[t]
    }

    /// Whether every edge is shared by exactly two faces running along it in opposite directions.
    pub fn is_closed(&self) -> bool {
        self.geometry.closed
    }

    /// Which side particles belong to.
    pub fn side(&self) -> Side {
        self.side
    }

    /// Its restitution and friction.
    pub fn surface(&self) -> Surface {
        self.surface
    }

    /// The same mesh with surface `surface` (the geometry shared).
    pub fn with_surface(&self, surface: Surface) -> TriangleMesh {
        TriangleMesh { surface, ..self.clone() }
    }

    /// The same mesh displaced by `pose` from where it was added (the geometry shared).
    pub fn posed(&self, pose: Pose) -> TriangleMesh {
        TriangleMesh {
            pose: Some(pose),
            ..self.clone()
        }
    }

    /// Its displacement from where it was added, if it moved.
    pub fn pose(&self) -> Option<Pose> {
        self.pose
    }

    /// The box around all vertices where the mesh is now, (lo, hi), m (around the turned
    /// box of its vertices as added, for a turned mesh).
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let root = self.geometry.bounds;
        let Some(pose) = self.pose else {
            return root;
        };
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for corner in 0..8 {
            let c = [0, 1, 2].map(|k| if corner >> k & 1 == 0 { root.0[k] } else { root.1[k] });
            let p = pose.point(c);
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }

    /// Largest |coordinate| of a vertex where the mesh is now, m (a bound for a moved mesh).
    pub fn scale(&self) -> f64 {
        if self.pose.is_none() {
            return self.geometry.scale;
        }
        let (lo, hi) = self.bounds();
        lo.iter().chain(&hi).fold(0.0, |m: f64, c| m.max(c.abs()))
    }

    /// A point (m) turned into the frame the geometry was added in.
    fn local(&self, p: [f64; 3]) -> [f64; 3] {
        self.pose.map_or(p, |pose| pose.point_back(p))
    }

    /// A direction turned into the frame the geometry was added in.
    fn local_vector(&self, d: [f64; 3]) -> [f64; 3] {
        self.pose.map_or(d, |pose| pose.vector_back(d))
    }

    /// A touch of the geometry's frame turned to where the mesh is.
    fn placed(&self, t: Touch) -> Touch {
        match self.pose {
            None => t,
            Some(pose) => Touch {
                normal: pose.vector(t.normal),
                ..t
            },
        }
    }

    /// The touch of a sphere at `p` of radius `r` (m) with triangle `t`, however far (the
    /// normal and overlap of an impact the continuous detection found on that triangle).
    /// `p` is where the mesh is now, and so is the normal (a moved mesh's geometry keeps the
    /// frame it was added in: the point goes into it, the normal comes out of it).
    pub fn touch_of_triangle(&self, t: usize, p: [f64; 3], r: f64) -> Touch {
        let near = self
            .near(t, self.local(p), f64::INFINITY)
            .expect("every triangle is within an infinite reach");
        self.placed(self.touches_of(&[near], r)[0].0)
    }

    /// Calls `each` with every touch of a sphere at `p` (m) of radius `r` (m) within
    /// `tolerance` (m), its true features only (the module's doc: one per face touched, one
    /// per convex edge or vertex), in the order of the triangles' indices.
    pub fn for_each_touch(&self, p: [f64; 3], r: f64, tolerance: f64, mut each: impl FnMut(Touch)) {
        for (_, touch, _, _) in self.touches(self.local(p), r, tolerance) {
            each(self.placed(touch));
        }
    }

    /// [`TriangleMesh::for_each_touch`] from the triangles `cache` keeps around a point near
    /// `p` (gathered again where they do not answer for it: [`NearCache`]): the same touches,
    /// without the search down the hierarchy while a sphere stays near one place.
    pub fn for_each_touch_near(&self, p: [f64; 3], r: f64, tolerance: f64, cache: &mut NearCache, mut each: impl FnMut(Touch)) {
        for (_, touch, _, _) in self.touches_near(self.local(p), r, tolerance, cache) {
            each(self.placed(touch));
        }
    }

    /// Whether point `p` (m) lies inside the closed mesh (false for an open one): the parity
    /// of the crossings of a ray from p with the triangles (a ray in a direction no mesh
    /// built of axis-aligned or simple angles lines up with).
    pub fn contains(&self, p: [f64; 3]) -> bool {
        if !self.geometry.closed {
            return false;
        }
        let p = self.local(p);
        let dir = {
            let d = [0.123_456_7, 0.067_891_2, 1.0];
            vec3::scale(1.0 / vec3::norm(d), d)
        };
        let g = &*self.geometry;
        let mut crossings = 0usize;
        g.visit_ray(p, dir, |t| {
            let [a, b, c] = g.faces[t].map(|k| g.vertices[k as usize]);
            if ray_hits_triangle(p, dir, a, b, c) {
                crossings += 1;
            }
        });
        crossings % 2 == 1
    }
}

/// Whether every edge is shared by exactly two faces that run along it in opposite directions
/// (the mesh is closed), and for each face how many faces share each of its edges; `None`:
/// the memory for them cannot be allocated.
fn adjacency(faces: &[[u32; 3]]) -> Option<(bool, Vec<[u8; 3]>)> {
    // per undirected edge: (uses a→b with a < b, uses b→a); a closed mesh has 3F/2 edges, an
    // open one up to 3F (the table grows, fallibly, beyond 3F/2)
    let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
    edges.try_reserve(3 * faces.len() / 2).ok()?;
    let key = |f: &[u32; 3], k: usize| {
        let (a, b) = (f[k], f[(k + 1) % 3]);
        ((a.min(b), a.max(b)), a < b)
    };
    for f in faces {
        if edges.capacity() - edges.len() < 3 {
            edges.try_reserve(edges.len().max(3)).ok()?;
        }
        for k in 0..3 {
            let (e, up) = key(f, k);
            let e = edges.entry(e).or_default();
            if up {
                e.0 += 1;
            } else {
                e.1 += 1;
            }
        }
    }
    let closed = edges.values().all(|&(up, down)| up == 1 && down == 1);
    let mut counts = mesh_buffer(faces.len(), faces.len()).ok()?;
    counts.extend(faces.iter().map(|f| {
        [0, 1, 2].map(|k| {
            let (up, down) = edges[&key(f, k).0];
            (up + down).min(255) as u8
        })
    }));
    Some((closed, counts))
}

/// Whether the ray p + s d (s > 0) crosses triangle abc (Möller–Trumbore).
fn ray_hits_triangle(p: [f64; 3], d: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> bool {
    let e1 = vec3::sub(b, a);
    let e2 = vec3::sub(c, a);
    let h = vec3::cross(d, e2);
    let det = vec3::dot(e1, h);
    if det == 0.0 {
        return false;
    }
    let inv = 1.0 / det;
    let s = vec3::sub(p, a);
    let u = inv * vec3::dot(s, h);
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = vec3::cross(s, e1);
    let w = inv * vec3::dot(d, q);
    if w < 0.0 || u + w > 1.0 {
        return false;
    }
    inv * vec3::dot(e2, q) > 0.0
}

/// The checks of [`TriangleMesh::new`] before any face is kept: finite vertices, faces of
/// three different vertices in range.
fn check_indices(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Result<(), Error> {
    for (v, p) in vertices.iter().enumerate() {
        if let Some((k, value)) = vec3::first_non_finite(p) {
            return Err(Error::invalid(
                format!("vertices[{v}][{k}]"),
                value,
                "a mesh's vertices must be finite",
            ));
        }
    }
    let n = vertices.len();
    for (f, face) in faces.iter().enumerate() {
        for (k, &index) in face.iter().enumerate() {
            if index as usize >= n {
                return Err(Error::invalid(
                    format!("faces[{f}][{k}]"),
                    index,
                    format!("a face's vertex index must be below the number of vertices ({n})"),
                ));
            }
        }
        if face[0] == face[1] || face[1] == face[2] || face[0] == face[2] {
            return Err(Error::invalid(
                format!("faces[{f}]"),
                format!("{face:?}"),
                "a face needs three different vertices",
            ));
        }
    }
    Ok(())
}

/// How many faces use each vertex (a buffer sized for a mesh of `triangles`).
fn vertex_valence(vertices: &[[f64; 3]], faces: &[[u32; 3]], triangles: usize) -> Result<Vec<u32>, Error> {
    let mut valence = mesh_buffer(vertices.len(), triangles)?;
    valence.resize(vertices.len(), 0u32);
    for f in faces {
        for &k in f {
            valence[k as usize] += 1;
        }
    }
    Ok(valence)
}

/// The box around the vertices the faces use, m.
fn bounds(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> ([f64; 3], [f64; 3]) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &v in faces.iter().flatten() {
        let p = vertices[v as usize];
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

#[cfg(test)]
#[path = "tests/mesh.rs"]
mod tests;
