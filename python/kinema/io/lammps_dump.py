"""LAMMPS's text dump format (`dump custom`), for OVITO, ASE, VMD and LAMMPS's own tools."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ._cell import element_names, frame_steps, particle_types, trajectory_cell
from ._files import Frames, atomic_file


def _lammps_ids(fr: Frames) -> np.ndarray:
    """LAMMPS atom ids, which must be positive: id + 1 when the ids are distinct and >= 0,
    otherwise 1..N in row order."""
    ids = fr.ids
    if ids.size and (ids.min() < 0 or np.unique(ids).size != ids.size):
        return np.arange(1, fr.n_particles + 1, dtype=np.int64)
    return ids + 1


def write_lammps(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    """Write `fr` to one LAMMPS text dump file at `path`, the frames one after the other, as
    LAMMPS's `dump custom` writes them; returns `[path]`.

    Each frame: `ITEM: TIMESTEP` (round(t/dt) when `dt` is known, else the frame index),
    `ITEM: NUMBER OF ATOMS`, `ITEM: BOX BOUNDS` with `pp` for a periodic axis (the
    world's periodic cell) and `ff` for the others (the walls of the world's `Box` where
    all particles stay between them, else bounds that enclose all frames' particles with a
    margin; a 2D trajectory's z is `pp` from −margin to +margin, as LAMMPS's 2D boxes are
    periodic in z), then `ITEM: ATOMS id type element x y z vx vy vz radius mass` and a row
    per particle: id + 1 (LAMMPS ids start at 1; 1..N in row order if the ids are not
    distinct and >= 0), type 1 (or 1 + the index of the particle's name in the trajectory's
    sorted `species`), `element` the species name only where every name is a chemical
    symbol or X (ASE reads the column as symbols and refuses other words; OVITO names its
    particle types by it, MDAnalysis reads it as the elements), radius and mass only where
    the trajectory has them. Every value is in SI units (m, m/s, kg).

    No `ITEM: UNITS` or `ITEM: TIME`: MDAnalysis's reader takes the first line of each
    frame as `ITEM: TIMESTEP` and counts a frame as N + 9 lines, and fails on either
    ("invalid literal for int() with base 10: '0.0'"); a frame's time is TIMESTEP × dt.

    Births and deaths (`alive`): each timestep lists the atoms alive at it only (`NUMBER
    OF ATOMS` varies; 0 for a frame with none), each with its own id, so a particle keeps
    its id from frame to frame. The dump has no bonds (the springs) and no colours. Floats
    are written with 17 significant digits: exact for float64 (ASE reads them back bit for
    bit; OVITO 3.17's parser can land 1 or 2 units in the last place off). `on_frame(i)`
    is called after frame `i` is written."""
    lo, hi, periodic, margin = trajectory_cell(traj, fr)
    if fr.dim == 2:  # LAMMPS's 2D boxes are periodic in z
        periodic[2] = True
    bounds = "ITEM: BOX BOUNDS " + " ".join("pp" if p else "ff" for p in periodic) + "\n"
    bounds += "".join(f"{float(a)!r} {float(b)!r}\n" for a, b in zip(lo, hi, strict=True))
    elements = element_names(traj, fr.n_particles)
    columns = "id type" + " element" * (elements is not None) + " x y z vx vy vz" + " radius" * (fr.radii is not None) + " mass" * (fr.masses is not None)
    _, typeid = particle_types(traj, fr.n_particles)
    prefixes = np.array(
        [f"{int(k)} {int(t) + 1} " + (f"{elements[t]} " if elements is not None else "") for k, t in zip(_lammps_ids(fr), typeid, strict=True)], dtype=object
    )
    per_particle = [a[:, None] for a in (fr.radii, fr.masses) if a is not None]
    steps = frame_steps(fr)
    with atomic_file(path) as tmp, open(tmp, "w", encoding="ascii") as f:
        for i in range(fr.n_frames):
            live = fr.live(i)
            table = np.hstack([fr.positions[i][live], fr.velocities[i][live], *(a[live] for a in per_particle)]).tolist()
            rows = "".join(p + " ".join(map(repr, r)) + "\n" for p, r in zip(prefixes[live], table, strict=True))
            f.write(f"ITEM: TIMESTEP\n{int(steps[i])}\nITEM: NUMBER OF ATOMS\n{live.size}\n{bounds}ITEM: ATOMS {columns}\n{rows}")
            on_frame(i)
    return [path]
