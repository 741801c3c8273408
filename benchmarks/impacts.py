"""Cost per impact of the impulse model's continuous detection, from 10² to 10⁴ m/s.

The scene: 400 discs (2D) of radius 0.01 m and mass 1 kg at random non-overlapping places in
a 1 m × 1 m box (area fraction 0.126), each moving at the same speed v in a random direction,
e = 1 (no energy lost: the speed distribution stays, so the impact rate does), dt = 1 ms,
velocity Verlet, no forces. At 10² m/s a disc crosses 10 diameters per step and meets others
about once a step; at 10⁴ m/s it crosses the box 10 times per step and meets ~80 others.

An event-driven scheme pays per impact: the two particles' next events, O(k log N) for k
candidates. Issue 11's target: the wall-clock time per impact (time per step / impacts per
step) within 3× from 10² to 10⁴ m/s. Before the event queue it was 30 µs at 10² m/s and
340 µs at 10⁴ m/s (a linear scan over all events for the next one).

Each speed runs in a fresh process (`--threads`, default 2), `--repeat` times, interleaved;
timed: `World.step(steps)` after a first `step(0)`. Prints the median time per step, impacts
per step and µs per impact, and the ratio of the fastest to the slowest speed's cost per
impact; exit status 1 when it is ≥ 3.

    python benchmarks/impacts.py [--steps 20] [--repeat 3] [--threads 2]
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

N = 400
RADIUS = 0.01
SIDE = 1.0
DT = 1e-3
SPEEDS = (1e2, 1e3, 1e4)
TARGET = 3.0


def build(speed: float, seed: int = 11):
    import kinema

    rng = np.random.default_rng(seed)
    x: list[np.ndarray] = []
    while len(x) < N:  # random sequential placement, no overlaps
        p = rng.uniform(RADIUS, SIDE - RADIUS, 2)
        if all(np.hypot(*(p - q)) > 2 * RADIUS for q in x):
            x.append(p)
    angle = rng.uniform(0, 2 * np.pi, N)
    pos = np.column_stack([np.array(x), np.zeros(N)])
    vel = np.column_stack([speed * np.cos(angle), speed * np.sin(angle), np.zeros(N)])
    w = kinema.World(dt=DT, method="verlet", dim=2)
    w.add_particles(pos, velocity=vel, mass=1.0, radius=RADIUS)
    w.add(kinema.Box([0.0, 0.0], [SIDE, SIDE]))
    w.set_collisions(restitution=1.0)
    return w


def worker(speed: float, steps: int) -> dict:
    w = build(speed)
    w.step(0)
    start = time.perf_counter()
    w.step(steps)
    seconds = time.perf_counter() - start
    impacts = w.collision_stats()["total"]["impacts"]
    return {"speed": speed, "seconds": seconds, "impacts": impacts, "times": w.stage_times()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--speed", type=float, default=1e2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        print(json.dumps(worker(args.speed, args.steps)))
        return 0

    env = {**os.environ, "RAYON_NUM_THREADS": str(args.threads), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    runs: dict[float, list[dict]] = {v: [] for v in SPEEDS}
    for _ in range(args.repeat):
        for v in SPEEDS:
            cmd = [sys.executable, __file__, "--worker", "--speed", str(v), "--steps", str(args.steps)]
            res = subprocess.run(cmd, env=env, capture_output=True, text=True)
            if res.returncode != 0:
                raise SystemExit(f"worker failed at {v} m/s:\n{res.stderr[-3000:]}")
            runs[v].append(json.loads(res.stdout.strip().splitlines()[-1]))

    print(
        f"impulse model, {N} discs of r = {RADIUS} m in a {SIDE} m box, e = 1, dt = {DT} s, {args.steps} steps, {args.threads} threads, median of {args.repeat}"
    )
    print(f"{'speed (m/s)':>12} {'s/step':>12} {'impacts/step':>14} {'µs/impact':>11}   stages (s: detect, respond, distribute)")
    cost = {}
    for v in SPEEDS:
        per_step = statistics.median(r["seconds"] for r in runs[v]) / args.steps
        impacts = statistics.median(r["impacts"] for r in runs[v]) / args.steps
        cost[v] = per_step / max(impacts, 1e-300) * 1e6
        t = runs[v][0]["times"]
        print(f"{v:>12.0e} {per_step:>12.3e} {impacts:>14.1f} {cost[v]:>11.2f}   {t['detect']:.3f}, {t['respond']:.3f}, {t['distribute']:.3f}")
    ratio = max(cost.values()) / min(cost.values())
    print(f"cost per impact, most / least over the speeds: {ratio:.2f}x (target < {TARGET}x)")
    return 0 if ratio < TARGET else 1


if __name__ == "__main__":
    sys.exit(main())
