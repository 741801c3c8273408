"""Batch mode: the period of a pendulum against its amplitude, one solve for all amplitudes.

    θ'' = -(g/L) sin θ,   θ(0) = θ₀,  θ'(0) = 0

The exact period is T(θ₀) = 4 K(k²) / ω₀ with k = sin(θ₀/2), ω₀ = √(g/L) and K the complete
elliptic integral of the first kind; small swings give the textbook 2π/ω₀. All amplitudes are
integrated together (`vectorized=True`: one call of the acceleration per step for the whole
batch) with velocity Verlet, and each period is read off the zero crossings of θ'.

    python examples/pendulum_periods.py [OUTDIR]
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from scipy.special import ellipk

import kinema

G, L = 9.81, 1.0
OMEGA0 = np.sqrt(G / L)


def accel(t, theta, omega):
    return -(G / L) * np.sin(theta)


def measured_periods(sol) -> np.ndarray:
    """Released from rest at +θ₀, the pendulum first stops again at −θ₀, half a period later:
    θ' crosses zero upwards there. The crossing time is interpolated linearly between steps."""
    v = sol.v[:, :, 0]  # (time, batch)
    periods = []
    for k in range(v.shape[1]):
        s = v[:, k]
        idx = np.nonzero((s[:-1] < 0) & (s[1:] >= 0))[0]
        times = sol.t[idx] - s[idx] * (sol.t[idx + 1] - sol.t[idx]) / (s[idx + 1] - s[idx])
        periods.append(2.0 * times[0])
    return np.array(periods)


def main(out: Path, h: float = 1e-3) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    amplitudes = np.radians(np.linspace(5.0, 170.0, 34))
    theta0 = amplitudes[:, None]
    sol = kinema.solve_second_order(accel, theta0, np.zeros_like(theta0), (0.0, 8.0), h=h, method="verlet", vectorized=True)
    measured = measured_periods(sol)
    exact = 4.0 * ellipk(np.sin(amplitudes / 2.0) ** 2) / OMEGA0
    rel = np.max(np.abs(measured / exact - 1.0))
    print(f"{amplitudes.size} amplitudes in one batch: {sol.nfev} evaluations of the acceleration, {sol.nsteps} steps")
    print(f"max relative error of the period against 4K(k^2)/omega0: {rel:.2e}")

    fig, ax = plt.subplots(figsize=(6.5, 4))
    deg = np.degrees(amplitudes)
    ax.plot(deg, exact * OMEGA0 / (2 * np.pi), color="0.6", lw=3, label="exact: 4K(sin²(θ₀/2)) / ω₀")
    ax.plot(deg, measured * OMEGA0 / (2 * np.pi), "o", ms=4, label=f"verlet, h = {h}, one batch")
    ax.set_xlabel("amplitude θ₀ (degrees)")
    ax.set_ylabel("period / (2π/ω₀)")
    ax.legend()
    fig.savefig(out / "pendulum_periods.png", dpi=120, bbox_inches="tight")
    plt.close(fig)
    return {"max_relative_error": rel, "nfev": sol.nfev, "nsteps": sol.nsteps}


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "out"))
