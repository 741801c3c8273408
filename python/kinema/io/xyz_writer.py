"""Extended XYZ, one text file of all frames, for OVITO, ASE and MDAnalysis."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ._cell import ELEMENTS, Extras, trajectory_cell
from ._files import Frames, atomic_file

#: The order of an orientation quaternion's components in the `orientation` column: x y z w,
#: as OVITO reads and writes it (kinema's quaternions are w x y z).
XYZW = [1, 2, 3, 0]


def _xyz(fr: Frames, i: int, header: str, first: list[str], after_pos: list[str], colors: np.ndarray | None) -> str:
    """Frame `i` of an extended XYZ file: the count, the comment line (`header` and the
    frame's `Time`), one row per particle alive at it: the columns of `Properties`, its
    `first` word (its type or species name), pos, its `after_pos` word (its `species`
    symbol; empty without), velo, momenta, radius, mass, masses, color, omega,
    orientation (x y z w), id, group (those the trajectory has; 17 significant digits, exact
    float64)."""
    live = fr.live(i)
    v = fr.velocities[i][live] if fr.has_velocities else None  # unknown velocities: no velo, no momenta
    masses = None if fr.masses is None else fr.masses[live][:, None]
    cols = [np.zeros((live.size, 0))] + ([v] if v is not None else [])
    if masses is not None and v is not None:
        cols.append(masses * v)
    if fr.radii is not None:
        cols.append(fr.radii[live][:, None])
    if masses is not None:
        cols += [masses, masses]
    if colors is not None:
        cols.append(colors[live])
    if fr.angular_velocities is not None:
        cols.append(fr.angular_velocities[i][live])
    if fr.orientations is not None:
        cols.append(fr.orientations[i][live][:, XYZW])
    pos, rest = fr.positions[i][live].tolist(), np.hstack(cols).tolist()
    groups = [f" {int(g)}" for g in fr.groups[live]] if fr.groups is not None else [""] * live.size
    rows = "".join(
        f"{first[c]} " + " ".join(map(repr, x)) + after_pos[c] + " " + " ".join(map(repr, r)) + f" {int(k)}{g}\n"
        for c, x, r, k, g in zip(live, pos, rest, fr.ids[live], groups, strict=True)
    )
    return f"{live.size}\n{header} Time={float(fr.t[i])!r}\n{rows}"


def write_xyz(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    """Write `fr` to one extended XYZ file at `path` for OVITO, ASE and MDAnalysis, the
    frames one after the other; returns `[path]`.

    Each frame (`_xyz`): N, the comment line `Lattice="ax 0 0 0 by 0 0 0 cz" Origin="ox oy
    oz" pbc="T T F" units=SI Properties=species:S:1:pos:R:3:velo:R:3:
    momenta:R:3:radius:R:1:mass:R:1:masses:R:1:color:R:3:id:I:1 Time=t`, then one row per
    particle; `color` (r g b in [0, 1], OVITO's Color) where the trajectory has colours.

    Units are SI, as `units=SI` says: positions, `Lattice` and `Origin` in m, `velo`
    in m/s, `momenta` (mass × velocity) in kg·m/s, `mass` and `masses` in kg,
    `radius` in m, `Time` in s. OVITO maps `velo` to Velocity, `mass` to Mass,
    `radius` to Radius, `id` to Particle Identifier and `species` to Particle Type, and
    places the cell at `Origin`. ASE reads `masses` as `atoms.get_masses()` and
    `momenta` as `atoms.get_momenta()`, so `atoms.get_velocities()` (momenta / masses)
    gives the velocities in m/s; ASE's own units are Å, amu and Å per ASE time unit, so
    these numbers are SI only, to be converted before ASE calculators see them. ASE keeps
    `Origin` in `atoms.info["Origin"]` (its cell starts at 0). `momenta`, `mass` and
    `masses` are written only when the trajectory has masses, `radius` when it has radii.

    The cell (`_cell.trajectory_cell`, shared with GSD and LAMMPS) is an orthogonal box,
    the same in every frame, that holds every particle of every frame: along a periodic axis
    the periodic cell (the world's `Box`); along an axis where that box has two walls and
    every particle stays between them, the walls; otherwise the particles' extent over all
    frames widened on each side by the largest radius or 5 % of the largest extent,
    whichever is more; a 2D trajectory's z spans that margin. No edge is zero, so OVITO's
    cell analysis and `atoms.get_volume()` work.

    Particle types: a trajectory with `species` names (`World.add_particles(species=)`, a
    scene's `species`) gets a first column `type:S:1` of the names, which OVITO takes as
    its Particle Type and MDAnalysis as the atom names (it reads a row as a name and x y z),
    then the positions, then a `species` column of the name where it is a chemical symbol
    and `X` (ASE's dummy element) where not, as ASE refuses other words; ASE keeps the
    names in `atoms.arrays["type"]`. Without species names the first column is
    `species`, every one `X`.

    Spin: a trajectory with angular velocities gets an `omega:R:3` column (rad/s), one with
    orientations an `orientation:R:4` column, the unit quaternion in the order x y z w:
    OVITO's, which reads (and writes) these two columns as its Angular Velocity and
    Orientation (X, Y, Z, W); ASE keeps them in `atoms.arrays["omega"]` and
    `atoms.arrays["orientation"]`. kinema's reader gives the orientation back w first.

    Collision groups: a trajectory with `groups` gets a last column `group:I:1`, each
    particle's collision group (0..31), which ASE keeps in `atoms.arrays["group"]` and
    OVITO reads as a particle property `group`.

    Every float is written with 17 significant digits (exact for float64). The file is
    written under a temporary name and renamed at the end. `on_frame(i)` is called after
    frame `i` is written."""
    # A trajectory's species names go to a `type` column, first: OVITO takes the first of
    # `type` and `species` as its Particle Type, and MDAnalysis's XYZ reader takes a row as a
    # name and x y z, so the positions come second. ASE reads `species` as chemical symbols
    # and refuses other words ("grain"), so that column, after the positions, holds the name
    # where it is an element's symbol and X (ASE's dummy element) where not; ASE keeps `type`
    # in atoms.arrays.
    extras = Extras(traj, fr)
    typed = extras.names is not None
    if typed:
        first = [extras.names[t] for t in extras.typeid]
        after_pos = [f" {name if name in ELEMENTS else 'X'}" for name in first]
    else:
        first, after_pos = ["X"] * fr.n_particles, [""] * fr.n_particles
    has_m, has_r, has_c = fr.masses is not None, fr.radii is not None, extras.colors is not None
    props = (
        ("type:S:1:pos:R:3:species:S:1" if typed else "species:S:1:pos:R:3")
        + ":velo:R:3" * fr.has_velocities
        + ":momenta:R:3" * (has_m and fr.has_velocities)
        + ":radius:R:1" * has_r
        + ":mass:R:1:masses:R:1" * has_m
        + ":color:R:3" * has_c
        + ":omega:R:3" * (fr.angular_velocities is not None)
        + ":orientation:R:4" * (fr.orientations is not None)
        + ":id:I:1"
        + ":group:I:1" * (fr.groups is not None)
    )
    cell = trajectory_cell(traj, fr)
    origin, edges, pbc = cell.lo, cell.hi - cell.lo, cell.periodic
    lattice = " ".join(repr(float(c)) for c in np.diag(edges).reshape(-1))
    header = (
        f'Lattice="{lattice}" Origin="{" ".join(repr(float(c)) for c in origin)}" pbc="{" ".join("T" if p else "F" for p in pbc)}" units=SI Properties={props}'
    )
    with atomic_file(path) as tmp, open(tmp, "w", encoding="ascii") as f:
        for i in range(fr.n_frames):
            f.write(_xyz(fr, i, header, first, after_pos, extras.colors))
            on_frame(i)
    return [path]
