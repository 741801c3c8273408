"""Haff's law on Dask: a gas of inelastic hard spheres (the impulse model) cools as
T(t) = T₀ / (1 + t/τ)², and Enskog's kinetic theory gives τ. A sweep over e × seeds measures
τ from each member and compares it with the theory.

The theory (homogeneous cooling state, Haff 1983; Brilliantov & Pöschel, Kinetic Theory of
Granular Gases, ch. 6): with T = m⟨v²⟩/3 and Enskog's collision frequency
ω(T) = 4 √π n σ² χ √(T/m), each collision of two equal spheres loses on average
(m/4)(1 − e²)⟨g_n²⟩ = (1 − e²) T (the flux-weighted ⟨g_n²⟩ = 4T/m of a Maxwellian), and a
particle takes part in ω collisions per unit time, half of them its own to count, so

    d(3T/2)/dt = −(ω/2)(1 − e²) T   ⇒   dT/dt = −(1 − e²) ω(T) T / 3,

whose solution is T₀/(1 + t/τ)² with 1/τ = (1 − e²) ω(T₀) / 6. χ is the pair correlation at
contact, Carnahan–Starling: χ = (1 − φ/2)/(1 − φ)³, φ = π n σ³/6.

τ is measured as the slope of √(T_s/T(t)) = 1 + (t − t_s)/τ_s, a straight line, fitted by
least squares from t_s = SETTLE on: the gas starts on a lattice, whose pair correlation is not
the fluid's χ, and takes a few collisions to forget it. τ_s belongs to the temperature T_s at
t_s; the law's τ ∝ 1/√T gives the τ of T₀ as τ_s √(T_s/T₀). The gas is small and short-lived
enough to stay homogeneous (no clusters).

    python examples/sweeps/haff.py [out_dir]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import kinema

E_VALUES = [0.7, 0.8, 0.9]
SEEDS = 3
NCELL = 10  # 1,000 spheres
DENSITY = 0.05  # n σ³: dilute (φ = 0.026), where molecular chaos holds
SIGMA = 1.0  # diameter
KT0 = 1.0  # initial temperature (m = 1)
SETTLE = 10.0  # time units (about 4 collisions per sphere) before the fit starts


def gas_scene(ncell: int = NCELL, duration: float = 60.0) -> dict:
    """A gas of unit spheres as a scene: a simple cubic lattice at n σ³ = DENSITY in a periodic
    box, Maxwell velocities at T = 1, no net momentum."""
    a = (1.0 / DENSITY) ** (1.0 / 3.0)
    side = ncell * a
    return {
        "world": {"dim": 3, "dt": 0.05, "method": "verlet", "duration": duration, "fps": 2.0},
        "particles": [
            {
                "type": "lattice",
                "origin": [a / 2] * 3,
                "counts": [ncell] * 3,
                "spacing": a,
                "mass": 1.0,
                "radius": SIGMA / 2,
                "velocity": {"kT": KT0, "zero_momentum": True},
                "seed": 1,
            }
        ],
        "colliders": [{"type": "box", "lo": [0.0] * 3, "hi": [side] * 3}],
        "collisions": {"model": "impulse", "restitution": 0.9, "periodic": [True, True, True]},
        "output": {"video": False, "plot": False},
    }


def enskog_tau(e: float, n: float = DENSITY, sigma: float = SIGMA, t0: float = KT0, m: float = 1.0) -> float:
    phi = np.pi * n * sigma**3 / 6
    chi = (1 - phi / 2) / (1 - phi) ** 3
    omega = 4 * np.sqrt(np.pi) * n * sigma**2 * chi * np.sqrt(t0 / m)
    return 6.0 / ((1 - e * e) * omega)


def haff_tau(traj, world) -> dict:
    """τ of T₀ from the slope of √(T_s/T) against t − t_s (module level: the workers import it)."""
    m = traj.masses[None, :, None]
    temperature = np.sum(m * traj.velocities**2, axis=(1, 2)) / (3 * traj.velocities.shape[1])
    late = traj.t >= SETTLE
    t_s, temp_s = traj.t[late][0], temperature[late][0]
    slope = np.polyfit(traj.t[late] - t_s, np.sqrt(temp_s / temperature[late]), 1)[0]
    return {"tau": float(np.sqrt(temp_s / temperature[0]) / slope), "T_final": float(temperature[-1] / temperature[0])}


def main(out: Path, client=None, ncell: int = NCELL, seeds: int = SEEDS, duration: float = 60.0) -> dict:
    result = kinema.sweep(
        gas_scene(ncell, duration), vary={"collisions.restitution": E_VALUES}, seeds=seeds, measure=haff_tau, out=out, client=client, progress=False
    )
    e = np.array([r["collisions.restitution"] for r in result.rows])
    tau = np.array([r["tau"] for r in result.rows])
    theory = np.array([enskog_tau(x) for x in e])
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4))
    grid = np.linspace(min(E_VALUES) - 0.05, max(E_VALUES) + 0.03, 100)
    ax.plot(grid, [enskog_tau(x) for x in grid], "k-", lw=1, label="Enskog theory")
    means = [tau[e == x].mean() for x in E_VALUES]
    spread = [tau[e == x].std() for x in E_VALUES]
    ax.plot(e, tau, ".", color="0.6", label=f"members ({seeds} seeds each)")
    ax.errorbar(E_VALUES, means, yerr=spread, fmt="o", color="C3", capsize=3, label="kinema, mean ± s.d.")
    ax.set_xlabel("coefficient of restitution e")
    ax.set_ylabel("Haff's time τ (σ √(m/T₀))")
    ax.set_yscale("log")
    ax.legend()
    ax.grid(True, alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(Path(out) / "haff_tau.png", dpi=120)
    plt.close(fig)
    rel = (np.array(means) - np.array([enskog_tau(x) for x in E_VALUES])) / np.array([enskog_tau(x) for x in E_VALUES])
    return {"e": e, "tau": tau, "theory": theory, "mean_relative_error": dict(zip(E_VALUES, rel.tolist(), strict=True))}


if __name__ == "__main__":
    r = main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/haff_sweep"))
    for x, err in r["mean_relative_error"].items():
        print(f"e = {x}: tau measured / Enskog - 1 = {err:+.3f} (Enskog tau = {enskog_tau(x):.3f})")
