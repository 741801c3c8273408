"""HOOMD-blue's GSD trajectory format (OVITO, HOOMD-blue, freud, MDAnalysis), written with the
``gsd`` package."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ._cell import frame_steps, particle_types, trajectory_cell
from ._files import Frames, atomic_file


def write_gsd(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    """Write ``fr`` to one GSD file (HOOMD schema) at ``path``; returns ``[path]``.

    One GSD frame per trajectory frame: ``configuration/step`` (round(t/dt) when ``dt`` is
    known, else the frame index), ``configuration/dimensions`` (2 or 3) and
    ``configuration/box`` [Lx, Ly, Lz, 0, 0, 0] (Lz = 0 in 2D, as HOOMD does); ``particles/N``,
    ``types`` (``["A"]``, or the trajectory's ``species`` names), ``typeid``, ``position`` (m),
    ``velocity`` (m/s), ``mass`` (kg) and ``diameter`` (2 × radius, m) where the trajectory
    has masses and radii. The box: along a periodic axis the world's periodic cell, along
    another the walls of the world's ``Box`` where all particles stay between them, else the
    extent of all frames' particles with a margin (GSD's box itself is periodic on every
    axis).

    Precision: GSD's HOOMD schema stores particle data as float32, so positions (relative to
    the box centre), velocities, masses and diameters keep about 7 significant digits (a
    relative error up to 6e-8). GSD's box is centred at the origin: the writer subtracts the
    box centre, and stores it in float64 as ``log/kinema/origin`` (3,), m; a position in
    kinema's coordinates is ``position + origin``. ``log/kinema/time`` (1,) is the frame
    time t in s (float64, exact) and ``log/particles/kinema/id`` (N,) the particle ids.
    OVITO shows the log values as the global attributes ``kinema/origin`` and
    ``kinema/time`` and the ids as the particle property ``kinema_id``.

    Births and deaths (``alive``): a frame holds the particles alive at it only, GSD's
    ``particles/N`` varying from frame to frame as HOOMD's does; ``typeid``, ``mass``,
    ``diameter`` and ``log/particles/kinema/id`` are those of the live particles, in the
    order of their ids, so a particle is followed across frames by its id (a frame may hold
    none).

    ``on_frame(i)`` is called after frame ``i`` is written. Needs the ``gsd`` package."""
    try:
        import gsd.hoomd
    except ImportError:
        raise ImportError("writing GSD needs the gsd package: pip install gsd") from None
    lo, hi, _, _ = trajectory_cell(traj, fr)
    origin = 0.5 * (lo + hi)
    lengths = hi - lo
    if fr.dim == 2:  # HOOMD's 2D box: Lz = 0, the particles at z = 0
        origin[2], lengths[2] = 0.0, 0.0
    box = [*(float(v) for v in lengths), 0.0, 0.0, 0.0]
    types, typeid = particle_types(traj, fr.n_particles)
    typeid = typeid.astype(np.uint32)
    masses = None if fr.masses is None else fr.masses.astype(np.float32)
    diameters = None if fr.radii is None else (2.0 * fr.radii).astype(np.float32)
    ids = fr.ids.astype(np.int64)
    steps = frame_steps(fr)
    with atomic_file(path) as tmp, gsd.hoomd.open(str(tmp), mode="w") as f:
        for i in range(fr.n_frames):
            frame = gsd.hoomd.Frame()
            frame.configuration.step = int(steps[i])
            frame.configuration.dimensions = fr.dim
            frame.configuration.box = box
            live = fr.live(i)
            p = frame.particles
            p.N = live.size
            p.types = types
            p.typeid = typeid[live]
            p.position = (fr.positions[i][live] - origin).astype(np.float32)
            p.velocity = fr.velocities[i][live].astype(np.float32)
            if masses is not None:
                p.mass = masses[live]
            if diameters is not None:
                p.diameter = diameters[live]
            frame.log["kinema/origin"] = origin.copy()
            frame.log["kinema/time"] = np.array([fr.t[i]], dtype=np.float64)
            frame.log["particles/kinema/id"] = ids[live]
            f.append(frame)
            on_frame(i)
    return [path]
