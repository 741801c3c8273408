"""The time-step check before a force model's first step: the fastest impact the scene can
produce, the duration of that contact, and the Rayleigh time of the smallest particle.

A pour or a drop starts at rest, where no contact exists to time: the stable-step advisor sees
no stiffness yet (Hertz's grows with the impact speed), and the first impacts, seconds later,
can be too short for the step. This check looks ahead instead, in four stages:

1. **Impact speeds.** Each movable particle i against each collider k: free fall along the
   world's gravity g from where i is to where it first touches k, on top of its own speed,
   and the collider's surface speed there (``Motion``/``Keyframes`` over the next step):

       u_ik = √(|v_i|² + 2 |g| d_ik) + s_ik      (energy: ½ u² = ½ v² + |g| d; exact for a
                                                  ballistic flight that ends on k)

   d_ik ≥ 0 is the drop along g before the sphere of radius r_i touches k: a plane facing
   up, falling straight onto it, d = ((x − p)·n − r) / (−n·ĝ); a box (a container) the same
   for each of its finite faces, the largest; a sphere obstacle, a mesh or the pinned
   particles, conservatively, the drop until the particle rests on their lowest point (the
   sphere's bottom, R below its centre; the mesh's lowest vertex; a fall onto them ends
   higher). A plane that does not face up, or no gravity, gives d = 0.
   Between particles, the two fastest speeds u_i = max_k √(|v_i|² + 2 |g| d_ik) add (two
   particles meet at most at the sum of their speeds; a particle that has bounced off
   something meets a falling one at no more); not when no pair collides
   (``self_collisions=False``). An ``Emitter`` counts as particles of its
   smallest and largest radius born at the top of its shape at its fastest speed.

2. **The shortest contact** of those impacts. Hertz (Landau & Lifshitz §9; Johnson, Contact
   Mechanics, §11.4): t_c = 2 I δ_max / u = 2.868 (m*² / (R* E*² u))^(1/5)
   (``contact_time.hertz_contact_time``), against a collider with m* = m_i, R* = r_i; between
   particles with the lightest pair's m* = 1/(w₁ + w₂) and the largest R* = r₁ r₂/(r₁ + r₂)
   of the two largest radii. The linear spring–dashpot's t_c = π / (ω₀ √(1 − ζ²)) does not
   depend on the speed: ω₀² = k_n / m* of the lightest pair (a single particle against a
   collider), ζ of the least damped contact (``contact_time.contact_time``).

3. **The Rayleigh time** of the particles (Hertz only: it needs E and ν), the time a surface
   (Rayleigh) wave takes to cross a particle, T_R = π r √(ρ/G) / (0.1631 ν + 0.8766) with
   G = E / (2 (1 + ν)) and ρ = m / (4/3 π r³) (a sphere's, in 2D worlds too), the smallest
   over the particles. LIGGGHTS (``fix check/timestep/gran``) and EDEM advise dt ≤ 0.1–0.2
   T_R; kinema uses 0.2 (:data:`RAYLEIGH_FRACTION`).

4. **The safe step** dt_safe = min(t_c / 20, 0.2 T_R) (20 = ``contact_time.STEPS_PER_CONTACT``:
   below it the restitution drifts). A coarser dt gives one ``ContactTimeWarning`` that names
   dt, the limiting figure and dt_safe and, for the contact, either that dt is beyond the
   method's stable step on that contact's stiffness (``stability.max_step_oscillator`` at the
   tangent stiffness of its deepest overlap, ω_t = 4.0302 / t_c for Hertz, ω₀ for Hooke), so
   that the run will likely diverge, or the restitution that step gives one head-on pair
   (``contact_time.restitution_at``). It warns rather than refuses: the speeds are an upper bound (a particle need not
   fall all the way, two need not meet head on), so a step beyond it is not certainly unstable.

Not counted: forces other than ``Gravity`` (a ``PythonForce``, springs) and the speeds they
give, periodic images, and a collider's motion after the next step.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _core, contact_time
from .contact_time import STEPS_PER_CONTACT, ContactTimeWarning

#: The fraction of the Rayleigh time a step may take (LIGGGHTS and EDEM advise 0.1–0.2).
RAYLEIGH_FRACTION = 0.2


@dataclass(frozen=True)
class Bodies:
    """What the check reads of the particles, one row per movable (or emitted) particle:
    ``x`` (N, 3), m; ``v`` (N, 3), m/s; ``r`` (N,), m; ``w`` (N,), 1/kg; ``label`` how the
    message names each ("particle 3", "emitter 0's particle of r = ...": ``Labels``); and the pinned
    particles, obstacles like a collider: ``fixed_x`` (P, 3), m, ``fixed_r`` (P,), m."""

    x: np.ndarray
    v: np.ndarray
    r: np.ndarray
    w: np.ndarray
    label: Labels
    fixed_x: np.ndarray
    fixed_r: np.ndarray


@dataclass(frozen=True)
class Impact:
    """The contact that limits the step: ``t_c`` (s), its ``omega`` (rad/s, the tangent
    stiffness at its deepest overlap over m*) and ``zeta``, the approach ``speed`` u (m/s;
    None for Hooke, whose t_c does not depend on it) and ``what`` (in words)."""

    t_c: float
    omega: float
    zeta: float
    speed: float | None
    what: str


@dataclass(frozen=True)
class StepCheck:
    """The check's figures: the shortest ``contact`` (None: no contact can happen), the
    smallest Rayleigh time ``rayleigh`` (s; None without E and ν) and the safe step
    ``dt_safe`` (s; inf when nothing limits it)."""

    contact: Impact | None
    rayleigh: float | None
    dt_safe: float


def rayleigh_time(r: np.ndarray, m: np.ndarray, youngs_modulus: float, poisson_ratio: float) -> np.ndarray:
    """T_R = π r √(ρ/G) / (0.1631 ν + 0.8766) (s) of spheres of radius ``r`` (m) and mass
    ``m`` (kg): ρ = m / (4/3 π r³), G = E / (2 (1 + ν)) from ``youngs_modulus`` E (Pa) and
    ``poisson_ratio`` ν (module doc, stage 3)."""
    r, m = np.asarray(r, float), np.asarray(m, float)
    rho = m / (4.0 / 3.0 * np.pi * r**3)
    shear = youngs_modulus / (2.0 * (1.0 + poisson_ratio))
    return np.pi * r * np.sqrt(rho / shear) / (0.1631 * poisson_ratio + 0.8766)


def gravity(forces: list[Any], dim: int) -> np.ndarray:
    """The sum of the ``Gravity`` forces' g (m/s², (3,)); zero without any."""
    from .forces import Gravity

    g = np.zeros(3)
    for f in forces:
        if isinstance(f, Gravity):
            g += np.asarray(f.vector(dim), float)
    return g


class Labels:
    """How the check's message names each body: ``"particle i"`` for the world's particle
    ``i`` (made when asked: a million of them as strings were 70 MB for a message that names
    two), then the emitters' ``extra`` names."""

    def __init__(self, particles: np.ndarray | range, extra: list[str]) -> None:
        self.particles, self.extra = particles, extra

    def __len__(self) -> int:
        return len(self.particles) + len(self.extra)

    def __getitem__(self, k: Any) -> str:
        k = int(k)
        n = len(self.particles)
        return f"particle {self.particles[k]}" if k < n else self.extra[k - n]


def bodies_of(world: Any, core: Any, motion: bool = True) -> Bodies:
    """The world's movable particles and, for each emitter, a particle of its smallest and its
    largest radius born at the top of its shape (along −g) at its fastest speed. Without
    ``motion`` (a model whose contact time depends on the masses alone) ``x``, ``v`` and
    ``fixed_x`` are empty: the world's positions and velocities are not read (48 MB at 10⁶
    particles, beside the first step's buffers)."""
    w = np.asarray(core.inverse_masses, float)
    r = np.asarray(core.radii, float)
    movable = (w > 0) & (r > 0)
    every = bool(movable.all())  # (then the arrays themselves, not copies of them)
    idx = range(len(movable)) if every else np.flatnonzero(movable)

    def of(a: np.ndarray) -> np.ndarray:
        return a if every else a[movable]

    x = [of(world.positions) if motion else np.empty((0, 3))]
    v = [of(world.velocities) if motion else np.empty((0, 3))]
    rs, ws, labels = [of(r)], [of(w)], []
    g = gravity(world.forces, core.dim)
    up = -g / np.linalg.norm(g) if g.any() else np.zeros(3)
    for k, source in enumerate(world._state().emitters):
        c = source.c
        if c["shape"] == "mesh":  # its highest vertex (its faces, vertices and volume lie below)
            top = c["mesh_vertices"][int(np.argmax(c["mesh_vertices"] @ up))]
        else:
            top = np.asarray(c["center"], float) + _reach(c, up) * up
        speed = c["speed"] + c["speed_spread"]
        for radius in sorted({c["particle_radius"] - c["radius_spread"], c["particle_radius"] + c["radius_spread"]}):
            if radius <= 0:
                continue
            mass = c["mass"] if c["mass"] is not None else c["density"] * 4.0 / 3.0 * np.pi * radius**3
            # twice: an emitter gives many such particles, and two of them can meet
            if motion:
                x.append(np.tile(top, (2, 1)))
                v.append(np.tile([speed, 0.0, 0.0], (2, 1)))  # (only |v| counts)
            rs.append(np.full(2, radius))
            ws.append(np.full(2, 1.0 / mass))
            labels += [f"emitter {k}'s particle of r = {radius:g} m"] * 2
    pinned = (w == 0) & (r > 0)

    def joined(parts: list[np.ndarray]) -> np.ndarray:
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    fixed_x = world.positions[pinned] if motion else np.empty((0, 3))
    return Bodies(joined(x), joined(v), joined(rs), joined(ws), Labels(idx, labels), fixed_x, r[pinned])


def _reach(c: dict, up: np.ndarray) -> float:
    """How far along ``up`` an emitter's shape reaches above its centre, m."""
    if c["shape"] == "box":
        return float(np.abs(up) @ np.asarray(c["size"], float)) / 2.0
    return float(c["radius"]) if c["shape"] in ("disc", "sphere") else 0.0


def _pose(c: Any, t: float, dt: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The collider's poses [R | o] (3, 4) at t and t + dt, or None for a still one."""
    if c.motion is None:
        return None
    poses = _core.collider_poses([t, t + dt], **c.motion._binding())
    return poses[0], poses[1]


def drop_and_speed(c: Any, x: np.ndarray, r: np.ndarray, down: np.ndarray, t: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """For particles at ``x`` (N, 3) of radii ``r`` and collider ``c`` at time ``t``: the drop
    d (N,), m, along the unit ``down`` before each touches it (module doc, stage 1; zeros for
    ``down`` = 0), and its surface speed s (N,), m/s, where each particle is (over the next
    step ``dt``)."""
    from .colliders import Box, Mesh, Plane, SphereObstacle

    pose = _pose(c, t, dt)
    rot, shift = (np.eye(3), np.zeros(3)) if pose is None else (pose[0][:, :3], pose[0][:, 3])

    def placed(p: Any) -> np.ndarray:  # a point of the collider as added -> where it is at t
        return rot @ np.ravel(np.asarray(p, float))[:3] + shift

    def onto_plane(p: np.ndarray, n: np.ndarray) -> np.ndarray:
        n = n / np.linalg.norm(n)
        facing = -float(n @ down)  # > 0: the plane faces up, a fall reaches it
        if facing <= 0.0:
            return np.zeros(len(r))
        return np.maximum(0.0, ((x - p) @ n - r) / facing)

    if not down.any():
        d = np.zeros(len(r))
    elif isinstance(c, Plane):
        point, normal = c._args[:2]  # (3-vectors, as checked)
        d = onto_plane(placed(point), rot @ np.asarray(normal, float))
    elif isinstance(c, Box):
        lo, hi = (np.asarray(b, float) for b in c._args[:2])  # (2 values each in 2D: open along z)
        d = np.zeros(len(r))
        for axis in range(lo.size):
            for bound, sign in ((lo[axis], 1.0), (hi[axis], -1.0)):
                if np.isfinite(bound):
                    n = np.zeros(3)
                    n[axis] = sign
                    p = np.zeros(3)
                    p[axis] = bound
                    d = np.maximum(d, onto_plane(p + shift, n))
    elif isinstance(c, SphereObstacle | Mesh):  # down to resting on its lowest point (a bound)
        if isinstance(c, SphereObstacle):
            lowest = float(placed(c._args[0]) @ down) + float(c._args[1])  # its bottom, R below its centre
        else:
            lowest = float(np.max((c.vertices @ rot.T + shift) @ down))  # its lowest vertex
        d = np.maximum(0.0, lowest - x @ down - r)
    else:  # pragma: no cover - every collider is one of the four
        raise TypeError(f"unknown collider {c!r}")
    if pose is None:
        return d, np.zeros(len(r))
    # the collider's material point at each particle, carried over the next step
    at_rest = (x - pose[0][:, 3]) @ pose[0][:, :3]  # x₀ = Rᵀ (x − o), row by row
    later = at_rest @ pose[1][:, :3].T + pose[1][:, 3]
    return d, np.linalg.norm(later - x, axis=1) / dt


def _obstacles(bodies: Bodies, colliders: list[Any], down: np.ndarray, t: float, dt: float) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Each obstacle in words, with the drop d (N,) and surface speed s (N,) of each particle
    towards it (``drop_and_speed``): the colliders, and the pinned particles as one, whose
    lowest point bounds the drop (as a sphere obstacle's)."""
    out = []
    for k, c in enumerate(colliders):
        d, s = drop_and_speed(c, bodies.x, bodies.r, down, t, dt)
        out.append((f"collider {k} ({type(c).__name__})", d, s))
    if len(bodies.fixed_r):
        lowest = float(np.max(bodies.fixed_x @ down + bodies.fixed_r)) if down.any() else -np.inf
        d = np.maximum(0.0, lowest - bodies.x @ down - bodies.r)
        out.append(("a pinned particle", d, np.zeros(len(bodies.r))))
    return out


# The contact models whose shortest contact depends on the masses alone (a Hooke spring's
# t_c, whatever the speed): `check` reads no positions or velocities for them.
MASSES_ONLY = ("spring_dashpot",)


def shortest_contact(settings: dict, bodies: Bodies, colliders: list[Any], g: np.ndarray, t: float, dt: float, restitution_max: float) -> Impact | None:
    """The shortest contact the scene can produce (module doc, stages 1 and 2), or None when
    no contact can happen (one particle and nothing fixed; Hertz: nothing moves or falls)."""
    n = len(bodies.r)
    fixed = bool(colliders) or len(bodies.fixed_r) > 0
    # pairs of particles can meet unless no pair collides (self_collisions off); a matrix that
    # spares some pairs and colliders that let some groups through are counted as colliding,
    # an upper bound as the rest of the check is
    pairs = n > 1 and settings.get("self_collisions", True)
    if n == 0 or (not pairs and not fixed):
        return None
    model = settings["model"]
    gabs = float(np.linalg.norm(g))
    down = g / gabs if gabs > 0 else np.zeros(3)
    zeta = contact_time._zeta(restitution_max)
    if model in MASSES_ONLY:  # (the spring–dashpot)
        k = settings["stiffness"]
        lightest_first = np.sort(bodies.w)[::-1]
        w_pair = lightest_first[0] + (lightest_first[1] if n > 1 else 0.0)
        w_eff = max(w_pair if pairs else 0.0, lightest_first[0] if fixed else 0.0)
        omega = math.sqrt(k * w_eff)
        if settings.get("damping") is not None:
            zeta = settings["damping"] / (2.0 * omega)
        t_c = contact_time.contact_time(model, omega, zeta)
        what = "the stiffest spring–dashpot pair (the lightest)" if w_eff == w_pair and pairs else "the lightest particle against a collider"
        return Impact(t_c, omega, zeta, None, what)
    # Hertz: each particle against each collider, and the lightest, largest pair at the two
    # fastest speeds
    e_star = settings["youngs_modulus"] / (2.0 * (1.0 - settings["poisson_ratio"] ** 2))
    best: tuple[float, float, str] | None = None  # (t_c, u, what)
    speed2 = np.einsum("ij,ij->i", bodies.v, bodies.v)
    free = np.sqrt(speed2)
    for name, d, s in _obstacles(bodies, colliders, down, t, dt):
        fall = np.sqrt(speed2 + 2.0 * gabs * d)
        free = np.maximum(free, fall)
        u = fall + s
        with np.errstate(divide="ignore", invalid="ignore"):
            t_c = np.where(u > 0, contact_time.hertz_contact_time(1.0 / bodies.w, bodies.r, e_star, u), np.inf)
        i = int(np.argmin(t_c))
        if np.isfinite(t_c[i]) and (best is None or t_c[i] < best[0]):
            how = f"falling {d[i]:.3g} m" if d[i] > 0 else "at its speed"
            best = (float(t_c[i]), float(u[i]), f"{bodies.label[i]} (r = {bodies.r[i]:g} m) {how} onto {name}")
    if pairs:
        order = np.argsort(free)[::-1]
        u = float(free[order[0]] + free[order[1]])
        w1, w2 = np.sort(bodies.w)[::-1][:2]
        r1, r2 = np.sort(bodies.r)[::-1][:2]
        if u > 0:
            t_c = float(contact_time.hertz_contact_time(1.0 / (w1 + w2), r1 * r2 / (r1 + r2), e_star, u))
            if best is None or t_c < best[0]:
                fastest = " and ".join(dict.fromkeys(bodies.label[i] for i in order[:2]))
                best = (t_c, u, f"two particles meeting (the lightest pair, the largest radii, the two fastest: {fastest})")
    if best is None:
        return None
    t_c, u, what = best
    return Impact(t_c, contact_time.HERTZ_TIME_OMEGA / t_c, zeta, u, what)


def check(world: Any, core: Any) -> StepCheck | None:
    """The figures of the check for ``world`` (its engine ``core``), or None without a force
    model."""
    settings = core.collisions or {}
    if settings.get("model") not in _core.FORCE_MODELS:
        return None
    bodies = bodies_of(world, core, motion=settings["model"] not in MASSES_ONLY)
    g = gravity(world.forces, core.dim)
    own = [e for e, _ in core.particle_materials() if e is not None and not math.isnan(e)]
    colliders = world.colliders
    walls = [c.restitution for c in colliders if c.restitution is not None]
    emitted = [s.c["restitution"] for s in world._state().emitters if s.c["restitution"] is not None]
    e_max = max([settings["restitution"], *own, *walls, *emitted])
    contact = shortest_contact(settings, bodies, colliders, g, core.time, core.dt, e_max)
    rayleigh = None
    if settings["model"] == "hertz" and len(bodies.r):
        rayleigh = float(np.min(rayleigh_time(bodies.r, 1.0 / bodies.w, settings["youngs_modulus"], settings["poisson_ratio"])))
    limits = [math.inf]
    if contact is not None:
        limits.append(contact.t_c / STEPS_PER_CONTACT)
    if rayleigh is not None:
        limits.append(RAYLEIGH_FRACTION * rayleigh)
    return StepCheck(contact, rayleigh, min(limits))


def advise(world: Any, core: Any) -> bool:
    """Warns once (``ContactTimeWarning``) if the world's dt is beyond the check's safe step;
    returns whether it warned (module doc)."""
    found = check(world, core)
    if found is None or core.dt <= found.dt_safe:
        return False
    dt, parts = core.dt, []
    contact = found.contact
    if contact is not None and dt * STEPS_PER_CONTACT > contact.t_c:
        steps = contact.t_c / dt
        speed = "" if contact.speed is None else f" at {contact.speed:.3g} m/s"
        parts.append(f"dt = {dt:g} s spans {steps:.3g} steps of the shortest contact the scene can make (t_c = {contact.t_c:.3g} s: {contact.what}{speed})")
        limit = _max_step(world, contact)
        if dt > limit:  # (a restitution measured there would be the instability's)
            parts.append(f"dt is beyond the stable step of method {core.method!r} on that contact ({limit:.3g} s): the run will likely diverge")
        elif core.collisions.get("damping") is None:
            e = core.collisions["restitution"]
            got = contact_time.restitution_at(core.collisions["model"], core.method, steps, e)
            parts.append(
                f"below {STEPS_PER_CONTACT} steps a contact's restitution drifts: with method {core.method!r} this step gives "
                f"e = {got:.4g} where e = {e:.4g} is set (a head-on pair, measured)"
            )
    if found.rayleigh is not None and dt > RAYLEIGH_FRACTION * found.rayleigh:
        parts.append(
            f"dt = {dt:g} s is {dt / found.rayleigh:.3g} of the smallest particle's Rayleigh time T_R = {found.rayleigh:.3g} s, "
            f"over the {RAYLEIGH_FRACTION:g} T_R that LIGGGHTS and EDEM advise"
        )
    warnings.warn("; ".join(parts) + f". Use dt <= {_round_down(found.dt_safe)} s", ContactTimeWarning, stacklevel=4)
    return True


def _max_step(world: Any, contact: Impact) -> float:
    """The method's largest stable step on the contact's oscillator (``inf`` if none)."""
    from .stability import max_step_oscillator

    try:
        return max_step_oscillator(world._state().method, contact.omega, min(contact.zeta, 1.0))
    except ValueError:  # a method without a stability function on oscillators
        return math.inf


def _round_down(t: float) -> str:
    """``t`` (s) to 3 significant digits, rounded down: a safe step stays safe."""
    if not math.isfinite(t) or t <= 0:
        return f"{t:g}"
    scale = 10.0 ** (math.floor(math.log10(t)) - 2)
    return f"{math.floor(t / scale) * scale:.3g}"
