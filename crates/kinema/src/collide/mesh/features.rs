//! The contacts of a sphere with a triangle mesh: each triangle's closest point (Ericson), and
//! the rules of the mesh module's doc that keep a surface's true contacts only (one contact
//! for a point seen from several triangles, an edge or vertex only in its Voronoi region of the
//! whole surface, touches within 10° of each other merged).

use super::{Feature, Geometry, Side, TriangleMesh};
use crate::collide::surface::Touch;
use crate::vec3;
use smallvec::SmallVec;
use std::sync::{Arc, Weak};

/// Contacts whose normals differ by less than this merge (rule 3 of the mesh module's doc): cos 10°.
const PARALLEL: f64 = 0.984_807_753_012_208;

/// Rule 3 of the mesh module's doc: the touches whose normals lie within 10° of a deeper one's are
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
pub(super) type Found = SmallVec<[(usize, Touch, [f64; 3], Feature); 4]>;

/// How far, as a fraction of the sphere's radius, a centre may move along each axis from the
/// point a [`NearCache`] was gathered at for its triangles to answer (1/1000: a ball resting
/// on a floor moves far less in a step; a ball that moves more gathers again).
const NEAR_SLACK: f64 = 1e-3;

/// The triangles one search of the hierarchy found around a point, kept so that the next
/// searches for a sphere near that point ask them alone ([`TriangleMesh::touches_near`]):
/// a ball resting on a floor of 10⁶ triangles was searched for from the root at the end of
/// every step (issue 51). Empty (the default) until a search fills it; it answers only for
/// the geometry it was gathered on.
///
/// **Why the answer is the same, bit for bit.** The search past the flat nodes
/// ([`TriangleMesh::touches`]) finds the same touches as the search of every triangle within
/// reach ([`TriangleMesh::touches_everywhere`], `flat.rs`): the triangles it leaves out lie
/// inside flat patches away from the foot and give no contact, however many of them are
/// asked. A cache gathers, around `at`, a search past the flat nodes widened so that it holds
/// every triangle the search from any centre p within `slack` of `at` (each axis) would ask,
/// with any r + tolerance up to `reach`: the box and the reach grown by 2·slack (p lies at
/// most √3·slack from `at`, and neither p's distance to a plane nor its foot moves more than
/// p), the flat nodes' margin by the same plus the largest rounding tolerance such a search
/// uses. So the triangles it asks lie between those of the search from p and those of the
/// search of every triangle: the same touches.
#[derive(Debug, Clone, Default)]
pub struct NearCache {
    /// The geometry searched (none while nothing is kept): held weakly, so that its
    /// address is never another geometry's while the cache lives.
    pub(super) geometry: Weak<Geometry>,
    /// The point searched around, in the mesh's own frame, m.
    pub(super) at: [f64; 3],
    /// How far from `at` along each axis a centre may lie, m.
    pub(super) slack: f64,
    /// The largest r + tolerance the triangles answer for, m.
    pub(super) reach: f64,
    /// The triangles, in ascending order.
    pub(super) triangles: SmallVec<[u32; 8]>,
}

/// A triangle `t` near a point p: its nearest point q, the feature q lies on, d = p − q and |d|.
#[derive(Debug, Clone, Copy)]
pub(super) struct Near {
    t: usize,
    q: [f64; 3],
    feature: Feature,
    d: [f64; 3],
    len: f64,
}

impl Near {
    /// Whether its nearest point lies within `r` (m) of p: what [`TriangleMesh::near`] with
    /// reach `r` finds.
    pub(super) fn is_within(&self, r: f64) -> bool {
        self.len < r
    }
}

impl TriangleMesh {
    /// Triangle t's point nearest to `p` if it lies within `reach` (m) of p.
    pub(super) fn near(&self, t: usize, p: [f64; 3], reach: f64) -> Option<Near> {
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
    pub(super) fn touches_of(&self, near: &[Near], r: f64) -> SmallVec<[(Touch, [f64; 3], Feature); 8]> {
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
                    // exactly ±n: d/|d| would keep the rounding of the foot q
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

    /// The touches of [`TriangleMesh::for_each_touch`] with each one's triangle and closest
    /// point (m) and feature, all in the frame the geometry was added in (`p` too).
    pub(super) fn touches(&self, p: [f64; 3], r: f64, tolerance: f64) -> Found {
        let reach = r + tolerance.max(0.0);
        let mut near: SmallVec<[Near; 8]> = SmallVec::new();
        // (past the flat nodes that give no contact: `flat.rs`; the margin is many times the
        // rules' own tolerance)
        let margin = 8.0 * self.eps(p, r);
        let (lo, hi) = (p.map(|c| c - reach), p.map(|c| c + reach));
        self.geometry.visit_past_flat(
            lo,
            hi,
            |flat| flat.holds_foot(p, reach, margin),
            |t| near.extend(self.near(t, p, reach)),
        );
        self.true_features(&mut near, p, r)
    }

    /// [`TriangleMesh::touches`] from the triangles `cache` keeps where they answer for `p`
    /// (the mesh's frame), `r` and `tolerance` (m), else gathered again around `p` first
    /// ([`NearCache`]): the same touches, bit for bit.
    pub(super) fn touches_near(&self, p: [f64; 3], r: f64, tolerance: f64, cache: &mut NearCache) -> Found {
        let reach = r + tolerance.max(0.0);
        let answers = std::ptr::eq(cache.geometry.as_ptr(), Arc::as_ptr(&self.geometry))
            && reach <= cache.reach
            && (0..3).all(|k| (p[k] - cache.at[k]).abs() <= cache.slack);
        if !answers {
            self.gather(p, reach, NEAR_SLACK * r, cache);
        }
        let mut near: SmallVec<[Near; 8]> = cache
            .triangles
            .iter()
            .filter_map(|&t| self.near(t as usize, p, reach))
            .collect();
        self.true_features(&mut near, p, r)
    }

    /// Fills `cache` with the triangles around `at` (the mesh's frame) that answer for every
    /// centre within `slack` (m) of it along each axis and every r + tolerance up to `reach`
    /// (m): [`NearCache`]'s widened search.
    fn gather(&self, at: [f64; 3], reach: f64, slack: f64, cache: &mut NearCache) {
        let g = &*self.geometry;
        // how far a centre, its distance to a plane and its foot move within the slack (√3·slack,
        // doubled), with the largest rounding tolerance `eps` of a search from there (r ≤ reach)
        // twice over: the widened reach and the flat nodes' margin, 8·eps beyond it
        let rounding = 1e-10 * (g.scale + vec3::norm(at) + 2.0 * slack + reach);
        let wide = 2.0 * slack + 2.0 * rounding;
        let (big, margin) = (reach + wide, 8.0 * rounding + wide);
        cache.triangles.clear();
        let (lo, hi) = (at.map(|c| c - big), at.map(|c| c + big));
        let triangles = &mut cache.triangles;
        g.visit_past_flat(
            lo,
            hi,
            |flat| flat.holds_foot(at, big, margin),
            |t| {
                if self.near(t, at, big).is_some() {
                    triangles.push(t as u32);
                }
            },
        );
        triangles.sort_unstable();
        *cache = NearCache {
            geometry: Arc::downgrade(&self.geometry),
            at,
            slack,
            reach,
            triangles: std::mem::take(triangles),
        };
    }

    /// Of the triangles `near` a sphere at `p` of radius `r` (m), all those within some reach
    /// ≥ r (and maybe more that give no contact: `flat.rs`): whether it touches one of them
    /// (within that reach), and its touches within 0. (The triangles within r are those of
    /// `near` nearer than r: a search within r passes the flat nodes by their foot alone,
    /// whatever the reach.)
    pub(super) fn within_and_now(&self, near: &mut SmallVec<[Near; 8]>, p: [f64; 3], r: f64) -> (bool, Found) {
        let mut now: SmallVec<[Near; 8]> = near.iter().filter(|c| c.is_within(r)).copied().collect();
        let now = self.true_features(&mut now, p, r);
        (!self.true_features(near, p, r).is_empty(), now)
    }

    /// [`TriangleMesh::touches`] searching every triangle within reach, flat nodes too (the
    /// tests' reference for what the flat nodes leave out).
    pub(super) fn touches_everywhere(&self, p: [f64; 3], r: f64, tolerance: f64) -> Found {
        let reach = r + tolerance.max(0.0);
        let (lo, hi) = ([0, 1, 2].map(|k| p[k] - reach), [0, 1, 2].map(|k| p[k] + reach));
        let mut near: SmallVec<[Near; 8]> = SmallVec::new();
        self.geometry.visit(lo, hi, |t| near.extend(self.near(t, p, reach)));
        self.true_features(&mut near, p, r)
    }

    /// The touches of the triangles `near` a sphere at `p` of radius `r` (m), their true
    /// features only (the mesh module's doc, rules 1 and 2), in the order of the triangles. Every
    /// triangle within the reach is in `near` (each around a reported edge or vertex is: it
    /// contains the reported point).
    pub(super) fn true_features(&self, near: &mut [Near], p: [f64; 3], r: f64) -> Found {
        let mut kept = Found::new();
        if near.is_empty() {
            return kept;
        }
        near.sort_unstable_by_key(|c| c.t);
        let found = self.touches_of(near, r);
        let eps = self.eps(p, r);
        let g = &*self.geometry;
        for (c, (touch, q, feature)) in near.iter().zip(found) {
            // (a point of an edge at one of its ends, to the coordinates' precision, is that
            // vertex: its region's boundary, where the closest point's test may say either;
            // as an edge only the two triangles along it would be asked, and a ball beside a
            // vertex of a flat floor would touch it, tilted)
            let feature = match feature {
                Feature::Edge(k) => {
                    let ends = [k as usize, (k as usize + 1) % 3];
                    let at = |e: usize| vec3::norm(vec3::sub(q, g.vertices[g.faces[c.t][e] as usize])) <= eps;
                    ends.into_iter()
                        .find(|&e| at(e))
                        .map_or(feature, |e| Feature::Vertex(e as u8))
                }
                other => other,
            };
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
    pub(super) fn eps(&self, p: [f64; 3], r: f64) -> f64 {
        1e-10 * (self.geometry.scale + vec3::norm(p) + r)
    }
}

/// The point of triangle abc closest to p, and the feature it lies on (Ericson, *Real-Time
/// Collision Detection*, §5.1.5: p's Voronoi region among the vertices, edges and face, from
/// the barycentric coordinates of its projection).
pub(super) fn closest_on_triangle(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> ([f64; 3], Feature) {
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
