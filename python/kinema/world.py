"""The particle world: particles with mass, position and velocity, moved by forces through
any integration method of the registry, colliding with each other and with static colliders.

``World`` owns its state: the engine and the Python extras it keeps per particle and per run,
whose field table is ``kinema._state.WorldState``. ``World._state()`` and
``World._restore(state)`` are the one way other modules of the package read and write that
state (the checkpoints, the scene export and builder, the contact-time check of
``kinema.first_step``, the recorder of ``kinema.trajectory``, ``kinema run``); besides them,
a resumed run goes on with the world's run loop, ``World._record``. The scene and checkpoint methods
(``to_scene``, ``save_checkpoint``, ``load_checkpoint``, ``scene``) are the class's own,
defined here; their bodies are in ``kinema.scene.export`` and ``kinema.checkpoint``, imported
when called: neither imports this module (the checkpoint's reader builds its world by
``scene.build()``), so the dependency goes one way (tests/test_no_import_circles.py).

The class is written in parts. This module holds ``World`` itself: its making, ``add`` and
``set_motion``, the steps (``step``, ``_advance``) and the stable-step advisor, ``run``'s
checks and plan (its ``callback`` is typed with ``World``, which a base's module could not
import without a circle), ``diagnostics``, the scene and checkpoint methods and the state
accessor. Its bases, each in its own module that never imports this one (the methods of one
part call those of another through ``self``), hold the rest:

- ``kinema._world_views.WorldViews``: the engine (thread-checked, lent by ``_engine`` while it
  calls back into Python, ``_Busy`` meanwhile) and the NumPy views of its state, with the state
  as arrays and values (``positions`` … ``forces``);
- ``kinema._world_particles.WorldParticles``: adding and removing particles
  (``add_particles``, ``add_particles_from``, ``remove_particles``; ``_add`` and ``_forget``,
  which keep what the Python world holds per particle in step with the engine);
- ``kinema._world_births.WorldBirths``: births and deaths between steps (the emitters'
  births where there is room, the kill volumes, the deaths dropped; ``emitter_stats``), which
  ``_advance`` (here) runs its batches of steps around;
- ``kinema._world_run.WorldRun``: the run loop (``_record``, which ``run``, here, and a
  resumed run go on with) and what it records, and the look at new meshes before a step;
- ``kinema.world_collisions.WorldCollisions``: the collision API.

``REENTRY`` and ``_other_thread`` (the messages of a world used while it steps, or from
another thread) are re-exported here from ``kinema._world_views``.
"""

from __future__ import annotations

import threading
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _checks, _core, first_step
from ._state import WorldState
from ._world_births import WorldBirths
from ._world_particles import WorldParticles
from ._world_run import WorldRun
from ._world_views import REENTRY as REENTRY  # (kinema.world.REENTRY: the message a force meets)
from ._world_views import WorldViews, _Busy
from ._world_views import _other_thread as _other_thread  # (kinema.world._other_thread)
from .colliders import Box, Collider
from .emitter import KILL_VOLUMES, Emitter, births_until
from .forces import Spring
from .frames import MAX_WORK as MAX_WORK  # (kinema.world.MAX_WORK, World.run's default)
from .frames import plan as frames_plan
from .ode import ButcherTableau, method_names
from .trajectory import Trajectory
from .world_collisions import WorldCollisions

if TYPE_CHECKING:
    from .scene.schema import Scene

SimulationDiverged = _core.SimulationDiverged


class StabilityWarning(UserWarning):
    """The time step exceeds the stable-step advisor's limit for the world's method."""


class PlacementWarning(UserWarning):
    """Particles placed overlapping each other or a collider's surface (by more than 1 % of
    the radii): accepted, but the collisions push them apart in the first steps, which sets
    them moving. Said once per placement (the engine's check before the first step after
    particles, colliders or collisions change), with the count and the deepest overlap.
    Deeper placements, a centre inside another particle or a collider, are refused with a
    ``ValueError`` instead."""


def _check_motion(dim: int, c: Collider, motion: Any) -> None:
    """Refuses what the engine would refuse of ``motion`` on ``c`` in a ``dim``-D world (a
    turning box, a motion out of the xy-plane in 2D), before ``c`` is added: the motion is
    set on a stand-in of its kind (its own box; a plane for the others) in an empty engine
    world. The engine's message names the parameter."""
    scratch = _core.World(dim, 1e-3, "verlet")
    if isinstance(c, Box):
        scratch.add_box(*c._args)
    else:
        scratch.add_plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], None, None)
    scratch.set_collider_motion(0, **motion._binding())


def _verlet_only(core: Any, colliders: list[Collider]) -> bool:
    """Whether the world (its engine ``core``, its ``colliders``) steps with ``method="verlet"``
    only: a force model's contacts with friction somewhere, the world's, a particle's own or a
    collider's (the engine's rule: ``has_friction`` in collide/contact_force/mod.rs)."""
    settings = core.collisions or {}
    if settings.get("model") not in _core.FORCE_MODELS:
        return False
    own = any(mu is not None and mu > 0 for _, mu in core.particle_materials())
    return settings["friction"] > 0 or own or any((c.friction or 0) > 0 for c in colliders)


class World(WorldViews, WorldParticles, WorldBirths, WorldRun, WorldCollisions):
    """Particles, forces, an integrator, a time step and the time.

    ``World(dim=3, dt=1e-3, method="verlet", spin=False)``: ``dim`` 2 keeps every particle in
    the xy-plane (z = 0 exactly); ``dt`` in s; ``method`` any name of ``kinema.method_names()``
    or a ``ButcherTableau``.

    ``spin=True`` gives every particle an angular velocity (:attr:`angular_velocities`, rad/s,
    0 to start; a 2D world turns about z) and a moment of inertia (:attr:`inertia`, kg·m²: a
    solid sphere's 2/5 m r² in 3D, a disc's 1/2 m r² in 2D, unless ``add_particles`` is given
    ``inertia``). Collision impulses then act at the contact point: friction acts on the
    contact point's velocity (v + ω × r) and turns both particles, so a ball with enough
    friction rolls, and :meth:`diagnostics` adds the rotational kinetic energy and the
    particles' own angular momentum Σ I ω. Without spin particles are points with mass, and
    every result is what it was before spin existed, bit for bit.

    ``positions``, ``velocities`` and ``masses`` are live NumPy views of the state: stepping
    updates them in place, and writing into them changes the world (checked at the next step).
    Adding particles makes new arrays; views taken before no longer follow the world.

    Before its first step (and after particles or forces are added) the world asks the
    stable-step advisor (:meth:`stable_step`) for the largest stable step of its method and
    issues one ``StabilityWarning`` in its lifetime if ``dt`` exceeds it.

    Collisions are off until :meth:`set_collisions` is called, a collider (``kinema.Plane``,
    ``Box``, ``SphereObstacle``) is added, or particles get their own ``restitution`` or
    ``friction``; particles then collide as spheres of their ``radius``. Those methods
    (``set_collisions``, ``collisions``, ``colliders``, ``periodic``, ``contacts``,
    ``collision_stats``, ``collider_books``, ``stage_times``) are in
    ``kinema.world_collisions``; a collider's ``motion`` (``kinema.Motion``,
    ``kinema.Keyframes``) moves it, and :meth:`set_motion` changes it.

    The particle count may change: :meth:`remove_particles`, and ``kinema.Emitter`` and kill
    volumes (``KillBox``, ``KillSphere``, ``KillPlane``) added with :meth:`add`, which give
    births and deaths between steps (``kinema.emitter``). Each particle has an id
    (:attr:`ids`) that stays with it and is never given again; indices are positions in the
    current arrays and shift when particles are removed.
    """

    #: The scene the world was built from (``kinema.load_scene``, ``Scene.build``, a checkpoint's
    #: scene), which keeps its duration, fps, render, output and analysis settings for
    #: :meth:`to_scene` and ``kinema run``; ``None`` for a world made in code.
    scene: Scene | None = None

    def __init__(self, dim: int = 3, dt: float = 1e-3, method: str | ButcherTableau = "verlet", spin: bool = False):
        dim = _checks.integer("dim", dim, 2, 3, what="a world is 2D (the xy-plane) or 3D: dim must be 2 or 3")
        spin = _checks.boolean("spin", spin)
        self._owner = threading.get_ident()
        self._core = _core.World(dim, _checks.real("dt", dt), method)
        if spin:
            self._core.set_spin(True)
        self._forces: list[Any] = []
        self._colliders: list[Collider] = []
        self._added: list[Collider] = []  # the objects given to add (set_motion knows them by these too)
        self._method_arg = method
        self._warned = False
        self._contact_warned = False
        self._advice_due = True
        self._species: list[str] | None = None  # per particle ("": none given); None while no particle has one
        # Births and deaths: the emitters at work, the kill volumes, and per particle its time
        # of death (inf: none), its colour (NaN: none) and the id pairs of the springs.
        self._emitters: list[Any] = []
        self._kills: list[Any] = []
        self._colors = np.empty((0, 3))
        self._spring_ids = np.empty((0, 2), dtype=np.int64)
        self._spring_rest: dict[int, np.ndarray] = {}  # index in the forces -> each spring's rest length, m
        self._advised_at = 0  # particles when the advisor last looked
        self._placed = 0  # the colliders whose placement has been looked at (MeshPlacementWarning)
        # kinema run's scene file and its scene's hash (scene_file, scene_sha256), written with
        # the checkpoints of its runs: --resume refuses a checkpoint of another scene
        self._run_source: dict[str, str] = {}
        self._new_views()

    def _advise(self, core: Any) -> None:
        """Warns once if dt is beyond the advisor's limit for the world's method (``core``: the
        engine, lent by :meth:`_engine`; the advisor evaluates the forces). Due after the
        particles were added: the set-up's temporaries are let go by then (NumPy's arrays the
        scene was made from, the checks' own), and what the C allocator keeps of them is given
        back to the system before the steps (``_core.give_back_memory``: 40–90 MB resident
        beside a gas of 10⁶ particles otherwise)."""
        if not self._advice_due:
            return
        try:
            self._advise_now(core)
        finally:
            _core.give_back_memory()

    def _advise_now(self, core: Any) -> None:
        """:meth:`_advise`'s checks and warnings."""
        self._advice_due = False
        self._advised_at = core.len
        contact_springs = (core.collisions or {}).get("model") in _core.FORCE_MODELS
        if contact_springs and not self._contact_warned and (core.len or self._emitters):
            # a step coarser than t_c / 20 of the fastest impact the scene can produce, or than
            # 0.2 of the Rayleigh time (kinema.first_step), emitters' particles counted
            self._contact_warned = first_step.advise(self, core)
            # (its looks at the positions and velocities are let go before the engine's
            # advisor and the steps: 48 MB at 10⁶ particles beside the first step's buffers)
            self._let_go()
        if core.len == 0 or not (self._forces or contact_springs):
            return
        if self._warned:
            return
        limit = core.stable_step(self._method_arg)
        if core.dt > limit:
            self._warned = True
            rates = core.rates()
            omega = max(rates["omega"], rates["standby_omega"] or 0.0)  # contacts not yet touching count
            # advise only what this world accepts: frictional contacts of a force model step
            # with Verlet alone (the engine refuses the others, world/integrate.rs)
            verlet_only = _verlet_only(core, self._colliders)
            if limit > 0:
                text = (
                    f"dt = {core.dt:g} s exceeds the stable-step advisor's limit {limit:.4g} s for method "
                    f"{core.method!r} on these forces (stiffest mode: omega = {omega:.4g} rad/s); the simulation will likely blow up: "
                    + (
                        "reduce dt (contacts with friction under a force model step with method='verlet' only)"
                        if verlet_only
                        else "reduce dt or use method='implicit_euler'"
                    )
                )
            else:  # |R(iωh)| > 1 for every h > 0: e.g. forward Euler on an undamped oscillation
                text = (
                    f"method {core.method!r} is unstable at every step on these forces: their stiffest mode "
                    f"(omega = {omega:.4g} rad/s) is undamped and each step multiplies its amplitude by more than 1, "
                    "so the energy grows; a smaller dt only slows the growth: "
                    + (
                        "use method='verlet' (contacts with friction under a force model step with it only)"
                        if verlet_only
                        else "use a symplectic method ('verlet', 'symplectic_euler'), 'rk4' or 'implicit_euler'"
                    )
                )
            warnings.warn(text, StabilityWarning, stacklevel=3)

    # -- building ---------------------------------------------------------------------------
    def add(self, item: Any) -> Any:
        """Add a force (``kinema.Gravity``, ``Drag``, ``Spring``, ``Attractor``, ``Wind``,
        ``Turbulence``, ``Vortex``, ``PythonForce``) or a collider (``kinema.Plane``, ``Box``, ``SphereObstacle``,
        ``Mesh``; this turns collisions on); returns it. A collider's ``motion`` moves it from
        then on: a ``Motion`` without a ``start`` starts now, from where the collider is
        placed (``w.colliders[k]`` is then a copy whose motion has the world's time now as its
        start); ``Keyframes`` place it where their keys have it at the world's time now.
        A motion the engine refuses (a turning ``Box``, a motion out of the xy-plane in a 2D
        world) is a ``ValueError`` naming it, and nothing is added."""
        attach = getattr(item, "_attach", None)
        if attach is None:
            raise TypeError(
                f"{type(item).__name__} is not a kinema force, collider or emitter; use kinema.Gravity, Drag, Spring, Attractor, "
                "Wind, Turbulence, Vortex, PythonForce, Plane, Box, SphereObstacle, Mesh, Emitter, KillBox, KillSphere or KillPlane"
            )
        if isinstance(item, Emitter):
            self._emitters.append(attach(self))  # (the emitter at work: kinema.emitter)
            return item
        if isinstance(item, KILL_VOLUMES):
            self._kills.append(attach(self))
            return item
        self._push()
        if isinstance(item, Collider) and item.motion is not None:
            _check_motion(self.dim, item, item.motion)  # refused before the collider is added
        attached = attach(self._core)
        if isinstance(item, Collider):
            if item._group_mask != (1 << _checks.GROUPS) - 1:
                self._core.set_collider_mask(attached, item._group_mask)
            kept = item
            if item.motion is not None:
                given = item.motion._given_at(self.time)  # a Motion starts when it is given
                kept = item if given is item.motion else item._moved(given)
                self._core.set_collider_motion(attached, **given._binding())
            self._colliders.append(kept)
            self._added.append(item)
        else:
            self._forces.append(item)
            self._advice_due = True
            if isinstance(item, Spring):  # drawn between these ids while both live
                # the rest lengths the engine took (from the positions when not given): a
                # scene or checkpoint of this world keeps them, not the distances of its day
                self._spring_rest[len(self._forces) - 1] = np.asarray(attached, dtype=float)
                i, j = item._args[:2]
                ends = np.array([i, j], dtype=np.int64).T.reshape(-1, 2)
                self._spring_ids = np.concatenate([self._spring_ids, self.ids[ends]])
        return item

    def set_motion(self, collider: Any, motion: Any) -> None:
        """Give a collider another prescribed motion: ``collider`` is one of :attr:`colliders`
        (the object added) or its index; ``motion`` a ``kinema.Motion``, ``kinema.Keyframes``
        or None (back to its placement as added, still). The motion is from the placement the
        collider was added in; a ``Motion`` without a ``start`` starts at the world's time
        now (so a floor given ``Motion(velocity=(0, 0, 1))`` at t = 4 s moves from where it
        was added, not 4 m at once), ``Keyframes`` are on the world's clock and place the
        collider where their keys have it now. ``w.colliders[k]`` is then a copy of the
        collider that carries the new motion (colliders are frozen; the object added keeps
        its own, and still names the collider here). A refused motion (a turning ``Box``, one out of the xy-plane in a 2D world)
        is a ``ValueError`` naming it, and the collider keeps its motion."""
        if isinstance(collider, Collider):
            k = next((k for k, pair in enumerate(zip(self._colliders, self._added, strict=True)) if any(c is collider for c in pair)), None)
            if k is None:
                raise ValueError(f"collider = {collider!r} is invalid: it is not one of this world's colliders (w.colliders); give one of them or its index")
        else:
            n = len(self._colliders)
            k = _checks.integer("collider", collider)
            if not 0 <= k < n:
                raise ValueError(f"collider = {k} is invalid: {f'an index of w.colliders, 0..{n - 1}' if n else 'the world has no colliders'}")
        moved = self._colliders[k]._moved(motion)  # checks the motion (a TypeError, a box's turn)
        if moved.motion is not None:
            moved = moved._moved(moved.motion._given_at(self.time))  # a Motion starts when it is given
        self._push()
        self._core.set_collider_motion(k, **({} if moved.motion is None else moved.motion._binding()))
        self._colliders[k] = moved

    # -- running ----------------------------------------------------------------------------
    def step(self, n: int = 1) -> None:
        """Advance ``n`` steps of ``dt``. Raises ``kinema.SimulationDiverged`` at a step that
        would leave a non-finite state or make the energy run away (see docs/world.md); the
        world then keeps the state from before it."""
        n = _checks.integer("n", n, 0, what="the number of steps must be >= 0")
        if n > _checks.UINT64_MAX:
            raise ValueError(f"n = {_checks.describe(n)} is invalid: the number of steps must be < 2**64")
        self._push()
        self._look_at_meshes()
        try:
            with self._engine() as core:
                self._advise(core)
            self._advance(n)
        finally:
            self._pull()

    def _advance(self, n: int, measure: bool = False, into: tuple[np.ndarray, np.ndarray] | None = None) -> dict | None:
        """``n`` steps; with ``measure``, the diagnostics at their end where the steps ran in
        one call (no births or deaths due: the contacts' energy is then summed by the last
        step's own force pass, ``World::advance_measured``), else ``None``; with ``into``
        ((N, 3) rooms for the positions and velocities), those at the end written there by
        the diagnostics' own pass (the dict's ``"state"`` says whether they were: a frame of
        :meth:`run`, ``Recorder.room``). With emitters, the steps run in batches up to the next step boundary at
        which a birth is due (or one at a time while a newborn waits for its place): the births
        due by a step's start are added before it (``kinema.emitter``). Deaths (times of death,
        kill volumes) are the engine's, after each step (``World::set_times_of_death``,
        ``World::set_kill_volumes``). The stable-step
        advisor looks at the newborn at the next call of :meth:`step` or the next frame of
        :meth:`run`."""
        if not self._changes_count():
            with self._engine() as core:
                measured = (core.step_measured(n) if into is None else core.step_measured(n, *into)) if measure else core.step(n)
                self._notice_placement(core)
            return measured
        left = n
        while left > 0:
            self._births()
            if self._advice_due and len(self) >= 2 * self._advised_at:
                # newborns may be stiffer than what was there (contacts of a first pair): the
                # advisor looks again at the first births and whenever the count has doubled
                with self._engine() as core:
                    self._advise(core)
            k = self._steps_before_births(left)
            before = np.asarray(self._core.ids, dtype=np.int64)
            try:
                with self._engine() as core:
                    self._send_deaths(core)
                    core.step(k)
                    self._notice_placement(core)
            finally:
                self._drop_removed(before)
                self._pull()
            left -= k
        return None

    @staticmethod
    def _notice_placement(core: Any) -> None:
        """Warns of the overlaps the engine's placement check accepted in the steps just taken
        (``PlacementWarning``: they will be pushed apart)."""
        notice = core.take_placement_notice()
        if notice:
            warnings.warn(notice, PlacementWarning, stacklevel=4)

    def run(
        self,
        duration: float,
        fps: float = 60.0,
        callback: Callable[[World], Any] | None = None,
        checkpoint: Any = None,
        checkpoint_every: float | None = None,
        *,
        max_work: float | None = MAX_WORK,
        record_contacts: bool = False,
    ) -> Trajectory:
        """Simulate ``duration`` seconds from now, recording a frame every 1/fps s, the current
        state included: frame k at t₀ + k/fps exactly, each frame ⌈1/(fps·dt)⌉ equal steps of
        at most dt (dt itself where it divides the frame; ``Trajectory.step`` says which:
        ``kinema.frames``), and the world ends at t₀ + ``duration`` (a last part-frame
        stepped, unrecorded, when the duration is no whole number of frames). ``callback(world)`` runs after
        each recorded frame. Returns the ``Trajectory``. In a world with spin each frame
        keeps the angular velocities (and the orientations, where the engine integrates them):
        ``Trajectory.angular_velocities`` and ``orientations``.

        ``record_contacts=True`` keeps :meth:`contacts` at each frame, the particles named by
        their ids, in ``Trajectory.contact_record`` (a ``kinema.contact_record.ContactRecord``):
        saved in H5MD (``/contacts``), exported as a LAMMPS ``dump local`` file and as VTK lines
        (docs/files.md).

        ``checkpoint`` (a path) with ``checkpoint_every`` (simulated seconds, rounded to whole
        frames): at those frames the world and the frames recorded so far are written there
        (``kinema.checkpoint``), replacing the last; ``kinema.resume_run(path)`` goes on from
        it to the same end, bit for bit as this run.

        ``max_work``: the most particle-steps (particles now and those the emitters will add,
        × steps) the run may take; a run
        over it is refused before any step with a ``ValueError`` that gives the estimate
        (default ``MAX_WORK`` = 1e11, the command line's limit: hours of work; ``None``: no
        limit)."""
        duration, fps = _checks.real("duration", duration), _checks.real("fps", fps)
        if callback is not None and not callable(callback):
            raise TypeError(f"callback = {_checks.describe(callback)} is invalid: it must be a function callback(world) or None")
        if not (np.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration = {duration} is invalid: it must be a finite number of seconds >= 0")
        if not (np.isfinite(fps) and fps > 0):
            raise ValueError(f"fps = {fps} is invalid: frames per second must be > 0")
        every_s = _checks.real("checkpoint_every", checkpoint_every, optional=True)
        if (checkpoint is None) != (every_s is None):
            raise ValueError("checkpoint and checkpoint_every go together: a path and how often to write it (s)")
        if every_s is not None and not (np.isfinite(every_s) and every_s > 0):
            raise ValueError(f"checkpoint_every = {every_s} is invalid: it must be a finite number of seconds > 0")
        steps_per_frame = 1.0 / fps / self.dt  # (fps * dt may underflow to 0: 5e-324 * 1e-3)
        if not steps_per_frame < 2.0**63:
            raise ValueError(
                f"fps = {_checks.describe(fps)} is invalid: one frame would take {steps_per_frame:.3g} steps of dt = {self.dt:g} s (at most 2**63)"
            )
        plan = frames_plan(duration, self.dt, fps)
        frames = plan.frames
        every = 0 if every_s is None else max(1, round(every_s * fps))
        limit = _checks.real("max_work", max_work, optional=True)
        if limit is not None and not limit > 0:
            raise ValueError(f"max_work = {_checks.describe(max_work)} is invalid: it must be a number of particle-steps > 0, or None for no limit")
        born = births_until(self._emitters, self.time + duration)
        n = len(self) + born
        work = float(n) * plan.steps
        if limit is not None and work > limit:
            whom = f"{len(self):,} particles" + (f" and up to {born:,} from the emitters" if born else "")
            raise ValueError(
                f"the run would take {work:.1e} particle-steps ({whom} × {plan.steps:,} steps of dt = {self.dt:g} s "
                f"for duration = {duration:g} s), over max_work = {limit:.1e}; give max_work=None (or a larger number) to run it anyway"
            )
        record_contacts = _checks.boolean("record_contacts", record_contacts)
        self._push()
        self._look_at_meshes()
        with self._engine() as core:
            self._advise(core)
        rec = Trajectory._recorder(frames + 1, contacts=record_contacts)
        rec.add(self)
        run = {
            "frames_done": 0,
            "frames_total": frames,
            "per_frame": plan.per_frame,
            "every": every,
            "fps": fps,
            "t0": self.time,
            "duration": duration,
            "recorder": rec,
            **self._run_source,
        }
        return self._record(run, callback, None if checkpoint is None else Path(checkpoint))

    # -- stability --------------------------------------------------------------------------
    def stable_step(self, method: str | ButcherTableau | None = None) -> float | dict[str, float]:
        """The largest stable time step, s, at the current state: for ``method`` (a name or a
        ``ButcherTableau``), or, with ``method=None``, a dict over every registered method.

        The advisor estimates the stiffest mode of the linearised forces and its damping ratio
        by power iteration on Jacobian-vector products, then applies each method's stability
        function on that damped oscillator (``kinema.stability.max_step_oscillator``) and on
        the largest pure damping rate. ``inf`` when no step is too large (implicit_euler;
        rk45, which sub-steps adaptively). Closed-form upper bounds (Gershgorin: for springs
        ω² ≤ max_p 2 Σ k/m_p) are reported by :meth:`rates`.
        """
        self._push()
        with self._engine() as core:
            if method is None:
                return {name: core.stable_step(name) for name in method_names()}
            return core.stable_step(method)

    def rates(self) -> dict:
        """The advisor's estimate at the current state: ``omega`` (rad/s, the highest natural
        frequency), its damping ratio ``zeta``, the largest damping rate ``damping_rate``
        (1/s), closed-form upper bounds ``omega_bound`` and ``damping_rate_bound`` (None when a
        force has none), the power ``iterations`` used, and ``standby_omega``/``standby_zeta``:
        the stiffest mode a force can reach from another state — a spring–dashpot contact
        not touching yet — or None."""
        self._push()
        with self._engine() as core:
            return core.rates()

    # -- the count and the diagnostics (the state as arrays: _world_views.py) ---------------
    def __len__(self) -> int:
        return self._core.len

    def diagnostics(self) -> dict:
        """Kinetic energy (J), potential energy per conservative force (J), linear momentum
        (kg·m/s), angular momentum about the origin (kg·m²/s) and ``kinetic_tensor``, Σ m v ⊗ v
        (J, 9 numbers, row-major: the kinetic part of the pressure tensor times the volume) now. With spin: ``rotational``,
        Σ ½ I |ω|² (J), and ``spin_angular_momentum``, Σ I ω (kg·m²/s), which
        ``angular_momentum`` includes."""
        self._push()
        with self._engine() as core:
            return core.diagnostics()

    # -- scenes, checkpoints and the state ---------------------------------------------------
    def to_scene(self) -> Scene:
        """The scene of the world as it is now: one explicit particle list, its forces, colliders
        and settings; duration, fps, render, output and analysis options come from :attr:`scene`
        when the world was loaded from one. Each particle's own restitution and friction come
        from the engine; a ``PythonForce`` cannot be written and raises ``ValueError``.

        What it makes is checked to be a scene kinema reads back and builds: the particles'
        values by the engine's rules (a mass written into ``world.masses`` as -1 is refused),
        then the whole scene by its schema. A value that fails is a ``SceneError`` (a
        ``ValueError``) of one line naming the key, the particle index and the value:
        ``<world>: particles[0].mass[3]: -1.0 is invalid: masses must be finite and > 0 kg ...``.
        (``kinema.scene.to_scene``.)"""
        from .scene.export import to_scene

        return to_scene(self)

    def save_checkpoint(self, path: str | Path, _run: dict | None = None) -> Path:
        """Write the world to ``path`` between steps, one HDF5 file that :meth:`load_checkpoint`
        reads back into a world that goes on exactly as this one (what it holds: the module
        ``kinema.checkpoint``), and restart its caches; returns the path. A world with a
        ``PythonForce`` cannot be written (``ValueError``). (``_run``: the progress of
        :meth:`run`, written by it; see ``kinema.resume_run``.)"""
        from .checkpoint import save_checkpoint

        return save_checkpoint(self, path, _run)

    @staticmethod
    def load_checkpoint(path: str | Path) -> World:
        """The world written by :meth:`save_checkpoint` at ``path``, ready to go on. Every field is
        checked first; a missing, damaged or foreign file is a ``kinema.checkpoint.CheckpointError``
        (a ``ValueError``), one line naming the file, the field and the value."""
        from .checkpoint import load_checkpoint

        return load_checkpoint(path)

    def _state(self, sync: bool = False) -> WorldState:
        """The world's state beyond its public API, as one object (``kinema._state``: its field
        table): the engine and the Python extras the world keeps, its own objects, not copies.
        With ``sync``, what was written into the views is handed to the engine first (a bad
        value is refused whole, as at a step). Package-internal: with :meth:`_restore`, the one
        way the package's other modules read and write a world's state (module doc)."""
        if sync:
            self._push()
        return WorldState(
            engine=self._core,
            colors=self._colors,
            spring_ids=self._spring_ids,
            spring_rest=self._spring_rest,
            emitters=self._emitters,
            kills=self._kills,
            method=self._method_arg,
            warned=self._warned,
            contact_warned=self._contact_warned,
            advice_due=self._advice_due,
            advised_at=self._advised_at,
            placed=self._placed,
            run_source=self._run_source,
        )

    def _restore(self, state: WorldState) -> None:
        """Gives the world the state ``state`` (as :meth:`_state` gives it, its fields set anew:
        a checkpoint's) and reads the views anew from its engine: views taken before no longer
        follow the world."""
        self._core = state.engine
        self._colors = state.colors
        if state.death_given is not None and (self._core.has_times_of_death or np.isfinite(state.death_given).any()):
            self._core.set_times_of_death(0, np.ascontiguousarray(state.death_given, dtype=float))
            state.death_given = None  # (the engine's now)
        self._spring_ids, self._spring_rest = state.spring_ids, state.spring_rest
        self._emitters, self._kills = state.emitters, state.kills
        self._method_arg = state.method
        self._warned, self._contact_warned = state.warned, state.contact_warned
        self._advice_due, self._advised_at = state.advice_due, state.advised_at
        self._placed, self._run_source = state.placed, state.run_source
        self._new_views()

    def __repr__(self) -> str:
        if isinstance(self._core, _Busy):
            return "World(stepping)"
        spin = ", spin=True" if self._core.spin else ""
        return f"World(dim={self.dim}, dt={self.dt}, method={self.method!r}{spin}, particles={len(self)}, t={self.time:g})"

    def _repr_html_(self) -> str:
        """A small table for Jupyter: the repr's values, the forces, colliders and collisions."""
        from html import escape

        if isinstance(self._core, _Busy):
            return "<b>kinema.World</b> (stepping)"
        collisions = self.collisions
        rows = [
            ("particles", f"{len(self)} in {self.dim}D"),
            ("time", f"t = {self.time:g} s, dt = {self.dt:g} s, method {self.method!r}"),
            ("forces", ", ".join(type(f).__name__ for f in self._forces) or "none"),
            ("colliders", ", ".join(type(c).__name__ for c in self._colliders) or "none"),
            ("collisions", "off" if collisions is None else f"{collisions.get('model', 'impulse')}"),
        ]
        cells = "".join(f"<tr><th style='text-align:left'>{escape(k)}</th><td style='text-align:left'>{escape(v)}</td></tr>" for k, v in rows)
        return f"<table><caption style='text-align:left'><b>kinema.World</b></caption>{cells}</table>"
