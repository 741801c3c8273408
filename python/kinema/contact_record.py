"""The contacts of every recorded frame (`World.run(record_contacts=True)`,
`Trajectory.contact_record`): what `World.contacts()` gives at each frame, its particles
named by id, all frames' contacts in one table with each frame's place in it.

`FIELDS` is the one home of what each column means and its unit: the recorder, the H5MD
writer and reader, the LAMMPS `dump local` and VTK line exports all read it. This module
imports nothing of kinema's, so that the trajectory and the file formats may both use it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class ContactField:
    """One column of the contact record: `unit` its SI unit as H5MD's units module writes
    it (`None`: a plain number), `kind` "int", "real" or "bool", `width` 0 for one
    value per contact, 3 for a vector, `meaning` in words."""

    unit: str | None
    kind: str
    width: int
    meaning: str


#: The columns a contact record may hold, in the order files write them. `i`, `j` and
#: `collider` are always there; the others where the world's `contacts()` gives them (the
#: impulse model gives `impulse_n` and `impulse_t` too, the force models do not).
FIELDS: dict[str, ContactField] = {
    "i": ContactField(None, "int", 0, "the particle's id"),
    "j": ContactField(None, "int", 0, "the other particle's id, -1 against a collider"),
    "collider": ContactField(None, "int", 0, "the collider's index in the trajectory's colliders, -1 between particles"),
    "point": ContactField("m", "real", 3, "the contact point"),
    "normal": ContactField(None, "real", 3, "the unit normal from the partner (particle or collider) towards i"),
    "overlap": ContactField("m", "real", 0, "the overlap (penetration) of the two surfaces"),
    "u_n": ContactField("m s-1", "real", 0, "the normal velocity (v_i - v_j) . normal, < 0 approaching"),
    "force_n": ContactField("N", "real", 3, "the normal force on i"),
    "force_t": ContactField("N", "real", 3, "the tangential (friction) force on i"),
    "sliding": ContactField(None, "bool", 0, "whether the contact slides (friction at its Coulomb limit)"),
    "impulse_n": ContactField("kg m s-1", "real", 3, "the normal impulse on i in the step (impulse model)"),
    "impulse_t": ContactField("kg m s-1", "real", 3, "the tangential impulse on i in the step (impulse model)"),
}
_DTYPES = {"int": np.int64, "real": np.float64, "bool": np.bool_}


def field_dtype(name: str) -> Any:
    """The dtype column `name` is kept in (float64 for a column `FIELDS` does not know)."""
    f = FIELDS.get(name)
    return np.float64 if f is None else _DTYPES[f.kind]


@dataclass
class ContactRecord:
    """The contacts of each frame of a trajectory, as one table: frame k's contacts are the
    rows `offsets[k]` to `offsets[k + 1]` of every column of `values` (`offsets` (F + 1,)
    int64, from 0, never decreasing). `values` {name: (K, ...)} holds the columns of
    `FIELDS` the world gave, in SI units; `i` and `j` are particle ids (`Trajectory.ids`),
    not indices, so that a record stays right when particles are born and die.

    `frame(k)` gives frame k's contacts as `World.contacts()` gives them (ids for
    indices), `counts` the number of contacts at each frame."""

    offsets: np.ndarray
    values: dict[str, np.ndarray]

    def __post_init__(self) -> None:
        self.offsets = np.asarray(self.offsets, dtype=np.int64).reshape(-1)
        problem = offsets_problem(self.offsets)
        if problem is not None:
            raise ValueError(f"contact record: offsets {problem}")
        total = int(self.offsets[-1])
        values = {}
        order = [n for n in FIELDS if n in self.values] + [n for n in self.values if n not in FIELDS]  # FIELDS' order, whatever a file's
        for name, a in ((n, self.values[n]) for n in order):
            a = np.asarray(a, dtype=field_dtype(name))
            if a.ndim == 0 or a.shape[0] != total:
                raise ValueError(f"contact record: column {name!r} has shape {a.shape}; it must have {total} rows, one per contact (offsets[-1])")
            values[name] = a
        for name in ("i", "j", "collider"):
            if name not in values:
                raise ValueError(f"contact record: column {name!r} is missing; every record has i, j and collider")
        self.values = values

    @property
    def n_frames(self) -> int:
        return self.offsets.size - 1

    @property
    def counts(self) -> np.ndarray:
        """The number of contacts at each frame (F,)."""
        return np.diff(self.offsets)

    def frame(self, k: int) -> dict[str, np.ndarray]:
        """Frame `k`'s contacts: each column's rows of that frame (views)."""
        lo, hi = int(self.offsets[k]), int(self.offsets[k + 1])
        return {name: a[lo:hi] for name, a in self.values.items()}

    def __getitem__(self, name: str) -> np.ndarray:
        return self.values[name]

    def __repr__(self) -> str:
        return f"ContactRecord(frames={self.n_frames}, contacts={int(self.offsets[-1])}, columns={', '.join(self.values)})"

    @classmethod
    def from_frames(cls, frames: list[dict[str, np.ndarray]]) -> ContactRecord:
        """The record of the frames' contacts, each a dict of columns (a column a frame
        lacks that another has is NaN there, or -1 and False for integers and flags)."""
        counts = [len(f["i"]) for f in frames]
        offsets = np.concatenate([[0], np.cumsum(counts, dtype=np.int64)])
        names = list(dict.fromkeys(name for f in frames for name in f))
        names = [n for n in FIELDS if n in names] + [n for n in names if n not in FIELDS]
        values = {}
        for name in names:
            shapes = {np.shape(f[name])[1:] for f in frames if name in f}
            tail = max(shapes, key=len)
            dtype = field_dtype(name)
            missing = {np.int64: -1, np.bool_: False}.get(dtype, np.nan)
            parts = [
                np.asarray(f[name], dtype=dtype).reshape(-1, *tail) if name in f else np.full((k, *tail), missing, dtype=dtype)
                for f, k in zip(frames, counts, strict=True)
            ]
            values[name] = np.concatenate(parts) if parts else np.zeros((0, *tail), dtype=dtype)
        return cls(offsets, values)


def offsets_problem(offsets: np.ndarray) -> str | None:
    """What is wrong with a record's `offsets` (F + 1,), or `None`: they start at 0 and
    never decrease."""
    if offsets.ndim != 1 or offsets.size < 1:
        return f"has shape {offsets.shape}; it must be (frames + 1,)"
    if offsets[0] != 0:
        return f"start at {int(offsets[0])}; they must start at 0"
    if offsets.size > 1 and (np.diff(offsets) < 0).any():
        k = int(np.argmax(np.diff(offsets) < 0))
        return f"decrease at frame {k} ({int(offsets[k])} then {int(offsets[k + 1])}); frame k's contacts are rows offsets[k] to offsets[k + 1]"
    return None


def as_ids(contacts: dict[str, np.ndarray], ids: np.ndarray) -> dict[str, np.ndarray]:
    """`World.contacts()`'s columns with `i` and `j` (indices into the world's arrays now)
    as the particles' `ids` (-1 stays -1: a collider); copies."""
    out = {name: np.array(a) for name, a in contacts.items()}
    ids = np.asarray(ids, dtype=np.int64)
    i, j = np.asarray(out["i"], dtype=np.int64), np.asarray(out["j"], dtype=np.int64)
    out["i"] = ids[i]
    out["j"] = np.where(j >= 0, ids[np.maximum(j, 0)] if ids.size else -1, -1)
    return out
