//! Static colliders: planes, box containers, sphere obstacles and triangle meshes
//! ([`super::mesh`]), and their contacts.
//!
//! A collider has infinite mass. It stays where it was added unless it is given a prescribed
//! motion ([`super::motion`]): then the collide stage places it at each step
//! ([`Collider::posed`]) and its [`Surface`] holds the velocity field of its surface, so
//! that a particle's relative velocity against it is u_n = (v_i − u(x))·n, u(x) the
//! surface's velocity at the contact point (0 for a still collider). Each contact's normal
//! points into the free side (the side the particles belong to), so that an impulse +j n
//! with j > 0 pushes the particle back there.
//!
//! In 2D give planes normals in the xy-plane, sphere obstacles centres with z = 0 (they are
//! then circles), and boxes no walls along z ([`BoxContainer::rect`]).

use super::contact::{Contact, Partner};
pub use super::mesh::{NearCache, Side, TriangleMesh};
use super::motion::{Pose, SurfaceVelocity};
pub use super::surface::{Surface, Touch};
use crate::error::Error;
use crate::vec3;

/// A plane through `point` with unit normal n: particles belong to the side n points to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    point: [f64; 3],
    normal: [f64; 3],
    surface: Surface,
}

impl Plane {
    /// The plane through `point` (m, finite) with normal `normal` (finite, non-zero; it is
    /// normalised here), keeping particles on the side `normal` points to.
    pub fn new(point: [f64; 3], normal: [f64; 3], surface: Surface) -> Result<Self, Error> {
        if let Some((k, value)) = vec3::first_non_finite(&point) {
            return Err(Error::invalid(format!("point[{k}]"), value, "a plane's point must be finite"));
        }
        if let Some((k, value)) = vec3::first_non_finite(&normal) {
            return Err(Error::invalid(
                format!("normal[{k}]"),
                value,
                "a plane's normal must be finite",
            ));
        }
        // Dividing by the largest component first keeps |n|² from underflowing (or
        // overflowing) for normals of any finite size.
        let largest = normal.iter().fold(0.0, |m: f64, c| m.max(c.abs()));
        if largest == 0.0 {
            return Err(Error::invalid(
                "normal",
                format!("{normal:?}"),
                "a plane's normal must be non-zero (it points to the side the particles stay on)",
            ));
        }
        let scaled = vec3::scale(1.0 / largest, normal);
        Ok(Plane {
            point,
            normal: vec3::scale(1.0 / vec3::norm(scaled), scaled),
            surface,
        })
    }

    /// A point of the plane, m.
    pub fn point(&self) -> [f64; 3] {
        self.point
    }

    /// Unit normal, towards the free side.
    pub fn normal(&self) -> [f64; 3] {
        self.normal
    }

    /// Its restitution and friction.
    pub fn surface(&self) -> Surface {
        self.surface
    }

    /// Signed distance of `p` from the plane, m: (p − point)·n, > 0 on the free side.
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        vec3::dot(vec3::sub(p, self.point), self.normal)
    }

    /// The touch of a sphere at `p` (m) of radius `r` (m) when its signed distance is below
    /// r + `tolerance`: overlap r − s, normal n.
    pub fn touch(&self, p: [f64; 3], r: f64, tolerance: f64) -> Option<Touch> {
        let s = self.signed_distance(p);
        (s < r + tolerance).then_some(Touch {
            normal: self.normal,
            overlap: r - s,
        })
    }
}

/// An axis-aligned box that keeps particles inside: six inward planes, one per face.
///
/// A bound may be infinite (−∞ for `lo`, +∞ for `hi`): that face has no wall.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxContainer {
    lo: [f64; 3],
    hi: [f64; 3],
    walls: Vec<Plane>,
    surface: Surface,
}

impl BoxContainer {
    /// The box [lo, hi] (m; `lo[k] < hi[k]`, not NaN; lo may be −∞ and hi +∞ for no wall),
    /// particles inside.
    pub fn new(lo: [f64; 3], hi: [f64; 3], surface: Surface) -> Result<Self, Error> {
        for k in 0..3 {
            if lo[k].is_nan() || lo[k] == f64::INFINITY {
                return Err(Error::invalid(
                    format!("lo[{k}]"),
                    lo[k],
                    "a lower bound must be a number < +inf",
                ));
            }
            if hi[k].is_nan() || hi[k] <= lo[k] {
                return Err(Error::invalid(
                    format!("hi[{k}]"),
                    hi[k],
                    format!("the box needs hi > lo along each axis (lo[{k}] = {})", lo[k]),
                ));
            }
        }
        // Wall order: −x, +x, −y, +y, −z, +z faces; each normal points into the box.
        let mut walls = Vec::with_capacity(6);
        for k in 0..3 {
            let mut inward = [0.0; 3];
            for (bound, sign) in [(lo[k], 1.0), (hi[k], -1.0)] {
                if bound.is_finite() {
                    let mut point = [0.0; 3];
                    point[k] = bound;
                    inward[k] = sign;
                    walls.push(Plane::new(point, inward, surface)?);
                }
            }
        }
        Ok(BoxContainer { lo, hi, walls, surface })
    }

    /// The rectangle [lo, hi] of a 2D domain (m), with no walls along z.
    pub fn rect(lo: [f64; 2], hi: [f64; 2], surface: Surface) -> Result<Self, Error> {
        BoxContainer::new([lo[0], lo[1], f64::NEG_INFINITY], [hi[0], hi[1], f64::INFINITY], surface)
    }

    /// Whether the particles whose centres lie inside the box fit in it: their spheres (discs
    /// in 2D, `dim` = 2) must not fill more than its volume (area), or they overlap wherever
    /// they are, and the impacts among hundreds of overlapping neighbours make a step last
    /// seconds. A box open along an axis holds anything. Equal spheres fill at most 0.74 of
    /// a box; more than 1 is refused, naming the largest radius.
    pub fn check_fill(&self, dim: usize, x: &[f64], radius: &[f64]) -> Result<(), Error> {
        let volume: f64 = (0..dim).map(|k| self.hi[k] - self.lo[k]).product();
        if !volume.is_finite() {
            return Ok(());
        }
        let (mut filled, mut count, mut largest) = (0.0, 0usize, 0.0_f64);
        for (i, &r) in radius.iter().enumerate() {
            if (0..dim).all(|k| x[3 * i + k] >= self.lo[k] && x[3 * i + k] <= self.hi[k]) {
                filled += if dim == 3 {
                    4.0 / 3.0 * std::f64::consts::PI * r * r * r
                } else {
                    std::f64::consts::PI * r * r
                };
                count += 1;
                largest = largest.max(r);
            }
        }
        let fraction = filled / volume;
        if fraction > 1.0 {
            let what = if dim == 3 { "spheres" } else { "discs" };
            return Err(Error::invalid(
                "radius",
                largest,
                format!(
                    "the {count} particles inside the box from {:?} to {:?} m would fill {fraction:.3} times its {} \
                     (the largest radius shown; {what} that fit fill at most 0.74 of it): the radii are too large for the box",
                    &self.lo[..dim],
                    &self.hi[..dim],
                    if dim == 3 { "volume" } else { "area" }
                ),
            ));
        }
        Ok(())
    }

    /// Lower corner, m.
    pub fn lo(&self) -> [f64; 3] {
        self.lo
    }

    /// Upper corner, m.
    pub fn hi(&self) -> [f64; 3] {
        self.hi
    }

    /// The walls, inward planes in the order −x, +x, −y, +y, −z, +z (faces at infinity left out).
    pub fn walls(&self) -> &[Plane] {
        &self.walls
    }

    /// Its restitution and friction.
    pub fn surface(&self) -> Surface {
        self.surface
    }
}

/// A static sphere (a circle in 2D) that keeps particles outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereObstacle {
    center: [f64; 3],
    radius: f64,
    surface: Surface,
}

impl SphereObstacle {
    /// The sphere of centre `center` (m, finite) and radius `radius` (m, finite, ≥ 0).
    pub fn new(center: [f64; 3], radius: f64, surface: Surface) -> Result<Self, Error> {
        if let Some((k, value)) = vec3::first_non_finite(&center) {
            return Err(Error::invalid(
                format!("center[{k}]"),
                value,
                "an obstacle's centre must be finite",
            ));
        }
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(Error::invalid(
                "radius",
                radius,
                "an obstacle's radius must be finite and >= 0 m",
            ));
        }
        Ok(SphereObstacle { center, radius, surface })
    }

    /// Centre, m.
    pub fn center(&self) -> [f64; 3] {
        self.center
    }

    /// Radius, m.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Its restitution and friction.
    pub fn surface(&self) -> Surface {
        self.surface
    }

    /// The touch of a sphere at `p` (m) of radius `r` (m) when its centre is closer than
    /// R + r + `tolerance` to the obstacle's: normal (p − c)/|p − c| (+x for p = c, as for
    /// coincident particles), overlap R + r − |p − c|.
    pub fn touch(&self, p: [f64; 3], r: f64, tolerance: f64) -> Option<Touch> {
        let d = vec3::sub(p, self.center);
        let sum = self.radius + r;
        let reach = sum + tolerance;
        let dist2 = vec3::dot(d, d);
        if dist2 >= reach * reach {
            return None;
        }
        let dist = dist2.sqrt();
        Some(Touch {
            normal: if dist > 0.0 {
                vec3::scale(1.0 / dist, d)
            } else {
                [1.0, 0.0, 0.0]
            },
            overlap: sum - dist,
        })
    }
}

/// What a plane of a 2D world must satisfy ([`Collider::check_dim`]).
pub const PLANE_IN_2D: &str = "a plane's normal must lie in the xy-plane";
/// What a sphere obstacle of a 2D world must satisfy ([`Collider::check_dim`]).
pub const SPHERE_IN_2D: &str = "an obstacle's centre must lie in the xy-plane";

/// The 2D rule for one vector: in a world of `dim` = 2 the component `name[2]` must be 0
/// (`what` says why). The binding calls it on the values as given, before a plane's normal
/// is normalised, so that the error names the user's number; [`Collider::check_dim`] calls
/// it on the collider.
pub fn check_planar(dim: usize, name: &str, v: [f64; 3], what: &str) -> Result<(), Error> {
    if dim == 2 && v[2] != 0.0 {
        return Err(Error::invalid(
            format!("{name}[2]"),
            v[2],
            format!("a 2D world keeps z = 0: {what}"),
        ));
    }
    Ok(())
}

/// Any static collider.
#[derive(Debug, Clone, PartialEq)]
pub enum Collider {
    /// A half-space boundary.
    Plane(Plane),
    /// A container.
    Box(BoxContainer),
    /// An obstacle.
    Sphere(SphereObstacle),
    /// A triangle mesh: two-sided if open, an obstacle or a container if closed.
    Mesh(TriangleMesh),
}

impl Collider {
    /// Its restitution and friction.
    pub fn surface(&self) -> Surface {
        match self {
            Collider::Plane(p) => p.surface(),
            Collider::Box(b) => b.surface(),
            Collider::Sphere(s) => s.surface(),
            Collider::Mesh(m) => m.surface(),
        }
    }

    /// Checks that the collider fits a world of `dim` dimensions. A 2D world keeps every
    /// particle on z = 0, and the colliders are 3D: a plane's normal must lie in the
    /// xy-plane, an obstacle's centre on it, and a box must be open along z (a rectangle,
    /// [`BoxContainer::rect`]), or they would push particles out of the plane.
    pub fn check_dim(&self, dim: usize) -> Result<(), Error> {
        match self {
            Collider::Plane(p) => check_planar(dim, "normal", p.normal(), PLANE_IN_2D),
            Collider::Sphere(s) => check_planar(dim, "center", s.center(), SPHERE_IN_2D),
            Collider::Box(b) if dim == 2 => {
                for (name, z, open) in [("lo", b.lo()[2], f64::NEG_INFINITY), ("hi", b.hi()[2], f64::INFINITY)] {
                    if z != open {
                        return Err(Error::invalid(
                            format!("{name}[2]"),
                            z,
                            "a 2D world keeps z = 0: its box is a rectangle, open along z (lo[2] = -inf, hi[2] = inf)",
                        ));
                    }
                }
                Ok(())
            }
            Collider::Box(_) => Ok(()),
            Collider::Mesh(_) if dim == 2 => Err(Error::invalid(
                "type",
                "'mesh'",
                "a triangle mesh is a 3D collider; a 2D world's colliders are planes, rectangles and circles",
            )),
            Collider::Mesh(_) => Ok(()),
        }
    }

    /// Calls `each` with every touch of a sphere at `p` (m) of radius `r` (m) within
    /// `tolerance` (m): at most one for a plane or an obstacle, up to three for a box (a
    /// particle in a corner touches three walls), one per face, convex edge or vertex
    /// touched for a mesh.
    pub fn for_each_touch(&self, p: [f64; 3], r: f64, tolerance: f64, each: impl FnMut(Touch)) {
        match self {
            Collider::Plane(plane) => plane.touch(p, r, tolerance).into_iter().for_each(each),
            Collider::Box(b) => b.walls().iter().filter_map(|w| w.touch(p, r, tolerance)).for_each(each),
            Collider::Sphere(s) => s.touch(p, r, tolerance).into_iter().for_each(each),
            Collider::Mesh(m) => m.for_each_touch(p, r, tolerance, each),
        }
    }

    /// [`Collider::for_each_touch`], a mesh's from the triangles `cache` keeps near `p`
    /// (`TriangleMesh::for_each_touch_near`: the same touches); the other colliders do not
    /// use it.
    pub fn for_each_touch_near(&self, p: [f64; 3], r: f64, tolerance: f64, cache: &mut NearCache, each: impl FnMut(Touch)) {
        match self {
            Collider::Mesh(m) => m.for_each_touch_near(p, r, tolerance, cache, each),
            other => other.for_each_touch(p, r, tolerance, each),
        }
    }
}

impl Collider {
    /// The collider as added, displaced by `pose` and with its surface moving at `velocity`
    /// (the collide stage's placement of a moving collider at a time). A box stays
    /// axis-aligned: it can only be translated (a turning container is a closed mesh).
    pub fn posed(&self, pose: &Pose, velocity: SurfaceVelocity) -> Result<Collider, Error> {
        let surface = self.surface().with_velocity(velocity);
        Ok(match self {
            Collider::Plane(p) => Plane::new(pose.point(p.point()), pose.vector(p.normal()), surface)?.into(),
            Collider::Sphere(s) => SphereObstacle::new(pose.point(s.center()), s.radius(), surface)?.into(),
            Collider::Box(b) => {
                if pose.rotates() {
                    return Err(Error::invalid(
                        "rotation",
                        "a turn",
                        "a box collider stays axis-aligned and can only be translated; a turning container is a closed mesh (inside = true)",
                    ));
                }
                let t = pose.translation;
                BoxContainer::new(
                    [0, 1, 2].map(|k| b.lo()[k] + t[k]),
                    [0, 1, 2].map(|k| b.hi()[k] + t[k]),
                    surface,
                )?
                .into()
            }
            Collider::Mesh(m) => m.with_surface(surface).posed(*pose).into(),
        })
    }

    /// The velocity of its surface at point `x` (m), m/s (0 for a still collider).
    pub fn velocity_at(&self, x: [f64; 3]) -> [f64; 3] {
        let v = self.surface().velocity();
        if v.is_still() {
            [0.0; 3]
        } else {
            v.at(x)
        }
    }

    /// The contact of particle `i` (centre `p`, m; velocity `v`, m/s; radius `r`, m) with this
    /// collider, its index `k`, from the touch `t`: u_n = (v − u)·n with u the surface's
    /// velocity at the contact point p − (r − overlap) n (exactly v·n for a still collider).
    #[allow(clippy::too_many_arguments)]
    pub fn contact(&self, k: usize, t: Touch, i: usize, p: [f64; 3], v: [f64; 3], r: f64) -> Contact {
        let w = self.velocity_at(vec3::sub(p, vec3::scale(r - t.overlap, t.normal)));
        Contact {
            i,
            other: Partner::Collider(k),
            normal: t.normal,
            overlap: t.overlap,
            u_n: vec3::dot(vec3::sub(v, w), t.normal),
            wall_velocity: w,
        }
    }

    /// Whether its surface moves now.
    pub fn is_moving(&self) -> bool {
        !self.surface().velocity().is_still()
    }
}

impl From<Plane> for Collider {
    fn from(p: Plane) -> Self {
        Collider::Plane(p)
    }
}

impl From<BoxContainer> for Collider {
    fn from(b: BoxContainer) -> Self {
        Collider::Box(b)
    }
}

impl From<TriangleMesh> for Collider {
    fn from(m: TriangleMesh) -> Self {
        Collider::Mesh(m)
    }
}

impl From<SphereObstacle> for Collider {
    fn from(s: SphereObstacle) -> Self {
        Collider::Sphere(s)
    }
}

#[cfg(test)]
mod tests {
    use super::super::oracles::collider_contacts;
    use super::*;

    #[test]
    fn plane_contact_by_hand() {
        // plane z = 1 with normal (0, 0, 2) → (0, 0, 1); sphere r = 0.5 at z = 1.3 overlaps 0.2
        let floor = Plane::new([5.0, 5.0, 1.0], [0.0, 0.0, 2.0], Surface::default()).unwrap();
        assert_eq!(floor.normal(), [0.0, 0.0, 1.0]);
        let mut out = Vec::new();
        let x = [0.0, 0.0, 1.3, 0.0, 0.0, 1.6];
        let v = [1.0, 0.0, -3.0, 0.0, 0.0, -1.0];
        collider_contacts(&[floor.into()], &x, &v, &[0.5, 0.5], 0.0, &mut out).unwrap();
        assert_eq!(out.len(), 1);
        let c = out[0];
        assert_eq!((c.i, c.other), (0, Partner::Collider(0)));
        assert!((c.overlap - 0.2).abs() < 1e-15);
        assert_eq!(c.u_n, -3.0);
        // the second sphere's gap is 0.1: found with a tolerance of 0.15
        collider_contacts(&[floor.into()], &x, &v, &[0.5, 0.5], 0.15, &mut out).unwrap();
        assert_eq!(out.len(), 3);
        assert!((out[2].overlap + 0.1).abs() < 1e-15);
    }

    #[test]
    fn box_corner_gives_three_inward_contacts() {
        let b = BoxContainer::new([0.0; 3], [1.0, 2.0, 3.0], Surface::default()).unwrap();
        assert_eq!(b.walls().len(), 6);
        let mut out = Vec::new();
        collider_contacts(
            &[b.into()],
            &[0.0625, 1.9375, 2.9375],
            &[-1.0, 2.0, 3.0],
            &[0.125],
            0.0,
            &mut out,
        )
        .unwrap();
        let normals: Vec<[f64; 3]> = out.iter().map(|c| c.normal).collect();
        assert_eq!(normals, vec![[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]);
        let u_n: Vec<f64> = out.iter().map(|c| c.u_n).collect();
        assert_eq!(u_n, vec![-1.0, -2.0, -3.0]);
        for c in &out {
            assert_eq!(c.overlap, 0.0625, "{c:?}");
        }
        // a particle that escaped through +x is pushed back through that face
        out.clear();
        collider_contacts(
            &[BoxContainer::rect([0.0, 0.0], [1.0, 1.0], Surface::default()).unwrap().into()],
            &[3.0, 0.5, 0.0],
            &[0.0; 3],
            &[0.1],
            0.0,
            &mut out,
        )
        .unwrap();
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].normal, [-1.0, 0.0, 0.0]);
        assert!((out[0].overlap - 2.1).abs() < 1e-15);
    }

    #[test]
    fn sphere_obstacle_pushes_outwards() {
        let s = SphereObstacle::new([1.0, 1.0, 0.0], 2.0, Surface::default()).unwrap();
        let t = s.touch([1.0, 3.2, 0.0], 0.5, 0.0).unwrap();
        assert_eq!(t.normal, [0.0, 1.0, 0.0]);
        assert!((t.overlap - 0.3).abs() < 1e-15);
        assert!(s.touch([1.0, 3.6, 0.0], 0.5, 0.0).is_none());
        assert_eq!(s.touch([1.0, 1.0, 0.0], 0.5, 0.0).unwrap().normal, [1.0, 0.0, 0.0]);
    }

    #[test]
    fn constructors_name_bad_values() {
        let e = Plane::new([0.0; 3], [0.0; 3], Surface::default()).unwrap_err().to_string();
        assert!(
            e.starts_with("normal = [0.0, 0.0, 0.0] is invalid: a plane's normal must be non-zero"),
            "{e}"
        );
        let e = Plane::new([0.0, f64::NAN, 0.0], [1.0, 0.0, 0.0], Surface::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("point[1] = NaN is invalid"), "{e}");
        let e = BoxContainer::new([0.0; 3], [1.0, 0.0, 1.0], Surface::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("hi[1] = 0 is invalid"), "{e}");
        let e = SphereObstacle::new([0.0; 3], -1.0, Surface::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("radius = -1 is invalid"), "{e}");
        let e = Surface::new(Some(1.5), None).unwrap_err().to_string();
        assert!(e.starts_with("restitution = 1.5 is invalid"), "{e}");
        let e = Surface::new(None, Some(-0.1)).unwrap_err().to_string();
        assert!(e.starts_with("friction = -0.1 is invalid"), "{e}");
        // tiny but non-zero normals are fine
        assert_eq!(
            Plane::new([0.0; 3], [0.0, 1e-300, 0.0], Surface::default()).unwrap().normal(),
            [0.0, 1.0, 0.0]
        );
    }
}
