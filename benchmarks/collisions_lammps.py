"""Cost per step of a granular settle with spring–dashpot contacts: kinema beside LAMMPS.

The problem: N equal spheres (d = 1 cm, m = 1.309 g: glass, 2500 kg/m³) start at rest on a
lattice of spacing 1.1 d, 20 layers high, 0.1 d above the floor, jittered by up to ±0.04 d
sideways (seed 0), in a box open at the top, and fall under gravity (9.81 m/s²) for `--steps`
steps of dt = 50 µs with velocity Verlet. Contacts, sphere–sphere and sphere–wall, are the
linear spring–dashpot with no tangential force, k_n = 1000 N/m and restitution e = 0.5:

  F_n = k_n δ − m_eff γ_n u_n,   γ_n = 2 ζ √(k_n / m_eff),   ζ = −ln e / √(π² + ln² e)

(m_eff = m/2 between two spheres, m against a wall; contact time 2.6 ms ≈ 52 steps).

  kinema   World(dt, method="verlet"), Gravity(), Box(lo, (Lx, Ly, inf)),
           set_collisions(model="spring_dashpot", stiffness=k_n, restitution=e)
  LAMMPS   pair_style gran/hooke k_n 0 γ_pair 0 0 0 (F = k_n δ n − m_eff γ_n v_n, no tangential
           force since γ_t = 0 and xmu = 0), fix wall/gran hooke k_n 0 γ_wall 0 0 0 on
           xplane, yplane and zplane (a wall's m_eff is the sphere's m), fix gravity,
           fix nve/sphere; neighbor skin 0.1 d, rebuilt when needed (delay 0 every 1 check yes)

gran/hooke takes one γ_n (1/s) for all pairs, so the rate e implies is computed for each kind
of contact: γ_pair = 2ζ√(2 k_n/m) and γ_wall = 2ζ√(k_n/m). This LAMMPS (29 Sep 2021) has no
`damping coeff_restitution` for pair_style granular, which would do that by itself. Neither
engine clips the dashpot's pull at the end of a contact (LAMMPS: no `limit_damping`).

Each engine runs single-threaded (kinema under RAYON_NUM_THREADS=1, LAMMPS one MPI process with
OMP_NUM_THREADS=1, no accelerator suffix); kinema also runs with its default threads. Timed:
kinema's `World.step(steps)` call (after the world is built and the stable-step advice made) and
LAMMPS's own `Loop time` (after its setup). Each runs `--repeat` times, interleaved; the table
gives median seconds per step and LAMMPS time / kinema time (> 1: kinema is faster).

Same work: a 3-sphere run checks that both give the requested e for a sphere pair and for a
wall; the settle's final mean height, kinetic energy and number of contacts are compared
between the two engines, each to a stated tolerance. Single spheres drift apart a little: the
two Verlet variants hand the dashpot different velocities (kinema the predictor v + h a,
LAMMPS the half kick v + h a/2), an O(dt) difference that the pile's contacts amplify.
Exit status 1 when a check disagrees (never on timings); LAMMPS missing: one line, status 0.

    python benchmarks/collisions_lammps.py [--sizes 2000,8000] [--steps 1500] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

D = 0.01  # sphere diameter, m
R = D / 2
RHO = 2500.0  # kg/m³
M = RHO * math.pi / 6 * D**3  # 1.309e-3 kg
K_N = 1000.0  # N/m
E = 0.5
DT = 5e-5  # s
G = 9.81
SPACING = 1.1 * D
LAYERS = 20
LN_E = math.log(E)
ZETA = -LN_E / math.hypot(math.pi, LN_E)
GAMMA_PAIR = 2 * ZETA * math.sqrt(K_N / (M / 2))  # 1/s, m_eff = m/2
GAMMA_WALL = 2 * ZETA * math.sqrt(K_N / M)  # 1/s, m_eff = m

# Cross-check tolerances (kinema vs LAMMPS, final state of the settle).
TOL_HEIGHT = 1e-2  # |Δ<z>| over the drop of <z> during the run
TOL_KE = 2e-2  # relative kinetic energy
TOL_CONTACTS = 5e-2  # relative number of contacts
TOL_E = 0.02  # measured restitution vs requested, at the benchmark's dt


def find_lammps() -> str | None:
    for name in ("lmp", "lmp_serial", "lmp_mpi"):
        path = shutil.which(name)
        if path:
            return path
    return None


def lattice(n: int) -> tuple[np.ndarray, float, float]:
    """The starting positions (n, 3) and the box's Lx, Ly for n = side² · LAYERS spheres."""
    side = math.isqrt(n // LAYERS)
    if side * side * LAYERS != n:
        raise SystemExit(f"N = {n} is invalid: it must be side² · {LAYERS} (2000, 8000, 18000, ...)")
    i, j, k = np.meshgrid(np.arange(side), np.arange(side), np.arange(LAYERS), indexing="ij")
    x = np.stack([(i + 0.5) * SPACING, (j + 0.5) * SPACING, R + 0.1 * D + k * SPACING], axis=-1).reshape(-1, 3)
    x[:, :2] += np.random.default_rng(0).uniform(-0.04 * D, 0.04 * D, (n, 2))
    return x, side * SPACING, side * SPACING


# -- kinema ------------------------------------------------------------------------------------
def kinema_settle(n: int, steps: int) -> tuple[float, np.ndarray, np.ndarray]:
    """Seconds for `steps` steps of the settle, and the final positions and velocities."""
    import kinema

    x, lx, ly = lattice(n)
    w = kinema.World(dt=DT, method="verlet")
    w.add_particles(x, mass=M, radius=R)
    w.add(kinema.Gravity((0.0, 0.0, -G)))
    w.add(kinema.Box([0.0, 0.0, 0.0], [lx, ly, math.inf]))
    w.set_collisions(model="spring_dashpot", stiffness=K_N, restitution=E)
    w.step(0)  # setup: the stable-step advice
    start = time.perf_counter()
    w.step(steps)
    return time.perf_counter() - start, w.positions.copy(), w.velocities.copy()


def run_kinema(n: int, steps: int, threads: str, out: str) -> float:
    """One timed kinema run in a fresh process (so its thread settings hold); state into `out`."""
    env = dict(os.environ)
    env.pop("RAYON_NUM_THREADS", None)
    if threads == "1":
        env.update(RAYON_NUM_THREADS="1", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", out, "--sizes", str(n), "--steps", str(steps)]
    res = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"kinema worker failed:\n{res.stderr}")
    return json.loads(res.stdout.strip().splitlines()[-1])["seconds"]


# -- LAMMPS ------------------------------------------------------------------------------------
def write_data(path: str, x: np.ndarray, v: np.ndarray | None, box: tuple[float, ...], diameters: np.ndarray | None = None) -> None:
    """A LAMMPS data file (atom_style sphere) of spheres of glass (RHO) at `x`, of diameter D
    or each its own (`diameters`), moving at `v` (no spin) or at rest (None)."""
    density = M / (4.0 / 3.0 * math.pi * R**3)  # LAMMPS: rmass = 4π/3 r³ ρ
    d = np.full(len(x), D) if diameters is None else np.asarray(diameters, dtype=float)
    lines = [
        "kinema benchmark",
        "",
        f"{len(x)} atoms",
        "1 atom types",
        "",
        f"{box[0]!r} {box[1]!r} xlo xhi",
        f"{box[2]!r} {box[3]!r} ylo yhi",
        f"{box[4]!r} {box[5]!r} zlo zhi",
        "",
        "Atoms # sphere",
        "",
    ]
    lines += [f"{i + 1} 1 {float(d[i])!r} {density!r} {float(p[0])!r} {float(p[1])!r} {float(p[2])!r}" for i, p in enumerate(x)]
    if v is not None:
        lines += ["", "Velocities", ""]
        lines += [f"{i + 1} {float(q[0])!r} {float(q[1])!r} {float(q[2])!r} 0 0 0" for i, q in enumerate(v)]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def lammps_input(walls: list[str], steps: int, dt: float, gravity: bool) -> str:
    wall = f"wall/gran hooke {K_N!r} 0.0 {GAMMA_WALL!r} 0.0 0.0 0"
    lines = [
        "units si",
        "atom_style sphere",
        "boundary f f f",
        "comm_modify vel yes",
        "read_data data.txt",
        f"pair_style gran/hooke {K_N!r} 0.0 {GAMMA_PAIR!r} 0.0 0.0 0",
        "pair_coeff * *",
        f"neighbor {0.1 * D!r} bin",
        "neigh_modify delay 0 every 1 check yes",
    ]
    if gravity:
        lines.append(f"fix grav all gravity {G!r} vector 0 0 -1")
    lines += [f"fix w{k} all {wall} {spec}" for k, spec in enumerate(walls)]
    lines += [
        "fix int all nve/sphere",
        f"timestep {dt!r}",
        "thermo 0",
        f"run {steps}",
        "write_dump all custom final.dump id x y z vx vy vz modify sort id format float %.17g",
    ]
    return "\n".join(lines) + "\n"


def run_lammps(lmp: str, workdir: str, tag: str) -> tuple[float, dict[str, float]]:
    """One LAMMPS run of in.lammps in `workdir`: its loop time, s, and the % of each part."""
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    log = os.path.join(workdir, f"log.{tag}")
    res = subprocess.run([lmp, "-in", "in.lammps", "-log", log, "-screen", "none"], cwd=workdir, env=env, capture_output=True, text=True)
    text = open(log).read() if os.path.exists(log) else ""
    loop = re.search(r"Loop time of (\S+) on 1 procs for (\d+) steps", text)
    if res.returncode != 0 or loop is None:
        tail = "\n".join((text or res.stdout + res.stderr).splitlines()[-5:])
        raise SystemExit(f"LAMMPS run failed:\n{tail}")
    split = {m.group(1): float(m.group(2)) for m in re.finditer(r"^(Pair|Neigh|Comm|Modify|Output|Other)\s*\|.*\|\s*([\d.]+)\s*$", text, re.M)}
    return float(loop.group(1)), split


def read_dump(path: str) -> tuple[np.ndarray, np.ndarray]:
    d = np.loadtxt(path, skiprows=9, ndmin=2)
    return d[:, 1:4], d[:, 4:7]


# -- checks ------------------------------------------------------------------------------------
def contact_law(lmp: str, dt: float) -> dict[str, tuple[float, float]]:
    """Measured restitution (pair, wall) in both engines: two spheres head-on at ±0.5 m/s and
    one at 0.5 m/s onto the floor, no gravity, until well after the contacts end."""
    import kinema

    u, steps = 0.5, int(round(0.02 / dt))
    x = np.array([[0.05 - R - 5e-4, 0.05, 0.05], [0.05 + R + 5e-4, 0.05, 0.05], [0.02, 0.02, R + 1e-3]])
    v = np.array([[u, 0.0, 0.0], [-u, 0.0, 0.0], [0.0, 0.0, -u]])
    w = kinema.World(dt=dt, method="verlet")
    w.add_particles(x, velocity=v, mass=M, radius=R)
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.set_collisions(model="spring_dashpot", stiffness=K_N, restitution=E)
    w.step(steps)
    vk = w.velocities
    with tempfile.TemporaryDirectory() as d:
        write_data(os.path.join(d, "data.txt"), x, v, (-D, 0.1 + D, -D, 0.1 + D, -D, 0.1 + D))
        with open(os.path.join(d, "in.lammps"), "w") as f:
            f.write(lammps_input(["zplane 0.0 NULL"], steps, dt, gravity=False))
        run_lammps(lmp, d, "law")
        _, vl = read_dump(os.path.join(d, "final.dump"))
    return {name: ((vv[1, 0] - vv[0, 0]) / (2 * u), vv[2, 2] / u) for name, vv in (("kinema", vk), ("LAMMPS", vl))}


def summary(x: np.ndarray, v: np.ndarray, lx: float, ly: float) -> tuple[float, float, int]:
    """Mean height (m), kinetic energy (J), and contacts: overlapping pairs plus wall contacts."""
    from scipy.spatial import cKDTree

    pairs = len(cKDTree(x).query_pairs(D))
    walls = int(np.count_nonzero(x[:, 0] < R) + np.count_nonzero(x[:, 0] > lx - R) + np.count_nonzero(x[:, 1] < R))
    walls += int(np.count_nonzero(x[:, 1] > ly - R) + np.count_nonzero(x[:, 2] < R))
    return float(x[:, 2].mean()), float(0.5 * M * np.sum(v * v)), pairs + walls


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="2000,8000", help="numbers of spheres, comma-separated (side² · 20)")
    ap.add_argument("--steps", type=int, default=1500)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--lmp", default=None, help="the LAMMPS binary (default: lmp or lmp_serial on PATH)")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]

    if args.worker:  # one timed kinema run, in its own process
        seconds, x, v = kinema_settle(sizes[0], args.steps)
        np.savez(args.worker, x=x, v=v)
        print(json.dumps({"seconds": seconds}))
        return 0

    lmp = args.lmp or find_lammps()
    if lmp is None or shutil.which(lmp) is None:
        where = f"{lmp} is not a program" if lmp else "no lmp, lmp_serial or lmp_mpi on PATH"
        print(f"collisions_lammps: LAMMPS not found ({where}; apt-get install lammps), skipped")
        return 0
    about = subprocess.run([lmp, "-h"], capture_output=True, text=True).stdout
    version = re.search(r"Simulator - (.+)", about)
    version = version.group(1).strip() if version else "version unknown"

    print(
        f"granular settle, Hookean spring-dashpot, k_n = {K_N:g} N/m, e = {E}, d = {D * 100:g} cm, m = {M * 1e3:.4g} g, "
        f"dt = {DT * 1e6:g} us, velocity Verlet; {os.cpu_count()} CPUs; median of {args.repeat} runs"
    )
    print(f"LAMMPS: {lmp} ({version}), gran/hooke + wall/gran hooke, gamma_n = {GAMMA_PAIR:.6g} 1/s (pairs), {GAMMA_WALL:.6g} 1/s (walls)")

    # Same contact law: the restitution each engine gives, at the benchmark's dt and finer.
    print(f"\ncontact law (requested e = {E}): restitution measured after one contact")
    print(f"{'dt':>8} {'engine':<8} {'e pair':>9} {'e wall':>9}")
    law_ok = True
    for dt in (DT, DT / 10):
        for name, (ep, ew) in contact_law(lmp, dt).items():
            print(f"{dt:>8.0e} {name:<8} {ep:>9.5f} {ew:>9.5f}")
            if dt == DT:
                law_ok &= abs(ep - E) <= TOL_E and abs(ew - E) <= TOL_E

    rows, checks, splits = [], [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            x0, lx, ly = lattice(n)
            d = os.path.join(tmp, f"n{n}")
            os.makedirs(d)
            top = float(x0[:, 2].max())
            write_data(os.path.join(d, "data.txt"), x0, None, (-D, lx + D, -D, ly + D, -D, 2 * top))
            with open(os.path.join(d, "in.lammps"), "w") as f:
                f.write(lammps_input([f"xplane 0.0 {lx!r}", f"yplane 0.0 {ly!r}", "zplane 0.0 NULL"], args.steps, DT, gravity=True))
            times: dict[str, list[float]] = {"1": [], "default": [], "lammps": []}
            for r in range(args.repeat):  # interleaved
                for threads in ("1", "default"):
                    times[threads].append(run_kinema(n, args.steps, threads, os.path.join(d, f"k{threads}_{r}.npz")))
                loop, splits[n] = run_lammps(lmp, d, str(r))
                times["lammps"].append(loop)
            med = {k: statistics.median(v) / args.steps for k, v in times.items()}
            for threads in ("1", "default"):
                rows.append((n, threads, med[threads], med["lammps"]))
            k1 = np.load(os.path.join(d, "k1_0.npz"))
            kd = np.load(os.path.join(d, "kdefault_0.npz"))
            xl, vl = read_dump(os.path.join(d, "final.dump"))
            checks.append(
                (
                    n,
                    float(x0[:, 2].mean()),
                    summary(k1["x"], k1["v"], lx, ly),
                    summary(xl, vl, lx, ly),
                    float(np.max(np.linalg.norm(k1["x"] - xl, axis=1))),
                    bool(np.array_equal(k1["x"], kd["x"]) and np.array_equal(k1["v"], kd["v"])),
                )
            )

    print(f"\n{'problem':<14} {'N':>6} {'steps':>6} {'kinema threads':>15} {'kinema s/step':>14} {'LAMMPS s/step':>14} {'LAMMPS/kinema':>14}")
    for n, threads, tk, tl in rows:
        print(f"{'hooke settle':<14} {n:>6} {args.steps:>6} {threads:>15} {tk:>14.3e} {tl:>14.3e} {tl / tk:>14.3f}")
    print("(LAMMPS: 1 process, 1 thread, in every row; its time split, last run: ", end="")
    print("; ".join(f"N = {n}: " + ", ".join(f"{k} {v:.0f}%" for k, v in s.items() if v >= 1) for n, s in splits.items()) + ")")

    print(f"\nsame work: the settle's final state (after {args.steps} steps, t = {args.steps * DT:g} s)")
    print(f"{'N':>6} {'engine':<8} {'<z> m':>12} {'KE J':>12} {'contacts':>9}")
    ok = law_ok
    for n, z0, (zk, ek, ck), (zl, el, cl), dx, same in checks:
        print(f"{n:>6} {'kinema':<8} {zk:>12.7f} {ek:>12.6g} {ck:>9d}")
        print(f"{n:>6} {'LAMMPS':<8} {zl:>12.7f} {el:>12.6g} {cl:>9d}")
        dz, de, dc = abs(zk - zl) / abs(z0 - zl), abs(ek - el) / el, abs(ck - cl) / cl
        agree = dz <= TOL_HEIGHT and de <= TOL_KE and dc <= TOL_CONTACTS
        ok &= agree
        print(
            f"{'':>6} |d<z>|/(<z> drop of {z0 - zl:.4f} m) = {dz:.1e} (tol {TOL_HEIGHT:g}), |dKE|/KE = {de:.1e} (tol {TOL_KE:g}), "
            f"|dcontacts|/contacts = {dc:.1e} (tol {TOL_CONTACTS:g}): {'agree' if agree else 'DISAGREE'}"
        )
        print(
            f"{'':>6} largest distance between a sphere's final positions in the two engines: {dx:.1e} m; kinema 1 thread = default threads, bit for bit: {same}"
        )
    print(f"contact law: |e - {E}| <= {TOL_E:g} at dt = {DT:g} s for both engines: {'yes' if law_ok else 'NO'}")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
