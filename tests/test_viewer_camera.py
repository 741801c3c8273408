"""The browser viewer opens at the scene's own ``[render] camera`` when it has one (issue 48:
the drum opened obliquely, not along its axis), and counts "1 particle" / "N particles".
Read back from the three.js camera through the page's ``window.kinemaViewer.info()`` in
headless Chromium, and from the data the page carries without a browser."""

from __future__ import annotations

import numpy as np
import pytest
from test_viewer import browser, chromium  # noqa: F401 (the browser fixtures)
from test_viewer_scene import _falling, _page_data, _traj, open_page  # noqa: F401 (open_page: a fixture)
from typer.testing import CliRunner

import kinema
from kinema.cli import app
from kinema.viewer import page as viewer_page

# The drum's camera (examples/scenes/drum.toml): along its axis (y), from the front.
DRUM_CAMERA = kinema.Camera3D(eye=(0.05, -1.35, 0.05), target=(0.0, 0.0, 0.0), fov_deg=28.0)


def _flat(n=5, frames=4) -> kinema.Trajectory:
    """``n`` discs moving along x in the xy-plane (2D)."""
    x = np.linspace(0.0, 1.0, frames)[:, None] + np.arange(n)[None, :] * 0.3
    positions = np.stack([x, np.full_like(x, 0.2), np.zeros_like(x)], axis=2)
    return _traj(positions, dim=2)


# -- the data the page carries -------------------------------------------------------------


def test_the_page_carries_the_camera_it_is_given():
    meta = _page_data(viewer_page.html_page(_falling(), camera=DRUM_CAMERA))
    assert meta["camera"] == {"type": "3d", "eye": [0.05, -1.35, 0.05], "target": [0.0, 0.0, 0.0], "up": [0.0, 0.0, 1.0], "fovDeg": 28.0}
    meta = _page_data(viewer_page.html_page(_flat(), camera=kinema.Camera2D(-1.0, -0.5, 3.0, 1.5)))
    assert meta["camera"] == {"type": "2d", "view": [-1.0, -0.5, 3.0, 1.5]}
    assert _page_data(viewer_page.html_page(_falling()))["camera"] is None


def test_a_camera_of_the_other_dimension_is_refused():
    with pytest.raises(ValueError, match=r"camera = .* is invalid: a 2D trajectory is viewed by a kinema.Camera2D"):
        viewer_page.html_page(_flat(), camera=DRUM_CAMERA)
    with pytest.raises(ValueError, match=r"camera = .* is invalid: a 3D trajectory is viewed by a kinema.Camera3D"):
        viewer_page.html_page(_falling(), camera=kinema.Camera2D(0, 0, 1, 1))
    with pytest.raises(TypeError, match=r"camera = 'front' is invalid: give a kinema.Camera3D"):
        viewer_page.html_page(_falling(), camera="front")


# -- in the browser ------------------------------------------------------------------------


def test_3d_opens_at_the_given_camera_and_keeps_it_on_resize(open_page):  # noqa: F811
    page = open_page(_falling(), size=(800, 600), camera=DRUM_CAMERA)
    cam = page.info()["camera"]
    assert cam["given"] == "3d"
    np.testing.assert_allclose(cam["position"], DRUM_CAMERA.eye, atol=1e-9)
    np.testing.assert_allclose(cam["target"], DRUM_CAMERA.target, atol=1e-9)
    np.testing.assert_allclose(cam["up"], [0, 0, 1], atol=1e-12)
    assert cam["fov"] == 28.0
    cam = page.resize((500, 700))["camera"]
    np.testing.assert_allclose(cam["position"], DRUM_CAMERA.eye, atol=1e-9)
    np.testing.assert_allclose(cam["target"], DRUM_CAMERA.target, atol=1e-9)


def test_3d_without_a_camera_fits_its_own_view(open_page):  # noqa: F811
    cam = open_page(_falling(), size=(800, 600)).info()["camera"]
    assert cam["given"] is None and cam["fov"] == 45.0
    assert np.linalg.norm(np.subtract(cam["position"], DRUM_CAMERA.eye)) > 0.1


def test_a_tilted_up_and_another_field_of_view_are_the_cameras(open_page):  # noqa: F811
    camera = kinema.Camera3D(eye=(3.0, 0.5, 0.5), target=(0.5, 0.5, 0.5), up=(0.0, 1.0, 1.0), fov_deg=60.0)
    cam = open_page(_falling(), camera=camera).info()["camera"]
    np.testing.assert_allclose(cam["position"], camera.eye, atol=1e-9)
    np.testing.assert_allclose(cam["up"], np.array([0.0, 1.0, 1.0]) / np.sqrt(2.0), atol=1e-12)
    assert cam["fov"] == 60.0


def test_2d_opens_at_the_given_rectangle_centred_aspect_kept(open_page):  # noqa: F811
    rect = (-1.0, -0.5, 3.0, 1.5)  # 4 m × 2 m
    for size in ((800, 600), (1200, 300)):
        cam = open_page(_flat(), size=size, camera=kinema.Camera2D(*rect)).info()["camera"]
        assert cam["given"] == "2d"
        x0, y0, x1, y1 = cam["view"]
        assert (x0 + x1) / 2 == pytest.approx(1.0) and (y0 + y1) / 2 == pytest.approx(0.5)
        # the rectangle fits: it is inside the view, and touches it on one pair of sides
        assert x0 <= rect[0] + 1e-9 and x1 >= rect[2] - 1e-9 and y0 <= rect[1] + 1e-9 and y1 >= rect[3] - 1e-9
        assert min(x1 - x0 - 4.0, y1 - y0 - 2.0) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("n, text", [(1, "1 particle ·"), (3, "3 particles ·")])
def test_the_count_agrees_with_its_noun(open_page, n, text):  # noqa: F811
    page = open_page(_falling(n=n))
    shown = page.page.evaluate("() => document.getElementById('kinema-info').textContent")
    assert shown.startswith(text), shown


def test_kinema_view_of_a_scene_opens_at_its_render_camera(open_page, browser, tmp_path):  # noqa: F811
    """`kinema view scene.toml --html` with the drum's [render] camera line (a few balls in a
    box, so that it runs in a moment)."""
    from test_viewer_scene import _Page

    scene = tmp_path / "s.toml"
    scene.write_text(
        "[world]\ndim = 3\ndt = 0.01\nduration = 0.1\nfps = 20\n"
        '[[particles]]\ntype = "list"\npositions = [[0.0, 0.0, 0.1], [0.05, 0.0, 0.1]]\nradius = 0.01\n'
        '[[forces]]\ntype = "gravity"\n'
        "[render]\n"
        'camera = { type = "3d", eye = [0.05, -1.35, 0.05], target = [0.0, 0.0, 0.0], fov_deg = 28 }\n'
    )
    out = tmp_path / "v.html"
    res = CliRunner().invoke(app, ["view", str(scene), "--html", str(out)])
    assert res.exit_code == 0, res.output
    assert _page_data(out.read_text(encoding="utf-8"))["camera"]["eye"] == [0.05, -1.35, 0.05]
    page = _Page(browser, out.resolve().as_uri() + "#frame=0", (640, 480))
    try:
        cam = page.info()["camera"]
        np.testing.assert_allclose(cam["position"], DRUM_CAMERA.eye, atol=1e-9)
        np.testing.assert_allclose(cam["target"], DRUM_CAMERA.target, atol=1e-9)
        assert cam["fov"] == 28.0
        shown = page.page.evaluate("() => document.getElementById('kinema-info').textContent")
        assert shown.startswith("2 particles ·"), shown
    finally:
        page.close()


def test_kinema_view_of_a_2d_scene_opens_at_its_rectangle(browser, tmp_path):  # noqa: F811
    from test_viewer_scene import _Page

    scene = tmp_path / "s2.toml"
    scene.write_text(
        "[world]\ndim = 2\ndt = 0.01\nduration = 0.1\nfps = 20\n"
        '[[particles]]\ntype = "list"\npositions = [[0.0, 0.1]]\nradius = 0.01\n'
        "[render]\n"
        'camera = { type = "2d", xmin = -2.0, ymin = -1.0, xmax = 2.0, ymax = 1.0 }\n'
    )
    out = tmp_path / "v2.html"
    res = CliRunner().invoke(app, ["view", str(scene), "--html", str(out)])
    assert res.exit_code == 0, res.output
    page = _Page(browser, out.resolve().as_uri() + "#frame=0", (800, 400))  # the canvas is 2:1 less the UI bar
    try:
        cam = page.info()["camera"]
        assert cam["given"] == "2d"
        x0, y0, x1, y1 = cam["view"]
        assert (x0 + x1) / 2 == pytest.approx(0.0, abs=1e-12) and (y0 + y1) / 2 == pytest.approx(0.0, abs=1e-12)
        assert min(x1 - x0 - 4.0, y1 - y0 - 2.0) == pytest.approx(0.0, abs=1e-9)
        shown = page.page.evaluate("() => document.getElementById('kinema-info').textContent")
        assert shown.startswith("1 particle ·"), shown
    finally:
        page.close()
