"""One moment of a granular system, as the analysis reads it: the particles' state and the
contact table, taken from a World or from a frame of a Trajectory."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .contacts import geometric_contacts


@dataclass(frozen=True)
class Snapshot:
    """The particles at one time and their contacts (copies, in the World's order).

    `positions` (N, 3) m, `velocities` (N, 3) m/s, `masses` (N,) kg, `radii` (N,) m,
    `ids` (N,) the particles' ids, `dim` (2 or 3), `period` (3,) m the periodic cell's
    length along each periodic axis (0 along the others), `time` s, and `contacts` the
    contact table (a dict of arrays indexing these rows: `kinema.analysis.contacts`), or
    None where none is known."""

    positions: np.ndarray
    velocities: np.ndarray
    masses: np.ndarray
    radii: np.ndarray
    ids: np.ndarray
    dim: int
    period: np.ndarray
    time: float
    contacts: dict[str, np.ndarray] | None = None

    def __len__(self) -> int:
        return len(self.positions)

    @classmethod
    def of_world(cls, world: Any) -> Snapshot:
        """The world now, with ``world.contacts()`` (its forces where the model gives them)."""
        about = world._trajectory_info()
        return cls(
            positions=np.array(world.positions, dtype=float),
            velocities=np.array(world.velocities, dtype=float),
            masses=np.array(about["masses"], dtype=float),
            radii=np.array(about["radii"], dtype=float),
            ids=np.array(about["ids"]),
            dim=int(about["dim"]),
            period=_period(about.get("periodic"), about.get("box_edges")),
            time=float(world.time),
            contacts={k: np.array(v) for k, v in world.contacts().items()},
        )

    @classmethod
    def of_frame(cls, trajectory: Any, frame: int, contacts: dict[str, Any] | None = None) -> Snapshot:
        """Frame ``frame`` of a Trajectory (recorded or loaded), the particles alive at it
        only (rows in the order of their ids). The contacts: ``contacts`` when given (a table
        indexing these rows); else the trajectory's own record of that frame where it has one
        (``World.run(record_contacts=True)``, ``kinema run --record-contacts``: its ids made
        these rows); else none (:meth:`with_geometric_contacts` finds them from geometry)."""
        frame = range(len(trajectory.t))[frame]  # (-1: the last; an IndexError past the ends)
        alive = np.isfinite(trajectory.positions[frame]).all(axis=1)
        if getattr(trajectory, "alive", None) is not None:
            alive &= np.asarray(trajectory.alive[frame], dtype=bool)
        if trajectory.masses is None or trajectory.radii is None:
            raise ValueError("trajectory.masses or trajectory.radii is None: a snapshot needs both (a file that records them, or World.run's trajectory)")
        ids = trajectory.ids if trajectory.ids is not None else np.arange(trajectory.positions.shape[1])
        record = getattr(trajectory, "contact_record", None)
        if contacts is None and record is not None:
            contacts = _rows_of_ids(record.frame(frame), np.asarray(ids)[alive], frame)
        return cls(
            positions=np.array(trajectory.positions[frame][alive], dtype=float),
            velocities=np.array(trajectory.velocities[frame][alive], dtype=float),
            masses=np.array(trajectory.masses, dtype=float)[alive],
            radii=np.array(trajectory.radii, dtype=float)[alive],
            ids=np.asarray(ids)[alive],
            dim=int(trajectory.dim or 3),
            period=_period(trajectory.periodic, trajectory.box_edges),
            time=float(trajectory.t[frame]),
            contacts=None if contacts is None else dict(contacts),
        )

    def with_geometric_contacts(self, gap: float = 0.0) -> Snapshot:
        """This snapshot with the contact table of its touching pairs, from geometry alone
        (:func:`kinema.analysis.geometric_contacts`: no forces)."""
        table = geometric_contacts(self.positions, self.radii, gap=gap, period=self.period)
        return Snapshot(**{**self.__dict__, "contacts": table})


def _period(periodic: Any, edges: Any) -> np.ndarray:
    """(3,) m: the cell's length along the periodic axes, 0 along the others."""
    if periodic is None or edges is None:
        return np.zeros(3)
    return np.where(np.asarray(periodic, dtype=bool), np.asarray(edges, dtype=float), 0.0)


def _rows_of_ids(contacts: dict[str, np.ndarray], ids: np.ndarray, frame: int) -> dict[str, np.ndarray]:
    """A recorded frame's contacts (``i``, ``j`` particle ids, −1 a collider) with ``i`` and
    ``j`` made rows of ``ids`` (the particles alive at the frame, in their rows); copies."""
    order = np.argsort(ids, kind="stable")
    known = np.asarray(ids, dtype=np.int64)[order]
    out = {name: np.array(a) for name, a in contacts.items()}
    for name in ("i", "j"):
        named = np.asarray(out[name], dtype=np.int64)
        particle = named >= 0 if name == "j" else np.ones(len(named), dtype=bool)
        at = np.minimum(np.searchsorted(known, named[particle]), max(len(known) - 1, 0))
        found = known[at] == named[particle] if len(known) else np.zeros(len(at), dtype=bool)
        if not found.all():
            missing = int(named[particle][np.argmin(found)])
            raise ValueError(f"contact_record: frame {frame} has a contact of the particle of id {missing}, which is not alive at that frame")
        named = named.copy()
        named[particle] = order[at]
        out[name] = named
    return out
