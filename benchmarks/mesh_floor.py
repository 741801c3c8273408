"""A resting pile on a floor of a million triangles against the same pile on a box's floor
(issue 51): what a sphere against a fine mesh costs beside a sphere against a plane.

The scene: 2,000 balls of radii 2.5–4 cm (seeded, density 2,500 kg/m³) resting in a square
pen 1.131 m wide, e = 0.3, μ = 0.5, gravity, dt = 1 ms, the impulse model. The pen's walls are a
`kinema.Box`; its floor is

  box     the box's own floor (z = 0)
  mesh    an open `kinema.Mesh` at z = 0 of 707 x 707 squares of 1.6 mm, two triangles each:
          999,698 triangles (the box's floor lowered to z = -1, out of reach)

The pile is poured once on the box's floor and let come to rest (1.5 s), and its state is
kept in a cache file; each run starts from it. Timed: `World.step(STEPS)` after one step that
builds the lists, on one thread (RAYON_NUM_THREADS=1), with sleeping as a user gets it (the
default `sleep_time`) and off (`sleep_time=None`: every ball's contacts solved at every step).
Each run is a fresh process; the floors run interleaved `--repeat` times; the table gives
medians of ms per step and mesh / box.

    python benchmarks/mesh_floor.py [--repeat 3] [--steps 100]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

N = 2000
SIDE = 707
CELL = 1.6e-3
WIDTH = SIDE * CELL
CACHE = Path(os.environ.get("KINEMA_BENCH_CACHE", "/tmp/kinema-bench")) / "mesh_floor_pile.npz"


def floor_mesh() -> tuple[np.ndarray, np.ndarray]:
    """The square [0, WIDTH]² at z = 0 as SIDE x SIDE squares of two triangles (normal +z)."""
    t = np.arange(SIDE + 1) * CELL
    x, y = np.meshgrid(t, t, indexing="xy")
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    row = SIDE + 1
    j, i = np.meshgrid(np.arange(SIDE), np.arange(SIDE), indexing="ij")
    q = (j * row + i).ravel()
    faces = np.concatenate([np.stack([q, q + 1, q + row + 1], -1), np.stack([q, q + row + 1, q + row], -1)])
    return vertices, faces


def world(floor: str, sleep: bool, x: np.ndarray, v: np.ndarray, radii: np.ndarray):
    import kinema

    w = kinema.World(dim=3, dt=1e-3, method="verlet")
    w.add(kinema.Gravity((0.0, 0.0, -9.81)))
    w.add_particles(x, v, mass=2500.0 * 4.0 / 3.0 * np.pi * radii**3, radius=radii)
    settings = dict(restitution=0.3, friction=0.5)
    if not sleep:
        settings["sleep_time"] = None
    w.set_collisions(**settings)
    if floor == "box":
        w.add(kinema.Box([0.0, 0.0, 0.0], [WIDTH, WIDTH, 10.0]))
    else:
        w.add(kinema.Box([0.0, 0.0, -1.0], [WIDTH, WIDTH, 10.0]))
        vertices, faces = floor_mesh()
        w.add(kinema.Mesh(vertices=vertices, faces=faces))
    return w


def settled() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pile at rest (positions, velocities, radii), poured once and cached."""
    if CACHE.exists():
        d = np.load(CACHE)
        return d["x"], d["v"], d["r"]
    rng = np.random.default_rng(51)
    radii = rng.uniform(0.025, 0.04, N)
    per_row = int(WIDTH / 0.085)
    k = np.arange(N)
    x = np.column_stack([0.05 + (k % per_row) * 0.085, 0.05 + (k // per_row % per_row) * 0.085, 0.05 + (k // per_row**2) * 0.085])
    x[:, :2] += rng.uniform(-0.003, 0.003, (N, 2))
    w = world("box", True, x, np.zeros_like(x), radii)
    w.step(1500)
    CACHE.parent.mkdir(parents=True, exist_ok=True)
    np.savez(CACHE, x=w.positions, v=w.velocities, r=radii)
    return w.positions, w.velocities, radii


def worker(floor: str, sleep: bool, steps: int) -> None:
    x, v, radii = settled()
    w = world(floor, sleep, x, v, radii)
    w.step(1)
    clock = time.perf_counter()
    w.step(steps)
    elapsed = time.perf_counter() - clock
    last = w.collision_stats()["last"]
    print(
        json.dumps(
            {
                "ms_per_step": 1e3 * elapsed / steps,
                "contacts": int(last["contacts"]),
                "asleep": int(last["asleep"]),
                "lowest": float((w.positions[:, 2] - radii).min()),
            }
        )
    )


def run(floor: str, sleep: bool, steps: int) -> dict:
    env = {**os.environ, "RAYON_NUM_THREADS": "1"}
    cmd = [sys.executable, __file__, "--worker", floor, "--sleep" if sleep else "--no-sleep", "--steps", str(steps)]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if out.returncode != 0:
        raise SystemExit(f"{floor} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(repeat: int, steps: int) -> dict:
    """Median ms per step of each floor, sleeping on and off, with mesh / box."""
    settled()
    table = {}
    for sleep in (True, False):
        times: dict[str, list[float]] = {"box": [], "mesh": []}
        last = {}
        for _ in range(repeat):
            for floor in ("box", "mesh"):
                r = run(floor, sleep, steps)
                times[floor].append(r["ms_per_step"])
                last[floor] = r
        box, mesh = statistics.median(times["box"]), statistics.median(times["mesh"])
        table["sleep" if sleep else "no sleep"] = {"box_ms": box, "mesh_ms": mesh, "ratio": mesh / box, "runs": last}
    return table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--worker", choices=("box", "mesh"))
    parser.add_argument("--sleep", action=argparse.BooleanOptionalAction, default=True)
    args = parser.parse_args()
    if args.worker:
        worker(args.worker, args.sleep, args.steps)
        return
    table = measure(args.repeat, args.steps)
    print(f"{N} balls resting on {2 * SIDE * SIDE:,} triangles of {CELL * 1e3:g} mm vs a box's floor, 1 thread, {args.repeat} runs each")
    print(f"{'sleeping':10} {'box ms':>9} {'mesh ms':>9} {'mesh/box':>9}  contacts (box, mesh)")
    for name, row in table.items():
        runs = row["runs"]
        print(f"{name:10} {row['box_ms']:9.3f} {row['mesh_ms']:9.3f} {row['ratio']:9.2f}  {runs['box']['contacts']}, {runs['mesh']['contacts']}")


if __name__ == "__main__":
    main()
