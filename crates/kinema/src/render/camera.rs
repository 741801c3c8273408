//! Camera: maps world positions (m) and radii (m) to pixel centres and pixel radii.
//!
//! Pixel convention: pixel (i, j) — column i, row j, row 0 at the top — covers the square
//! [i, i+1) × [j, j+1) of the image plane; its centre is (i + 0.5, j + 0.5).

use crate::vec3::{add, cross, dot, norm, scale, sub};
use crate::Error;

/// The margin [`Camera::frame_box`] leaves on each side of the image, a fraction of its width
/// (left and right) and height (top and bottom).
pub const FRAME_MARGIN: f64 = 0.03;

/// How world coordinates become pixel coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Camera {
    /// 2D orthographic view of the xy-plane (z is ignored); x grows to the right, y upwards.
    Orthographic {
        /// World point (m) that lands at the image centre.
        center: [f64; 2],
        /// Scale, pixels per metre (the same along x and y, so discs stay round).
        pixels_per_unit: f64,
    },
    /// 3D pinhole camera.
    Perspective {
        /// Eye position, m.
        eye: [f64; 3],
        /// Point looked at, m (lands at the image centre).
        target: [f64; 3],
        /// Up direction (need not be unit or orthogonal to the view; z-up scenes use (0, 0, 1)).
        up: [f64; 3],
        /// Vertical field of view, degrees, in (0, 180).
        fov_y_deg: f64,
        /// Near distance, m: particles whose centre is nearer than this along the view axis
        /// (or behind the eye) are not drawn.
        near: f64,
    },
}

/// A particle as the camera sees it: centre and radius in pixels, depth for ordering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projected {
    /// Centre, pixels from the left edge.
    pub x: f64,
    /// Centre, pixels from the top edge.
    pub y: f64,
    /// Radius, pixels (before the minimum radius is applied).
    pub r: f64,
    /// Distance along the view axis, m (0 for the orthographic camera).
    pub depth: f64,
}

impl Camera {
    /// Orthographic camera that fits the world rectangle `[lo, hi]` (m, xy) into a
    /// `width × height` image, centred, keeping the aspect ratio (the looser axis gets margins).
    pub fn fit_2d(lo: [f64; 2], hi: [f64; 2], width: usize, height: usize) -> Result<Self, Error> {
        let span = [hi[0] - lo[0], hi[1] - lo[1]];
        if !(span[0] > 0.0 && span[1] > 0.0 && span[0].is_finite() && span[1].is_finite()) {
            return Err(invalid(
                "view",
                format!("{lo:?}..{hi:?}"),
                "a finite rectangle with hi > lo on both axes",
            ));
        }
        check_size(width, height)?;
        // The rectangle fits when both of its sides do: the scale is the smaller of the two.
        let pixels_per_unit = (width as f64 / span[0]).min(height as f64 / span[1]);
        Ok(Camera::Orthographic {
            center: [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])],
            pixels_per_unit,
        })
    }

    /// Perspective camera at `eye` looking at `target`, checked (see the variant's fields).
    /// The near distance is 1e-6 of the eye–target distance.
    pub fn perspective(eye: [f64; 3], target: [f64; 3], up: [f64; 3], fov_y_deg: f64) -> Result<Self, Error> {
        let cam = Camera::Perspective {
            eye,
            target,
            up,
            fov_y_deg,
            near: 1e-6 * norm(sub(target, eye)),
        };
        cam.basis()?;
        Ok(cam)
    }

    /// Perspective camera that frames the box `[lo, hi]` (m): it looks from the direction
    /// `from` (a vector pointing from the box towards the eye) and its 8 corners fill a
    /// `width × height` image up to a margin of [`FRAME_MARGIN`] of each side, centred
    /// ([`Camera::frame_points`] of the corners). Up is +z unless `from` is vertical (then +y).
    pub fn frame_box(
        lo: [f64; 3],
        hi: [f64; 3],
        from: [f64; 3],
        fov_y_deg: f64,
        width: usize,
        height: usize,
    ) -> Result<Self, Error> {
        if !(0..3).all(|k| hi[k] >= lo[k] && lo[k].is_finite() && hi[k].is_finite()) {
            return Err(invalid("box", format!("{lo:?}..{hi:?}"), "finite corners with hi >= lo"));
        }
        let corners: Vec<[f64; 3]> = (0..8)
            .map(|c| std::array::from_fn(|k| if c >> k & 1 == 1 { hi[k] } else { lo[k] }))
            .collect();
        let (w, h) = (width as f64, height as f64);
        let window = [
            FRAME_MARGIN * w,
            FRAME_MARGIN * h,
            (1.0 - FRAME_MARGIN) * w,
            (1.0 - FRAME_MARGIN) * h,
        ];
        Ok(Camera::frame_points(&corners, from, fov_y_deg, width, height, window)?.0)
    }

    /// Perspective camera looking from the direction `from` (from the points towards the eye)
    /// whose `width × height` image shows every point inside `window` = [x0, y0, x1, y1]
    /// (pixels, x to the right, y down), as large as that allows: the points touch the
    /// window's sides along one image axis (or both) and are centred in it along the other.
    /// Returns the camera and the points' pixel bounding box [x0, y0, x1, y1].
    ///
    /// Both fields of view are fitted, not a bounding sphere to the narrower one, so a tall
    /// scene in a wide image fills its height. With the camera basis (right, up, forward) of
    /// `from`, a point at (x, y, z) from the points' centre c, and the eye at
    /// c + sx·right + sy·up − D·forward, the point lands at the tangent u = (x − sx)/(z + D)
    /// right of the view axis (v = (y − sy)/(z + D) up). It is inside the window when
    /// a₀ ≤ u ≤ a₁, a the window's sides as tangents (pixels from the image centre over the
    /// focal length f), i.e. x − a₁z − a₁D ≤ sx ≤ x − a₀z − a₀D. Some sx suits every point
    /// when D (a₁ − a₀) ≥ maxᵢ(xᵢ − a₁zᵢ) − minᵢ(xᵢ − a₀zᵢ): the least D is exact, per axis,
    /// and the larger of the two axes' is taken. Along the axis with room to spare, sx is
    /// chosen (by bisection: the projected extent's midpoint falls as sx grows) to centre the
    /// points' projected extent in the window.
    pub fn frame_points(
        points: &[[f64; 3]],
        from: [f64; 3],
        fov_y_deg: f64,
        width: usize,
        height: usize,
        window: [f64; 4],
    ) -> Result<(Self, [f64; 4]), Error> {
        let dir = check_framing(points, from, fov_y_deg, (width, height), window)?;
        let (w, h) = (width as f64, height as f64);
        let [x0, y0, x1, y1] = window;
        let (world_up, forward, right, up) = view_basis(dir);
        let f = 0.5 * h / (0.5 * fov_y_deg.to_radians()).tan();
        // The window's sides as tangents from the view axis: a along right, b along up.
        let (a0, a1) = ((x0 - 0.5 * w) / f, (x1 - 0.5 * w) / f);
        let (b0, b1) = ((0.5 * h - y1) / f, (0.5 * h - y0) / f);
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in points {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let centre = scale(0.5, add(lo, hi));
        let size = norm(sub(hi, lo));
        let local: Vec<[f64; 3]> = points
            .iter()
            .map(|&p| {
                let d = sub(p, centre);
                [dot(d, right), dot(d, up), dot(d, forward)]
            })
            .collect();
        // The least distance along each axis (axis 0: x with a, axis 1: y with b).
        let least = |k: usize, t0: f64, t1: f64| least_distance(&local, k, (t0, t1));
        let zmin = local.iter().map(|q| q[2]).fold(f64::INFINITY, f64::min);
        // Never inside the points: the eye stays in front of the nearest by a little.
        let floor = -zmin + 1e-3 * size.max(1e-9);
        let distance = least(0, a0, a1).max(least(1, b0, b1)).max(floor).max(1e-9);
        // The shift along one axis: the feasible range, then bisection to centre the extent.
        let shift = |k: usize, t0: f64, t1: f64| centring_shift(&local, k, (t0, t1), distance);
        let (sx, sy) = (shift(0, a0, a1), shift(1, b0, b1));
        let target = add(centre, add(scale(sx, right), scale(sy, up)));
        let eye = sub(target, scale(distance, forward));
        let camera = Camera::Perspective {
            eye,
            target,
            up: world_up,
            fov_y_deg,
            near: 1e-3 * distance,
        };
        let mut bbox = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
        for q in &local {
            let z = q[2] + distance;
            let (px, py) = (0.5 * w + f * (q[0] - sx) / z, 0.5 * h - f * (q[1] - sy) / z);
            bbox = [bbox[0].min(px), bbox[1].min(py), bbox[2].max(px), bbox[3].max(py)];
        }
        Ok((camera, bbox))
    }

    /// Checks the camera's parameters; an orthographic camera needs a finite positive scale,
    /// a perspective one a non-degenerate view direction and up, and 0 < fov < 180.
    pub fn validate(&self) -> Result<(), Error> {
        match *self {
            Camera::Orthographic { center, pixels_per_unit } => {
                if !(pixels_per_unit > 0.0 && pixels_per_unit.is_finite()) {
                    return Err(invalid("pixels_per_unit", pixels_per_unit, "a finite number > 0"));
                }
                if !(center[0].is_finite() && center[1].is_finite()) {
                    return Err(invalid("center", format!("{center:?}"), "finite coordinates"));
                }
                Ok(())
            }
            Camera::Perspective { .. } => self.basis().map(|_| ()),
        }
    }

    /// True for the 3D perspective camera (spheres are shaded), false for the 2D one (flat discs).
    pub fn is_3d(&self) -> bool {
        matches!(self, Camera::Perspective { .. })
    }

    /// A projector for a `width × height` image: precomputes the basis and focal length.
    pub(crate) fn projector(&self, width: usize, height: usize) -> Result<Projector, Error> {
        check_size(width, height)?;
        self.validate()?;
        let (w, h) = (width as f64, height as f64);
        Ok(match *self {
            Camera::Orthographic { center, pixels_per_unit } => Projector::Ortho {
                cx: 0.5 * w - pixels_per_unit * center[0],
                cy: 0.5 * h + pixels_per_unit * center[1],
                s: pixels_per_unit,
            },
            Camera::Perspective {
                eye, fov_y_deg, near, ..
            } => {
                let (right, up, forward) = self.basis()?;
                // Pinhole: a point at camera coordinates (xc, yc, zc), zc along the view axis,
                // lands at f·xc/zc, f·yc/zc from the image centre, where the focal length in
                // pixels f = (H/2) / tan(fov_y/2) puts the top edge at the fov_y/2 angle.
                let f = 0.5 * h / (0.5 * fov_y_deg.to_radians()).tan();
                Projector::Persp {
                    eye,
                    right,
                    up,
                    forward,
                    f,
                    cx: 0.5 * w,
                    cy: 0.5 * h,
                    near: near.max(0.0),
                }
            }
        })
    }

    /// Orthonormal camera basis (right, up, forward) of a perspective camera.
    fn basis(&self) -> Result<Basis, Error> {
        let Camera::Perspective {
            eye,
            target,
            up,
            fov_y_deg,
            near,
        } = *self
        else {
            unreachable!("basis of an orthographic camera")
        };
        check_fov(fov_y_deg)?;
        if !(near >= 0.0 && near.is_finite()) {
            return Err(invalid("near", near, "a finite distance >= 0"));
        }
        let d = sub(target, eye);
        let nd = norm(d);
        if !(nd > 0.0 && nd.is_finite()) {
            return Err(invalid("target", format!("{target:?}"), "a finite point different from eye"));
        }
        let forward = scale(1.0 / nd, d);
        let r = cross(forward, up);
        let nr = norm(r);
        if !(nr > 1e-12 * norm(up) && nr.is_finite()) {
            return Err(invalid(
                "up",
                format!("{up:?}"),
                "a finite direction not parallel to target - eye",
            ));
        }
        let right = scale(1.0 / nr, r);
        Ok((right, cross(right, forward), forward))
    }
}

/// Unit vectors (right, up, forward) of a perspective camera, in world coordinates.
type Basis = ([f64; 3], [f64; 3], [f64; 3]);

/// The camera with its per-image constants, ready to project many particles.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Projector {
    Ortho {
        cx: f64,
        cy: f64,
        s: f64,
    },
    Persp {
        eye: [f64; 3],
        right: [f64; 3],
        up: [f64; 3],
        forward: [f64; 3],
        f: f64,
        cx: f64,
        cy: f64,
        near: f64,
    },
}

impl Projector {
    /// Projects a particle at `p` (m) of radius `radius` (m); `None` when it is behind the
    /// camera (nearer than `near`).
    #[inline]
    pub(crate) fn project(&self, p: [f64; 3], radius: f64) -> Option<Projected> {
        match *self {
            Projector::Ortho { cx, cy, s } => Some(Projected {
                x: cx + s * p[0],
                y: cy - s * p[1],
                r: s * radius,
                depth: 0.0,
            }),
            Projector::Persp {
                eye,
                right,
                up,
                forward,
                f,
                cx,
                cy,
                near,
            } => {
                let d = sub(p, eye);
                let zc = dot(d, forward);
                // NaN depths (cannot happen for checked finite input) fall through to `None` too.
                if zc.partial_cmp(&near) != Some(std::cmp::Ordering::Greater) {
                    return None;
                }
                let k = f / zc;
                // The exact outline of a sphere off the axis is an ellipse whose minor radius
                // is f·R/sqrt(zc² − R²) (on the axis); R ≪ zc makes it the disc of radius
                // f·R/zc drawn here, which is also what keeps "twice as far, half as big".
                Some(Projected {
                    x: cx + k * dot(d, right),
                    y: cy - k * dot(d, up),
                    r: k * radius,
                    depth: zc,
                })
            }
        }
    }
}

impl Projector {
    /// Camera coordinates (xc, yc, zc) of a world point: right, up and along the view axis,
    /// m from the eye. Perspective only; the orthographic camera returns (x, y, 0).
    #[inline]
    pub(crate) fn camera_coords(&self, p: [f64; 3]) -> [f64; 3] {
        match *self {
            Projector::Ortho { .. } => [p[0], p[1], 0.0],
            Projector::Persp {
                eye, right, up, forward, ..
            } => {
                let d = sub(p, eye);
                [dot(d, right), dot(d, up), dot(d, forward)]
            }
        }
    }

    /// The focal length f and the image centre (cx, cy), pixels, of a perspective camera
    /// (a point at camera coordinates (x, y, z) lands at (cx + f·x/z, cy − f·y/z)); the
    /// orthographic camera's scale and offsets.
    pub(crate) fn focal(&self) -> (f64, f64, f64) {
        match *self {
            Projector::Ortho { cx, cy, s } => (s, cx, cy),
            Projector::Persp { f, cx, cy, .. } => (f, cx, cy),
        }
    }

    /// Pixel position of a point given in camera coordinates with zc > 0 (the pinhole
    /// projection of [`Projector::project`]); for the orthographic camera, of the world point
    /// (x, y, ·).
    #[inline]
    pub(crate) fn camera_to_pixel(&self, c: [f64; 3]) -> [f64; 2] {
        match *self {
            Projector::Ortho { cx, cy, s } => [cx + s * c[0], cy - s * c[1]],
            Projector::Persp { f, cx, cy, .. } => {
                let k = f / c[2];
                [cx + k * c[0], cy - k * c[1]]
            }
        }
    }
}

pub(crate) fn invalid(parameter: &str, value: impl std::fmt::Display, allowed: &str) -> Error {
    Error::InvalidParameter {
        parameter: parameter.to_string(),
        value: value.to_string(),
        allowed: allowed.to_string(),
    }
}

pub(crate) fn check_size(width: usize, height: usize) -> Result<(), Error> {
    const MAX: usize = 1 << 15;
    if width == 0 || width > MAX {
        return Err(invalid("width", width, "1 ..= 32768 pixels"));
    }
    if height == 0 || height > MAX {
        return Err(invalid("height", height, "1 ..= 32768 pixels"));
    }
    Ok(())
}

fn check_fov(fov_y_deg: f64) -> Result<(), Error> {
    if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
        return Err(invalid(
            "fov_y_deg",
            fov_y_deg,
            "an angle in degrees strictly between 0 and 180",
        ));
    }
    Ok(())
}

/// The checks of [`Camera::frame_points`]' arguments: the unit direction of `from`.
fn check_framing(
    points: &[[f64; 3]],
    from: [f64; 3],
    fov_y_deg: f64,
    (width, height): (usize, usize),
    window: [f64; 4],
) -> Result<[f64; 3], Error> {
    check_size(width, height)?;
    check_fov(fov_y_deg)?;
    if points.is_empty() || !points.iter().flatten().all(|c| c.is_finite()) {
        return Err(invalid(
            "points",
            format!("{} points", points.len()),
            "at least one point, finite",
        ));
    }
    let (w, h) = (width as f64, height as f64);
    let [x0, y0, x1, y1] = window;
    if !(0.0 <= x0 && x0 < x1 && x1 <= w && 0.0 <= y0 && y0 < y1 && y1 <= h) {
        return Err(invalid(
            "window",
            format!("{window:?}"),
            &format!("x0 < x1 within [0, {width}] and y0 < y1 within [0, {height}] pixels"),
        ));
    }
    let n = norm(from);
    if !(n > 0.0 && n.is_finite()) {
        return Err(invalid("from", format!("{from:?}"), "a finite non-zero direction"));
    }
    Ok(scale(1.0 / n, from))
}

/// The camera basis of a view from the unit direction `dir` (from the scene towards the
/// eye): the world's up (z, or y when looking along z), forward, right and the image's up.
fn view_basis(dir: [f64; 3]) -> ([f64; 3], [f64; 3], [f64; 3], [f64; 3]) {
    let world_up = if dir[0].abs() < 1e-9 && dir[1].abs() < 1e-9 {
        [0.0, 1.0, 0.0]
    } else {
        [0.0, 0.0, 1.0]
    };
    let forward = scale(-1.0, dir);
    let right = {
        let r = cross(forward, world_up);
        scale(1.0 / norm(r), r)
    };
    let up = cross(right, forward);
    (world_up, forward, right, up)
}

/// The least eye distance D at which every point of `local` (camera basis, from the
/// points' centre) fits between the window's sides (t0, t1) as tangents along axis k:
/// (maxᵢ(xᵢ − t1 zᵢ) − minᵢ(xᵢ − t0 zᵢ)) / (t1 − t0).
fn least_distance(local: &[[f64; 3]], k: usize, (t0, t1): (f64, f64)) -> f64 {
    let top = local.iter().map(|q| q[k] - t1 * q[2]).fold(f64::NEG_INFINITY, f64::max);
    let bottom = local.iter().map(|q| q[k] - t0 * q[2]).fold(f64::INFINITY, f64::min);
    (top - bottom) / (t1 - t0)
}

/// The eye's shift along axis k at `distance` that centres the points' projected extent
/// between the window's sides (t0, t1): the feasible range, then bisection (the extent's
/// midpoint falls as the shift grows).
fn centring_shift(local: &[[f64; 3]], k: usize, (t0, t1): (f64, f64), distance: f64) -> f64 {
    let lo_s = local
        .iter()
        .map(|q| q[k] - t1 * (q[2] + distance))
        .fold(f64::NEG_INFINITY, f64::max);
    let hi_s = local
        .iter()
        .map(|q| q[k] - t0 * (q[2] + distance))
        .fold(f64::INFINITY, f64::min);
    let (mut a, mut b) = (lo_s.min(hi_s), lo_s.max(hi_s));
    let target = t0 + t1;
    let mid = |s: f64| {
        let (mut u0, mut u1) = (f64::INFINITY, f64::NEG_INFINITY);
        for q in local {
            let u = (q[k] - s) / (q[2] + distance);
            u0 = u0.min(u);
            u1 = u1.max(u);
        }
        u0 + u1
    };
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if mid(m) > target {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}
