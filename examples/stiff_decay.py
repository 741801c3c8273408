"""A stiff problem: explicit methods need a tiny step, implicit Euler does not.

    y' = -1000 (y - cos t) - sin t,   y(0) = 2      exact: y = cos t + e^{-1000 t}

The fast mode e^{-1000t} dies in milliseconds, yet it decides the stable step of an explicit
method: h ≤ max_step(method, λ = -1000). Implicit Euler is stable at any step (A-stable) and
follows the slow solution cos t with h = 0.05, fifty times the explicit limit.

    python examples/stiff_decay.py [OUTDIR]
"""

import sys
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import kinema

LAM = -1000.0


def f(t, y):
    return LAM * (y - np.cos(t)) - np.sin(t)


def jac(t, y):
    return np.array([[LAM]])


def main(out: Path) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    limits = {m: kinema.stability.max_step(m, LAM) for m in ("euler", "rk4", "implicit_euler")}
    for m, h in limits.items():
        print(f"{m:15s} largest stable h for λ = {LAM:g}: {h:.6g}")
    h = 0.05
    implicit = kinema.solve(f, [2.0], (0.0, 2.0), h=h, method="implicit_euler", jac=jac)
    with warnings.catch_warnings(), np.errstate(over="ignore", invalid="ignore"):
        warnings.simplefilter("ignore", kinema.SolverWarning)
        explicit = kinema.solve(f, [2.0], (0.0, 2.0), h=h, method="rk4")
    fine = kinema.solve(f, [2.0], (0.0, 2.0), h=0.9 * limits["rk4"], method="rk4")
    err = np.max(np.abs(implicit.y[2:, 0] - np.cos(implicit.t[2:])))
    print(f"implicit Euler, h = {h}: {implicit.nsteps} steps, max |y - cos t| for t >= 0.1: {err:.2e}")
    print(f"rk4, h = {h}: |y| reaches {np.max(np.abs(explicit.y)):.1e} ({explicit.message})")
    print(f"rk4, h = {0.9 * limits['rk4']:.4g} (90% of its limit): {fine.nsteps} steps, {fine.nfev} evaluations of f")

    fig, ax = plt.subplots(figsize=(7, 4))
    t = np.linspace(0, 2, 400)
    ax.plot(t, np.cos(t) + np.exp(LAM * t), color="0.6", lw=3, label="exact")
    ax.plot(implicit.t, implicit.y[:, 0], "o-", ms=3, label=f"implicit Euler, h = {h}")
    ax.plot(explicit.t, explicit.y[:, 0], "x", label=f"RK4, h = {h} (diverges)")
    ax.set_ylim(-1.5, 2.5)
    ax.set_xlabel("t")
    ax.set_ylabel("y")
    ax.legend()
    fig.savefig(out / "stiff_decay.png", dpi=120, bbox_inches="tight")
    plt.close(fig)
    # Stable is not accurate: at hλ = -2.5 RK4 damps the fast mode by R(-2.5) = 0.65 per step
    # where the exact flow damps it by e^{-2.5} = 0.08, so the transient is wrong but dies out;
    # after t = 0.1 only the slow solution is left and RK4 follows it closely.
    late = fine.t >= 0.1
    fine_err = np.max(np.abs(fine.y[late, 0] - (np.cos(fine.t[late]) + np.exp(LAM * fine.t[late]))))
    print(f"rk4 at 90% of its limit: max error for t >= 0.1: {fine_err:.1e}")
    return {
        "limits": limits,
        "implicit_error": err,
        "explicit_max": float(np.max(np.abs(explicit.y))),
        "fine_max": float(np.max(np.abs(fine.y))),
        "fine_error": fine_err,
    }


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "out"))
