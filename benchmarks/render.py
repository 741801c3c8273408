"""Frames per second of the off-screen renderer: 10,000 particles at 1280×720.

The scene: 10,000 particles uniform in the unit cube (seed 0), radius 0.005 m (3D: spheres
seen by the camera that frames the box; 2D: discs in the unit square seen from +z), drifting
a little between frames, coloured by speed, time stamp on. For each of 3D spheres and 2D
discs, two rows:

  raster        kinema.render.render_frames alone: median seconds per frame over --frames
  raster+mp4    the same frames piped into write_video(.mp4, H.264, x264 --preset): median
                seconds between consecutive frames, and the whole file's frames / wall time

Goal: ≥ 60 frames per second of output (raster+mp4) on a 2-core machine.

    python benchmarks/render.py [--frames 60] [--preset ultrafast]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time

import numpy as np

from kinema.render import render_frames, write_video

N = 10_000
WIDTH, HEIGHT = 1280, 720
RADIUS = 0.005


def scene(frames: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    x0 = rng.random((N, 3))
    v = rng.normal(scale=0.05, size=(N, 3))
    t = np.arange(frames) / 30.0
    x = x0[None] + t[:, None, None] * v[None]
    return x, np.broadcast_to(v, x.shape), t


def timed(frames):
    """Yield the frames, recording the seconds between consecutive yields."""
    times = []
    last = time.perf_counter()
    for f in frames:
        yield f
        now = time.perf_counter()
        times.append(now - last)
        last = now
    timed.times = times


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--preset", default="ultrafast")
    args = ap.parse_args()
    x, v, t = scene(args.frames)
    print(f"render: {N} particles, {WIDTH}x{HEIGHT}, {args.frames} frames, {os.cpu_count()} CPUs, x264 preset {args.preset}")
    print(f"{'scene':<10} {'stage':<12} {'median ms/frame':>16} {'fps (median)':>13} {'fps (total)':>12}")
    for dim in (3, 2):
        kw = dict(dim=dim, velocities=v[:, :, :dim], width=WIDTH, height=HEIGHT)
        xs = x if dim == 3 else x[:, :, :2]
        # Warm-up: one frame (thread pool start, page faults).
        next(render_frames(xs[:1], RADIUS, t[:1], **{**kw, "velocities": v[:1, :, :dim]}))
        start = time.perf_counter()
        for _ in timed(render_frames(xs, RADIUS, t, **kw)):
            pass
        total = time.perf_counter() - start
        med = statistics.median(timed.times)
        name = "3D sphere" if dim == 3 else "2D disc"
        print(f"{name:<10} {'raster':<12} {1e3 * med:>16.2f} {1 / med:>13.1f} {args.frames / total:>12.1f}")
        with tempfile.TemporaryDirectory() as d:
            start = time.perf_counter()
            write_video(timed(render_frames(xs, RADIUS, t, **kw)), os.path.join(d, "bench.mp4"), fps=30, preset=args.preset)
            total = time.perf_counter() - start
            size = os.path.getsize(os.path.join(d, "bench.mp4"))
        med = statistics.median(timed.times)
        print(f"{name:<10} {'raster+mp4':<12} {1e3 * med:>16.2f} {1 / med:>13.1f} {args.frames / total:>12.1f}   ({size / 1e6:.1f} MB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
