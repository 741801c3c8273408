"""A hard-sphere gas relaxes to the Maxwell–Boltzmann distribution.

examples/scenes/maxwell_gas.toml starts 1,000 spheres at one speed, 1 m/s, in random
directions. Elastic collisions keep the energy and exchange it between particles, and the speeds
spread out to the Maxwell–Boltzmann distribution of the same energy:

    f(v) = √(2/π) v²/a³ exp(−v²/2a²),   a² = kT/m = ⟨v²⟩/3      (equipartition: ½m⟨v²⟩ = 3/2 kT)

The distance to it is measured by the Kolmogorov–Smirnov statistic D = sup |F_n(v) − F(v)| of
the speeds at each frame. Boltzmann's H = ∫ f ln f dv, from the histogram, falls as it goes.

    python examples/maxwell_gas.py [OUTDIR]
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from scipy import stats

import kinema

SCENE = Path(__file__).resolve().parent / "scenes" / "maxwell_gas.toml"


def main(out: Path, duration: float | None = None) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    world = kinema.load_scene(SCENE)
    duration = world.scene.world.duration if duration is None else duration
    traj = world.run(duration, fps=world.scene.world.fps)
    speed = np.linalg.norm(traj.velocities, axis=2)  # (frames, particles), m/s
    a = np.sqrt((speed[-1] ** 2).mean() / 3.0)  # m/s; the energy is conserved, so any frame gives it
    maxwell = stats.maxwell(scale=a)
    ks = np.array([stats.kstest(s, maxwell.cdf).statistic for s in speed])
    print(f"{speed.shape[1]} spheres, a = sqrt(kT/m) = {a:.5f} m/s, {world.collision_stats()['total']['impacts']} impacts")
    for k in np.linspace(0, len(traj.t) - 1, 6).astype(int):
        print(f"t = {traj.t[k]:4.2f} s   KS distance to Maxwell–Boltzmann D = {ks[k]:.4f}")

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [3, 2]})
    bins = np.linspace(0.0, 4.0 * a, 41)
    v = np.linspace(0.0, 4.0 * a, 400)
    for k, colour in zip(np.searchsorted(traj.t, [0.0, 0.2, 0.4]), ["0.6", "C1", "C2"], strict=True):
        left.hist(speed[k], bins=bins, density=True, histtype="step", lw=1.5, color=colour, label=f"t = {traj.t[k]:.1f} s")
    # In equilibrium the frames are draws from the same distribution: pool the last quarter.
    late = traj.t >= 0.75 * traj.t[-1]
    label = f"t = {traj.t[late][0]:.1f}–{traj.t[-1]:.1f} s ({late.sum()} frames)"
    left.hist(speed[late].ravel(), bins=bins, density=True, histtype="step", lw=2.2, color="C0", label=label)
    left.plot(v, maxwell.pdf(v), "k", lw=2, label="Maxwell–Boltzmann")
    left.set_xlabel("speed |v| (m/s)")
    left.set_ylabel("probability density (s/m)")
    left.set_ylim(0, 3.0 * maxwell.pdf(np.sqrt(2.0) * a))
    left.legend(fontsize="small")
    left.set_title("speeds of 1,000 hard spheres, all 1 m/s at t = 0")
    right.semilogy(traj.t, ks, "C0")
    right.axhline(1.63 / np.sqrt(speed.shape[1]), color="k", ls="--", lw=1, label="1 % level of the KS test")
    right.set_xlabel("t (s)")
    right.set_ylabel("KS distance D")
    right.legend(fontsize="small")
    right.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "maxwell_gas.png", dpi=110)
    plt.close(fig)
    return {"t": traj.t, "ks": ks, "a": a, "speed": speed, "trajectory": traj}


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out"))
