"""The angle of repose of a poured pile, kinema beside LAMMPS GRANULAR: the same discs, the same
contact model, the same pour; the two piles' slopes compared.

The scene (2D, gravity 9.81 m/s² along −y): N discs (radii uniform in [0.9, 1.1] r, r = 5 mm,
the masses of glass spheres of those radii, 2500 kg/m³, spinning with I = 1/2 m r²) start on a
jittered lattice in a column 20 diameters wide above a floor y = 0, at rest, and pour onto it
into a heap. Contacts (between discs, and with the floor) follow LAMMPS's `pair granular`
model, in kinema its force model `spring_dashpot` with the tangential part:

  normal     hooke k_n = 1e4 N/m, damping mass_velocity γ_n (1/s) from e = 0.5 for a pair
             (kinema: stiffness=k_n, damping=γ_n)
  tangential linear_history k_t = 2/7 k_n, x_γt = 0.5, μ = 0.5
             (kinema: friction=μ, tangential_stiffness, tangential_damping)
  rolling    sds k_r = k_t, γ_r = 0.5 m_eff γ_n, μ_r = 0.1    (kinema: rolling_friction,
             rolling_stiffness, rolling_damping)
  twisting   marshall                                       (kinema: with rolling friction)

  kinema   World(dim=2, spin=True, method="verlet"), Plane y = 0, dt = 30 µs
  LAMMPS   dimension 2, atom_style sphere, fix nve/sphere disc, fix enforce2d, pair granular
           as above, fix wall/gran granular (the same) yplane 0, dt = 30 µs

After T seconds each pile's free surface (the highest disc top in bins of 2 d along x) is fitted
by a line on each flank, between 10 % and 90 % of the pile's height; the angle is the mean of
the two flanks' atan |slope|. Printed: each engine's angle per seed and their difference (the
issue's target: within 2°), with the largest speed left (the pile at rest) and the wall time.
LAMMPS missing: kinema alone, status 0.

    python benchmarks/angle_of_repose.py [--n 1200] [--seeds 6] [--settle 1.5]
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

G, R, RHO = 9.81, 0.005, 2500.0
D = 2 * R
K_N, E_REST = 1e4, 0.5
MU, MU_R = 0.5, 0.1
X_GT = 0.5
DT = 3e-5
WIDTH = 20  # diameters


def masses(radii: np.ndarray) -> np.ndarray:
    return RHO * 4 / 3 * math.pi * radii**3


def damping_rate(m_pair: float) -> float:
    """γ_n (1/s) that gives e for a pair of reduced mass m_pair: 2 ζ √(k_n/m*)."""
    zeta = -math.log(E_REST) / math.sqrt(math.pi**2 + math.log(E_REST) ** 2)
    return 2 * zeta * math.sqrt(K_N / m_pair)


M0 = float(masses(np.array([R]))[0])
GAMMA_N = damping_rate(M0 / 2)
K_T = 2 / 7 * K_N
K_R = K_T
GAMMA_R = 0.5 * (M0 / 2) * GAMMA_N


BATCH = 3  # discs per pour, side by side
EVERY = 0.03  # s between pours
SPEED = 0.5  # m/s downwards at a pour
SETTLE = 1.5  # s after the last pour


def pour(n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The pours: (positions (k, 3), radii (k,)) for each, every EVERY seconds. A pour drops
    BATCH discs side by side 1.1 d apart about the axis (each jittered by ±d/20), moving down at
    SPEED, 6 d above where the pile's apex would stand by then at 35° (the discs so far, of
    area π r² at packing 0.82): a small fall onto the heap, the same in both engines whatever
    their piles do. (By the next pour a batch has moved SPEED·EVERY + g EVERY²/2 = 1.9 cm,
    clear of the next.)"""
    rng = np.random.default_rng(seed)
    out, placed = [], 0
    while placed < n:
        k = min(BATCH, n - placed)
        apex = math.sqrt(placed * math.pi * R * R / 0.82 * math.tan(math.radians(35.0)))
        x = (np.arange(k) - (k - 1) / 2) * 1.1 * D + rng.uniform(-0.05, 0.05, k) * D
        y = np.full(k, apex + 6 * D)
        out.append((np.column_stack([x, y, np.zeros(k)]), R * rng.uniform(0.9, 1.1, k)))
        placed += k
    return out


def angle(x: np.ndarray, y: np.ndarray, r: np.ndarray) -> float:
    """The mean of the two flanks' angles, degrees (see the module doc)."""
    top = y + r
    edges = np.arange(x.min() - D, x.max() + 2 * D, 2 * D)
    which = np.digitize(x, edges)
    centres, heights = [], []
    for b in np.unique(which):
        sel = which == b
        centres.append(x[sel].mean())
        heights.append(top[sel].max())
    c, h = np.array(centres), np.array(heights)
    peak = h.max()
    apex = c[np.argmax(h)]
    flank = (h > 0.1 * peak) & (h < 0.9 * peak)
    angles = []
    for side in (c < apex, c > apex):
        sel = flank & side
        if sel.sum() < 3:
            return float("nan")
        slope = np.polyfit(c[sel], h[sel], 1)[0]
        angles.append(math.degrees(math.atan(abs(slope))))
    return float(np.mean(angles))


def run_kinema(n: int, seed: int, settle: float) -> dict:
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "python"))
    import kinema

    w = kinema.World(dt=DT, dim=2, spin=True, method="verlet")
    w.add(kinema.Gravity([0, -G, 0]))
    w.add(kinema.Plane([0, 0, 0], [0, 1, 0]))
    w.set_collisions(
        model="spring_dashpot",
        stiffness=K_N,
        damping=GAMMA_N,
        restitution=E_REST,
        friction=MU,
        rolling_friction=MU_R,
        tangential_stiffness=K_T,
        tangential_damping=X_GT,
        rolling_stiffness=K_R,
        rolling_damping=GAMMA_R,
    )
    steps = int(round(EVERY / DT))
    radii = []
    start = time.perf_counter()
    for x, r in pour(n, seed):
        w.add_particles(x, velocity=[0.0, -SPEED, 0.0], mass=masses(r), radius=r)
        radii.append(r)
        w.step(steps)
    w.step(int(round(settle / DT)))
    wall = time.perf_counter() - start
    p, v = w.positions, w.velocities
    r = np.concatenate(radii)
    return {"angle": angle(p[:, 0], p[:, 1], r), "vmax": float(np.abs(v).max()), "wall": wall, "x": p[:, 0], "y": p[:, 1], "r": r}


LAMMPS_INPUT = """
units si
dimension 2
atom_style sphere
boundary f f p
atom_modify map array
comm_modify vel yes
region box block -{half} {half} -0.01 {top} -0.5 0.5 units box
create_box 1 box
pair_style granular
pair_coeff * * hooke {kn} {gn} tangential linear_history {kt} {xgt} {mu} rolling sds {kr} {gr} {mur} twisting marshall damping mass_velocity
fix grav all gravity {g} vector 0 -1 0
fix wall all wall/gran granular hooke {kn} {gn} tangential linear_history {kt} {xgt} {mu} rolling sds {kr} {gr} {mur} twisting marshall damping mass_velocity yplane 0.0 NULL
fix integrate all nve/sphere disc
fix flat all enforce2d
neighbor {skin} bin
neigh_modify delay 0
timestep {dt}
thermo 100000
{pours}
run {settle} post no
write_dump all custom final.dump id x y radius vx vy modify sort id format float %.10g
"""


def run_lammps(lmp: str, n: int, seed: int, settle: float) -> dict | None:
    pours = []
    count = 0
    for x, r in pour(n, seed):
        for k in range(len(r)):
            count += 1
            pours.append(f"create_atoms 1 single {float(x[k, 0])!r} {float(x[k, 1])!r} 0.0 units box")
            pours.append(f"set atom {count} diameter {float(2 * r[k])!r}")
            pours.append(f"set atom {count} mass {float(masses(r[k : k + 1])[0])!r}")
            pours.append(f"set atom {count} vy {-SPEED!r}")
        pours.append(f"run {int(round(EVERY / DT))} post no")
    top = max(float(x[:, 1].max()) for x, _ in pour(n, seed)) + 1.0
    with tempfile.TemporaryDirectory() as work:
        with open(os.path.join(work, "in.lammps"), "w") as f:
            f.write(
                LAMMPS_INPUT.format(
                    half=3.0,
                    top=top,
                    kn=K_N,
                    gn=GAMMA_N,
                    kt=K_T,
                    xgt=X_GT,
                    mu=MU,
                    kr=K_R,
                    gr=GAMMA_R,
                    mur=MU_R,
                    g=G,
                    dt=DT,
                    skin=0.6 * R,
                    pours="\n".join(pours),
                    settle=int(round(settle / DT)),
                )
            )
        env = dict(os.environ, OMP_NUM_THREADS="1")
        start = time.perf_counter()
        res = subprocess.run(
            ["mpirun", "--allow-run-as-root", "-np", "2", lmp, "-in", "in.lammps", "-log", "log.lammps", "-screen", "none"],
            cwd=work,
            env=env,
            capture_output=True,
            text=True,
        )
        wall = time.perf_counter() - start
        log_path = os.path.join(work, "log.lammps")
        log = open(log_path).read() if os.path.exists(log_path) else ""
        dump = os.path.join(work, "final.dump")
        if res.returncode != 0 or not os.path.exists(dump):
            print(f"LAMMPS failed ({res.returncode}): {(res.stderr + log)[-800:]}")
            return None
        text = open(dump).read()
    body = text.split("ITEM: ATOMS")[1].splitlines()[1:]
    a = np.array([[float(c) for c in line.split()] for line in body if line.strip()])
    return {"angle": angle(a[:, 1], a[:, 2], a[:, 3]), "vmax": float(np.abs(a[:, 4:6]).max()), "wall": wall, "x": a[:, 1], "y": a[:, 2], "r": a[:, 3]}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=1200)
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--settle", type=float, default=SETTLE, help="simulated time after the last pour, s")
    args = ap.parse_args()
    lmp = shutil.which("lmp") or shutil.which("lmp_serial")
    if lmp is None:
        print("LAMMPS (lmp) not installed: apt-get install -y lammps; kinema alone below")
    print(
        f"N = {args.n} discs poured {BATCH} every {EVERY} s, then {args.settle} s; dt = {DT} s; k_n = {K_N} N/m, γ_n = {GAMMA_N:.1f} 1/s, k_t = k_r = {K_T:.1f} N/m, μ = {MU}, μ_r = {MU_R}"
    )
    print(
        f"{'seed':>4s} {'kinema (deg)':>13s} {'LAMMPS (deg)':>13s} {'diff':>7s}   {'kinema max|v|':>13s} {'LAMMPS max|v|':>13s}  {'kinema s':>8s} {'LAMMPS s':>8s}"
    )
    ours, theirs = [], []
    for seed in range(args.seeds):
        k = run_kinema(args.n, seed, args.settle)
        ours.append(k["angle"])
        lam = run_lammps(lmp, args.n, seed, args.settle) if lmp else None
        if lam is None:
            print(f"{seed:4d} {k['angle']:13.2f} {'-':>13s} {'-':>7s}   {k['vmax']:13.2e} {'-':>13s}  {k['wall']:8.1f} {'-':>8s}")
            continue
        theirs.append(lam["angle"])
        print(
            f"{seed:4d} {k['angle']:13.2f} {lam['angle']:13.2f} {k['angle'] - lam['angle']:+7.2f}   {k['vmax']:13.2e} {lam['vmax']:13.2e}  {k['wall']:8.1f} {lam['wall']:8.1f}"
        )
    if theirs:
        a, b = float(np.mean(ours)), float(np.mean(theirs))
        spread = float(np.std(ours + theirs))
        sem = spread * math.sqrt(1 / len(ours) + 1 / len(theirs))
        print(
            f"mean: kinema {a:.2f}°, LAMMPS {b:.2f}°, difference {a - b:+.2f}° ± {sem:.2f}° (its standard error; target: within 2°); "
            f"spread of all piles {spread:.2f}°"
        )
    else:
        print(f"mean: kinema {float(np.mean(ours)):.2f}°")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
