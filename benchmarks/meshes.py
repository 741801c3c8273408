"""Mesh colliders against a box: what a triangle mesh costs per contact, from 12 triangles to 10^6.

The same particles in the same 1 m cube, held by one of three containers:

  box       kinema.Box([0, 0, 0], [1, 1, 1]): six analytic walls
  mesh12    the cube as a closed kinema.Mesh of 12 triangles, inside=True
  mesh1M    the cube as a closed kinema.Mesh with each face cut into k x k squares of two
            triangles, k = 289: 6 * 2 * 289^2 = 1,002,252 triangles, inside=True

and two scenes, each with N = 10,000 balls of mass 1 kg:

  gas       an elastic gas of balls of radius 0.01 m (e = 1, no gravity) on a lattice
            filling the cube, speeds
            uniform in [-1, 1] m/s per axis (seeded), 300 steps of 1 ms: wall impacts found
            inside the step (continuous detection) at a few per step.
  layer     one layer of 100 x 100 balls of radius 0.004 m (1 cm apart) resting on the
            floor (e = 0.5, mu = 0.3, gravity,
            sleeping off so that every ball keeps its floor contact in every step), 300 steps
            of 1 ms: 10,000 end-of-step contacts with the container in every step.

Each run is a fresh process (`python benchmarks/meshes.py --worker scene container`);
containers run interleaved (box, mesh12, mesh1M, box, ...) `--repeat` times (default 3).
Timed: the steps alone (`World.step(300)` after a first `step(1)` that builds the lists);
the mesh's construction (its hierarchy) is reported apart. The table prints the median
step time, the ratio to the box, and for the mesh the build time.

Run: `make bench` runs every benchmark; this one alone: `.venv/bin/python benchmarks/meshes.py`.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time

import numpy as np

CONTAINERS = ("box", "mesh12", "mesh1M")
SCENES = ("gas", "layer")
N_SIDE = 100
STEPS = 300
RADIUS = {"gas": 0.01, "layer": 0.004}


def cube_mesh(k: int) -> tuple[np.ndarray, np.ndarray]:
    """The unit cube with each face cut into k x k squares of two triangles, counter-clockwise
    from outside, vertices shared along the cube's edges."""
    t = np.linspace(0.0, 1.0, k + 1)
    faces_out = []
    points = []
    # each face: a corner and two edge directions whose cross product points out
    frames = [
        ((0, 0, 0), (0, 1, 0), (1, 0, 0)),
        ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
        ((0, 0, 0), (1, 0, 0), (0, 0, 1)),
        ((0, 1, 0), (0, 0, 1), (1, 0, 0)),
        ((0, 0, 0), (0, 0, 1), (0, 1, 0)),
        ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    ]
    base = 0
    for o, a, b in frames:
        s, u = np.meshgrid(t, t, indexing="xy")
        p = np.asarray(o, float) + s[..., None] * np.asarray(a, float) + u[..., None] * np.asarray(b, float)
        points.append(p.reshape(-1, 3))
        row = k + 1
        j, i = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
        q = base + j * row + i
        faces_out.append(np.stack([q, q + 1, q + row + 1], -1).reshape(-1, 3))
        faces_out.append(np.stack([q, q + row + 1, q + row], -1).reshape(-1, 3))
        base += row * row
    v = np.concatenate(points)
    f = np.concatenate(faces_out)
    # weld the faces' shared border vertices (exact coordinates: multiples of 1/k)
    key = np.round(v * k).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return v[first], inverse.reshape(-1)[f]


def build(scene: str, container: str):
    import kinema

    w = kinema.World(dim=3, dt=1e-3, method="verlet")
    rng = np.random.default_rng(7)
    if scene == "gas":
        side = 22  # 22^3 = 10,648 lattice sites, the first 10,000 used
        g = (np.arange(side) + 0.5) / side
        x = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)[: N_SIDE * N_SIDE]
        v = rng.uniform(-1.0, 1.0, x.shape)
        w.set_collisions(restitution=1.0, friction=0.0)
    else:
        g = (np.arange(N_SIDE) + 0.5) / N_SIDE
        xy = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
        x = np.column_stack([xy, np.full(len(xy), RADIUS[scene])])
        v = np.zeros_like(x)
        w.add(kinema.Gravity((0.0, 0.0, -9.81)))
        w.set_collisions(restitution=0.5, friction=0.3, sleep_time=None)
    w.add_particles(x, v, mass=1.0, radius=RADIUS[scene])
    clock = time.perf_counter()
    if container == "box":
        w.add(kinema.Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]))
        triangles = 0
    else:
        k = 1 if container == "mesh12" else 289
        vertices, faces = cube_mesh(k)
        w.add(kinema.Mesh(vertices=vertices, faces=faces, inside=True))
        triangles = len(faces)
    built = time.perf_counter() - clock
    return w, triangles, built


def worker(scene: str, container: str) -> None:
    w, triangles, built = build(scene, container)
    w.step(1)
    clock = time.perf_counter()
    w.step(STEPS)
    elapsed = time.perf_counter() - clock
    stats = w.collision_stats()["total"]
    x = w.positions
    r = RADIUS[scene]
    inside = bool(np.all((x >= r - 1e-6) & (x <= 1.0 - r + 1e-6)))
    print(
        json.dumps(
            {
                "step_s": elapsed / STEPS,
                "triangles": triangles,
                "build_s": built,
                "impacts": int(stats["impacts"]),
                "contacts": int(w.collision_stats()["last"]["contacts"]),
                "inside": inside,
            }
        )
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--scenes", nargs="*", default=list(SCENES))
    parser.add_argument("--worker", nargs=2, metavar=("SCENE", "CONTAINER"))
    args = parser.parse_args()
    if args.worker:
        worker(*args.worker)
        return
    runs: dict[tuple[str, str], list[dict]] = {}
    for scene in args.scenes:
        for _ in range(args.repeat):
            for container in CONTAINERS:
                out = subprocess.run([sys.executable, __file__, "--worker", scene, container], capture_output=True, text=True, check=True)
                runs.setdefault((scene, container), []).append(json.loads(out.stdout.strip().splitlines()[-1]))
    print(f"N = {N_SIDE * N_SIDE} balls, {STEPS} steps of 1 ms; medians of {args.repeat} runs each, interleaved")
    print(f"{'scene':6} {'container':9} {'triangles':>10} {'ms/step':>9} {'x box':>7} {'build s':>8} {'impacts':>8} {'contacts':>9} {'inside':>7}")
    for scene in args.scenes:
        box = statistics.median(r["step_s"] for r in runs[(scene, "box")])
        for container in CONTAINERS:
            rs = runs[(scene, container)]
            step = statistics.median(r["step_s"] for r in rs)
            build_s = statistics.median(r["build_s"] for r in rs)
            print(
                f"{scene:6} {container:9} {rs[0]['triangles']:>10,} {1e3 * step:>9.2f} {step / box:>7.2f} {build_s:>8.2f} "
                f"{rs[0]['impacts']:>8} {rs[0]['contacts']:>9} {str(all(r['inside'] for r in rs)):>7}"
            )


if __name__ == "__main__":
    main()
