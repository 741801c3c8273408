"""What `World.run` records at each frame (`Recorder`: positions and velocities copied into
one block of frames, the diagnostics, the particles' sets, spins, contacts and the collider
books), and those frames made the fields of a `Trajectory` at the end (`Recorder.fields`:
columns by id where particles were born or died, the pressure of a periodic world).

`kinema.trajectory._Recorder` is `Recorder` with `finish`, the `Trajectory` made; this module
imports nothing of `kinema.trajectory` (which imports it), and holds what both use:
`COLLIDER_RECORD`, the collider books a trajectory keeps."""

from __future__ import annotations

import mmap
import os
from typing import Any

import numpy as np

from .contact_record import ContactRecord, as_ids


def _has_cell(about: dict) -> bool:
    """Whether the world ``about`` describes is periodic along every axis of its dimension,
    with a cell: the volume a pressure needs."""
    dim, periodic = about.get("dim", 3), about.get("periodic")
    return periodic is not None and about.get("box_edges") is not None and all(periodic[:dim])


def _pressure(t: np.ndarray, virial: np.ndarray, kinetic: np.ndarray, about: dict) -> np.ndarray | None:
    """The pressure tensor at each frame (`Trajectory.pressure`) from the time `t` (F,),
    the virial summed over all steps (F, 9), N·m·s, and Σ m v ⊗ v (F, 9) at each frame, in a
    periodic cell (`about`: its `dim`, `periodic` and `box_edges`); `None` without
    one."""
    if not _has_cell(about):
        return None
    dim, edges = about.get("dim", 3), about["box_edges"]
    volume = float(np.prod(np.asarray(edges, dtype=float)[:dim]))
    pressure = np.full((len(t), 3, 3), np.nan)
    if len(t) > 1:
        rate = np.diff(virial, axis=0) / np.diff(t)[:, None]
        pressure[1:] = ((kinetic[1:] + rate) / volume).reshape(-1, 3, 3)
    return pressure


# The kinetic tensor of a frame where no pressure is made (zeros: what a checkpoint writes).
_NO_TENSOR = np.zeros(9)

# The collider books `World.run` records at each frame: the trajectory's attribute and the key
# of `World.collider_books` it holds (F, K, 3), N·s.
COLLIDER_RECORD = {"collider_momentum": "momentum", "collider_normal": "normal", "collider_tangential": "tangential"}


def _prefaulted(shape: tuple[int, ...]) -> np.ndarray:
    """An uninitialised float64 array of `shape` whose memory the kernel maps in one go
    (`MAP_POPULATE`, Linux) rather than one page fault at a time as the frames are written.

    A run's block of frames is fresh memory, and writing it the first time faults in every
    4 KiB page: measured on this project's machine (a VM), 48 ms per frame of 10⁶ particles'
    positions, against 2 ms for the copy itself and 8 ms per frame populated at once. Small
    blocks, systems without the flag, and blocks over half of the memory available now
    (which faulting in at once could exhaust) get a plain `np.empty`."""
    size = 8 * int(np.prod(shape))
    populate = getattr(mmap, "MAP_POPULATE", 0)
    if not populate or size < (1 << 22):
        return np.empty(shape)
    try:
        available = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError):
        available = 0
    if size > available // 2:
        return np.empty(shape)
    try:
        buffer = mmap.mmap(-1, size, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS | populate)
    except (OSError, ValueError):
        return np.empty(shape)
    return np.frombuffer(buffer, dtype=np.float64).reshape(shape)


class Recorder:
    """Collects frames while a world runs (`kinema.trajectory._Recorder` is this class with
    `finish`, which makes the `Trajectory` of `fields`). Particles are columns by id: when the set of ids
    changes (births, deaths), the columns are the union of all ids, NaN where not alive.

    With the number of frames `expected` (`World.run` knows it), positions and velocities
    are copied straight into one block of that many frames, which the trajectory then uses as
    it is: each frame's state is copied once, not once into the frame and again into the stack
    (for 10⁶ particles that second copy was a fifth of a 60 fps run's time). A frame that does
    not fit the block (a changed set of particles, more frames) is kept on its own.

    In a world with spin each frame also keeps its angular velocities and, where the engine
    has them, its orientations (`turning`); with `contacts`, each frame's `World.contacts()`,
    particles named by id (`touching`); each frame, what the particles had given each
    collider so far (`walls`, `COLLIDER_RECORD`'s keys of `World.collider_books`)."""

    def __init__(self, expected: int = 0, contacts: bool = False) -> None:
        self.frames: list[tuple] = []
        self._expected = expected
        self._block: tuple[np.ndarray, np.ndarray] | None = None
        self.about: dict[str, Any] = {}
        # (ids, masses, radii, species, colors, groups) each time the set of particles changed
        self.sets: list[tuple] = []
        # the engine's count of changes to its set of particles when the ids were last read
        self._membership: int | None = None
        # per frame: {"angular_velocities": (n, 3), "orientations": (n, 4)}, those the world has
        self.turning: list[dict[str, np.ndarray]] = []
        # per frame with `contacts`: World.contacts() with ids for indices
        self.contacts = contacts
        self.touching: list[dict[str, np.ndarray]] = []
        # per frame: {"momentum", "normal", "tangential"} (K, 3) N·s, the collider books so far
        # (K: the colliders then); None for good once a frame's steps booked nothing
        self.walls: list[dict[str, np.ndarray]] | None = []

    def add(self, world: Any, diagnostics: dict | None = None) -> None:
        """Records the world's frame now; `diagnostics`: its `World.diagnostics()` where the
        steps that led here measured them (`World._advance`), else they are read now."""
        # What the world is (masses, radii, species, colliders, ...) is read only when its set of
        # particles changed, not at every frame; the ids are compared each frame.
        state = world._state()  # (kinema._state.WorldState: the engine, the springs' ends)
        # the ids are read again only when the set of particles changed (the engine's count of
        # changes moved): at 10⁶ particles, three arrays of 8 MB a frame otherwise
        membership = state.engine.membership
        if self.sets and membership == self._membership:
            ids = self.sets[-1][0]
        else:
            ids = np.asarray(state.engine.ids, dtype=np.int64)
            self._membership = membership
        if not self.sets or (ids is not self.sets[-1][0] and not np.array_equal(ids, self.sets[-1][0])):
            info = world._trajectory_info()
            if not self.about:
                self.about = info
            self.sets.append((ids, info["masses"], info["radii"], info["species"], info["colors"], info["groups"]))
        springs = state.spring_ids  # springs added mid-run count
        self.about["springs"] = springs.copy() if springs.size else None
        d = world._diagnostics_as_pulled() if diagnostics is None else diagnostics
        stats = world._collision_stats_as_pulled()
        if stats is None:
            contacts, balance, lost, impacts, virial = 0, np.zeros(3), 0.0, 0, np.zeros(9)
        else:
            total = stats["total"]
            contacts, balance, lost = stats["last"]["contacts"], total["impulse_balance"], total["energy_lost"]
            impacts, virial = total["impacts"], np.ravel(total["virial"])
        x, v = self._keep(state.engine, len(ids), diagnostics is not None and diagnostics.get("state") is True)
        # Σ m v ⊗ v, row-major (the kinetic part of the pressure tensor, times the volume),
        # summed with the diagnostics: kept in a periodic cell only, the one place a pressure
        # is made
        kinetic = np.array(d["kinetic_tensor"]) if _has_cell(self.about) else _NO_TENSOR
        frame = (d["t"], x, v, d["kinetic"], d["potential"], d["momentum"], d["angular_momentum"])
        self.frames.append((*frame, contacts, balance, lost, ids, impacts, virial, kinetic))
        self.turning.append(_turning(world))
        if self.contacts:
            self.touching.append(as_ids(state.engine.contacts(), ids))
        if self.walls is not None:
            if world._books_colliders():
                books = world._collider_books_as_pulled()
                self.walls.append({key: books[key] for key in COLLIDER_RECORD.values()})
            else:
                self.walls = None

    def room(self, n: int) -> tuple[np.ndarray, np.ndarray] | None:
        """The next frame's place in the block for the positions and velocities of `n`
        particles, where it has one: the steps that lead to the frame write them there as they
        measure its diagnostics (`World._advance`: one pass over the state, not two), and
        `add` then keeps them as they are."""
        k, block = len(self.frames), self._block
        if block is not None and 0 < k < block[0].shape[0] and block[0].shape[1] == n:
            return block[0][k], block[1][k]
        return None

    def _keep(self, engine: Any, n: int, written: bool) -> tuple[np.ndarray, np.ndarray]:
        """This frame's positions and velocities of the `n` particles, read from the `engine`
        (right after the world's views were pulled: the state the user sees) into their place
        in the block when they fit, else into arrays of their own; `written`: the steps wrote
        them into their place already (`room`)."""
        k = len(self.frames)
        if self._block is None and k == 0 and self._expected > 1:
            self._block = (_prefaulted((self._expected, n, 3)), _prefaulted((self._expected, n, 3)))
        room = self.room(n)
        if room is not None and written:
            return room
        block = self._block
        if block is not None and k < block[0].shape[0] and block[0].shape[1] == n:
            x, v = block[0][k], block[1][k]
        else:
            x, v = np.empty((n, 3)), np.empty((n, 3))
        engine.read_state(x=x, v=v)
        return x, v

    def _stacked(self, x: tuple, v: tuple) -> tuple[np.ndarray, np.ndarray]:
        """The frames as (frames, N, 3) arrays: the block itself when every frame is its place."""
        block = self._block
        if block is not None and len(x) <= block[0].shape[0]:

            def place(a: np.ndarray) -> int:
                return a.__array_interface__["data"][0]

            if all(place(xk) == place(block[0][k]) and place(vk) == place(block[1][k]) for k, (xk, vk) in enumerate(zip(x, v, strict=True))):
                return block[0][: len(x)], block[1][: len(v)]
        return np.array(x), np.array(v)

    def fields(self) -> dict[str, Any]:
        """The recorded frames as the `Trajectory`'s fields (its constructor's keywords)."""
        t, x, v, ke, pot, p, ang, contacts, balance, lost, ids, impacts, virial, kinetic = zip(*self.frames, strict=True)
        names = list(dict.fromkeys(name for frame in pot for name in frame))  # a force added mid-run counts from then
        # The world sums the impulse balance over all its steps; a frame gets what its steps
        # added (the first frame none).
        balance = np.diff(np.array(balance), axis=0, prepend=np.array(balance)[:1])
        about = dict(self.about)
        if len(self.sets) == 1:
            (positions, velocities), alive = self._stacked(x, v), None
        else:
            positions, velocities, alive = self._by_id(x, v, ids, about)
        every = about["ids"] if alive is not None else None
        turning = {name: _stacked_by_id([f.get(name) for f in self.turning], ids, every) for name in ("angular_velocities", "orientations")}
        inertia = _stacked_by_id([f.get("inertia") for f in self.turning], ids, every)
        if inertia is not None:  # each particle's, from the first frame it is alive in
            inertia = inertia[np.argmax(np.isfinite(inertia[..., 0]), axis=0), np.arange(inertia.shape[1]), 0]
        return dict(
            t=np.array(t),
            positions=positions,
            velocities=velocities,
            kinetic=np.array(ke),
            potential={name: np.array([f.get(name, 0.0) for f in pot]) for name in names},
            momentum=np.array(p),
            angular_momentum=np.array(ang),
            contacts=np.array(contacts, dtype=np.int64),
            impulse_balance=balance,
            collision_energy_lost=np.array(lost),
            impacts=np.diff(np.array(impacts, dtype=np.int64), prepend=impacts[0]),
            pressure=_pressure(np.array(t), np.array(virial), np.array(kinetic), about),
            alive=alive,
            contact_record=ContactRecord.from_frames(self.touching) if self.contacts else None,
            **_stacked_walls(self.walls),
            **turning,
            inertia=inertia,
            **about,
        )

    def _by_id(self, x, v, ids, about) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Frames of changing particle sets as columns by id (the union of all ids, sorted)."""
        every = np.unique(np.concatenate([s[0] for s in self.sets]))
        frames, n = len(x), every.size
        positions, velocities = np.full((frames, n, 3), np.nan), np.full((frames, n, 3), np.nan)
        alive = np.zeros((frames, n), dtype=bool)
        for k, (xk, vk, ik) in enumerate(zip(x, v, ids, strict=True)):
            col = np.searchsorted(every, ik)
            positions[k, col], velocities[k, col], alive[k, col] = xk, vk, True
        masses, radii = np.full(n, np.nan), np.full(n, np.nan)
        species = np.full(n, "X", dtype=object) if any(s[3] is not None for s in self.sets) else None
        colors = np.full((n, 3), np.nan) if any(s[4] is not None for s in self.sets) else None
        groups = np.zeros(n, dtype=np.int64)
        # each particle's group as the last set it is in has it (a particle regrouped while
        # others were born or died; a regrouping alone makes no new set)
        for ik, m, r, sp, c, g in self.sets:
            col = np.searchsorted(every, ik)
            masses[col], radii[col], groups[col] = m, r, g
            if species is not None and sp is not None:
                species[col] = sp
            if colors is not None and c is not None:
                colors[col] = c
        about.update(
            ids=every,
            masses=masses,
            radii=radii,
            species=None if species is None else species.astype(str),
            colors=colors,
            groups=groups,
        )
        return positions, velocities, alive


def _turning(world: Any) -> dict[str, np.ndarray]:
    """Copies of the world's angular velocities, moments of inertia (n, 1) and orientations
    now, those it has: none without spin; orientations where the engine integrates them
    (`World.orientations`)."""
    if not world.spin:
        return {}
    out = {"angular_velocities": world.angular_velocities.copy(), "inertia": np.asarray(world._state().engine.inertia, dtype=np.float64).reshape(-1, 1)}
    if hasattr(type(world), "orientations"):
        out["orientations"] = np.array(world.orientations, dtype=np.float64)
    return out


def _stacked_walls(walls: list[dict[str, np.ndarray]] | None) -> dict[str, np.ndarray | None]:
    """The recorder's collider books per frame (`Recorder.walls`) as the trajectory's
    `COLLIDER_RECORD` arrays (F, K, 3), K the most colliders of any frame (a collider added
    later took nothing before: zeros); all `None` without colliders or books."""
    k = max((len(f["momentum"]) for f in walls), default=0) if walls is not None else 0
    if k == 0:
        return dict.fromkeys(COLLIDER_RECORD)
    out = {}
    for name, key in COLLIDER_RECORD.items():
        a = np.zeros((len(walls), k, 3))
        for i, f in enumerate(walls):
            a[i, : len(f[key])] = f[key]
        out[name] = a
    return out


def _stacked_by_id(rows: list[np.ndarray | None], ids: tuple, every: np.ndarray | None) -> np.ndarray | None:
    """Per-frame rows (n_k, w) as (F, N, w): stacked where the particles never change
    (`every` None), else one column per id of `every`, NaN where a particle is not alive;
    `None` unless every frame has them."""
    if not rows or any(r is None for r in rows):
        return None
    if every is None:
        return np.array(rows)
    out = np.full((len(rows), every.size, rows[0].shape[1]), np.nan)
    for k, (r, ik) in enumerate(zip(rows, ids, strict=True)):
        out[k, np.searchsorted(every, ik)] = r
    return out
