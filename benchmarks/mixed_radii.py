"""Mixed radii: one boulder among 40,000 grains must not make a step quadratic.

The scene: 40,000 grains of radius 0.01 m (mass 1e-3 kg) on a 100 × 100 × 4 lattice of
spacing 0.025 m (a bed 2.5 m × 2.5 m × 0.1 m), random velocities of up to 0.1 m/s per
component, under gravity, in a box 2.5 m × 2.5 m × 3 m; and one boulder of radius R (0.3 m
and 1 m; mass 1 kg) just above the centre of the bed, falling onto it. Collisions by the
default impulse model (e = 0.5) and, second, by spring–dashpot contacts (k = 1e3 N/m,
damping 0.1 kg/s); dt = 1e-3 s, velocity Verlet.

A uniform grid with cells as wide as the largest particle puts the whole bed into a few
cells, and each grain then tests thousands of others: a step costs 40–130× the grains'
alone. Issue 10's target: with the boulder a step costs less than 2× the grains alone.

Each case runs in a fresh process (`--threads`, default 2), `--repeat` times, interleaved;
timed: `World.step(steps)` after a first `step(0)`. Prints the median seconds per step of
the grains alone and with each boulder, and the ratio; exit status 1 when a ratio is ≥ 2.

    python benchmarks/mixed_radii.py [--steps 50] [--repeat 3] [--threads 2]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

GRAIN_RADIUS = 0.01
SPACING = 0.025
LATTICE = (100, 100, 4)
BOX = (2.5, 2.5, 3.0)
DT = 1e-3
TARGET = 2.0


def build(boulder: float, model: str):
    """The scene as a kinema World; `boulder` = 0 for the grains alone."""
    import kinema

    nx, ny, nz = LATTICE
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    x = (np.stack([i, j, k], axis=-1).reshape(-1, 3) + 0.5) * SPACING
    v = np.random.default_rng(1).uniform(-0.1, 0.1, x.shape)
    w = kinema.World(dt=DT, method="verlet")
    w.add_particles(x, velocity=v, mass=1e-3, radius=GRAIN_RADIUS)
    if boulder > 0:
        top = nz * SPACING
        w.add_particles([[BOX[0] / 2, BOX[1] / 2, top + boulder + 0.005]], mass=1.0, radius=boulder)
    w.add(kinema.Gravity())
    w.add(kinema.Box([0.0, 0.0, 0.0], list(BOX)))
    if model == "impulse":
        w.set_collisions(restitution=0.5)
    else:
        w.set_collisions(model="spring_dashpot", stiffness=1e3, damping=0.1)
    return w


def worker(boulder: float, model: str, steps: int) -> dict:
    w = build(boulder, model)
    w.step(0)
    t0 = time.perf_counter()
    w.step(steps)
    return {"seconds_per_step": (time.perf_counter() - t0) / steps, "n": len(w.positions)}


def run(boulder: float, model: str, steps: int, threads: int) -> dict:
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    out = subprocess.run(
        [sys.executable, __file__, "--worker", str(boulder), model, str(steps)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        print(json.dumps(worker(float(sys.argv[2]), sys.argv[3], int(sys.argv[4]))))
        return 0
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=50)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--boulders", type=float, nargs="+", default=[0.3, 1.0])
    p.add_argument("--models", nargs="+", default=["impulse", "spring_dashpot"])
    args = p.parse_args()

    failed = False
    for model in args.models:
        cases = [0.0, *args.boulders]
        times: dict[float, list[float]] = {b: [] for b in cases}
        for _ in range(args.repeat):
            for b in cases:
                times[b].append(run(b, model, args.steps, args.threads)["seconds_per_step"])
        alone = statistics.median(times[0.0])
        print(f"{model}: 40,000 grains of r = {GRAIN_RADIUS} m, {args.steps} steps, {args.threads} threads, median of {args.repeat}")
        print(f"  {'case':<22}{'s/step':>12}{'× grains alone':>18}")
        print(f"  {'grains alone':<22}{alone:>12.3e}{1.0:>18.2f}")
        for b in args.boulders:
            t = statistics.median(times[b])
            ratio = t / alone
            failed |= ratio >= TARGET
            print(f"  {f'+ boulder R = {b:g} m':<22}{t:>12.3e}{ratio:>18.2f}")
    print(f"target: every ratio < {TARGET:g}: {'missed' if failed else 'met'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
