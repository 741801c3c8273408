//! Domain: the space particles collide in — 2D or 3D, open or periodic along each axis.
//!
//! Along a periodic axis of period L = hi − lo, a particle at x is also at x + kL for every
//! integer k. Two particles interact through their nearest images only: the minimum-image
//! displacement d − L·round(d / L), which lies in [−L/2, L/2]. When two particles could
//! touch through two images at once (r_i + r_j + margin > L/2) only the nearest one counts.

use crate::error::Error;
use crate::vec3;
use rayon::prelude::*;

/// A box [lo, hi) whose opposite faces are identified along the axes marked periodic.
///
/// Bounds along the other axes are not used (they may be any finite numbers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Periodic {
    lo: [f64; 3],
    hi: [f64; 3],
    axes: [bool; 3],
    /// 1 / (hi − lo) on periodic axes (0 on the others), 1/m.
    inv_period: [f64; 3],
    /// Half the period on periodic axes, +∞ on the others, m: a displacement longer than it
    /// along an axis is not its own minimum image (one comparison on the hot path, where
    /// the axis's flag, a subtraction and a product were).
    half_period: [f64; 3],
    /// The cell's bounds on periodic axes and ±∞ on the others, m: a coordinate outside them
    /// needs wrapping (one test per coordinate, the axis's flag folded in).
    wrap_lo: [f64; 3],
    wrap_hi: [f64; 3],
}

impl Periodic {
    /// Periodic along the axes with `axes[k]` true, with period `hi[k] − lo[k]` (m); on every
    /// periodic axis `lo[k]`, `hi[k]` finite and `hi[k] > lo[k]`. The bounds of the other axes
    /// are not used (a 2D rectangle's z bounds are infinite).
    pub fn new(lo: [f64; 3], hi: [f64; 3], axes: [bool; 3]) -> Result<Self, Error> {
        for (name, b) in [("lo", lo), ("hi", hi)] {
            if let Some(k) = (0..3).find(|&k| axes[k] && !b[k].is_finite()) {
                return Err(Error::invalid(
                    format!("{name}[{k}]"),
                    b[k],
                    "the bounds of a periodic axis must be finite",
                ));
            }
        }
        for k in 0..3 {
            if axes[k] && hi[k] <= lo[k] {
                return Err(Error::invalid(
                    format!("hi[{k}]"),
                    hi[k],
                    format!("a periodic axis needs hi > lo (lo[{k}] = {}); its period is hi − lo", lo[k]),
                ));
            }
        }
        let inv_period = [0, 1, 2].map(|k| if axes[k] { 1.0 / (hi[k] - lo[k]) } else { 0.0 });
        let half_period = [0, 1, 2].map(|k| if axes[k] { 0.5 * (hi[k] - lo[k]) } else { f64::INFINITY });
        let wrap_lo = [0, 1, 2].map(|k| if axes[k] { lo[k] } else { f64::NEG_INFINITY });
        let wrap_hi = [0, 1, 2].map(|k| if axes[k] { hi[k] } else { f64::INFINITY });
        Ok(Periodic {
            lo,
            hi,
            axes,
            inv_period,
            half_period,
            wrap_lo,
            wrap_hi,
        })
    }

    /// Lower corner, m.
    pub fn lo(&self) -> [f64; 3] {
        self.lo
    }

    /// Upper corner, m.
    pub fn hi(&self) -> [f64; 3] {
        self.hi
    }

    /// Which axes are periodic.
    pub fn axes(&self) -> [bool; 3] {
        self.axes
    }

    /// Period along axis k, m (`hi[k] − lo[k]`; meaningful on periodic axes).
    pub fn period(&self, k: usize) -> f64 {
        self.hi[k] - self.lo[k]
    }

    /// The minimum image of the displacement `d` (m): along each periodic axis
    /// d − L·round(d / L), in [−L/2, L/2] (to rounding); unchanged along the others.
    #[inline]
    pub fn min_image(&self, d: [f64; 3]) -> [f64; 3] {
        let mut out = d;
        for k in 0..3 {
            // Within half a period, d/L rounds to 0 (0.5 itself ties to even, 0) and d stays
            // as it is: the formula's result, bit for bit, without its arithmetic. That is
            // nearly every pair of a neighbour search.
            // (`half_period`: 0.5·L, the same bits, or +∞ along an open axis)
            if d[k].abs() > self.half_period[k] {
                out[k] = d[k] - self.period(k) * nearest_integer(d[k] * self.inv_period[k]);
            }
        }
        out
    }

    /// Coordinate `c` (m) of axis `k` wrapped into [lo, hi) when the axis is periodic.
    #[inline]
    pub fn wrap_coordinate(&self, k: usize, c: f64) -> f64 {
        if !self.axes[k] {
            return c;
        }
        let (lo, hi, l) = (self.lo[k], self.hi[k], self.period(k));
        let w = c - l * floor((c - lo) / l);
        // c just below lo gives floor = −1 and w = c + L, which can round up to hi itself;
        // that point is lo's image.
        if w >= hi {
            lo
        } else {
            w.max(lo)
        }
    }

    /// The position `p` (m) wrapped into [lo, hi) along the periodic axes.
    #[inline]
    pub fn wrap(&self, p: [f64; 3]) -> [f64; 3] {
        [
            self.wrap_coordinate(0, p[0]),
            self.wrap_coordinate(1, p[1]),
            self.wrap_coordinate(2, p[2]),
        ]
    }

    /// Wraps every position of the flat array `x` (m, 3 per particle) into the box along
    /// the periodic axes, in place, on all threads.
    pub fn wrap_positions(&self, x: &mut [f64]) {
        x.par_chunks_mut(3 * 4096).for_each(|chunk| self.wrap_positions_serial(chunk));
    }

    /// [`Periodic::wrap_positions`] on the calling thread (for a pass that has the positions
    /// at hand already).
    #[inline]
    pub fn wrap_positions_serial(&self, x: &mut [f64]) {
        // A coordinate already in [lo, hi) is its own wrap (floor gives 0 there): only the few
        // that left the cell in a step pay for the division and the floor.
        let (lo, hi) = (self.wrap_lo, self.wrap_hi);
        // (first a pass without branches, which the compiler vectorises, over whether any
        // coordinate left: in a step few do, and most chunks of a gas need nothing more)
        let inside = |p: &[f64]| (0..3).fold(true, |all, k| all & (p[k] >= lo[k]) & (p[k] < hi[k]));
        if x.chunks_exact(3).fold(true, |all, p| all & inside(p)) {
            return;
        }
        for p in x.chunks_exact_mut(3) {
            for (k, c) in p.iter_mut().enumerate() {
                if !(*c >= lo[k] && *c < hi[k]) {
                    *c = self.wrap_coordinate(k, *c); // (itself along an open axis)
                }
            }
        }
    }
}

/// ⌊v⌋ without a library call: `f64::floor` is one on x86-64 without SSE4.1 (a slow software
/// routine linked in), and LLVM hoists it out of branches, so the broad phase paid for it on
/// every open axis too. Below 2⁵² the cast to i64 truncates exactly, and truncation is the
/// floor except for negative non-integers (one less); from 2⁵² on every double is an integer
/// (NaN stays NaN). Returns +0 for −0.
#[inline]
pub(crate) fn floor(v: f64) -> f64 {
    if v.abs() < 4_503_599_627_370_496.0 {
        let t = v as i64 as f64;
        if t > v {
            t - 1.0
        } else {
            t
        }
    } else {
        v
    }
}

/// The integer nearest to `v` (ties to even). For |v| < 2⁵¹, adding 1.5·2⁵² lands in
/// [2⁵², 2⁵³), where doubles are spaced exactly 1 apart, so the addition itself rounds v to
/// an integer and subtracting the constant again is exact. This is plain arithmetic, where
/// `f64::round` is a library call on x86-64 without SSE4.1, and the broad phase's pair test
/// calls it three times per candidate pair.
#[inline]
fn nearest_integer(v: f64) -> f64 {
    const SHIFT: f64 = 6_755_399_441_055_744.0; // 1.5 · 2⁵²
    if v.abs() < 2_251_799_813_685_248.0 {
        (v + SHIFT) - SHIFT
    } else {
        v.round()
    }
}

/// The space of a collision query: its dimension and its periodic axes, if any.
///
/// In 2D (`dim` = 2) particles are circles in the xy-plane (z = 0 kept exactly); the stages
/// then search no neighbours along z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Domain {
    dim: usize,
    periodic: Option<Periodic>,
}

impl Domain {
    /// An unbounded domain of dimension `dim` (2 or 3).
    pub fn open(dim: usize) -> Result<Self, Error> {
        if dim != 2 && dim != 3 {
            return Err(Error::invalid("dim", dim, "2 (circles in the xy-plane) or 3 (spheres)"));
        }
        Ok(Domain { dim, periodic: None })
    }

    /// A domain of dimension `dim` (2 or 3) with the periodic axes of `periodic`.
    pub fn periodic(dim: usize, periodic: Periodic) -> Result<Self, Error> {
        Ok(Domain {
            periodic: Some(periodic),
            ..Domain::open(dim)?
        })
    }

    /// 2 or 3.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The periodic box, if any.
    pub fn periodic_box(&self) -> Option<&Periodic> {
        self.periodic.as_ref()
    }

    /// Whether particles of these radii (m) can collide in this domain. Along a periodic axis
    /// of edge L the minimum image is a touching pair's partner only while r_i + r_j < L/2,
    /// so a diameter of L/2 or more is refused, naming the largest particle (HOOMD and
    /// LAMMPS refuse a box this small for their cutoff too). The broad phase itself finds
    /// the nearest images in any box; it is the contacts that need this.
    pub fn check_radii(&self, radius: &[f64]) -> Result<(), Error> {
        let Some(cell) = &self.periodic else { return Ok(()) };
        let (i, r_max) = radius
            .iter()
            .enumerate()
            .fold((0, 0.0_f64), |best, (i, &r)| if r > best.1 { (i, r) } else { best });
        match (0..3).find(|&k| cell.axes[k] && 4.0 * r_max >= cell.period(k)) {
            None => Ok(()),
            Some(k) => Err(Error::invalid(
                format!("radius[{i}]"),
                r_max,
                format!(
                    "a particle's diameter must be less than half the periodic cell's edge ({} m along {}), \
                     where the minimum image finds its partners",
                    cell.period(k),
                    ["x", "y", "z"][k]
                ),
            )),
        }
    }

    /// The displacement x_i − x_j (m), as its minimum image along periodic axes.
    #[inline]
    pub fn displacement(&self, xi: [f64; 3], xj: [f64; 3]) -> [f64; 3] {
        let d = vec3::sub(xi, xj);
        match &self.periodic {
            Some(p) => p.min_image(d),
            None => d,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_diameter_of_half_the_periodic_cell_is_refused_naming_the_particle() {
        // a cell 1 m along x: r = 0.25 makes r_i + r_j = L/2, where the minimum image of a
        // touching pair is ambiguous; a radius just below passes, and so does any open axis
        let cell = Periodic::new([0.0; 3], [1.0, 4.0, 4.0], [true, true, true]).unwrap();
        let domain = Domain::periodic(3, cell).unwrap();
        let err = domain.check_radii(&[0.1, 0.25, 0.2]).unwrap_err().to_string();
        assert!(
            err.starts_with("radius[1] = 0.25 is invalid: a particle's diameter must be less than half"),
            "{err}"
        );
        assert!(err.contains("(1 m along x)"), "{err}");
        assert!(domain.check_radii(&[0.1, 0.2499, 0.2]).is_ok());
        let open_x = Periodic::new([0.0; 3], [1.0, 4.0, 4.0], [false, true, true]).unwrap();
        assert!(Domain::periodic(3, open_x).unwrap().check_radii(&[0.9]).is_ok());
        assert!(Domain::open(3).unwrap().check_radii(&[1e9]).is_ok());
    }

    fn unit_box() -> Periodic {
        Periodic::new([0.0, -1.0, 5.0], [2.0, 1.0, 6.0], [true, true, false]).unwrap()
    }

    #[test]
    fn min_image_is_the_nearest_copy() {
        let p = unit_box();
        // period 2 along x and y: 1.5 → −0.5, −1.7 → 0.3, 4.2 → 0.2; z is open.
        let d = p.min_image([1.5, -1.7, 4.2]);
        assert!((d[0] + 0.5).abs() < 1e-15 && (d[1] - 0.3).abs() < 1e-15, "{d:?}");
        assert_eq!(d[2], 4.2);
        assert!(d[..2].iter().all(|c| c.abs() <= 1.0));
    }

    #[test]
    fn floors_without_the_library() {
        for v in [
            0.0,
            0.3,
            1.0,
            2.5,
            -0.5,
            -1.0,
            -1.5,
            -3.0,
            1e15 + 0.5,
            -1e15 - 0.5,
            4.6e15 + 1.0,
            -9e15,
            1e300,
            -1e300,
        ] {
            assert_eq!(floor(v), v.floor(), "{v}");
        }
        assert!(floor(f64::NAN).is_nan());
        assert_eq!(floor(f64::NEG_INFINITY), f64::NEG_INFINITY);
    }

    #[test]
    fn nearest_integers() {
        for (v, n) in [
            (0.4, 0.0),
            (0.6, 1.0),
            (-0.6, -1.0),
            (2.5, 2.0),
            (3.5, 4.0),
            (-1e15 - 0.7, -1e15 - 1.0),
            (1e300, 1e300),
        ] {
            assert_eq!(nearest_integer(v), n, "{v}");
        }
        assert_eq!(nearest_integer(-0.2), 0.0);
    }

    #[test]
    fn wrapping_lands_in_the_half_open_box() {
        let p = unit_box();
        assert_eq!(p.wrap([2.0, 1.0, 9.0]), [0.0, -1.0, 9.0]);
        assert_eq!(p.wrap([-0.5, 2.5, 9.0]), [1.5, 0.5, 9.0]);
        // just below lo: c + L rounds to hi in floating point, which is lo's image
        let w = p.wrap_coordinate(0, -1e-17);
        assert!((0.0..2.0).contains(&w), "{w}");
        let mut x = vec![7.0, -3.0, 0.0, 0.5, 0.5, 0.5];
        p.wrap_positions(&mut x);
        assert_eq!(&x[..3], &[1.0, -1.0, 0.0]);
        assert_eq!(&x[3..], &[0.5, 0.5, 0.5]);
    }

    #[test]
    fn bad_boxes_are_named() {
        let e = Periodic::new([0.0; 3], [1.0, 0.0, 1.0], [true, true, false])
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("hi[1] = 0 is invalid: a periodic axis needs hi > lo"), "{e}");
        let e = Periodic::new([0.0, f64::NAN, 0.0], [1.0; 3], [false, true, false])
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("lo[1] = NaN is invalid"), "{e}");
        // the bounds of an axis that is not periodic are not used: a 2D rectangle's ±inf z
        assert!(Periodic::new([0.0, 0.0, f64::NEG_INFINITY], [1.0, 1.0, f64::INFINITY], [true, true, false]).is_ok());
        // a flat box is fine along an open axis
        assert!(Periodic::new([0.0; 3], [1.0, 1.0, 0.0], [true, true, false]).is_ok());
        let e = Domain::open(4).unwrap_err().to_string();
        assert!(e.starts_with("dim = 4 is invalid"), "{e}");
    }
}
