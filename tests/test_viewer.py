"""The browser viewer: the self-contained page and the local server, driven in headless Chromium."""

from __future__ import annotations

import base64
import html
import json
import os
import queue
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import kinema
from kinema import viewer
from kinema.viewer import page as viewer_page
from kinema.viewer import server as viewer_server

BACKGROUND = np.array([16, 16, 20])  # the page's clear colour, 0x101014
VIEW_ROWS = 540  # the 3D view of an 800x600 window; the UI bar (time, slider) is below
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--disable-background-networking"]
WAIT_MS = 120_000  # a bound on waits for the browser, so that a hang fails; never a speed limit

# The body of _trajectory, also run in a Jupyter kernel by the notebook test.
TRAJECTORY_CODE = """
import numpy as np
import kinema

rng = np.random.default_rng(7)
world = kinema.World(dt=1e-3)
world.add_particles(rng.uniform(-1, 1, (40, 3)), velocity=rng.normal(0, 1.0, (40, 3)), radius=0.08)
traj = world.run(1.0, fps=10)
"""


def _trajectory() -> kinema.Trajectory:
    scope: dict = {}
    exec(TRAJECTORY_CODE, scope)
    return scope["traj"]


def _random_motion(n: int, frames: int, fps: float) -> kinema.Trajectory:
    """``n`` particles in the unit cube stepping at random: ``frames`` frames at ``fps``."""
    rng = np.random.default_rng(3)
    velocities = rng.normal(0.0, 0.05, (frames, n, 3))
    positions = rng.random((1, n, 3)) + np.cumsum(velocities, axis=0) / fps
    zeros = np.zeros(frames)
    three = np.zeros((frames, 3))
    return kinema.Trajectory(
        t=np.arange(frames) / fps,
        positions=positions,
        velocities=velocities,
        kinetic=zeros,
        potential={},
        momentum=three,
        angular_momentum=three,
        contacts=np.zeros(frames, dtype=int),
        impulse_balance=three,
        collision_energy_lost=zeros,
        radii=np.full(n, 0.004),
    )


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


def test_serve_refuses_a_foreign_host_header(traj):
    # DNS rebinding: a page of evil.example, its name now resolving to 127.0.0.1, asks for the
    # data with "Host: evil.example:PORT"; only 127.0.0.1:PORT and localhost:PORT are served.
    url, server = viewer.serve(traj, open_browser=False)
    port = server.server_address[1]
    try:
        for host in (f"evil.example:{port}", "evil.example", f"127.0.0.1.evil.example:{port}", f"localhost:{port + 1}", "127.0.0.1", ""):
            for path in ("", "data.bin"):
                request = urllib.request.Request(url + path, headers={"Host": host})
                with pytest.raises(urllib.error.HTTPError) as refused:
                    urllib.request.urlopen(request, timeout=10)
                assert refused.value.code == 403, host
                body = refused.value.read().decode()
                assert body.startswith("forbidden: this viewer answers only to") and len(body) < 200, body
        for host in (f"127.0.0.1:{port}", f"localhost:{port}", f"LOCALHOST:{port}"):
            request = urllib.request.Request(url + "data.bin", headers={"Host": host})
            with urllib.request.urlopen(request, timeout=10) as blob:
                assert blob.status == 200 and len(blob.read()) > 0
    finally:
        server.shutdown()
        server.server_close()


def test_large_trajectory_is_downsampled_with_a_warning(traj, tmp_path):
    with pytest.warns(viewer.ViewerWarning, match="showing"):
        path = viewer.write_html(traj, tmp_path / "small.html", max_bytes=40 * 16 * 4)
    data = _page_data(path.read_text(encoding="utf-8"))
    assert data["frames"] * data["n"] * 16 <= 40 * 16 * 4
    assert data["note"].startswith("showing")


def test_missing_bundle_says_to_build(traj, tmp_path, monkeypatch):
    monkeypatch.setattr(viewer_page, "BUNDLE", tmp_path / "absent.js")
    with pytest.raises(viewer.BundleMissingError, match="make viewer"):
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


# --- Playback at 100,000 particles, driven by playwright ------------------------------------


@pytest.fixture(scope="module")
def browser(chromium):
    """Headless Chromium (WebGL by SwiftShader) under playwright, which drives the system's
    Chromium and downloads none of its own."""
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed: pip install -r requirements/viewer-test.txt")
    with sync_api.sync_playwright() as pw:
        launched = pw.chromium.launch(executable_path=chromium, args=CHROMIUM_FLAGS)
        try:
            yield launched
        finally:
            launched.close()


def test_plays_100k_particles_through_every_frame(browser):
    # Frames 0.5 s apart: the page advances playback by at most 0.25 s an animation frame, so
    # however slow the drawing, it shows every frame in turn (0, 1, ..., 5, 0, ...).
    frames = 6
    traj = _random_motion(100_000, frames, fps=2.0)
    url, server = viewer.serve(traj, open_browser=False)
    page = browser.new_page(viewport={"width": 800, "height": 600})
    try:
        page.goto(url)
        page.wait_for_function("() => window.kinemaViewer.ready || window.kinemaViewer.error", timeout=WAIT_MS)
        assert page.evaluate("() => window.kinemaViewer.error") is None
        assert page.evaluate("() => window.kinemaViewer.playing")  # a page without #frame= plays
        assert "100,000 particles" in page.inner_text("#kinema-info")
        # The frame shown at each animation frame, recorded in the page.
        page.evaluate(
            """() => { window.seen = [];
                const note = () => { window.seen.push(window.kinemaViewer.frame); requestAnimationFrame(note); };
                requestAnimationFrame(note); }"""
        )
        # Until the playback has wrapped round from the last frame to the first and gone on.
        wrapped = f"() => window.seen.lastIndexOf({frames - 1}) >= 0 && window.seen.lastIndexOf(1) > window.seen.lastIndexOf({frames - 1})"
        page.wait_for_function(wrapped, timeout=WAIT_MS)
        seen = page.evaluate("() => window.seen")
        shown = [k for i, k in enumerate(seen) if i == 0 or k != seen[i - 1]]
        assert set(shown) == set(range(frames))
        assert all(b == (a + 1) % frames for a, b in zip(shown, shown[1:], strict=False)), f"frames shown out of turn: {shown}"
        stats = page.evaluate("() => window.kinemaViewer.stats.snapshot()")
        assert stats["steps"] >= frames and stats["draws"] >= stats["steps"] and stats["ticks"] >= stats["draws"]
        assert stats["frameMs"] > 0 and stats["fps"] > 0 and stats["drawMs"] >= 0
        # The animation loop keeps running.
        page.wait_for_function(f"() => window.kinemaViewer.stats.ticks >= {stats['ticks'] + 5}", timeout=WAIT_MS)
    finally:
        page.close()
        server.shutdown()
        server.server_close()


def test_page_steps_colours_and_reports_stats(traj, browser, tmp_path):
    # The page's controls on the inline page: scrubbing shows a frame and stops, the colourings
    # switch, and the statistics count what was drawn.
    path = viewer.write_html(traj, tmp_path / "run.html")
    page = browser.new_page(viewport={"width": 800, "height": 600})
    try:
        page.goto(path.resolve().as_uri() + "#frame=3")
        page.wait_for_function("() => window.kinemaViewer.ready", timeout=WAIT_MS)
        assert page.evaluate("() => [window.kinemaViewer.playing, window.kinemaViewer.frame]") == [False, 3]
        assert "frame 4/11" in page.inner_text("#kinema-info")
        page.fill("#kinema-scrub", "7")
        page.dispatch_event("#kinema-scrub", "input")
        assert page.evaluate("() => window.kinemaViewer.frame") == 7 and "t = 0.700 s" in page.inner_text("#kinema-info")
        before = page.evaluate("() => window.kinemaViewer.stats.snapshot().draws")
        for colouring in ("id", "none", "speed"):
            page.select_option("#kinema-colour", colouring)
            page.wait_for_function(f"() => window.kinemaViewer.stats.draws > {before}", timeout=WAIT_MS)
            before = page.evaluate("() => window.kinemaViewer.stats.draws")
        page.click("#kinema-play")
        page.wait_for_function("() => window.kinemaViewer.frame !== 7", timeout=WAIT_MS)
        assert page.evaluate("() => window.kinemaViewer.error") is None
    finally:
        page.close()


# --- `kinema view` as a command --------------------------------------------------------------


class _Command:
    """A command running with its output read on a thread (``lines``); SIGINT as a terminal's
    Ctrl-C gives it (the default action, even where this process was started ignoring it)."""

    def __init__(self, args: list[str], cwd: Path) -> None:
        self.proc = subprocess.Popen(
            args,
            cwd=cwd,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        self.lines: queue.Queue[str] = queue.Queue()
        self.stdout: list[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            self.stdout.append(line)
            self.lines.put(line)

    def wait_for(self, pattern: str, timeout: float = 120.0) -> re.Match:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                found = re.search(pattern, self.lines.get(timeout=0.5))
            except queue.Empty:
                if self.proc.poll() is not None:
                    break
                continue
            if found:
                return found
        self.proc.kill()
        pytest.fail(f"no line matching {pattern!r}; status {self.proc.poll()}; stdout {''.join(self.stdout)!r}; stderr {self.proc.stderr.read()[-2000:]!r}")

    def interrupt(self) -> tuple[int, str]:
        """Ctrl-C, then the exit status and stderr; ``stdout`` holds every line once this
        returns (the reader is joined: it ends when the pipe closes at the command's exit)."""
        self.proc.send_signal(signal.SIGINT)
        try:
            status = self.proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            pytest.fail("the command did not stop on SIGINT")
        self.reader.join(timeout=30)
        return status, self.proc.stderr.read()


def _fetch(url: str) -> tuple[str, bytes]:
    with urllib.request.urlopen(url, timeout=30) as page:
        assert page.status == 200
        html_text = page.read().decode("utf-8")
    with urllib.request.urlopen(url + "data.bin", timeout=30) as blob:
        assert blob.status == 200 and blob.headers["Content-Type"] == "application/octet-stream"
        return html_text, blob.read()


TINY_SCENE = """
[world]
dim = 3
dt = 0.01
duration = 0.2
fps = 10.0

[[particles]]
type = "list"
positions = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
velocity = [0.5, 0, 0]
mass = 1.0
radius = 0.1
"""


@pytest.mark.parametrize("source", ["run.h5", "scene.toml"])
def test_kinema_view_serves_until_ctrl_c(source, tmp_path):
    # `python -m kinema view SOURCE --no-browser`: the URL on stdout, the page and the frames
    # over HTTP, and on Ctrl-C a clean stop (status 0, no traceback).
    if source == "run.h5":
        w = kinema.World(dt=0.01)
        w.add_particles([[0, 0, 0], [1, 0, 0]], velocity=[[0, 1, 0], [0, -1, 0]], radius=0.1)
        w.run(0.2, fps=10).save(tmp_path / source)
        n, frames = 2, 3
    else:
        (tmp_path / source).write_text(textwrap.dedent(TINY_SCENE), encoding="utf-8")
        n, frames = 3, 3
    command = _Command([sys.executable, "-m", "kinema", "view", source, "--no-browser"], cwd=tmp_path)
    try:
        url = command.wait_for(r"serving (http://127\.0\.0\.1:\d+/) — Ctrl-C to stop").group(1)
        page, body = _fetch(url)
    finally:
        status, stderr = command.interrupt()
    assert viewer_page.bundle() in page  # the bundled viewer, inlined
    data = _page_data(page)
    assert (data["n"], data["frames"], data["source"]) == (n, frames, "data.bin")
    assert len(body) == 4 * (frames * n * 3 + frames * n + n)  # positions, speed, radii as float32
    start, count = data["layout"]["radii"]
    np.testing.assert_allclose(np.frombuffer(body, "<f4", count, start), 0.1, rtol=1e-6)
    assert status == 0, stderr
    assert "Traceback" not in stderr and "error" not in stderr.lower(), stderr
    assert sum(url in line for line in command.stdout) == 1, command.stdout  # the URL printed once


def test_kinema_view_rejects_a_bad_port(tmp_path):
    from typer.testing import CliRunner

    from kinema.cli import app

    (tmp_path / "scene.toml").write_text(textwrap.dedent(TINY_SCENE), encoding="utf-8")
    result = CliRunner().invoke(app, ["view", str(tmp_path / "scene.toml"), "--port", "70000", "--no-browser"])
    assert result.exit_code == 2 and "--port 70000" in result.output


def test_serve_opens_the_browser_when_there_is_one(traj, monkeypatch):
    opened: list[str] = []
    monkeypatch.setattr(viewer_server.webbrowser, "open", lambda url, *args, **kwargs: opened.append(url) or True)
    for gui, open_browser, expected in ((True, True, 1), (False, True, 0), (True, False, 0)):
        monkeypatch.setattr(viewer_server, "_gui_available", lambda gui=gui: gui)
        url, server = viewer.serve(traj, open_browser=open_browser)
        server.shutdown()
        server.server_close()
        assert opened[len(opened) - expected :] == [url] * expected, (gui, open_browser, opened)
        opened.clear()

    def no_browser(url, *args, **kwargs):
        raise viewer_server.webbrowser.Error("could not locate runnable browser")

    monkeypatch.setattr(viewer_server, "_gui_available", lambda: True)
    monkeypatch.setattr(viewer_server.webbrowser, "open", no_browser)
    url, server = viewer.serve(traj)  # a browser that cannot start is not an error
    server.shutdown()
    server.server_close()


def test_gui_is_a_display(monkeypatch):
    monkeypatch.setattr(viewer_server.sys, "platform", "linux")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert not viewer_server._gui_available()
    monkeypatch.setenv("DISPLAY", ":0")
    assert viewer_server._gui_available()


# --- Trajectory.show --------------------------------------------------------------------------


def test_show_outside_a_notebook_serves_the_viewer(traj):
    url = traj.show(open_browser=False)
    assert url.startswith("http://127.0.0.1:")
    page, body = _fetch(url)
    frames, n = traj.positions.shape[:2]
    assert _page_data(page)["n"] == n and len(body) == 4 * (frames * n * 4 + n)


def test_show_video_outside_a_notebook_writes_an_mp4(traj):
    path = Path(traj.show(mode="video", width=160, height=120))
    try:
        assert path.suffix == ".mp4" and path.read_bytes()[4:8] == b"ftyp"
    finally:
        path.unlink()


def test_show_rejects_an_unknown_mode(traj):
    with pytest.raises(ValueError, match=r"mode = 'movie' is invalid: use 'viewer' .* or 'video'"):
        traj.show(mode="movie")


def test_show_in_jupyter_inlines_the_viewer_and_a_video(traj, tmp_path, jupyter_kernel):
    # A real kernel runs the cells (nbclient): show() gives the viewer's page in an iframe with
    # the frames inside, without IPython's "Consider using IPython.display.IFrame" warning,
    # show(mode="video") an HTML5 video with the MP4 inside, and a trajectory as a cell's last
    # line a short table (and a one-line text repr), not every frame.
    import nbclient
    import nbformat

    cells = [TRAJECTORY_CODE, "traj.show()", 'traj.show(mode="video", width=320, height=240)', "traj"]
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code) for code in cells])
    client = nbclient.NotebookClient(notebook, timeout=600, kernel_name=jupyter_kernel, resources={"metadata": {"path": str(tmp_path)}})
    client.execute()

    def html_output(cell) -> str:
        found = [o["data"]["text/html"] for o in cell.outputs if o["output_type"] in ("execute_result", "display_data") and "text/html" in o["data"]]
        assert len(found) == 1, cell.outputs
        return found[0]

    frame = re.fullmatch(r'<div><iframe srcdoc="([^"]*)"[^>]*></iframe></div>', html_output(notebook.cells[1]))
    assert frame, "show() gave no iframe"
    streams = [o.get("text", "") for cell in notebook.cells for o in cell.outputs if o["output_type"] == "stream"]
    assert not any("Warning" in text for text in streams), streams
    page = html.unescape(frame.group(1))
    assert viewer_page.bundle() in page  # the bundled viewer, inlined
    data = _page_data(page)
    positions = np.frombuffer(base64.b64decode(data["positions"]), dtype="<f4").reshape(traj.positions.shape)
    np.testing.assert_allclose(positions, traj.positions, rtol=1e-6, atol=1e-6)

    video = re.search(r'<video [^>]*>\s*<source src="data:video/mp4;base64,([A-Za-z0-9+/=]+)" type="video/mp4">', html_output(notebook.cells[2]))
    assert video, "show(mode='video') gave no inline video"
    mp4 = base64.b64decode(video.group(1))
    assert mp4[4:8] == b"ftyp" and len(mp4) > 1000

    summary = html_output(notebook.cells[3])
    assert "kinema.Trajectory" in summary and f"<td style='text-align:left'>{traj.positions.shape[0]}</td>" in summary, summary
    (text,) = [o["data"]["text/plain"] for o in notebook.cells[3].outputs if o["output_type"] == "execute_result"]
    assert text.startswith("Trajectory(frames=") and len(text) < 200, text
