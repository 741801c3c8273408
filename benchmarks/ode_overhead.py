"""Cost per step of an ODE solve with a Python right-hand side: kinema beside its peers.

The Lorenz system (σ = 10, ρ = 28, β = 8/3) from y0 = (1, 1, 1), 100,000 fixed RK4 steps of
h = 1e-3, three ways in one run, each with the same Python right-hand side:

  kinema       kinema.solve(lorenz, y0, (0, 100), h=1e-3, method="rk4")
  numpy-loop   a hand-written RK4 loop over NumPy arrays (what one writes without a library)
  solve_ivp    scipy.integrate.solve_ivp(method="RK45") over the same interval, per step it takes

Each runs `--repeat` times (interleaved); the table gives the median microseconds per step
and the ratios. A fourth row times the four right-hand-side calls of a step alone, in a bare
Python loop: the floor, so kinema's own cost per step is the difference. Goal: kinema ≤ 0.7× the NumPy loop and ≥ 5× faster per step than solve_ivp.
The kinema and NumPy-loop final states are compared to show it is the same work.

    python benchmarks/ode_overhead.py [--steps 100000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.integrate import solve_ivp

import kinema

SIGMA, RHO, BETA = 10.0, 28.0, 8.0 / 3.0


def lorenz(t, y):
    x, yy, z = y
    return np.array([SIGMA * (yy - x), x * (RHO - z) - yy, x * yy - BETA * z])


def numpy_rk4(f, y0, h, n):
    y = np.array(y0, dtype=float)
    t = 0.0
    ys = np.empty((n + 1, y.size))
    ys[0] = y
    for i in range(n):
        k1 = f(t, y)
        k2 = f(t + 0.5 * h, y + 0.5 * h * k1)
        k3 = f(t + 0.5 * h, y + 0.5 * h * k2)
        k4 = f(t + h, y + h * k3)
        y = y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        t = (i + 1) * h
        ys[i + 1] = y
    return ys


def run_kinema(y0, h, n):
    start = time.perf_counter()
    sol = kinema.solve(lorenz, y0, (0.0, n * h), h=h, method="rk4")
    elapsed = time.perf_counter() - start
    return elapsed / sol.nsteps, sol.y


def run_numpy(y0, h, n):
    start = time.perf_counter()
    ys = numpy_rk4(lorenz, y0, h, n)
    elapsed = time.perf_counter() - start
    return elapsed / n, ys


def run_callback_alone(y0, h, n):
    """The floor: the right-hand side's own cost, 4 calls per RK4 step, from a bare loop."""
    y = np.array(y0, dtype=float)
    start = time.perf_counter()
    for i in range(n):
        t = i * h
        lorenz(t, y)
        lorenz(t, y)
        lorenz(t, y)
        lorenz(t, y)
    return (time.perf_counter() - start) / n


def run_solve_ivp(y0, h, n):
    start = time.perf_counter()
    sol = solve_ivp(lorenz, (0.0, n * h), y0, method="RK45")
    elapsed = time.perf_counter() - start
    return elapsed / (sol.t.size - 1), sol.t.size - 1


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    y0 = np.array([1.0, 1.0, 1.0])
    h = 1e-3
    times = {"kinema": [], "numpy-loop": [], "solve_ivp": [], "4 f calls": []}
    ivp_steps = 0
    for _ in range(args.repeat):
        t_k, y_k = run_kinema(y0, h, args.steps)
        t_n, y_n = run_numpy(y0, h, args.steps)
        t_s, ivp_steps = run_solve_ivp(y0, h, args.steps)
        times["4 f calls"].append(run_callback_alone(y0, h, args.steps))
        times["kinema"].append(t_k)
        times["numpy-loop"].append(t_n)
        times["solve_ivp"].append(t_s)
    med = {k: statistics.median(v) * 1e6 for k, v in times.items()}
    # Same work: the same RK4 steps give the same states up to rounding. Lorenz is chaotic, so
    # rounding differences grow like e^{0.9 t}; compare at t = 1 (step 1000).
    check = min(1000, args.steps)
    same = np.max(np.abs(y_k[check] - y_n[check])) / np.max(np.abs(y_n[check]))
    print(f"Lorenz, RK4, h = {h}, {args.steps} steps, median of {args.repeat} runs (solve_ivp RK45 took {ivp_steps} steps)")
    print(f"{'runner':<12} {'us/step':>10} {'kinema / runner':>16}")
    for k in ("kinema", "numpy-loop", "solve_ivp", "4 f calls"):
        print(f"{k:<12} {med[k]:>10.2f} {med['kinema'] / med[k]:>16.3f}")
    print(f"kinema's own cost per step (kinema - 4 f calls): {med['kinema'] - med['4 f calls']:.2f} us")
    print(f"kinema vs numpy-loop: {med['kinema'] / med['numpy-loop']:.3f}x the time per step (goal <= 0.7)")
    print(f"kinema vs solve_ivp: {med['solve_ivp'] / med['kinema']:.1f}x faster per step (goal >= 5)")
    print(f"same work: max |y_kinema - y_numpy| / max |y| at t = {check * h:g}: {same:.1e}")


if __name__ == "__main__":
    main()
