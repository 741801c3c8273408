"""The browser viewer's scene: colliders, springs, births and deaths, the colour legend and the
camera's framing, read through the page's `window.kinemaViewer.info()` in headless Chromium
(and the data the page carries, without a browser)."""

from __future__ import annotations

import base64
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from test_viewer import WAIT_MS, browser, chromium  # noqa: F401 (the browser fixtures)

import kinema
from kinema import viewer
from kinema.render import NO_OWN_COLOR
from kinema.scene import Scene
from kinema.viewer import page as viewer_page
from kinema.viewer import server as viewer_server

SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"
FLOOR = np.array([224, 224, 220])  # the scenery's colours, as kinema's renderer draws them
BOX_FLOOR = np.array([212, 212, 206])
OBSTACLE = np.array([176, 178, 184])
WIDE, TALL = (1200, 420), (420, 1000)


def _traj(positions, velocities=None, **about) -> kinema.Trajectory:
    """A trajectory by hand: positions (F, N, 3), frames 0.1 s apart."""
    positions = np.asarray(positions, dtype=np.float64)
    frames = positions.shape[0]
    if velocities is None:
        velocities = np.gradient(positions, 0.1, axis=0) if frames > 1 else np.zeros_like(positions)
    zeros, three = np.zeros(frames), np.zeros((frames, 3))
    about.setdefault("radii", np.full(positions.shape[1], 0.05))
    return kinema.Trajectory(
        t=np.arange(frames) * 0.1,
        positions=positions,
        velocities=velocities,
        kinetic=zeros,
        potential={},
        momentum=three,
        angular_momentum=three,
        contacts=np.zeros(frames, dtype=int),
        impulse_balance=three,
        collision_energy_lost=zeros,
        **about,
    )


def _falling(n=12, frames=8, seed=1, **about) -> kinema.Trajectory:
    """``n`` balls in the unit square falling from z = 1 to z = 0.05 (3D)."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0.1, 0.9, (n, 2))
    z = np.linspace(1.0, 0.05, frames)[:, None].repeat(n, axis=1)
    positions = np.concatenate([np.broadcast_to(xy, (frames, n, 2)), z[..., None]], axis=2)
    return _traj(positions, **about)


def _page_data(text: str) -> dict:
    match = re.search(r'<script type="application/json" id="kinema-data">(.*?)</script>', text, re.S)
    assert match, "the page has no kinema-data element"

    def refuse(constant: str):
        raise AssertionError(f"the page's JSON holds {constant}, which JSON.parse refuses")

    return json.loads(match.group(1), parse_constant=refuse)


class _Page:
    """A viewer page open in headless Chromium at a viewport size; ``info()`` is the page's
    ``window.kinemaViewer.info()``."""

    def __init__(self, browser, url: str, size: tuple[int, int]) -> None:  # noqa: F811 (the fixture's name)
        self.page = browser.new_page(viewport={"width": size[0], "height": size[1]})
        self.page.goto(url)
        self.page.wait_for_function("() => window.kinemaViewer.ready || window.kinemaViewer.error", timeout=WAIT_MS)
        assert self.page.evaluate("() => window.kinemaViewer.error") is None

    def info(self) -> dict:
        return self.page.evaluate("() => window.kinemaViewer.info()")

    def show(self, frame: int) -> dict:
        self.page.evaluate(f"() => window.kinemaViewer.setFrame({frame})")
        info = self.info()
        assert info["frame"] == frame
        return info

    def resize(self, size: tuple[int, int]) -> dict:
        self.page.set_viewport_size({"width": size[0], "height": size[1]})
        self.page.wait_for_function(f"() => window.kinemaViewer.info().canvas.width === {size[0]}", timeout=WAIT_MS)
        return self.info()

    def pixels(self, path) -> np.ndarray:
        """The view (the canvas, the UI bar left out) as RGB."""
        box = self.page.locator("#kinema-view canvas").bounding_box()
        self.page.screenshot(path=str(path), clip=box)
        return np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)

    def close(self) -> None:
        self.page.close()


@pytest.fixture
def open_page(browser, tmp_path):  # noqa: F811 (the fixture's name)
    """Open ``traj``'s self-contained page (or, served, its page and data.bin) at a size."""
    opened: list = []

    def open_(traj, size=(800, 600), frame=0, served=False, **options) -> _Page:
        if served:
            url, server = viewer.serve(traj, open_browser=False, announce=False, **options)
            opened.append(server)
        else:
            url = viewer.write_html(traj, tmp_path / f"page{len(opened)}.html", **options).resolve().as_uri()
        page = _Page(browser, f"{url}#frame={frame}", size)
        opened.append(page)
        return page

    yield open_
    for thing in opened:
        if isinstance(thing, _Page):
            thing.close()
        else:
            thing.shutdown()
            thing.server_close()


def _share(image: np.ndarray, color: np.ndarray, tol: int = 6) -> float:
    """The share of the image's pixels within ``tol`` of ``color``."""
    return float((np.abs(image - color).max(axis=2) <= tol).mean())


def _assert_in_view(info: dict) -> None:
    room = info["inView"]
    assert room["particles"] and room["colliders"], f"something projects outside the {info['canvas']} canvas: {room}"
    # The framing is tight: the framed points span nearly all of the width or of the height.
    assert max(info["fill"]) > 0.85 and max(info["fill"]) <= 1.0, info["fill"]


# --- Colliders --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("lo", "hi", "edges"),
    [
        ([0, 0, 0], [1, 1, 1.2], 12),  # closed: all 12
        ([0, 0, 0], [1, 1, math.inf], 8),  # no lid: the 4 rim edges of the top go, the 4 walls' edges rise to the extent
        ([0, 0, -math.inf], [1, 1, math.inf], 4),  # a chimney: the 4 vertical edges alone
        ([-math.inf, 0, 0], [1, 1, 1.2], 8),  # open towards -x: the 4 edges of that face go
    ],
)
def test_a_box_draws_its_edges_less_the_open_faces(open_page, tmp_path, lo, hi, edges):
    traj = _falling(colliders=[{"type": "box", "lo": lo, "hi": hi}])
    page = open_page(traj)
    info = page.info()
    assert info["colliders"] == {"plane": 0, "box": 1, "sphere": 0, "mesh": 0}
    assert info["boxEdges"] == edges
    _assert_in_view(info)
    image = page.pixels(tmp_path / "box.png")
    floor = _share(image, BOX_FLOOR)
    # The floor face is drawn when the lower z face is closed (and then it shows).
    assert (floor > 0.01) == math.isfinite(lo[2]), f"box floor colour on {floor:.3%} of the view"


def test_a_plane_is_a_floor_patch_and_a_sphere_a_shaded_ball(open_page, tmp_path):
    colliders = [{"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}, {"type": "sphere", "center": [0.5, 0.5, 0.3], "radius": 0.25}]
    page = open_page(_falling(colliders=colliders))
    info = page.info()
    assert info["colliders"] == {"plane": 1, "box": 0, "sphere": 1, "mesh": 0}
    assert info["colliderCorners"] == 4 + 8  # the patch's corners, the sphere's bounding box
    _assert_in_view(info)
    image = page.pixels(tmp_path / "plane.png")
    assert _share(image, FLOOR) > 0.05, "the floor patch does not show"
    # The sphere is shaded: many pixels of its grey, a little darker or lighter.
    grey = np.abs(image - image.mean(axis=2, keepdims=True)).max(axis=2) < 8
    assert (grey & (image.mean(axis=2) > 40) & (image.mean(axis=2) < 200)).mean() > 0.01, "the sphere obstacle does not show"
    # Without colliders, none of that.
    bare = open_page(_falling())
    assert bare.info()["colliders"] == {"plane": 0, "box": 0, "sphere": 0, "mesh": 0}
    assert _share(bare.pixels(tmp_path / "bare.png"), FLOOR) < 1e-3


def test_2d_colliders_a_line_a_rectangle_a_disc(open_page, tmp_path):
    # A 2D world (xy, orthographic): the floor y = 0 with its solid side below, a box
    # open at the top (3 sides), a disc.
    n, frames = 8, 6
    x = np.linspace(0.2, 1.8, n)
    y = np.linspace(1.5, 0.1, frames)
    positions = np.stack([np.broadcast_to(x, (frames, n)), np.broadcast_to(y[:, None], (frames, n)), np.zeros((frames, n))], axis=2)
    colliders = [
        {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0]},
        {"type": "box", "lo": [0, 0], "hi": [2, math.inf]},
        {"type": "sphere", "center": [1.0, 0.8, 0], "radius": 0.2},
    ]
    page = open_page(_traj(positions, dim=2, colliders=colliders), size=WIDE)
    info = page.info()
    assert info["dim"] == 2 and info["colliders"] == {"plane": 1, "box": 1, "sphere": 1, "mesh": 0}
    assert info["boxEdges"] == 3
    _assert_in_view(info)
    image = page.pixels(tmp_path / "flat.png")
    assert _share(image, OBSTACLE, tol=3) > 0.005, "the disc does not show"
    # The solid side (below the floor line, the bottom of the view) is lightly filled: the
    # bottom rows are lighter than the background, the top rows are not.
    assert image[-3:].mean() > image[:3].mean() + 10


def _bowl(centre=(0.5, 0.5, 0.7), radius=0.7, rings=12, segments=32) -> tuple[np.ndarray, np.ndarray]:
    """An open hemispherical bowl (the lower half of a sphere) as vertices (V, 3) and
    triangles (F, 3): a fan about the bottom, then ``rings - 1`` bands of quads up to the rim."""
    theta = np.linspace(0, np.pi / 2, rings + 1)[1:]
    phi = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), -np.cos(t)], axis=-1).reshape(-1, 3)
    vertices = np.asarray(centre) + radius * np.vstack([[0.0, 0.0, -1.0], ring])
    at = lambda i, j: 1 + i * segments + j % segments  # noqa: E731 (ring i, vertex j)
    faces = [[0, at(0, j), at(0, j + 1)] for j in range(segments)]
    for i in range(rings - 1):
        for j in range(segments):
            faces += [[at(i, j), at(i + 1, j), at(i + 1, j + 1)], [at(i, j), at(i + 1, j + 1), at(i, j + 1)]]
    return vertices, np.asarray(faces)


@pytest.mark.parametrize("served", [False, True])
def test_a_mesh_is_a_translucent_surface_with_its_rim_and_what_is_inside_shows(browser, tmp_path, served):  # noqa: F811 (the fixture's name)
    vertices, faces = _bowl()
    mesh = {"type": "mesh", "vertices": vertices.tolist(), "faces": faces.tolist(), "inside": False}
    if served:
        url, server = viewer.serve(_falling(colliders=[mesh]), open_browser=False, announce=False)
    else:
        url = viewer.write_html(_falling(colliders=[mesh]), tmp_path / "bowl.html").resolve().as_uri()
    page = browser.new_page(viewport={"width": 800, "height": 600})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    # three.js reports a shader that fails to compile on the console (the served page's
    # missing favicon is no error of the page's).
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" and not m.location.get("url", "").endswith("favicon.ico") else None)
    try:
        page.goto(f"{url}#frame=7")
        page.wait_for_function("() => window.kinemaViewer.ready || window.kinemaViewer.error", timeout=WAIT_MS)
        assert page.evaluate("() => window.kinemaViewer.error") is None
        info = page.evaluate("() => window.kinemaViewer.info()")
        assert errors == [], errors  # the shader compiled, nothing threw
        assert info["colliders"] == {"plane": 0, "box": 0, "sphere": 0, "mesh": 1}
        # Every triangle; the rim's 32 edges are the only ones drawn (no crease reaches 30°).
        assert info["meshes"] == [{"triangles": len(faces), "edges": 32, "opacity": 0.3, "transparent": True, "depthWrite": False, "doubleSided": True}]
        assert info["colliderCorners"] == 8  # the bowl's box, framed
        _assert_in_view(info)
        # The surface shows (lighter than the background) and the balls resting in it show
        # through it: all 12 drawn, and the view's particle colours are there.
        box = page.locator("#kinema-view canvas").bounding_box()
        page.screenshot(path=str(tmp_path / "bowl.png"), clip=box)
        image = np.asarray(Image.open(tmp_path / "bowl.png").convert("RGB"), dtype=np.int16)
        grey = (np.abs(image - image.mean(axis=2, keepdims=True)).max(axis=2) < 10) & (image.mean(axis=2) > 35)
        assert grey.mean() > 0.05, f"the bowl covers {grey.mean():.1%} of the view"
        assert info["particles"] == {"total": 12, "visible": 12}
        coloured = np.ptp(image, axis=2) > 40
        assert coloured.mean() > 0.002, "the balls do not show through the bowl"
    finally:
        page.close()
        if served:
            server.shutdown()
            server.server_close()


def test_a_mesh_reaches_the_page_as_float32_and_uint32_and_is_framed(tmp_path):
    vertices, faces = _bowl(centre=(0.5, 0.5, 2.0), radius=1.5)
    colliders = [{"type": "mesh", "vertices": vertices.tolist(), "faces": faces.tolist(), "inside": False}]
    data = _page_data(viewer.write_html(_falling(colliders=colliders), tmp_path / "m.html").read_text(encoding="utf-8"))
    [mesh] = data["colliders"]
    assert mesh["type"] == "mesh" and mesh["inside"] is False
    assert (mesh["vertexCount"], mesh["faceCount"]) == (len(vertices), len(faces))
    np.testing.assert_array_equal(np.frombuffer(base64.b64decode(mesh["vertices"]), "<f4").reshape(-1, 3), vertices.astype(np.float32))
    np.testing.assert_array_equal(np.frombuffer(base64.b64decode(mesh["faces"]), "<u4").reshape(-1, 3), faces)
    np.testing.assert_allclose(mesh["lo"], vertices.min(axis=0))
    np.testing.assert_allclose(mesh["hi"], vertices.max(axis=0))
    # The extent holds the bowl (wider than the falling balls: x from -1 to 2, z up to 2).
    assert data["extent"]["min"][0] <= -1.0 + 1e-9 and data["extent"]["max"][2] >= 2.0 - 1e-9
    # What cannot be drawn is left out: an index past the vertices, non-finite vertices.
    bad = [
        {"type": "mesh", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "faces": [[0, 1, 3]]},
        {"type": "mesh", "vertices": [[0, 0, math.nan], [1, 0, 0], [0, 1, 0]], "faces": [[0, 1, 2]]},
        {"type": "mesh", "vertices": "nonsense", "faces": [[0, 1, 2]]},
    ]
    assert _page_data(viewer.write_html(_falling(colliders=bad), tmp_path / "b.html").read_text(encoding="utf-8"))["colliders"] == []


# --- Moving colliders --------------------------------------------------------------------------

MOVING_SPHERE = {"type": "sphere", "center": [0.0, 0.0, 0.5], "radius": 0.2, "motion": {"velocity": [1.0, 0.0, 0.0]}}
LIFTED_MESH = {
    "type": "mesh",
    "vertices": [[-0.5, 1.0, 0.0], [0.5, 1.0, 0.0], [0.0, 1.5, 0.0]],
    "faces": [[0, 1, 2]],
    "motion": {
        "times": [0.0, 1.0],
        "translations": [[0, 0, 0], [0, 0, 0.5]],
        "rotations": [[1, 0, 0, 0], [0.7071067811865476, 0, 0, 0.7071067811865476]],
        "pivot": [0, 1.25, 0],
    },
}


def _beside_a_moving_sphere() -> kinema.Trajectory:
    """Four balls resting on a line for 1 s (11 frames), beside a sphere moving 1 m along x, a
    triangle rising and turning, and a still floor."""
    positions = np.zeros((11, 4, 3))
    positions[:, :, 0] = np.linspace(-0.5, 1.5, 4)
    positions[:, :, 1] = -0.8
    positions[:, :, 2] = 0.1
    floor = {"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}
    return _traj(positions, colliders=[floor, MOVING_SPHERE, LIFTED_MESH])


def _page_poses(entry: dict) -> np.ndarray:
    """A page collider's poses as (F, 4, 4) row-major matrices."""
    return np.frombuffer(base64.b64decode(entry["poses"]), "<f4").reshape(-1, 4, 4).transpose(0, 2, 1)


def test_moving_colliders_reach_the_page_as_a_matrix_per_frame(tmp_path):
    from kinema.render.descriptions import collider_poses

    traj = _beside_a_moving_sphere()
    data = _page_data(viewer.write_html(traj, tmp_path / "m.html").read_text(encoding="utf-8"))
    floor, sphere, mesh = data["colliders"]
    assert "poses" not in floor  # still: drawn as described
    # The sphere and the mesh are described as added, with the engine's pose at each frame time.
    assert sphere["center"] == [0.0, 0.0, 0.5] and mesh["lo"] == [-0.5, 1.0, 0.0]
    for entry, description in ((sphere, MOVING_SPHERE), (mesh, LIFTED_MESH)):
        poses = _page_poses(entry)
        assert poses.shape == (11, 4, 4)
        expected = collider_poses(description, data["t"])
        np.testing.assert_allclose(poses[:, :3, :], expected, atol=1e-6)
        np.testing.assert_array_equal(poses[:, 3], np.tile([0, 0, 0, 1], (11, 1)))
    np.testing.assert_allclose(_page_poses(sphere)[-1, :3, 3], [1.0, 0.0, 0.0], atol=1e-6)  # 1 m along x at t = 1 s
    # The extent holds where they go: the sphere's far side at x = 1.2, the mesh's top at z = 0.5.
    assert data["extent"]["max"][0] >= 1.2 - 1e-9 and data["extent"]["max"][2] >= 0.5 - 1e-9
    # A motion the engine refuses is not drawn (as a malformed description is not).
    bad = {**MOVING_SPHERE, "motion": {"velocity": [1.0, 0.0]}}
    assert _page_data(viewer.write_html(_falling(colliders=[bad]), tmp_path / "b.html").read_text(encoding="utf-8"))["colliders"] == []


@pytest.mark.parametrize("served", [False, True])
def test_a_moving_collider_moves_on_the_page_from_frame_to_frame(open_page, tmp_path, served):
    traj = _beside_a_moving_sphere()
    page = open_page(traj, served=served)
    first = page.show(0)
    assert [m["type"] for m in first["moving"]] == ["sphere", "mesh"]
    start = page.pixels(tmp_path / "start.png")
    last = page.show(10)
    end = page.pixels(tmp_path / "end.png")
    # The objects are drawn with the poses of the frame shown.
    data = viewer_page.pack(traj, viewer_page.HTML_MAX_BYTES)
    for m, entry in zip(last["moving"], data.meta["colliders"][1:], strict=True):
        np.testing.assert_allclose(np.reshape(m["matrix"], (4, 4)).T, _page_poses(entry)[10], atol=1e-6)
    np.testing.assert_allclose(np.reshape(first["moving"][0]["matrix"], (4, 4)), np.eye(4), atol=1e-7)
    _assert_in_view(last)
    # The sphere moved across the view: the shaded grey (darker than the floor and its grid)
    # seen only at the start and that seen only at the end lie a sixth of the width apart.
    grey = lambda image: (np.ptp(image, axis=2) < 12) & (image.mean(axis=2) > 60) & (image.mean(axis=2) < 170)  # noqa: E731
    a, b = grey(start), grey(end)
    gone, come = a & ~b, b & ~a
    assert gone.sum() > 500 and come.sum() > 500
    shift = np.nonzero(come)[1].mean() - np.nonzero(gone)[1].mean()
    assert abs(shift) > start.shape[1] / 6, f"the sphere moved {shift:.1f} px"


# --- Springs, births and deaths ----------------------------------------------------------------


def _chain(frames=6, death=3) -> kinema.Trajectory:
    """Four particles of ids 10..13 in a row joined by three springs; 13 dies at ``death``."""
    n = 4
    positions = np.zeros((frames, n, 3))
    positions[:, :, 0] = np.arange(n) * 0.4
    positions[:, :, 2] = np.linspace(1, 0.5, frames)[:, None]
    alive = np.ones((frames, n), dtype=bool)
    alive[death:, 3] = False
    positions[~alive] = np.nan
    return _traj(positions, ids=np.arange(10, 10 + n), alive=alive, springs=np.array([[10, 11], [11, 12], [12, 13]]))


@pytest.mark.parametrize("served", [False, True])
def test_springs_are_drawn_while_both_ends_live(open_page, tmp_path, served):
    page = open_page(_chain(), served=served)
    first = page.info()
    assert first["springs"] == {"total": 3, "visible": 3} and first["particles"] == {"total": 4, "visible": 4}
    later = page.show(4)
    assert later["springs"] == {"total": 3, "visible": 2} and later["particles"]["visible"] == 3
    assert page.show(2)["springs"]["visible"] == 3  # and back
    _assert_in_view(later)


def _births_and_deaths(n=30, frames=10) -> kinema.Trajectory:
    """Particle i is born at frame i // 4 and dies at frame 4 + i // 3 (some never die)."""
    rng = np.random.default_rng(5)
    born = np.arange(n) // 4
    dies = 4 + np.arange(n) // 3
    k = np.arange(frames)[:, None]
    alive = (k >= born) & (k < dies)
    positions = rng.uniform(0, 1, (1, n, 3)) + 0.05 * k[..., None] * rng.normal(size=(1, n, 3))
    velocities = np.broadcast_to(rng.normal(size=(1, n, 3)), (frames, n, 3)).copy()
    positions[~alive] = np.nan
    velocities[~alive] = np.nan
    return _traj(positions, velocities, alive=alive)


@pytest.mark.parametrize("served", [False, True])
def test_only_the_live_particles_are_drawn(open_page, served):
    traj = _births_and_deaths()
    page = open_page(traj, served=served)
    for k in (0, 3, 5, 9):
        info = page.show(k)
        assert info["particles"] == {"total": 30, "visible": int(traj.alive[k].sum())}, k
        assert info["inView"]["particles"]
    assert "of 30 particles" in page.page.inner_text("#kinema-info")


def test_dead_particles_leave_no_pixels(open_page, tmp_path):
    # A 2D grid of 24 discs, still and well apart; disc i lives from frame i // 6 to frame
    # 2 + i // 4: the discs one sees on the canvas are the live ones.
    ndimage = pytest.importorskip("scipy.ndimage")
    n, frames = 24, 6
    xy = np.stack(np.meshgrid(np.arange(6), np.arange(4)), axis=-1).reshape(n, 2).astype(float)
    positions = np.broadcast_to(np.concatenate([xy, np.zeros((n, 1))], axis=1), (frames, n, 3)).copy()
    k = np.arange(frames)[:, None]
    alive = (k >= np.arange(n) // 6) & (k <= 2 + np.arange(n) // 4)
    positions[~alive] = np.nan
    traj = _traj(positions, np.zeros_like(positions), alive=alive, dim=2, radii=np.full(n, 0.2))
    page = open_page(traj, size=(800, 600))
    page.page.select_option("#kinema-colour", "none")  # no legend over the view
    for frame in (0, 2, 5):
        info = page.show(frame)
        image = page.pixels(tmp_path / f"alive{frame}.png")
        lit = np.abs(image - np.array([16, 16, 20])).max(axis=2) > 40
        _, blobs = ndimage.label(lit)
        assert blobs == info["particles"]["visible"] == alive[frame].sum(), (frame, blobs)


def test_the_page_carries_alive_as_bits_and_no_nan(tmp_path):
    traj = _births_and_deaths()
    data = _page_data(viewer.write_html(traj, tmp_path / "run.html").read_text(encoding="utf-8"))
    frames, n = traj.alive.shape
    bits = np.frombuffer(base64.b64decode(data["alive"]), dtype=np.uint8).reshape(frames, -1)
    assert data["aliveBytes"] == bits.shape[1] == math.ceil(n / 8)
    np.testing.assert_array_equal(np.unpackbits(bits, axis=1, bitorder="little")[:, :n].astype(bool), traj.alive)
    positions = np.frombuffer(base64.b64decode(data["positions"]), dtype="<f4").reshape(frames, n, 3)
    assert np.isfinite(positions).all() and not positions[~traj.alive].any()
    np.testing.assert_allclose(positions[traj.alive], traj.positions[traj.alive], rtol=1e-6, atol=1e-6)
    # The extent is the live particles' with their radii.
    live = traj.positions[traj.alive]
    np.testing.assert_allclose(data["extent"]["min"], live.min(axis=0) - 0.05, rtol=1e-9)
    np.testing.assert_allclose(data["extent"]["max"], live.max(axis=0) + 0.05, rtol=1e-9)
    # All alive: no mask at all (and the served data is as long as before).
    plain = _page_data(viewer.write_html(_falling(), tmp_path / "plain.html").read_text(encoding="utf-8"))
    assert plain["alive"] is None and plain["aliveBytes"] == 0 and plain["springs"] is None


def test_springs_map_ids_to_columns_and_survive_left_out_particles(tmp_path):
    traj = _chain()
    packed = viewer_page.pack(traj, viewer_page.HTML_MAX_BYTES)
    np.testing.assert_array_equal(packed.springs, [0, 1, 1, 2, 2, 3])
    # Springs to an id the trajectory has not are dropped; with every other particle left
    # out, only springs between kept particles remain, renumbered.
    traj.springs = np.array([[10, 12], [11, 12], [10, 99]])
    with pytest.warns(viewer.ViewerWarning):
        packed = viewer_page.pack(traj, max_bytes=6 * 2 * 16)  # 6 frames of 2 particles
    assert packed.meta["n"] == 2 and packed.meta["springCount"] == 1
    np.testing.assert_array_equal(packed.springs, [0, 1])
    body, layout = viewer_server._binary(packed)
    start, count = layout["springs"]
    np.testing.assert_array_equal(np.frombuffer(body, "<i4", count, start), [0, 1])
    assert layout["alive"] is None  # the one particle that dies (id 13) is left out
    # Served, the alive bits follow the rest, one byte per frame here (4 particles).
    packed = viewer_page.pack(_chain(), viewer_page.SERVE_MAX_BYTES)
    body, layout = viewer_server._binary(packed)
    start, count = layout["alive"]
    assert count == 6 and len(body) == start + 8  # padded to a multiple of 4 bytes
    np.testing.assert_array_equal(np.frombuffer(body, np.uint8, count, start), [15, 15, 15, 7, 7, 7])


def test_colliders_reach_the_page_without_infinities(tmp_path):
    colliders = [
        {"type": "box", "lo": [0, 0], "hi": [2, math.inf], "restitution": 0.5},
        {"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 2]},
        {"type": "sphere", "center": [0, 0, 3], "radius": 0.5},
    ]
    data = _page_data(viewer.write_html(_falling(colliders=colliders), tmp_path / "c.html").read_text(encoding="utf-8"))
    assert data["colliders"] == [
        {"type": "box", "lo": [0, 0, None], "hi": [2, None, None]},
        {"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 2]},
        {"type": "sphere", "center": [0, 0, 3], "radius": 0.5},
    ]
    # The extent holds the box's finite bounds and the sphere (not the open ones).
    assert data["extent"]["min"][:2] == [-0.5, -0.5] and data["extent"]["max"][0] == 2 and data["extent"]["max"][2] == 3.5


def test_unknown_velocities_give_no_speed_colouring(tmp_path):
    # A file without velocities loads with NaN velocities: the page colours by id, not by a
    # speed of 0 everywhere.
    traj = _falling()
    traj.velocities = np.full_like(traj.positions, np.nan)
    data = _page_data(viewer.write_html(traj, tmp_path / "v.html").read_text(encoding="utf-8"))
    assert data["speed"] is None and data["speedMin"] == data["speedMax"] == 0


# --- The legend ---------------------------------------------------------------------------------


def test_the_legend_names_the_colouring_and_its_range(open_page):
    traj = _births_and_deaths()
    speed = np.linalg.norm(traj.velocities, axis=2)[traj.alive]
    page = open_page(traj)

    def legend() -> tuple[str, float, float]:
        assert page.page.is_visible("#kinema-legend")
        label = page.page.inner_text("#kinema-legend-label")
        return label, float(page.page.inner_text("#kinema-legend-min")), float(page.page.inner_text("#kinema-legend-max"))

    label, low, high = legend()
    assert label == "speed (m/s)" and page.info()["legend"]["label"] == label
    assert low == pytest.approx(speed.min(), rel=5e-3) and high == pytest.approx(speed.max(), rel=5e-3)
    page.page.select_option("#kinema-colour", "id")
    assert legend() == ("particle id", 0, 29)
    page.page.select_option("#kinema-colour", "none")
    assert not page.page.is_visible("#kinema-legend") and page.info()["legend"] == {"shown": False}
    page.page.select_option("#kinema-colour", "speed")
    assert legend()[0] == "speed (m/s)"


def _legend_text(page) -> tuple[str, str]:
    return page.page.inner_text("#kinema-legend-min"), page.page.inner_text("#kinema-legend-max")


@pytest.mark.parametrize("served", [False, True])
def test_the_id_legend_is_the_least_and_greatest_id_shown(open_page, served):
    # 1,250 particles, ids 0 … 1249 (the fountain's): the legend read 0 … 1250 (1249 to three
    # significant digits); ids are shown exactly, whatever their number of digits.
    traj = _falling(n=1250, frames=3)
    page = open_page(traj, served=served, color_by="id")
    assert page.info()["legend"]["label"] == "particle id"
    assert _legend_text(page) == ("0", "1249")
    traj.ids = np.arange(1250) + 98_765_000  # a later stretch of ids
    page = open_page(traj, served=served, color_by="id")
    assert _legend_text(page) == ("98765000", "98766249")
    # Every other particle left out: the legend is what is shown (the kept columns' ids).
    with pytest.warns(viewer.ViewerWarning):
        page = open_page(traj, served=served, color_by="id", max_bytes=3 * 625 * 16)
    assert page.info()["particles"]["total"] == 625
    assert _legend_text(page) == ("98765000", "98766248")


def test_the_speed_legend_is_the_least_and_greatest_live_speed(open_page):
    # Speeds from 0.0123456 to 1249.7 m/s among the live particles, 5000 m/s on a dead one's
    # column (NaN in the trajectory, never shown): the legend is 0.0123 … 1250, three
    # significant digits as the renderer's legend but never fewer than the integer digits.
    traj = _births_and_deaths()
    speeds = np.linspace(0.0123456, 1249.7, 30)
    velocities = np.zeros_like(traj.velocities)
    velocities[..., 0] = speeds
    velocities[~traj.alive] = np.nan
    traj.velocities = velocities
    page = open_page(traj)
    legend = page.info()["legend"]
    assert legend["label"] == "speed (m/s)"
    live = np.linalg.norm(velocities, axis=2)[traj.alive].astype(np.float32)
    assert legend["min"] == pytest.approx(live.min(), rel=1e-7) and legend["max"] == pytest.approx(live.max(), rel=1e-7)
    assert _legend_text(page) == ("0.0123", "1250")
    velocities[..., 0] *= 0.01  # 0.000123456 … 12.497 m/s
    assert _legend_text(open_page(traj)) == ("0.000123", "12.5")


def test_color_draws_each_particles_own_colour_without_legend(open_page, tmp_path):
    # An emitter's particles have their own colour (Trajectory.colors; NaN: none, drawn in
    # the renderer's NO_OWN_COLOR); "color" shows them and no legend.
    positions = np.zeros((2, 3, 3))
    positions[:, :, 0] = [0, 1, 2]
    colors = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [np.nan, np.nan, np.nan]])
    traj = _traj(positions, dim=2, radii=np.full(3, 0.3), colors=colors)
    data = _page_data(viewer.write_html(traj, tmp_path / "c.html").read_text(encoding="utf-8"))
    rgba = np.frombuffer(base64.b64decode(data["colors"]), dtype=np.uint8).reshape(3, 4)
    np.testing.assert_array_equal(rgba, [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 0, 0]])
    assert data["noOwnColor"] == list(NO_OWN_COLOR) and data["colorBy"] is None
    page = open_page(traj)
    option = page.page.locator('#kinema-colour option[value="color"]')
    assert option.inner_text() == "color"
    assert page.info()["colouring"]["choice"] == "speed"  # the default: speed
    page.page.select_option("#kinema-colour", "color")
    info = page.info()
    assert info["legend"] == {"shown": False} and info["colouring"]["mode"] == 2
    # The colour buffer the GPU draws from: each particle's own, NO_OWN_COLOR for none.
    assert page.page.evaluate("() => window.kinemaViewer.ownColours()") == [[255, 0, 0], [0, 255, 0], list(NO_OWN_COLOR)]
    image = page.pixels(tmp_path / "own.png")
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    assert ((r > 150) & (g < 30) & (b < 30)).sum() > 100, "no red disc"
    assert ((g > 150) & (r < 30) & (b < 30)).sum() > 100, "no green disc"
    # The third disc is NO_OWN_COLOR shaded (r : g : b as 70 : 130 : 200), not the plain colour.
    own = (b > 100) & (b > r + 40)
    assert own.sum() > 100, "no disc in NO_OWN_COLOR"
    np.testing.assert_allclose([np.median(r[own] / b[own]), np.median(g[own] / b[own])], [70 / 200, 130 / 200], atol=0.02)
    # Without own colours there is no such choice, unless the trajectory asks for it.
    plain = open_page(_falling())
    assert plain.page.locator('#kinema-colour option[value="color"]').count() == 0
    asked = open_page(_falling(n=3), color_by="color")
    assert asked.info()["colouring"]["choice"] == "color"
    assert asked.page.evaluate("() => window.kinemaViewer.ownColours()") == [list(NO_OWN_COLOR)] * 3
    with pytest.raises(ValueError, match="color_by"):
        viewer.write_html(traj, tmp_path / "bad.html", color_by="colour")


@pytest.fixture(scope="module")
def fountain() -> kinema.Trajectory:
    """examples/scenes/fountain.toml over 2.5 s at 10 frames a second (droplets born and
    dying, an emitter colour, a floor plane)."""
    return Scene.from_toml(SCENES / "fountain.toml").build(source="fountain").run(2.5, fps=10)


@pytest.mark.parametrize("served", [False, True])
def test_the_fountain_in_its_own_colour(open_page, fountain, tmp_path, served):
    # The emitter's droplets (#2f7fd8) are born and die: in "color" the live ones are drawn in
    # that colour, shaded (r : g : b as 47 : 127 : 216), the dead ones not at all.
    traj = fountain
    assert traj.colors is not None and np.isfinite(traj.colors).all()
    page = open_page(traj, served=served, frame=20, color_by="color")
    assert page.page.eval_on_selector("#kinema-colour", "e => e.value") == "color"
    info = page.info()
    assert info["colouring"]["mode"] == 2 and info["legend"] == {"shown": False}
    assert info["particles"] == {"total": traj.alive.shape[1], "visible": int(traj.alive[20].sum())}
    assert 0 < info["particles"]["visible"] < info["particles"]["total"]
    colours = np.array(page.page.evaluate("() => window.kinemaViewer.ownColours()"))
    np.testing.assert_array_equal(colours, np.broadcast_to([0x2F, 0x7F, 0xD8], colours.shape))
    image = page.pixels(tmp_path / "fountain_color.png")
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    drop = (b > 60) & (b > r + 30)  # the droplets: blue on the grey floor and the dark background
    assert drop.sum() > 2000, drop.sum()
    np.testing.assert_allclose([np.median(r[drop] / b[drop]), np.median(g[drop] / b[drop])], [47 / 216, 127 / 216], atol=0.03)
    assert ((g > b) & (g > r + 30)).sum() == 0  # nothing green: no speed colours
    # Frame 0 holds the first droplets alone; by speed the droplets are viridis's greens.
    assert page.show(0)["particles"]["visible"] == int(traj.alive[0].sum())
    page.page.select_option("#kinema-colour", "speed")
    page.show(20)
    image = page.pixels(tmp_path / "fountain_speed.png")
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    assert ((g > b) & (g > r + 30)).sum() > 500


def test_a_scene_that_asks_for_own_colours_opens_in_them(open_page):
    # examples/scenes/pour.toml: [render] color_by = "color", the grains #c8a165, in a box
    # whose bottom is the floor.
    scene = Scene.from_toml(SCENES / "pour.toml")
    assert scene.render.color_by == "color"
    traj = scene.build(source="pour").run(0.6, fps=10)
    page = open_page(traj, frame=5, color_by=scene.render.color_by)
    info = page.info()
    assert page.page.eval_on_selector("#kinema-colour", "e => e.value") == "color"
    assert info["colouring"]["choice"] == "color" and info["colouring"]["mode"] == 2 and info["legend"] == {"shown": False}
    assert 0 < info["particles"]["visible"] < info["particles"]["total"]
    assert page.page.evaluate("() => window.kinemaViewer.ownColours()") == [[0xC8, 0xA1, 0x65]] * info["particles"]["total"]
    assert info["camera"]["floor"] == 0
    _assert_above(_drag(page, (400, 500), (400, 20), times=3))
    # Asked for "speed" (or nothing), the page opens by speed.
    assert open_page(traj, color_by="speed").info()["colouring"]["choice"] == "speed"


# --- The orbit ----------------------------------------------------------------------------------


def _drag(page, start, end, button="left", times=1) -> dict:
    for _ in range(times):
        page.page.mouse.move(*start)
        page.page.mouse.down(button=button)
        page.page.mouse.move(*end, steps=20)
        page.page.mouse.up(button=button)
    return page.info()["camera"]


def _assert_above(camera: dict) -> None:
    floor, clearance = camera["floor"], camera["clearance"]
    assert camera["position"][2] >= floor + clearance * (1 - 1e-6), camera
    assert camera["target"][2] >= floor - 1e-9 * clearance, camera
    assert camera["polar"] <= camera["maxPolar"] + 1e-9, camera


@pytest.mark.parametrize(
    ("floor", "colliders"),
    [
        (0.0, [{"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}]),
        (-0.2, [{"type": "box", "lo": [0, 0, -0.2], "hi": [1, 1, math.inf]}]),
        # The lowest floor: a box's bottom over a plane.
        (-0.5, [{"type": "plane", "point": [0, 0, -0.5], "normal": [0, 0, 3]}, {"type": "box", "lo": [0, 0, 0], "hi": [1, 1, 1.5]}]),
    ],
)
def test_the_orbit_stays_above_the_floor(open_page, floor, colliders):
    # Dragging up turns the camera down under the target; it stops just above the floor
    # (its clearance, 0.2 % of the scene's size), by orbiting, zooming out and panning down.
    page = open_page(_falling(colliders=colliders))
    camera = page.info()["camera"]
    assert camera["floor"] == pytest.approx(floor, abs=1e-12)
    start = camera["polar"]
    assert start < math.pi / 2 and camera["maxPolar"] > math.pi / 2  # may look up from below the target, above the floor
    camera = _drag(page, (400, 500), (400, 20), times=3)
    _assert_above(camera)
    assert camera["polar"] > start + 0.2 and camera["polar"] == pytest.approx(camera["maxPolar"], abs=1e-9)
    assert camera["position"][2] == pytest.approx(floor + camera["clearance"], rel=1e-6, abs=1e-9)
    page.page.mouse.move(400, 300)
    for _ in range(8):
        page.page.mouse.wheel(0, 400)  # zoom out: further away at the same height
    page.page.wait_for_function("(z) => window.kinemaViewer.info().camera.position[2] >= z", arg=floor, timeout=WAIT_MS)
    _assert_above(page.info()["camera"])
    camera = _drag(page, (400, 540), (400, 20), button="right", times=3)  # pan: the scene up, the target down
    _assert_above(camera)
    assert camera["target"][2] == pytest.approx(floor, abs=1e-9)  # stopped at the floor
    # A page that is not touched keeps its framing.
    _assert_in_view(open_page(_falling(colliders=colliders)).info())


def test_without_a_floor_the_orbit_is_free_and_2d_has_none(open_page, tmp_path):
    page = open_page(_falling())
    camera = page.info()["camera"]
    assert camera["floor"] is None and camera["maxPolar"] == pytest.approx(math.pi)
    camera = _drag(page, (400, 500), (400, 20), times=3)
    assert camera["polar"] > math.pi / 2 + 0.3  # under where a floor would be
    # A wall (a plane facing sideways) and a ceiling are no floor.
    walls = [{"type": "plane", "point": [0, 0, 0], "normal": [1, 0, 0]}, {"type": "plane", "point": [0, 0, 2], "normal": [0, 0, -1]}]
    assert open_page(_falling(colliders=walls)).info()["camera"]["floor"] is None
    positions = np.zeros((2, 3, 3))
    positions[:, :, 0] = [0, 1, 2]
    flat = _traj(positions, dim=2, colliders=[{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0]}])
    assert open_page(flat).info()["camera"]["floor"] is None


# --- Framing ------------------------------------------------------------------------------------


def _cradle() -> kinema.Trajectory:
    """examples/scenes/newtons_cradle.toml (2D), shortened, with its strings: springs from the
    pinned anchors (ids 0–4, the bar) to the balls (5–9)."""
    world = kinema.load_scene(Path(__file__).resolve().parent.parent / "examples" / "scenes" / "newtons_cradle.toml")
    traj = world.run(0.3, fps=20)
    if traj.springs is None:  # (worlds that do not record their springs yet)
        traj.springs = np.array([[i, i + 5] for i in range(5)])
    return traj


@pytest.mark.parametrize("scene", ["box and plane", "cradle"])
def test_everything_is_in_view_at_a_wide_and_a_tall_aspect(open_page, scene):
    if scene == "cradle":
        traj = _cradle()
    else:
        colliders = [{"type": "plane", "point": [0, 0, -0.5], "normal": [0, 0, 1]}, {"type": "box", "lo": [0, 0, 0], "hi": [1, 1, 1.5]}]
        traj = _falling(colliders=colliders)
    frames = traj.t.size
    page = open_page(traj, size=WIDE, frame=frames - 1)
    for size in (WIDE, TALL):
        info = page.resize(size) if size != WIDE else page.info()
        assert info["canvas"]["width"] == size[0]
        _assert_in_view(info)
        for k in (0, frames // 2):
            _assert_in_view(page.show(k))
    if scene == "cradle":
        assert info["springs"] == {"total": 5, "visible": 5} and info["particles"]["visible"] == 10


def test_slow_particles_stay_visible_on_the_dark_background(open_page, tmp_path):
    # Issue 28: viridis's bottom (luma 30) is near black on the page's near-black background;
    # the slowest value sits at low_end("viridis") = 0.25 of the map, as in kinema's renderer:
    # a ball at rest beside a fast one is steel blue (luma about 80), not near black.
    assert kinema.render.low_end("viridis") == 0.25
    x = np.array([[[-0.3, 0.0, 0.0], [0.3, 0.0, 0.0]]] * 3)
    v = np.zeros_like(x)
    v[:, 1, 0] = 2.0  # the right ball moves at 2 m/s, the left one is at rest
    traj = _traj(x, v, radii=np.full(2, 0.2))
    page = open_page(traj, frame=1, color_by="speed")
    image = page.pixels(tmp_path / "slow.png").astype(float)
    luma = image @ [0.299, 0.587, 0.114]
    left = luma[:, : image.shape[1] // 3]  # the slow ball's side (the fast one is right of centre)
    slow = left[left > 20]  # its pixels: the background's luma is about 16
    assert slow.size > 500, slow.size
    # steel blue (median luma 66 as drawn, shaded) where viridis's own bottom gave 27
    assert np.median(slow) > 50, np.median(slow)
