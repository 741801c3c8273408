"""VTK XML PolyData series for ParaView and OVITO: a .pvd collection of one .vtp per frame (a
.vtm per frame with the springs' own .vtp), and the colliders as a .vtp of lines and polygons
(a mesh collider: its own triangles)."""

from __future__ import annotations

import base64
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from ._cell import Extras, box_corners, live_springs, trajectory_cell
from ._files import SERIES_DIGITS, Frames, atomic_outputs, series_names

SUFFIXES = (".pvd", ".vtp")  # a path's suffixes that name a VTK export (``exports._SUFFIXES``)


def _vtk_array(name: str, a: np.ndarray, components: int = 1, count: str = "NumberOfComponents") -> str:
    """An inline binary DataArray: base64 of the byte count (UInt64) and the little-endian
    data, as one stream (uncompressed data, header_type="UInt64")."""
    vtk_type = {"f8": "Float64", "i8": "Int64"}[a.dtype.str[1:]]
    data = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<")).tobytes()
    payload = base64.b64encode(np.uint64(len(data)).tobytes() + data).decode("ascii")
    return f'<DataArray type="{vtk_type}" Name={quoteattr(name)} {count}="{components}" format="binary">{payload}</DataArray>'


def _vtk_strings(name: str, values: Sequence[str]) -> str:
    """A field data array of strings, as VTK's XML writer writes one in ASCII: each string's
    UTF-8 bytes as numbers, each string ended by a 0."""
    codes = " ".join(" ".join(str(b) for b in v.encode("utf-8")) + " 0" for v in values)
    return f'<Array type="String" Name={quoteattr(name)} NumberOfTuples="{len(values)}" format="ascii">{codes}</Array>'


def _cells(cells: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The connectivity and offsets arrays of a list of cells: each an array of point
    indices, or a (C, k) array of C cells of k points (a mesh's triangles, in one piece)."""
    if not cells:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    sizes = np.concatenate([np.full(len(c), c.shape[1]) if c.ndim == 2 else [len(c)] for c in cells])
    return np.concatenate([c.reshape(-1) for c in cells]).astype(np.int64), np.cumsum(sizes, dtype=np.int64)


def _polydata(
    points: np.ndarray,
    point_data: Sequence[str] = (),
    cell_data: Sequence[str] = (),
    field_data: Sequence[str] = (),
    attributes: str = "",
    declared: Sequence[str] = ("Verts", "Lines", "Strips", "Polys"),
    **cells: tuple[np.ndarray, np.ndarray],
) -> str:
    """An XML PolyData file (one Piece): `points` (n, 3) float64, the DataArrays of
    `point_data`, `cell_data` and `field_data`, `attributes` of <PointData> (the
    active `Scalars` and `Vectors`), and the cells `verts`, `lines`, `polys` as
    (connectivity, offsets) pairs; the <Piece> states the counts of the kinds `declared`
    (VTK takes a count left out as 0).

    The <FieldData> comes after the Piece: VTK reads it anywhere in <PolyData>, but OVITO's
    format check walks from <VTKFile> to the first <Piece> and gives up at the end of a
    DataArray before it, so a frame with its FieldData first is not recognised (and an OVITO
    .pvd import silently loads no particles)."""
    counts = {name: len(cells[name.lower()][1]) if name.lower() in cells else 0 for name in declared}
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
        "<PolyData>",
        f'<Piece NumberOfPoints="{len(points)}" ' + " ".join(f'NumberOf{k}="{v}"' for k, v in counts.items()) + ">",
        f"<PointData{attributes}>",
        *point_data,
        "</PointData>",
        *(["<CellData>", *cell_data, "</CellData>"] if cell_data else []),
        f"<Points>{_vtk_array('Points', np.asarray(points, dtype=np.float64).reshape(-1, 3), 3)}</Points>",
    ]
    for name in ("Verts", "Lines", "Polys"):
        if name.lower() in cells:
            connectivity, offsets = cells[name.lower()]
            lines.append(f"<{name}>{_vtk_array('connectivity', connectivity)}{_vtk_array('offsets', offsets)}</{name}>")
    lines.append("</Piece>")
    if field_data:
        lines.append(f"<FieldData>{''.join(field_data)}</FieldData>")
    lines += ["</PolyData>", "</VTKFile>"]
    return "\n".join(lines) + "\n"


def _vtp(fr: Frames, i: int, extras: Extras) -> str:
    """Frame `i`: the particles alive at it as points and vertex cells, point data `v`
    (velocity), `speed`, `radius`, `mass`, `id` (the names OVITO maps to Velocity,
    Radius, Mass and Particle Identifier; ParaView takes `v` as the active vectors),
    `type` (the index of the particle's species in the field `type_names`), `Color`
    (r g b in [0, 1], the name OVITO maps to its Color), `angular_velocity` (rad/s),
    `orientation` (the unit quaternion w x y z) and `group` (the collision group, int64)
    where the trajectory has them, the field `TimeValue`."""
    live = fr.live(i)
    n = live.size
    x, v = fr.positions[i][live], fr.velocities[i][live]
    # unknown velocities (all NaN): no v (the speed stays, NaN: kinema's reader knows its files by it)
    point_data = ([_vtk_array("v", v, 3)] if fr.has_velocities else []) + [_vtk_array("speed", np.linalg.norm(v, axis=1))]
    if fr.radii is not None:
        point_data.append(_vtk_array("radius", fr.radii[live]))
    if fr.masses is not None:
        point_data.append(_vtk_array("mass", fr.masses[live]))
    point_data.append(_vtk_array("id", fr.ids[live]))
    field_data = [_vtk_array("TimeValue", np.array([fr.t[i]]), 1, "NumberOfTuples")]
    if extras.names is not None:
        point_data.append(_vtk_array("type", extras.typeid[live]))
        field_data.append(_vtk_strings("type_names", extras.names))
    if extras.colors is not None:
        point_data.append(_vtk_array("Color", extras.colors[live], 3))
    if fr.angular_velocities is not None:
        point_data.append(_vtk_array("angular_velocity", fr.angular_velocities[i][live], 3))
    if fr.orientations is not None:
        point_data.append(_vtk_array("orientation", fr.orientations[i][live], 4))
    if fr.groups is not None:
        point_data.append(_vtk_array("group", fr.groups[live].astype(np.int64)))
    # One vertex cell per particle, so that ParaView draws the points without a filter (and
    # OVITO reads the file as particles: as many vertices as points, no other cells).
    cells = np.arange(n, dtype=np.int64)
    return _polydata(x, point_data, field_data=field_data, attributes=' Scalars="speed" Vectors="v"', verts=(cells, cells + 1))


def _springs_vtp(fr: Frames, i: int, springs: np.ndarray, rest: np.ndarray) -> str:
    """The springs of frame `i` whose two ends are alive: one line cell per spring between
    its own two points (the ends' positions, m), the cell data `id1` and `id2` the ends'
    ids. This is the layout of a contact network beside a particles file (Aspherix's), which
    OVITO reads as lines between particle ids; a particle file with line cells it does not
    open at all. The <Piece> states the numbers of points and lines only: OVITO takes a file
    that states as many vertices as points for particles.

    A frame in which no spring has both ends alive holds one line of zero length at `rest`
    (the middle of the scene) with `id1` = `id2` = -1: OVITO 3.17 dies of a floating
    point exception on a file of no lines, and keeps the previous frame's lines where the
    frame has no springs file."""
    rows = live_springs(springs, fr, i)
    if not len(rows):
        none = np.array([-1], dtype=np.int64)
        points, id1, id2 = np.stack([rest, rest]), none, none
    else:
        ends = fr.live(i)[rows]  # (K, 2) columns
        points, id1, id2 = fr.positions[i][ends.reshape(-1)], fr.ids[ends[:, 0]], fr.ids[ends[:, 1]]
    k = np.arange(len(points), dtype=np.int64)
    return _polydata(points, cell_data=[_vtk_array("id1", id1), _vtk_array("id2", id2)], declared=("Lines",), lines=(k, k[1::2] + 1))


def _contacts_vtp(fr: Frames, i: int, record: Any, periodic: np.ndarray, edges: np.ndarray, rest: np.ndarray) -> str:
    """The contacts between particles at frame `i` (`record`, a
    `kinema.contact_record.ContactRecord`) as a force network: one line cell per contact
    from the centre of `i` to the centre of `j` (each its own two points, m; across a
    periodic boundary, `j`'s image nearest `i`: the `periodic` axes of cell `edges`),
    cell data `force_n_magnitude` and `force_t_magnitude` (N), `sliding` (1 or 0),
    `overlap` (m), `impulse_n_magnitude` and `impulse_t_magnitude` (N s, the impulse
    model's) where the record has them, and `id1`, `id2` the two ids. ParaView colours the
    lines by a cell array (a force chain picture), OVITO reads the file as lines.

    A frame without a contact between particles holds one line of zero length at `rest`
    with `id1` = `id2` = -1 and zeros, as `_springs_vtp` does (OVITO 3.17 dies on a file
    of no lines). Contacts with colliders are not drawn (no second centre)."""
    part = record.frame(i)
    pairs = part["j"] >= 0
    k = int(pairs.sum())
    if k:
        order = np.argsort(fr.ids, kind="stable")  # the columns of ids
        at = order[np.searchsorted(fr.ids[order], np.concatenate([part["i"][pairs], part["j"][pairs]]))]
        a, b = fr.positions[i][at[:k]], fr.positions[i][at[k:]]
        if periodic.any():  # j's image nearest i
            length = np.where(periodic, edges, 1.0)
            b = b + np.where(periodic, np.round((a - b) / length) * length, 0.0)
        points = np.stack([a, b], axis=1).reshape(-1, 3)
        id1, id2 = part["i"][pairs], part["j"][pairs]
    else:
        points, id1, id2 = np.stack([rest, rest]), np.array([-1], dtype=np.int64), np.array([-1], dtype=np.int64)

    def per_line(values: np.ndarray) -> np.ndarray:
        return values if k else np.zeros(1, dtype=values.dtype)

    cell_data = []
    for name, word in (
        ("force_n", "force_n_magnitude"),
        ("force_t", "force_t_magnitude"),
        ("impulse_n", "impulse_n_magnitude"),
        ("impulse_t", "impulse_t_magnitude"),
    ):
        if name in part:
            a = np.asarray(part[name], dtype=np.float64)[pairs]
            cell_data.append(_vtk_array(word, per_line(np.abs(a) if a.ndim == 1 else np.linalg.norm(a, axis=1))))
    if "sliding" in part:
        cell_data.append(_vtk_array("sliding", per_line(np.asarray(part["sliding"])[pairs].astype(np.int64))))
    if "overlap" in part:
        cell_data.append(_vtk_array("overlap", per_line(np.asarray(part["overlap"], dtype=np.float64)[pairs])))
    cell_data += [_vtk_array("id1", np.asarray(id1, dtype=np.int64)), _vtk_array("id2", np.asarray(id2, dtype=np.int64))]
    ends = np.arange(len(points), dtype=np.int64)
    return _polydata(points, cell_data=cell_data, declared=("Lines",), lines=(ends, ends[1::2] + 1))


def _vtm(blocks: list[tuple[str, str]]) -> str:
    """A multi-block file of one frame: its blocks (name, file) in order: `particles` (the
    frame's .vtp), then `springs` and `contacts` where the trajectory has them."""
    sets = "".join(f'<DataSet index="{k}" name={quoteattr(name)} file={quoteattr(file)}/>\n' for k, (name, file) in enumerate(blocks))
    return (
        '<?xml version="1.0"?>\n<VTKFile type="vtkMultiBlockDataSet" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n'
        f"<vtkMultiBlockDataSet>\n{sets}</vtkMultiBlockDataSet>\n</VTKFile>\n"
    )


_SPHERE_BANDS, _SPHERE_SEGMENTS = 16, 32  # a sphere obstacle's latitude bands and longitudes
_DISK_SEGMENTS = 64  # the sides of a 2D sphere obstacle's disk


def _unit(a: np.ndarray) -> np.ndarray:
    return a / np.linalg.norm(a)


def _scene_bounds(traj: Any, fr: Frames, colliders: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) of the trajectory's cell (`_cell.trajectory_cell`: all particles of all
    frames, or the box's walls) and of the colliders' finite parts: the room open box faces
    and planes are drawn in."""
    cell = trajectory_cell(traj, fr)
    lo, hi = cell.lo.astype(np.float64), cell.hi.astype(np.float64)
    for d in colliders:
        if d["type"] == "sphere":
            c, r = np.asarray(d["center"], dtype=np.float64), float(d["radius"])
            lo, hi = np.minimum(lo, c - r), np.maximum(hi, c + r)
        elif d["type"] == "box":
            for bound in (d["lo"], d["hi"]):
                b = np.full(3, np.nan)
                b[: len(bound)] = bound
                finite = np.isfinite(b)
                lo[finite], hi[finite] = np.minimum(lo[finite], b[finite]), np.maximum(hi[finite], b[finite])
        elif d["type"] == "mesh" and len(d["vertices"]):
            v = np.asarray(d["vertices"], dtype=np.float64)
            lo, hi = np.minimum(lo, v.min(axis=0)), np.maximum(hi, v.max(axis=0))
    return lo, hi


def _uv_sphere() -> tuple[np.ndarray, list[np.ndarray]]:
    """The unit sphere as `_SPHERE_BANDS` bands of `_SPHERE_SEGMENTS` faces: its points
    (the poles first and last, the rings between) and its faces (triangles at the poles,
    quads between), anticlockwise seen from outside."""
    m, s = _SPHERE_BANDS, _SPHERE_SEGMENTS
    theta, phi = np.pi * np.arange(1, m) / m, 2 * np.pi * np.arange(s) / s
    ring = np.stack([np.sin(theta)[:, None] * np.cos(phi), np.sin(theta)[:, None] * np.sin(phi), np.cos(theta)[:, None] * np.ones(s)], axis=2)
    points = np.concatenate([[[0.0, 0.0, 1.0]], ring.reshape(-1, 3), [[0.0, 0.0, -1.0]]])
    north, south = 0, len(points) - 1

    def at(band: int, j: int) -> int:
        return 1 + band * s + j % s

    faces = [np.array([north, at(0, j), at(0, j + 1)]) for j in range(s)]
    faces += [np.array([at(b, j), at(b + 1, j), at(b + 1, j + 1), at(b, j + 1)]) for b in range(m - 2) for j in range(s)]
    faces += [np.array([south, at(m - 2, j + 1), at(m - 2, j)]) for j in range(s)]
    return points, faces


def _collider_geometry(traj: Any, fr: Frames) -> tuple[np.ndarray, list[tuple[int, np.ndarray]], list[tuple[int, np.ndarray]]] | None:
    """The trajectory's colliders as points (m) and line and polygon cells, each cell (or
    (C, k) block of cells, `_cells`) with the index of its collider; `None` without
    colliders.

    A box is its 12 edges (a 2D trajectory's box: the 4 edges of its rectangle at z = 0), an
    open face at the bound of `_scene_bounds`; a plane is a square centred on the point
    of the plane nearest the middle of the scene, as wide as the scene's diagonal, so that it
    covers the scene (2D: a line segment at z = 0); a sphere obstacle is a UV sphere of
    `_SPHERE_BANDS` × `_SPHERE_SEGMENTS` faces, its points at exactly its radius (2D: a
    disk of `_DISK_SEGMENTS` sides at z = 0); a mesh is its own vertices and triangles, as
    described (its faces' vertex order, so their normals, kept).

    The geometry is each collider's placement as added: a moving one's `motion` is not
    applied (one file for the whole series)."""
    if not getattr(traj, "colliders", None):
        return None
    from ..collider_descriptions import _describe_colliders

    colliders = _describe_colliders(traj.colliders)
    lo, hi = _scene_bounds(traj, fr, colliders)
    middle, half = (lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2
    points: list[np.ndarray] = []
    lines: list[tuple[int, np.ndarray]] = []
    polys: list[tuple[int, np.ndarray]] = []
    base = 0

    def add(p: np.ndarray) -> int:
        nonlocal base
        points.append(np.asarray(p, dtype=np.float64).reshape(-1, 3))
        first, base = base, base + len(points[-1])
        return first

    for k, d in enumerate(colliders):
        if d["type"] == "box":
            b_lo, b_hi = box_corners(d)
            b_lo, b_hi = np.where(np.isfinite(b_lo), b_lo, lo), np.where(np.isfinite(b_hi), b_hi, hi)
            if fr.dim == 2:
                first = add([[b_lo[0], b_lo[1], 0], [b_hi[0], b_lo[1], 0], [b_hi[0], b_hi[1], 0], [b_lo[0], b_hi[1], 0]])
                lines += [(k, first + np.array([j, (j + 1) % 4])) for j in range(4)]
            else:
                # Corner j has the upper bound along the axes of its set bits (x: 1, y: 2, z: 4).
                first = add([[(b_hi if j >> a & 1 else b_lo)[a] for a in range(3)] for j in range(8)])
                lines += [(k, first + np.array([j, j | 1 << a])) for j in range(8) for a in range(3) if not j >> a & 1]
        elif d["type"] == "plane":
            n = np.asarray(d["normal"], dtype=np.float64)
            if not np.linalg.norm(n) > 0:
                raise ValueError(f"colliders[{k}]: the plane's normal = {d['normal']!r} is invalid: it must not be zero")
            n = _unit(n)
            centre = middle - np.dot(middle - np.asarray(d["point"], dtype=np.float64), n) * n
            in_xy = np.cross(n, [0.0, 0.0, 1.0])
            if fr.dim == 2 and np.linalg.norm(in_xy) > 1e-12:
                u = _unit(in_xy)
                along = np.array([0.0, 0.0, 1.0]) - n[2] * n  # in the plane, up
                centre -= centre[2] / along[2] * along  # along the plane to z = 0
                lines.append((k, add([centre - half * u, centre + half * u]) + np.arange(2)))
            else:
                u = _unit(np.cross(n, np.eye(3)[np.argmin(np.abs(n))]))
                w = np.cross(n, u)  # u × w = n: the square's corners turn anticlockwise seen from the side n points to
                corners = [centre + half * (su * u + sw * w) for su, sw in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
                polys.append((k, add(corners) + np.arange(4)))
        elif d["type"] == "mesh":
            first = add(np.asarray(d["vertices"], dtype=np.float64).reshape(-1, 3))
            polys.append((k, first + np.asarray(d["faces"], dtype=np.int64).reshape(-1, 3)))  # (F, 3): F cells
        else:
            c, r = np.asarray(d["center"], dtype=np.float64), float(d["radius"])
            if fr.dim == 2:
                phi = 2 * np.pi * np.arange(_DISK_SEGMENTS) / _DISK_SEGMENTS
                disk = np.stack([c[0] + r * np.cos(phi), c[1] + r * np.sin(phi), np.zeros_like(phi)], axis=1)
                polys.append((k, add(disk) + np.arange(_DISK_SEGMENTS)))
            else:
                unit, faces = _uv_sphere()
                first = add(c + r * unit)
                polys += [(k, first + f) for f in faces]
    return np.concatenate(points) if points else np.zeros((0, 3)), lines, polys


def _colliders_vtp(traj: Any, fr: Frames) -> str | None:
    """The colliders file: the geometry of `_collider_geometry` as line and polygon cells,
    with the cell data `collider` (the index in `traj.colliders`); `None` without
    colliders."""
    geometry = _collider_geometry(traj, fr)
    if geometry is None:
        return None
    points, lines, polys = geometry
    index = np.concatenate([np.full(len(c) if c.ndim == 2 else 1, k, dtype=np.int64) for k, c in lines + polys])  # VTK numbers lines before polygons
    return _polydata(
        points,
        cell_data=[_vtk_array("collider", index)],
        lines=_cells([c for _, c in lines]),
        polys=_cells([c for _, c in polys]),
    )


def write_vtk(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    """Write `fr` as a VTK series for ParaView and OVITO; returns the paths written: the
    .pvd, the colliders file where the trajectory has colliders, then each frame's files.

    `<stem>.pvd` (open this one: a collection whose timesteps are the frame times) and the
    folder `<stem>_vtk/` with one XML PolyData file per frame, `<stem>_00000.vtp`: points
    (m) as vertex cells, point data `v` (velocity, m/s), `speed` (m/s), `radius` (m),
    `mass` (kg), `id`; float64 and int64, base64; `type` (the index of the species in
    the field `type_names`), `Color` (r g b in [0, 1]) and `group` (the collision group,
    int64) where the trajectory has species, colours and groups (`_vtp`). OVITO maps `v`, `radius`, `mass`, `id` and
    `Color` to Velocity, Radius, Mass, Particle Identifier and Color, `type` to Material
    Type. With `springs`, each frame is a multi-block `<stem>_00000.vtm` (the one the
    .pvd names) of the particles .vtp and `<stem>_springs_00000.vtp`, a line per spring
    whose ends are alive (`_springs_vtp`), which OVITO reads as Lines. With a
    `contact_record` (`World.run(record_contacts=True)`) each frame's .vtm also holds
    `<stem>_contacts_00000.vtp`, the contacts between particles as lines from centre to
    centre with the cell data `force_n_magnitude`, `force_t_magnitude`, `sliding`,
    `overlap` (and the impulse model's `impulse_n_magnitude`, `impulse_t_magnitude`),
    `id1` and `id2` (`_contacts_vtp`): force chains, which ParaView colours by a force
    (Color by `force_n_magnitude` on that block). When the trajectory
    has `colliders`, `<stem>_colliders.vtp` beside the .pvd holds them: a box as its 12
    edges (lines), a plane as a square (a polygon) that covers the scene, a sphere obstacle
    as a sphere of polygons (2D: a rectangle, a segment and a disk at z = 0), a mesh as its
    triangles (polygons), the cell data
    `collider` the index in `colliders` (`_collider_geometry`). OVITO reads the
    polygons of that file, not the lines. The stem is the name of `path` less its suffix
    where that is .pvd or .vtp, the whole name otherwise.

    The folder, the colliders file and the .pvd are all written under temporary names before
    any is put in place, the .pvd last, so a failed export leaves nothing new and an earlier
    export (its .pvd, its series and its colliders) as it was; the new folder takes the
    place of an existing `<stem>_vtk/` only if that holds nothing but an earlier series.
    `on_frame(i)` is called after frame `i` is written."""
    folder, stem, _ = series_names(path, "vtk", ".vtp", SUFFIXES)
    # the frames, and with springs or contacts their files and the multi-block files of all
    pattern = rf"{re.escape(stem)}(_springs|_contacts)?_\d{{{SERIES_DIGITS},}}\.(vtp|vtm)"
    pvd = path.with_name(stem + ".pvd")
    colliders = path.with_name(stem + "_colliders.vtp")
    scenery = _colliders_vtp(traj, fr)  # before anything is written: a bad collider is a ValueError
    extras = Extras(traj, fr)
    record = getattr(traj, "contact_record", None)
    middle = np.zeros(3)  # where a frame without springs (contacts) puts its line of zero length
    periodic, edges = np.zeros(3, dtype=bool), np.zeros(3)
    if extras.springs is not None or record is not None:
        cell = trajectory_cell(traj, fr)
        middle = 0.5 * (cell.lo + cell.hi)
        periodic, edges = np.asarray(cell.periodic, dtype=bool), cell.hi - cell.lo
    names = [f"{stem}_{i:0{SERIES_DIGITS}d}.vtp" for i in range(fr.n_frames)]
    # With springs or contacts each frame is a multi-block file (.vtm) of its particles and those.
    blocks = extras.springs is not None or record is not None
    entries = names if not blocks else [f"{stem}_{i:0{SERIES_DIGITS}d}.vtm" for i in range(fr.n_frames)]
    datasets = "\n".join(f'<DataSet timestep="{float(fr.t[i])!r}" part="0" file={quoteattr(f"{folder.name}/{name}")}/>' for i, name in enumerate(entries))
    collection = (
        f'<?xml version="1.0"?>\n<VTKFile type="Collection" version="1.0" byte_order="LittleEndian">\n<Collection>\n{datasets}\n</Collection>\n</VTKFile>\n'
    )
    written: list[Path] = []
    # Everything is written under temporary names first: the frames, the colliders, the
    # collection that points at the frames; only then are they put in place, the .pvd last.
    # A write that fails leaves nothing new, and an earlier export (its .pvd, its series and
    # its colliders) as it was.
    with atomic_outputs(pvd) as out:
        tmp_pvd = out.file(pvd)
        tmp_colliders = out.file(colliders) if scenery is not None else None
        tmp = out.folder(folder, pattern)
        with out.naming(folder):
            for i, name in enumerate(names):
                (tmp / name).write_text(_vtp(fr, i, extras), encoding="ascii")
                if blocks:
                    parts = [("particles", name)]
                    if extras.springs is not None:
                        parts.append(("springs", f"{stem}_springs_{i:0{SERIES_DIGITS}d}.vtp"))
                        (tmp / parts[-1][1]).write_text(_springs_vtp(fr, i, extras.springs, middle), encoding="ascii")
                    if record is not None:
                        parts.append(("contacts", f"{stem}_contacts_{i:0{SERIES_DIGITS}d}.vtp"))
                        (tmp / parts[-1][1]).write_text(_contacts_vtp(fr, i, record, periodic, edges, middle), encoding="ascii")
                    (tmp / entries[i]).write_text(_vtm(parts), encoding="utf-8")
                    written += [folder / entries[i], *(folder / file for _, file in parts)]
                else:
                    written.append(folder / name)
                on_frame(i)
        if tmp_colliders is not None:
            with out.naming(colliders):
                tmp_colliders.write_text(scenery, encoding="ascii")
        with out.naming(pvd):
            tmp_pvd.write_text(collection, encoding="utf-8")
    return [pvd, *([colliders] if scenery is not None else []), *written]
