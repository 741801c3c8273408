"""Reading USD stages (`.usd`, `.usda`, `.usdc`, `.usdz`) with Pixar's `usd-core`:
`read_usd` gives a `LoadedTrajectory` in SI units of kinema's own USD export (its
`/World/particles`, `kinema:time`, own colours and springs back) or of another program's
stage (its first `UsdGeom.Points` prim, in the stage's `metersPerUnit`)."""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ._assemble import RawFrame, assemble
from ._h5md_checks import fail
from ._usd import MAGIC_CRATE as MAGIC_CRATE  # (moved to _usd, with MAGIC_TEXT: kept here by name)
from ._usd import MAGIC_TEXT as MAGIC_TEXT
from ._usd import _usd_reason, meters_per_unit_problem
from .h5md_reader import LoadedTrajectory
from .mesh_files import _open
from .mesh_files import check_layers as check_layers  # (a stage's layers, checked as a mesh's side files)
from .units import Scales, UnitWarning

#: The fewest time codes per second of a stage read (a time code of 11.6 days): fewer, and a
#: time code / timeCodesPerSecond overflows or loses the frames' order.
MIN_TIME_CODES_PER_SECOND = 1e-6


def read_usd(path: Path) -> LoadedTrajectory:
    """Read the USD stage `path`.

    kinema's own export (`/World` has `kinema:time`; see `usd_writer.write_usd`):
    `/World/particles` at time code k = frame k, its time `kinema:time` (s); `points`
    (m), `velocities` (m/s), `widths` / 2 (radii, m), `ids`, the primvars `mass`
    (kg), `species` and `collisionGroup` (the collision groups); the colours (`displayColor`, linear, back to sRGB) of the
    particles `kinema:colorIds` names, the others' being the speed colour map's (NaN:
    none); the springs (`kinema:springs`, id pairs); the spin of `/World/spheres` (its
    `orientationsf` and `angularVelocities`, degrees per second as rad/s). float32 values come back as the
    float64 of the float32. The colliders (guide meshes) are not read.

    Another stage: its first `UsdGeom.Points` prim (in the order of the stage's tree), a
    frame at each time sample of its `points` (one frame, at time 0, without any), its time
    the time code / `timeCodesPerSecond`; positions with the prim's transform, velocities
    (USD's are per second) with its rotation and scale, radii `widths` / 2 (m: × the cube
    root of the scale's volume factor), all × the stage's `metersPerUnit` (USD's fallback
    0.01, centimetres, with a `UnitWarning` where the stage does not say it); `ids` and
    the primvar `species` where it has them; the primvar `mass` only where the stage says
    `kilogramsPerUnit` (UsdPhysics), else no masses (a `UnitWarning` says so); no colours
    (its `displayColor` is not said to be the particles' own). A stage whose up axis is
    Y is turned to kinema's +z up (gravity along -z) as the mesh reader turns a mesh:
    (x, y, z) → (x, −z, y), exact.

    Raises `ImportError` naming `pip install usd-core` without it, and
    `TrajectoryFileError` naming `path`: not a stage usd-core opens, a layer it names
    (sublayer, reference, payload) that is not a regular file (`check_layers`), no Points
    prim, an attribute whose length is not the number of points, a `metersPerUnit` that is
    not finite and > 0, another stage's `timeCodesPerSecond` that is not finite and at least
    `MIN_TIME_CODES_PER_SECOND`."""
    try:
        from pxr import Tf, Usd, UsdGeom, UsdPhysics
    except ImportError:
        raise ImportError("reading USD needs the usd-core package: pip install usd-core (or kinema[usd])") from None
    try:
        stage = _open(path)
    except Tf.ErrorException as e:
        raise fail(path, f"not a USD stage that can be read ({_usd_reason(e)})") from None
    if stage is None:
        raise fail(path, "not a USD stage that can be read")
    world = stage.GetPrimAtPath("/World")
    clock = world.GetAttribute("kinema:time") if world else None
    own = bool(clock and clock.HasAuthoredValue())
    prim = stage.GetPrimAtPath("/World/particles") if own else next((p for p in stage.Traverse() if p.IsA(UsdGeom.Points)), None)
    if prim is None or not prim.IsA(UsdGeom.Points):
        where = "at /World/particles, where kinema writes its particles" if own else "(the particles kinema reads)"
        raise fail(path, f"holds no UsdGeom.Points prim {where}")
    points = UsdGeom.Points(prim)
    metres = UsdGeom.GetStageMetersPerUnit(stage)
    bad = meters_per_unit_problem(metres)
    if bad:
        raise fail(path, bad)
    said: list[str] = []  # what the UnitWarning says
    if not own and not UsdGeom.StageHasAuthoredMetersPerUnit(stage):
        said.append(f"the stage does not say its metersPerUnit: USD's fallback {metres!r} m (centimetres) is taken")
    mass_primvar = UsdGeom.PrimvarsAPI(points).GetPrimvar("mass")
    # kinema's masses are kg; another stage's only where it says its unit of mass
    kilograms = 1.0 if own else (UsdPhysics.GetStageKilogramsPerUnit(stage) if UsdPhysics.StageHasAuthoredKilogramsPerUnit(stage) else None)
    if mass_primvar and kilograms is None:
        said.append("its primvar mass is not read: the stage does not say its kilogramsPerUnit (UsdPhysics), so the masses' unit is unknown")
    # a +y-up stage (USD's fallback, Maya's, Blender's export option) is turned to kinema's +z
    # up as the mesh reader turns one (mesh_files.y_up_to_z_up: exact)
    y_up = UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    if said:
        warnings.warn(f"{path}: {'; '.join(said)}", UnitWarning, stacklevel=3)
    if own:
        codes = list(clock.GetTimeSamples())
        times: list[float | None] = [float(clock.Get(Usd.TimeCode(c))) for c in codes]
    else:
        codes = list(points.GetPointsAttr().GetTimeSamples())
        per_second = stage.GetTimeCodesPerSecond()
        if not (math.isfinite(per_second) and per_second >= MIN_TIME_CODES_PER_SECOND):
            raise fail(
                path,
                f"timeCodesPerSecond = {per_second!r} is invalid: it must be finite and at least {MIN_TIME_CODES_PER_SECOND:g} "
                "(a frame's time is its time code / timeCodesPerSecond, s)",
            )
        times = [c / per_second for c in codes]
        if not codes:
            codes, times = [None], [None]  # the default values: one frame, at time 0
    reading = _Reading(path, points, own, kilograms, Usd, UsdGeom)
    spheres = stage.GetPrimAtPath("/World/spheres") if own else None
    reading.spheres = UsdGeom.PointInstancer(spheres) if spheres and spheres.IsA(UsdGeom.PointInstancer) else None
    frames = [reading.frame(k, code, time) for k, (code, time) in enumerate(zip(codes, times, strict=True))]
    if y_up:
        for fr in frames:
            _turn_to_z_up(fr)
    springs = None
    if own:
        curves = stage.GetPrimAtPath("/World/springs")
        ends = curves.GetAttribute("kinema:springs") if curves else None
        springs = np.asarray(ends.Get(), dtype=np.int64).reshape(-1, 2) if ends and ends.HasAuthoredValue() else None
    scales = Scales(metres, 1.0, 1.0 if kilograms is None else kilograms, metres, f"the stage's metersPerUnit {metres!r}")
    out = assemble(path, frames, scales, creator="kinema" if own else None, springs=springs)
    if reading.colours:
        out.colors = np.full((out.positions.shape[1], 3), np.nan)
        for i, rgb in reading.colours.items():
            out.colors[np.searchsorted(out.ids, i)] = rgb
    return out


def _turn_to_z_up(fr: Any) -> None:
    """Frame `fr` of a +y-up stage in kinema's +z-up axes: positions, velocities and angular
    velocities by (x, y, z) → (x, −z, y), the +90° turn about x; orientations turned by it."""
    from ._quaternions import multiply
    from .mesh_files import y_up_to_z_up

    for name in ("positions", "velocities", "angular_velocities"):
        value = getattr(fr, name)
        if value is not None:
            setattr(fr, name, y_up_to_z_up(np.asarray(value, dtype=np.float64).reshape(-1, 3)))
    if fr.orientations is not None:
        half = np.sqrt(0.5)  # (cos 45°, sin 45° x): the turn as a unit quaternion, w first
        fr.orientations = multiply(np.array([half, half, 0.0, 0.0]), np.asarray(fr.orientations, dtype=np.float64))


class _Reading:
    """The frames of one Points prim, read one time code at a time; `colours`: the sRGB
    colour of each particle that has its own (by id), where it first appears."""

    def __init__(self, path: Path, points: Any, own: bool, kilograms: float | None, Usd: Any, UsdGeom: Any) -> None:
        self.path, self.points, self.own, self.Usd = path, points, own, Usd
        primvars = UsdGeom.PrimvarsAPI(points)
        self.mass = primvars.GetPrimvar("mass") if kilograms is not None else None
        self.species = primvars.GetPrimvar("species")
        self.groups = primvars.GetPrimvar("collisionGroup") if own else None  # kinema's collision groups
        self.display = points.GetDisplayColorPrimvar()
        marked = points.GetPrim().GetAttribute("kinema:colorIds") if own else None
        self.colour_ids = np.asarray(marked.Get(), dtype=np.int64) if marked and marked.HasAuthoredValue() else np.zeros(0, dtype=np.int64)
        self.colours: dict[int, np.ndarray] = {}
        self.xformable = UsdGeom.Xformable(points)
        self.constant = UsdGeom.Tokens.constant
        self.spheres: Any = None  # kinema's /World/spheres (a PointInstancer: the spin)

    def _values(self, attr: Any, code: Any, n: int | None, name: str, where: str, width: int = 1, constant: bool = False) -> np.ndarray | None:
        """The values of `attr` (an attribute, or a primvar: flattened through its indices)
        at `code` as a NumPy array of `n` rows (any number where `n` is None; a
        `constant` value stands for every point's), `None` where it has none."""
        if not attr or not attr.HasAuthoredValue():
            return None
        v = attr.ComputeFlattened(code) if hasattr(attr, "ComputeFlattened") else attr.Get(code)
        if v is None:
            return None
        a = np.array(v)
        a = a.reshape(-1, width) if width > 1 else a.reshape(-1)
        if constant and len(a) == 1 and n:
            a = np.repeat(a, n, axis=0)
        if n is not None and len(a) != n:
            raise fail(self.path, f"{where}: {name} has {len(a)} values for {n} points")
        return a

    def frame(self, k: int, code: float | None, time: float | None) -> RawFrame:
        Usd = self.Usd
        at = Usd.TimeCode.Default() if code is None else Usd.TimeCode(code)
        where = f"frame {k}" + ("" if code is None else f" (time code {code:g})")
        x = self._values(self.points.GetPointsAttr(), at, None, "points", where, 3)
        x = np.zeros((0, 3)) if x is None else x.astype(np.float64)
        n = len(x)
        v = self._values(self.points.GetVelocitiesAttr(), at, n, "velocities", where, 3)
        p = self.points
        widths = self._values(p.GetWidthsAttr(), at, n, "widths", where, constant=p.GetWidthsInterpolation() == self.constant)
        ids = self._values(p.GetIdsAttr(), at, n, "ids", where)
        masses = self._values(self.mass, at, n, "primvar mass", where, constant=self.mass.GetInterpolation() == self.constant) if self.mass else None
        species = (
            self._values(self.species, at, n, "primvar species", where, constant=self.species.GetInterpolation() == self.constant) if self.species else None
        )
        groups = (
            self._values(self.groups, at, n, "primvar collisionGroup", where, constant=self.groups.GetInterpolation() == self.constant) if self.groups else None
        )
        v = None if v is None or (n and np.isnan(v).all()) else v.astype(np.float64)  # (kinema writes NaN for unknown velocities)
        radii = None if widths is None else widths.astype(np.float64) / 2
        if not self.own:
            x, v, radii = self._placed(at, x, v, radii)
        if ids is not None and self.colour_ids.size:
            display = self._values(self.display, at, n, "displayColor", where, 3)
            mine = np.isin(ids, self.colour_ids)
            if display is not None:
                for i, rgb in zip(ids[mine].tolist(), display[mine], strict=True):
                    self.colours.setdefault(int(i), linear_to_srgb(rgb.astype(np.float64)))
        spin = self._spin(at, ids, n, where) if self.spheres is not None else {}
        return RawFrame(
            positions=x,
            where=where,
            ids=None if ids is None else ids.astype(np.int64),
            **spin,
            velocities=v,
            masses=None if masses is None else masses.astype(np.float64),
            radii=radii,
            species=None if species is None else np.array([str(s) for s in species], dtype=object),
            groups=None if groups is None else groups.astype(np.int64),
            time=time,
            step=k,
        )

    def _spin(self, at: Any, ids: np.ndarray | None, n: int, where: str) -> dict[str, np.ndarray]:
        """kinema's spin of a frame, from `/World/spheres` (`usd_writer._Spheres`): the
        orientations (`orientationsf`, else the half-precision `orientations`), w first, and
        the angular velocities (`angularVelocities`, degrees per second, as rad/s), one per
        point of the frame in the same order (its `ids` must be the points')."""
        s = self.spheres
        own_ids = self._values(s.GetIdsAttr(), at, n, "/World/spheres ids", where)
        if own_ids is not None and ids is not None and not np.array_equal(own_ids, ids):
            raise fail(
                self.path,
                f"{where}: /World/spheres has the ids {own_ids[:5].tolist()}... but /World/particles {ids[:5].tolist()}...: they must be the same particles",
            )
        out = {}
        full = s.GetOrientationsfAttr()
        q = self._values(full if full and full.HasAuthoredValue() else s.GetOrientationsAttr(), at, n, "/World/spheres orientations", where, 4)
        if q is not None:  # (numpy of Gf quaternions: i, j, k, w)
            q = q.astype(np.float64)[:, [3, 0, 1, 2]]
            out["orientations"] = q / np.linalg.norm(q, axis=1, keepdims=True) if len(q) else q
        w = self._values(s.GetAngularVelocitiesAttr(), at, n, "/World/spheres angularVelocities", where, 3)
        if w is not None:
            out["angular_velocities"] = np.radians(w.astype(np.float64))
        return out

    def _placed(self, at: Any, x: np.ndarray, v: np.ndarray | None, radii: np.ndarray | None) -> tuple:
        """Another stage's points in its world: the prim's local-to-world transform on the
        positions, its linear part on the velocities, the cube root of its volume factor on
        the radii (none of them where it is the identity)."""
        m = np.array(self.xformable.ComputeLocalToWorldTransform(at), dtype=np.float64)  # row vectors: x' = [x 1] m
        if np.array_equal(m, np.eye(4)):
            return x, v, radii
        linear = m[:3, :3]
        x = x @ linear + m[3, :3]
        v = None if v is None else v @ linear
        radii = None if radii is None else radii * abs(np.linalg.det(linear)) ** (1 / 3)
        return x, v, radii


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """Linear values in [0, 1] to sRGB-encoded ones (IEC 61966-2-1), the inverse of
    `_usd_colliders._srgb_to_linear`; clipped to [0, 1]."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.clip(np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055), 0.0, 1.0)
