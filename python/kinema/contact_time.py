"""How long a contact of the force models lasts, and what a coarse step does to its restitution.

A spring–dashpot contact is a damped oscillator of the pair's reduced mass m* on the spring
k_n: it lasts half a damped period,

    t_c = π / (ω₀ √(1 − ζ²)),   ω₀² = k_n / m*,   ζ = −ln e / √(π² + ln² e)

(ζ ≥ 1, e = 0: π / ω₀, the time to the deepest overlap and back to the start of the spring's
push). A Hertzian contact at approach speed u lasts t_c = 2 I δ_max / u with δ_max = (5 m* u² /
(4 k_h))^(2/5), k_h = 4/3 E* √R*, I = ∫₀¹ dx / √(1 − x^(5/2)) = 1.4716 (Landau & Lifshitz §9):
in terms of the tangent stiffness at δ_max, ω_t² = 3/2 k_h √δ_max / m* = 15/8 (u/δ_max)², so
t_c = 2 I √(15/8) / ω_t = 4.0302 / ω_t. The stable-step advisor's ``standby_omega`` is that ω₀
(ω_t for Hertz: the contact reached at the fastest approach the velocities allow) of the
stiffest contact the particles can make, with the ζ of the least damped; ``contact_time``
turns it into t_c.

A step of more than t_c / 20 (:data:`STEPS_PER_CONTACT`) changes the restitution the contact
gives: the integrator samples the force too coarsely. ``restitution_at`` measures it, on one
head-on pair with the world's method and the same dt / t_c, and the ``ContactTimeWarning``
(issued by ``kinema.first_step`` before the first step, for the fastest impact the scene can
produce) says what it is. Measured (velocity Verlet, a head-on pair; docs/collisions.md has the table
and the command, docs/restitution_table.py): at 10 steps per contact e = 0.3 comes out 0.282
(Hooke) and 0.281 (Hertz), e = 0.1 0.064 and 0.087, at 5 steps 0.229 and 0.238 (and e = 0.1
0.713 with Hooke); at 50 steps within 1 % of the set e.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from . import _core

#: Steps a contact should span at least: below, its restitution drifts (the table above).
STEPS_PER_CONTACT = 20

#: I = ∫₀¹ dx / √(1 − x^(5/2)) (module doc; scipy's quad to 1e-15).
HERTZ_INTEGRAL = 1.471_637_592_162_107

#: t_c ω_t of an elastic Hertzian contact (module doc): 2 I √(15/8) = 4.0302.
HERTZ_TIME_OMEGA = 2 * HERTZ_INTEGRAL * math.sqrt(15 / 8)


class ContactTimeWarning(UserWarning):
    """The time step is coarser than a twentieth of the shortest contact's duration, so the
    spring–dashpot or Hertz contacts bounce with another restitution than the one set."""


def _zeta(e: float) -> float:
    """ζ(e) of the spring–dashpot contact (module doc), as the engine computes it
    (`kinema::collide::damping_ratio`, its one home); 1 for e <= 0."""
    return 1.0 if e <= 0.0 else _core.damping_ratio(min(float(e), 1.0))


def contact_time(model: str, omega: float | None, zeta: float | None) -> float | None:
    """t_c (s) of a contact of ``model`` (``"spring_dashpot"`` or ``"hertz"``) whose stiffest
    mode is ``omega`` (rad/s; the advisor's ``standby_omega``) with damping ratio ``zeta``;
    ``None`` without one."""
    if not omega or omega <= 0.0 or not math.isfinite(omega):
        return None
    if model == "hertz":
        return HERTZ_TIME_OMEGA / omega
    z = zeta or 0.0
    return math.pi / omega if z >= 1.0 else math.pi / (omega * math.sqrt(1.0 - z * z))


def hertz_contact_time(m_star: Any, r_star: Any, e_star: float, u: Any) -> Any:
    """t_c (s) of an elastic Hertzian impact at approach speed ``u`` (m/s) of reduced mass
    ``m_star`` m* (kg) and reduced radius ``r_star`` R* (m), with ``e_star`` E* (Pa):
    2 I δ_max / u, δ_max = (5 m* u² / (4 k_h))^(2/5), k_h = 4/3 E* √R* (module doc). In
    Johnson's form (Contact Mechanics, §11.4: δ_max = (15 m* u² / (16 E* √R*))^(2/5)) it is
    2 I (15/16)^(2/5) (m*² / (R* E*² u))^(1/5) = 2.868 (m*² / (R* E*² u))^(1/5), his 2.87.
    Elementwise on arrays."""
    k_h = 4.0 / 3.0 * e_star * np.sqrt(r_star)
    deepest = (5.0 * m_star * u * u / (4.0 * k_h)) ** 0.4
    return 2.0 * HERTZ_INTEGRAL * deepest / u


def restitution_at(model: str, method: Any, steps_per_contact: float, restitution: float) -> float:
    """The restitution a head-on pair comes out with when its contact of ``model`` spans
    ``steps_per_contact`` steps of ``method``, for the set ``restitution`` (a pair with
    m* = 1 kg, ω₀ = 1 rad/s or k_h = 1 N/m^(3/2) at 1 m/s: the ratio depends on dt / t_c
    alone).

    The pair is stepped by the engine (``_core.World``) itself, not by a ``kinema.World``:
    ``kinema.first_step`` measures this while it checks a ``kinema.World``, so building one
    here would tie this module into a circle with ``kinema.world``
    (tests/test_no_import_circles.py). The engine gets what a ``kinema.World`` would hand it:
    the collision settings (the engine's defaults, these changed), the two particles, and the
    steps."""
    if model == "hertz":
        # r = 2 m each: R* = 1 m; E* = 3/4 Pa: k_h = 1; m = 2 kg each: m* = 1 kg
        radius, params = 2.0, {"youngs_modulus": 0.75 * 2 * (1 - 0.3**2), "poisson_ratio": 0.3}
        t_c = HERTZ_TIME_OMEGA / math.sqrt(1.5 * 1.25**0.2)  # ω_t at δ_max = (5/4)^(2/5) m
    else:
        radius, params = 1.0, {"stiffness": 1.0}
        t_c = contact_time(model, 1.0, _zeta(restitution))
    dt = t_c / steps_per_contact
    core = _core.World(3, float(dt), method)
    core.set_collisions({**_core.collision_defaults(), "model": model, "restitution": float(restitution), **params})
    gap = 1.5 * dt  # closed within the first two steps at 1 m/s
    x = np.array([[-radius - gap / 2, 0, 0], [radius + gap / 2, 0, 0]], dtype=np.float64)
    v = np.array([[0.5, 0, 0], [-0.5, 0, 0]], dtype=np.float64)
    pair = {"x": x, "v": v, "mass": np.full(2, 2.0), "radius": np.full(2, radius), "pinned": np.zeros(2, dtype=bool)}
    core.add_particles({**pair, "restitution": None, "friction": None, "group": None})
    core.step(int(3 * steps_per_contact) + 10)
    core.read_state(x, v)
    return float(v[1, 0] - v[0, 0])
