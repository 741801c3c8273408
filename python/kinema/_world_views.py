"""The engine of a ``kinema.World`` and the NumPy views of its state: ``WorldViews``, a base
class of ``World``, not used alone.

- The engine (``_core``) is the thread's that made the world, checked at every use (else
  ``_other_thread``'s error); ``_engine`` lends it for work that calls back into Python, and
  meanwhile the world's own methods meet ``_Busy`` (``REENTRY``) and its views are read-only.
- The views exist while somebody looks at them: ``_view`` makes one from the engine's state at
  the first look, ``_push`` hands what the user wrote into those that exist to the engine,
  ``_pull`` after a step reads the engine's state into those still held outside the world
  (a ``w.positions`` kept in a variable, or a slice of it, stays live) and drops the others
  (a step of 10⁶ particles keeps no 56 MB of copies nobody reads), ``_new_views`` drops them
  all (the particles changed), ``_assign`` writes a whole array (``w.positions = ...``).
- The state as arrays and values: ``positions``, ``velocities``, ``masses``, ``ids``,
  ``radii``, ``groups``, ``spin``, ``angular_velocities``, ``orientations``, ``inertia``,
  ``momenta``, ``accelerations``, ``particle_stress``, ``time``, ``dt``, ``method``, ``dim``,
  ``species`` and ``forces``.

Its methods use what ``World.__init__`` sets (``_owner``, ``_species``, ``_forces``) and the
engine's state; ``kinema.world`` re-exports ``REENTRY``. Units: m, s, kg."""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from . import _checks

REENTRY = (
    "the world was used while it is stepping (from one of its own forces, or another thread): "
    "a force computes F(t, x, v) from its arguments and must leave its world alone"
)


def _other_thread(owner: int) -> RuntimeError:
    return RuntimeError(
        f"this World was made on thread {owner} and is used on thread {threading.get_ident()}: a World (its engine and its "
        "Python forces) belongs to the thread that made it; make one per thread (or per process: kinema.sweep runs members so)"
    )


# The references `WorldViews._held` counts to a view only the world holds: the world's
# attribute, `_held`'s local name and `getrefcount`'s argument (measured here, not assumed:
# the count differs between Python versions' calling conventions).
class _Probe:
    def __init__(self) -> None:
        self.a = np.empty(1)

    def held(self) -> int:
        a = self.a
        return sys.getrefcount(a)


_OWN_REFERENCES = _Probe().held()


class _Busy:
    """Stands in for the engine while it runs work that calls back into Python (a
    ``PythonForce`` in a step, the advisor, ``accelerations``). The engine is borrowed for
    that work, so any use of the world from there (reading ``time``, writing ``positions``,
    stepping it again) would meet pyo3's bare "Already borrowed"; it meets this instead."""

    def __init__(self, lent: Any = None, views: list | None = None) -> None:
        # (set in the instance's dict: `__getattr__` is asked only for what is not there)
        self.__dict__.update(lent=lent, views=views if views is not None else [])

    def __getattr__(self, name: str) -> Any:
        raise RuntimeError(REENTRY)


class WorldViews:
    """The engine and the state's views of a ``kinema.World``: see ``World`` and docs/world.md."""

    # The engine is the thread's that made the world (its Python forces, the `_Busy` lending
    # and the shared views are not made for two threads at once; any thread may drop it,
    # though: the engine is Send + Sync). Every use of it goes through `_core`, which
    # checks the thread first: from another thread, a RuntimeError that says so, where pyo3
    # would raise its PanicException (a BaseException, with a Rust backtrace).
    @property
    def _core(self) -> Any:
        if threading.get_ident() != self._owner:
            raise _other_thread(self._owner)
        return self._engine_core

    @_core.setter
    def _core(self, core: Any) -> None:
        self._engine_core = core

    @contextmanager
    def _engine(self) -> Iterator[Any]:
        """The engine, lent for work that may call back into Python; meanwhile the world's own
        methods see ``_Busy`` (the views stay readable, and can be made while the engine is not
        stepping: the advisor reads them)."""
        core = self._core
        if isinstance(core, _Busy):
            raise RuntimeError(REENTRY)
        views: list[np.ndarray] = []
        try:  # (all inside: a Ctrl-C anywhere here still gives the engine back)
            self._core = _Busy(core, views)
            # The views are read-only meanwhile: a write into one from a force would be lost or
            # kept depending on what called it (a step reads the state back after, `rates` not).
            for a in (self._x, self._v, self._m, self._w):
                if a is not None and a.flags.writeable:
                    a.flags.writeable = False
                    views.append(a)
            yield core
        finally:
            for a in views:
                a.flags.writeable = True
            self._core = core

    # The views by name: positions, velocities, masses, angular velocities; each `None` where
    # none exists now (nobody looked since the last step, or the particles changed since).
    _VIEWS = ("_x", "_v", "_m", "_w")

    def _new_views(self) -> None:
        """Drops every view (the particles changed): the next look makes it afresh."""
        self._x = self._v = self._m = self._w = None

    def _view(self, name: str) -> np.ndarray:
        """The view ``name`` (one of ``_VIEWS``), made from the engine's state if none exists
        (while the engine is lent, read-only until it is given back, as the others)."""
        a = getattr(self, name)
        core = self._core
        if isinstance(core, _Busy):
            if a is None:
                try:
                    a = self._made(name, core.lent)
                except RuntimeError:  # (pyo3's borrow: read from a force while the engine steps)
                    raise RuntimeError(REENTRY) from None
                a.flags.writeable = False
                core.views.append(a)
                setattr(self, name, a)
            return a
        if a is None or a.shape[0] != core.len:
            a = self._made(name, core)
            setattr(self, name, a)
        return a

    @staticmethod
    def _made(name: str, core: Any) -> np.ndarray:
        """A new view ``name`` of ``core``'s state."""
        n = core.len
        if name == "_m":
            return np.array(core.masses)
        if name == "_w":
            a = np.zeros((n, 3) if core.spin else (0, 3))
            if core.spin:
                core.read_spin(a)
            return a
        a = np.empty((n, 3))
        core.read_state(**{"x" if name == "_x" else "v": a})
        return a

    def _held(self, name: str) -> np.ndarray | None:
        """The view ``name`` if it exists and somebody outside the world holds it (itself or a
        view of its memory: a slice holds its base)."""
        a = getattr(self, name)
        return a if a is not None and sys.getrefcount(a) > _OWN_REFERENCES else None

    def _push(self) -> None:
        """Hands what the user wrote into the views that exist to the world (a no-op when
        unchanged), then lets go of those nobody outside holds. A bad value is refused whole: the
        world keeps its state and the views show it again."""
        if self._x is None and self._v is None and self._m is None and self._w is None:
            return  # (nobody looked: nothing written)
        try:
            self._core.sync(self._x, self._v, self._m)
            if self._core.spin and self._w is not None:
                self._core.sync_spin(self._w)
        except ValueError:
            self._pull(keep=True)
            if self._m is not None:
                self._m[...] = self._core.masses
            raise
        # What nobody outside the world holds is let go before the engine works (made again at
        # the next look): a passing look such as ``np.sum(w.velocities**2)`` between two steps
        # does not stay resident while the world steps (24 MB at 10⁶ particles).
        self._let_go()

    def _let_go(self) -> None:
        """Drops the views nobody outside the world holds (made again at the next look)."""
        for name in self._VIEWS:
            if self._held(name) is None:
                setattr(self, name, None)

    def _pull(self, keep: bool = False) -> None:
        """After the engine changed the state: the views held outside the world read it (they
        are live), the others are dropped (made again at the next look); with ``keep``, every
        view that exists reads it."""
        n = self._core.len
        x, v, m, w = (getattr(self, a) if keep else self._held(a) for a in self._VIEWS)
        if any(a is not None and a.shape[0] != n for a in (x, v, m, w)):  # (a Ctrl-C between a birth and its new views)
            self._new_views()
            return
        self._x, self._v, self._m, self._w = x, v, m, w  # (masses: no step changes them)
        if x is not None or v is not None:
            self._core.read_state(x=x, v=v)
        if w is not None and self._core.spin:
            self._core.read_spin(w)

    # -- state ------------------------------------------------------------------------------
    @property
    def positions(self) -> np.ndarray:
        """Positions (N, 3), m: a live view (updated by each step while it is held; writes move
        the particles)."""
        return self._view("_x")

    @positions.setter
    def positions(self, value: Any) -> None:
        self._assign("_x", value, "positions", (len(self), 3))

    @property
    def velocities(self) -> np.ndarray:
        """Velocities (N, 3), m/s: a live view, as :attr:`positions` (pinned particles keep 0)."""
        return self._view("_v")

    @velocities.setter
    def velocities(self, value: Any) -> None:
        self._assign("_v", value, "velocities", (len(self), 3))

    @property
    def masses(self) -> np.ndarray:
        """Masses (N,), kg: a live view (pinned particles keep theirs and stay pinned)."""
        return self._view("_m")

    @masses.setter
    def masses(self, value: Any) -> None:
        self._assign("_m", value, "masses", (len(self),))

    @property
    def ids(self) -> np.ndarray:
        """Each particle's id (N,): given in the order particles are added, kept for life,
        never given again (a new read-only array)."""
        out = np.asarray(self._core.ids, dtype=np.int64)
        out.flags.writeable = False
        return out

    @property
    def radii(self) -> np.ndarray:
        """Radii (N,), m: a new read-only array (set by ``add_particles(..., radius=...)``)."""
        out = np.asarray(self._core.radii, dtype=np.float64)
        out.flags.writeable = False
        return out

    @property
    def groups(self) -> np.ndarray:
        """Each particle's collision group (N,), an integer in 0..31 (default 0): a new
        read-only array. Assign ``w.groups = ...`` (a group for all, or one per particle) to
        move particles to other groups; ``add_particles(..., group=...)`` and an emitter's
        ``group`` set them at birth. Which groups collide: :attr:`collision_matrix`."""
        out = np.asarray(self._core.groups, dtype=np.int64)
        out.flags.writeable = False
        return out

    @groups.setter
    def groups(self, value: Any) -> None:
        g = _checks.groups("groups", value, len(self))
        self._push()
        self._core.set_groups(0, g.tolist())

    @property
    def spin(self) -> bool:
        """Whether the particles turn (``World(spin=True)``)."""
        return self._core.spin

    @property
    def angular_velocities(self) -> np.ndarray:
        """Angular velocities ω (N, 3), rad/s, in a world with spin: a live view (updated by each
        step; writes turn the particles; pinned particles keep 0; a 2D world turns about z)."""
        self._need_spin("angular_velocities")
        return self._view("_w")

    @angular_velocities.setter
    def angular_velocities(self, value: Any) -> None:
        self._need_spin("angular_velocities")
        self._assign("_w", value, "angular_velocities", (len(self), 3))

    @property
    def orientations(self) -> np.ndarray:
        """Orientations (N, 4) in a world with spin: unit quaternions (w, x, y, z), the
        identity when a particle is added, turned at each step by the rotation
        (cos(θ/2), sin(θ/2) ω̂), θ = dt |ω̄|, of the step's mean angular velocity ω̄ (world
        frame; exact for a steady spin: a ball that rolls at v turns by v t / ρ). A new
        read-only array; assign an (N, 4) array to set them (each is normalised)."""
        self._need_spin("orientations")
        out = np.asarray(self._core.orientations)
        out.flags.writeable = False
        return out

    @orientations.setter
    def orientations(self, value: Any) -> None:
        self._need_spin("orientations")
        q = np.ascontiguousarray(_checks.real_array("orientations", value), dtype=float)
        self._core.set_orientations(q.reshape(-1, 4) if q.ndim == 1 and q.size == 4 * len(self) else q)

    @property
    def inertia(self) -> np.ndarray:
        """Moments of inertia about the centres (N,), kg·m², in a world with spin (a new
        read-only array; set by ``add_particles(..., inertia=...)``)."""
        self._need_spin("inertia")
        out = np.asarray(self._core.inertia)
        out.flags.writeable = False
        return out

    def _need_spin(self, name: str) -> None:
        if not self._core.spin:
            raise ValueError(f"{name}: this world has no spin (its particles are points with mass); make it with kinema.World(..., spin=True)")

    def _assign(self, view_name: str, value: Any, name: str, shape: tuple[int, ...]) -> None:
        if isinstance(self._core, _Busy):  # (from a force while the world steps)
            raise RuntimeError(REENTRY)
        view = self._view(view_name)
        new = _checks.real_array(name, value)
        try:
            new = np.broadcast_to(new, shape)
        except ValueError:
            raise ValueError(f"{name} has shape {np.shape(value)}; it must be {shape}") from None
        old = view.copy()
        view[...] = new
        try:
            self._push()
        except ValueError:
            view[...] = old  # nothing half-written
            raise
        self._pull(keep=True)

    @property
    def momenta(self) -> np.ndarray:
        """Momenta L = m v (N, 3), kg·m/s (0 for pinned particles); a new read-only array."""
        self._push()
        out = self.masses[:, None] * self.velocities
        out.flags.writeable = False
        return out

    @property
    def accelerations(self) -> np.ndarray:
        """Accelerations a = F/m (N, 3), m/s², under the forces now (0 for pinned particles); a
        new read-only array."""
        self._push()
        with self._engine() as core:
            out = core.accelerations()
        out.flags.writeable = False
        return out

    def particle_stress(self, kinetic: bool = True) -> np.ndarray:
        """Each particle's share of the stress now, (N, 3, 3) in N·m (Pa·m³: stress times
        volume): ½ Σ_j (x_i − x_j) ⊗ F_ij over the particles it touches (the force models'
        contact forces, tangential part included; colliders left out, as in
        ``Trajectory.pressure``), plus m_i v_i ⊗ v_i with ``kinetic``. Summed over the
        particles and divided by the volume (an area in 2D) it is the pressure tensor; LAMMPS's
        ``compute stress/atom`` gives its negative. Needs the ``"spring_dashpot"`` or
        ``"hertz"`` model (the impulse model's collisions are impulses, not forces: a
        ``ValueError`` says so); without collisions, the kinetic part alone. A new read-only
        array."""
        self._push()
        with self._engine() as core:
            out = core.particle_stress(_checks.boolean("kinetic", kinetic))
        out.flags.writeable = False
        return out

    @property
    def time(self) -> float:
        return self._core.time

    @property
    def dt(self) -> float:
        return self._core.dt

    @property
    def method(self) -> str:
        return self._core.method

    @property
    def dim(self) -> int:
        return self._core.dim

    @property
    def species(self) -> np.ndarray | None:
        """Each particle's species name (N,), ``X`` where none was given; ``None`` when no
        particle has one."""
        if self._species is None or not any(self._species):
            return None
        return np.array([s or "X" for s in self._species])

    @property
    def forces(self) -> list[Any]:
        return list(self._forces)
