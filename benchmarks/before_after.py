"""Seconds of kinema's benchmark workloads in two builds of kinema, interleaved: a change of
shape (issue 16) must leave every benchmark no slower.

Each workload runs in a fresh process with ``PYTHONPATH=<tree>/python`` (so ``import kinema``
takes that tree's package and its built ``_core``), ``--repeat`` times, alternating the two
trees in pairs whose order alternates too (before, after, after, before, ...), on
``--threads`` rayon threads. The workloads are those of
the benchmarks beside this file, smaller so that both builds fit a few minutes:

  gas        benchmarks/granular_gas.py's worker: the LAMMPS peer scene (spring–dashpot
             contacts, velocity Verlet), N = ncell³
  impulse    the same gas with the seed's impulse model
  cloth      benchmarks/springs.py's cloth (59,000 springs on 10,000 nodes) by verlet
  implicit   the same cloth by implicit_euler (the Force trait's linearisation, the
             conjugate-gradient solve)
  solve      benchmarks/ode_overhead.py's Lorenz system by rk4 and rk45 (kinema.solve)
  render     benchmarks/render.py's frames of a 3D gas (the renderer alone)

The table gives each workload's median seconds in both trees and after / before (< 1: the
second tree is faster), then the spread of that ratio: run k of the after tree over run k of
the before tree (the two ran one after the other, in the same minute of a shared machine),
its median and quartiles over the pairs, and "noise" where the quartiles hold 1 (half the
pairs or more on either side of no change). A machine that changes speed between minutes
moves both runs of a pair alike; one that changes between builds does not, and two builds
of the same code differ by a few % in their code's layout alone: give a tree twice (A/A)
to see the spread of nothing. Timings only: nothing here fails on them.

    python benchmarks/before_after.py BEFORE_TREE [AFTER_TREE (default: this checkout)]
                                      [--repeat 5] [--threads 2] [--only gas,implicit]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

# Each worker prints one JSON line {"seconds": ...}: the timed part only, after set-up.
WORKERS = {
    "gas": f"""
import json, sys
sys.path.insert(0, {str(HERE)!r})
import granular_gas as g
print(json.dumps({{"seconds": g.worker(30, 400, "spring_dashpot")["seconds"]}}))
""",
    "impulse": f"""
import json, sys
sys.path.insert(0, {str(HERE)!r})
import granular_gas as g
print(json.dumps({{"seconds": g.worker(30, 1000, "impulse")["seconds"]}}))
""",
    "cloth": f"""
import json, sys
sys.path.insert(0, {str(HERE)!r})
import springs as s
print(json.dumps({{"seconds": s.kinema_run(100, "verlet", 1e-4, 200)[0]}}))
""",
    "implicit": f"""
import json, sys
sys.path.insert(0, {str(HERE)!r})
import springs as s
print(json.dumps({{"seconds": s.kinema_run(100, "implicit_euler", 1e-2, 20)[0]}}))
""",
    "solve": """
import json, time
import numpy as np
import kinema

def lorenz(t, y):
    return np.array([10.0 * (y[1] - y[0]), y[0] * (28.0 - y[2]) - y[1], y[0] * y[1] - 8.0 / 3.0 * y[2]])

start = time.perf_counter()
kinema.solve(lorenz, [1.0, 1.0, 1.0], (0.0, 50.0), h=1e-3, method="rk4")
kinema.solve(lorenz, [1.0, 1.0, 1.0], (0.0, 50.0), method="rk45", rtol=1e-9, atol=1e-12)
print(json.dumps({"seconds": time.perf_counter() - start}))
""",
    "render": """
import json, time
import numpy as np
import kinema

rng = np.random.default_rng(1)
# 5000 of a lattice 0.11 m apart, jittered by 1 cm (uniform random places overlapped, which
# the placement check now refuses)
g = np.linspace(-0.95, 0.95, 18)
x = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)[:5000] + rng.uniform(-0.01, 0.01, (5000, 3))
w = kinema.World(dt=1e-3)
w.add_particles(x, radius=0.01)
w.add(kinema.Box([-1.2, -1.2, -1.2], [1.2, 1.2, 1.2]))
traj = w.run(0.01, fps=1000)
render_frames = kinema.render_frames  # (imported at first use: not timed)
start = time.perf_counter()
for _ in range(3):
    list(render_frames(traj.positions, np.full(5000, 0.01), traj.t, colliders=traj.colliders, width=640, height=480))
print(json.dumps({"seconds": time.perf_counter() - start}))
""",
}


def pair_ratios(before: list[float], after: list[float]) -> tuple[float, float, float]:
    """The median and quartiles (first, third) of after[k] / before[k] over the pairs k:
    the quartiles by `statistics.quantiles`' inclusive method (linear between the order
    statistics, the ends the smallest and largest: 2 pairs give those two)."""
    ratios = [a / b for b, a in zip(before, after, strict=True)]
    if len(ratios) == 1:
        return ratios[0], ratios[0], ratios[0]
    q1, med, q3 = statistics.quantiles(ratios, n=4, method="inclusive")
    return med, q1, q3


def run(tree: Path, workload: str, threads: int) -> float:
    env = {
        **os.environ,
        "PYTHONPATH": str(tree / "python"),
        "RAYON_NUM_THREADS": str(threads),
        "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
    }
    res = subprocess.run([sys.executable, "-c", WORKERS[workload]], env=env, capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"{workload} in {tree} failed:\n{res.stderr[-2000:]}")
    return float(json.loads(res.stdout.strip().splitlines()[-1])["seconds"])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("before", type=Path, help="a checkout of kinema with its _core built")
    ap.add_argument("after", type=Path, nargs="?", default=HERE.parent)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--only", default=",".join(WORKERS), help="comma-separated workloads")
    args = ap.parse_args()
    names = [n for n in args.only.split(",") if n]
    for n in names:
        if n not in WORKERS:
            raise SystemExit(f"--only: {n!r} is not a workload; choose from {', '.join(WORKERS)}")
    trees = {"before": args.before.resolve(), "after": args.after.resolve()}
    for label, tree in trees.items():
        if not (tree / "python" / "kinema").is_dir():
            raise SystemExit(f"{label} = {tree}: no python/kinema there (a kinema checkout with _core built)")
    print(f"before: {trees['before']}\nafter:  {trees['after']}\n{args.threads} threads, {args.repeat} runs each, interleaved\n")
    print(f"{'workload':10} {'before s':>10} {'after s':>10} {'after/before':>13}   pairs: median [quartiles]")
    for name in names:
        times: dict[str, list[float]] = {"before": [], "after": []}
        for k in range(args.repeat):
            # (ABBA: which tree runs first alternates, so that what the first run of a pair
            # leaves the second (warm files, a clock that ramps) falls on both alike; with
            # the before tree always first, an A/A run of the cloth gave 0.85)
            for label in ("before", "after") if k % 2 == 0 else ("after", "before"):
                times[label].append(run(trees[label], name, args.threads))
        b, a = statistics.median(times["before"]), statistics.median(times["after"])
        med, q1, q3 = pair_ratios(times["before"], times["after"])
        verdict = "noise" if q1 <= 1.0 <= q3 else ("faster" if q3 < 1.0 else "slower")
        print(f"{name:10} {b:10.3f} {a:10.3f} {a / b:13.3f}   {med:.3f} [{q1:.3f}, {q3:.3f}] {verdict}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
