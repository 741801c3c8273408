"""LAMMPS's text dump format (`dump custom`), for OVITO, ASE, VMD and LAMMPS's own tools."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..contact_record import FIELDS
from ._cell import element_names, frame_steps, particle_types, trajectory_cell
from ._files import Frames, atomic_outputs

#: The `dump custom` columns of a spinning particle, as LAMMPS names them: its angular
#: velocity (`omegax omegay omegaz`, atom style sphere) and its orientation quaternion
#: (`quatw quati quatj quatk`, atom styles ellipsoid and body), which OVITO reads as its
#: Angular Velocity and Orientation (W, X, Y, Z).
SPIN_COLUMNS = "omegax omegay omegaz"
ORIENTATION_COLUMNS = "quatw quati quatj quatk"
#: The column of each contact field in the contacts' `dump local` file, as `dump_modify
#: colname` would name it; a vector's three columns are the name and x, y, z (`fnx fny fnz`).
LOCAL_COLUMNS = {
    "i": "id1",
    "j": "id2",
    "collider": "collider",
    "point": "p",
    "normal": "n",
    "overlap": "overlap",
    "u_n": "un",
    "force_n": "fn",
    "force_t": "ft",
    "sliding": "sliding",
    "impulse_n": "jn",
    "impulse_t": "jt",
}


def _lammps_ids(fr: Frames) -> np.ndarray:
    """LAMMPS atom ids, which must be positive: id + 1 when the ids are distinct and >= 0,
    otherwise 1..N in row order."""
    ids = fr.ids
    if ids.size and (ids.min() < 0 or np.unique(ids).size != ids.size):
        return np.arange(1, fr.n_particles + 1, dtype=np.int64)
    return ids + 1


# Over 100 lines (issue 50) by its docstring (48 lines): the dump's items and columns as
# LAMMPS, ASE, OVITO and MDAnalysis read them; the code is 53 lines.
def write_lammps(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any], plain: bool = False) -> list[Path]:
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

    `ITEM: UNITS` `si` before the first frame and `ITEM: TIME` (the frame's time, s) before
    each `ITEM: TIMESTEP`, as LAMMPS's `dump_modify units yes time yes` writes them, so the
    dump reads back with its times exactly and without `units=` (OVITO and ASE read them;
    MDAnalysis's reader, which takes a frame's first line for `ITEM: TIMESTEP`, does not).
    Where the species are not all chemical symbols (no `element` column), the first frame
    also has `ITEM: ATOM TYPE LABELS K` and K rows `type name` (the data files' `Atom Type
    Labels`), which kinema reads back as the species and OVITO and ASE skip. Unknown
    velocities (all NaN) get no `vx vy vz` columns. `plain=True` leaves these three items
    out: LAMMPS's default `dump custom` layout, the one MDAnalysis reads (kinema then reads
    the frames' times as their TIMESTEP, unless `units=` gives the time scale).

    Births and deaths (`alive`): each timestep lists the atoms alive at it only (`NUMBER
    OF ATOMS` varies; 0 for a frame with none), each with its own id, so a particle keeps
    its id from frame to frame. The dump has no bonds (the springs) and no colours. Floats
    are written with 17 significant digits: exact for float64 (ASE reads them back bit for
    bit; OVITO 3.17's parser can land 1 or 2 units in the last place off). `on_frame(i)`
    is called after frame `i` is written.

    Spin: a trajectory with angular velocities gets the columns `omegax omegay omegaz`
    (rad/s) after the others, and with orientations `quatw quati quatj quatk` (the unit
    quaternion, w first), LAMMPS's names, which OVITO reads as Angular Velocity and
    Orientation.

    Collision groups (`traj.groups`): a last column `group`, each particle's group (an
    integer 0..31; kinema's name: a LAMMPS dump has no column for LAMMPS's own groups), which
    OVITO reads as a particle property `group`; `type` stays the species.

    Contacts (`traj.contact_record`): two more files beside `path`, as LAMMPS's `dump
    local` writes a `compute property/local` and `compute pair/local`
    (`write_contacts_local`): `<stem>_contacts.dump`, the contacts between particles, and
    `<stem>_collider_contacts.dump`, those of particles with colliders; returned after
    `path`. The files are put in place together."""
    lo, hi, periodic, margin = trajectory_cell(traj, fr)
    if fr.dim == 2:  # LAMMPS's 2D boxes are periodic in z
        periodic[2] = True
    bounds = "ITEM: BOX BOUNDS " + " ".join("pp" if p else "ff" for p in periodic) + "\n"
    bounds += "".join(f"{float(a)!r} {float(b)!r}\n" for a, b in zip(lo, hi, strict=True))
    elements = element_names(traj, fr.n_particles)
    velocities = fr.has_velocities
    columns = (
        "id type"
        + " element" * (elements is not None)
        + " x y z"
        + " vx vy vz" * velocities
        + " radius" * (fr.radii is not None)
        + " mass" * (fr.masses is not None)
    )
    spin = [a for a in (fr.angular_velocities, fr.orientations) if a is not None]
    columns += f" {SPIN_COLUMNS}" * (fr.angular_velocities is not None) + f" {ORIENTATION_COLUMNS}" * (fr.orientations is not None)
    # the collision groups last: the columns before keep their places (kinema's name; LAMMPS's
    # own groups are no per-atom value of a dump)
    columns += " group" * (fr.groups is not None)
    suffixes = np.array([f" {int(g)}" for g in fr.groups] if fr.groups is not None else [""] * fr.n_particles, dtype=object)
    type_names, typeid = particle_types(traj, fr.n_particles)
    # the species names where no element column carries them: LAMMPS's data-file section
    # "Atom Type Labels" as an item of the first frame (OVITO and ASE skip it; kinema reads it)
    labels = ""
    if elements is None and getattr(traj, "species", None) is not None:
        labels = f"ITEM: ATOM TYPE LABELS {len(type_names)}\n" + "".join(f"{k + 1} {name}\n" for k, name in enumerate(type_names))
    ids = _lammps_ids(fr)
    prefixes = np.array(
        [f"{int(k)} {int(t) + 1} " + (f"{elements[t]} " if elements is not None else "") for k, t in zip(ids, typeid, strict=True)], dtype=object
    )
    per_particle = [a[:, None] for a in (fr.radii, fr.masses) if a is not None]
    steps = frame_steps(fr)
    record = getattr(traj, "contact_record", None)
    local = {"particles": path.with_name(f"{path.stem}_contacts.dump"), "colliders": path.with_name(f"{path.stem}_collider_contacts.dump")}
    with atomic_outputs(path) as out:
        tmp = out.file(path)
        with out.naming(path), open(tmp, "w", encoding="ascii") as f:
            for i in range(fr.n_frames):
                live = fr.live(i)
                table = np.hstack(
                    [fr.positions[i][live], *([fr.velocities[i][live]] if velocities else []), *(a[live] for a in per_particle), *(a[i][live] for a in spin)]
                ).tolist()
                rows = "".join(p + " ".join(map(repr, r)) + g + "\n" for p, r, g in zip(prefixes[live], table, suffixes[live], strict=True))
                head = "" if plain else (f"ITEM: UNITS\nsi\n{labels}" if i == 0 else "") + f"ITEM: TIME\n{float(fr.t[i])!r}\n"
                f.write(f"{head}ITEM: TIMESTEP\n{int(steps[i])}\nITEM: NUMBER OF ATOMS\n{live.size}\n{bounds}ITEM: ATOMS {columns}\n{rows}")
                on_frame(i)
        if record is not None:
            for between, target in local.items():
                tmp_local = out.file(target)
                with out.naming(target), open(tmp_local, "w", encoding="ascii") as f:
                    write_contacts_local(f, record, fr, steps, bounds, between)
    return [path] + (list(local.values()) if record is not None else [])


def write_contacts_local(f: Any, record: Any, fr: Frames, steps: np.ndarray, bounds: str, between: str = "particles") -> None:
    """The contacts of each frame (`record`, a `kinema.contact_record.ContactRecord`)
    `between` two particles ("particles") or a particle and a collider ("colliders") to
    the open text file `f` as LAMMPS's `dump local` writes them: each frame `ITEM:
    TIMESTEP`, `ITEM: NUMBER OF ENTRIES` (K, 0 for a frame without such contacts), the box
    `bounds` of the atoms' dump, `ITEM: ENTRIES index ...` and a row per contact.

    Columns (`LOCAL_COLUMNS`, those the record has, named as `dump_modify colname` would
    name them): `index` (1 … K, as LAMMPS numbers a frame's entries), `id1` and (between
    particles) `id2` the particles' LAMMPS ids (the atoms' dump's: kinema's id + 1), or
    (with colliders) `collider`, its index in the trajectory's colliders; `px py pz` the
    contact point (m), `nx ny nz` the unit normal from the partner to `id1`, `overlap`
    (m), `un` the normal velocity (m/s, < 0 approaching), `fnx fny fnz` and `ftx fty ftz`
    the normal and tangential force on `id1` (N), `sliding` 1 or 0, `jnx jny jnz` and
    `jtx jty jtz` the impulse model's normal and tangential impulses on `id1` (N s). SI
    units, 17 significant digits.

    The contacts between particles are pairs of atoms, as `compute pair/local` lists them:
    OVITO's LAMMPS dump local reader, as a Load Trajectory modifier's file beside the atoms'
    dump, makes them bonds (`id1 id2` mapped to Particle Identifiers) with the other
    columns as bond properties; a collider is no atom, hence the second file."""
    pairs = record["j"] >= 0
    keep = pairs if between == "particles" else ~pairs
    drop = "collider" if between == "particles" else "j"
    names = [n for n in LOCAL_COLUMNS if n in record.values and n != drop]
    labels = ["index"]
    for n in names:
        stem = LOCAL_COLUMNS[n]
        labels += [stem + c for c in "xyz"] if record[n].ndim == 2 else [stem]
    header = " ".join(labels)
    for k in range(record.n_frames):
        lo, hi = int(record.offsets[k]), int(record.offsets[k + 1])
        rows_here = keep[lo:hi]
        part = {n: a[rows_here] for n, a in record.frame(k).items()}
        count = len(part["i"])
        if count == 0:
            f.write(f"ITEM: TIMESTEP\n{int(steps[k])}\nITEM: NUMBER OF ENTRIES\n0\n{bounds}ITEM: ENTRIES {header}\n")
            continue
        words = [np.arange(1, count + 1).astype(str)[:, None]]  # index: 1 … K
        for n in names:
            a = part[n]
            if n in ("i", "j"):
                a = _lammps_id_map(fr, a)
            if FIELDS[n].kind == "real":
                text = np.array([repr(v) for v in a.reshape(-1).tolist()], dtype=object)
            else:
                text = a.astype(np.int64).astype(str).astype(object)
            words.append(text.reshape(count, -1))
        rows = "".join(" ".join(r) + "\n" for r in np.hstack(words).tolist())
        f.write(f"ITEM: TIMESTEP\n{int(steps[k])}\nITEM: NUMBER OF ENTRIES\n{count}\n{bounds}ITEM: ENTRIES {header}\n{rows}")


def _lammps_id_map(fr: Frames, ids: np.ndarray) -> np.ndarray:
    """The LAMMPS ids (`_lammps_ids`) of the particles of kinema ids `ids`; 0 for -1 (a
    collider: no atom)."""
    lammps = _lammps_ids(fr)
    order = np.argsort(fr.ids, kind="stable")
    if ids.size == 0 or order.size == 0:
        return np.zeros(ids.shape, dtype=np.int64)
    at = np.minimum(np.searchsorted(fr.ids[order], np.maximum(ids, 0)), order.size - 1)
    return np.where(ids >= 0, lammps[order][at], 0)
