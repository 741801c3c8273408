"""Unit quaternions (w, x, y, z) as the exports need them: the product, the conjugate, a
vector turned, and HOOMD-blue's angular momentum of a sphere from its orientation and ω.

kinema's orientation q turns a particle's body frame into the world's: a vector b of the
body is q ⊗ (0, b) ⊗ q* in the world (HOOMD-blue's, OVITO's and LAMMPS's convention)."""

from __future__ import annotations

import numpy as np


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The Hamilton product a ⊗ b of quaternions (..., 4), w first."""
    aw, av = a[..., :1], a[..., 1:]
    bw, bv = b[..., :1], b[..., 1:]
    w = aw * bw - np.sum(av * bv, axis=-1, keepdims=True)
    v = aw * bv + bw * av + np.cross(av, bv)
    return np.concatenate([w, v], axis=-1)


def conjugate(q: np.ndarray) -> np.ndarray:
    """q* = (w, −x, −y, −z): the inverse of a unit quaternion."""
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def pure(v: np.ndarray) -> np.ndarray:
    """The quaternion (0, v) of vectors v (..., 3)."""
    return np.concatenate([np.zeros(v.shape[:-1] + (1,)), v], axis=-1)


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The vectors v (..., 3) turned by the unit quaternions q: (q ⊗ (0, v) ⊗ q*).v."""
    return multiply(multiply(q, pure(v)), conjugate(q))[..., 1:]


def hoomd_angmom(q: np.ndarray, omega: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """HOOMD-blue's `particles/angmom` (..., 4) of spheres of orientation q (..., 4),
    angular velocity ω (..., 3) in the world's frame, rad/s, and moment of inertia I (...,)
    about every axis.

    HOOMD integrates the rotation with the quaternion conjugate momentum p of Kamberaj, Low
    and Neal (J. Chem. Phys. 122, 224114, 2005), and its integrators read the body-frame
    angular momentum back as L_body = ½ (q* ⊗ p).v (the `s = (1/2 conj(q) * p).v` of its
    Langevin and NVE steps). So

        p = 2 q ⊗ (0, L_body),  L_body = I_body ω_body,  ω_body = (q* ⊗ (0, ω) ⊗ q).v,

    ω_body being ω in the particle's own frame. A sphere's inertia tensor is I times the
    identity in every frame (`particles/moment_inertia` = (I, I, I)), so L_body = I ω_body
    and, since q ⊗ (0, ω_body) = q ⊗ q* ⊗ (0, ω) ⊗ q = (0, ω) ⊗ q for a unit q,

        p = 2 I (0, ω) ⊗ q,

    computed here in that first form, which holds for any body: p = 2 q ⊗ (0, I ω_body)."""
    omega_body = multiply(multiply(conjugate(q), pure(omega)), q)[..., 1:]
    return 2.0 * multiply(q, pure(np.asarray(inertia)[..., None] * omega_body))


def omega_of_angmom(q: np.ndarray, p: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """The angular velocity ω (..., 3) in the world's frame of spheres of orientation q,
    HOOMD angular momentum p and moment of inertia I (> 0): ω = q ⊗ (0, L_body / I) ⊗ q*
    with L_body = ½ (q* ⊗ p).v (`hoomd_angmom` inverted); 0 where I = 0."""
    body = 0.5 * multiply(conjugate(q), p)[..., 1:]
    inertia = np.asarray(inertia, dtype=np.float64)[..., None]
    with np.errstate(divide="ignore", invalid="ignore"):
        body = np.where(inertia > 0, body / inertia, 0.0)
    return rotate(q, body)
