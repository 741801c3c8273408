//! Continuous detection against a triangle mesh: the first time a sphere on a parabola meets a
//! triangle while approaching it, faces on the parabola, edges and vertices on its chord over
//! the horizon (each the first root of a quadratic, as in `toi.rs`); times in s, lengths in m.

use super::features::{closest_on_triangle, Near};
use super::{Feature, TriangleMesh};
use crate::collide::roots::toi_half_space;
use crate::vec3;
use smallvec::SmallVec;

/// The most planes of flat nodes passed by their feet that [`TriangleMesh::toi_within`]'s
/// first search notes (a floor has one; more: the second search).
const PASSED: usize = 4;

impl TriangleMesh {
    /// Whether point q lies within `eps` of the plane of one of `faces` (triangle, a point of it).
    fn in_face_plane(&self, faces: &[(usize, [f64; 3])], q: [f64; 3], eps: f64) -> bool {
        faces
            .iter()
            .any(|&(t, qf)| vec3::dot(vec3::sub(q, qf), self.geometry.normals[t]).abs() <= eps)
    }

    /// First time τ ∈ [0, `horizon`] (s) at which a sphere of radius `r` (m) starting at `x`
    /// (m) with velocity `v` (m/s) and constant acceleration `a` (m/s²) meets a triangle while
    /// approaching it, with that triangle's index; `None` if it does not. Faces are met on
    /// the exact parabola (as [`crate::collide::toi::toi_plane`]), edges and vertices on its chord
    /// x + (v + ½ a T) τ over the horizon T (the same end point; the parabola bulges at
    /// most ⅛ |a| T² from it, which the end-of-step contacts take up). A sphere that touches a true feature now (the
    /// touches of [`TriangleMesh::for_each_touch`]) and approaches it meets it at 0; one
    /// that slides along a face it touches meets no edge or vertex in that face's plane (the
    /// seams of a flat patch, as rule 2 of the mesh module's doc).
    pub fn toi(&self, x: [f64; 3], v: [f64; 3], a: [f64; 3], r: f64, horizon: f64) -> Option<(f64, usize)> {
        self.toi_within(x, v, a, r, horizon, None).1
    }

    /// [`TriangleMesh::toi`], and whether the sphere comes within `margin` (m) of a true
    /// feature now ([`TriangleMesh::for_each_touch`] with that tolerance finds a touch)
    /// (`None`: not asked, false).
    pub fn toi_within(
        &self,
        x: [f64; 3],
        v: [f64; 3],
        a: [f64; 3],
        r: f64,
        horizon: f64,
        margin: Option<f64>,
    ) -> (bool, Option<(f64, usize)>) {
        self.toi_search(x, v, a, r, horizon, margin, true)
    }

    /// [`TriangleMesh::toi_within`] with every triangle within reach searched, flat nodes
    /// too (the tests' reference for what the flat nodes leave out).
    #[cfg(test)]
    pub(super) fn toi_everywhere(
        &self,
        x: [f64; 3],
        v: [f64; 3],
        a: [f64; 3],
        r: f64,
        horizon: f64,
        margin: Option<f64>,
    ) -> (bool, Option<(f64, usize)>) {
        self.toi_search(x, v, a, r, horizon, margin, false)
    }

    /// [`TriangleMesh::toi_within`], past the flat nodes that cannot touch or be met when
    /// `past_flat` (`flat.rs`), else over every triangle in reach.
    #[allow(clippy::too_many_arguments)]
    fn toi_search(
        &self,
        x: [f64; 3],
        v: [f64; 3],
        a: [f64; 3],
        r: f64,
        horizon: f64,
        margin: Option<f64>,
        past_flat: bool,
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
        // the triangles the path may meet: not those it touches now, nor those whose plane it
        // never reaches, nor those of flat nodes it comes nowhere near (`flat.rs`)
        let candidate = |t: usize, within: bool| {
            // the path's distance from the plane changes by at most |v·n| T + ½ |a·n| T²: a
            // triangle whose plane stays farther than r is never met
            let n = g.normals[t];
            let s0 = vec3::dot(vec3::sub(x, g.vertices[g.faces[t][0] as usize]), n).abs();
            let reached = s0 - r <= vec3::dot(v, n).abs() * horizon + 0.5 * vec3::dot(accel, n).abs() * horizon * horizon;
            (reached && !within).then_some(t as u32)
        };
        let mut candidates: SmallVec<[u32; 16]> = SmallVec::new();
        let eps = self.eps(x, r);
        let (touching, now) = if past_flat {
            // one search for both: what it touches now and within the margin (past the flat
            // nodes that do not hold its foot) and what its path may meet. First past the flat
            // nodes its path's feet do not cross, too: of those it could come within reach of,
            // the planes are noted, and the search holds where it touches a face of each now
            // (a sphere sliding on a face meets no edge or vertex of its plane, and a face of
            // the plane only where the path's foot lies in it: `Flat::foot_path_near`). A
            // sphere resting on a floor of small triangles so looks at those under its foot,
            // not at every one within its reach of the plane (√(2 r δ) at an overlap δ).
            // Else, or where the planes are too many to note, the search again past the flat
            // nodes it may come within reach of.
            let (reach, margin8) = (r + margin_len, 8.0 * eps);
            let mut held = None;
            for feet_only in [true, false] {
                candidates.clear();
                let mut near: SmallVec<[Near; 8]> = SmallVec::new();
                let mut passed: SmallVec<[usize; PASSED]> = SmallVec::new();
                let mut too_many = false;
                g.visit_past_flat(
                    lo,
                    hi,
                    |flat| {
                        if flat.holds_foot(x, reach, margin8) {
                            return true;
                        }
                        if !feet_only {
                            return flat.near_path((x, end), bulge, r, margin8);
                        }
                        if flat.foot_path_near((x, end), bulge, margin8) {
                            return true;
                        }
                        if flat.near_path((x, end), bulge, r, margin8) {
                            let t = flat.plane;
                            let noted = passed
                                .iter()
                                .any(|&p| g.same_plane(p, g.normals[t], g.vertices[g.faces[t][0] as usize]));
                            if !noted {
                                too_many |= passed.len() == PASSED;
                                if !too_many {
                                    passed.push(t);
                                }
                            }
                        }
                        false
                    },
                    |t| {
                        let found = self.near(t, x, reach);
                        candidates.extend(candidate(t, found.is_some_and(|c| c.is_within(r))));
                        near.extend(found);
                    },
                );
                let (within, now) = self.within_and_now(&mut near, x, r);
                let approached = now.iter().any(|f| vec3::dot(v, f.1.normal) < 0.0);
                let face_of = |p: usize| {
                    now.iter()
                        .any(|f| f.3 == Feature::Face && g.same_plane(p, g.normals[f.0], g.vertices[g.faces[f.0][0] as usize]))
                };
                if !feet_only || approached || (!too_many && passed.iter().all(|&p| face_of(p))) {
                    held = Some((margin.is_some() && within, now));
                    break;
                }
            }
            held.expect("the second search always holds")
        } else {
            // (the tests' reference: every triangle within reach)
            g.visit(lo, hi, |t| candidates.extend(candidate(t, self.near(t, x, r).is_some())));
            (
                margin.is_some() && !self.touches_everywhere(x, r, margin_len).is_empty(),
                self.touches_everywhere(x, r, 0.0),
            )
        };
        if let Some(&(t, ..)) = now.iter().find(|f| vec3::dot(v, f.1.normal) < 0.0) {
            return (touching, Some((0.0, t)));
        }
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
