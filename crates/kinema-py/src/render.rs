//! Bindings of the off-screen renderer: one frame from NumPy arrays, colormaps, camera framing.

use std::borrow::Cow;

use kinema::render::{
    categorical, collider_boxes, render_frame as render_core, scene_extent, text, yuv, Camera, Colormap, Frame, Region,
    RenderParams, Scenery,
};
use numpy::ndarray::Dimension;
use numpy::{
    Element, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::collisions::{self, Description};
use crate::errors::to_py;

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

#[pymethods]
impl PyScenery {
    /// `colliders`: descriptions as `Trajectory.colliders` holds them; `positions`: (P, 3),
    /// m, the particles of every frame (NaN where one is not alive); `radius`: (N,), m. An
    /// error names the collider (`colliders[2].radius`).
    #[new]
    fn new(
        py: Python<'_>,
        colliders: Vec<Description>,
        positions: PyReadonlyArray2<'_, f64>,
        radius: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        if positions.shape()[1] != 3 {
            return Err(bad(
                "positions",
                format!("an array of shape {:?}", positions.shape()),
                "shape (P, 3)",
            ));
        }
        let colliders = collisions::colliders(&colliders).map_err(to_py)?;
        let (pos, rad) = (data(&positions), data(&radius));
        let extent = py.detach(|| scene_extent(&pos, &rad, &colliders)).map_err(to_py)?;
        Ok(PyScenery {
            inner: Scenery {
                colliders,
                extent: Some(extent),
            },
        })
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

/// Renders one frame; returns an (height, width, 3) uint8 array. The GIL is released while
/// colours are mapped and pixels are drawn.
///
/// `scenery`: a `Scenery`, the colliders drawn with the particles and the extent that
/// sizes planes and clamps infinite box bounds.
/// `springs`: (S, 2) integer indices of particles joined by a line `spring_width` pixels wide.
#[pyfunction]
#[pyo3(signature = (
    positions, radius, *, colors=None, values=None, colormap="viridis", vmin=None, vmax=None,
    width=1280, height=720, view=None, eye=None, target=None, up=[0.0, 0.0, 1.0], fov_deg=40.0,
    background=(255, 255, 255), min_radius_px=1.0, label=None, label_scale=2,
    label_color=(0, 0, 0), scenery=None, springs=None, spring_width=1.5
))]
#[allow(clippy::too_many_arguments)]
fn render_frame<'py>(
    py: Python<'py>,
    positions: PyReadonlyArray2<'py, f64>,
    radius: PyReadonlyArray1<'py, f64>,
    colors: Option<PyReadonlyArray2<'py, u8>>,
    values: Option<PyReadonlyArray1<'py, f64>>,
    colormap: &str,
    vmin: Option<f64>,
    vmax: Option<f64>,
    width: usize,
    height: usize,
    view: Option<(f64, f64, f64, f64)>,
    eye: Option<[f64; 3]>,
    target: Option<[f64; 3]>,
    up: [f64; 3],
    fov_deg: f64,
    background: (u8, u8, u8),
    min_radius_px: f64,
    label: Option<&str>,
    label_scale: usize,
    label_color: (u8, u8, u8),
    scenery: Option<Bound<'py, PyScenery>>,
    springs: Option<PyReadonlyArray2<'py, i64>>,
    spring_width: f64,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let springs: Vec<[usize; 2]> = match springs {
        None => Vec::new(),
        Some(a) => {
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
                .collect::<PyResult<_>>()?
        }
    };
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
    let camera = match (view, eye, target) {
        (Some((x0, y0, x1, y1)), None, None) => Camera::fit_2d([x0, y0], [x1, y1], width, height).map_err(to_py)?,
        (None, Some(eye), Some(target)) => Camera::perspective(eye, target, up, fov_deg).map_err(to_py)?,
        _ => {
            return Err(PyValueError::new_err(
                "camera is invalid: give either view=(xmin, ymin, xmax, ymax) for 2D or eye and target for 3D",
            ))
        }
    };
    let colors: Cow<[u8]> = match (colors, values) {
        (Some(c), None) => {
            if c.shape() != [n, 3] {
                return Err(bad(
                    "colors",
                    format!("an array of shape {:?}", c.shape()),
                    &format!("shape ({n}, 3) uint8"),
                ));
            }
            Cow::Owned(data(&c).into_owned())
        }
        (None, Some(v)) => {
            if v.len() != n {
                return Err(bad(
                    "values",
                    format!("an array of length {}", v.len()),
                    &format!("one value per particle ({n})"),
                ));
            }
            let cmap = Colormap::from_name(colormap).map_err(to_py)?;
            let v = data(&v);
            let (lo, hi) = value_range(&v, vmin, vmax);
            let mut out = vec![0u8; 3 * n];
            py.detach(|| cmap.map(&v, lo, hi, &mut out)).map_err(to_py)?;
            Cow::Owned(out)
        }
        (Some(_), Some(_)) => return Err(PyValueError::new_err("colors and values are both given: give one of them")),
        (None, None) => Cow::Owned(vec![0u8; 3 * n]),
    };
    let params = RenderParams {
        background: [background.0, background.1, background.2],
        min_radius_px,
        spring_width_px: spring_width,
        ..RenderParams::new(width, height)
    };
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
        };
        render_core(&camera, &frame, &params, &mut image)?;
        if let Some(label) = label {
            let lc = [label_color.0, label_color.1, label_color.2];
            let margin = 4 * label_scale.max(1);
            text::draw_text(&mut image, width, height, [margin, margin], label_scale, lc, label)?;
        }
        Ok(())
    })
    .map_err(to_py)?;
    PyArray1::from_vec(py, image).reshape([height, width, 3])
}

/// (vmin, vmax): the given ones, or the finite minimum and maximum of the values.
fn value_range(v: &[f64], vmin: Option<f64>, vmax: Option<f64>) -> (f64, f64) {
    let finite = v.iter().copied().filter(|x| x.is_finite());
    let lo = vmin.unwrap_or_else(|| finite.clone().fold(f64::INFINITY, f64::min));
    let hi = vmax.unwrap_or_else(|| finite.fold(f64::NEG_INFINITY, f64::max));
    if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        (0.0, 1.0)
    }
}

/// Colours of values through a named colormap: an (N, 3) uint8 array.
#[pyfunction]
#[pyo3(signature = (values, colormap="viridis", vmin=None, vmax=None))]
fn colormap<'py>(
    py: Python<'py>,
    values: PyReadonlyArray1<'py, f64>,
    colormap: &str,
    vmin: Option<f64>,
    vmax: Option<f64>,
) -> PyResult<Bound<'py, PyArray2<u8>>> {
    let cmap = Colormap::from_name(colormap).map_err(to_py)?;
    let v = data(&values);
    let (lo, hi) = value_range(&v, vmin, vmax);
    let mut out = vec![0u8; 3 * v.len()];
    cmap.map(&v, lo, hi, &mut out).map_err(to_py)?;
    PyArray1::from_vec(py, out).reshape([v.len(), 3])
}

/// Categorical colours (tab10, repeating) of integer ids: an (N, 3) uint8 array.
#[pyfunction]
fn categorical_colors<'py>(py: Python<'py>, ids: PyReadonlyArray1<'py, u64>) -> PyResult<Bound<'py, PyArray2<u8>>> {
    let ids = data(&ids);
    let out: Vec<u8> = ids.iter().flat_map(|&i| categorical(i)).collect();
    PyArray1::from_vec(py, out).reshape([ids.len(), 3])
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
/// `LINE_COLOR` (springs, box edges) and `FRAME_MARGIN`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScenery>()?;
    m.add_function(wrap_pyfunction!(render_frame, m)?)?;
    m.add_function(wrap_pyfunction!(colormap, m)?)?;
    m.add_function(wrap_pyfunction!(categorical_colors, m)?)?;
    m.add_function(wrap_pyfunction!(frame_box, m)?)?;
    m.add_function(wrap_pyfunction!(frame_points, m)?)?;
    m.add_function(wrap_pyfunction!(rgb_to_yuv420p, m)?)?;
    m.add("COLORMAP_NAMES", kinema::render::COLORMAP_NAMES.to_vec())?;
    m.add("LINE_COLOR", kinema::render::paint::LINE_COLOR.to_vec())?;
    m.add("FRAME_MARGIN", kinema::render::FRAME_MARGIN)?;
    Ok(())
}
