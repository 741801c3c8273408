"""Reading triangle meshes from files for `kinema.Mesh`: OBJ, STL, PLY and glTF (.gltf, .glb)
through `trimesh`, USD (.usd, .usda, .usdc, .usdz) through Pixar's `usd-core` (`pxr`).

`read_mesh(path)` gives the file's vertices (V, 3) float64, in metres with +z up (kinema's
axes), and its triangles (F, 3) int64: polygons (quads, n-gons) are cut into fans
(v0, vk, vk+1), a file of several meshes gives all of them, concatenated, each placed by its
node's or prim's transform. Vertices at exactly the same coordinates are made one (the first
keeps its place in the file's order, so a file without such duplicates keeps its vertex order):
an STL file stores every triangle's corners apart, and a UV seam splits a vertex in two; for a
collider they are one point, and only a surface whose triangles share their vertices is known
to be closed. Faces left with a repeated vertex by that (they had no area) are dropped.

Up axes. kinema's gravity points along −z: +z is up. glTF and USD say which way is up, and
are read so: glTF's +y is up by its specification (2.0, §3.4: "+Y is up"), USD's the stage's
`upAxis` (Y or Z). OBJ, STL and PLY carry no axis: `up_axis` says it, "z" (the default) or
"y" (Blender's OBJ export, Maya, Unity, three.js). A +y-up file is turned so that its +y is
+z, a right-handed +90° turn about x: (x, y, z) → (x, −z, y). Blender's OBJ exporter writes
a Blender point (x, y, z) as (x, z, −y) (forward −Z, up +Y, its defaults), so reading that
file with up_axis="y" gives back (x, y, z), exactly (a permutation and a sign: no rounding).

Side files. A file a mesh names is checked as the mesh file is, before it is opened: a glTF
buffer (its `uri`; a `data:` URI is in the file) and a USD layer's sublayers, references and
payloads must be regular files (not a FIFO, a device, a folder) of at most
`MAX_MESH_FILE_BYTES`, and a glTF buffer's declared `byteLength` at most its file's size. An
OBJ's `mtllib` (materials) is not read at all: a collider has no material.

A refused file is a `ValueError` of one line: `file = '<path>' is invalid: <why>` (no such
file, a directory, a FIFO or a device, a file over `MAX_MESH_FILE_BYTES`, a format not read (the
list of those read), a file the format's reader cannot read, one with no triangle, a face's
vertex index outside 0 … V − 1, a side file refused as above (named with who names it), a USD
stage's `metersPerUnit` not finite and > 0).
"""

from __future__ import annotations

import os
import stat
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ._usd import MAGIC_CRATE, MAGIC_TEXT, SUFFIXES

#: Memory a triangle takes while a mesh file is read (trimesh's arrays, the merge of equal
#: vertices), bytes, at the peak: measured 760 for a binary STL floor of 2·10⁶ triangles
#: (1.6 GB); the engine then keeps about 100 (`kinema::collide::mesh::BYTES_PER_TRIANGLE`).
MESH_READ_BYTES = 800

#: The up axes a file may be read with (`up_axis`): kinema's own, and the common other one.
UP_AXES = ("z", "y")
#: The formats that say their own up axis (glTF by its specification, USD by its stage's
#: upAxis); `up_axis` is for the others.
OWN_AXIS = ("glTF", "USD")

#: The formats read, with the suffixes that name them (the one home of this list).
MESH_FORMATS = {
    "OBJ": (".obj",),
    "STL": (".stl",),
    "PLY": (".ply",),
    "glTF": (".gltf", ".glb"),
    "USD": (".usd", ".usda", ".usdc", ".usdz"),
}


#: The largest mesh file, and the largest file one names (a glTF buffer, a USD layer), read: 1 GiB
#: (tens of millions of triangles; a collider's mesh is far smaller). Refused before reading.
MAX_MESH_FILE_BYTES = 1 << 30


class SideFileError(ValueError):
    """A file a mesh file names (a glTF buffer, a USD sublayer) that is refused; its message
    says which file and who names it (`read_mesh` puts it after the mesh file's name)."""


def checked_file(path: str | os.PathLike, what: str) -> int:
    """The size of `path`, a file named by `what` (words: "the glTF buffer 'x.bin' named by
    buffers[0].uri"), checked without opening it: a regular file (followed through links) of
    at most `MAX_MESH_FILE_BYTES`; else a `SideFileError` of one line."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise SideFileError(f"{what} does not exist ({path})") from None
    except OSError as e:
        raise SideFileError(f"{what} cannot be read ({e.strerror or e})") from None
    if not stat.S_ISREG(st.st_mode):
        from ._files import special_kind

        kind = "a directory" if stat.S_ISDIR(st.st_mode) else f"a {special_kind(st.st_mode) or 'special file'}"
        raise SideFileError(f"{what} is {kind}, not a regular file ({path})")
    if st.st_size > MAX_MESH_FILE_BYTES:
        raise SideFileError(f"{what} holds {st.st_size} bytes; a mesh's files are read up to {MAX_MESH_FILE_BYTES} bytes (1 GiB)")
    return st.st_size


def mesh_format(path: str | os.PathLike) -> str | None:
    """The format `path` names by its suffix (a key of `MESH_FORMATS`), or None."""
    suffix = Path(path).suffix.lower()
    return next((name for name, suffixes in MESH_FORMATS.items() if suffix in suffixes), None)


def formats_text() -> str:
    """The formats read, in words, as a refusal names them."""
    return ", ".join(f"{name} ({', '.join(s)})" for name, s in MESH_FORMATS.items())


def y_up_to_z_up(vertices: np.ndarray) -> np.ndarray:
    """The points (V, 3) of a +y-up file in kinema's +z-up axes: (x, y, z) → (x, −z, y), the
    right-handed +90° turn about x that takes +y to +z (and +z to −y). Exact: no rounding."""
    v = np.asarray(vertices, dtype=np.float64)
    return np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1) + 0.0  # (−0.0 + 0.0 = 0.0)


def check_up_axis(value: object, name: str = "up_axis") -> str | None:
    """`value` ("z", "y", upper case too, or None: the file's own or z) as "z", "y" or None; else a
    `ValueError` naming `name`."""
    if value is None:
        return None
    if isinstance(value, str) and value.strip().lower() in UP_AXES:
        return value.strip().lower()
    raise ValueError(f'{name} = {value!r} is invalid: use "z" (+z is up, kinema\'s own) or "y" (+y is up: Blender\'s OBJ export, glTF)')


def read_mesh(path: str | os.PathLike, name: str = "file", up_axis: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The vertices (V, 3) float64 and triangles (F, 3) int64 of the mesh file `path`, in
    kinema's axes: `read_mesh_axis`'s first two."""
    vertices, faces, _ = read_mesh_axis(path, name, up_axis)
    return vertices, faces


def read_mesh_axis(path: str | os.PathLike, name: str = "file", up_axis: str | None = None) -> tuple[np.ndarray, np.ndarray, str]:
    """The vertices (V, 3) float64 and triangles (F, 3) int64 of the mesh file `path` (see
    the module doc), in kinema's axes (+z up); `name` is the parameter a refusal names.

    `up_axis`: the file's up axis, "z" or "y", for a format that does not say it (OBJ, STL,
    PLY; None: "z"). glTF (+y up) and USD (its stage's upAxis) say theirs and are read by it;
    an `up_axis` given for them that disagrees is a `ValueError` (it would be a second turn).
    The third value is the up axis the file was read with, "z" or "y"."""
    path = Path(path)
    up_axis = check_up_axis(up_axis)

    def refuse(why: str) -> ValueError:
        return ValueError(f"{name} = {str(path)!r} is invalid: {why}")

    fmt = mesh_format(path)
    if fmt is None:
        said = f"'{path.suffix}'" if path.suffix else "(no suffix)"
        raise refuse(f"unknown mesh format {said}; the formats read are {formats_text()}")
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        where = "" if path.is_absolute() else f" (looked in {os.getcwd()})"
        raise refuse(f"no such file{where}") from None
    except OSError as e:
        raise refuse(f"cannot be read ({e.strerror or e})") from None
    if stat.S_ISDIR(mode):
        raise refuse(f"is a directory, not a mesh file ({formats_text()})")
    if not stat.S_ISREG(mode):
        from ._files import special_kind

        raise refuse(f"is not a regular file (a {special_kind(mode) or 'special file'}); a mesh is a file")
    try:
        checked_file(path, "the file")
    except SideFileError as e:
        raise refuse(str(e).removeprefix("the file ")) from None
    try:
        if fmt == "USD":
            vertices, faces, own = _read_usd(path, refuse)
        else:
            vertices, faces = _read_trimesh(path, fmt, refuse)
            own = "y" if fmt == "glTF" else None
        return _placed(path, fmt, vertices, faces, own, up_axis, refuse)
    except MemoryError:
        raise MemoryError(
            f"{name} = {str(path)!r}: reading this mesh ({os.stat(path).st_size} bytes) needs more memory than is available "
            f"(about {MESH_READ_BYTES} B per triangle while a mesh file is read and merged)"
        ) from None


def _placed(path: Path, fmt: str, vertices: Any, faces: Any, own: str | None, up_axis: str | None, refuse: Any) -> tuple[np.ndarray, np.ndarray, str]:
    """The mesh read from `path` (format `fmt`) in kinema's axes, its vertices merged and
    checked (the end of `read_mesh_axis`): `own` the up axis the file says, `up_axis` the one
    given."""
    if own is not None and up_axis is not None and up_axis != own:
        said = "by the glTF specification" if fmt == "glTF" else "by its stage's upAxis"
        raise ValueError(
            f"up_axis = {up_axis!r} is invalid for {path}: a {fmt} file says its own up axis (+{own} {said}) and is read "
            f"by it, turned to kinema's +z up; leave up_axis out (it is for OBJ, STL and PLY, which say none)"
        )
    axis = own or up_axis or "z"
    if axis == "y":
        vertices = y_up_to_z_up(np.asarray(vertices, dtype=np.float64).reshape(-1, 3))
    vertices, faces = _merged(vertices, faces)
    if len(faces) == 0:
        raise refuse("it holds no triangle (a mesh collider needs faces; a point cloud or a set of lines has none)")
    bad = ~np.isfinite(vertices)
    if bad.any():
        v, k = (int(i) for i in np.argwhere(bad)[0])
        raise refuse(f"its vertex {v} has the coordinate {vertices[v, k]!r}; a mesh's vertices must be finite")
    return vertices, faces, axis


def _merged(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One vertex for each set of vertices of exactly equal coordinates (in the order of their
    first appearance; −0.0 is 0.0), the faces re-indexed, faces with a repeated vertex dropped."""
    vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3) + 0.0  # -0.0 + 0.0 = 0.0
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(vertices) == 0:
        return vertices, faces[:0]
    _, first, inverse = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    order = np.argsort(first, kind="stable")  # the unique rows by first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    kept = vertices[first[order]]
    faces = rank[inverse[faces]]
    whole = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    return kept, faces[whole]


def fan(counts: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """The triangles (F, 3) of polygons given as their vertex counts and their vertex indices
    one after the other (USD's faceVertexCounts and faceVertexIndices, OBJ's faces): the fan
    (v0, vk, vk+1), k = 1 … n − 2, of each (a convex polygon's triangulation)."""
    counts = np.asarray(counts, dtype=np.int64).reshape(-1)
    indices = np.asarray(indices, dtype=np.int64).reshape(-1)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    per = np.maximum(counts - 2, 0)
    poly = np.repeat(np.arange(len(counts)), per)
    k = np.arange(int(per.sum())) - np.repeat(np.cumsum(per) - per, per) + 1  # 1 … n − 2 in each polygon
    s = starts[poly]
    return np.stack([indices[s], indices[s + k], indices[s + k + 1]], axis=1)


def _read_trimesh(path: Path, fmt: str, refuse: Any) -> tuple[np.ndarray, np.ndarray]:
    """OBJ, STL, PLY, glTF through trimesh, as the file has them (`process=False`: no vertex
    merged, reordered or dropped by trimesh; a scene of several meshes concatenated with its
    nodes' transforms by `force="mesh"`). The file is read here (it was checked to be a
    regular file); an OBJ is decoded as UTF-8, else Latin-1 (a comment in another encoding
    is no reason to refuse its geometry), its `mtllib` not followed; a glTF's buffers are
    checked (`_check_gltf_buffers`) and read through `_CheckedResolver`. A face's vertex
    index outside 0 … V − 1 (PLY's −1 would be taken as the last vertex) is refused."""
    try:
        import trimesh
    except ImportError:
        raise ImportError(f"reading {fmt} meshes needs the trimesh package: pip install trimesh") from None
    import io

    try:
        with open(path, "rb") as f:
            data = f.read(MAX_MESH_FILE_BYTES + 1)
    except OSError as e:
        raise refuse(f"cannot be read ({e.strerror or e})") from None
    kwargs: dict[str, Any] = {}
    if fmt == "OBJ":
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            text = data.decode("latin-1")  # (every byte is a Latin-1 character; OBJ's numbers and keywords are ASCII)
        data = text.encode("utf-8")
        kwargs["skip_materials"] = True
    try:
        if fmt == "glTF":
            _check_gltf_buffers(path, data)
        resolver = _checked_resolver(path)
        loaded = trimesh.load(io.BytesIO(data), file_type=path.suffix.lower().lstrip("."), force="mesh", process=False, resolver=resolver, **kwargs)
    except SideFileError as e:
        raise refuse(str(e)) from None
    except Exception as e:  # trimesh's parsers raise what their input makes them raise
        text = str(e).strip().splitlines()
        raise refuse(f"cannot be read as {fmt} (trimesh: {type(e).__name__}{': ' + text[0] if text else ''})") from None
    vertices = np.asarray(getattr(loaded, "vertices", np.zeros((0, 3))), dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
    out = (faces < 0) | (faces >= len(vertices))
    if out.any():
        f, k = (int(i) for i in np.argwhere(out)[0])
        raise refuse(
            f"its face {f} has the vertex index {int(faces[f, k])}; a face's vertex indices are 0 … {len(vertices) - 1} (the file has {len(vertices)} vertices)"
        )
    return vertices, faces


def _checked_resolver(path: Path) -> Any:
    """A trimesh resolver of the files beside `path` that checks each (`checked_file`) before
    reading it: a FIFO would block the read, a device never end it."""
    from trimesh.resolvers import FilePathResolver

    class _CheckedResolver(FilePathResolver):
        def get(self, name: str) -> bytes:
            target = self.absolute(name)
            checked_file(target, f"the file {name!r} named by {path.name}")
            with open(target, "rb") as f:
                return f.read(MAX_MESH_FILE_BYTES + 1)

    return _CheckedResolver(str(path))


def _check_gltf_buffers(path: Path, data: bytes) -> None:
    """Each buffer of the glTF (`.gltf` JSON or `.glb`'s JSON chunk) `data` that names a file
    (a `uri` not `data:`): `checked_file`, and its declared `byteLength` at most the file's
    size. Nothing is read here; a file trimesh cannot parse is left to it."""
    import json
    import struct

    try:
        if data[:4] == b"glTF":
            length, kind = struct.unpack("<II", data[12:20])
            if kind != 0x4E4F534A:  # "JSON"
                return
            tree = json.loads(data[20 : 20 + length])
        else:
            tree = json.loads(data)
    except (ValueError, struct.error):
        return
    buffers = tree.get("buffers") if isinstance(tree, dict) else None
    for k, buffer in enumerate(buffers if isinstance(buffers, list) else []):
        uri = buffer.get("uri") if isinstance(buffer, dict) else None
        if not isinstance(uri, str) or uri.startswith("data:"):
            continue
        from urllib.parse import unquote

        what = f"the glTF buffer {uri!r} (buffers[{k}].uri)"
        size = checked_file(path.parent / unquote(uri), what)
        declared = buffer.get("byteLength")
        if not isinstance(declared, int) or isinstance(declared, bool) or not 0 <= declared <= size:
            raise SideFileError(
                f"buffers[{k}].byteLength = {declared!r} is invalid: {what} holds {size} bytes (a byteLength is an integer 0 … the file's size)"
            )


def _open(path: Path) -> Any:
    """The stage of `path`, its layers checked (`check_layers`), for both USD readers (meshes
    here, particles in `read_usd`). usd-core tells a layer's format by its suffix only, so a file
    named otherwise (known by its first bytes) is read into an anonymous layer of its format."""
    from pxr import Sdf, Usd

    from ._h5md_checks import fail

    if path.suffix.lower() in SUFFIXES:
        root = Sdf.Layer.FindOrOpen(str(path))  # (the root layer alone: nothing it names is opened)
        if root is None:
            return None
        check_layers(path, root, path.parent)
        return Usd.Stage.Open(root)
    with open(path, "rb") as f:
        head = f.read(8)
    kind = "usdc" if head.startswith(MAGIC_CRATE) else "usda" if head.startswith(MAGIC_TEXT) else None
    if kind is None:
        raise fail(path, f"not a USD stage: neither a binary nor a text layer by its first bytes, and not named {', '.join(SUFFIXES)}")
    layer = Sdf.Layer.CreateAnonymous(f"{path.stem}.{kind}")
    if not layer.Import(str(path)):
        raise fail(path, f"not a USD stage that can be read (usd-core could not read it as {kind})")
    check_layers(path, layer, path.parent)
    return Usd.Stage.Open(layer)


def check_layers(path: Path, layer: Any, folder: Path, seen: set[str] | None = None) -> None:
    """Every layer `layer` names (sublayers, references, payloads), and those they name, is a
    regular file of at most `mesh_files.MAX_MESH_FILE_BYTES`, checked before the stage is
    composed (which would open them: a FIFO blocks the reader, a device never ends); else a
    `TrajectoryFileError` naming `path`, the layer and who names it. `folder`: where `layer`'s
    relative paths start. Paths inside a .usdz package are its own (read from the zip)."""
    from pxr import Ar, Sdf

    from ._h5md_checks import fail

    seen = set() if seen is None else seen
    for asset in layer.GetCompositionAssetDependencies():
        if not asset or Ar.IsPackageRelativePath(asset):
            continue
        target = Path(asset) if os.path.isabs(asset) else folder / asset
        key = os.path.realpath(target)
        if key in seen:
            continue
        seen.add(key)
        named_by = "the stage" if layer.anonymous or Path(layer.realPath) == Path(path).resolve() else Path(layer.realPath).name
        try:
            checked_file(target, f"the layer {asset!r} named by {named_by} (a sublayer, reference or payload)")
        except SideFileError as e:
            raise fail(path, str(e)) from None
        if target.suffix.lower() == ".usdz":
            continue  # (its own layers are inside the zip)
        sub = Sdf.Layer.FindOrOpen(str(target))
        if sub is not None:
            check_layers(path, sub, target.parent, seen)


def _read_usd(path: Path, refuse: Any) -> tuple[np.ndarray, np.ndarray]:
    """Every `UsdGeom.Mesh` prim of the stage but guides (its purpose `guide`: kinema's own
    export drew its colliders so) and kinema's exported colliders (`kinema:collider`), at the earliest time code: `points` by the prim's
    local-to-world transform, × the stage's `metersPerUnit` (USD's fallback 0.01,
    centimetres, with a `UnitWarning` where the stage does not say it, as
    `kinema.io.read_usd` reads particles); `faceVertexCounts` and `faceVertexIndices`
    cut into fans; a `leftHanded` prim's triangles turned to run counter-clockwise. Also the
    stage's up axis, "y" or "z" (read_mesh turns a +y-up stage's points to +z up)."""
    try:
        from pxr import Tf, Usd, UsdGeom
    except ImportError:
        raise ImportError("reading USD meshes needs the usd-core package: pip install usd-core (or kinema[usd])") from None
    from ._usd import _usd_reason, meters_per_unit_problem
    from .units import UnitWarning

    try:
        stage = _open(path)
    except Tf.ErrorException as e:
        raise refuse(f"not a USD stage that can be read ({_usd_reason(e)})") from None
    except ValueError as e:  # _open's refusal of a file that is no layer
        raise refuse(str(e).split(": ", 1)[-1]) from None
    if stage is None:
        raise refuse("not a USD stage that can be read")
    time = Usd.TimeCode.EarliestTime()
    parts_v, parts_f, offset = [], [], 0
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh) or UsdGeom.Imageable(prim).ComputePurpose() == UsdGeom.Tokens.guide or prim.HasAttribute("kinema:collider"):
            continue
        mesh = UsdGeom.Mesh(prim)
        points = mesh.GetPointsAttr().Get(time)
        counts = mesh.GetFaceVertexCountsAttr().Get(time)
        indices = mesh.GetFaceVertexIndicesAttr().Get(time)
        if points is None or counts is None or indices is None or len(points) == 0:
            continue
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        c, i = np.asarray(counts, dtype=np.int64), np.asarray(indices, dtype=np.int64)
        where = f"{prim.GetPath()}"
        if (c < 3).any():
            k = int(np.argmax(c < 3))
            raise refuse(f"{where}: faceVertexCounts[{k}] = {int(c[k])}; a face has at least 3 vertices")
        if int(c.sum()) != len(i):
            raise refuse(f"{where}: faceVertexCounts add up to {int(c.sum())}, but faceVertexIndices has {len(i)} indices")
        if len(i) and (i.min() < 0 or i.max() >= len(p)):
            k = int(np.argmax((i < 0) | (i >= len(p))))
            raise refuse(f"{where}: faceVertexIndices[{k}] = {int(i[k])}; the prim has {len(p)} points (indices 0..{len(p) - 1})")
        tris = fan(c, i)
        if mesh.GetOrientationAttr().Get(time) == UsdGeom.Tokens.leftHanded:
            tris = tris[:, [0, 2, 1]]
        m = np.array(UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(time), dtype=np.float64)  # row vectors: p' = [p 1] M
        p = p @ m[:3, :3] + m[3, :3]
        parts_v.append(p)
        parts_f.append(tris + offset)
        offset += len(p)
    if not parts_v:
        raise refuse("the stage holds no UsdGeom.Mesh prim with points and faces (guides left out)")
    metres = UsdGeom.GetStageMetersPerUnit(stage)
    bad = meters_per_unit_problem(metres)
    if bad:
        raise refuse(bad)
    said = []
    if not UsdGeom.StageHasAuthoredMetersPerUnit(stage):
        said.append(f"the stage does not say its metersPerUnit: USD's fallback {metres!r} m (centimetres) is taken")
    up = "y" if UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y else "z"  # (USD allows Y or Z; its fallback is Y)
    if said:
        warnings.warn(f"{path}: {'; '.join(said)}", UnitWarning, stacklevel=4)
    return np.concatenate(parts_v) * metres, np.concatenate(parts_f), up
