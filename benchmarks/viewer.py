"""Frame times of the browser viewer (three.js) in headless Chromium: 10,000 and 100,000 particles.

The scene: particles uniform in the unit cube (seed 0), radius 0.004 m, a random walk of
--frames frames recorded at 60 frames per second, coloured by speed, shown in an 800×600
window served by ``kinema.viewer.serve``. For each particle count, two rows:

  orbit         paused, the camera turning (``#rotate=1``): the scene is drawn every
                animation frame, nothing is uploaded
  play+orbit    playing at real time and turning: a new trajectory frame is uploaded and
                drawn about every animation frame

Each row is measured over --seconds after a second of warm-up, from the page's own
statistics (``window.kinemaViewer.stats``): the median time between animation frames
(``frame ms``; its inverse is ``fps``, at most the display's 60), the median script work in
a frame that drew (``draw ms``: setting the frame and issuing the draw, not the GPU's work),
and the trajectory frames stepped. Headless Chromium here draws WebGL in software
(SwiftShader, on the CPU): a GPU is many times faster, so read the figures as the
page's cost relative to itself, not as what a user's browser reaches.

Needs playwright (requirements/viewer-test.txt; it drives the system's Chromium, it
downloads no browser) and the built viewer (``make build``).

    python benchmarks/viewer.py [--particles 10000 100000] [--seconds 4] [--frames 60] [--bundle JS]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import shutil
import sys
import time
from pathlib import Path

import numpy as np

import kinema
from kinema import viewer
from kinema.viewer import page as viewer_page

CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-background-networking",
]


def random_walk(n: int, frames: int, fps: float = 60.0) -> kinema.Trajectory:
    """``n`` particles in the unit cube stepping at random, ``frames`` frames at ``fps``."""
    rng = np.random.default_rng(0)
    t = np.arange(frames) / fps
    velocities = rng.normal(0.0, 0.05, (frames, n, 3))
    positions = rng.random((1, n, 3)) + np.cumsum(velocities, axis=0) / fps
    zeros = np.zeros(frames)
    return kinema.Trajectory(
        t=t,
        positions=positions,
        velocities=velocities,
        kinetic=zeros,
        potential={},
        momentum=np.zeros((frames, 3)),
        angular_momentum=np.zeros((frames, 3)),
        contacts=zeros.astype(int),
        impulse_balance=np.zeros((frames, 3)),
        collision_energy_lost=zeros,
        radii=np.full(n, 0.004),
    )


def measure(browser, url: str, seconds: float) -> dict:
    """Open ``url`` in a new 800x600 page, let it run a second, then ``seconds`` more; the
    page's frame statistics."""
    page = browser.new_page(viewport={"width": 800, "height": 600})
    page.goto(url)
    page.wait_for_function("() => window.kinemaViewer.ready || window.kinemaViewer.error", timeout=120_000)
    error = page.evaluate("() => window.kinemaViewer.error")
    if error:
        raise RuntimeError(f"the viewer failed: {error}")
    time.sleep(1.0)
    page.evaluate("() => window.kinemaViewer.stats.reset()")
    time.sleep(seconds)
    stats = page.evaluate("() => window.kinemaViewer.stats.snapshot()")
    page.close()
    return stats


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--particles", type=int, nargs="+", default=[10_000, 100_000])
    ap.add_argument("--seconds", type=float, default=4.0)
    ap.add_argument("--frames", type=int, default=60, help="trajectory frames (60 per second of playback)")
    ap.add_argument("--chromium", default=shutil.which("chromium") or "/usr/bin/chromium")
    ap.add_argument("--bundle", type=Path, help="a viewer script to measure instead of the built one (to compare builds)")
    args = ap.parse_args()
    if args.bundle is not None:
        viewer_page.BUNDLE = args.bundle
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        print("playwright is not installed: pip install -r requirements/viewer-test.txt", file=sys.stderr)
        return 2

    print("kinema viewer in headless Chromium, 800x600, WebGL in software (SwiftShader on the CPU, no GPU):")
    print("figures are for comparing the page with itself; a GPU browser is many times faster.")
    print(f"{'particles':>10} {'case':<11} {'frame ms':>9} {'fps':>6} {'draw ms':>8} {'frames':>7} {'drawn':>6} {'stepped':>8}")
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=args.chromium, args=CHROMIUM_ARGS)
        try:
            for n in args.particles:
                with contextlib.redirect_stdout(io.StringIO()):  # serve prints its URL
                    url, server = viewer.serve(random_walk(n, args.frames), open_browser=False)
                try:
                    for case, fragment in (("orbit", "#frame=0&rotate=1"), ("play+orbit", "#play=1&rotate=1")):
                        s = measure(browser, url + fragment, args.seconds)
                        print(
                            f"{n:>10,} {case:<11} {s['frameMs']:>9.1f} {s['fps']:>6.1f} {s['drawMs']:>8.2f} {s['ticks']:>7} {s['draws']:>6} {s['steps']:>8}",
                            flush=True,
                        )
                finally:
                    server.shutdown()
                    server.server_close()
        finally:
            browser.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
