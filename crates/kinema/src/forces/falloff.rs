//! Falloff: a weight w(x) in [0, 1] that shapes a field force in space, F = w(x) F₀.
//!
//! As Blender's force-field falloff (Shape, Min/Max Distance) and Houdini's: a distance d(x)
//! from a shape, then a law that turns it into a weight.
//!
//! Shapes, each d(x) = |q(x)| for an offset q (∇d = q/|q|, since ∂q/∂x projects onto the
//! directions q lives in):
//! - sphere about `center` c: q = x − c;
//! - tube about the line through `center` c along the unit `axis` a: q = (I − a aᵀ)(x − c),
//!   the distance from the axis;
//! - box `center` c ± `half_size` h (axis-aligned): q_k = sign(x_k − c_k) max(0, |x_k − c_k| − h_k),
//!   the distance from the box, 0 inside it.
//!
//! Laws, with r₀ = `min_distance` and r₁ = `max_distance` (∞ allowed where said), w = 1 for
//! d ≤ r₀ and w = 0 for d > r₁, and between them, with t = (d − r₀)/(r₁ − r₀):
//! - constant: w = 1 (a cut at r₁: w jumps there);
//! - linear: w = 1 − t (continuous; r₁ finite);
//! - smooth: w = 1 − (3t² − 2t³) (continuous with its slope: w' = 0 at both ends; r₁ finite);
//! - inverse_square: w = (r₀/d)² (continuous at r₀ > 0; jumps to 0 at a finite r₁).
//!
//! The gradient ∇w = w'(d) ∇d is what a force's Jacobian needs (∂(w F₀)/∂x = w ∂F₀/∂x +
//! F₀ ∇wᵀ). Where w jumps its gradient is a delta, which is left out: the Jacobian is that of
//! either side. At d = 0 (the centre, the axis, inside the box) ∇w = 0.

use crate::error::Error;
use crate::vec3::{dot, norm, sub};

/// The shape a falloff measures its distance from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// Distance from a point, m.
    Sphere {
        /// The centre, m.
        center: [f64; 3],
    },
    /// Distance from a line, m.
    Tube {
        /// A point of the line, m.
        center: [f64; 3],
        /// Its direction (unit).
        axis: [f64; 3],
    },
    /// Distance from an axis-aligned box (0 inside), m.
    Box {
        /// The box's centre, m.
        center: [f64; 3],
        /// Its half sizes, m (≥ 0).
        half_size: [f64; 3],
    },
}

/// How the weight falls with the distance (see the module's doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Law {
    /// w = 1 up to `max_distance`, 0 beyond.
    Constant,
    /// w = 1 − t.
    Linear,
    /// w = 1 − (3t² − 2t³).
    Smooth,
    /// w = (r₀/d)² beyond r₀.
    InverseSquare,
}

impl Law {
    /// The law named `name` (`"constant"`, `"linear"`, `"smooth"`, `"inverse_square"`).
    pub fn from_name(name: &str) -> Result<Law, Error> {
        Ok(match name {
            "constant" => Law::Constant,
            "linear" => Law::Linear,
            "smooth" => Law::Smooth,
            "inverse_square" => Law::InverseSquare,
            _ => {
                return Err(Error::invalid(
                    "falloff.law",
                    format!("{name:?}"),
                    "the falloff law must be 'constant', 'linear', 'smooth' or 'inverse_square'",
                ))
            }
        })
    }
}

/// A weight w(x) in [0, 1] from a [`Shape`]'s distance and a [`Law`] (see the module's doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Falloff {
    /// What the distance is measured from.
    pub shape: Shape,
    /// How the weight falls with it.
    pub law: Law,
    /// r₀, m (≥ 0; > 0 for the inverse square): full weight up to here.
    pub min_distance: f64,
    /// r₁, m (> r₀; may be ∞ for the constant and inverse-square laws): no weight beyond.
    pub max_distance: f64,
}

fn finite3(name: &str, v: [f64; 3], what: &str) -> Result<(), Error> {
    match v.iter().position(|c| !c.is_finite()) {
        Some(k) => Err(Error::invalid(format!("falloff.{name}[{k}]"), v[k], what)),
        None => Ok(()),
    }
}

impl Falloff {
    /// A falloff of `shape` and `law` between `min_distance` and `max_distance` (m); a tube's
    /// axis is normalised here. Checks what the module's doc asks of each law.
    pub fn new(shape: Shape, law: Law, min_distance: f64, max_distance: f64) -> Result<Falloff, Error> {
        let shape = match shape {
            Shape::Tube { center, axis } => {
                let a = norm(axis);
                if !(a.is_finite() && a > 0.0) {
                    return Err(Error::invalid(
                        "falloff.axis",
                        format!("{axis:?}"),
                        "a tube's axis must be a finite, non-zero direction",
                    ));
                }
                Shape::Tube {
                    center,
                    axis: [axis[0] / a, axis[1] / a, axis[2] / a],
                }
            }
            s => s,
        };
        let f = Falloff {
            shape,
            law,
            min_distance,
            max_distance,
        };
        f.check()?;
        Ok(f)
    }

    /// Checks the fields (they are public and may have changed).
    pub fn check(&self) -> Result<(), Error> {
        match self.shape {
            Shape::Sphere { center } => finite3("center", center, "the falloff's centre must be finite (m)")?,
            Shape::Tube { center, axis } => {
                finite3("center", center, "the falloff's centre must be finite (m)")?;
                finite3("axis", axis, "a tube's axis must be finite")?;
                if (norm(axis) - 1.0).abs() > 1e-12 {
                    return Err(Error::invalid(
                        "falloff.axis",
                        format!("{axis:?}"),
                        "a tube's axis must be a unit vector",
                    ));
                }
            }
            Shape::Box { center, half_size } => {
                finite3("center", center, "the falloff's centre must be finite (m)")?;
                if let Some(k) = half_size.iter().position(|h| !(h.is_finite() && *h >= 0.0)) {
                    return Err(Error::invalid(
                        format!("falloff.half_size[{k}]"),
                        half_size[k],
                        "a box's half sizes must be finite and >= 0 m",
                    ));
                }
            }
        }
        let (r0, r1) = (self.min_distance, self.max_distance);
        let r0_ok = r0.is_finite() && if self.law == Law::InverseSquare { r0 > 0.0 } else { r0 >= 0.0 };
        if !r0_ok {
            let need = if self.law == Law::InverseSquare {
                "the inverse-square falloff needs min_distance > 0 m (finite): its weight is (min_distance/d)²"
            } else {
                "min_distance must be finite and >= 0 m"
            };
            return Err(Error::invalid("falloff.min_distance", r0, need));
        }
        let finite_needed = matches!(self.law, Law::Linear | Law::Smooth);
        if r1.is_nan() || r1 <= r0 || (finite_needed && r1.is_infinite()) {
            let need = if finite_needed {
                format!("a linear or smooth falloff needs a finite max_distance > min_distance = {r0} m")
            } else {
                format!("max_distance must be > min_distance = {r0} m (inf: no limit)")
            };
            return Err(Error::invalid("falloff.max_distance", r1, need));
        }
        Ok(())
    }

    /// The offset q(x) whose length is the distance d (see the module's doc).
    fn offset(&self, x: [f64; 3]) -> [f64; 3] {
        match self.shape {
            Shape::Sphere { center } => sub(x, center),
            Shape::Tube { center, axis } => {
                let r = sub(x, center);
                let along = dot(r, axis);
                [r[0] - along * axis[0], r[1] - along * axis[1], r[2] - along * axis[2]]
            }
            Shape::Box { center, half_size } => {
                let mut q = [0.0; 3];
                for k in 0..3 {
                    let r = x[k] - center[k];
                    q[k] = r.signum() * (r.abs() - half_size[k]).max(0.0);
                }
                q
            }
        }
    }

    /// The distance d(x), m.
    pub fn distance(&self, x: [f64; 3]) -> f64 {
        norm(self.offset(x))
    }

    /// The weight w(d) and its slope dw/dd (1/m) at the distance `d`.
    pub fn law_at(&self, d: f64) -> (f64, f64) {
        let (r0, r1) = (self.min_distance, self.max_distance);
        if d > r1 {
            return (0.0, 0.0);
        }
        if d <= r0 {
            return (1.0, 0.0);
        }
        match self.law {
            Law::Constant => (1.0, 0.0),
            Law::Linear => ((r1 - d) / (r1 - r0), -1.0 / (r1 - r0)),
            Law::Smooth => {
                // w = 1 − t²(3 − 2t), dw/dd = −6 t (1 − t) / (r₁ − r₀)
                let t = (d - r0) / (r1 - r0);
                (1.0 - t * t * (3.0 - 2.0 * t), -6.0 * t * (1.0 - t) / (r1 - r0))
            }
            Law::InverseSquare => {
                // w = r₀²/d², dw/dd = −2 r₀²/d³
                let w = (r0 / d) * (r0 / d);
                (w, -2.0 * w / d)
            }
        }
    }

    /// The weight w(x).
    pub fn weight(&self, x: [f64; 3]) -> f64 {
        self.law_at(self.distance(x)).0
    }

    /// The weight w(x) and its gradient ∇w = w'(d) q/|q| (1/m; 0 where d = 0).
    pub fn weight_and_gradient(&self, x: [f64; 3]) -> (f64, [f64; 3]) {
        let q = self.offset(x);
        let d = norm(q);
        let (w, slope) = self.law_at(d);
        if slope == 0.0 || d == 0.0 {
            return (w, [0.0; 3]);
        }
        let c = slope / d;
        (w, [c * q[0], c * q[1], c * q[2]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(law: Law, r0: f64, r1: f64) -> Falloff {
        Falloff::new(Shape::Sphere { center: [1.0, 2.0, 3.0] }, law, r0, r1).unwrap()
    }

    /// Theory: the laws of the module's doc, at distances chosen so that the values are
    /// exact in binary: r₀ = 1, r₁ = 3; d = 2 is t = ½.
    #[test]
    fn laws_match_their_formulas() {
        let at = |f: &Falloff, d: f64| f.weight([1.0 + d, 2.0, 3.0]);
        let lin = sphere(Law::Linear, 1.0, 3.0);
        assert_eq!(
            [
                at(&lin, 0.5),
                at(&lin, 1.0),
                at(&lin, 2.0),
                at(&lin, 2.5),
                at(&lin, 3.0),
                at(&lin, 3.5)
            ],
            [1.0, 1.0, 0.5, 0.25, 0.0, 0.0]
        );
        let smooth = sphere(Law::Smooth, 1.0, 3.0);
        // t = ¼: 1 − (3/16 − 2/64) = 1 − 5/32
        assert_eq!(
            [
                at(&smooth, 1.0),
                at(&smooth, 1.5),
                at(&smooth, 2.0),
                at(&smooth, 3.0),
                at(&smooth, 4.0)
            ],
            [1.0, 27.0 / 32.0, 0.5, 0.0, 0.0]
        );
        let inv = sphere(Law::InverseSquare, 1.0, f64::INFINITY);
        assert_eq!(
            [at(&inv, 0.5), at(&inv, 1.0), at(&inv, 2.0), at(&inv, 4.0)],
            [1.0, 1.0, 0.25, 0.0625]
        );
        let inv = sphere(Law::InverseSquare, 1.0, 3.0);
        assert_eq!([at(&inv, 2.0), at(&inv, 3.0), at(&inv, 3.0 + 1e-9)], [0.25, 1.0 / 9.0, 0.0]);
        let cut = sphere(Law::Constant, 0.0, 2.0);
        assert_eq!([at(&cut, 0.0), at(&cut, 2.0), at(&cut, 2.5)], [1.0, 1.0, 0.0]);
        let everywhere = sphere(Law::Constant, 0.0, f64::INFINITY);
        assert_eq!(at(&everywhere, 1e300), 1.0);
    }

    /// Theory: linear and smooth are continuous at r₀ and r₁, the smooth one with a zero
    /// slope at both; the inverse square is continuous at r₀.
    #[test]
    fn continuity_where_promised() {
        let e = 1e-9;
        for law in [Law::Linear, Law::Smooth] {
            let f = sphere(law, 1.0, 3.0);
            for r in [1.0, 3.0] {
                let (a, b) = (f.law_at(r - e).0, f.law_at(r + e).0);
                assert!((a - b).abs() < 1e-8, "{law:?} at {r}: {a} vs {b}");
            }
        }
        let f = sphere(Law::Smooth, 1.0, 3.0);
        assert_eq!(f.law_at(1.0 + e).1.abs() < 1e-8 && f.law_at(3.0 - e).1.abs() < 1e-8, true);
        let f = sphere(Law::InverseSquare, 2.0, f64::INFINITY);
        assert!((f.law_at(2.0 - e).0 - f.law_at(2.0 + e).0).abs() < 1e-8);
    }

    /// Theory: each shape's distance: from the centre, from the axis (not along it), from the
    /// box's surface (0 inside, the Euclidean distance to the nearest point outside).
    #[test]
    fn shape_distances() {
        let tube = Falloff::new(
            Shape::Tube {
                center: [0.0, 0.0, 1.0],
                axis: [0.0, 0.0, 2.0],
            },
            Law::Constant,
            0.0,
            f64::INFINITY,
        )
        .unwrap();
        assert_eq!(tube.distance([3.0, 4.0, -7.0]), 5.0);
        let cube = Falloff::new(
            Shape::Box {
                center: [1.0, 1.0, 1.0],
                half_size: [1.0, 2.0, 3.0],
            },
            Law::Constant,
            0.0,
            f64::INFINITY,
        )
        .unwrap();
        assert_eq!(cube.distance([1.5, 2.5, -1.0]), 0.0);
        assert_eq!(cube.distance([5.0, 1.0, 1.0]), 3.0); // a face: 5 − 1 − 1
        assert_eq!(cube.distance([5.0, 7.0, 1.0]), 5.0); // an edge: (3, 4)
        assert_eq!(cube.distance([1.0, 1.0, 1.0]), 0.0);
    }

    /// Theory: ∇w = w'(d) ∇d, by central differences, for every shape and law (away from
    /// the kinks at r₀ and r₁).
    #[test]
    fn gradient_matches_finite_differences() {
        let shapes = [
            Shape::Sphere {
                center: [0.1, -0.2, 0.3],
            },
            Shape::Tube {
                center: [0.0, 0.5, 0.0],
                axis: [1.0, 2.0, -0.5],
            },
            Shape::Box {
                center: [0.0, 0.0, 0.2],
                half_size: [0.3, 0.4, 0.5],
            },
        ];
        let laws = [
            (Law::Linear, 0.2, 1.7),
            (Law::Smooth, 0.1, 1.9),
            (Law::InverseSquare, 0.3, f64::INFINITY),
        ];
        let mut rng = super::super::testing::Rng::new(5);
        let h = 1e-6;
        for shape in shapes {
            for (law, r0, r1) in laws {
                let f = Falloff::new(shape, law, r0, r1).unwrap();
                let mut tested = 0;
                while tested < 20 {
                    let x = [rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5)];
                    let d = f.distance(x);
                    if (d - r0).abs() < 1e-3 || (d - r1).abs() < 1e-3 || d < 1e-3 {
                        continue;
                    }
                    let (_, g) = f.weight_and_gradient(x);
                    for k in 0..3 {
                        let (mut xp, mut xm) = (x, x);
                        xp[k] += h;
                        xm[k] -= h;
                        let fd = (f.weight(xp) - f.weight(xm)) / (2.0 * h);
                        assert!(
                            (fd - g[k]).abs() < 1e-6 * (1.0 + g[k].abs()),
                            "{shape:?} {law:?} at {x:?}: {fd} vs {}",
                            g[k]
                        );
                    }
                    tested += 1;
                }
            }
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let s = Shape::Sphere { center: [0.0; 3] };
        let e = Falloff::new(s, Law::Linear, 0.0, f64::INFINITY).unwrap_err().to_string();
        assert!(
            e.starts_with("falloff.max_distance = inf is invalid: a linear or smooth falloff needs a finite"),
            "{e}"
        );
        let e = Falloff::new(s, Law::InverseSquare, 0.0, f64::INFINITY)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("falloff.min_distance = 0 is invalid: the inverse-square falloff needs"),
            "{e}"
        );
        let e = Falloff::new(s, Law::Smooth, 2.0, 1.0).unwrap_err().to_string();
        assert!(e.starts_with("falloff.max_distance = 1 is invalid"), "{e}");
        let tube = Shape::Tube {
            center: [0.0; 3],
            axis: [0.0; 3],
        };
        let e = Falloff::new(tube, Law::Constant, 0.0, 1.0).unwrap_err().to_string();
        assert!(e.starts_with("falloff.axis = [0.0, 0.0, 0.0] is invalid"), "{e}");
        let e = Law::from_name("cubic").unwrap_err().to_string();
        assert!(e.starts_with("falloff.law = \"cubic\" is invalid"), "{e}");
    }
}
