//! What the collision stages report, as Python dicts of arrays and back: the contacts, what
//! the particles gave each collider (books), the begin and end of touch events, and the
//! collision statistics (`World.contacts`, `collider_books`, `contact_events`,
//! `collision_stats`, and a checkpoint's restore of the last three).

use kinema::collide::{ContactReport, Partner};
use kinema::world::CollisionStats;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The contacts as arrays: `i`, `j` (−1 against a collider), `collider` (−1 between
/// particles), `normal` (K, 3), `overlap`, `u_n`, `point` (K, 3), `force_n` and `force_t`
/// (K, 3), `sliding`; with `impulses` (the impulse model) also `impulse_n` and `impulse_t`
/// (K, 3).
pub fn contacts_dict<'py>(py: Python<'py>, reports: &[ContactReport], impulses: bool) -> PyResult<Bound<'py, PyDict>> {
    let k = reports.len();
    let (mut i, mut j, mut collider) = (Vec::new(), Vec::new(), Vec::new());
    let (mut normal, mut overlap, mut u_n) = (Vec::new(), Vec::new(), Vec::new());
    let (mut point, mut force_n, mut force_t, mut sliding) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut impulse_n, mut impulse_t) = (Vec::new(), Vec::new());
    for r in reports {
        let c = &r.contact;
        i.push(c.i as i64);
        let (pj, pk) = match c.other {
            Partner::Particle(j) => (j as i64, -1),
            Partner::Collider(k) => (-1, k as i64),
        };
        j.push(pj);
        collider.push(pk);
        normal.extend_from_slice(&c.normal);
        overlap.push(c.overlap);
        u_n.push(c.u_n);
        point.extend_from_slice(&r.point);
        force_n.extend_from_slice(&r.force_n);
        force_t.extend_from_slice(&r.force_t);
        sliding.push(r.sliding);
        impulse_n.extend_from_slice(&r.impulse[0]);
        impulse_t.extend_from_slice(&r.impulse[1]);
    }
    let out = PyDict::new(py);
    let rows = |v: Vec<f64>| PyArray1::from_vec(py, v).reshape([k, 3]);
    out.set_item("i", PyArray1::from_vec(py, i))?;
    out.set_item("j", PyArray1::from_vec(py, j))?;
    out.set_item("collider", PyArray1::from_vec(py, collider))?;
    out.set_item("normal", rows(normal)?)?;
    out.set_item("overlap", PyArray1::from_vec(py, overlap))?;
    out.set_item("u_n", PyArray1::from_vec(py, u_n))?;
    out.set_item("point", rows(point)?)?;
    out.set_item("force_n", rows(force_n)?)?;
    out.set_item("force_t", rows(force_t)?)?;
    out.set_item("sliding", PyArray1::from_vec(py, sliding))?;
    if impulses {
        out.set_item("impulse_n", rows(impulse_n)?)?;
        out.set_item("impulse_t", rows(impulse_t)?)?;
    }
    Ok(out)
}

/// What each collider took, as arrays (`World.collider_books`): `momentum`,
/// `angular_momentum`, `normal`, `tangential` (K, 3) and `work` (K,).
pub fn books_dict<'py>(py: Python<'py>, books: &[kinema::world::ColliderBooks]) -> PyResult<Bound<'py, PyDict>> {
    let n = books.len();
    let rows = |f: fn(&kinema::world::ColliderBooks) -> [f64; 3]| {
        PyArray1::from_vec(py, books.iter().flat_map(f).collect::<Vec<f64>>()).reshape([n, 3])
    };
    let out = PyDict::new(py);
    out.set_item("momentum", rows(|b| b.momentum)?)?;
    out.set_item("angular_momentum", rows(|b| b.angular_momentum)?)?;
    out.set_item("work", PyArray1::from_vec(py, books.iter().map(|b| b.work).collect()))?;
    out.set_item("normal", rows(|b| b.normal)?)?;
    out.set_item("tangential", rows(|b| b.tangential)?)?;
    Ok(out)
}

/// [`books_dict`]'s arrays back (a checkpoint's): one row per collider.
pub fn books_from(d: &Bound<'_, PyDict>) -> PyResult<Vec<kinema::world::ColliderBooks>> {
    let values = |key: &str| -> PyResult<Vec<f64>> {
        let item = d
            .get_item(key)?
            .ok_or_else(|| pyo3::exceptions::PyValueError::new_err(format!("collider books: '{key}' is missing")))?;
        let a: numpy::PyReadonlyArrayDyn<'_, f64> = item.extract()?;
        Ok(a.as_array().iter().copied().collect())
    };
    let (p, l, w, n, t) = (
        values("momentum")?,
        values("angular_momentum")?,
        values("work")?,
        values("normal")?,
        values("tangential")?,
    );
    let k = w.len();
    if [&p, &l, &n, &t].iter().any(|v| v.len() != 3 * k) {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "collider books: each of momentum, angular_momentum, normal and tangential must hold 3 numbers per collider ({k})"
        )));
    }
    let three = |v: &[f64], c: usize| [v[3 * c], v[3 * c + 1], v[3 * c + 2]];
    Ok((0..k)
        .map(|c| kinema::world::ColliderBooks {
            momentum: three(&p, c),
            angular_momentum: three(&l, c),
            work: w[c],
            normal: three(&n, c),
            tangential: three(&t, c),
        })
        .collect())
}

/// Begin and end of touch events as arrays: `time`, `begin` (bool), `i` and `j` (ids; −1
/// against a collider), `collider` (−1 between particles) and `impulse`.
pub fn touch_events_dict<'py>(py: Python<'py>, events: &[kinema::collide::TouchEvent]) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let ids = |f: &dyn Fn(&kinema::collide::TouchEvent) -> Option<u64>| -> Vec<i64> {
        events.iter().map(|e| f(e).map_or(-1, |v| v as i64)).collect()
    };
    out.set_item("time", PyArray1::from_vec(py, events.iter().map(|e| e.time).collect()))?;
    out.set_item("begin", PyArray1::from_vec(py, events.iter().map(|e| e.begin).collect()))?;
    out.set_item("i", PyArray1::from_vec(py, ids(&|e| Some(e.i))))?;
    out.set_item("j", PyArray1::from_vec(py, ids(&|e| e.j)))?;
    out.set_item("collider", PyArray1::from_vec(py, ids(&|e| e.collider.map(|k| k as u64))))?;
    out.set_item("impulse", PyArray1::from_vec(py, events.iter().map(|e| e.impulse).collect()))?;
    Ok(out)
}

pub fn stats_dict<'py>(py: Python<'py>, s: &CollisionStats) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("contacts", s.contacts)?;
    out.set_item("resting", s.resting)?;
    out.set_item("speculative", s.speculative)?;
    out.set_item("bounced", s.bounced)?;
    out.set_item("impacts", s.impacts)?;
    out.set_item("impulses", s.impulses)?;
    out.set_item("impulse_balance", PyArray1::from_slice(py, &s.impulse_balance))?;
    out.set_item("energy_lost", s.energy_lost)?;
    out.set_item("virial", PyArray1::from_slice(py, &s.virial).reshape([3, 3])?)?;
    out.set_item("max_overlap", s.max_overlap)?;
    out.set_item("solver_sweeps", s.solver_sweeps)?;
    out.set_item("islands", s.islands)?;
    out.set_item("asleep", s.asleep)?;
    out.set_item("asleep_contacts", s.asleep_contacts)?;
    out.set_item("slept", s.slept)?;
    out.set_item("woke", s.woke)?;
    out.set_item("unconverged", s.unconverged)?;
    // (over one step: whether its solver converged; over many: whether every step's did)
    out.set_item("converged", s.unconverged == 0)?;
    Ok(out)
}

/// The reverse of [`stats_dict`], for a checkpoint's collision books.
pub fn stats_from(d: &Bound<'_, PyDict>) -> PyResult<CollisionStats> {
    let get = |key: &str| -> PyResult<Bound<'_, PyAny>> {
        d.get_item(key)?
            .ok_or_else(|| pyo3::exceptions::PyValueError::new_err(format!("collision stats: {key} is missing")))
    };
    // (checkpoints written before these figures existed lack them: 0)
    let count = |key: &str| -> PyResult<usize> { d.get_item(key)?.map_or(Ok(0), |v| v.extract()) };
    Ok(CollisionStats {
        contacts: get("contacts")?.extract()?,
        resting: count("resting")?,
        speculative: count("speculative")?,
        bounced: count("bounced")?,
        impacts: get("impacts")?.extract()?,
        impulses: get("impulses")?.extract()?,
        impulse_balance: get("impulse_balance")?.extract()?,
        energy_lost: get("energy_lost")?.extract()?,
        virial: match d.get_item("virial")? {
            Some(v) => {
                let flat: Vec<f64> = v.call_method0("ravel")?.extract()?;
                flat.try_into()
                    .map_err(|_| pyo3::exceptions::PyValueError::new_err("collision stats: virial must hold 3 × 3 values"))?
            }
            None => [0.0; 9],
        },
        max_overlap: get("max_overlap")?.extract()?,
        solver_sweeps: get("solver_sweeps")?.extract()?,
        islands: get("islands")?.extract()?,
        asleep: count("asleep")?,
        asleep_contacts: count("asleep_contacts")?,
        slept: count("slept")?,
        woke: count("woke")?,
        unconverged: get("unconverged")?.extract()?,
    })
}
