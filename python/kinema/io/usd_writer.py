"""Pixar's USD (Blender, Houdini, Omniverse, usdview), written with the ``usd-core`` package:
the particles as one ``UsdGeom.Points`` prim with time samples, the colliders as simple prims."""

from __future__ import annotations

import errno
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ._cell import box_corners, trajectory_cell
from ._files import FileWriteError, Frames, TrajectoryFileError, copy_into, os_errors_as_write_errors, private_folder, refuse_special_target

#: The suffixes USD writes: binary crate (.usd, .usdc), text (.usda), a zip package (.usdz).
#: USD picks a layer's format from its suffix, and refuses another.
SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")


def write_usd(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    """Write ``fr`` to one USD stage at ``path``; returns ``[path]``.

    The stage: ``upAxis`` Z (kinema's gravity points along -z), ``metersPerUnit`` 1 (kinema
    is SI); frame k at time code k (k = 0 … F − 1: ``startTimeCode`` 0, ``endTimeCode``
    F − 1), ``timeCodesPerSecond`` = ``framesPerSecond`` = the recording's frame rate (1 / the
    median interval), so that a 3D application asking at whole frames, as Blender and Houdini
    do, gets each frame exactly (time codes t × rate, 1.0000000000000027, 2.0000000000000053,
    …, gave the previous frame in 172 of the fountain's 182 frames). The frames' own times (s,
    float64) are the time samples of ``/World``'s ``kinema:time``. ``/World`` (the default
    prim, an Xform) holds:

    - ``/World/particles``, a ``UsdGeom.Points``: ``points`` (m) and ``velocities`` (m/s:
      USD's velocities are in units per second, whatever the time codes) as a time sample per
      frame, float32 as USD's point arrays are; ``widths`` 2r (m) and ``ids`` constant;
      primvar ``mass`` (kg) where the trajectory has masses. With births and deaths
      (``alive``) each time sample holds the particles alive at that frame only: ``points``,
      ``velocities``, ``widths``, ``ids`` and ``mass`` are then all time-sampled, their
      length varying from frame to frame (0 for a frame with none), and ``ids`` tells which
      particle each point is.
    - ``/World/colliders``: a ``box_k`` (a ``UsdGeom.Cube`` scaled to the box, open faces
      closed at the particles' extent), ``plane_k`` (a ``UsdGeom.Plane``, as wide as the
      scene) and ``sphere_k`` (a ``UsdGeom.Sphere``) per collider, with the ``guide`` purpose
      so that renders show the particles only, and ``kinema:collider`` naming the type.

    In Blender: File → Import → Universal Scene Description, then play: the Points prim
    becomes a point cloud whose positions follow the time samples. In Houdini: a LOP
    network's Sublayer or a SOP ``usdimport``. ``on_frame(i)`` is called after frame ``i``.

    The suffix of ``path`` chooses the file: ``.usd`` or ``.usdc`` (binary), ``.usda``
    (text), ``.usdz`` (the binary stage in a zip package, ``UsdUtils.CreateNewUsdzPackage``);
    another is a ``ValueError`` listing them, before anything is written. A failure of the
    system (a name too long, a full disk) is a ``FileWriteError`` naming ``path``, with
    ``path`` left as it was: the stage (and its package, checked whole) is built in a private
    folder of the system's temporary folder (``tempfile.gettempdir()``, ``$TMPDIR``) and
    copied to a temporary name beside ``path``, renamed over it when complete."""
    if path.suffix.lower() not in SUFFIXES:
        raise ValueError(f"path = {str(path)!r}: the suffix {path.suffix or '(none)'!r} is not a USD file's; allowed: {', '.join(SUFFIXES)}")
    try:
        from pxr import Gf, Sdf, Usd, UsdGeom, Vt
    except ImportError:
        raise ImportError("writing USD needs the usd-core package: pip install usd-core (or kinema[usd])") from None
    with os_errors_as_write_errors(path):
        return _write_stage(traj, fr, path, on_frame, (Gf, Sdf, Usd, UsdGeom, Vt))


def _write_stage(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any], pxr: tuple) -> list[Path]:
    rate = _frame_rate(fr.t)  # (a ValueError before anything is written)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise TrajectoryFileError(f"cannot write {path}: the folder {parent} does not exist")
    if path.is_dir():
        raise TrajectoryFileError(f"cannot write {path}: it is a directory; give a file name such as {path / 'run.usdc'}")
    refuse_special_target(path)
    # USD picks the file format from the name's suffix, so the stage is written under its own
    # name in a private folder of the system's temporary folder, then copied to the target by
    # Python (atomic_file: a temporary name beside it, renamed over it). usd-core cannot be
    # trusted with a failed write: UsdUtils.CreateNewUsdzPackage returns True though its
    # write failed (a full disk), leaving a truncated package; so nothing of usd-core's is
    # written on the target's file system, the package is checked before it is copied, and a
    # full disk at the target is Python's own FileWriteError, with what was there kept.
    with private_folder(path) as staging:
        _build_stage(traj, fr, path, staging, rate, on_frame, pxr)
    return [path]


def _build_stage(traj: Any, fr: Frames, path: Path, staging: Path, rate: float, on_frame: Callable[[int], Any], pxr: tuple) -> None:
    """Writes the stage of ``fr`` in the folder ``staging`` and copies it (or its .usdz
    package) to ``path``."""
    Gf, Sdf, Usd, UsdGeom, Vt = pxr
    where = f"in the temporary folder {staging.parent}, where the stage is built"  # (usd-core's failures are there)
    try:
        package = path.suffix.lower() == ".usdz"  # a zip of a binary stage: written as .usdc, then packed
        tmp = staging / (path.stem + ".usdc" if package else path.name)
        stage = Usd.Stage.CreateNew(str(tmp))
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        stage.SetTimeCodesPerSecond(rate)
        stage.SetFramesPerSecond(rate)
        codes = np.arange(fr.n_frames, dtype=float)  # frame k at time code k
        stage.SetStartTimeCode(0.0)
        stage.SetEndTimeCode(float(max(fr.n_frames - 1, 0)))
        world = UsdGeom.Xform.Define(stage, "/World")
        stage.SetDefaultPrim(world.GetPrim())
        time = world.GetPrim().CreateAttribute("kinema:time", Sdf.ValueTypeNames.Double)
        for k in range(fr.n_frames):
            time.Set(float(fr.t[k]), Usd.TimeCode(float(k)))

        points = UsdGeom.Points.Define(stage, "/World/particles")
        radii = fr.radii if fr.radii is not None else np.zeros(fr.n_particles)
        widths, ids = (2.0 * radii).astype(np.float32), fr.ids.astype(np.int64)
        masses = None if fr.masses is None else fr.masses.astype(np.float32)
        widths_attr, ids_attr = points.CreateWidthsAttr(), points.CreateIdsAttr()
        mass = None
        if masses is not None:
            mass = UsdGeom.PrimvarsAPI(points).CreatePrimvar("mass", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex)
        # Without births and deaths the per-particle values are constant (one default value);
        # with them, a time sample per frame of the live particles' values.
        changes = fr.changes_count
        if not changes:
            widths_attr.Set(Vt.FloatArray.FromNumpy(widths))
            ids_attr.Set(Vt.Int64Array.FromNumpy(ids))
            if mass is not None:
                mass.Set(Vt.FloatArray.FromNumpy(masses))
        positions, velocities = points.CreatePointsAttr(), points.CreateVelocitiesAttr()
        lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
        for i in range(fr.n_frames):
            code = Usd.TimeCode(float(codes[i]))
            live = fr.live(i)
            x = fr.positions[i][live]
            positions.Set(Vt.Vec3fArray.FromNumpy(x.astype(np.float32)), code)
            velocities.Set(Vt.Vec3fArray.FromNumpy(fr.velocities[i][live].astype(np.float32)), code)
            if changes:
                widths_attr.Set(Vt.FloatArray.FromNumpy(widths[live]), code)
                ids_attr.Set(Vt.Int64Array.FromNumpy(ids[live]), code)
                if mass is not None:
                    mass.Set(Vt.FloatArray.FromNumpy(masses[live]), code)
            if live.size:
                reach = radii[live][:, None]
                lo, hi = np.minimum(lo, (x - reach).min(axis=0)), np.maximum(hi, (x + reach).max(axis=0))
            on_frame(i)
        if np.all(lo <= hi):
            points.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))]))
        _colliders(stage, traj, fr, UsdGeom, Gf)
        if not stage.GetRootLayer().Save():
            raise FileWriteError(errno.EIO, f"usd-core could not save the stage ({where})", str(path))
        if package:
            from pxr import UsdUtils

            packed = staging / path.name
            if not UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(tmp)), str(packed)) or not _whole_package(packed, tmp):
                raise FileWriteError(errno.EIO, f"usd-core could not make the .usdz package ({where})", str(path))
            tmp = packed
        del stage  # (its layer lets go of the file)
        copy_into(tmp, path)
    except OSError as e:
        if isinstance(e, FileWriteError):
            raise
        raise FileWriteError(e.errno, f"{e.strerror or e} ({where})", str(path)) from None
    except Exception as e:
        from pxr import Tf

        if not isinstance(e, Tf.ErrorException):
            raise
        # USD's errors are several lines ("Error in '...' at line ... : 'what'"): the last part
        lines = [line.strip() for line in str(e).splitlines() if line.strip()]
        reason = lines[0].rsplit(" : ", 1)[-1].strip("'") if lines else "usd-core failed"
        raise FileWriteError(errno.EIO, f"usd-core failed: {reason} ({where})", str(path)) from None


def _whole_package(packed: Path, layer: Path) -> bool:
    """Whether the .usdz ``packed`` is a whole zip archive holding the stage ``layer`` as it
    was saved (its size, every member's CRC): usd-core reports a package as made though a
    write of it failed."""
    import zipfile

    try:
        with zipfile.ZipFile(packed) as z:
            sizes = {info.filename: info.file_size for info in z.infolist()}
            return sizes.get(layer.name) == layer.stat().st_size and z.testzip() is None
    except (OSError, EOFError, zipfile.BadZipFile, ValueError):
        return False


def _frame_rate(t: np.ndarray) -> float:
    """Frames per second of the recording (the stage's time codes per second): 1 / the median
    interval, 24 (USD's default) for a single frame."""
    if t.size < 2:
        return 24.0
    step = float(np.median(np.diff(t)))
    if not (np.isfinite(step) and step > 0):
        raise ValueError(f"t: the frames' times must increase to give USD a frame rate (median interval {step!r} s)")
    return 1.0 / step


def _colliders(stage: Any, traj: Any, fr: Frames, UsdGeom: Any, Gf: Any) -> None:
    """The trajectory's colliders as simple prims under /World/colliders (see write_usd)."""
    described = [c for c in getattr(traj, "colliders", None) or [] if isinstance(c, dict)]
    if not described:
        return
    cell = trajectory_cell(traj, fr)
    centre, size = 0.5 * (cell.lo + cell.hi), float(np.max(cell.hi - cell.lo))
    UsdGeom.Scope.Define(stage, "/World/colliders")
    for k, c in enumerate(described):
        kind = c.get("type")
        prim_path = f"/World/colliders/{kind}_{k}"
        if kind == "box":
            lo, hi = box_corners(c)
            lo, hi = np.where(np.isfinite(lo), lo, cell.lo), np.where(np.isfinite(hi), hi, cell.hi)  # open faces: the scene's extent
            geom = UsdGeom.Cube.Define(stage, prim_path)
            geom.CreateSizeAttr(1.0)
            xf = UsdGeom.XformCommonAPI(geom)
            xf.SetTranslate(Gf.Vec3d(*(0.5 * (lo + hi)).tolist()))
            xf.SetScale(Gf.Vec3f(*np.maximum(hi - lo, 1e-9).tolist()))
        elif kind == "plane":
            normal = np.asarray(c["normal"], float).reshape(-1)
            normal = normal / np.linalg.norm(normal)
            point = np.asarray(c["point"], float).reshape(-1)
            geom = UsdGeom.Plane.Define(stage, prim_path)
            geom.CreateAxisAttr(UsdGeom.Tokens.z)
            geom.CreateWidthAttr(2.0 * size)
            geom.CreateLengthAttr(2.0 * size)
            # the plane's point nearest the scene's centre, its z axis turned onto the normal
            foot = centre - np.dot(centre - point, normal) * normal
            rotation = Gf.Rotation(Gf.Vec3d(0.0, 0.0, 1.0), Gf.Vec3d(*normal.tolist()))
            xf = UsdGeom.Xformable(geom)
            xf.AddTranslateOp().Set(Gf.Vec3d(*foot.tolist()))
            xf.AddOrientOp().Set(Gf.Quatf(rotation.GetQuat()))
        elif kind == "sphere":
            geom = UsdGeom.Sphere.Define(stage, prim_path)
            geom.CreateRadiusAttr(float(c["radius"]))
            UsdGeom.XformCommonAPI(geom).SetTranslate(Gf.Vec3d(*np.asarray(c["center"], float).reshape(-1)[:3].tolist()))
        else:
            continue
        geom.CreatePurposeAttr(UsdGeom.Tokens.guide)
        geom.GetPrim().CreateAttribute("kinema:collider", _token_type()).Set(kind)


def _token_type() -> Any:
    from pxr import Sdf

    return Sdf.ValueTypeNames.Token
