//! The flat patches of a mesh, so that a sphere over a floor of a million small triangles
//! costs what it costs over one (issue 51).
//!
//! **Why a flat patch needs only its foot.** A sphere's contacts with a mesh are the surface's
//! true features within reach (the mesh module's doc): its face contacts, and the edges and
//! vertices where *every* triangle around has its nearest point. Call a triangle *inside a
//! flat patch* when every triangle around each of its three vertices lies in its plane and
//! the vertex's fan closes (no border or non-manifold edge there): a neighbourhood of the
//! triangle, edges and corners included, is then a piece of one plane P (covered once, or
//! more than once where a fan winds round twice: either way every direction from the vertex
//! is covered). On P the distance to the centre p is smallest at one point, the foot f = p − s n
//! (s = n·(p − a)), and grows away from it. So a point q of such a triangle other than f is
//! no contact: if the triangle's nearest point q lies on an edge or a vertex, the triangle
//! around it on the side towards f has a nearer point, and rule 2 drops q; and the triangle
//! has a face contact only if f lies in it. Such a triangle gives a contact only where it
//! holds f (to the rules' tolerance `eps`).
//!
//! **In the hierarchy.** A node whose triangles all lie inside flat patches of one plane (a
//! *flat node*, [`FLAT_NONE`] otherwise) keeps a triangle of that plane. A query that meets
//! it works out the foot on that plane and goes on into the node only if the foot lies
//! within its box (widened by a margin far above the rounding, `TriangleMesh::touches`): over
//! a floor of 1.6 mm triangles the search goes down one path of the tree to the few
//! triangles around the foot, not to the ~2,000 under a 3 cm ball. The contacts are those of
//! the search that visits every triangle, bit for bit: the triangles left out are exactly
//! those that give none (`tests/mesh.rs` compares the two searches at random points over
//! floors, terraces, cubes and spheres).

use super::Geometry;
use crate::vec3;

/// Two unit normals are one plane's when |n₁ × n₂| is at most this (1e-12 rad), and a vertex
/// lies in a plane when it is within this times the mesh's scale: a patch of a generated
/// floor is flat to the last bit, and a patch noisier than this is searched triangle by
/// triangle, as before.
pub(super) const FLAT: f64 = 1e-12;

/// A node that is no flat node.
pub(super) const FLAT_NONE: u32 = u32::MAX;

impl Geometry {
    /// Whether normal `n` and point `a` (a vertex of triangle `t`) lie in triangle `t`'s plane.
    pub(super) fn same_plane(&self, t: usize, n: [f64; 3], a: [f64; 3]) -> bool {
        let m = self.normals[t];
        let b = self.vertices[self.faces[t][0] as usize];
        vec3::dot(m, n) > 0.0
            && vec3::norm(vec3::cross(m, n)) <= FLAT
            && vec3::dot(m, vec3::sub(a, b)).abs() <= FLAT * self.scale.max(f64::MIN_POSITIVE)
    }

    /// For each triangle, whether it lies inside a flat patch (the module's doc); `None`: the
    /// buffers cannot be allocated.
    pub(super) fn inside_flat_patches(&self) -> Option<Vec<bool>> {
        let (nv, nf) = (self.vertices.len(), self.faces.len());
        // each vertex: a triangle of its fan, and whether the fan is flat so far (5 B a vertex)
        let mut first: Vec<u32> = super::mesh_buffer(nv, nf).ok()?;
        first.resize(nv, u32::MAX);
        let mut flat: Vec<bool> = super::mesh_buffer(nv, nf).ok()?;
        flat.resize(nv, true);
        for (t, f) in self.faces.iter().enumerate() {
            for k in 0..3 {
                let v = f[k] as usize;
                if self.edge_faces[t][k] != 2 {
                    // a border or non-manifold edge: neither end's fan closes
                    flat[v] = false;
                    flat[f[(k + 1) % 3] as usize] = false;
                }
                if first[v] == u32::MAX {
                    first[v] = t as u32;
                } else if flat[v] && !self.same_plane(first[v] as usize, self.normals[t], self.vertices[v]) {
                    flat[v] = false;
                }
            }
        }
        let mut inside: Vec<bool> = super::mesh_buffer(nf, nf).ok()?;
        inside.extend(self.faces.iter().map(|f| f.iter().all(|&v| flat[v as usize])));
        Some(inside)
    }
}
