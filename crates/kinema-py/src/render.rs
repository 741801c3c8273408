//! Bindings of the off-screen renderer: one frame from NumPy arrays, colormaps, camera framing.

use std::borrow::Cow;

use kinema::collide::{Collider, Pose};
use kinema::render::{
    collider_boxes, render_frame as render_core, scene_extent, text, yuv, Camera, Colormap, Frame, Region, RenderParams, Scenery,
};
use numpy::ndarray::Dimension;
use numpy::{
    Element, PyArray1, PyArray3, PyArrayMethods, PyReadonlyArray, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyReadonlyArray4, PyUntypedArrayMethods,
};
use pyo3::conversion::FromPyObjectOwned;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use crate::collide::{self, Description};
use crate::errors::to_py;

mod colours;

/// The array's data in C order, borrowed when it already is contiguous.
fn data<'a, T: Element + Copy, D: Dimension>(a: &'a PyReadonlyArray<'_, T, D>) -> Cow<'a, [T]> {
    match a.as_slice() {
        Ok(s) => Cow::Borrowed(s),
        Err(_) => Cow::Owned(a.as_array().iter().copied().collect()),
    }
}

fn bad(parameter: &str, got: impl std::fmt::Display, expected: &str) -> PyErr {
    PyValueError::new_err(format!("{parameter} = {got} is invalid: {expected}"))
}

/// The colliders a video draws, made into the engine's once (the conversions `World.add`
/// uses), with the video's extent: the region every frame's scenery is laid out in, so that
/// it stays put while the particles move (`kinema::render::scene_extent`).
#[pyclass(frozen, name = "Scenery", module = "kinema._core")]
pub struct PyScenery {
    inner: Scenery,
}

/// The poses of `(.., C, 3, 4)` matrices [R | o] (x = R x₀ + o), in C order: pivot 0,
/// translation o. Shapes were checked by the caller.
fn poses_of(m: &[f64]) -> Vec<Pose> {
    m.chunks_exact(12)
        .map(|a| Pose {
            rotation: [[a[0], a[1], a[2]], [a[4], a[5], a[6]], [a[8], a[9], a[10]]],
            pivot: [0.0; 3],
            translation: [a[3], a[7], a[11]],
        })
        .collect()
}

#[pymethods]
impl PyScenery {
    /// `colliders`: descriptions as `Trajectory.colliders` holds them; `positions`: (P, 3),
    /// m, the particles of every frame (NaN where one is not alive); `radius`: (N,), m;
    /// `poses`: where moving colliders are at each frame, (F, C, 3, 4) matrices [R | o]
    /// (`kinema.render.descriptions.collider_poses`), so that the extent holds them at every
    /// frame too (None: the colliders as described). An error names the collider
    /// (`colliders[2].radius`).
    #[new]
    #[pyo3(signature = (colliders, positions, radius, poses=None))]
    fn new(
        py: Python<'_>,
        colliders: Vec<Description>,
        positions: PyReadonlyArray2<'_, f64>,
        radius: PyReadonlyArray1<'_, f64>,
        poses: Option<PyReadonlyArray4<'_, f64>>,
    ) -> PyResult<Self> {
        if positions.shape()[1] != 3 {
            return Err(bad(
                "positions",
                format!("an array of shape {:?}", positions.shape()),
                "shape (P, 3)",
            ));
        }
        let colliders = collide::colliders(&colliders).map_err(to_py)?;
        let (pos, rad) = (data(&positions), data(&radius));
        let mut inner = Scenery { colliders, extent: None };
        // The extent of a scene with moving colliders holds them at every frame's pose.
        let mut every: Vec<Collider> = Vec::new();
        if let Some(poses) = &poses {
            let shape = poses.shape();
            if shape[1] != inner.colliders.len() || shape[2] != 3 || shape[3] != 4 {
                return Err(bad(
                    "poses",
                    format!("an array of shape {shape:?}"),
                    &format!(
                        "shape (F, {}, 3, 4): a matrix [R | o] per frame and collider",
                        inner.colliders.len()
                    ),
                ));
            }
            for frame in poses_of(&data(poses)).chunks_exact(inner.colliders.len().max(1)) {
                every.extend(inner.posed(frame).map_err(to_py)?.colliders);
            }
        }
        let all = if every.is_empty() { &inner.colliders } else { &every };
        inner.extent = Some(py.detach(|| scene_extent(&pos, &rad, all)).map_err(to_py)?);
        Ok(PyScenery { inner })
    }

    /// The same scenery with its colliders where `poses` ((C, 3, 4) matrices [R | o], one per
    /// collider, from `collider_poses` at a frame's time) put them, its extent kept: one
    /// frame of a video with moving colliders (`kinema::render::Scenery::posed`).
    fn posed(&self, py: Python<'_>, poses: PyReadonlyArray3<'_, f64>) -> PyResult<Self> {
        let shape = poses.shape();
        if shape[0] != self.inner.colliders.len() || shape[1] != 3 || shape[2] != 4 {
            return Err(bad(
                "poses",
                format!("an array of shape {shape:?}"),
                &format!("shape ({}, 3, 4): a matrix [R | o] per collider", self.inner.colliders.len()),
            ));
        }
        let poses = poses_of(&data(&poses));
        let inner = py.detach(|| self.inner.posed(&poses)).map_err(to_py)?;
        Ok(PyScenery { inner })
    }

    /// (lo, hi), m: the region the scenery is laid out in.
    #[getter]
    fn extent(&self) -> Region {
        self.inner.extent.expect("made with its extent")
    }

    /// (lo, hi) of each box and sphere obstacle, in order, a box's infinite bounds at the
    /// extent's: what the default 3D camera frames besides the particles.
    #[getter]
    fn boxes(&self) -> Vec<Region> {
        collider_boxes(&self.inner.colliders, self.extent())
    }

    fn __len__(&self) -> usize {
        self.inner.colliders.len()
    }
}

/// The keyword arguments of `render_frame`, which each group below reads by name (`get`),
/// with its default where one is not given.
struct Keywords<'a, 'py> {
    py: Python<'py>,
    given: Option<&'a Bound<'py, PyDict>>,
}

/// The names `render_frame` takes after `positions` and `radius`, in the order of its
/// signature.
const KEYWORDS: [&str; 25] = [
    "colors",
    "values",
    "colormap",
    "vmin",
    "vmax",
    "width",
    "height",
    "view",
    "eye",
    "target",
    "up",
    "fov_deg",
    "background",
    "min_radius_px",
    "label",
    "label_scale",
    "label_color",
    "scenery",
    "springs",
    "spring_width",
    "trails",
    "trail_width",
    "markers",
    "marker_radius",
    "label_at",
];

impl<'a, 'py> Keywords<'a, 'py> {
    /// The keywords given; a name `render_frame` does not take is a TypeError, as Python's
    /// own functions raise it.
    fn new(py: Python<'py>, given: Option<&'a Bound<'py, PyDict>>) -> PyResult<Self> {
        for name in given.into_iter().flat_map(|d| d.keys()) {
            let name: String = name.extract()?;
            if !KEYWORDS.contains(&name.as_str()) {
                return Err(PyTypeError::new_err(format!(
                    "render_frame() got an unexpected keyword argument '{name}'"
                )));
            }
        }
        Ok(Keywords { py, given })
    }

    /// The value of keyword `name`, or `default` when it is not given; a value of the wrong
    /// type is a TypeError that names the argument.
    fn get<T: FromPyObjectOwned<'py>>(&self, name: &str, default: T) -> PyResult<T> {
        let Some(value) = self.given.map(|d| d.get_item(name)).transpose()?.flatten() else {
            return Ok(default);
        };
        value.extract::<T>().map_err(|e| {
            let e: PyErr = e.into();
            if e.is_instance_of::<PyTypeError>(self.py) {
                PyTypeError::new_err(format!("argument '{name}': {}", e.value(self.py)))
            } else {
                e
            }
        })
    }
}

/// The camera: `view` = (xmin, ymin, xmax, ymax), m, for a 2D frame, or `eye` and `target`
/// (m) with `up` and the vertical field of view `fov_deg` (degrees) for a 3D one.
struct CameraArgs {
    view: Option<(f64, f64, f64, f64)>,
    eye: Option<[f64; 3]>,
    target: Option<[f64; 3]>,
    up: [f64; 3],
    fov_deg: f64,
}

impl CameraArgs {
    fn read(kw: &Keywords) -> PyResult<Self> {
        Ok(CameraArgs {
            view: kw.get("view", None)?,
            eye: kw.get("eye", None)?,
            target: kw.get("target", None)?,
            up: kw.get("up", [0.0, 0.0, 1.0])?,
            fov_deg: kw.get("fov_deg", 40.0)?,
        })
    }

    /// The camera of a `width × height` frame.
    fn camera(&self, width: usize, height: usize) -> PyResult<Camera> {
        match (self.view, self.eye, self.target) {
            (Some((x0, y0, x1, y1)), None, None) => Camera::fit_2d([x0, y0], [x1, y1], width, height).map_err(to_py),
            (None, Some(eye), Some(target)) => Camera::perspective(eye, target, self.up, self.fov_deg).map_err(to_py),
            _ => Err(PyValueError::new_err(
                "camera is invalid: give either view=(xmin, ymin, xmax, ymax) for 2D or eye and target for 3D",
            )),
        }
    }
}

/// The particles' colours: fixed `colors` ((N, 3) uint8), or `values` ((N,)) through the
/// colormap `colormap` from `vmin` to `vmax` (default: the values' finite range); black
/// without either.
struct ColourArgs<'py> {
    colors: Option<PyReadonlyArray2<'py, u8>>,
    values: Option<PyReadonlyArray1<'py, f64>>,
    colormap: String,
    vmin: Option<f64>,
    vmax: Option<f64>,
}

impl<'py> ColourArgs<'py> {
    fn read(kw: &Keywords<'_, 'py>) -> PyResult<Self> {
        Ok(ColourArgs {
            colors: kw.get("colors", None)?,
            values: kw.get("values", None)?,
            colormap: kw.get("colormap", "viridis".to_string())?,
            vmin: kw.get("vmin", None)?,
            vmax: kw.get("vmax", None)?,
        })
    }

    /// RGB8 of each of the `n` particles; the GIL is released while values are mapped.
    fn colours(&self, py: Python<'_>, n: usize) -> PyResult<Vec<u8>> {
        match (&self.colors, &self.values) {
            (Some(c), None) => {
                if c.shape() != [n, 3] {
                    return Err(bad(
                        "colors",
                        format!("an array of shape {:?}", c.shape()),
                        &format!("shape ({n}, 3) uint8"),
                    ));
                }
                Ok(data(c).into_owned())
            }
            (None, Some(v)) => {
                if v.len() != n {
                    return Err(bad(
                        "values",
                        format!("an array of length {}", v.len()),
                        &format!("one value per particle ({n})"),
                    ));
                }
                let cmap = Colormap::from_name(&self.colormap).map_err(to_py)?;
                let v = data(v);
                let (lo, hi) = colours::value_range(&v, self.vmin, self.vmax);
                let mut out = vec![0u8; 3 * n];
                py.detach(|| cmap.map(&v, lo, hi, &mut out)).map_err(to_py)?;
                Ok(out)
            }
            (Some(_), Some(_)) => Err(PyValueError::new_err("colors and values are both given: give one of them")),
            (None, None) => Ok(vec![0u8; 3 * n]),
        }
    }
}

/// The image: `width × height` pixels, `background` RGB8, the smallest drawn radius
/// `min_radius_px` (pixels) and the springs' width `spring_width` (pixels).
struct ImageArgs {
    width: usize,
    height: usize,
    background: (u8, u8, u8),
    min_radius_px: f64,
    spring_width: f64,
    trail_width: f64,
    marker_radius: f64,
}

impl ImageArgs {
    fn read(kw: &Keywords) -> PyResult<Self> {
        Ok(ImageArgs {
            width: kw.get("width", 1280)?,
            height: kw.get("height", 720)?,
            background: kw.get("background", (255, 255, 255))?,
            min_radius_px: kw.get("min_radius_px", 1.0)?,
            spring_width: kw.get("spring_width", 1.5)?,
            trail_width: kw.get("trail_width", 1.5)?,
            marker_radius: kw.get("marker_radius", 5.0)?,
        })
    }

    fn params(&self) -> RenderParams {
        RenderParams {
            background: [self.background.0, self.background.1, self.background.2],
            min_radius_px: self.min_radius_px,
            spring_width_px: self.spring_width,
            trail_width_px: self.trail_width,
            marker_radius_px: self.marker_radius,
            ..RenderParams::new(self.width, self.height)
        }
    }
}

/// The time stamp: `label` (none by default), its glyphs `label_scale` times the font's
/// pixels, in `label_color` (RGB8), its top left corner at `label_at` (column, row) pixels,
/// by default 4 glyph pixels from the top left corner of the frame.
struct LabelArgs {
    label: Option<String>,
    label_scale: usize,
    label_color: (u8, u8, u8),
    label_at: Option<(usize, usize)>,
}

impl LabelArgs {
    fn read(kw: &Keywords) -> PyResult<Self> {
        Ok(LabelArgs {
            label: kw.get("label", None)?,
            label_scale: kw.get("label_scale", 2)?,
            label_color: kw.get("label_color", (0, 0, 0))?,
            label_at: kw.get("label_at", None)?,
        })
    }

    /// Stamps the label onto a finished `width × height` frame.
    fn draw(&self, image: &mut [u8], width: usize, height: usize) -> Result<(), kinema::Error> {
        if let Some(label) = &self.label {
            let (c, scale) = (self.label_color, self.label_scale);
            let margin = 4 * scale.max(1);
            let (x, y) = self.label_at.unwrap_or((margin, margin));
            text::draw_text(image, width, height, [x, y], scale, [c.0, c.1, c.2], label)?;
        }
        Ok(())
    }
}

/// (S, 2) particle indices as pairs, checked >= 0 (the engine checks < N).
fn spring_pairs(springs: Option<PyReadonlyArray2<'_, i64>>) -> PyResult<Vec<[usize; 2]>> {
    let Some(a) = springs else {
        return Ok(Vec::new());
    };
    if a.shape()[1] != 2 {
        return Err(bad("springs", format!("an array of shape {:?}", a.shape()), "shape (S, 2)"));
    }
    let v = data(&a);
    v.chunks_exact(2)
        .enumerate()
        .map(|(k, p)| {
            if p[0] < 0 || p[1] < 0 {
                Err(bad(&format!("springs[{k}]"), format!("{p:?}"), "particle indices >= 0"))
            } else {
                Ok([p[0] as usize, p[1] as usize])
            }
        })
        .collect()
}

/// Renders one frame; returns an (height, width, 3) uint8 array. The GIL is released while
/// colours are mapped and pixels are drawn.
///
/// The keywords, by group: the camera (`CameraArgs`), the colours (`ColourArgs`), the image
/// (`ImageArgs`), the time stamp (`LabelArgs`); `scenery`: a `Scenery`, the colliders drawn
/// with the particles and the extent that sizes planes and clamps infinite box bounds;
/// `springs`: (S, 2) integer indices of particles joined by a line `spring_width` pixels wide;
/// `trails`: (N, L, 3) float, m, each particle's recent path (oldest first, NaN breaks it),
/// drawn `trail_width` pixels wide in its colour, fading with age; `markers`: (M, 3), m,
/// points drawn as amber discs of radius `marker_radius` pixels (attractors).
#[pyfunction]
#[pyo3(signature = (positions, radius, **keywords))]
#[pyo3(
    text_signature = "(positions, radius, *, colors=None, values=None, colormap='viridis', vmin=None, vmax=None, \
    width=1280, height=720, view=None, eye=None, target=None, up=[0.0, 0.0, 1.0], fov_deg=40.0, \
    background=(255, 255, 255), min_radius_px=1.0, label=None, label_scale=2, label_color=(0, 0, 0), \
    scenery=None, springs=None, spring_width=1.5, trails=None, trail_width=1.5, markers=None, \
    marker_radius=5.0, label_at=None)"
)]
fn render_frame<'py>(
    py: Python<'py>,
    positions: PyReadonlyArray2<'py, f64>,
    radius: PyReadonlyArray1<'py, f64>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let kw = Keywords::new(py, keywords)?;
    let colouring = ColourArgs::read(&kw)?;
    let look = ImageArgs::read(&kw)?;
    let view = CameraArgs::read(&kw)?;
    let stamp = LabelArgs::read(&kw)?;
    let scenery: Option<Bound<'py, PyScenery>> = kw.get("scenery", None)?;
    let springs = spring_pairs(kw.get("springs", None)?)?;
    let trails: Option<PyReadonlyArray3<'py, f64>> = kw.get("trails", None)?;
    let markers: Option<PyReadonlyArray2<'py, f64>> = kw.get("markers", None)?;
    let n = positions.shape()[0];
    if positions.shape()[1] != 3 {
        return Err(bad(
            "positions",
            format!("an array of shape {:?}", positions.shape()),
            "shape (N, 3)",
        ));
    }
    if radius.len() != n {
        return Err(bad(
            "radius",
            format!("an array of length {}", radius.len()),
            &format!("one radius per particle ({n})"),
        ));
    }
    let trail_len = match &trails {
        Some(a) if a.shape()[0] != n || a.shape()[2] != 3 || a.shape()[1] < 2 => {
            return Err(bad(
                "trails",
                format!("an array of shape {:?}", a.shape()),
                &format!("shape ({n}, L, 3), L >= 2"),
            ))
        }
        Some(a) => a.shape()[1],
        None => 0,
    };
    if let Some(m) = &markers {
        if m.shape()[1] != 3 {
            return Err(bad("markers", format!("an array of shape {:?}", m.shape()), "shape (M, 3)"));
        }
    }
    let trail_points = trails.as_ref().map(data).unwrap_or_default();
    let marker_points = markers.as_ref().map(data).unwrap_or_default();
    let (width, height) = (look.width, look.height);
    let camera = view.camera(width, height)?;
    let colors = colouring.colours(py, n)?;
    let params = look.params();
    let pos = data(&positions);
    let rad = data(&radius);
    let mut image = vec![0u8; width.saturating_mul(height).saturating_mul(3).min(3 << 30)];
    let drawn: &Scenery = scenery.as_ref().map_or(&NO_SCENERY, |s| &s.get().inner);
    py.detach(|| -> Result<(), kinema::Error> {
        let frame = Frame {
            positions: &pos,
            radius: &rad,
            colors: &colors,
            springs: &springs,
            scenery: drawn,
            trails: &trail_points,
            trail_len,
            markers: &marker_points,
        };
        render_core(&camera, &frame, &params, &mut image)?;
        stamp.draw(&mut image, width, height)
    })
    .map_err(to_py)?;
    PyArray1::from_vec(py, image).reshape([height, width, 3])
}

/// (eye, target, up) of a perspective camera framing the box [lo, hi] seen from direction
/// `from_` in a width × height image with vertical field of view fov_deg.
#[pyfunction]
#[pyo3(signature = (lo, hi, from_=[1.0, -1.6, 0.9], fov_deg=40.0, width=1280, height=720))]
#[allow(clippy::type_complexity)]
fn frame_box(
    lo: [f64; 3],
    hi: [f64; 3],
    from_: [f64; 3],
    fov_deg: f64,
    width: usize,
    height: usize,
) -> PyResult<([f64; 3], [f64; 3], [f64; 3])> {
    match Camera::frame_box(lo, hi, from_, fov_deg, width, height).map_err(to_py)? {
        Camera::Perspective { eye, target, up, .. } => Ok((eye, target, up)),
        Camera::Orthographic { .. } => unreachable!("frame_box makes a perspective camera"),
    }
}

/// (eye, target, up, bbox) of a perspective camera looking from direction `from_` whose
/// width × height image shows the (P, 3) points inside `window` = (x0, y0, x1, y1) pixels, as
/// large as that allows; bbox (x0, y0, x1, y1) is where the points land, pixels.
#[pyfunction]
#[pyo3(signature = (points, from_, fov_deg, width, height, window))]
#[allow(clippy::type_complexity)]
fn frame_points(
    points: PyReadonlyArray2<'_, f64>,
    from_: [f64; 3],
    fov_deg: f64,
    width: usize,
    height: usize,
    window: [f64; 4],
) -> PyResult<([f64; 3], [f64; 3], [f64; 3], [f64; 4])> {
    if points.shape()[1] != 3 {
        return Err(bad(
            "points",
            format!("an array of shape {:?}", points.shape()),
            "shape (P, 3)",
        ));
    }
    let pts: Vec<[f64; 3]> = data(&points).chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    match Camera::frame_points(&pts, from_, fov_deg, width, height, window).map_err(to_py)? {
        (Camera::Perspective { eye, target, up, .. }, bbox) => Ok((eye, target, up, bbox)),
        (Camera::Orthographic { .. }, _) => unreachable!("frame_points makes a perspective camera"),
    }
}

/// An (H, W, 3) uint8 RGB frame (H and W even) as YUV 4:2:0 bytes (planes Y, U, V; BT.601
/// limited range) for the H.264 encoder. The GIL is released while converting.
#[pyfunction]
fn rgb_to_yuv420p<'py>(py: Python<'py>, frame: PyReadonlyArray3<'py, u8>) -> PyResult<Bound<'py, PyBytes>> {
    let shape = frame.shape();
    if shape[2] != 3 {
        return Err(bad("frame", format!("an array of shape {shape:?}"), "shape (H, W, 3) uint8"));
    }
    let (h, w) = (shape[0], shape[1]);
    let rgb = data(&frame);
    let mut out = vec![0u8; yuv::yuv420p_len(w, h)];
    py.detach(|| yuv::rgb_to_yuv420p(&rgb, w, h, &mut out)).map_err(to_py)?;
    Ok(PyBytes::new(py, &out))
}

/// No colliders: what a frame without `scenery` draws besides the particles.
static NO_SCENERY: Scenery = Scenery {
    colliders: Vec::new(),
    extent: None,
};

/// Registers the class `Scenery`, the render functions (`render_frame`, `colormap`, `categorical_colors`,
/// `frame_box`, `frame_points`, `rgb_to_yuv420p`) and the constants `COLORMAP_NAMES`,
/// `LINE_COLOR` (springs, box edges), `MARKER_COLOR` (attractors) and `FRAME_MARGIN`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScenery>()?;
    m.add_function(wrap_pyfunction!(render_frame, m)?)?;
    m.add_function(wrap_pyfunction!(colours::colormap, m)?)?;
    m.add_function(wrap_pyfunction!(colours::categorical_colors, m)?)?;
    m.add_function(wrap_pyfunction!(frame_box, m)?)?;
    m.add_function(wrap_pyfunction!(frame_points, m)?)?;
    m.add_function(wrap_pyfunction!(rgb_to_yuv420p, m)?)?;
    m.add("COLORMAP_NAMES", kinema::render::COLORMAP_NAMES.to_vec())?;
    m.add("LINE_COLOR", kinema::render::paint::LINE_COLOR.to_vec())?;
    m.add("MARKER_COLOR", kinema::render::MARKER_COLOR.to_vec())?;
    m.add("FRAME_MARGIN", kinema::render::FRAME_MARGIN)?;
    Ok(())
}
