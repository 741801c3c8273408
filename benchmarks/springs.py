"""Steps per second of a hanging cloth of springs: kinema beside a hand-written NumPy loop.

The cloth: 100 × 100 nodes 1 cm apart in the xz-plane (10 g each), the two top corners pinned,
under gravity, with about 59,000 springs (k_n in N/m, damping c = 0.05 N·s/m along each):

  structural  each node to its right and lower neighbour   19,800 springs, k = 500
  shear       each node to its two lower diagonal ones      19,602 springs, k = 500
  bend        each node to the node two to the right/below  19,600 springs, k = 100

  kinema    World(method=M).add(Gravity()).add(Spring(i, j, k, damping=c)) stepped by
            verlet and rk4 at dt = 1e-4 s, and implicit_euler at dt = 1e-2 s (100× larger;
            the conjugate-gradient iterations per step are printed)
  numpy     velocity Verlet at dt = 1e-4 s written with NumPy: spring forces from the index
            arrays, gathered onto the nodes with np.bincount; the same scheme as kinema's
            (the dashpot sees the Euler predictor v + h a)

Each runs `--repeat` times, interleaved; the table gives the median steps per second and
kinema / NumPy (goal: verlet >= 20x). Same work: after the timed steps, kinema's verlet and
the NumPy loop must agree on the cloth's positions (they are the same scheme in the same
floating-point operations up to the order of the sums).

    python benchmarks/springs.py [--n 100] [--steps 300] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

import kinema

SPACING = 0.01  # m
MASS = 0.01  # kg per node
DAMPING = 0.05  # N·s/m
G = 9.81


def cloth(n: int):
    """Positions (n², 3), masses, pinned flags and the springs (i, j, k, rest length)."""
    r, c = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")  # row (down), column (right)
    x = np.stack([c * SPACING, np.zeros_like(c, dtype=float), -r * SPACING], axis=-1).reshape(-1, 3).astype(float)
    idx = np.arange(n * n).reshape(n, n)
    pairs = [
        (idx[:, :-1], idx[:, 1:], 500.0),  # structural: right
        (idx[:-1, :], idx[1:, :], 500.0),  # structural: down
        (idx[:-1, :-1], idx[1:, 1:], 500.0),  # shear: down-right
        (idx[:-1, 1:], idx[1:, :-1], 500.0),  # shear: down-left
        (idx[:, :-2], idx[:, 2:], 100.0),  # bend: two right
        (idx[:-2, :], idx[2:, :], 100.0),  # bend: two down
    ]
    i = np.concatenate([p[0].ravel() for p in pairs])
    j = np.concatenate([p[1].ravel() for p in pairs])
    k = np.concatenate([np.full(p[0].size, p[2]) for p in pairs])
    rest = np.linalg.norm(x[j] - x[i], axis=1)
    pinned = np.zeros(n * n, dtype=bool)
    pinned[[idx[0, 0], idx[0, -1]]] = True
    return x, pinned, i, j, k, rest


def kinema_run(n: int, method: str, dt: float, steps: int) -> tuple[float, np.ndarray, float | None]:
    x, pinned, i, j, k, rest = cloth(n)
    w = kinema.World(dt=dt, method=method)
    w.add_particles(x, mass=MASS, pinned=pinned)
    w.add(kinema.Gravity((0.0, 0.0, -G)))
    w.add(kinema.Spring(i, j, k, rest_length=rest, damping=DAMPING))
    w.step(1)  # setup: the stable-step advice, the first force evaluation
    start = time.perf_counter()
    w.step(steps)
    seconds = time.perf_counter() - start
    cg = w._core.linear_solve()
    return seconds, w.positions.copy(), (cg[0] if cg else None)


def numpy_verlet(n: int, dt: float, steps: int) -> tuple[float, np.ndarray]:
    """Velocity Verlet with NumPy arrays: what one writes without an engine."""
    x, pinned, i, j, k, rest = cloth(n)
    m = np.full(len(x), MASS)
    inv_m = np.where(pinned, 0.0, 1.0 / m)[:, None]
    v = np.zeros_like(x)
    nn = len(x)

    def accel(x, v):
        d = x[j] - x[i]
        length = np.sqrt(np.einsum("ij,ij->i", d, d))
        u = d / length[:, None]
        fs = k * (length - rest) + DAMPING * np.einsum("ij,ij->i", v[j] - v[i], u)
        f = fs[:, None] * u
        total = np.empty_like(x)
        for c in range(3):
            total[:, c] = np.bincount(i, f[:, c], minlength=nn) - np.bincount(j, f[:, c], minlength=nn)
        total[:, 2] -= m * G
        return total * inv_m

    a = accel(x, v)

    # the same first step as kinema's setup step
    def step(x, v, a):
        x = x + (dt * v + 0.5 * dt * dt * a)
        a1 = accel(x, v + dt * a)
        v = v + 0.5 * dt * (a + a1)
        return x, v, a1

    x, v, a = step(x, v, a)
    start = time.perf_counter()
    for _ in range(steps):
        x, v, a = step(x, v, a)
    return time.perf_counter() - start, x


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100, help="nodes per side")
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    runs: dict[str, list[float]] = {"numpy verlet": [], "kinema verlet": [], "kinema rk4": [], "kinema implicit_euler": []}
    steps = {"numpy verlet": args.steps, "kinema verlet": args.steps, "kinema rk4": max(1, args.steps // 3), "kinema implicit_euler": max(1, args.steps // 10)}
    cg_iterations = None
    x_numpy = x_kinema = None
    for _ in range(args.repeat):  # interleaved
        s, x_numpy = numpy_verlet(args.n, 1e-4, steps["numpy verlet"])
        runs["numpy verlet"].append(s)
        s, x_kinema, _ = kinema_run(args.n, "verlet", 1e-4, steps["kinema verlet"])
        runs["kinema verlet"].append(s)
        s, _, _ = kinema_run(args.n, "rk4", 1e-4, steps["kinema rk4"])
        runs["kinema rk4"].append(s)
        s, _, cg_iterations = kinema_run(args.n, "implicit_euler", 1e-2, steps["kinema implicit_euler"])
        runs["kinema implicit_euler"].append(s)
    x, _, i, *_ = cloth(args.n)
    print(f"hanging cloth, {args.n}x{args.n} nodes, {len(i):,} springs, two corners pinned; {os.cpu_count()} CPUs; median of {args.repeat} interleaved runs")
    rate = {name: statistics.median(steps[name] / t for t in ts) for name, ts in runs.items()}
    print(f"\n{'engine':<24} {'dt (s)':>8} {'steps':>6} {'steps/s':>10} {'vs numpy':>9}")
    for name in runs:
        dt = 1e-2 if "implicit" in name else 1e-4
        print(f"{name:<24} {dt:>8.0e} {steps[name]:>6} {rate[name]:>10.1f} {rate[name] / rate['numpy verlet']:>8.2f}x")
    print(f"kinema verlet / numpy verlet: {rate['kinema verlet'] / rate['numpy verlet']:.1f}x (goal >= 20)")
    if cg_iterations is not None:
        print(f"implicit_euler: {cg_iterations} conjugate-gradient iterations in its last step")
    diff = float(np.max(np.abs(x_kinema - x_numpy)))
    print(f"same work: largest |x_kinema - x_numpy| after {steps['kinema verlet'] + 1} verlet steps = {diff:.1e} m")
    return 0 if diff < 1e-9 else 1


if __name__ == "__main__":
    raise SystemExit(main())
