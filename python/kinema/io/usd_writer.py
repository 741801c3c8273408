"""Pixar's USD (Blender, Houdini, Omniverse, usdview), written with the `usd-core` package:
the particles as one `UsdGeom.Points` prim with time samples (and the primvars Blender and
Houdini read), the springs as `UsdGeom.BasisCurves`, the colliders as rendered translucent
meshes, every one with a bound `UsdPreviewSurface` material.

The colliders' meshes and prims, and the sRGB to linear conversion of the colours, are in
`kinema.io._usd_colliders`."""

from __future__ import annotations

import errno
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ._cell import spring_columns
from ._files import FileWriteError, Frames, TrajectoryFileError, copy_into, os_errors_as_write_errors, private_folder, refuse_special_target
from ._usd import SUFFIXES  # the suffixes USD writes (kinema.io._usd, which the readers share)
from ._usd_colliders import COLLIDER_COLOR, COLLIDER_OPACITY, SPHERE_RINGS, SPHERE_SEGMENTS, _colliders, _srgb_to_linear, sphere_mesh


def write_usd(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    """Write `fr` to one USD stage at `path`; returns `[path]`.

    The stage: `upAxis` Z (kinema's gravity points along -z), `metersPerUnit` 1 (kinema
    is SI); frame k at time code k (k = 0 … F − 1; `startTimeCode` and `endTimeCode` the first
    and last frames with a live particle, 0 and F − 1 without births and deaths: see
    `_frame_range`), `timeCodesPerSecond` = `framesPerSecond` = the rate the frames were asked at
    (`_frame_rate`: `traj.fps`, 30 for `World.run(fps=30)`, which records frame k at k/30 s;
    else a common rate within 2 % of the recording's, else 1 / the median
    interval), so that a 3D application asking at whole frames, as Blender and Houdini
    do, gets each frame exactly (time codes t × rate, 1.0000000000000027, 2.0000000000000053,
    …, gave the previous frame in 172 of the fountain's 182 frames). The frames' own times (s,
    float64) are the time samples of `/World`'s `kinema:time`. `/World` (the default
    prim, an Xform) holds:

    - `/World/particles`, a `UsdGeom.Points`: `points` (m) and `velocities` (m/s:
      USD's velocities are in units per second, whatever the time codes) as a time sample per
      frame, float32 as USD's point arrays are; `widths` 2r (m), `ids` (int64, Houdini's
      `id`), the primvar `id` (int32: the ids again, as Blender's importer takes them; it
      drops `ids`; left out if an id is beyond int32), the primvar `mass` (kg) where the
      trajectory has masses, `species` (strings) where it has species names and
      `collisionGroup` (int32, each particle's collision group) where it has groups, constant.
      `displayColor` (vertex): each particle's own colour (`traj.colors`) where it has
      one, the others by speed as kinema's videos colour them (see `_Colours`), a time
      sample per frame unless all have their own. With births and deaths (`alive`) each
      time sample holds the particles alive at that frame only: `points`, `velocities`,
      `widths`, `ids` and every primvar are then all time-sampled, their length varying
      from frame to frame (0 for a frame with none), and `ids` tells which particle each
      point is. `kinema:colorIds` (int64, constant; where some particle has its own
      colour): the ids of the particles whose `displayColor` is their own colour, which
      kinema's reader gives back (the others' is the speed colour map's).
    - `/World/springs` where the trajectory has springs: a `UsdGeom.BasisCurves` of
      `linear` curves of 2 vertices (`curveVertexCounts` all 2), one per spring whose two
      ends are alive at the frame, its `points` the two particles' positions as a time
      sample per frame; `widths` half the smallest radius of their ends (m), grey as in
      kinema's videos, with the default purpose: a cloth's springs render. A spring whose
      ends are ids the trajectory does not hold is left out. `kinema:springs` (int64,
      constant): the ids at the two ends of each spring, a pair after pair (2 S values); a
      frame's curves are the springs among them whose two ends are alive, in that order.
    - `/World/spheres` where the trajectory has spin (angular velocities, orientations): a
      `UsdGeom.PointInstancer` of one prototype, `/World/spheres/prototypes/ball`, a unit
      UV sphere with texture coordinates (`primvars:st`) and stripes of two greys along its
      meridians (`displayColor`, uniform), so that a ball seen turning turns: per frame
      (time sample) `positions` (m), `scales` (r, r, r), `protoIndices` (all 0), `ids`,
      `velocities` (m/s), `angularVelocities` (degrees per second, as USD's schema has
      them) and the orientations, as `orientations` (quath, the attribute every reader
      knows, Blender's importer among them) and `orientationsf` (quatf, which USD prefers
      where both are there), identity where the trajectory has angular velocities but no
      orientations. In Blender the instancer's balls turn with the particles: give the
      prototype a material with an image texture (its UVs are there) to see a textured ball
      roll; hide `/World/particles`, whose point cloud draws spheres at the same places.
    - `/World/colliders`: a `UsdGeom.Mesh` per collider, `box_k` (its 8 corners and 6
      quads; open faces closed at the scene's extent), `plane_k` (one square quad in the
      plane, twice the scene's size wide, centred on the plane's point nearest the scene's
      centre), `sphere_k` (a UV sphere of 448 quads and 64 triangles, with its normals)
      and `mesh_k` (a triangle mesh's vertices and triangles as they are described, a
      closed one turned to face out), in world coordinates (m), facing out, with the
      default purpose (rendered), `displayColor` `COLLIDER_COLOR` and `displayOpacity`
      `COLLIDER_OPACITY` (translucent, as kinema's videos draw planes and meshes, so that
      what is inside shows) and `kinema:collider` naming the type. A moving collider (one with a `motion`) is described as added and carries a
      time-sampled `xformOp:transform`, its pose at each frame's time code (from the
      engine's motion, `collider_poses`), so that it moves in a 3D application as in
      kinema's videos.
    - `/World/materials`: `particles`, a `UsdPreviewSurface` whose `diffuseColor` is the
      prim's own `displayColor` (a `UsdPrimvarReader_float3`), bound to the particles, the
      springs and the spheres' ball; `colliders`, `COLLIDER_COLOR` at opacity
      `COLLIDER_OPACITY`, bound to every collider. usdview, Houdini and Omniverse render
      the colours; Blender's importer makes the colliders' material and the ball's (an
      Attribute node reading `displayColor`) but gives its point clouds no material, and
      keeps its scene's frame rate: `blend_writer.write_blend` makes the Blender scene.

    In Blender (5.0): File → Import → Universal Scene Description, then play: the Points
    prim becomes a point cloud whose positions follow the time samples, with the attributes
    `radius`, `velocity`, `id`, `mass`, `collisionGroup` and `displayColor` (not `species`: it
    takes no strings); the springs a Curves object; the colliders meshes with their material. Blender asks at
    time code = frame, and takes the frame range but not the rate nor the point cloud's
    material (`kinema export --format blend` sets both).
    In Houdini: a LOP network's Sublayer or a SOP `usdimport`. `on_frame(i)` is called
    after frame `i`.

    The suffix of `path` chooses the file: `.usd` or `.usdc` (binary), `.usda`
    (text), `.usdz` (the binary stage in a zip package, `UsdUtils.CreateNewUsdzPackage`);
    another is a `ValueError` listing them, before anything is written. A failure of the
    system (a name too long, a full disk) is a `FileWriteError` naming `path`, with
    `path` left as it was: the stage (and its package, checked whole) is built in a private
    folder of the system's temporary folder (`tempfile.gettempdir()`, `$TMPDIR`) and
    copied to a temporary name beside `path`, renamed over it when complete."""
    if path.suffix.lower() not in SUFFIXES:
        raise ValueError(f"path = {str(path)!r}: the suffix {path.suffix or '(none)'!r} is not a USD file's; allowed: {', '.join(SUFFIXES)}")
    try:
        from pxr import Gf, Sdf, Usd, UsdGeom, Vt
    except ImportError:
        raise ImportError("writing USD needs the usd-core package: pip install usd-core (or kinema[usd])") from None
    with os_errors_as_write_errors(path):
        return _write_stage(traj, fr, path, on_frame, (Gf, Sdf, Usd, UsdGeom, Vt))


def _write_stage(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any], pxr: tuple) -> list[Path]:
    # (ValueErrors before anything is written)
    rate = _frame_rate(fr.t, getattr(traj, "fps", None))
    parts = (_Colours(traj, fr), _species(traj, fr), spring_columns(traj, fr))
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
        _build_stage(traj, fr, path, staging, rate, parts, on_frame, pxr)
    return [path]


def _build_stage(traj: Any, fr: Frames, path: Path, staging: Path, rate: float, parts: tuple, on_frame: Callable[[int], Any], pxr: tuple) -> None:
    """Writes the stage of `fr` in the folder `staging` and copies it (or its .usdz
    package) to `path`; `parts`: the particles' colours, species and the springs'
    columns."""
    Gf, Sdf, Usd, UsdGeom, Vt = pxr
    where = f"in the temporary folder {staging.parent}, where the stage is built"  # (usd-core's failures are there)
    colours, species, pairs = parts
    try:
        package = path.suffix.lower() == ".usdz"  # a zip of a binary stage: written as .usdc, then packed
        tmp = staging / (path.stem + ".usdc" if package else path.name)
        stage = Usd.Stage.CreateNew(str(tmp))
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        stage.SetTimeCodesPerSecond(rate)
        stage.SetFramesPerSecond(rate)
        first, last = _frame_range(fr)
        stage.SetStartTimeCode(float(first))  # frame k at time code k, whatever the range
        stage.SetEndTimeCode(float(last))
        world = UsdGeom.Xform.Define(stage, "/World")
        stage.SetDefaultPrim(world.GetPrim())
        time = world.GetPrim().CreateAttribute("kinema:time", Sdf.ValueTypeNames.Double)
        for k in range(fr.n_frames):
            time.Set(float(fr.t[k]), Usd.TimeCode(float(k)))
        particles = _Particles(stage, fr, colours, species, pxr)
        springs = _Springs(stage, fr, pairs, pxr) if len(pairs) else None
        spheres = _Spheres(stage, fr, pxr) if fr.angular_velocities is not None or fr.orientations is not None else None
        for i in range(fr.n_frames):
            particles.write(i)
            if springs is not None:
                springs.write(i)
            if spheres is not None:
                spheres.write(i)
            on_frame(i)
        particles.finish()
        if springs is not None:
            springs.finish()
        if spheres is not None:
            spheres.finish(particles.lo, particles.hi)
        _colliders(stage, traj, fr, pxr)
        _bind_materials(stage, pxr)
        if not stage.GetRootLayer().Save():
            raise FileWriteError(errno.EIO, f"usd-core could not save the stage ({where})", str(path))
        if package:
            from pxr import UsdUtils

            packed = staging / path.name
            if not UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(tmp)), str(packed)) or not _whole_package(packed, tmp):
                raise FileWriteError(errno.EIO, f"usd-core could not make the .usdz package ({where})", str(path))
            tmp = packed
        del stage, particles, springs, spheres  # (its layer lets go of the file)
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


class _Particles:
    """`/World/particles`, a `UsdGeom.Points`, written one frame at a time (see write_usd).
    Without births and deaths the per-particle values are constant (one default value); with
    them, a time sample per frame of the live particles' values."""

    def __init__(self, stage: Any, fr: Frames, colours: _Colours, species: np.ndarray | None, pxr: tuple) -> None:
        Gf, Sdf, Usd, UsdGeom, Vt = pxr
        self.fr, self.colours, self.pxr = fr, colours, pxr
        self.prim = points = UsdGeom.Points.Define(stage, "/World/particles")
        primvars = UsdGeom.PrimvarsAPI(points)
        self.radii = fr.radii if fr.radii is not None else np.zeros(fr.n_particles)
        self.changes = fr.changes_count
        # name: (attribute, per-particle values (N, ...), Vt array type); the per-frame ones
        # (positions, velocities, colours) are written by write()
        self.values: dict[str, tuple[Any, np.ndarray, Any]] = {
            "widths": (points.CreateWidthsAttr(), (2.0 * self.radii).astype(np.float32), Vt.FloatArray),
            "ids": (points.CreateIdsAttr(), fr.ids.astype(np.int64), Vt.Int64Array),
        }
        if _fits_int32(fr.ids):  # Blender's importer takes int32 primvars, not the int64 ids
            attr = primvars.CreatePrimvar("id", Sdf.ValueTypeNames.IntArray, UsdGeom.Tokens.vertex)
            self.values["id"] = (attr, fr.ids.astype(np.int32), Vt.IntArray)
        if fr.masses is not None:
            attr = primvars.CreatePrimvar("mass", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex)
            self.values["mass"] = (attr, fr.masses.astype(np.float32), Vt.FloatArray)
        if species is not None:
            attr = primvars.CreatePrimvar("species", Sdf.ValueTypeNames.StringArray, UsdGeom.Tokens.vertex)
            self.values["species"] = (attr, species, lambda a: Vt.StringArray(a.tolist()))
        if fr.groups is not None:  # the collision groups: int32, as Blender's importer takes them
            attr = primvars.CreatePrimvar("collisionGroup", Sdf.ValueTypeNames.IntArray, UsdGeom.Tokens.vertex)
            self.values["collisionGroup"] = (attr, fr.groups.astype(np.int32), Vt.IntArray)
        if not self.changes:
            for attr, values, array in self.values.values():
                attr.Set(_vt(array, values, Vt))
        self.color = points.CreateDisplayColorPrimvar(UsdGeom.Tokens.vertex)
        if colours.has_own.any():  # which colours a reader gives back as the particles' own (the others are the speed map's)
            own_ids = fr.ids[colours.has_own].astype(np.int64)
            points.GetPrim().CreateAttribute("kinema:colorIds", Sdf.ValueTypeNames.Int64Array).Set(Vt.Int64Array.FromNumpy(own_ids))
        if not colours.per_frame and not self.changes:
            self.color.Set(Vt.Vec3fArray.FromNumpy(colours.at(0, np.arange(fr.n_particles))))
        self.positions, self.velocities = points.CreatePointsAttr(), points.CreateVelocitiesAttr()
        self.lo, self.hi = np.full(3, np.inf), np.full(3, -np.inf)

    def write(self, i: int) -> None:
        """The time samples of frame `i` (time code `i`)."""
        Gf, Sdf, Usd, UsdGeom, Vt = self.pxr
        code, live = Usd.TimeCode(float(i)), self.fr.live(i)
        x = self.fr.positions[i][live]
        self.positions.Set(Vt.Vec3fArray.FromNumpy(x.astype(np.float32)), code)
        self.velocities.Set(Vt.Vec3fArray.FromNumpy(self.fr.velocities[i][live].astype(np.float32)), code)
        if self.changes:
            for attr, values, array in self.values.values():
                attr.Set(_vt(array, values[live], Vt), code)
        if self.colours.per_frame or self.changes:
            self.color.Set(Vt.Vec3fArray.FromNumpy(self.colours.at(i, live)), code)
        if live.size:
            reach = self.radii[live][:, None]
            self.lo, self.hi = np.minimum(self.lo, (x - reach).min(axis=0)), np.maximum(self.hi, (x + reach).max(axis=0))

    def finish(self) -> None:
        Gf, Sdf, Usd, UsdGeom, Vt = self.pxr
        if np.all(self.lo <= self.hi):
            self.prim.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, self.lo)), Gf.Vec3f(*map(float, self.hi))]))


def _frame_range(fr: Frames) -> tuple[int, int]:
    """The stage's `startTimeCode` and `endTimeCode`: the first and last frames with a live
    particle, or 0 and F − 1 where every frame or none has one. Blender 5.0 aborts
    (`std::bad_alloc`, the whole process) exporting USD, or anything, from a point cloud of
    no points, which is what an emitter's frame 0 imports as; its importer makes the
    timeline the stage's range, so that exporting the animation (`export_animation`) runs
    over frames that have particles. The time samples still cover every frame, frame k at
    time code k, and kinema's reader gives every frame back."""
    some = np.flatnonzero(fr.alive.any(axis=1))
    if some.size == 0:
        return 0, max(fr.n_frames - 1, 0)
    return int(some[0]), int(some[-1])


def _vt(array: Any, values: np.ndarray, Vt: Any) -> Any:
    """`values` as the Vt array type `array` (numeric ones straight from numpy)."""
    return array.FromNumpy(np.ascontiguousarray(values)) if array in (Vt.FloatArray, Vt.IntArray, Vt.Int64Array) else array(values)


def _fits_int32(ids: np.ndarray) -> bool:
    return bool(ids.size == 0 or (ids.min() >= np.iinfo(np.int32).min and ids.max() <= np.iinfo(np.int32).max))


#: The colour map of the particles without their own colour: kinema's videos' default.
SPEED_COLORMAP = "viridis"


class _Colours:
    """The particles' `displayColor`, linear RGB as USD's colours are (sRGB decoded: a
    colour looks in a 3D application as it does in kinema's videos): a particle's own colour
    (`traj.colors`, sRGB in [0, 1], NaN: none) where it has one; the others by speed, |v|
    through `SPEED_COLORMAP` (as `kinema.render_frames`' default `color_by="speed"`)
    from the lowest to the highest speed of those particles over the run (m/s). A particle
    whose speed is unknown (NaN velocities) gets the low end's colour."""

    def __init__(self, traj: Any, fr: Frames) -> None:
        n = fr.n_particles
        own = getattr(traj, "colors", None)
        self.own = np.full((n, 3), np.nan)
        if own is not None:
            own = np.asarray(own, dtype=np.float64)
            if own.shape != (n, 3):
                raise ValueError(f"colors has shape {own.shape}; it must be ({n}, 3), one r g b per particle (NaN: none)")
            self.own = own
        self.has_own = np.all(np.isfinite(self.own), axis=1)
        self.own_linear = _srgb_to_linear(np.clip(np.where(self.has_own[:, None], self.own, 0.0), 0.0, 1.0))
        # with every particle's own colour, the colours do not change from frame to frame
        self.per_frame = not bool(self.has_own.all())
        self.speed = np.linalg.norm(fr.velocities, axis=2) if self.per_frame else None
        self.vmin = self.vmax = 0.0
        if self.speed is not None:
            counted = self.speed[fr.alive & ~self.has_own[None, :]]
            counted = counted[np.isfinite(counted)]
            if counted.size:
                self.vmin, self.vmax = float(counted.min()), float(counted.max())

    def at(self, i: int, columns: np.ndarray) -> np.ndarray:
        """(len(columns), 3) float32 linear RGB of those particles at frame `i`."""
        out = self.own_linear[columns]
        if self.speed is not None:
            by_speed = ~self.has_own[columns]
            if by_speed.any():
                v = self.speed[i, columns[by_speed]]
                v = np.where(np.isfinite(v), v, self.vmin)
                from .._core import colormap

                out[by_speed] = _srgb_to_linear(colormap(np.ascontiguousarray(v, dtype=np.float64), SPEED_COLORMAP, self.vmin, self.vmax) / 255.0)
        return out.astype(np.float32)


def _species(traj: Any, fr: Frames) -> np.ndarray | None:
    """The trajectory's species names (N,) as str, or None where it has none."""
    names = getattr(traj, "species", None)
    if names is None:
        return None
    a = np.asarray(names).astype(str)
    if a.shape != (fr.n_particles,):
        raise ValueError(f"species has shape {a.shape}; it must be ({fr.n_particles},), one name per particle")
    return a


#: The springs' colour, kinema's videos' (``_core.LINE_COLOR``), sRGB 8-bit.
SPRING_COLOR = (96, 96, 100)


class _Springs:
    """`/World/springs`, a `UsdGeom.BasisCurves` of linear curves, one of 2 vertices per
    spring whose two ends are alive at the frame, from one particle's centre to the other's
    (see write_usd)."""

    def __init__(self, stage: Any, fr: Frames, pairs: np.ndarray, pxr: tuple) -> None:
        Gf, Sdf, Usd, UsdGeom, Vt = pxr
        self.fr, self.pairs, self.pxr = fr, pairs, pxr
        self.prim = curves = UsdGeom.BasisCurves.Define(stage, "/World/springs")
        curves.CreateTypeAttr(UsdGeom.Tokens.linear)
        curves.CreateWrapAttr(UsdGeom.Tokens.nonperiodic)
        self.counts, self.points = curves.CreateCurveVertexCountsAttr(), curves.CreatePointsAttr()
        # the curves' ends as ids, which their points alone do not tell (two particles may meet)
        ends = Vt.Int64Array.FromNumpy(fr.ids[pairs].reshape(-1).astype(np.int64))
        curves.GetPrim().CreateAttribute("kinema:springs", Sdf.ValueTypeNames.Int64Array).Set(ends)
        self.changes = fr.changes_count
        if not self.changes:
            self.counts.Set(Vt.IntArray.FromNumpy(np.full(len(pairs), 2, dtype=np.int32)))
        # a quarter of the smallest particle diameter (the lines kinema's videos draw are thin)
        radii = fr.radii[pairs.reshape(-1)] if fr.radii is not None else np.zeros(0)
        radii = radii[radii > 0]
        self.width = 0.5 * float(radii.min()) if radii.size else None
        if self.width is not None:
            curves.CreateWidthsAttr(Vt.FloatArray([self.width]))
            curves.SetWidthsInterpolation(UsdGeom.Tokens.constant)
        grey = _srgb_to_linear(np.array(SPRING_COLOR) / 255.0)
        curves.CreateDisplayColorPrimvar(UsdGeom.Tokens.constant).Set(Vt.Vec3fArray([Gf.Vec3f(*map(float, grey))]))
        self.lo, self.hi = np.full(3, np.inf), np.full(3, -np.inf)

    def write(self, i: int) -> None:
        """The time samples of frame `i` (time code `i`)."""
        Gf, Sdf, Usd, UsdGeom, Vt = self.pxr
        code, alive = Usd.TimeCode(float(i)), self.fr.alive[i]
        pairs = self.pairs[alive[self.pairs[:, 0]] & alive[self.pairs[:, 1]]] if self.changes else self.pairs
        x = self.fr.positions[i][pairs.reshape(-1)]
        self.points.Set(Vt.Vec3fArray.FromNumpy(x.astype(np.float32)), code)
        if self.changes:
            self.counts.Set(Vt.IntArray.FromNumpy(np.full(len(pairs), 2, dtype=np.int32)), code)
        if len(x):
            self.lo, self.hi = np.minimum(self.lo, x.min(axis=0)), np.maximum(self.hi, x.max(axis=0))

    def finish(self) -> None:
        Gf, Sdf, Usd, UsdGeom, Vt = self.pxr
        if np.all(self.lo <= self.hi):
            reach = 0.5 * (self.width or 0.0)
            lo, hi = self.lo - reach, self.hi + reach
            self.prim.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))]))


#: The two greys of a ball's stripes (sRGB 8-bit), by meridian: its turning shows.
BALL_STRIPES = ((220, 220, 220), (60, 60, 60))


class _Spheres:
    """`/World/spheres`, a `UsdGeom.PointInstancer` of a textured unit ball placed, scaled
    and turned as each particle alive at the frame (see write_usd)."""

    def __init__(self, stage: Any, fr: Frames, pxr: tuple) -> None:
        Gf, Sdf, Usd, UsdGeom, Vt = pxr
        self.fr, self.pxr = fr, pxr
        self.prim = instancer = UsdGeom.PointInstancer.Define(stage, "/World/spheres")
        # the prototype beneath the instancer, as USD advises: drawn only where it is instanced
        UsdGeom.Scope.Define(stage, "/World/spheres/prototypes")
        ball = UsdGeom.Mesh.Define(stage, "/World/spheres/prototypes/ball")
        points, faces, st, stripes = ball_mesh()
        ball.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points.astype(np.float32)))
        ball.CreateFaceVertexCountsAttr(Vt.IntArray([len(f) for f in faces]))
        ball.CreateFaceVertexIndicesAttr(Vt.IntArray([int(i) for f in faces for i in f]))
        ball.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(points.astype(np.float32)))
        ball.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
        ball.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        ball.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(-1.0, -1.0, -1.0), Gf.Vec3f(1.0, 1.0, 1.0)]))
        primvars = UsdGeom.PrimvarsAPI(ball)
        primvars.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.faceVarying).Set(Vt.Vec2fArray.FromNumpy(st.astype(np.float32)))
        grey = _srgb_to_linear(np.array(BALL_STRIPES, dtype=np.float64) / 255.0)[stripes]
        ball.CreateDisplayColorPrimvar(UsdGeom.Tokens.uniform).Set(Vt.Vec3fArray.FromNumpy(grey.astype(np.float32)))
        instancer.CreatePrototypesRel().SetTargets([ball.GetPath()])
        self.attrs = {
            "positions": instancer.CreatePositionsAttr(),
            "scales": instancer.CreateScalesAttr(),
            "protoIndices": instancer.CreateProtoIndicesAttr(),
            "ids": instancer.CreateIdsAttr(),
            "velocities": instancer.CreateVelocitiesAttr(),
            "angularVelocities": instancer.CreateAngularVelocitiesAttr(),
            "orientations": instancer.CreateOrientationsAttr(),
            "orientationsf": instancer.CreateOrientationsfAttr(),
        }
        self.radii = fr.radii if fr.radii is not None else np.zeros(fr.n_particles)

    def write(self, i: int) -> None:
        """The time samples of frame `i` (time code `i`)."""
        Gf, Sdf, Usd, UsdGeom, Vt = self.pxr
        fr, code, live = self.fr, Usd.TimeCode(float(i)), self.fr.live(i)
        q = fr.orientations[i][live] if fr.orientations is not None else np.tile([1.0, 0.0, 0.0, 0.0], (live.size, 1))
        omega = fr.angular_velocities[i][live] if fr.angular_velocities is not None else np.zeros((live.size, 3))
        # Vt's quaternion arrays from NumPy take (i, j, k, w): the imaginary part first
        ijkw = np.ascontiguousarray(q[:, [1, 2, 3, 0]])
        values = {
            "positions": Vt.Vec3fArray.FromNumpy(fr.positions[i][live].astype(np.float32)),
            "scales": Vt.Vec3fArray.FromNumpy(np.repeat(self.radii[live][:, None], 3, axis=1).astype(np.float32)),
            "protoIndices": Vt.IntArray.FromNumpy(np.zeros(live.size, dtype=np.int32)),
            "ids": Vt.Int64Array.FromNumpy(fr.ids[live].astype(np.int64)),
            "velocities": Vt.Vec3fArray.FromNumpy(fr.velocities[i][live].astype(np.float32)),
            "angularVelocities": Vt.Vec3fArray.FromNumpy(np.degrees(omega).astype(np.float32)),
            "orientations": Vt.QuathArray.FromNumpy(ijkw.astype(np.float16)),
            "orientationsf": Vt.QuatfArray.FromNumpy(ijkw.astype(np.float32)),
        }
        for name, value in values.items():
            self.attrs[name].Set(value, code)

    def finish(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """The instancer's extent: the particles' (`_Particles`' `lo`, `hi`, m)."""
        Gf, Sdf, Usd, UsdGeom, Vt = self.pxr
        if np.all(lo <= hi):
            self.prim.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))]))


def ball_mesh() -> tuple[np.ndarray, list[list[int]], np.ndarray, np.ndarray]:
    """The unit ball of `_Spheres`: a UV sphere as `sphere_mesh` makes it (its points,
    its faces counter-clockwise seen from outside), with its texture coordinates per face
    vertex (u = longitude / 2π, v = 1 − colatitude / π: an equirectangular image wraps it
    once) and the stripe of each face (0 or 1 by longitude segment, for `BALL_STRIPES`)."""
    points, faces = sphere_mesh(np.zeros(3), 1.0)
    m, rings = SPHERE_SEGMENTS, SPHERE_RINGS
    st, stripes = [], []
    # sphere_mesh's faces: m north triangles, (rings - 2) × m quads, m south triangles
    for k in range(m):
        st += [((k + 0.5) / m, 1.0), (k / m, 1 - 1 / rings), ((k + 1) / m, 1 - 1 / rings)]
        stripes.append(k % 2)
    for j in range(rings - 2):
        for k in range(m):
            top, bottom = 1 - (j + 1) / rings, 1 - (j + 2) / rings
            st += [(k / m, top), (k / m, bottom), ((k + 1) / m, bottom), ((k + 1) / m, top)]
            stripes.append(k % 2)
    for k in range(m):
        st += [((k + 0.5) / m, 0.0), ((k + 1) / m, 1 / rings), (k / m, 1 / rings)]
        stripes.append(k % 2)
    return points, faces, np.array(st, dtype=np.float64), np.array(stripes, dtype=np.int64)


def _whole_package(packed: Path, layer: Path) -> bool:
    """Whether the .usdz `packed` is a whole zip archive holding the stage `layer` as it
    was saved (its size, every member's CRC): usd-core reports a package as made though a
    write of it failed."""
    import zipfile

    try:
        with zipfile.ZipFile(packed) as z:
            sizes = {info.filename: info.file_size for info in z.infolist()}
            return sizes.get(layer.name) == layer.stat().st_size and z.testzip() is None
    except (OSError, EOFError, zipfile.BadZipFile, ValueError):
        return False


def _frame_rate(t: np.ndarray, asked: Any = None) -> float:
    """Frames per second of the stage's time codes: the rate the frames were asked at
    where the trajectory says it (`Trajectory.fps`, `World.run(fps=)`, kept in kinema's
    H5MD) and the recording's rate, 1 / the median interval, is its rounding to whole steps
    (`render.playback_rate`: 30 for `fps=30`; an older kinema recorded every 33 steps of
    1 ms, 30.30 a second); else the common rate (24, 25, 30, 50, 60) within 2 % of the recording's;
    else the recording's. A rate within 1e-9 of a fraction of denominator up to 1001 is
    written as it (25, not 24.99999999999998; 30000/1001). 24 (USD's default) for a single
    frame without an asked rate."""
    from ..render.video import playback_rate

    if t.size >= 2:
        step = float(np.median(np.diff(t)))
        if not (np.isfinite(step) and step > 0):
            raise ValueError(f"t: the frames' times must increase to give USD a frame rate (median interval {step!r} s)")
    elif not (isinstance(asked, (int, float, np.floating, np.integer)) and np.isfinite(asked) and asked > 0):
        return 24.0
    rate = float(playback_rate(t, asked)[0])
    from fractions import Fraction

    near = Fraction(rate).limit_denominator(1001)
    return float(near) if abs(float(near) - rate) <= 1e-9 * rate else rate


def _material(stage: Any, path: str, pxr: tuple, colour: Any = None, opacity: float | None = None) -> Any:
    """A `UsdShade.Material` at `path` whose surface is a `UsdPreviewSurface`: its
    `diffuseColor` `colour` (linear RGB), or where `colour` is None the prim's own
    `displayColor` through a `UsdPrimvarReader_float3` (Blender's importer makes it an
    Attribute node reading `displayColor`); `opacity` where given."""
    from pxr import UsdShade

    Gf, Sdf, Usd, UsdGeom, Vt = pxr
    material = UsdShade.Material.Define(stage, path)
    surface = UsdShade.Shader.Define(stage, f"{path}/surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    diffuse = surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f)
    if colour is None:
        reader = UsdShade.Shader.Define(stage, f"{path}/displayColor")
        reader.CreateIdAttr("UsdPrimvarReader_float3")
        reader.CreateInput("varname", Sdf.ValueTypeNames.Token).Set("displayColor")
        reader.CreateInput("fallback", Sdf.ValueTypeNames.Float3).Set(Gf.Vec3f(0.5, 0.5, 0.5))
        diffuse.ConnectToSource(reader.CreateOutput("result", Sdf.ValueTypeNames.Float3))
    else:
        diffuse.Set(Gf.Vec3f(*map(float, colour)))
    surface.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.5)
    if opacity is not None:
        surface.CreateInput("opacity", Sdf.ValueTypeNames.Float).Set(float(opacity))
    material.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    return material


def _bind_materials(stage: Any, pxr: tuple) -> None:
    """`/World/materials`: `particles` (each prim's own `displayColor`), bound to the
    particles, the springs and the spheres' ball; `colliders` (`COLLIDER_COLOR` at
    `COLLIDER_OPACITY`), bound to every collider (see write_usd)."""
    from pxr import UsdShade

    Gf, Sdf, Usd, UsdGeom, Vt = pxr
    UsdGeom.Scope.Define(stage, "/World/materials")
    own = _material(stage, "/World/materials/particles", pxr)
    for path in ("/World/particles", "/World/springs", "/World/spheres/prototypes/ball"):
        prim = stage.GetPrimAtPath(path)
        if prim:
            UsdShade.MaterialBindingAPI.Apply(prim).Bind(own)
    colliders = stage.GetPrimAtPath("/World/colliders")
    if colliders and colliders.GetChildren():
        grey = _srgb_to_linear(np.array(COLLIDER_COLOR) / 255.0)
        shared = _material(stage, "/World/materials/colliders", pxr, grey, COLLIDER_OPACITY)
        for prim in colliders.GetChildren():
            UsdShade.MaterialBindingAPI.Apply(prim).Bind(shared)
