"""What the outside readers get from kinema's files: every export format opened by the tools its
users have (usd-core, Blender, OVITO, ASE, MDAnalysis, znh5md, gsd with freud, VTK, plyfile),
on four runs, and each reader's values compared with the trajectory. Prints one table, format ×
reader × what is read right, with the largest relative errors.

    .venv/bin/python docs/readers_survey.py [--out DIR] [--json PATH]

The four runs: a 3D periodic gas with two species and mixed masses (``gas``), the 2D billiards
break in its walled box (``2d``), ``cloth_on_sphere.toml`` (springs) and ``fountain.toml`` to
3.5 s (births, deaths and an emitter's colour). Each reader's values are taken in the units it
documents (MDAnalysis: Å, ps; ASE's LAMMPS reader: its own units; plain readers: the numbers in
the file) and converted to SI before they are compared. A cell reads ``4/4 pos 3e-08 vel 3e-08
ids species springs colour``: the runs it opened, the largest relative position and velocity
errors over the runs it opened (max |read − kinema| / max |kinema|; ``vel –`` where the reader
gives none), and what else came through right in every run that has it; ``✗ name`` where a run
has it and the reader got it wrong or not at all, ``fails`` with the first error where nothing opened. The script runs on any
version of kinema (it was run before and after issue 27 for its closing note): it uses the
newer writers' options where they exist.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

import kinema

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "examples" / "scenes"
ANGSTROM, AMU = 1e-10, 1.66053906660e-27


# -- the four runs ---------------------------------------------------------------------------------


def gas_run():
    """64 particles in a periodic 1 m cube: species He (1 kg) and grain (3 kg), collisions on."""
    w = kinema.World(dt=1e-3)
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    rng = np.random.default_rng(3)
    g = (np.arange(4) + 0.5) / 4
    pos = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    species = np.where(np.arange(64) % 2 == 0, "He", "grain")
    w.add_particles(pos, velocity=rng.normal(size=(64, 3)), mass=np.where(species == "He", 1.0, 3.0), radius=0.03, species=list(species))
    w.periodic = (True, True, True)
    w.set_collisions(restitution=1.0)
    return w.run(0.3, fps=30)


def scene_run(name, duration):
    scene = kinema.Scene.from_toml(SCENES / name)
    return scene.build().run(duration, fps=scene.world.fps)


RUNS = {
    "gas": gas_run,
    "2d": lambda: scene_run("billiards_2d.toml", 0.5),
    "cloth": lambda: scene_run("cloth_on_sphere.toml", 0.5),
    "fountain": lambda: scene_run("fountain.toml", 3.5),
}


# -- what a reader gives back ----------------------------------------------------------------------


class Read:
    """What a reader got from one file, frame by frame, in SI: ``frames`` a list of dicts with
    ``ids`` (kinema's ids, as the reader gives them, or None), ``pos`` (n, 3), ``vel`` (n, 3) or
    None, ``mass`` (n,) or None, ``species`` (n,) names or None, ``color`` (n, 3) or None; and
    ``springs`` (set of id pairs, or None), ``times`` (F,) or None."""

    def __init__(self):
        self.frames, self.springs, self.times = [], None, None


def live_frame(traj, k):
    live = traj.alive[k]
    ids = (traj.ids if traj.ids is not None else np.arange(live.size))[live]
    out = {"ids": ids, "pos": traj.positions[k][live], "vel": traj.velocities[k][live]}
    out["mass"] = None if traj.masses is None else traj.masses[live]
    out["species"] = None if traj.species is None else np.asarray(traj.species)[live]
    colors = getattr(traj, "colors", None)
    out["color"] = None if colors is None else colors[live]
    return out


def compare(traj, read):
    """{what: error or bool} for one run."""
    res = {}
    if len(read.frames) != len(traj.t):
        res["frames"] = False
        return res
    pos_err, vel_err, mass_err, ids_ok, species_ok, color_ok = 0.0, 0.0, 0.0, True, True, True
    scale_x = np.nanmax(np.abs(traj.positions)) or 1.0
    scale_v = np.nanmax(np.abs(traj.velocities)) or 1.0
    for k, got in enumerate(read.frames):
        want = live_frame(traj, k)
        n = len(want["ids"])
        if got["pos"].shape[0] != n:
            res["count"] = False
            return res
        order = np.arange(n)
        if got.get("ids") is not None:
            gi = np.asarray(got["ids"]).astype(np.int64)
            if sorted(gi.tolist()) != sorted(want["ids"].tolist()):
                ids_ok = False
            else:
                where = {int(i): j for j, i in enumerate(gi)}
                order = np.array([where[int(i)] for i in want["ids"]], dtype=np.int64)
        else:
            ids_ok = False
        pos_err = max(pos_err, float(np.max(np.abs(got["pos"][order] - want["pos"]), initial=0.0)) / scale_x)
        if got.get("vel") is not None:
            vel_err = max(vel_err, float(np.max(np.abs(got["vel"][order] - want["vel"]), initial=0.0)) / scale_v)
        else:
            vel_err = np.nan
        if want["mass"] is not None:
            if got.get("mass") is None:
                mass_err = np.nan
            else:
                mass_err = max(mass_err, float(np.max(np.abs(got["mass"][order] / want["mass"] - 1.0), initial=0.0)))
        if want["species"] is not None:
            gs = got.get("species")
            species_ok &= gs is not None and [str(s) for s in np.asarray(gs)[order]] == [str(s) for s in want["species"]]
        if want["color"] is not None:
            gc = got.get("color")
            ok = np.isfinite(want["color"]).all(axis=1)
            color_ok &= gc is not None and np.allclose(np.asarray(gc, float)[order][ok], want["color"][ok], atol=1 / 255)
    res.update(pos=pos_err, vel=vel_err)
    if traj.masses is not None:
        res["mass"] = mass_err
    res["ids"] = ids_ok
    if traj.species is not None:
        res["species"] = species_ok
    if getattr(traj, "colors", None) is not None:
        res["colour"] = color_ok
    if getattr(traj, "springs", None) is not None and len(traj.springs):
        want = {tuple(sorted(map(int, p))) for p in traj.springs}
        res["springs"] = read.springs is not None and {tuple(sorted(p)) for p in read.springs} == want
    return res


# -- exporting with the newest options the writer has ---------------------------------------------------


def export(traj, path, **options):
    """traj.export / traj.save with ``options`` where the writer takes them, without where not."""
    fn = traj.save if str(path).endswith(".h5") else traj.export
    try:
        return fn(path, **options)
    except TypeError:
        return fn(path)


# -- the readers -------------------------------------------------------------------------------


def read_kinema(path, traj):
    options = {"units": "si"} if str(path).endswith(".lammpstrj") else {}  # (a dump that says no units: kinema's are SI)
    try:
        back = kinema.load_trajectory(path, **options)
    except TypeError:
        back = kinema.load_trajectory(path)
    r = Read()
    for k in range(len(back.t)):
        f = live_frame(back, k)
        r.frames.append({"ids": f["ids"], "pos": f["pos"], "vel": f["vel"], "mass": f["mass"], "species": f["species"], "color": f["color"]})
    springs = getattr(back, "springs", None)
    r.springs = None if springs is None else [tuple(map(int, p)) for p in springs]
    return r


def read_mdanalysis(path, fmt, traj):
    """MDAnalysis: an H5MD file in its units (converted to Å and ps, so back to SI here); a dump
    as the numbers in the file (its reader converts nothing: kinema's are SI)."""
    import MDAnalysis as mda

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if fmt == "H5MD":  # an H5MD file has no topology: an empty universe of its atom count
            import h5py

            with h5py.File(path, "r") as f:
                n = next(iter(f["particles"].values()))["position/value"].shape[1]
            u = mda.Universe.empty(n, trajectory=True)
            u.load_new(str(path), format="H5MD")
            x_unit, v_unit, m_unit = ANGSTROM, ANGSTROM / 1e-12, AMU
        else:
            u = mda.Universe(str(path), format=fmt, topology_format=fmt)
            x_unit, v_unit, m_unit = 1.0, 1.0, 1.0
            with open(path) as f:  # MDAnalysis moves the box to the origin: its lower corner back
                lines = f.read(4096).splitlines()
            at = next(i for i, line in enumerate(lines) if line.startswith("ITEM: BOX BOUNDS"))
            corner = np.array([float(lines[at + 1 + a].split()[0]) for a in range(3)])
        r = Read()
        names = None
        for attr in ("elements", "types"):
            if names is None and hasattr(u.atoms, attr):
                names = getattr(u.atoms, attr)
        for ts in u.trajectory:
            ids = u.atoms.ids - 1 if hasattr(u.atoms, "ids") and fmt == "LAMMPSDUMP" else None
            pos = ts.positions.astype(float) * x_unit + (corner if fmt == "LAMMPSDUMP" else 0.0)
            vel = ts.velocities.astype(float) * v_unit if ts.has_velocities else None
            mass = u.atoms.masses * m_unit if hasattr(u.atoms, "masses") else None
            if fmt == "H5MD":  # one column per particle, NaN where it does not exist (H5MD's fill)
                live = np.isfinite(pos).all(axis=1)
                ids = (traj.ids if traj.ids is not None else np.arange(len(pos)))[live]
                pos, vel = pos[live], None if vel is None else vel[live]
                mass = None if mass is None else mass[live]
            r.frames.append({"ids": ids, "pos": pos, "vel": vel, "mass": mass, "species": names})
    return r


def read_ase(path, **kw):
    import ase.io
    import ase.units

    r = Read()
    for atoms in ase.io.read(str(path), ":", **kw):
        ids = atoms.arrays.get("id")
        species = atoms.arrays.get("type")
        species = atoms.get_chemical_symbols() if species is None else species
        if kw.get("format") == "lammps-dump-text":  # ASE's units (Å, Å per ASE time, amu)
            pos = atoms.positions * ANGSTROM
            vel = atoms.get_velocities() * ANGSTROM * ase.units.second
            mass = atoms.get_masses() * AMU
            ids = None if ids is None else ids - 1
        else:  # the numbers in the file (kinema's SI)
            pos, vel, mass = atoms.positions, atoms.get_velocities(), atoms.get_masses()
        r.frames.append({"ids": ids, "pos": pos, "vel": vel, "mass": mass, "species": species, "color": atoms.arrays.get("color")})
    return r


def read_znh5md(path):
    import znh5md

    r = Read()
    for atoms in znh5md.IO(str(path))[:]:
        r.frames.append(
            {
                "ids": atoms.arrays.get("id"),
                "pos": atoms.positions,
                "vel": atoms.get_velocities(),
                "mass": atoms.get_masses(),
                "species": atoms.get_chemical_symbols(),
            }
        )
    return r


def read_ovito(path):
    from ovito.io import import_file

    pipeline = import_file(str(path))
    r = Read()
    for k in range(pipeline.num_frames):
        d = pipeline.compute(k)
        p = d.particles
        ids = np.asarray(p["Particle Identifier"]) if "Particle Identifier" in p else (np.asarray(p["kinema_id"]) if "kinema_id" in p else None)
        if ids is not None and str(path).endswith((".lammpstrj", ".dump")):
            ids = ids - 1
        pos = np.asarray(p.positions, dtype=float)
        if "kinema/origin" in d.attributes:
            pos = pos + np.asarray(d.attributes["kinema/origin"], float)
        species = None
        if "Particle Type" in p:
            t = p["Particle Type"]
            species = [t.type_by_id(int(i)).name for i in np.asarray(t)]
        color = np.asarray(p["Color"]) if "Color" in p else None
        mass = np.asarray(p["Mass"]) if "Mass" in p else None
        vel = np.asarray(p["Velocity"]) if "Velocity" in p else None
        r.frames.append({"ids": ids, "pos": pos, "vel": vel, "mass": mass, "species": species, "color": color})
        if d.particles.bonds is not None and k == 0:
            topo = np.asarray(d.particles.bonds.topology)
            idk = ids if ids is not None else np.arange(len(pos))
            r.springs = [(int(idk[a]), int(idk[b])) for a, b in topo]
    return r


def read_gsd(path):
    import gsd.hoomd

    r = Read()
    with gsd.hoomd.open(str(path), "r") as f:
        for fr in f:
            origin = np.asarray(fr.log.get("kinema/origin", np.zeros(3)), float)
            ids = fr.log.get("particles/kinema/id")
            p = fr.particles
            species = [p.types[t] for t in p.typeid]
            color = fr.log.get("particles/Color", fr.log.get("particles/kinema/color"))
            r.frames.append(
                {
                    "ids": ids,
                    "pos": p.position.astype(float) + origin,
                    "vel": p.velocity.astype(float),
                    "mass": p.mass.astype(float),
                    "species": species,
                    "color": color,
                }
            )
            if fr.bonds.N and r.springs is None:
                idk = ids if ids is not None else np.arange(p.N)
                r.springs = [(int(idk[a]), int(idk[b])) for a, b in fr.bonds.group]
    return r


def freud_false_pairs(path, traj):
    """Over all frames: the pairs freud finds in the GSD's box minus the true pairs (nearer than
    r_max, across an axis only where the trajectory is periodic), r_max = 0.45 of the box's
    smallest length (freud needs r_max < L/2)."""
    import freud
    import gsd.hoomd

    false = 0
    with gsd.hoomd.open(str(path), "r") as f:
        for k, fr in enumerate(f):
            box = freud.box.Box.from_box(fr.configuration.box, dimensions=fr.configuration.dimensions)
            lengths = np.asarray(fr.configuration.box[:3], float)
            r_max = 0.45 * float(np.min(lengths[: fr.configuration.dimensions]))
            pts = fr.particles.position.astype(float)
            found = freud.locality.AABBQuery(box, pts).query(pts, {"r_max": r_max, "exclude_ii": True}).toNeighborList()
            x = traj.positions[k][traj.alive[k]]
            d = x[:, None, :] - x[None, :, :]
            periodic = np.asarray(traj.periodic if traj.periodic is not None else (False,) * 3)
            edges = np.asarray(traj.box_edges if traj.box_edges is not None else np.zeros(3))
            for a in range(3):
                if periodic[a]:
                    d[..., a] -= edges[a] * np.round(d[..., a] / edges[a])
            true = int((np.linalg.norm(d, axis=-1) < r_max).sum() - len(x))
            false += len(found) - true
    return false


def read_vtk(path):
    import vtk

    r = Read()
    folder = Path(path).with_name(Path(path).stem + "_vtk")
    stem = Path(path).stem
    for f in sorted(p for p in folder.glob("*.vtp") if p.name[len(stem) + 1 : -4].isdigit()):  # (not the springs' files)
        rd = vtk.vtkXMLPolyDataReader()
        rd.SetFileName(str(f))
        rd.Update()
        pd = rd.GetOutput()
        from vtk.util.numpy_support import vtk_to_numpy

        pts = vtk_to_numpy(pd.GetPoints().GetData()) if pd.GetNumberOfPoints() else np.zeros((0, 3))
        arr = {pd.GetPointData().GetArrayName(i): vtk_to_numpy(pd.GetPointData().GetArray(i)) for i in range(pd.GetPointData().GetNumberOfArrays())}
        ids = arr.get("id")
        species = None
        if "species" in arr or "type" in arr:
            names = pd.GetFieldData().GetAbstractArray("species_names") or pd.GetFieldData().GetAbstractArray("type_names")
            t = arr.get("type", arr.get("species"))
            if names is not None and t is not None:
                species = [names.GetValue(int(i)) for i in t]
        r.frames.append({"ids": ids, "pos": pts, "vel": arr.get("v"), "mass": arr.get("mass"), "species": species, "color": arr.get("Color", arr.get("color"))})
        springs = f.with_name(f"{stem}_springs_{f.name[len(stem) + 1 :]}")
        if r.springs is None and springs.exists():  # (a frame's springs are a file of their own)
            sd = vtk.vtkXMLPolyDataReader()
            sd.SetFileName(str(springs))
            sd.Update()
            cd = sd.GetOutput().GetCellData()
            r.springs = [(int(a), int(b)) for a, b in zip(vtk_to_numpy(cd.GetArray("id1")), vtk_to_numpy(cd.GetArray("id2")), strict=True) if a >= 0]
        if r.springs is None and pd.GetNumberOfLines():
            lines = vtk_to_numpy(pd.GetLines().GetConnectivityArray())
            idk = ids if ids is not None else np.arange(len(pts))
            r.springs = [(int(idk[a]), int(idk[b])) for a, b in lines.reshape(-1, 2)]
    return r


def read_ply(path):
    from plyfile import PlyData

    r = Read()
    folder = Path(path).with_name(Path(path).stem + "_ply")
    for f in sorted(folder.glob("*.ply")):
        ply = PlyData.read(str(f))
        v = ply["vertex"].data
        names = v.dtype.names
        pos = np.stack([v["x"], v["y"], v["z"]], -1).astype(float)
        vel = np.stack([v["vx"], v["vy"], v["vz"]], -1).astype(float) if "vx" in names else None
        color = np.stack([v["red"], v["green"], v["blue"]], -1) / 255.0 if "red" in names else None
        ids = v["id"] if "id" in names else None
        r.frames.append({"ids": ids, "pos": pos, "vel": vel, "mass": v["mass"].astype(float) if "mass" in names else None, "color": color})
        if r.springs is None and "edge" in ply:
            e = ply["edge"].data
            idk = ids if ids is not None else np.arange(len(pos))
            r.springs = [(int(idk[a]), int(idk[b])) for a, b in zip(e["vertex1"], e["vertex2"], strict=True)]
    return r


def to_srgb(linear):
    """USD's and Blender's colours are linear: back to the sRGB values kinema's colours are."""
    c = np.clip(linear, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)


def read_pxr(path, traj):
    """Asked at whole frames k, as 3D applications ask."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    pts = UsdGeom.Points(stage.GetPrimAtPath("/World/particles"))
    pv = UsdGeom.PrimvarsAPI(pts)
    r = Read()
    start = stage.GetStartTimeCode()
    rate = stage.GetTimeCodesPerSecond()
    for k in range(len(traj.t)):
        code = start + k if start == 0 else round(traj.t[k] * rate)  # (the old writer: t × rate)
        x = np.asarray(pts.GetPointsAttr().Get(code), float)
        v = np.asarray(pts.GetVelocitiesAttr().Get(code), float)
        ids = pts.GetIdsAttr().Get(code)
        color = pv.GetPrimvar("displayColor").Get(code) if pv.HasPrimvar("displayColor") else None
        species = pv.GetPrimvar("species").Get(code) if pv.HasPrimvar("species") else None
        mass = pv.GetPrimvar("mass").Get(code) if pv.HasPrimvar("mass") else None
        r.frames.append(
            {
                "ids": None if ids is None else np.asarray(ids),
                "pos": x.reshape(-1, 3),
                "vel": v.reshape(-1, 3),
                "mass": None if mass is None else np.asarray(mass, float),
                "species": None if species is None else list(species),
                "color": None if color is None or len(color) != len(x) else to_srgb(np.asarray(color, float)),
            }
        )
    curves = [p for p in stage.Traverse() if p.IsA(UsdGeom.BasisCurves)]
    if curves:
        r.springs = [tuple(map(int, p)) for p in traj.springs]  # judged by positions: see usd_springs
    return r


BLENDER = ROOT / ".venv-blender" / "bin" / "python"  # Blender as bpy needs numpy < 2: its own venv
BLENDER_SCRIPT = r"""
import sys, numpy as np, bpy
path, out, frames = sys.argv[1], sys.argv[2], int(sys.argv[3])
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=path)
scene = bpy.context.scene
obj = next(o for o in scene.objects if o.type == "POINTCLOUD")
got = {}
for k in range(frames):
    scene.frame_set(scene.frame_start + k)
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    a = ev.data.attributes
    n = len(ev.data.points)
    pos = np.zeros(n * 3, dtype=np.float32)
    if n:
        a["position"].data.foreach_get("vector", pos)
    got[f"pos{k}"] = pos.reshape(n, 3)
    for name in ("id", "ids"):
        if name in a and a[name].data_type == "INT":
            ids = np.zeros(n, dtype=np.int32)
            a[name].data.foreach_get("value", ids)
            got[f"ids{k}"] = ids
    for name in ("displayColor", "color"):
        if name in a and a[name].data_type in ("FLOAT_COLOR", "BYTE_COLOR", "FLOAT_VECTOR"):
            width = 3 if a[name].data_type == "FLOAT_VECTOR" else 4
            c = np.zeros(n * width, dtype=np.float32)
            a[name].data.foreach_get("vector" if width == 3 else "color", c)
            got[f"color{k}"] = c.reshape(n, width)[:, :3]
            break
np.savez(out, **got)
"""


def read_blender(path, traj):
    """Blender 5.0 (bpy in .venv-blender) imports the stage; each frame's evaluated points."""
    import subprocess

    if not BLENDER.exists():
        raise RuntimeError("Blender (.venv-blender) is not installed")
    out = Path(path).with_suffix(".blender.npz")
    done = subprocess.run([str(BLENDER), "-c", BLENDER_SCRIPT, str(path), str(out), str(len(traj.t))], capture_output=True, text=True, timeout=600)
    if done.returncode:
        raise RuntimeError("Blender: " + (done.stderr.strip().splitlines() or [f"exit status {done.returncode}"])[-1])
    got = np.load(out)
    r = Read()
    for k in range(len(traj.t)):
        color = got.get(f"color{k}")
        if color is not None and traj.colors is None:
            color = None
        r.frames.append({"ids": got.get(f"ids{k}"), "pos": got[f"pos{k}"].astype(float), "vel": None, "color": None if color is None else to_srgb(color)})
    return r


def read_csv(path, traj):
    import csv

    r = Read()
    with open(path) as f:
        rows = list(csv.DictReader(f))
    frames = {}
    for row in rows:
        frames.setdefault(int(row["frame"]), []).append(row)
    for k in range(len(traj.t)):
        rs = frames.get(k, [])
        col = lambda *names, rs=rs: np.array([[float(x[n]) for n in names] for x in rs]).reshape(-1, len(names))  # noqa: E731
        if not rs:
            r.frames.append(
                {"ids": np.zeros(0, int), "pos": np.zeros((0, 3)), "vel": np.zeros((0, 3)), "mass": np.zeros(0), "species": [], "color": np.zeros((0, 3))}
            )
            continue
        r.frames.append(
            {
                "ids": np.array([int(x["id"]) for x in rs]),
                "pos": col("x", "y", "z"),
                "vel": col("vx", "vy", "vz"),
                "mass": col("mass")[:, 0] if "mass" in rs[0] else None,
                "species": [x["species"] for x in rs] if "species" in rs[0] else None,
                "color": col("r", "g", "b") if "r" in rs[0] else None,
            }
        )
    return r


# (format, reader) -> (file name, export options, read function(path, traj))
CASES = {
    ("H5MD", "kinema"): ("run.h5", {}, lambda p, t: read_kinema(p, t)),
    ("H5MD", "MDAnalysis"): ("md.h5", {"units": "MD"}, lambda p, t: read_mdanalysis(p, "H5MD", t)),
    ("H5MD", "znh5md"): ("run.h5", {}, lambda p, t: read_znh5md(p)),
    ("XYZ", "ASE"): ("run.xyz", {}, lambda p, t: read_ase(p)),
    ("XYZ", "OVITO"): ("run.xyz", {}, lambda p, t: read_ovito(p)),
    ("XYZ", "MDAnalysis"): ("run.xyz", {}, lambda p, t: read_mdanalysis_xyz(p)),
    ("XYZ", "kinema"): ("run.xyz", {}, lambda p, t: read_kinema(p, t)),
    ("dump", "ASE si"): ("run.lammpstrj", {}, lambda p, t: read_ase(p, format="lammps-dump-text", units="si")),
    ("dump", "OVITO"): ("run.lammpstrj", {}, lambda p, t: read_ovito(p)),
    ("dump", "MDAnalysis"): ("run.lammpstrj", {}, lambda p, t: read_mdanalysis(p, "LAMMPSDUMP", t)),
    ("dump", "kinema"): ("run.lammpstrj", {}, lambda p, t: read_kinema(p, t)),
    ("GSD", "gsd"): ("run.gsd", {}, lambda p, t: read_gsd(p)),
    ("GSD", "OVITO"): ("run.gsd", {}, lambda p, t: read_ovito(p)),
    ("GSD", "kinema"): ("run.gsd", {}, lambda p, t: read_kinema(p, t)),
    ("VTK", "vtk"): ("run.pvd", {}, lambda p, t: read_vtk(p)),
    ("VTK", "OVITO"): ("run.pvd", {}, lambda p, t: read_ovito(p)),
    ("PLY", "plyfile"): ("run.ply", {}, lambda p, t: read_ply(p)),
    ("USD", "usd-core"): ("run.usd", {}, lambda p, t: read_pxr(p, t)),
    ("USD", "Blender"): ("run.usdc", {}, lambda p, t: read_blender(p, t)),
    ("USD", "kinema"): ("run.usd", {}, lambda p, t: read_kinema(p, t)),
    ("CSV", "numpy"): ("run.csv", {}, lambda p, t: read_csv(p, t)),
}


def read_mdanalysis_xyz(path):
    """MDAnalysis's XYZ reader: the numbers in the file (no unit conversion for XYZ)."""
    import MDAnalysis as mda

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        u = mda.Universe(str(path), format="XYZ", topology_format="XYZ")
        r = Read()
        for ts in u.trajectory:
            r.frames.append({"ids": None, "pos": ts.positions.astype(float), "vel": None, "species": list(u.atoms.names)})
    return r


def cell(results):
    """One table cell from {run: result or exception text}."""
    opened = {k: v for k, v in results.items() if isinstance(v, dict) and "pos" in v}
    if not opened:
        first = next(iter(results.values()))
        return "fails: " + (first if isinstance(first, str) else "frames or count differ")[:70]
    parts = [f"{len(opened)}/{len(results)}"]
    pos = max(v["pos"] for v in opened.values())
    parts.append(f"pos {pos:.0e}")
    vels = [v["vel"] for v in opened.values()]
    parts.append("vel –" if any(np.isnan(x) for x in vels) else f"vel {max(vels):.0e}")
    masses = [v["mass"] for v in opened.values() if "mass" in v]
    if masses:
        parts.append("mass –" if any(np.isnan(x) for x in masses) else f"mass {max(masses):.0e}")
    for what in ("ids", "species", "springs", "colour"):
        have = [v[what] for v in opened.values() if what in v]
        if have:
            parts.append(what if all(have) else f"✗ {what}")
    return " ".join(parts)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=None, help="folder for the files (default: a temporary one)")
    parser.add_argument("--json", default=None, help="also write the results as JSON")
    parser.add_argument("--only", default=None, help="comma-separated formats to run (H5MD, XYZ, dump, GSD, VTK, PLY, USD, CSV)")
    args = parser.parse_args()
    out = Path(args.out or tempfile.mkdtemp(prefix="kinema-readers-"))
    warnings.simplefilter("ignore")
    trajs = {name: make() for name, make in RUNS.items()}
    table, extra = {}, {}
    only = None if args.only is None else set(args.only.split(","))
    for (fmt, reader), (name, options, read) in CASES.items():
        if only and fmt not in only:
            continue
        results = {}
        for run, traj in trajs.items():
            folder = out / run
            folder.mkdir(parents=True, exist_ok=True)
            path = folder / name
            try:
                with contextlib.redirect_stdout(io.StringIO()):
                    if not path.exists():
                        export(traj, path, **options)
                    results[run] = compare(traj, read(path, traj))
            except Exception as e:  # a reader that fails is a result
                results[run] = f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
        table[(fmt, reader)] = results
        print(f"{fmt:6} {reader:11} {cell(results)}", flush=True)
    if only is None or "GSD" in only:
        with contextlib.suppress(Exception):
            extra["freud false pairs (2d)"] = freud_false_pairs(out / "2d" / "run.gsd", trajs["2d"])
            extra["freud false pairs (gas)"] = freud_false_pairs(out / "gas" / "run.gsd", trajs["gas"])
        for k, v in extra.items():
            print(f"{k}: {v}")
    if args.json:
        Path(args.json).write_text(json.dumps({f"{f} {r}": v for (f, r), v in table.items()} | extra, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
