"""A restitution sweep of examples/sweeps/bounce.toml: one ball dropped from h₀ = 1 m, its
first rebound apex h₁ measured for each e and compared with Newton's law at the floor,
u⁺ = −e u⁻, which gives h₁/h₀ = e² exactly.

The apex comes from the first recorded frame after the bounce, by energy in free flight:
h₁ = (z − r) + v_z²/(2g), exact for velocity Verlet under constant gravity (it integrates a
parabola exactly), so the ratio matches e² to rounding.

    python examples/sweeps/bounce.py [out_dir]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import kinema

HERE = Path(__file__).resolve().parent
G = 9.81
E_VALUES = [0.3, 0.5, 0.7, 0.9]


def apex_ratio(traj, world) -> dict:
    """h₁/h₀ of the first rebound (module level: the Dask workers import it)."""
    z, vz = traj.positions[:, 0, 2], traj.velocities[:, 0, 2]
    r = traj.radii[0]
    h0 = z[0] - r + vz[0] ** 2 / (2 * G)
    up = np.flatnonzero(vz > 0)
    if up.size == 0:
        return {"apex_ratio": float("nan")}
    k = up[0]
    h1 = z[k] - r + vz[k] ** 2 / (2 * G)
    return {"apex_ratio": float(h1 / h0)}


def main(out: Path, client=None) -> dict:
    result = kinema.sweep(HERE / "bounce.toml", vary={"collisions.restitution": E_VALUES}, measure=apex_ratio, out=out, client=client, progress=False)
    e = np.array([r["collisions.restitution"] for r in result.rows])
    ratio = np.array([r["apex_ratio"] for r in result.rows])
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 4))
    grid = np.linspace(0, 1, 101)
    ax.plot(grid, grid**2, "k-", lw=1, label="Newton: $h_1/h_0 = e^2$")
    ax.plot(e, ratio, "o", color="C0", label="kinema sweep")
    ax.set_xlabel("coefficient of restitution e")
    ax.set_ylabel("apex ratio $h_1/h_0$")
    ax.legend()
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(Path(out) / "apex_ratio.png", dpi=120)
    plt.close(fig)
    return {"e": e, "ratio": ratio, "max_error": float(np.max(np.abs(ratio - e**2)))}


if __name__ == "__main__":
    r = main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/bounce_sweep"))
    for e, q in zip(r["e"], r["ratio"], strict=True):
        print(f"e = {e:.2f}: h1/h0 = {q:.15f}, e^2 = {e * e:.15f}")
    print(f"largest |h1/h0 - e^2| = {r['max_error']:.2e}")
