"""What the exports need to know about a trajectory beyond its frames, computed once for
every format: the cell that holds it (OVITO, ASE, HOOMD and LAMMPS all want a box), the step
number of each frame, the particles' species, their colours and the springs between them."""

from __future__ import annotations

import re
from typing import Any, NamedTuple

import numpy as np

from .. import _checks
from ._files import Frames

_MARGIN = 0.05  # of the particles' largest extent, around them where no periodic cell is known
ELEMENTS = frozenset(
    "H He Li Be B C N O F Ne Na Mg Al Si P S Cl Ar K Ca Sc Ti V Cr Mn Fe Co Ni Cu Zn Ga Ge As Se Br Kr Rb Sr Y Zr "
    "Nb Mo Tc Ru Rh Pd Ag Cd In Sn Sb Te I Xe Cs Ba La Ce Pr Nd Pm Sm Eu Gd Tb Dy Ho Er Tm Yb Lu Hf Ta W Re Os Ir "
    "Pt Au Hg Tl Pb Bi Po At Rn Fr Ra Ac Th Pa U Np Pu Am Cm Bk Cf Es Fm Md No Lr Rf Db Sg Bh Hs Mt Ds Rg Cn Nh Fl "
    "Mc Lv Ts Og".split()
)  # the chemical symbols ASE accepts as an atom's symbol, besides X (its dummy element)


def box_corners(description: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi), (3,) each, m, of a box collider's description (`Trajectory.colliders`):
    ±inf for open faces and along z of a 2D box (2 values each)."""
    lo, hi = np.full(3, -np.inf), np.full(3, np.inf)
    a = np.asarray(description["lo"], dtype=np.float64).reshape(-1)[:3]
    b = np.asarray(description["hi"], dtype=np.float64).reshape(-1)[:3]
    lo[: a.size], hi[: b.size] = a, b
    return lo, hi


def box_collider(traj: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """The corners (`box_corners`) of the trajectory's first box collider (the one a
    world's periodic cell comes from); `None` without one."""
    for c in getattr(traj, "colliders", None) or []:
        if isinstance(c, dict) and c.get("type") == "box":
            return box_corners(c)
    return None


class Cell(NamedTuple):
    """An orthogonal box holding every particle of every frame."""

    lo: np.ndarray  # (3,) m, the lower corner
    hi: np.ndarray  # (3,) m, the upper corner: hi > lo on every axis
    periodic: np.ndarray  # (3,) bools
    margin: float  # m, the room left around the particles along an open axis


def trajectory_cell(traj: Any, fr: Frames) -> Cell:
    """The cell of the whole trajectory, the same for every frame (of the particles alive at
    each frame: births and deaths leave no trace).

    A periodic axis takes the bounds of the trajectory's box collider (the world's periodic
    cell), or, when it records none, its `box_edges` from the lowest coordinate on that
    axis; so does an axis where the box has two walls and all frames' particles lie between
    them. Any other axis takes the bounds of all frames' particles widened on each side by
    `margin`: the largest radius plus 5 % of their largest extent (of 1 m when all sit at
    one point), so the spheres fit with room. In 2D, z is [-margin, margin] and not
    periodic: no edge is ever zero (OVITO's cell analysis and ASE's `get_volume` need a 3D
    box; HOOMD's Lz = 0 is the GSD writer's own). A periodic axis with no edge is a
    `ValueError`."""
    periodic = getattr(traj, "periodic", None)
    periodic = np.zeros(3, dtype=bool) if periodic is None else np.resize(np.asarray(periodic, dtype=bool).reshape(-1), 3)
    edges = getattr(traj, "box_edges", None)
    edges = np.zeros(3) if edges is None else np.resize(np.asarray(edges, dtype=np.float64).reshape(-1), 3)
    box = box_collider(traj)
    x = fr.positions[fr.alive]  # the particles that exist, (K, 3)
    x = x[np.all(np.isfinite(x), axis=1)]
    lo, hi = (x.min(axis=0), x.max(axis=0)) if len(x) else (np.zeros(3), np.zeros(3))
    axes = fr.dim
    r_max = float(np.max(fr.radii)) if fr.radii is not None and fr.radii.size else 0.0
    margin = r_max + _MARGIN * (float(np.max(hi[:axes] - lo[:axes])) or 1.0)
    cell_lo, cell_hi, is_periodic = lo - margin, hi + margin, np.zeros(3, dtype=bool)
    for k in range(axes):
        walls = box is not None and np.isfinite(box[0][k]) and np.isfinite(box[1][k]) and box[1][k] > box[0][k]
        if walls and (periodic[k] or (box[0][k] <= lo[k] and hi[k] <= box[1][k])):
            cell_lo[k], cell_hi[k], is_periodic[k] = box[0][k], box[1][k], bool(periodic[k])
        elif periodic[k]:
            if not (np.isfinite(edges[k]) and edges[k] > 0):
                flags = tuple(bool(p) for p in periodic)
                raise ValueError(f"periodic = {flags} but box_edges[{k}] = {float(edges[k])!r}: a periodic axis needs its cell edge > 0 m")
            cell_lo[k], cell_hi[k], is_periodic[k] = lo[k], lo[k] + edges[k], True
    if axes == 2:
        cell_lo[2], cell_hi[2] = -margin, margin
    return Cell(cell_lo, cell_hi, is_periodic, margin)


def frame_steps(fr: Frames) -> np.ndarray:
    """The step number of each frame: round(t/h) when the steps' length h is known (the
    run's `step` where dt did not divide its frames, else `dt`) and those numbers are >= 0
    and increase; otherwise the frame index."""
    h = fr.step if fr.step is not None else fr.dt
    if h is not None and h > 0 and np.all(np.isfinite(fr.t)):
        steps = np.rint(fr.t / h)
        if fr.n_frames == 0 or (steps[0] >= 0 and np.all(np.diff(steps) > 0) and steps[-1] < 2**62):
            return steps.astype(np.int64)
    return np.arange(fr.n_frames, dtype=np.int64)


def particle_types(traj: Any, n: int) -> tuple[list[str], np.ndarray]:
    """(type names, type index of each particle (N,)): the sorted distinct names of the
    trajectory's `species` (N,) when it has them, else the single type `"A"`."""
    names = getattr(traj, "species", None)
    if names is None:
        return ["A"], np.zeros(n, dtype=np.int64)
    a = np.asarray(names).astype(str)
    if a.shape != (n,):
        raise ValueError(f"species has shape {a.shape}; it must be ({n},), one name per particle")
    unique, index = np.unique(a, return_inverse=True)
    return unique.tolist(), index.astype(np.int64)


def spring_columns(traj: Any, fr: Frames) -> np.ndarray:
    """(S, 2) int64: the columns (the particles, in the order of `fr.ids`) at the two ends
    of each of the trajectory's `springs` (pairs of ids), in the order of `springs`; a
    spring with an end whose id the trajectory does not hold is left out, as the renderer
    leaves it out. (0, 2) without springs."""
    springs = getattr(traj, "springs", None)
    if springs is None or np.size(springs) == 0:
        return np.zeros((0, 2), dtype=np.int64)
    pairs = np.asarray(springs)
    if pairs.ndim != 2 or pairs.shape[1] != 2 or not np.issubdtype(pairs.dtype, np.integer):
        raise ValueError(f"springs has shape {pairs.shape} and type {pairs.dtype}; it must be (S, 2) integers, the ids at the ends of each spring")
    order = np.argsort(fr.ids, kind="stable")
    sorted_ids = fr.ids[order]
    at = np.clip(np.searchsorted(sorted_ids, pairs), 0, max(sorted_ids.size - 1, 0))
    known = (sorted_ids[at] == pairs).all(axis=1) if sorted_ids.size else np.zeros(len(pairs), dtype=bool)
    return order[at[known]].astype(np.int64).reshape(-1, 2)


def live_springs(columns: np.ndarray, fr: Frames, i: int) -> np.ndarray:
    """(K, 2) int64: the springs of `columns` (`spring_columns`) whose two ends are alive
    at frame `i`, as rows of that frame (indices into `fr.live(i)`: the order every
    format writes the frame's particles in), in the order of `columns`."""
    row = np.full(fr.n_particles, -1, dtype=np.int64)
    live = fr.live(i)
    row[live] = np.arange(live.size)
    ends = row[columns]
    return ends[(ends >= 0).all(axis=1)]


def particle_colors(traj: Any, n: int) -> np.ndarray | None:
    """(N, 3) float64: each particle's own colour (`Trajectory.colors`, r g b in [0, 1]),
    the renderer's `NO_OWN_COLOR` (RGB 70 130 200, the colour a video draws such a particle
    with) where it has none (a row with NaN); `None` when the trajectory has no colours.
    A colour outside [0, 1] or infinite is a `ValueError`."""
    colors = getattr(traj, "colors", None)
    if colors is None:
        return None
    c = np.array(colors, dtype=np.float64)
    if c.shape != (n, 3):
        raise ValueError(f"colors has shape {c.shape}; it must be ({n}, 3), r g b per particle")
    none = np.isnan(c).any(axis=1)
    bad = ~none & ~((c >= 0) & (c <= 1)).all(axis=1)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"colors[{k}] = {c[k].tolist()} is invalid: r g b must be in [0, 1] (NaN: the particle has no colour of its own)")
    from ..render import NO_OWN_COLOR

    c[none] = np.asarray(NO_OWN_COLOR, dtype=np.float64) / 255.0
    return c


def colors_uint8(colors: np.ndarray) -> np.ndarray:
    """(N, 3) uint8 of `particle_colors`: round(255 c), as the renderer's own colours."""
    return np.round(colors * 255.0).astype(np.uint8)


def element_names(traj: Any, n: int) -> list[str] | None:
    """The species names of the particles' types (`particle_types`) when every one is a
    chemical symbol or `X` (ASE's dummy element), as a LAMMPS `element` column needs them
    (ASE refuses other words there); `None` without species or when one is another word."""
    if getattr(traj, "species", None) is None:
        return None
    names, _ = particle_types(traj, n)
    return names if all(name in ELEMENTS or name == "X" for name in names) else None


class Extras:
    """What a trajectory adds to its particles beyond `Frames`, computed once before the
    files: the type names and each particle's type (`None` without species), the colours
    (`particle_colors`; `None` without) and the springs as pairs of columns
    (`spring_columns`; `None` without)."""

    def __init__(self, traj: Any, fr: Frames) -> None:
        self.names, self.typeid = particle_types(traj, fr.n_particles) if getattr(traj, "species", None) is not None else (None, None)
        # every reader takes a name as one word (XYZ's columns, a PLY comment, a CSV field)
        for name in self.names or []:
            if not re.fullmatch(_checks.SPECIES_PATTERN, name):
                raise ValueError(f"species: {name!r} is invalid: a species name is one word of letters, digits and _ . + -")
        self.colors = particle_colors(traj, fr.n_particles)
        springs = spring_columns(traj, fr)
        self.springs = springs if springs.size else None
