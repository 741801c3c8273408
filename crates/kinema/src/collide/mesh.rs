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
use super::roots::toi_half_space;
use super::surface::{Surface, Touch};
use crate::error::Error;
use crate::vec3;
use smallvec::SmallVec;

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

/// A node of the hierarchy: a box and either two children (the left one follows the node,
/// the right one at `right`) or `count` triangles of `order` from `start`. The box is kept in
/// f32, rounded outwards (it only ever holds more than the triangles): 40 bytes a node
/// rather than 64, and a traversal of a large mesh is bound by the nodes it loads.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Node {
    lo: [f32; 3],
    hi: [f32; 3],
    right: u32,
    start: u32,
    count: u32,
}

/// The largest f32 at most `x` (a box's lower side, rounded outwards).
fn f32_below(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) > x {
        y.next_down()
    } else {
        y
    }
}

/// The smallest f32 at least `x`.
fn f32_above(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x {
        y.next_up()
    } else {
        y
    }
}

/// Contacts whose normals differ by less than this merge (rule 3 of the module's doc): cos 10°.
const PARALLEL: f64 = 0.984_807_753_012_208;

/// Rule 3 of the module's doc: the touches whose normals lie within 10° of a deeper one's are
/// one touch, with the deepest overlap and the mean of their normals weighted by how much
/// deeper than the shallowest each is (plus 0.1 % of r, so that equal ones weigh alike).
fn merge_parallel(kept: &mut Found, r: f64) {
    kept.sort_by(|a, b| b.1.overlap.total_cmp(&a.1.overlap).then(a.0.cmp(&b.0)));
    let mut out = Found::new();
    let mut taken = vec![false; kept.len()];
    for s in 0..kept.len() {
        if taken[s] {
            continue;
        }
        // within 10° of the deepest, then (twice) of the members' mean: a symmetric ring of
        // normals (a cone's apex) is gathered whole whichever member seeds it
        let mut seed = kept[s].1.normal;
        let mut members: SmallVec<[usize; 8]> = SmallVec::new();
        for _ in 0..3 {
            members = (s..kept.len())
                .filter(|&k| !taken[k] && (k == s || vec3::dot(kept[k].1.normal, seed) >= PARALLEL))
                .collect();
            let sum = members.iter().fold([0.0; 3], |a, &k| vec3::add(a, kept[k].1.normal));
            seed = vec3::scale(1.0 / vec3::norm(sum), sum);
        }
        if members.len() == 1 {
            taken[s] = true;
            out.push(kept[s]);
            continue;
        }
        let least = members.iter().map(|&k| kept[k].1.overlap).fold(f64::INFINITY, f64::min);
        let mut sum = [0.0; 3];
        for &k in &members {
            taken[k] = true;
            let w = kept[k].1.overlap - least + 1e-3 * r;
            sum = vec3::add(sum, vec3::scale(w, kept[k].1.normal));
        }
        let (t, touch, q, feature) = kept[s];
        out.push((
            t,
            Touch {
                normal: vec3::scale(1.0 / vec3::norm(sum), sum),
                overlap: touch.overlap,
            },
            q,
            feature,
        ));
    }
    out.sort_by_key(|f| f.0);
    *kept = out;
}

/// Touches with their triangle, nearest point (m) and feature.
type Found = SmallVec<[(usize, Touch, [f64; 3], Feature); 4]>;

/// A triangle `t` near a point p: its nearest point q, the feature q lies on, d = p − q and |d|.
#[derive(Debug, Clone, Copy)]
struct Near {
    t: usize,
    q: [f64; 3],
    feature: Feature,
    d: [f64; 3],
    len: f64,
}

/// The most triangles a leaf of the hierarchy holds.
const LEAF: usize = 4;

/// The most memory the engine takes while it builds a mesh, per triangle, bytes (a closed
/// mesh of 4·10⁶ triangles, V ≈ F/2, measured: 93 B peak, 69 B kept; the caller's float64
/// vertices and int64 faces are another 36 B; `docs/collisions.md`): said in the error when
/// a mesh does not fit.
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

/// How many nodes the hierarchy of `n` triangles has (median splits down to leaves of at
/// most [`LEAF`]), so that its buffer is allocated once, fallibly. A level holds at most two
/// sizes of subtree (⌊m/2⌋ and ⌈m/2⌉ of the level above's).
fn node_count(n: usize) -> usize {
    let mut level: SmallVec<[(usize, usize); 4]> = SmallVec::from_slice(&[(n, 1)]);
    let mut total = 0;
    while !level.is_empty() {
        let mut next: SmallVec<[(usize, usize); 4]> = SmallVec::new();
        for (size, many) in level {
            total += many;
            if size > LEAF {
                for half in [size / 2, size - size / 2] {
                    match next.iter_mut().find(|e| e.0 == half) {
                        Some(e) => e.1 += many,
                        None => next.push((half, many)),
                    }
                }
            }
        }
        level = next;
    }
    total
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
        let mut valence = mesh_buffer(vertices.len(), triangles)?;
        valence.resize(vertices.len(), 0u32);
        for f in &faces {
            for &k in f {
                valence[k as usize] += 1;
            }
        }
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
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for &v in geometry.faces.iter().flatten() {
            let p = geometry.vertices[v as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        geometry.bounds = (lo, hi);
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

    /// Triangle t's point nearest to `p` if it lies within `reach` (m) of p.
    fn near(&self, t: usize, p: [f64; 3], reach: f64) -> Option<Near> {
        let g = &*self.geometry;
        let [a, b, c] = g.faces[t].map(|k| g.vertices[k as usize]);
        // no point of the triangle is nearer than its plane, or than its box: cheap
        // rejections before the closest point
        if vec3::dot(vec3::sub(p, a), g.normals[t]).abs() >= reach
            || (0..3).any(|k| a[k].min(b[k]).min(c[k]) >= p[k] + reach || a[k].max(b[k]).max(c[k]) <= p[k] - reach)
        {
            return None;
        }
        let (q, feature) = closest_on_triangle(p, a, b, c);
        let d = vec3::sub(p, q);
        let len = vec3::norm(d);
        (len < reach).then_some(Near { t, q, feature, d, len })
    }

    /// The touches of a sphere of radius `r` (m) with the triangles `near` it (all within
    /// its reach), in their order.
    ///
    /// On the particles' side of the surface (always, for an open mesh) each normal points
    /// from the triangle's nearest point to the centre (±n_face for a face): overlap r − |d|.
    /// A centre on the wrong side of a closed mesh (pushed through it) is pushed back: each
    /// normal points to the free side (n_face outwards for an obstacle, inwards for a
    /// container; from the centre to an edge or vertex), overlap r + |d|. Which side the
    /// centre is on is the nearest triangles' verdict: the sign of Σ d·n_face over those at
    /// the least distance (on a convex edge seen from outside both say outside). A far face
    /// of a solid thinner than the ball, behind the centre, is then no push through the solid.
    fn touches_of(&self, near: &[Near], r: f64) -> SmallVec<[(Touch, [f64; 3], Feature); 8]> {
        let g = &*self.geometry;
        let wrong_side = match self.side {
            Side::Both => false,
            side => {
                let least = near.iter().fold(f64::INFINITY, |m, c| m.min(c.len));
                let eps = 1e-10 * (g.scale + r + least);
                let verdict: f64 = near
                    .iter()
                    .filter(|c| c.len <= least + eps)
                    .map(|c| vec3::dot(c.d, g.normals[c.t]))
                    .sum();
                if side == Side::Outside {
                    verdict < 0.0
                } else {
                    verdict > 0.0
                }
            }
        };
        near.iter()
            .map(|c| {
                let n = g.normals[c.t];
                let normal = if wrong_side {
                    match (c.feature, self.side) {
                        (Feature::Face, Side::Inside) => vec3::scale(-1.0, n),
                        (Feature::Face, _) => n,
                        _ if c.len > 0.0 => vec3::scale(-1.0 / c.len, c.d),
                        (_, Side::Inside) => vec3::scale(-1.0, n),
                        _ => n,
                    }
                } else if c.feature == Feature::Face && c.len > 0.0 {
                    // exactly ±n: d/|d| would carry the rounding of the foot q
                    if vec3::dot(c.d, n) >= 0.0 {
                        n
                    } else {
                        vec3::scale(-1.0, n)
                    }
                } else if c.len > 0.0 {
                    // an edge or vertex straight above (or below) it, to the coordinates'
                    // precision, is the face's: the normal of a flat patch's seam is then its
                    // plane's, exactly, not tilted by the rounding of where the centre is
                    let off = vec3::sub(c.d, vec3::scale(vec3::dot(c.d, n), n));
                    let eps = 1e-10 * (g.scale + vec3::norm(vec3::add(c.q, c.d)) + r);
                    if vec3::norm(off) <= eps {
                        if vec3::dot(c.d, n) >= 0.0 {
                            n
                        } else {
                            vec3::scale(-1.0, n)
                        }
                    } else {
                        vec3::scale(1.0 / c.len, c.d)
                    }
                } else {
                    // the centre on the surface itself: the face's normal towards the free side
                    if self.side == Side::Inside {
                        vec3::scale(-1.0, n)
                    } else {
                        n
                    }
                };
                let overlap = if wrong_side { r + c.len } else { r - c.len };
                (Touch { normal, overlap }, c.q, c.feature)
            })
            .collect()
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

    /// The touches of [`TriangleMesh::for_each_touch`] with each one's triangle and closest
    /// point (m) and feature, all in the frame the geometry was added in (`p` too).
    fn touches(&self, p: [f64; 3], r: f64, tolerance: f64) -> Found {
        let reach = r + tolerance.max(0.0);
        let (lo, hi) = ([0, 1, 2].map(|k| p[k] - reach), [0, 1, 2].map(|k| p[k] + reach));
        let mut near: SmallVec<[Near; 8]> = SmallVec::new();
        self.geometry.visit(lo, hi, |t| near.extend(self.near(t, p, reach)));
        self.true_features(&mut near, p, r)
    }

    /// The touches of the triangles `near` a sphere at `p` of radius `r` (m), their true
    /// features only (the module's doc, rules 1 and 2), in the order of the triangles. Every
    /// triangle within the reach is in `near` (each around a reported edge or vertex is: it
    /// contains the reported point).
    fn true_features(&self, near: &mut [Near], p: [f64; 3], r: f64) -> Found {
        let mut kept = Found::new();
        if near.is_empty() {
            return kept;
        }
        near.sort_unstable_by_key(|c| c.t);
        let found = self.touches_of(near, r);
        let eps = self.eps(p, r);
        let g = &*self.geometry;
        for (c, (touch, q, feature)) in near.iter().zip(found) {
            let around = match feature {
                Feature::Face => 1,
                Feature::Edge(k) => g.edge_faces[c.t][k as usize] as usize,
                Feature::Vertex(k) => g.valence[g.faces[c.t][k as usize] as usize] as usize,
            };
            if around > 1 {
                // rule 2: every triangle around the edge or vertex has its nearest point there,
                // or one of them has a nearer one and this is no contact of the surface
                let reports = near.iter().filter(|o| vec3::norm(vec3::sub(o.q, q)) <= eps).count();
                // rule 1: seen from another triangle
                let seen = kept.iter().any(|k| vec3::norm(vec3::sub(k.2, q)) <= eps);
                if reports < around || seen {
                    continue;
                }
            }
            kept.push((c.t, touch, q, feature));
        }
        if kept.len() > 1 {
            merge_parallel(&mut kept, r);
        }
        kept
    }

    /// The length below which a point counts as in a face's plane, or two points as one, m:
    /// the relative precision of the coordinates near `p`.
    fn eps(&self, p: [f64; 3], r: f64) -> f64 {
        1e-10 * (self.geometry.scale + vec3::norm(p) + r)
    }

    /// Whether point q lies within `eps` of the plane of one of `faces` (triangle, a point of it).
    fn in_face_plane(&self, faces: &[(usize, [f64; 3])], q: [f64; 3], eps: f64) -> bool {
        faces
            .iter()
            .any(|&(t, qf)| vec3::dot(vec3::sub(q, qf), self.geometry.normals[t]).abs() <= eps)
    }

    /// First time τ ∈ [0, `horizon`] (s) at which a sphere of radius `r` (m) starting at `x`
    /// (m) with velocity `v` (m/s) and constant acceleration `a` (m/s²) meets a triangle while
    /// approaching it, with that triangle's index; `None` if it does not. Faces are met on
    /// the exact parabola (as [`super::toi::toi_plane`]), edges and vertices on its chord
    /// x + (v + ½ a T) τ over the horizon T (the same end point; the parabola bulges at
    /// most ⅛ |a| T² from it, which the end-of-step contacts take up). A sphere that touches a true feature now (the
    /// touches of [`TriangleMesh::for_each_touch`]) and approaches it meets it at 0; one
    /// that slides along a face it touches meets no edge or vertex in that face's plane (the
    /// seams of a flat patch, as rule 2 of the module's doc).
    pub fn toi(&self, x: [f64; 3], v: [f64; 3], a: [f64; 3], r: f64, horizon: f64) -> Option<(f64, usize)> {
        self.toi_within(x, v, a, r, horizon, None).1
    }

    /// [`TriangleMesh::toi`], and whether the sphere comes within `margin` (m) of a true
    /// feature now ([`TriangleMesh::for_each_touch`] with that tolerance finds a touch), from
    /// one traversal of the hierarchy (`None`: not asked, false).
    pub fn toi_within(
        &self,
        x: [f64; 3],
        v: [f64; 3],
        a: [f64; 3],
        r: f64,
        horizon: f64,
        margin: Option<f64>,
    ) -> (bool, Option<(f64, usize)>) {
        if horizon.is_nan() || horizon < 0.0 {
            let touching = margin.is_some_and(|m| !self.touches(self.local(x), r, m).is_empty());
            return (touching, None);
        }
        let (x, v, a) = (self.local(x), self.local_vector(v), self.local_vector(a));
        let margin_len = margin.unwrap_or(0.0).max(0.0);
        let (g, accel) = (&*self.geometry, a);
        let chord = [0, 1, 2].map(|k| v[k] + 0.5 * a[k] * horizon);
        let end = [0, 1, 2].map(|k| x[k] + chord[k] * horizon);
        let bulge = 0.125 * vec3::norm(a) * horizon * horizon;
        let lo = [0, 1, 2].map(|k| x[k].min(end[k]) - r - bulge - margin_len);
        let hi = [0, 1, 2].map(|k| x[k].max(end[k]) + r + bulge + margin_len);
        // one traversal over the path's box: the triangles it may meet, those it touches now
        // and those within the margin (the path's box holds the sphere's)
        let mut candidates: SmallVec<[u32; 16]> = SmallVec::new();
        let mut near: SmallVec<[Near; 8]> = SmallVec::new();
        let mut within: SmallVec<[Near; 8]> = SmallVec::new();
        g.visit(lo, hi, |t| {
            if margin.is_some() {
                within.extend(self.near(t, x, r + margin_len));
            }
            // the path's distance from the plane changes by at most |v·n| T + ½ |a·n| T²: a
            // triangle whose plane stays farther than r is never met
            let n = g.normals[t];
            let s0 = vec3::dot(vec3::sub(x, g.vertices[g.faces[t][0] as usize]), n).abs();
            if s0 - r > vec3::dot(v, n).abs() * horizon + 0.5 * vec3::dot(accel, n).abs() * horizon * horizon {
                return;
            }
            match self.near(t, x, r) {
                Some(c) => near.push(c),
                None => candidates.push(t as u32),
            }
        });
        let touching = margin.is_some() && !self.true_features(&mut within, x, r).is_empty();
        let now = self.true_features(&mut near, x, r);
        if let Some(&(t, ..)) = now.iter().find(|f| vec3::dot(v, f.1.normal) < 0.0) {
            return (touching, Some((0.0, t)));
        }
        let eps = self.eps(x, r);
        let faces: SmallVec<[(usize, [f64; 3]); 8]> = now.iter().filter(|f| f.3 == Feature::Face).map(|f| (f.0, f.2)).collect();
        let mut first: Option<(f64, usize)> = None;
        // (triangles touched now, true features or ghosts, are not met again: handled above)
        for t in candidates.into_iter().map(|t| t as usize) {
            let limit = first.map_or(horizon, |f| f.0);
            let [a, b, c] = g.faces[t].map(|k| g.vertices[k as usize]);
            if let Some((tau, q, feature)) = toi_triangle(Path { x, v, a: accel, chord }, r, [a, b, c], g.normals[t], limit) {
                if feature != Feature::Face && self.in_face_plane(&faces, q, eps) {
                    continue;
                }
                if first.is_none_or(|f| tau < f.0 || (tau == f.0 && t < f.1)) {
                    first = Some((tau, t));
                }
            }
        }
        (touching, first)
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

impl Geometry {
    /// Builds the hierarchy: a median split of the triangles' centroids along the longest
    /// axis of their box, down to leaves of at most [`LEAF`] triangles.
    /// `None`: its buffers cannot be allocated.
    fn build(&mut self) -> Option<()> {
        let centroid = |t: u32| {
            let [a, b, c] = self.faces[t as usize].map(|k| self.vertices[k as usize]);
            [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0)
        };
        let n = self.faces.len();
        let mut centroids: Vec<[f64; 3]> = mesh_buffer(n, n).ok()?;
        centroids.extend((0..n as u32).map(centroid));
        let mut order: Vec<u32> = mesh_buffer(n, n).ok()?;
        order.extend(0..n as u32);
        // exactly as many as `split` pushes: it never grows the buffer
        let mut nodes = mesh_buffer(node_count(n), n).ok()?;
        self.split(&mut order, 0, &centroids, &mut nodes);
        debug_assert_eq!(nodes.len(), node_count(n));
        self.order = order;
        self.nodes = nodes;
        Some(())
    }

    fn split(&self, order: &mut [u32], start: usize, centroids: &[[f64; 3]], nodes: &mut Vec<Node>) {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for &t in order.iter() {
            for &v in &self.faces[t as usize] {
                let p = self.vertices[v as usize];
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let me = nodes.len();
        nodes.push(Node {
            lo: lo.map(f32_below),
            hi: hi.map(f32_above),
            right: 0,
            start: start as u32,
            count: order.len() as u32,
        });
        if order.len() <= LEAF {
            return;
        }
        let (mut clo, mut chi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for &t in order.iter() {
            for k in 0..3 {
                clo[k] = clo[k].min(centroids[t as usize][k]);
                chi[k] = chi[k].max(centroids[t as usize][k]);
            }
        }
        let axis = (0..3)
            .max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b])))
            .unwrap_or(0);
        let mid = order.len() / 2;
        order.select_nth_unstable_by(mid, |&a, &b| {
            centroids[a as usize][axis]
                .total_cmp(&centroids[b as usize][axis])
                .then(a.cmp(&b))
        });
        let (left, right) = order.split_at_mut(mid);
        self.split(left, start, centroids, nodes);
        let r = nodes.len();
        self.split(right, start + mid, centroids, nodes);
        nodes[me].right = r as u32;
        nodes[me].count = 0;
    }

    /// Calls `each(t)` with every triangle whose leaf's box overlaps the box [lo, hi].
    fn visit(&self, lo: [f64; 3], hi: [f64; 3], mut each: impl FnMut(usize)) {
        let mut stack = Stack::new();
        while let Some(k) = stack.pop() {
            let node = self.nodes[k as usize];
            if (0..3).any(|a| f64::from(node.hi[a]) < lo[a] || f64::from(node.lo[a]) > hi[a]) {
                continue;
            }
            if node.count > 0 {
                for &t in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    each(t as usize);
                }
            } else {
                stack.push(node.right);
                stack.push(k + 1);
            }
        }
    }

    /// Calls `each(t)` with every triangle whose leaf's box the ray p + s d (s ≥ 0) meets.
    fn visit_ray(&self, p: [f64; 3], d: [f64; 3], mut each: impl FnMut(usize)) {
        let mut stack = Stack::new();
        while let Some(k) = stack.pop() {
            let node = self.nodes[k as usize];
            // the slab test: the ray's parameter interval inside each axis's slab
            let (mut enter, mut leave) = (0.0_f64, f64::INFINITY);
            for a in 0..3 {
                let (lo, hi) = (f64::from(node.lo[a]), f64::from(node.hi[a]));
                if d[a] == 0.0 {
                    if p[a] < lo || p[a] > hi {
                        leave = -1.0;
                    }
                } else {
                    let (s1, s2) = ((lo - p[a]) / d[a], (hi - p[a]) / d[a]);
                    enter = enter.max(s1.min(s2));
                    leave = leave.min(s1.max(s2));
                }
            }
            if enter > leave {
                continue;
            }
            if node.count > 0 {
                for &t in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    each(t as usize);
                }
            } else {
                stack.push(node.right);
                stack.push(k + 1);
            }
        }
    }
}

/// The nodes a traversal has still to visit, on the stack of the thread (no allocation per
/// query). A median split halves the triangles at each level, so a path from the root is at
/// most ⌈log₂ T⌉ + 1 nodes long (33 for 2³² triangles), and a depth-first traversal holds at
/// most one sibling per level: 64 entries always suffice.
struct Stack {
    nodes: [u32; 64],
    len: usize,
}

impl Stack {
    fn new() -> Self {
        Stack { nodes: [0; 64], len: 1 }
    }

    fn push(&mut self, k: u32) {
        self.nodes[self.len] = k;
        self.len += 1;
    }

    fn pop(&mut self) -> Option<u32> {
        (self.len > 0).then(|| {
            self.len -= 1;
            self.nodes[self.len]
        })
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

/// The point of triangle abc closest to p, and the feature it lies on (Ericson, *Real-Time
/// Collision Detection*, §5.1.5: p's Voronoi region among the vertices, edges and face, from
/// the barycentric coordinates of its projection).
fn closest_on_triangle(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> ([f64; 3], Feature) {
    let ab = vec3::sub(b, a);
    let ac = vec3::sub(c, a);
    let ap = vec3::sub(p, a);
    let d1 = vec3::dot(ab, ap);
    let d2 = vec3::dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(0));
    }
    let bp = vec3::sub(p, b);
    let d3 = vec3::dot(ab, bp);
    let d4 = vec3::dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let s = d1 / (d1 - d3);
        return (vec3::add(a, vec3::scale(s, ab)), Feature::Edge(0));
    }
    let cp = vec3::sub(p, c);
    let d5 = vec3::dot(ab, cp);
    let d6 = vec3::dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let s = d2 / (d2 - d6);
        return (vec3::add(a, vec3::scale(s, ac)), Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (vec3::add(b, vec3::scale(s, vec3::sub(c, b))), Feature::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (vec3::add(a, vec3::add(vec3::scale(v, ab), vec3::scale(w, ac))), Feature::Face)
}

/// First root τ ∈ [0, h] of |d + u τ|² = R² while the distance falls, for |d| ≥ R: the
/// smaller root of a τ² + 2 b τ + c (a = u·u, b = d·u, c = |d|² − R²), in the
/// cancellation-free form c / (−b + √(b² − a c)) of `toi.rs`. At exactly |d| = R and
/// approaching, 0: such a sphere is no touch of [`TriangleMesh::near`] (within R, strictly),
/// and a ball placed exactly on a flat mesh's seam and driven into it fell through between
/// the two.
fn first_approach(d: [f64; 3], u: [f64; 3], radius: f64, h: f64) -> Option<f64> {
    let a = vec3::dot(u, u);
    let b = vec3::dot(d, u);
    let len = vec3::norm(d);
    let c = (len - radius) * (len + radius);
    if c < 0.0 || b >= 0.0 || a == 0.0 {
        return None;
    }
    if c == 0.0 {
        return Some(0.0);
    }
    let disc = b * b - a * c;
    if disc <= 0.0 {
        return None;
    }
    let tau = c / (-b + disc.sqrt());
    (tau <= h).then_some(tau)
}

/// A sphere's motion over the horizon: x + v τ + ½ a τ², and the chord's velocity.
#[derive(Debug, Clone, Copy)]
struct Path {
    x: [f64; 3],
    v: [f64; 3],
    a: [f64; 3],
    chord: [f64; 3],
}

/// First time τ ∈ [0, h] at which a sphere of radius r on `path` comes within r of
/// triangle `tri` (unit normal `n`) while approaching it: the earliest of its face (the
/// plane at distance r on the parabola, the foot of the centre inside the triangle), on the
/// chord x + chord τ its edges (the
/// cylinder of radius r about each edge's line, the foot within the edge) and its vertices
/// (the sphere of radius r about each), with the point met and its feature; `None` if it
/// misses (the caller handles a sphere that touches it now).
fn toi_triangle(path: Path, r: f64, tri: [[f64; 3]; 3], n: [f64; 3], h: f64) -> Option<(f64, [f64; 3], Feature)> {
    let [a, b, c] = tri;
    let Path {
        x,
        v: v0,
        a: accel,
        chord: v,
    } = path;
    let mut first: Option<(f64, [f64; 3], Feature)> = None;
    let mut take = |tau: f64, q: [f64; 3], feature: Feature| {
        if (0.0..=h).contains(&tau) && first.is_none_or(|f| tau < f.0) {
            first = Some((tau, q, feature));
        }
    };
    // the face: the parabola's distance from its plane reaches r on the side it starts on
    let side = if vec3::dot(vec3::sub(x, a), n) >= 0.0 {
        n
    } else {
        vec3::scale(-1.0, n)
    };
    if let Some(tau) = toi_half_space(x, v0, accel, r, a, side, h) {
        let p = vec3::parabola(x, v0, accel, tau);
        let (q, feature) = closest_on_triangle(p, a, b, c);
        if feature == Feature::Face {
            take(tau, q, feature);
        }
    }
    // the edges: the centre's distance from the edge's line, the parts across the edge
    for (k, (p0, p1)) in [(a, b), (b, c), (c, a)].into_iter().enumerate() {
        let e = vec3::sub(p1, p0);
        let ee = vec3::dot(e, e);
        let d = vec3::sub(x, p0);
        let across = |w: [f64; 3]| vec3::sub(w, vec3::scale(vec3::dot(w, e) / ee, e));
        if let Some(tau) = first_approach(across(d), across(v), r, h) {
            let along = vec3::dot(vec3::add(d, vec3::scale(tau, v)), e) / ee;
            if (0.0..=1.0).contains(&along) {
                take(tau, vec3::add(p0, vec3::scale(along, e)), Feature::Edge(k as u8));
            }
        }
    }
    for (k, p0) in [a, b, c].into_iter().enumerate() {
        if let Some(tau) = first_approach(vec3::sub(x, p0), v, r, h) {
            take(tau, p0, Feature::Vertex(k as u8));
        }
    }
    first
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

#[cfg(test)]
#[path = "tests/mesh.rs"]
mod tests;
