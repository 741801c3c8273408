"""Adding and removing the particles of a ``kinema.World``: ``WorldParticles``, a base class of
``World``, not used alone.

``add_particles`` and ``add_particles_from`` check what they are given (``_species_names``
the species) and hand it to ``_add``, which the emitters' births use too
(``World._births``); ``remove_particles`` and the engine's deaths (``World._drop_removed``)
end in ``_forget``. ``_add`` and ``_forget`` keep what the Python world holds per particle
besides the engine's state in step with it: the species names and the colours (``_unset``,
``_grown``, ``_kept``; ``kinema._world_run``'s ``_trajectory_info`` reads the colours with ``_unset`` too).

Its methods use the world's engine and views (``_core``, ``_push``, ``_new_views``:
``kinema._world_views``) and what ``World.__init__`` sets (``_species``, ``_colors``,
``_advice_due``). Units: m, s, kg."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _checks


# What the Python world keeps per particle besides the engine's state — each particle's own
# colour (r, g, b; NaN: none) — is, while no particle has one, a read-only broadcast of that one
# value: no memory per particle (24 B at 10⁶ particles). (Times of death are the engine's.)
def _unset(a: np.ndarray) -> bool:
    """Whether ``a`` holds no particle's own value (empty, or the broadcast of the default)."""
    return a.size == 0 or a.strides[0] == 0


def _grown(a: np.ndarray, n: int, default: float, values: Any) -> np.ndarray:
    """``a`` with ``n`` more particles' ``values`` (None: the default ``default``)."""
    if values is None and _unset(a):
        return np.broadcast_to(np.float64(default), (len(a) + n, *a.shape[1:]))
    return np.concatenate([a, np.full((n, *a.shape[1:]), default) if values is None else values])


def _kept(a: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """``a`` of the particles that ``keep`` keeps."""
    if _unset(a) and a.size:
        return np.broadcast_to(a.flat[0], (int(keep.sum()), *a.shape[1:]))
    return a[keep]


class WorldParticles:
    """Adding and removing the particles of a ``kinema.World``: see ``World`` and docs/world.md."""

    def add_particles(
        self,
        position: Any,
        velocity: Any = None,
        mass: Any = 1.0,
        radius: Any = 0.0,
        pinned: Any = None,
        restitution: Any = None,
        friction: Any = None,
        species: Any = None,
        angular_velocity: Any = None,
        inertia: Any = None,
        group: Any = 0,
    ) -> np.ndarray:
        """Add particles; returns their indices.

        ``position`` (N, 3) in m (a single (3,) point adds one particle); ``velocity`` (N, 3)
        in m/s (default 0); ``mass`` in kg and ``radius`` in m, scalars or (N,); ``pinned``
        bool, scalar or (N,): a pinned particle never moves (inverse mass 0) nor turns.

        In a world with spin: ``angular_velocity`` (N, 3) or one (3,) vector, rad/s (default
        0; a 2D world turns about z only, so x and y must be 0); ``inertia`` the moment of
        inertia about the centre, kg·m², a scalar or (N,) (default 2/5 m r² in 3D, 1/2 m r² in
        2D). Either in a world without spin is a ``ValueError``.

        ``restitution`` e ∈ [0, 1] and ``friction`` μ ≥ 0: each particle's own collision
        values, scalars or (N,) (``None`` or NaN entries: the world's values of
        :meth:`set_collisions`). A pair combines its two by Box2D's rule, e = max(e_i, e_j) and
        μ = √(μ_i μ_j); a collider's own value overrides the particle's. Giving any turns
        collisions on.

        ``species``: a name for these particles, or one per particle (one word each: letters,
        digits, ``_ . + -``), recorded in trajectories and written by the exports as the particle type (OVITO,
        ASE's chemical symbol, HOOMD's types, H5MD's species); particles without one are
        ``X`` once any particle has one.

        ``group``: the particles' collision group, an integer in 0..31 or one per particle
        (default 0): which particles and colliders they collide with is set per group
        (:meth:`set_group_collisions`, :attr:`collision_matrix`, a collider's
        ``collides_with``; Box2D's category bits). :attr:`groups` reads and changes them.

        Nothing is coerced: numbers are real numbers (ints or floats, NumPy scalars or arrays
        of an int or float dtype), and a bool, a complex number, a string or a date among them
        is a ``TypeError`` naming the parameter and the value; ``pinned`` takes only bools
        (``True``/``False``, NumPy bools), not ``'no'`` or ``0``.
        """
        x = np.atleast_2d(_checks.real_array("position", position))
        if x.ndim != 2 or x.shape[1] != 3:
            raise ValueError(f"position has shape {np.shape(position)}; it must be (N, 3) or a single (3,) point")
        n = x.shape[0]
        each = f"a scalar or one value per particle, ({n},)"
        v = np.zeros_like(x) if velocity is None else np.atleast_2d(_checks.real_array("velocity", velocity))
        v = _checks.broadcast("velocity", v, (n, 3), f"a (3,) vector or one per particle, ({n}, 3)")
        m = _checks.broadcast("mass", _checks.real_array("mass", mass), (n,), each)
        r = _checks.broadcast("radius", _checks.real_array("radius", radius), (n,), each)
        p = _checks.broadcast("pinned", _checks.bool_array("pinned", False if pinned is None else pinned), (n,), each)
        e, mu = (
            None if a is None else _checks.broadcast(name, _checks.real_array(name, a, none_is_nan=True), (n,), each).tolist()
            for name, a in (("restitution", restitution), ("friction", friction))
        )
        names = self._species_names(species, n)
        groups = _checks.groups("group", group, n)
        spin = None
        if angular_velocity is not None or inertia is not None:
            if not self._core.spin:
                given = "angular_velocity" if angular_velocity is not None else "inertia"
                raise ValueError(f"{given} is given, but this world has no spin: make it with kinema.World(..., spin=True)")
            w = None if angular_velocity is None else np.atleast_2d(_checks.real_array("angular_velocity", angular_velocity))
            w = None if w is None else _checks.broadcast("angular_velocity", w, (n, 3), f"a (3,) vector or one per particle, ({n}, 3)")
            i = None if inertia is None else _checks.broadcast("inertia", _checks.real_array("inertia", inertia), (n,), each)
            spin = (w, i)
        return self._add(x, v, m, r, p, e, mu, names, spin=spin, group=groups)

    def add_particles_from(
        self,
        path: Any,
        frame: int = -1,
        units: Any = None,
        *,
        format: str | None = None,
        atom_style: str | None = None,
        translate: Any = None,
        velocity: Any = None,
        mass: Any = 1.0,
        radius: Any = 0.0,
        species: Any = None,
        pinned: Any = None,
        restitution: Any = None,
        friction: Any = None,
        group: Any = 0,
    ) -> np.ndarray:
        """Add the particles of frame ``frame`` (-1: the last) of a trajectory file; returns
        their indices, as :meth:`add_particles` does.

        ``path``: any file ``Trajectory.load`` reads (kinema's H5MD and exports, extended XYZ,
        GSD, a LAMMPS dump or data file; docs/files.md), read in SI units: ``units`` for a file
        that does not say its own (a LAMMPS style such as ``"real"``, ``"ase"``, or
        {"length": m, "time": s, "mass": kg}), ``format`` and ``atom_style`` as
        ``Trajectory.load`` takes them. The particles alive at that frame are added in the order
        of their ids, at their positions plus ``translate`` (a (3,) vector, m), each with the
        file's velocity, mass, radius, species and collision group where the file has them
        (kinema's files keep the groups); where it has none, ``velocity`` (default 0),
        ``mass`` (default 1 kg), ``radius`` (default 0), ``species`` and ``group`` (default 0)
        are used, checked as :meth:`add_particles` checks them, as are ``pinned``,
        ``restitution`` and ``friction``. A 2D world takes a file whose z are 0.
        The file's box, colliders and springs are not added: they are the world's own."""
        from .io.readers import particles_from

        got = particles_from(path, frame, units, format=format, atom_style=atom_style)
        x = got["positions"]
        if translate is not None:
            shift = _checks.real_array("translate", translate)
            if shift.shape != (3,):
                raise ValueError(f"translate has shape {shift.shape}; it must be a (3,) vector, m")
            x = x + shift
        v = got["velocities"] if got["velocities"] is not None else velocity
        m = got["masses"] if got["masses"] is not None else mass
        r = got["radii"] if got["radii"] is not None else radius
        names = got["species"] if got["species"] is not None else species
        groups = got["groups"] if got["groups"] is not None else group
        return self.add_particles(x, v, m, r, pinned=pinned, restitution=restitution, friction=friction, species=names, group=groups)

    def _add(self, x, v, m, r, p, e, mu, names, death=None, color=None, spin=None, group=None) -> np.ndarray:
        """Adds checked particles with their species names, times of death, colours, collision
        groups (checked, (N,); None: group 0) and, in a world with spin, their (angular
        velocities, inertias) where given."""
        n = len(m)
        self._push()
        if spin is not None:
            # checked before anything is added: a bad value adds nothing
            self._core.check_particle_spin(*(None if a is None else np.ascontiguousarray(a, dtype=float) for a in spin))
        arrays = {
            k: np.ascontiguousarray(a, dtype=d) for k, a, d in (("x", x, float), ("v", v, float), ("mass", m, float), ("radius", r, float), ("pinned", p, bool))
        }
        given = None if group is None or not np.any(group) else np.asarray(group, dtype=np.int64).tolist()
        start, end = self._core.add_particles({**arrays, "restitution": e, "friction": mu, "group": given})
        if spin is not None:
            self._core.set_particle_spin(start, end, *(None if a is None else np.ascontiguousarray(a, dtype=float) for a in spin))
        if self._species is not None or any(names):  # (no list of N empty names while nobody names one)
            self._species = (self._species if self._species is not None else [""] * start) + names
        if death is not None:
            # the engine keeps them with the particles (none while no particle has one)
            self._core.set_times_of_death(start, np.ascontiguousarray(np.broadcast_to(death, (n,)), dtype=float))
        self._colors = _grown(self._colors, n, np.nan, None if color is None else np.broadcast_to(color, (n, 3)))
        self._new_views()
        self._advice_due = True
        return np.arange(start, end)

    def remove_particles(self, indices: Any) -> None:
        """Remove the particles at these indices (integers, or a bool mask of length N). The
        others keep their order, ids and state, and their indices shift down; springs ending
        on a removed particle go with it. Views taken before no longer follow the world."""
        n = len(self)
        if np.asarray(indices).dtype == bool:
            mask = _checks.bool_array("indices", indices)
            if mask.shape != (n,):
                raise ValueError(f"indices is a bool mask of shape {mask.shape}; it must be ({n},), one flag per particle")
            gone = np.flatnonzero(mask)
        else:
            gone = _checks.index_array("indices", indices, n)
        if gone.size == 0:
            return
        self._push()
        self._core.remove_particles(gone.tolist())
        keep = np.ones(n, dtype=bool)
        keep[gone] = False
        self._forget(keep)

    def _forget(self, keep: np.ndarray) -> None:
        """Keeps what the Python world holds per particle for the particles ``keep`` (a mask
        over the particles before a removal) and reads the state anew."""
        if self._species is not None:
            self._species = [s for s, k in zip(self._species, keep, strict=True) if k]
        self._colors = _kept(self._colors, keep)
        self._new_views()
        self._advice_due = True

    @staticmethod
    def _species_names(species: Any, n: int) -> list[str]:
        """``species`` (None, a name, or one name per particle) as n names ("" for none)."""
        if species is None:
            return [""] * n
        if isinstance(species, str):
            given = [("species", species)]
        elif isinstance(species, (list, tuple, np.ndarray)) and len(species) == n:
            given = [(f"species[{k}]", name) for k, name in enumerate(np.asarray(species, dtype=object).reshape(-1).tolist())]
        else:
            raise TypeError(f"species = {_checks.describe(species)} is invalid: give a name (a string) or one per particle, ({n},)")
        for label, name in given:
            _checks.species(label, name)
        return [species] * n if isinstance(species, str) else [name for _, name in given]
