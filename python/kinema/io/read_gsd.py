"""Reading GSD files (HOOMD-blue's schema, and kinema's own `.gsd`) with the `gsd` package:
`read_gsd` gives a `LoadedTrajectory` in SI units."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ._assemble import Box, RawFrame, assemble
from ._h5md_checks import fail
from ._quaternions import omega_of_angmom
from .h5md_reader import LoadedTrajectory
from .units import SI, UnitWarning, scales

MAGIC = bytes.fromhex("df65df65df65df65")  # the first 8 bytes of every GSD file (0x65DF65DF65DF65DF, little-endian)


def _log(f: Any, k: int, name: str) -> np.ndarray | None:
    """The chunk `log/<name>` of frame `k` (or of frame 0, where GSD keeps a value that does
    not change), `None` where there is none."""
    for frame in (k, 0):
        if f.file.chunk_exists(frame=frame, name=f"log/{name}"):
            return f.file.read_chunk(frame=frame, name=f"log/{name}")
    return None


def _empty_names(f: Any, k: int, name: str) -> bool:
    """Whether the chunk `name` of frame `k` (type names, uint8 rows) is there and 0 bytes wide."""
    for frame in (k, 0):
        if f.file.chunk_exists(frame=frame, name=name):
            a = f.file.read_chunk(frame=frame, name=name)
            return a.ndim < 2 or a.shape[1] == 0
    return False


# The least bytes an item of each GSD group takes in a file that gives it: a particle's
# position (3 float32), an n-body group's particle indices (n uint32). A count beyond the
# file's size over this is not a count the file holds (a damaged `N` chunk): gsd.hoomd would
# fill default arrays of that many rows (a billion: minutes and gigabytes), so it is refused
# before the frame is read.
_ITEM_BYTES = {"particles": 12, "bonds": 8, "angles": 12, "dihedrals": 16, "impropers": 16, "constraints": 8, "pairs": 8}


def _check_counts(f: Any, path: Path, k: int, size: int) -> None:
    """Refuse frame `k` where a group's count (`<group>/N`, of frame `k` or else frame 0, as
    gsd.hoomd reads it) is negative or more than a file of `size` bytes can hold."""
    for group, least in _ITEM_BYTES.items():
        name = f"{group}/N"
        for frame in (k, 0):
            if f.file.chunk_exists(frame=frame, name=name):
                n = np.asarray(f.file.read_chunk(frame=frame, name=name)).reshape(-1)
                if n.size != 1 or n.dtype.kind not in "iu":
                    raise fail(path, f"frame {frame}: {name} holds {n.size} {n.dtype} values; it is one unsigned integer, the number of {group}")
                count = int(n[0])
                if count < 0 or count * least > size:
                    raise fail(
                        path,
                        f"frame {frame}: {name} = {count}, more {group} than a file of {size} bytes can hold ({least} bytes each at least); the file is damaged",
                    )
                break


def _spin(f: Any, k: int, p: Any, own: bool) -> dict[str, np.ndarray]:
    """The spin of frame `k` (particles `p`) where the file has one: `orientations`
    (`particles/orientation`, HOOMD's w x y z), `inertia` (the x moment of
    `particles/moment_inertia`) and `angular_velocities`, in kinema's files
    `log/particles/kinema/omega` (float64, exact), in another's from `particles/angmom` and
    `particles/moment_inertia` (HOOMD's conjugate momentum of a sphere: its x moment of
    inertia; `_quaternions.omega_of_angmom`). Nothing for a file whose frames leave them at
    their defaults (identity, 0), as HOOMD writes a run without rotation."""
    out: dict[str, np.ndarray] = {}
    has = {name: f.file.chunk_exists(frame=k, name=name) or f.file.chunk_exists(frame=0, name=name) for name in ("particles/orientation", "particles/angmom")}
    if not any(has.values()):
        return out
    q = np.asarray(p.orientation, dtype=np.float64).reshape(-1, 4)
    out["orientations"] = q / np.linalg.norm(q, axis=1, keepdims=True)
    out["inertia"] = np.asarray(p.moment_inertia, dtype=np.float64).reshape(-1, 3)[:, 0]
    omega = _log(f, k, "particles/kinema/omega") if own else None
    if omega is not None:
        out["angular_velocities"] = np.asarray(omega, dtype=np.float64).reshape(-1, 3)
    elif has["particles/angmom"]:
        out["angular_velocities"] = omega_of_angmom(out["orientations"], np.asarray(p.angmom, dtype=np.float64).reshape(-1, 4), out["inertia"])
    return out


def _groups(path: Path, chunk: np.ndarray, where: str) -> np.ndarray:
    """The collision groups of a frame (`log/particles/collision_group`, integers)."""
    a = np.asarray(chunk).reshape(-1)
    if a.dtype.kind not in "iu":
        raise fail(path, f"{where}: log/particles/collision_group holds {a.dtype} values; collision groups are integers")
    return a.astype(np.int64)


def read_gsd(path: Path, units: Any = None) -> LoadedTrajectory:
    """Read the GSD file `path` (schema "hoomd") with `gsd.hoomd`.

    Each frame: `particles/position` (+ `log/kinema/origin` in kinema's files, whose GSD box
    is centred at 0), `velocity`, `mass` and `diameter` (radius = diameter / 2) as HOOMD
    reads them, its defaults where a file has none (mass 1, diameter 1, velocity 0, as the
    schema says: gsd leaves out a value equal to its default), the type names
    (`particles/types` by `typeid`) as species, `configuration/step`,
    `configuration/dimensions` and the box [Lx, Ly, Lz] centred at the origin (periodic on
    every axis, as HOOMD's box is; a tilted box is refused). A number of particles that varies
    is read by kinema's ids (`log/particles/kinema/id`); without them it is refused.
    kinema's files also give the periodic axes (`log/kinema/periodic`: along another axis
    the cell is the box halved), the springs (bonds of type "spring", as ids), the
    colours (`log/particles/Color`) and the collision groups
    (`log/particles/collision_group`). Spin: `particles/orientation` as the orientations,
    and the angular velocities from kinema's `log/particles/kinema/omega`, else from
    HOOMD's `particles/angmom` and `moment_inertia` (a sphere's: `_spin`).

    Units: HOOMD is unitless. A file kinema wrote (`log/kinema/time`) is SI and its times are
    `log/kinema/time`; another file's numbers are in the units `units` gives (see
    `kinema.io.units.scales`), or, without them, taken as SI with a `UnitWarning` naming the
    file (its masses as kg). Its frames' times are their index (0, 1, 2, ... s; the steps are
    `source.step`)."""
    try:
        import gsd.hoomd
    except ImportError:
        raise ImportError("reading GSD needs the gsd package: pip install gsd") from None
    try:
        f = gsd.hoomd.open(str(path), mode="r")
    except (RuntimeError, OSError, ValueError) as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise fail(path, f"not a GSD file that can be read ({first})") from None
    with f:
        if f.file.schema != "hoomd":
            raise fail(path, f"a GSD file of schema {f.file.schema!r}; kinema reads HOOMD's schema ('hoomd')")
        count = len(f)
        if count == 0:
            raise fail(path, "holds no frame")
        own = f.file.chunk_exists(frame=0, name="log/kinema/time")
        if own:
            if units is not None and scales(units, "units") != SI:
                raise fail(path, f"kinema wrote this file in SI units (log/kinema/time), which units = {units!r} contradicts")
            unit_scales = SI
        elif units is not None:
            unit_scales = scales(units, "units")
        else:
            warnings.warn(
                f"{path}: a HOOMD GSD file has no units; its numbers are taken as SI (positions in m, velocities in m/s, masses in kg, diameters in m); "
                "give units= to say what they are",
                UnitWarning,
                stacklevel=3,
            )
            unit_scales = SI
        frames = []
        springs: list[tuple[int, int]] = []  # the ids at the ends of kinema's springs (its bonds of type "spring")
        dim = None
        size = path.stat().st_size
        for k in range(count):
            raw, dim = _raw_frame(f, path, k, _frame(f, path, k, size), own, dim, springs)
            frames.append(raw)
        creator = "kinema" if own else (f.file.application or None)
    return assemble(path, frames, unit_scales, dim=dim or 3, creator=creator, springs=list(dict.fromkeys(springs)))


def _frame(f: Any, path: Path, k: int, size: int) -> Any:
    """Frame `k` of the open GSD file `f` (of `size` bytes), its chunks' counts checked
    first (`_check_counts`); a frame gsd cannot read is refused in one line."""
    _check_counts(f, path, k, size)
    try:
        return f[k]
    except IndexError:  # gsd.hoomd cannot view a chunk of strings 0 bytes wide
        chunk = next(
            (
                n
                for n in ("particles/types", "bonds/types", "angles/types", "dihedrals/types", "impropers/types", "pairs/types", "constraints/types")
                if _empty_names(f, k, n)
            ),
            None,
        )
        if chunk is None:
            raise
        raise fail(path, f"frame {k}: {chunk} holds only empty names (a chunk of width 0); GSD type names must be non-empty") from None
    except (RuntimeError, OSError, ValueError) as e:
        raise fail(path, f"frame {k} cannot be read ({str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__})") from None


def _raw_frame(f: Any, path: Path, k: int, frame: Any, own: bool, dim: int | None, springs: list[tuple[int, int]]) -> tuple[RawFrame, int]:
    """The GSD `frame` (the `k`-th of `f`; `own`: a file kinema wrote) as a `RawFrame`, and
    the file's dimension (the first frame's, `dim` once known); the ids at the ends of its
    springs (kinema's bonds of type "spring") added to `springs`."""
    where = f"frame {k}"
    c, p = frame.configuration, frame.particles
    box = np.asarray(c.box, dtype=np.float64)
    if np.any(box[3:] != 0):
        raise fail(path, f"{where}: the box has tilt factors {box[3:].tolist()}; kinema reads boxes along the axes only")
    dim = int(c.dimensions) if dim is None else dim
    origin = _log(f, k, "kinema/origin") if own else None
    origin = np.zeros(3) if origin is None else np.asarray(origin, dtype=np.float64).reshape(3)
    # kinema's files say which axes are periodic; along another its box is the cell
    # doubled about its centre (room beyond the walls, gsd_writer.write_gsd)
    flags = _log(f, k, "kinema/periodic") if own else None
    periodic = np.array([True, True, dim == 3]) if flags is None else np.asarray(flags).reshape(3).astype(bool) & np.array([True, True, dim == 3])
    lengths = np.where(periodic | (flags is None), 1.0, 0.5) * box[:3]
    ids = _log(f, k, "particles/kinema/id") if own else None
    time = _log(f, k, "kinema/time") if own else None
    types = [str(t) for t in p.types]
    typeid = np.asarray(p.typeid, dtype=np.int64)
    if typeid.size and (typeid.min() < 0 or typeid.max() >= len(types)):
        raise fail(path, f"{where}: particles/typeid holds {int(typeid.max())}, but particles/types names {len(types)} types")
    color = _log(f, k, "particles/Color") if own else None
    groups = _log(f, k, "particles/collision_group") if own else None
    spin = _spin(f, k, p, own)
    if ids is not None and frame.bonds.N and list(frame.bonds.types) == ["spring"]:
        ends = np.asarray(ids, dtype=np.int64).reshape(-1)[np.asarray(frame.bonds.group, dtype=np.int64).reshape(-1, 2)]
        springs.extend(map(tuple, ends.tolist()))
    raw = RawFrame(
        positions=np.asarray(p.position, dtype=np.float64).reshape(-1, 3) + origin,
        where=where,
        ids=None if ids is None else np.asarray(ids, dtype=np.int64).reshape(-1),
        velocities=None if own and _log(f, k, "kinema/velocities_unknown") is not None else np.asarray(p.velocity, dtype=np.float64).reshape(-1, 3),
        masses=np.asarray(p.mass, dtype=np.float64).reshape(-1),
        radii=np.asarray(p.diameter, dtype=np.float64).reshape(-1) / 2,
        species=np.array(types, dtype=object)[typeid] if types else None,
        colors=None if color is None else np.asarray(color, dtype=np.float64).reshape(-1, 3),
        groups=None if groups is None else _groups(path, groups, where),
        **spin,
        time=None if time is None else float(np.asarray(time).reshape(-1)[0]),
        step=int(c.step),
        box=Box(origin - lengths / 2, origin + lengths / 2, periodic),
    )
    return raw, dim
