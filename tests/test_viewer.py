"""The browser viewer: the self-contained page and the local server, driven in headless Chromium."""

from __future__ import annotations

import base64
import json
import os
import re
import shutil
import subprocess
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import kinema
from kinema import viewer
from kinema.viewer import page as viewer_page

BACKGROUND = np.array([16, 16, 20])  # the page's clear colour, 0x101014
VIEW_ROWS = 540  # the 3D view of an 800x600 window; the UI bar (time, slider) is below


def _trajectory() -> kinema.Trajectory:
    rng = np.random.default_rng(7)
    world = kinema.World(dt=1e-3)
    world.add_particles(rng.uniform(-1, 1, (40, 3)), velocity=rng.normal(0, 1.0, (40, 3)), radius=0.08)
    return world.run(1.0, fps=10)


@pytest.fixture(scope="module")
def traj() -> kinema.Trajectory:
    return _trajectory()


@pytest.fixture(scope="module")
def chromium() -> str:
    found = shutil.which("chromium") or ("/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None)
    if found is None and shutil.which("apt-get") and os.geteuid() == 0:
        install = "apt-get install -y chromium || (apt-get update && apt-get install -y chromium)"
        subprocess.run(["sh", "-c", install], capture_output=True, timeout=900)
        found = shutil.which("chromium")
    if found is None:
        pytest.skip("Debian's chromium is not installed and could not be installed (apt-get install -y chromium)")
    return found


def _screenshot(chromium: str, url: str, out: Path) -> np.ndarray:
    """The page at ``url`` in headless Chromium (WebGL by SwiftShader), 800x600, as RGB."""
    profile = out.with_suffix(".profile")
    command = [
        chromium,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        f"--user-data-dir={profile}",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--hide-scrollbars",
        "--window-size=800,600",
        "--virtual-time-budget=5000",
        f"--screenshot={out}",
        url,
    ]
    run = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert out.exists(), f"chromium wrote no screenshot (status {run.returncode}):\n{run.stderr[-2000:]}"
    return np.asarray(Image.open(out).convert("RGB"), dtype=np.int16)


def _particle_mask(image: np.ndarray) -> np.ndarray:
    view = image[:VIEW_ROWS]
    return np.abs(view - BACKGROUND).max(axis=2) > 40


def _page_data(html: str) -> dict:
    match = re.search(r'<script type="application/json" id="kinema-data">(.*?)</script>', html, re.S)
    assert match, "the page has no kinema-data element"
    return json.loads(match.group(1))


def test_html_page_draws_particles_that_move(traj, chromium, tmp_path):
    path = viewer.write_html(traj, tmp_path / "run.html")
    url = path.resolve().as_uri()
    first = _screenshot(chromium, url + "#frame=0", tmp_path / "frame0.png")
    last = _screenshot(chromium, url + "#frame=9", tmp_path / "frame9.png")
    drawn0, drawn9 = _particle_mask(first), _particle_mask(last)
    # 40 discs of a few pixels' radius each: hundreds of lit pixels, and far from all of them.
    assert 200 < drawn0.sum() < 0.5 * drawn0.size, f"{drawn0.sum()} non-background pixels at frame 0"
    assert 200 < drawn9.sum() < 0.5 * drawn9.size, f"{drawn9.sum()} non-background pixels at frame 9"
    # The particles moved: many pixels are lit in one frame and not the other.
    moved = np.logical_xor(drawn0, drawn9).sum()
    assert moved > 0.3 * min(drawn0.sum(), drawn9.sum()), f"only {moved} pixels changed between frames 0 and 9"


def test_served_page_draws_particles(traj, chromium, tmp_path):
    url, server = viewer.serve(traj, open_browser=False)
    try:
        image = _screenshot(chromium, url + "#frame=5", tmp_path / "served.png")
    finally:
        server.shutdown()
    assert _particle_mask(image).sum() > 200


def test_html_is_self_contained(traj, tmp_path):
    html = viewer.write_html(traj, tmp_path / "run.html").read_text(encoding="utf-8")
    assert "<script src" not in html and "<link" not in html and "import(" not in html
    data = _page_data(html)
    assert data["n"] == 40 and data["frames"] == 11 and data["note"] == ""
    positions = np.frombuffer(base64.b64decode(data["positions"]), dtype="<f4").reshape(11, 40, 3)
    np.testing.assert_allclose(positions, traj.positions, rtol=1e-6, atol=1e-6)
    assert not list(tmp_path.glob("*.part")), "the temporary file was left behind"


def test_serve_answers_on_loopback(traj):
    url, server = viewer.serve(traj, open_browser=False)
    try:
        assert url.startswith("http://127.0.0.1:") and server.server_address[1] != 0
        with urllib.request.urlopen(url, timeout=10) as page:
            assert page.status == 200
            data = _page_data(page.read().decode("utf-8"))
        with urllib.request.urlopen(url + "data.bin", timeout=10) as blob:
            assert blob.status == 200
            body = blob.read()
        frames, n = traj.positions.shape[:2]
        assert len(body) == 4 * (frames * n * 3 + frames * n + n)  # positions, speed, radii
        start, count = data["layout"]["positions"]
        np.testing.assert_allclose(np.frombuffer(body, "<f4", count, start).reshape(frames, n, 3), traj.positions, rtol=1e-6, atol=1e-6)
        with pytest.raises(urllib.error.HTTPError) as missing:
            urllib.request.urlopen(url + "elsewhere", timeout=10)
        assert missing.value.code == 404
    finally:
        server.shutdown()


def test_large_trajectory_is_downsampled_with_a_warning(traj, tmp_path):
    with pytest.warns(viewer.ViewerWarning, match="showing"):
        path = viewer.write_html(traj, tmp_path / "small.html", max_bytes=40 * 16 * 4)
    data = _page_data(path.read_text(encoding="utf-8"))
    assert data["frames"] * data["n"] * 16 <= 40 * 16 * 4
    assert data["note"].startswith("showing")


def test_missing_bundle_says_to_build(traj, tmp_path, monkeypatch):
    monkeypatch.setattr(viewer_page, "BUNDLE", tmp_path / "absent.js")
    with pytest.raises(viewer.BundleMissingError, match="make build"):
        viewer.write_html(traj, tmp_path / "run.html")
    assert not (tmp_path / "run.html").exists()


def test_kinema_view_writes_a_self_contained_page(tmp_path):
    # `kinema view TRAJ --html out.html`: one file, nothing fetched; the same page the
    # viewer serves, with the trajectory's positions inside.
    from typer.testing import CliRunner

    from kinema.cli import app

    w = kinema.World(dt=0.01)
    w.add_particles([[0, 0, 0], [1, 0, 0]], velocity=[[0, 1, 0], [0, -1, 0]], radius=0.1)
    traj = w.run(0.2, fps=10)
    traj.save(tmp_path / "run.h5")
    result = CliRunner().invoke(app, ["view", str(tmp_path / "run.h5"), "--html", str(tmp_path / "page.html")])
    assert result.exit_code == 0, result.output
    text = (tmp_path / "page.html").read_text()
    assert "<script src" not in text and 'id="kinema-data"' in text
    bad = CliRunner().invoke(app, ["view", str(tmp_path / "missing.h5"), "--html", str(tmp_path / "x.html")])
    assert bad.exit_code == 2 and "no such file" in bad.output
