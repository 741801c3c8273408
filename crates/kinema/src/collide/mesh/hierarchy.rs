//! The bounding-volume hierarchy of a triangle mesh: a median split of the triangles'
//! centroids along the longest axis of their box, down to leaves of at most four triangles,
//! each node's box kept in f32 and rounded outwards, and its flat nodes (`flat.rs`); and its
//! traversals, over a box (past the flat nodes that cannot touch: [`Flat`]), and along a ray,
//! on a stack of the thread.

use super::flat::{FLAT, FLAT_NONE};
use super::{mesh_buffer, Geometry};
use crate::simd::prefetch;
use crate::vec3;
use smallvec::SmallVec;

/// A node of the hierarchy: a box and either two children (the left one follows the node,
/// the right one at `right`) or `count` triangles of `order` from `start`. The box is kept in
/// f32, rounded outwards (it only ever holds more than the triangles): 44 bytes a node
/// rather than 68, and a traversal of a large mesh is bound by the nodes it loads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Node {
    lo: [f32; 3],
    hi: [f32; 3],
    right: u32,
    start: u32,
    count: u32,
    /// A triangle of the one plane of a flat node (`flat.rs`), or [`FLAT_NONE`].
    plane: u32,
}

impl Node {
    /// Whether it is a flat node (`flat.rs`).
    #[cfg(test)]
    pub(super) fn is_flat(&self) -> bool {
        self.plane != FLAT_NONE
    }
}

/// A flat node as the traversals' tests see it: its plane (unit normal `n`, a point `a`) and
/// its box [lo, hi] (m).
pub(super) struct Flat {
    /// The triangle whose plane is the node's.
    pub(super) plane: usize,
    n: [f64; 3],
    a: [f64; 3],
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Flat {
    /// Whether a sphere at `p` within `reach` (m) can touch a triangle of the node, to within
    /// `margin` (m): the foot of p on the plane lies in the box, and p within reach of the
    /// plane (`flat.rs`: a triangle inside a flat patch touches only where it holds the foot).
    pub(super) fn holds_foot(&self, p: [f64; 3], reach: f64, margin: f64) -> bool {
        // the normals of a flat node's triangles are its plane's to FLAT: over `reach` their
        // feet lie that much apart
        let margin = margin + 2.0 * FLAT * reach;
        let s = vec3::dot(self.n, vec3::sub(p, self.a));
        let foot = vec3::sub(p, vec3::scale(s, self.n));
        s.abs() < reach + margin && (0..3).all(|k| self.hi[k] + margin >= foot[k] && self.lo[k] - margin <= foot[k])
    }

    /// Whether the chord from `x` to `end` (m), or a path within `bulge` (m) of it, comes
    /// within `reach` (m) of the node's part of the plane, to within `margin` (m).
    ///
    /// A point q of the plane lies |c − q|² = s² + |f − q|² from a centre c at signed distance
    /// s from the plane with foot f. Along the chord s is linear, so its least |s| is 0 if the
    /// chord crosses the plane, else the smaller of its ends'; a path within `bulge` of the
    /// chord comes within `reach` of q only if the chord comes within `reach` + `bulge` of it,
    /// that is only if q lies within ρ = √((reach + bulge)² − s_min²) of the chord's feet,
    /// which run along the segment between the feet of its ends.
    pub(super) fn near_path(&self, (x, end): ([f64; 3], [f64; 3]), bulge: f64, reach: f64, margin: f64) -> bool {
        let reach = reach + bulge;
        let margin = margin + 2.0 * FLAT * (reach + vec3::norm(vec3::sub(end, x)));
        let (s0, s1) = (
            vec3::dot(self.n, vec3::sub(x, self.a)),
            vec3::dot(self.n, vec3::sub(end, self.a)),
        );
        let least = if s0 * s1 <= 0.0 { 0.0 } else { s0.abs().min(s1.abs()) };
        if least >= reach + margin {
            return false;
        }
        let rho = (reach * reach - least * least).max(0.0).sqrt() + margin;
        let (f0, f1) = (vec3::sub(x, vec3::scale(s0, self.n)), vec3::sub(end, vec3::scale(s1, self.n)));
        (0..3).all(|k| self.hi[k] + rho >= f0[k].min(f1[k]) && self.lo[k] - rho <= f0[k].max(f1[k]))
    }
}

impl Flat {
    /// Whether the feet on the node's plane of a path within `bulge` (m) of the chord from
    /// `x` to `end` (m) come within `margin` (m) of the node's box: the segment between the
    /// feet of the chord's ends, widened by `bulge` (a foot moves no more than its point).
    /// Where the sphere touches a face of this plane now, a triangle of the node can be met
    /// first only at its face, with the path's foot inside it (`TriangleMesh::toi_within`).
    pub(super) fn foot_path_near(&self, (x, end): ([f64; 3], [f64; 3]), bulge: f64, margin: f64) -> bool {
        let rho = bulge + margin + 2.0 * FLAT * vec3::norm(vec3::sub(end, x));
        let (s0, s1) = (
            vec3::dot(self.n, vec3::sub(x, self.a)),
            vec3::dot(self.n, vec3::sub(end, self.a)),
        );
        let (f0, f1) = (vec3::sub(x, vec3::scale(s0, self.n)), vec3::sub(end, vec3::scale(s1, self.n)));
        (0..3).all(|k| self.hi[k] + rho >= f0[k].min(f1[k]) && self.lo[k] - rho <= f0[k].max(f1[k]))
    }
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

/// The most triangles a leaf of the hierarchy holds.
const LEAF: usize = 4;

/// How many nodes the hierarchy of `n` triangles has (median splits down to leaves of at
/// most [`LEAF`]), so that its buffer is allocated once, fallibly. A level holds at most two
/// sizes of subtree (⌊m/2⌋ and ⌈m/2⌉ of the level above's).
pub(super) fn node_count(n: usize) -> usize {
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

impl Geometry {
    /// Builds the hierarchy: a median split of the triangles' centroids along the longest
    /// axis of their box, down to leaves of at most [`LEAF`] triangles.
    /// `None`: its buffers cannot be allocated.
    pub(super) fn build(&mut self) -> Option<()> {
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
        drop(centroids); // (before the flat nodes' buffers: the build's peak stays the split's)
        self.mark_flat()
    }

    /// Marks the flat nodes (`flat.rs`): a leaf whose triangles all lie inside flat patches of
    /// one plane, a parent of two flat nodes of one plane; children come after their parent,
    /// so one pass from the last node up, and one down that gives a flat subtree its top's
    /// triangle. `None`: a buffer cannot be allocated.
    fn mark_flat(&mut self) -> Option<()> {
        let inside = self.inside_flat_patches()?;
        for k in (0..self.nodes.len()).rev() {
            let node = self.nodes[k];
            let plane = if node.count > 0 {
                let leaf = &self.order[node.start as usize..(node.start + node.count) as usize];
                let t0 = leaf[0] as usize;
                let one = leaf.iter().all(|&t| {
                    let t = t as usize;
                    inside[t] && self.same_plane(t0, self.normals[t], self.vertices[self.faces[t][0] as usize])
                });
                if one {
                    t0 as u32
                } else {
                    FLAT_NONE
                }
            } else {
                let (l, r) = (self.nodes[k + 1].plane, self.nodes[node.right as usize].plane);
                let one = l != FLAT_NONE && r != FLAT_NONE && {
                    let r = r as usize;
                    self.same_plane(l as usize, self.normals[r], self.vertices[self.faces[r][0] as usize])
                };
                if one {
                    l
                } else {
                    FLAT_NONE
                }
            };
            self.nodes[k].plane = plane;
        }
        // one triangle for the plane of a whole flat subtree, its top's: a search down it
        // reads the same plane at every level, which stays in the cache
        for k in 0..self.nodes.len() {
            let node = self.nodes[k];
            if node.plane != FLAT_NONE && node.count == 0 {
                for child in [k + 1, node.right as usize] {
                    self.nodes[child].plane = node.plane;
                }
            }
        }
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
            plane: FLAT_NONE,
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

    /// Calls `each(t)` with every triangle whose leaf's box overlaps the box [lo, hi] (the
    /// tests' reference for the searches past the flat nodes).
    pub(super) fn visit(&self, lo: [f64; 3], hi: [f64; 3], each: impl FnMut(usize)) {
        self.visit_past_flat(lo, hi, |_| true, each);
    }

    /// Calls `each(t)` with every triangle whose leaf's box overlaps the box [lo, hi], but
    /// those of the flat nodes (`flat.rs`) that `keep` turns down.
    pub(super) fn visit_past_flat(
        &self,
        lo: [f64; 3],
        hi: [f64; 3],
        mut keep: impl FnMut(&Flat) -> bool,
        mut each: impl FnMut(usize),
    ) {
        let mut stack = Stack::new();
        while let Some(k) = stack.pop() {
            let node = self.nodes[k as usize];
            if (0..3).any(|a| f64::from(node.hi[a]) < lo[a] || f64::from(node.lo[a]) > hi[a]) {
                continue;
            }
            if node.plane != FLAT_NONE {
                let t = node.plane as usize;
                let flat = Flat {
                    plane: t,
                    n: self.normals[t],
                    a: self.vertices[self.faces[t][0] as usize],
                    lo: node.lo.map(f64::from),
                    hi: node.hi.map(f64::from),
                };
                if !keep(&flat) {
                    continue;
                }
            }
            if node.count > 0 {
                let leaf = &self.order[node.start as usize..(node.start + node.count) as usize];
                // (its triangles' corners and normals asked for at once: each `each` waits on
                // them otherwise, one triangle after the other; their vertices too made no
                // difference)
                for &t in leaf {
                    prefetch(&self.faces[t as usize]);
                    prefetch(&self.normals[t as usize]);
                }
                for &t in leaf {
                    each(t as usize);
                }
            } else {
                // (the right child is tested only after the left one's subtree, and in a
                // large mesh it lies far from its parent: its line asked for now)
                prefetch(&self.nodes[node.right as usize]);
                stack.push(node.right);
                stack.push(k + 1);
            }
        }
    }

    /// Calls `each(t)` with every triangle whose leaf's box the ray p + s d (s ≥ 0) meets.
    pub(super) fn visit_ray(&self, p: [f64; 3], d: [f64; 3], mut each: impl FnMut(usize)) {
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
