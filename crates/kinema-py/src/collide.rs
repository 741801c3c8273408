//! Conversions of the collision stages: settings, colliders, materials (what the collisions
//! report, contacts, books, events and statistics, are in `reports.rs`).
//!
//! The `World` methods that use them are thin wrappers in `world.rs` (one `#[pymethods]` block
//! per class); every rule is the engine's, and its errors name the parameter.

use kinema::collide::colliders::{check_planar, PLANE_IN_2D, SPHERE_IN_2D};
use kinema::collide::mesh::mesh_buffer;
use kinema::collide::{BoxContainer, Collider, Material, Motion, Plane, SphereObstacle, Surface, TriangleMesh};
use kinema::world::{Accuracy, Cohesion, CollisionParams, ContactModel, ModelArgs, TangentialArgs, TangentialKind};
use kinema::Error;
use numpy::{PyArray1, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `World.set_collisions`' keyword arguments, read by name from the dict Python passes (the
/// values already checked for their types by Python).
#[derive(FromPyObject)]
pub struct CollisionArgs {
    #[pyo3(item)]
    model: String,
    #[pyo3(item)]
    restitution: f64,
    #[pyo3(item)]
    friction: f64,
    #[pyo3(item)]
    ccd: bool,
    #[pyo3(item)]
    restitution_threshold: Option<f64>,
    #[pyo3(item)]
    sleep_time: Option<f64>,
    #[pyo3(item)]
    sleep_speed: Option<f64>,
    #[pyo3(item)]
    stiffness: Option<f64>,
    #[pyo3(item)]
    damping: Option<f64>,
    #[pyo3(item)]
    youngs_modulus: Option<f64>,
    #[pyo3(item)]
    poisson_ratio: Option<f64>,
    #[pyo3(item)]
    cohesion: Option<String>,
    #[pyo3(item)]
    surface_energy: Option<f64>,
    #[pyo3(item)]
    event_driven: bool,
    #[pyo3(item)]
    rolling_friction: f64,
    #[pyo3(item)]
    tangential: Option<String>,
    #[pyo3(item)]
    tangential_stiffness: Option<f64>,
    #[pyo3(item)]
    tangential_damping: Option<f64>,
    #[pyo3(item)]
    rolling_stiffness: Option<f64>,
    #[pyo3(item)]
    rolling_damping: Option<f64>,
    #[pyo3(item)]
    accuracy: String,
    #[pyo3(item)]
    self_collisions: bool,
}

impl CollisionArgs {
    /// The engine's settings: the model by its name (the engine's rule), the rest as given.
    pub fn params(&self) -> Result<CollisionParams, Error> {
        Ok(CollisionParams {
            model: ContactModel::from_name(
                &self.model,
                ModelArgs {
                    stiffness: self.stiffness,
                    damping: self.damping,
                    youngs_modulus: self.youngs_modulus,
                    poisson_ratio: self.poisson_ratio,
                    cohesion: cohesion_of(self.cohesion.as_deref(), self.surface_energy)?,
                },
            )?,
            restitution: self.restitution,
            friction: self.friction,
            ccd: self.ccd,
            restitution_threshold: self.restitution_threshold,
            sleep_time: self.sleep_time,
            sleep_speed: self.sleep_speed,
            event_driven: self.event_driven,
            rolling_friction: self.rolling_friction,
            tangential: TangentialArgs {
                kind: self.tangential.as_deref().map(TangentialKind::from_name).transpose()?,
                stiffness: self.tangential_stiffness,
                damping: self.tangential_damping,
                rolling_stiffness: self.rolling_stiffness,
                rolling_damping: self.rolling_damping,
            },
            accuracy: Accuracy::from_name(&self.accuracy)?,
            self_collisions: self.self_collisions,
        })
    }
}

/// The cohesion model from its name and the `surface_energy` γ (J/m²): the two go together.
fn cohesion_of(cohesion: Option<&str>, surface_energy: Option<f64>) -> Result<Option<Cohesion>, Error> {
    match (cohesion, surface_energy) {
        (None, None) => Ok(None),
        (None, Some(g)) => Err(Error::invalid(
            "surface_energy",
            g,
            "it is the surface energy of a cohesion model: give cohesion='dmt' or 'jkr' with it",
        )),
        (Some(name), None) => {
            let model = Cohesion::from_name(name, 0.0)?;
            let pull_off = match model {
                Cohesion::Dmt { .. } => "4π γ R*",
                Cohesion::Jkr { .. } => "3π γ R*",
            };
            Err(Error::invalid(
                "surface_energy",
                "None",
                format!("cohesion='{name}' needs the surface energy γ, finite and >= 0 J/m² (its pull-off force is {pull_off})"),
            ))
        }
        (Some(name), Some(g)) => Cohesion::from_name(name, g).map(Some),
    }
}

/// The engine's default collision settings, as `World.set_collisions`' keyword arguments:
/// the one place Python reads them from (its signature, the scene files' defaults).
#[pyfunction]
fn collision_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    params_dict(py, &CollisionParams::default())
}

/// Checks a contact model's name and which of its parameters it takes, by the engine's rule
/// (for the scene files, before any world is built); ValueError otherwise.
#[pyfunction]
#[pyo3(signature = (model, stiffness, damping, youngs_modulus=None, poisson_ratio=None, cohesion=None, surface_energy=None))]
#[allow(clippy::too_many_arguments)]
fn check_contact_model(
    model: &str,
    stiffness: Option<f64>,
    damping: Option<f64>,
    youngs_modulus: Option<f64>,
    poisson_ratio: Option<f64>,
    cohesion: Option<&str>,
    surface_energy: Option<f64>,
) -> PyResult<()> {
    let args = ModelArgs {
        stiffness,
        damping,
        youngs_modulus,
        poisson_ratio,
        cohesion: cohesion_of(cohesion, surface_energy).map_err(crate::errors::to_py)?,
    };
    ContactModel::from_name(model, args).map(|_| ()).map_err(crate::errors::to_py)
}

/// A collider's prescribed motion from its parts (the keyword arguments of
/// `World.set_collider_motion` and of `collider_poses`): steady (`velocity`, m/s,
/// `angular_velocity`, rad/s) or keyframes (`times`, s, with `translations`, m, and
/// `rotations`, unit quaternions w, x, y, z), about `pivot` (m); `None` when none is given.
#[allow(clippy::too_many_arguments)]
pub fn motion(
    velocity: Option<[f64; 3]>,
    angular_velocity: Option<[f64; 3]>,
    pivot: Option<[f64; 3]>,
    times: Option<Vec<f64>>,
    translations: Option<Vec<[f64; 3]>>,
    rotations: Option<Vec<[f64; 4]>>,
    start: Option<f64>,
) -> Result<Option<Motion>, Error> {
    let pivot = pivot.unwrap_or([0.0; 3]);
    match (times, velocity.is_some() || angular_velocity.is_some()) {
        (Some(_), true) => Err(Error::invalid(
            "times",
            "given with a velocity",
            "a collider's motion is steady (velocity, angular_velocity) or keyframes (times, translations, rotations), not both",
        )),
        (Some(times), false) => {
            let n = times.len();
            let translations = translations.unwrap_or_else(|| vec![[0.0; 3]; n]);
            let rotations = rotations.unwrap_or_else(|| vec![[1.0, 0.0, 0.0, 0.0]; n]);
            Motion::keyframes(times, translations, rotations, pivot).map(Some)
        }
        (None, true) => Motion::steady(velocity.unwrap_or([0.0; 3]), angular_velocity.unwrap_or([0.0; 3]), pivot)
            .and_then(|m| m.starting_at(start.unwrap_or(0.0)))
            .map(Some),
        (None, false) => Ok(None),
    }
}

/// Where a collider with this motion is at each of `at` (s): (len(at), 3, 4) matrices
/// [R | o] with x = R x₀ + o for a point x₀ of its placement as added (m); the one
/// implementation of the motion that the pictures, the viewer and the USD export share.
#[pyfunction]
#[pyo3(signature = (at, velocity=None, angular_velocity=None, pivot=None, times=None, translations=None, rotations=None, start=None))]
#[allow(clippy::too_many_arguments)]
fn collider_poses<'py>(
    py: Python<'py>,
    at: Vec<f64>,
    velocity: Option<[f64; 3]>,
    angular_velocity: Option<[f64; 3]>,
    pivot: Option<[f64; 3]>,
    times: Option<Vec<f64>>,
    translations: Option<Vec<[f64; 3]>>,
    rotations: Option<Vec<[f64; 4]>>,
    start: Option<f64>,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let m = motion(velocity, angular_velocity, pivot, times, translations, rotations, start).map_err(crate::errors::to_py)?;
    let mut out = Vec::with_capacity(12 * at.len());
    for &t in &at {
        let pose = m.as_ref().map_or(kinema::collide::Pose::IDENTITY, |m| m.at(t).0);
        let o = pose.point([0.0; 3]);
        for (row, oc) in pose.rotation.iter().zip(o) {
            out.extend_from_slice(row);
            out.push(oc);
        }
    }
    Ok(PyArray1::from_vec(py, out).reshape([at.len(), 3, 4])?)
}

/// The damping ratio ζ of the spring–dashpot contact that bounces back with restitution `e`
/// (in [0, 1]): ζ = −ln e / √(π² + ln² e), 1 for e = 0 (`kinema::collide::damping_ratio`,
/// the one place it is computed; `kinema.contact_time` asks it here). ValueError outside.
#[pyfunction]
fn damping_ratio(e: f64) -> PyResult<f64> {
    kinema::collide::damping_ratio(e).map_err(crate::errors::to_py)
}

/// Registers the module-level functions of the collision settings.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(damping_ratio, m)?)?;
    m.add_function(wrap_pyfunction!(collider_poses, m)?)?;
    m.add_function(wrap_pyfunction!(collision_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(check_contact_model, m)?)?;
    m.add("CONTACT_MODELS", ContactModel::NAMES.to_vec())?;
    m.add("FORCE_MODELS", ContactModel::FORCE_MODELS.to_vec())?;
    m.add("TANGENTIAL_MODELS", TangentialKind::NAMES.to_vec())?;
    // the force models' sub-models (kind, name, LAMMPS's name, the settings that choose it)
    let sub_models: Vec<_> = kinema::collide::SUB_MODELS
        .iter()
        .map(|m| (m.kind.name(), m.name, m.lammps, m.chosen_by))
        .collect();
    m.add("CONTACT_SUB_MODELS", sub_models)?;
    m.add("ACCURACIES", Accuracy::NAMES.to_vec())?;
    Ok(())
}

/// The settings as the keyword arguments of `World.set_collisions` (so that they round-trip).
pub fn params_dict<'py>(py: Python<'py>, p: &CollisionParams) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let (model, args) = p.model.named();
    out.set_item("model", model)?;
    out.set_item("restitution", p.restitution)?;
    out.set_item("friction", p.friction)?;
    out.set_item("ccd", p.ccd)?;
    out.set_item("restitution_threshold", p.restitution_threshold)?;
    out.set_item("sleep_time", p.sleep_time)?;
    out.set_item("sleep_speed", p.sleep_speed)?;
    out.set_item("stiffness", args.stiffness)?;
    out.set_item("damping", args.damping)?;
    out.set_item("youngs_modulus", args.youngs_modulus)?;
    out.set_item("poisson_ratio", args.poisson_ratio)?;
    out.set_item("cohesion", args.cohesion.map(|c| c.name()))?;
    out.set_item("surface_energy", args.cohesion.map(|c| c.surface_energy()))?;
    out.set_item("event_driven", p.event_driven)?;
    out.set_item("rolling_friction", p.rolling_friction)?;
    let t = p.tangential;
    out.set_item("tangential", t.kind.map(|k| k.name()))?;
    out.set_item("tangential_stiffness", t.stiffness)?;
    out.set_item("tangential_damping", t.damping)?;
    out.set_item("rolling_stiffness", t.rolling_stiffness)?;
    out.set_item("rolling_damping", t.rolling_damping)?;
    out.set_item("accuracy", p.accuracy.name())?;
    out.set_item("self_collisions", p.self_collisions)?;
    Ok(out)
}

/// A plane, the engine's 2D rule checked on the normal as given (before it is normalised, so
/// that the error names the user's number; `World::add_collider` checks it again).
pub fn plane(dim: usize, point: [f64; 3], normal: [f64; 3], surface: Surface) -> Result<Plane, Error> {
    check_planar(dim, "normal", normal, PLANE_IN_2D)?;
    Plane::new(point, normal, surface)
}

pub fn sphere_obstacle(dim: usize, center: [f64; 3], radius: f64, surface: Surface) -> Result<SphereObstacle, Error> {
    check_planar(dim, "center", center, SPHERE_IN_2D)?;
    SphereObstacle::new(center, radius, surface)
}

/// A box of a 3D world from 3 values per corner, a rectangle of a 2D world (no walls along z)
/// from 2.
pub fn box_container(dim: usize, lo: &[f64], hi: &[f64], surface: Surface) -> Result<BoxContainer, Error> {
    for (name, c) in [("lo", lo), ("hi", hi)] {
        if c.len() != dim {
            return Err(Error::invalid(
                name,
                format!("{c:?}"),
                format!(
                    "a {dim}D world's box has {dim} values per corner ({})",
                    if dim == 2 {
                        "x, y: a rectangle, open along z"
                    } else {
                        "x, y, z"
                    }
                ),
            ));
        }
    }
    if dim == 2 {
        BoxContainer::rect([lo[0], lo[1]], [hi[0], hi[1]], surface)
    } else {
        BoxContainer::new([lo[0], lo[1], lo[2]], [hi[0], hi[1], hi[2]], surface)
    }
}

/// A triangle mesh of `vertices` (m) and `faces` (vertex indices, 3 per face): the indices
/// are checked here (a negative one, or one beyond u32, names its place), the rest by
/// [`TriangleMesh::new`]. `inside`: particles inside a closed mesh. `faces` are read once,
/// into a buffer allocated fallibly (a mesh too large is a `MemoryError`, not an abort).
pub fn mesh(
    vertices: Vec<[f64; 3]>,
    faces: impl ExactSizeIterator<Item = [i64; 3]>,
    inside: bool,
    surface: Surface,
) -> Result<TriangleMesh, Error> {
    let mut tris = mesh_buffer(faces.len(), faces.len())?;
    for (f, face) in faces.enumerate() {
        let mut t = [0u32; 3];
        for k in 0..3 {
            t[k] = u32::try_from(face[k]).map_err(|_| {
                Error::invalid(
                    format!("faces[{f}][{k}]"),
                    face[k],
                    format!("a face's vertex index must be in [0, {})", vertices.len()),
                )
            })?;
        }
        tris.push(t);
    }
    TriangleMesh::new(vertices, tris, inside, surface)
}

/// A collider as a plain description, the dicts `Trajectory.colliders` holds (written by
/// `kinema.render._describe_colliders`): {"type": "plane", "point", "normal"}, {"type":
/// "box", "lo", "hi"} (2 or 3 values per corner, ±inf for an open face), {"type": "sphere",
/// "center", "radius"}, {"type": "mesh", "vertices" (V × 3), "faces" (F × 3), "inside"}, with
/// "restitution" and "friction" where the collider sets them; m.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct Description {
    #[pyo3(item("type"))]
    kind: String,
    #[pyo3(default)]
    point: Option<[f64; 3]>,
    #[pyo3(default)]
    normal: Option<[f64; 3]>,
    #[pyo3(default)]
    lo: Option<Vec<f64>>,
    #[pyo3(default)]
    hi: Option<Vec<f64>>,
    #[pyo3(default)]
    center: Option<[f64; 3]>,
    #[pyo3(default)]
    radius: Option<f64>,
    #[pyo3(default)]
    vertices: Option<Vec<[f64; 3]>>,
    #[pyo3(default)]
    faces: Option<Vec<[i64; 3]>>,
    #[pyo3(default)]
    inside: Option<bool>,
    #[pyo3(default)]
    restitution: Option<f64>,
    #[pyo3(default)]
    friction: Option<f64>,
}

/// The engine's collider of a description, made by the conversions `World.add` uses, with
/// their checks: a box with 2 values per corner is a 2D world's rectangle (open along z),
/// with 3 a 3D world's box; a plane or a sphere is taken as it is (a picture has no 2D rule:
/// the 2D view draws the xy part). Errors name the field (`radius`, `normal[2]`, `hi[1]`).
pub fn collider(d: &Description) -> Result<Collider, Error> {
    let surface = Surface::new(d.restitution, d.friction)?;
    let missing = |needs: &str| {
        Error::invalid(
            "type",
            format!("'{}'", d.kind),
            format!("a {} needs {needs}, and this description lacks one of them", d.kind),
        )
    };
    match (d.kind.as_str(), d.point, d.normal, &d.lo, &d.hi, d.center, d.radius) {
        ("plane", Some(point), Some(normal), ..) => Ok(plane(3, point, normal, surface)?.into()),
        ("plane", ..) => Err(missing("point and normal")),
        ("box", _, _, Some(lo), Some(hi), ..) => {
            let dim = if lo.len() == 2 { 2 } else { 3 };
            Ok(box_container(dim, lo, hi, surface)?.into())
        }
        ("box", ..) => Err(missing("lo and hi")),
        ("sphere", .., Some(center), Some(radius)) => Ok(sphere_obstacle(3, center, radius, surface)?.into()),
        ("sphere", ..) => Err(missing("center and radius")),
        ("mesh", ..) => match (&d.vertices, &d.faces) {
            (Some(v), Some(f)) => Ok(mesh(v.clone(), f.iter().copied(), d.inside.unwrap_or(false), surface)?.into()),
            _ => Err(missing("vertices and faces")),
        },
        (other, ..) => Err(Error::invalid(
            "type",
            format!("'{other}'"),
            "a collider is a 'plane', a 'box', a 'sphere' or a 'mesh'",
        )),
    }
}

/// [`collider`] of each description, in order; an error names the collider by its index
/// (`colliders[2].radius`).
pub fn colliders(descriptions: &[Description]) -> Result<Vec<Collider>, Error> {
    descriptions
        .iter()
        .enumerate()
        .map(|(k, d)| {
            collider(d).map_err(|err| match err {
                Error::InvalidParameter {
                    parameter,
                    value,
                    allowed,
                } => Error::InvalidParameter {
                    parameter: format!("colliders[{k}].{parameter}"),
                    value,
                    allowed,
                },
                other => other,
            })
        })
        .collect()
}

/// Per-particle restitution and friction of `n` new particles (NaN: the world's global value),
/// checked with the engine's rule before anything is added; `None` when no particle has its
/// own (the world then keeps collisions as they are).
#[allow(clippy::type_complexity)]
pub fn materials(
    n: usize,
    restitution: Option<Vec<f64>>,
    friction: Option<Vec<f64>>,
) -> Result<Option<(Vec<Option<f64>>, Vec<Option<f64>>)>, Error> {
    let own = |name: &str, values: Option<Vec<f64>>| -> Result<Vec<Option<f64>>, Error> {
        let values = values.unwrap_or_else(|| vec![f64::NAN; n]);
        if values.len() != n {
            return Err(Error::invalid(
                name,
                format!("{} values", values.len()),
                format!("one per new particle ({n})"),
            ));
        }
        Ok(values.into_iter().map(|v| (!v.is_nan()).then_some(v)).collect())
    };
    let (e, mu) = (own("restitution", restitution)?, own("friction", friction)?);
    if e.iter().chain(&mu).all(Option::is_none) {
        return Ok(None);
    }
    for (k, (ek, mk)) in e.iter().zip(&mu).enumerate() {
        Material::new(ek.unwrap_or(0.0), mk.unwrap_or(0.0)).map_err(|err| match err {
            Error::InvalidParameter {
                parameter,
                value,
                allowed,
            } => Error::InvalidParameter {
                parameter: format!("{parameter}[{k}]"),
                value,
                allowed,
            },
            other => other,
        })?;
    }
    Ok(Some((e, mu)))
}
