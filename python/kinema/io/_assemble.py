"""The frames a reader of another program's format found (`RawFrame`: each frame's rows, in
the file's units), checked and made one `LoadedTrajectory` in SI units (`assemble`): one
column per particle id, NaN and `alive` False where a particle is not in a frame, the
per-particle values where each particle first appears, the box of the first frame as the
periodic cell."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._checks import available_memory, first_non_finite, gib, number
from ._h5md_checks import edges_problem, fail, group_problem, increase_problem, mass_problem, radius_problem, species_problem
from .h5md_reader import LoadedTrajectory
from .units import Scales


@dataclass
class Box:
    """A frame's orthogonal box, in the file's units: `lo` and `hi` (3,), `periodic` (3,)
    bools."""

    lo: np.ndarray
    hi: np.ndarray
    periodic: np.ndarray


@dataclass
class RawFrame:
    """One frame as a file holds it, in the file's units: `positions` (n, 3) and, where the file
    has them, `ids` (n,) ints, `velocities` (n, 3), `masses` and `radii` (n,),
    `species` (n,) names, `colors` (n, 3) r g b in [0, 1], `angular_velocities` (n, 3)
    (in 1 / the file's time unit) and `orientations` (n, 4) unit quaternions (w, x, y,
    z), `inertia` (n,) moments of inertia, `groups` (n,) collision groups (ints), the frame's `time` and `step` and its `box`. `where` names the frame in messages
    (`"frame 3"`, `"frame 3 (line 120)"`)."""

    positions: np.ndarray
    where: str
    ids: np.ndarray | None = None
    velocities: np.ndarray | None = None
    masses: np.ndarray | None = None
    radii: np.ndarray | None = None
    species: np.ndarray | None = None
    colors: np.ndarray | None = None
    angular_velocities: np.ndarray | None = None
    orientations: np.ndarray | None = None
    inertia: np.ndarray | None = None
    groups: np.ndarray | None = None
    time: float | None = None
    step: int | None = None
    box: Box | None = None


def _check_rows(path: Path, fr: RawFrame) -> None:
    """The values of one frame: finite positions and velocities, masses > 0, radii >= 0,
    printable species names, ids once each."""
    for word, a in (
        ("positions", fr.positions),
        ("velocities", fr.velocities),
        ("angular velocities", fr.angular_velocities),
        ("orientations", fr.orientations),
    ):
        at = None if a is None else first_non_finite(a)
        if at is not None:
            raise fail(path, f"{fr.where}: {word} have a non-finite value ({number(a[at])}) at row {at[0]}")
    if fr.masses is not None and (problem := mass_problem(fr.masses)) is not None:
        raise fail(path, f"{fr.where}: {problem.replace('mass[', 'the mass of row [')}")
    if fr.radii is not None and (problem := radius_problem(fr.radii)) is not None:
        raise fail(path, f"{fr.where}: {problem.replace('radius[', 'the radius of row [')}")
    if fr.species is not None and (problem := species_problem(list(fr.species))) is not None:
        raise fail(path, f"{fr.where}: {problem}")
    if fr.groups is not None and (problem := group_problem(fr.groups)) is not None:
        raise fail(path, f"{fr.where}: {problem.replace('group[', 'the collision group of row [')}")
    if fr.colors is not None and not ((fr.colors >= 0) & (fr.colors <= 1)).all():
        r = int(np.argmax(~((fr.colors >= 0) & (fr.colors <= 1)).all(axis=1)))
        raise fail(path, f"{fr.where}: the colour of row {r} is {fr.colors[r].tolist()}; r g b must be in [0, 1]")
    if fr.ids is not None:
        uniq, counts = np.unique(fr.ids, return_counts=True)
        if (counts > 1).any():
            raise fail(path, f"{fr.where}: id {int(uniq[np.argmax(counts > 1)])} appears twice (an id names one particle)")


def assemble(
    path: Path,
    frames: list[RawFrame],
    scales: Scales,
    dim: int = 3,
    creator: str | None = None,
    author: str | None = None,
    group: str = "all",
    springs: np.ndarray | None = None,
) -> LoadedTrajectory:
    """The trajectory of `frames`, converted to SI by `scales`.

    Particles are followed by their ids where every frame has them (one column per id that
    appears, ascending; `alive` False and NaN positions and velocities where a particle is
    not in a frame); without ids every frame must hold the same number of rows, the particles
    in the same order. Velocities are `None` when no frame has them (NaN in a frame without
    them when others have them), and so are angular velocities (converted by the file's
    time unit) and orientations; masses, radii, species and collision groups are each particle's where it first
    appears, `None` when no frame has them (so are colours; a particle whose first frame has no
    groups when others do is in group 0). `springs` (S, 2) are the ids
    at the ends of each spring, as the file names them. Times are the frames' own times, or, when the file
    has none, the frame index (0, 1, 2, ... s; `source.step` keeps the file's steps).
    The first frame's box gives `periodic`, `box_edges` and, with a periodic axis, a box
    collider at its faces (±inf on open axes), which keeps the cell's corner where kinema's
    exports and renderer look for it; `box_edges_by_frame` holds every frame's edges.

    Raises `TrajectoryFileError` naming `path` and the frame when a value is not finite, a
    mass not > 0, a radius < 0, an id appears twice in one frame, times do not increase,
    the number of rows changes without ids, some frames have times and others not, or the
    file holds no frame or no particle."""
    if not frames:
        raise fail(path, "holds no frame")
    ids = _particle_ids(path, frames, dim)
    by_id = ids is not None
    c = _columns(path, frames, ids)
    t, steps = _times(path, frames, scales)
    masses, radii, species, inertia, spin = c["masses"], c["radii"], c["species"], c["inertia"], c["spin"]
    out = LoadedTrajectory(
        t=t,
        positions=c["positions"] * scales.length,
        velocities=None if c["velocities"] is None else c["velocities"] * scales.velocity,
        step=steps,
        masses=None if masses is None else masses * scales.mass,
        radii=None if radii is None else radii * scales.length,
        ids=ids,
        species=None if species is None else species.astype(str),
        dim=dim,
        alive=None if c["alive"].all() else c["alive"],
        group=group,
        author=author,
        creator=creator,
        path=path,
        springs=None if springs is None or not len(springs) else np.asarray(springs, dtype=np.int64).reshape(-1, 2),
        colors=c["colors"],
        angular_velocities=None if spin["angular_velocities"] is None else spin["angular_velocities"] / scales.time,
        orientations=spin["orientations"],
        inertia=None if inertia is None else inertia * scales.mass * scales.length**2,
        groups=c["groups"],
    )
    # a particle that has no value of its own where it first appears (another frame's column
    # had one): unknown values are refused, as a file of another program would be
    for word, a in (("masses", out.masses), ("radii", out.radii)):
        if a is not None and np.isnan(a).any():
            raise fail(
                path, f"some particles have {word} and others not (particle id {int(ids[np.argmax(np.isnan(a))]) if by_id else int(np.argmax(np.isnan(a)))})"
            )
    _box(path, frames, scales, dim, out)
    return out


def _particle_ids(path: Path, frames: list[RawFrame], dim: int) -> np.ndarray | None:
    """Each frame's values checked (`_check_rows`; z = 0 in 2D), and the ids the particles are
    followed by: every id that appears, ascending, where every frame has ids; `None` where
    not, when every frame must hold the same number of rows."""
    for fr in frames:
        _check_rows(path, fr)
        if dim == 2 and fr.positions.size and np.any(fr.positions[:, 2] != 0):
            z = fr.positions[np.argmax(fr.positions[:, 2] != 0), 2]
            raise fail(path, f"{fr.where}: a 2D file with z = {number(z)} (a 2D trajectory lies in the xy-plane)")
    by_id = all(fr.ids is not None for fr in frames)
    if by_id:
        ids = np.unique(np.concatenate([fr.ids for fr in frames]).astype(np.int64))
    else:
        n0 = frames[0].positions.shape[0]
        for fr in frames:
            if fr.positions.shape[0] != n0:
                raise fail(
                    path,
                    f"{fr.where} holds {fr.positions.shape[0]} particles but {frames[0].where} {n0}, and the file has no ids to follow them by "
                    "(kinema reads a number of particles that changes only with an id column)",
                )
        ids = None
    return ids


def _columns(path: Path, frames: list[RawFrame], ids: np.ndarray | None) -> dict:
    """The frames' rows as one column per particle (by `ids`, or by row), in the file's units:
    `positions`, `velocities` and the `spin` arrays (F, N, ...), NaN where a particle is not
    in a frame, `alive` (F, N), and the per-particle values where each particle first appears
    (None where no frame has them); refused beyond the memory available."""
    by_id = ids is not None
    n = ids.size if by_id else frames[0].positions.shape[0]
    f = len(frames)
    if n == 0:
        raise fail(path, "holds no particles")
    need = f * n * (3 * 8 * 2 + 1)
    free = available_memory()
    if free is not None and need > free:
        raise fail(path, f"needs {gib(need)} GiB of memory for {f:,} frames of {n:,} particles, more than the {gib(free)} GiB available")
    positions = np.full((f, n, 3), np.nan)
    has_v = any(fr.velocities is not None for fr in frames)
    velocities = np.full((f, n, 3), np.nan) if has_v else None
    spin = {
        name: np.full((f, n, width), np.nan) if any(getattr(fr, name) is not None for fr in frames) else None
        for name, width in (("angular_velocities", 3), ("orientations", 4))
    }
    alive = np.zeros((f, n), dtype=bool)
    masses = np.full(n, np.nan) if any(fr.masses is not None for fr in frames) else None
    radii = np.full(n, np.nan) if any(fr.radii is not None for fr in frames) else None
    species = np.full(n, "X", dtype=object) if any(fr.species is not None for fr in frames) else None
    colors = np.full((n, 3), np.nan) if any(fr.colors is not None for fr in frames) else None
    inertia = np.full(n, np.nan) if any(fr.inertia is not None for fr in frames) else None
    groups = np.zeros(n, dtype=np.int64) if any(fr.groups is not None for fr in frames) else None
    seen = np.zeros(n, dtype=bool)  # the particles whose per-particle values are set
    for k, fr in enumerate(frames):
        col = np.searchsorted(ids, fr.ids) if by_id else np.arange(n)
        positions[k, col] = fr.positions
        if fr.velocities is not None:
            velocities[k, col] = fr.velocities
        for name, whole in spin.items():
            if whole is not None and getattr(fr, name) is not None:
                whole[k, col] = getattr(fr, name)
        alive[k, col] = True
        new = ~seen[col]
        if new.any():
            for whole, rows in ((masses, fr.masses), (radii, fr.radii), (species, fr.species), (colors, fr.colors), (inertia, fr.inertia), (groups, fr.groups)):
                if whole is not None and rows is not None:
                    whole[col[new]] = np.asarray(rows)[new]
            seen[col[new]] = True
    return {
        "positions": positions,
        "velocities": velocities,
        "spin": spin,
        "alive": alive,
        "masses": masses,
        "radii": radii,
        "species": species,
        "colors": colors,
        "inertia": inertia,
        "groups": groups,
    }


def _times(path: Path, frames: list[RawFrame], scales: Scales) -> tuple[np.ndarray, np.ndarray]:
    """The frames' times in s (the frame index where the file has none) and steps (the
    file's, else the frame index); every frame has a time or none has, and they increase."""
    f = len(frames)
    times = [fr.time for fr in frames]
    missing = [k for k, t in enumerate(times) if t is None]
    if missing and len(missing) < f:
        raise fail(path, f"{frames[missing[0]].where} has no time but {frames[times.index(next(t for t in times if t is not None))].where} has one")
    t = np.arange(f, dtype=np.float64) if missing else np.array(times, dtype=np.float64) * scales.time
    problem = increase_problem(t)
    if problem is not None:
        raise fail(path, f"the frames' times {problem}")
    steps = np.array([k if fr.step is None else fr.step for k, fr in enumerate(frames)], dtype=np.int64)
    return t, steps


def _box(path: Path, frames: list[RawFrame], scales: Scales, dim: int, out: LoadedTrajectory) -> None:
    """The frames' boxes, where every frame has one, given to `out`: the first's `periodic`
    and `box_edges`, every frame's `box_edges_by_frame` (checked), and with a periodic axis a
    box collider at the first box's faces (±inf on open axes)."""
    boxes = [fr.box for fr in frames]
    if boxes[0] is not None and all(b is not None for b in boxes):
        lo = np.array([b.lo for b in boxes], dtype=np.float64) * scales.length
        hi = np.array([b.hi for b in boxes], dtype=np.float64) * scales.length
        periodic = np.asarray(boxes[0].periodic, dtype=bool)
        if dim == 2:  # (a 2D run's z is no axis of its world: LAMMPS's 2D boxes are periodic in z)
            periodic = periodic & np.array([True, True, False])
        edges = hi - lo
        problem = edges_problem(edges, periodic, by_frame=True)
        if problem is not None:
            raise fail(path, f"the box {problem}")
        out.periodic = tuple(bool(p) for p in periodic)
        out.box_edges_by_frame = edges
        out.box_edges = edges[0].copy()
        if periodic.any():
            face_lo = np.where(periodic, lo[0], -np.inf)[:dim]
            face_hi = np.where(periodic, hi[0], np.inf)[:dim]
            out.colliders = [{"type": "box", "lo": face_lo.tolist(), "hi": face_hi.tolist()}]
