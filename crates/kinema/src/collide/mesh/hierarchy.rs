//! The bounding-volume hierarchy of a triangle mesh: a median split of the triangles'
//! centroids along the longest axis of their box, down to leaves of at most four triangles,
//! each node's box kept in f32 and rounded outwards; and its traversals, over a box and along
//! a ray, on a stack of the thread.

use super::{mesh_buffer, Geometry};
use smallvec::SmallVec;

/// A node of the hierarchy: a box and either two children (the left one follows the node,
/// the right one at `right`) or `count` triangles of `order` from `start`. The box is kept in
/// f32, rounded outwards (it only ever holds more than the triangles): 40 bytes a node
/// rather than 64, and a traversal of a large mesh is bound by the nodes it loads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Node {
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
    pub(super) fn visit(&self, lo: [f64; 3], hi: [f64; 3], mut each: impl FnMut(usize)) {
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
