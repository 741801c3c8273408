"""HOOMD-blue's GSD trajectory format (OVITO, HOOMD-blue, freud, MDAnalysis), written with the
`gsd` package."""

from __future__ import annotations

import contextlib
import errno
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ._cell import frame_steps, live_springs, particle_colors, particle_types, spring_columns, trajectory_cell
from ._files import FileWriteError, Frames, close_descriptors_on, copy_into, private_folder, write_error
from ._quaternions import hoomd_angmom


# Over 100 lines (issue 50) by its docstring (62 lines): the GSD layout written, which
# HOOMD, OVITO and kinema's reader rely on; the code is 51 lines, each frame made by `_gsd_frame`.
def write_gsd(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    """Write `fr` to one GSD file (HOOMD schema) at `path`; returns `[path]`.

    One GSD frame per trajectory frame: `configuration/step` (round(t/dt) when `dt` is
    known, else the frame index), `configuration/dimensions` (2 or 3) and
    `configuration/box` [Lx, Ly, Lz, 0, 0, 0] (Lz = 0 in 2D, as HOOMD does); `particles/N`,
    `types` (`["A"]`, or the trajectory's `species` names), `typeid`, `position` (m),
    `velocity` (m/s), `mass` (kg) and `diameter` (2 × radius, m) where the trajectory
    has masses and radii.

    The box: GSD's box is periodic on every axis, as HOOMD's always is. Along a periodic axis
    it is the world's periodic cell. Along another axis the cell (`_cell.trajectory_cell`:
    the walls of the world's `Box` where all particles stay between them, else the extent
    of all frames' particles with a margin) is doubled in length about its centre, room
    beyond the walls: two particles in the cell are at most its length L apart along that
    axis, so their image across the padded box is at least L away, and no neighbour search
    whose cut-off is below half the box's length (the largest freud accepts) finds a pair
    across a wall. `log/kinema/periodic` (3,) uint8 says which axes are periodic (1) and
    which are padded (0): the cell is the box with a padded axis halved.

    Precision: GSD's HOOMD schema stores particle data as float32, so positions (relative to
    the box centre), velocities, masses and diameters keep about 7 significant digits (a
    relative error up to 6e-8). GSD's box is centred at the origin: the writer subtracts the
    box centre, and stores it in float64 as `log/kinema/origin` (3,), m; a position in
    kinema's coordinates is `position + origin`. `log/kinema/time` (1,) is the frame
    time t in s (float64, exact) and `log/particles/kinema/id` (N,) the particle ids.
    OVITO shows the log values as the global attributes `kinema/origin`, `kinema/time`
    and `kinema/periodic` and the ids as the particle property `kinema_id`.

    Springs (`traj.springs`): each frame's `bonds/N`, `bonds/types` (`["spring"]`),
    `bonds/typeid` (0) and `bonds/group` (the two ends as indices into the frame's
    particles) hold the springs whose two ends are alive then; OVITO reads them as its Bonds.
    Colours (`traj.colors`): `log/particles/Color` (N, 3) float32, r g b in [0, 1] (the
    renderer's `NO_OWN_COLOR` for a particle without its own), which HOOMD's schema has no
    place for and OVITO reads as its Color property. Collision groups (`traj.groups`):
    `log/particles/collision_group` (N,) int32, each particle's group 0..31 (HOOMD's schema
    has no free integer per particle: `typeid` is the species, `body` a rigid body's), which
    `gsd.hoomd` reads as `frame.log["particles/collision_group"]`.

    Births and deaths (`alive`): a frame holds the particles alive at it only, GSD's
    `particles/N` varying from frame to frame as HOOMD's does; `typeid`, `mass`,
    `diameter`, the colours, the groups and `log/particles/kinema/id` are those of the live
    particles, in the order of their ids, so a particle is followed across frames by its id
    (a frame may hold none).

    Spin (a trajectory with angular velocities): `particles/orientation` (N, 4) the unit
    quaternion (w, x, y, z) that turns the particle's body frame into the world's, HOOMD's
    convention (identity where the trajectory has no orientations), `particles/moment_inertia`
    (N, 3) = (I, I, I) kg·m², a sphere's, and `particles/angmom` (N, 4) HOOMD's quaternion
    conjugate momentum of the angular velocity ω, p = 2 q ⊗ (0, I ω_body) with ω_body =
    q* ⊗ ω ⊗ q, which for a sphere is 2 I (0, ω) ⊗ q (derived in
    `_quaternions.hoomd_angmom`), so that HOOMD goes on with the same spins and
    `log/particles/kinema/omega` (N, 3) float64, ω itself in rad/s, exactly. The moments of
    inertia are the trajectory's `inertia`, else a solid sphere's 2/5 m r² (a disc's 1/2 m
    r² in 2D), what `World(spin=True)` gives by default.

    `on_frame(i)` is called after frame `i` is written. Needs the `gsd` package.

    gsd builds the file in a private folder of the system's temporary folder
    (`tempfile.gettempdir()`), and Python copies it to a temporary name beside `path`,
    renamed over `path` when complete: a failure of the system (a full disk, a file-size
    limit, there or at `path`) is one `FileWriteError` naming `path`, with `path` left
    as it was and no file or descriptor left behind."""
    try:
        import gsd.hoomd
    except ImportError:
        raise ImportError("writing GSD needs the gsd package: pip install gsd") from None
    lo, hi, periodic, _ = trajectory_cell(traj, fr)
    origin = 0.5 * (lo + hi)
    lengths = np.where(periodic, 1.0, 2.0) * (hi - lo)  # room beyond the walls: see above
    if fr.dim == 2:  # HOOMD's 2D box: Lz = 0, the particles at z = 0
        origin[2], lengths[2] = 0.0, 0.0
    types, typeid = particle_types(traj, fr.n_particles)
    colors = particle_colors(traj, fr.n_particles)
    # what every frame takes its live particles' rows from
    columns = {
        "box": [*(float(v) for v in lengths), 0.0, 0.0, 0.0],
        "origin": origin,
        "periodic": periodic,
        "types": types,
        "typeid": typeid.astype(np.uint32),
        "masses": None if fr.masses is None else fr.masses.astype(np.float32),
        "diameters": None if fr.radii is None else (2.0 * fr.radii).astype(np.float32),
        "colors": None if colors is None else colors.astype(np.float32),
        "groups": None if fr.groups is None else fr.groups.astype(np.int32),
        "springs": spring_columns(traj, fr),
        "ids": fr.ids.astype(np.int64),
        "inertia": _inertia(fr),
        "steps": frame_steps(fr),
    }
    # gsd writes its file in a private folder of the system's temporary folder, never on the
    # target's file system, and the finished bytes are copied to the target by Python: gsd
    # 5.0.1 cannot be trusted with a failed write (its gsd_close returns before close(fd) when
    # its last flush fails, leaving the file open, and a failure part way can surface as
    # RuntimeError("Invalid gsd argument: ...")). A full disk or a file-size limit at the
    # target is then one FileWriteError from Python's own write; one met by gsd in the
    # temporary folder is a FileWriteError naming the target too, its descriptor closed.
    with private_folder(path) as scratch:
        built = scratch / "frames.gsd"
        try:
            f = _gsd_call(path, scratch, gsd.hoomd.open, str(built), mode="w")
            try:
                for i in range(fr.n_frames):
                    _gsd_call(path, scratch, f.append, _gsd_frame(gsd.hoomd.Frame(), fr, i, columns))
                    on_frame(i)
            except BaseException:
                with contextlib.suppress(Exception):
                    f.close()
                raise
            _gsd_call(path, scratch, f.close)
        finally:
            close_descriptors_on(built)  # what gsd left open when its close failed
        copy_into(built, path)
    return [path]


def _inertia(fr: Frames) -> np.ndarray | None:
    """Each particle's moment of inertia (N,) kg·m² where the trajectory has spin: its own,
    else `World(spin=True)`'s default, a solid sphere's 2/5 m r² (a disc's 1/2 m r² in 2D);
    `None` without spin."""
    if fr.angular_velocities is None:
        return None
    inertia = fr.inertia
    if inertia is None:  # World(spin=True)'s default: a solid sphere's, a disc's in 2D
        inertia = (
            (0.4 if fr.dim == 3 else 0.5)
            * (fr.masses if fr.masses is not None else np.ones(fr.n_particles))
            * (fr.radii if fr.radii is not None else np.zeros(fr.n_particles)) ** 2
        )
    return np.asarray(inertia, dtype=np.float64)


def _gsd_frame(frame: Any, fr: Frames, i: int, c: dict[str, Any]) -> Any:
    """The GSD `frame` (a `gsd.hoomd.Frame`) of trajectory frame `i`, its live particles'
    rows of the `columns` `write_gsd` made: the configuration, the particles, their spins,
    the springs as bonds and kinema's log (see `write_gsd`)."""
    frame.configuration.step = int(c["steps"][i])
    frame.configuration.dimensions = fr.dim
    frame.configuration.box = c["box"]
    live = fr.live(i)
    p = frame.particles
    p.N = live.size
    p.types = c["types"]
    p.typeid = c["typeid"][live]
    p.position = (fr.positions[i][live] - c["origin"]).astype(np.float32)
    if fr.has_velocities:  # (unknown velocities: none, not NaN)
        p.velocity = fr.velocities[i][live].astype(np.float32)
    if c["masses"] is not None:
        p.mass = c["masses"][live]
    if c["diameters"] is not None:
        p.diameter = c["diameters"][live]
    inertia = c["inertia"]
    if inertia is not None:
        q = fr.orientations[i][live] if fr.orientations is not None else np.tile([1.0, 0.0, 0.0, 0.0], (live.size, 1))
        omega = fr.angular_velocities[i][live]
        p.orientation = q.astype(np.float32)
        p.moment_inertia = np.repeat(inertia[live][:, None], 3, axis=1).astype(np.float32)
        p.angmom = hoomd_angmom(q, omega, inertia[live]).astype(np.float32)
        frame.log["particles/kinema/omega"] = np.ascontiguousarray(omega, dtype=np.float64)
    if c["springs"].size:
        # A frame whose springs are all gone still writes bonds/N = 0: gsd
        # gives a frame without the chunk the value of frame 0.
        group = live_springs(c["springs"], fr, i)
        b = frame.bonds
        b.N = len(group)
        b.types = ["spring"]
        b.typeid = np.zeros(len(group), dtype=np.uint32)
        b.group = group.astype(np.uint32).reshape(-1, 2)
    frame.log["kinema/origin"] = c["origin"].copy()
    frame.log["kinema/time"] = np.array([fr.t[i]], dtype=np.float64)
    frame.log["kinema/periodic"] = c["periodic"].astype(np.uint8)
    if not fr.has_velocities:  # (GSD's missing velocity is 0: kinema's files say "unknown")
        frame.log["kinema/velocities_unknown"] = np.ones(1, dtype=np.uint8)
    frame.log["particles/kinema/id"] = c["ids"][live]
    if c["colors"] is not None:
        frame.log["particles/Color"] = c["colors"][live]
    if c["groups"] is not None:
        frame.log["particles/collision_group"] = c["groups"][live]
    return frame


def _gsd_call(path: Path, scratch: Path, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """`fn(*args, **kwargs)`, a gsd call on the file it builds for `path` in the folder
    `scratch`: its failure (gsd's OSError of the system's errno, or its RuntimeError of a
    state its own failure left) is a `FileWriteError` naming `path`, its reason saying
    where it happened (the system's temporary folder, which may be the full one)."""
    where = f"in the temporary folder {scratch.parent}, where gsd builds the file"
    try:
        return fn(*args, **kwargs)
    except FileWriteError:
        raise
    except OSError as e:
        raise write_error(path, e.errno or errno.EIO, f"{e.strerror or type(e).__name__} ({where})") from None
    except RuntimeError as e:
        what = str(e).split(":", 1)[0].strip() or type(e).__name__  # (the rest names gsd's temporary file)
        raise FileWriteError(errno.EIO, f"gsd failed: {what} ({where})", str(path)) from None
