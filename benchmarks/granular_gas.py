"""Particle-steps per second of the granular gas: kinema beside LAMMPS, same scene, same cores.

The scene is `benchmarks/peers/granular_gas.in` (a copy of the project's LAMMPS peer scene; units lj): N = ncell³ spheres of
diameter 1 and mass 1 on a simple cubic lattice of spacing (1/0.3)^(1/3) = 1.4938 (number
density 0.3) in a cubic periodic box of side ncell·a; random velocities (uniform components,
zero total momentum) scaled to temperature 1 (T = 2 KE / (3N − 3)); normal spring–dashpot
contacts only while two spheres overlap, F_n = k_n δ − m_eff γ_n u_n with k_n = 2000 and
γ_n = 50 (restitution e = 0.2588, contact time 0.0541); velocity Verlet, dt = 0.001.

  kinema   World(dt=1e-3, method="verlet"), Box + periodic = (True, True, True),
           set_collisions(model="spring_dashpot", stiffness=2000, damping=50)
           or, with --model impulse, set_collisions(model="impulse", restitution=0.2588)
           (the seed's Newton restitution law at the spring–dashpot's e)
  LAMMPS   lmp -in granular_gas.in -var ncell N -var steps S, under mpirun -np THREADS
           (one MPI rank per kinema thread, OMP_NUM_THREADS=1)

Each engine runs in a fresh process, `--repeat` times, interleaved (kinema, LAMMPS, kinema,
...). Timed: kinema's `World.step(steps)` after the world is built and a first `step(0)`;
LAMMPS's own "Loop time" (after its setup). Throughput = N · steps / time, particle-steps/s;
the table gives medians and kinema / LAMMPS (> 1: kinema is faster).

Same work: both engines print the gas's temperature every 100 steps; with the same e the gas
cools the same way (Haff's law; the two start from different random velocities, so the curves
agree to the noise of N particles). The cooled fraction T(t)/T(0) of the two is compared at
each print, to TOL_COOLING; exit status 1 when they disagree (never on timings).

`--sizes` prints a scaling table instead: N = 10³, 10⁴, 10⁵, 10⁶ (and 10⁷ with `--large`),
300 steps each,
kinema with 1 and 2 threads (and LAMMPS with 1 and 2 ranks when present): particle-steps/s,
ns per particle-step, and peak resident memory per particle (the whole process's peak RSS
over N; at small N the interpreter's ~60 MB dominates), and writes a plot of the cost per
particle-step against N (`--plot`, default out/granular_gas_scaling.png).

    python benchmarks/granular_gas.py [--ncell 47] [--steps 1000] [--threads 2] [--repeat 3]
                                      [--model spring_dashpot|impulse] [--sizes [--large]]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
LAMMPS_SCENE = HERE / "peers" / "granular_gas.in"

DENSITY = 0.3  # spheres per unit volume
SPACING = (1.0 / DENSITY) ** (1.0 / 3.0)
DT = 1e-3
K_N = 2000.0
GAMMA_N = 50.0
# Restitution of that spring–dashpot between two unit masses: m_eff = 1/2, ω₀² = k_n/m_eff,
# damping γ_n/2, e = exp(−(γ_n/2) π / ω_d) with ω_d = √(ω₀² − (γ_n/2)²).
OMEGA_D = math.sqrt(K_N / 0.5 - (GAMMA_N / 2) ** 2)
RESTITUTION = math.exp(-(GAMMA_N / 2) * math.pi / OMEGA_D)  # 0.2588
PRINT_EVERY = 100
TOL_COOLING = 0.03  # |T_k/T_k(0) − T_l/T_l(0)| over T_l/T_l(0) at each print (N ≥ 10⁵)
SIZES = [10, 22, 47, 100]  # ncell: N = 1,000, 10,648, 103,823, 1,000,000
LARGE = 216  # N = 10,077,696
SIZES_STEPS = 300  # steps per run of the scaling table: 100 of free flight, then contacts


# -- kinema ------------------------------------------------------------------------------------
def build_gas(ncell: int, model: str, seed: int = 4928459):
    """The scene as a kinema World."""
    import kinema

    n = ncell**3
    i, j, k = np.meshgrid(np.arange(ncell), np.arange(ncell), np.arange(ncell), indexing="ij")
    x = np.stack([i, j, k], axis=-1).reshape(-1, 3) * SPACING
    v = np.random.default_rng(seed).uniform(-0.5, 0.5, (n, 3))
    v -= v.mean(axis=0)
    v *= math.sqrt(1.0 / temperature(v))
    side = ncell * SPACING
    w = kinema.World(dt=DT, method="verlet")
    w.add_particles(x, velocity=v, mass=1.0, radius=0.5)
    w.add(kinema.Box([0.0, 0.0, 0.0], [side, side, side]))
    w.periodic = (True, True, True)
    if model == "spring_dashpot":
        w.set_collisions(model="spring_dashpot", stiffness=K_N, damping=GAMMA_N)
    else:
        w.set_collisions(model="impulse", restitution=RESTITUTION)
    return w


def temperature(v: np.ndarray) -> float:
    """LAMMPS's temperature of unit masses: 2 KE / (3N − 3), k_B = 1."""
    return float(np.sum(v * v) / (3 * len(v) - 3))


def world_temperature(w) -> float:
    """The world's temperature as `temperature` defines it, from the engine's own kinetic
    energy (`World.diagnostics`): as LAMMPS's thermo, no copy of the velocities (the memory
    row counts the whole process; a copy and its square were 48 B a particle)."""
    return 2.0 * w.diagnostics()["kinetic"] / (3 * len(w) - 3)


def worker(ncell: int, steps: int, model: str) -> dict:
    """One timed run in this process: seconds, the temperatures every PRINT_EVERY steps, peak RSS."""
    w = build_gas(ncell, model)
    w.step(0)  # setup: the stable-step advice
    temps = [world_temperature(w)]
    seconds = 0.0
    done = 0
    while done < steps:
        chunk = min(PRINT_EVERY, steps - done)
        start = time.perf_counter()
        w.step(chunk)
        seconds += time.perf_counter() - start
        done += chunk
        temps.append(world_temperature(w))
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB
    return {"n": ncell**3, "seconds": seconds, "temps": temps, "peak_rss": peak}


def run_kinema(ncell: int, steps: int, threads: int, model: str) -> dict:
    env = {**os.environ, "RAYON_NUM_THREADS": str(threads), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    cmd = [sys.executable, __file__, "--worker", "--ncell", str(ncell), "--steps", str(steps), "--model", model]
    res = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"kinema worker failed (ncell {ncell}, {threads} threads):\n{res.stderr[-3000:]}")
    return json.loads(res.stdout.strip().splitlines()[-1])


# -- LAMMPS ------------------------------------------------------------------------------------
def find_lammps() -> str | None:
    for name in ("lmp", "lmp_mpi", "lmp_serial"):
        if shutil.which(name):
            return shutil.which(name)
    return None


def run_lammps(lmp: str, ncell: int, steps: int, ranks: int) -> dict:
    """One LAMMPS run of the scene: loop seconds, temperatures at each thermo print, peak RSS."""
    cmd = [lmp, "-in", str(LAMMPS_SCENE), "-var", "ncell", str(ncell), "-var", "steps", str(steps), "-log", "none"]
    if ranks > 1:
        cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(ranks), *cmd]
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    wrapped = ["/usr/bin/time", "-f", "MAXRSS_KB %M", *cmd] if os.path.exists("/usr/bin/time") else cmd
    with tempfile.TemporaryDirectory() as d:
        res = subprocess.run(wrapped, cwd=d, env=env, capture_output=True, text=True)
    text = res.stdout + res.stderr
    loop = re.search(r"Loop time of (\S+) on (\d+) procs for (\d+) steps with (\d+) atoms", text)
    if res.returncode != 0 or loop is None:
        raise SystemExit("LAMMPS run failed:\n" + "\n".join(text.splitlines()[-8:]))
    temps = [float(m.group(1)) for m in re.finditer(r"^\s*\d+\s+(\S+)\s+\S+\s+\S+\s+\S+\s+\S+\s*$", text, re.M)]
    rss = re.search(r"MAXRSS_KB (\d+)", text)
    return {
        "n": int(loop.group(4)),
        "seconds": float(loop.group(1)),
        "temps": temps,
        "peak_rss": int(rss.group(1)) * 1024 * ranks if rss else None,  # mpirun reports its largest child
    }


# -- the two modes -----------------------------------------------------------------------------
def compare(args: argparse.Namespace, lmp: str | None) -> int:
    n = args.ncell**3
    runs: dict[str, list[dict]] = {"kinema": [], "LAMMPS": []}
    for _ in range(args.repeat):  # interleaved
        runs["kinema"].append(run_kinema(args.ncell, args.steps, args.threads, args.model))
        if lmp:
            runs["LAMMPS"].append(run_lammps(lmp, args.ncell, args.steps, args.threads))
    print(
        f"granular gas, N = {n:,} (ncell {args.ncell}), {args.steps} steps of dt = {DT:g}, periodic, velocity Verlet; "
        f"{os.cpu_count()} CPUs; median of {args.repeat} interleaved runs"
    )
    print(
        f"kinema: {args.threads} threads, model {args.model}"
        + (f" (e = {RESTITUTION:.4f})" if args.model == "impulse" else f" (k_n = {K_N:g}, gamma_n = {GAMMA_N:g})")
    )
    print(f"LAMMPS: {lmp} gran/hooke, {args.threads} MPI ranks" if lmp else "LAMMPS: not found (apt-get install lammps): kinema alone")
    rate = {name: statistics.median(n * args.steps / r["seconds"] for r in rs) for name, rs in runs.items() if rs}
    print(f"\n{'engine':<8} {'particle-steps/s':>17} {'runs (s)':>30}")
    for name, rs in runs.items():
        if rs:
            secs = " ".join(f"{r['seconds']:.3f}" for r in rs)
            print(f"{name:<8} {rate[name]:>17.3e} {secs:>30}")
    ok = True
    if lmp:
        goal = "goal >= 2.0, issues 10 and 51" if args.model == "spring_dashpot" else "goal >= 2.0 against LAMMPS's spring-dashpot, issue 45"
        print(f"kinema / LAMMPS: {rate['kinema'] / rate['LAMMPS']:.2f}x ({goal})")
        tk, tl = runs["kinema"][0]["temps"], runs["LAMMPS"][0]["temps"]
        print(f"\nsame work: the gas cools (T(t)/T(0), every {PRINT_EVERY} steps; tolerance {TOL_COOLING:g} relative, N >= 1e5)")
        print(f"{'step':>6} {'kinema':>9} {'LAMMPS':>9} {'rel. diff':>10}")
        for k, (a, b) in enumerate(zip(tk, tl, strict=True)):
            ra, rb = a / tk[0], b / tl[0]
            diff = abs(ra - rb) / rb
            print(f"{k * PRINT_EVERY:>6} {ra:>9.4f} {rb:>9.4f} {diff:>10.2e}")
            if n >= 100_000:
                ok &= diff <= TOL_COOLING
        if args.model == "impulse":
            print("(impulse model: instantaneous impacts with the spring-dashpot's e; Haff's law is the same to O(contact time))")
        print("cooling agrees" if ok else "COOLING DISAGREES")
    return 0 if ok else 1


def sizes(args: argparse.Namespace, lmp: str | None) -> int:
    ncells = SIZES + ([LARGE] if args.large else [])
    rows = []
    for ncell in ncells:
        n = ncell**3
        # The same steps at every N (the lattice starts with no contact: the first ~100 steps
        # are free flight, so fewer steps at large N would time a different mix of work).
        steps = min(args.steps, SIZES_STEPS)
        reps = args.repeat if n < 10**7 else 1
        engines = [("kinema", t) for t in (1, 2)] + ([("LAMMPS", t) for t in (1, 2)] if lmp else [])
        got: dict[tuple[str, int], list[dict]] = {e: [] for e in engines}
        for _ in range(reps):
            for name, t in engines:
                r = run_kinema(ncell, steps, t, args.model) if name == "kinema" else run_lammps(lmp, ncell, steps, t)
                got[(name, t)].append(r)
        for (name, t), rs in got.items():
            rate = statistics.median(n * steps / r["seconds"] for r in rs)
            rss = max(r["peak_rss"] or 0 for r in rs)
            rows.append((name, t, n, steps, rate, rss / n if rss else float("nan")))
        print(f"  N = {n:,}: done", file=sys.stderr, flush=True)
    print(f"granular gas scaling, model {args.model}, median of {args.repeat} runs (1 at N = 10^7); {os.cpu_count()} CPUs")
    print(f"{'engine':<8} {'threads':>7} {'N':>11} {'steps':>6} {'particle-steps/s':>17} {'ns/particle-step':>17} {'peak B/particle':>16}")
    for name, t, n, steps, rate, bpp in rows:
        print(f"{name:<8} {t:>7} {n:>11,} {steps:>6} {rate:>17.3e} {1e9 / rate:>17.1f} {bpp:>16.0f}")
    for name, t in sorted({(r[0], r[1]) for r in rows}):
        cost = {r[2]: 1e9 / r[4] for r in rows if r[0] == name and r[1] == t}
        big = [c for nn, c in cost.items() if nn >= 10**4]
        if len(big) > 1:
            print(f"{name} {t} thread(s): cost per particle-step from N = 1e4 up varies {max(big) / min(big):.2f}x (goal <= 1.5 for kinema)")
    plot(rows, Path(args.plot))
    return 0


def plot(rows: list[tuple], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name, t in sorted({(r[0], r[1]) for r in rows}):
        pts = sorted((r[2], 1e9 / r[4]) for r in rows if r[0] == name and r[1] == t)
        ax.plot(
            *zip(*pts, strict=True),
            marker="o",
            ls="-" if name == "kinema" else "--",
            label=f"{name}, {t} {'thread' if name == 'kinema' else 'rank'}{'s' if t > 1 else ''}",
        )
    ax.set_xscale("log")
    ax.set_xlabel("particles N")
    ax.set_ylabel("wall time per particle-step (ns)")
    ax.set_ylim(bottom=0)
    ax.set_title("granular gas (spring-dashpot, periodic, density 0.3): cost per particle-step")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp.png")
    fig.savefig(tmp, dpi=120, bbox_inches="tight")
    os.replace(tmp, path)
    print(f"plot: {path}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ncell", type=int, default=47, help="lattice cells per side: N = ncell^3 (47: 103,823)")
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--threads", type=int, default=2, help="kinema threads = LAMMPS MPI ranks")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--model", choices=("spring_dashpot", "impulse"), default="spring_dashpot")
    ap.add_argument("--sizes", action="store_true", help="the scaling table from N = 1e3 to 1e6")
    ap.add_argument("--large", action="store_true", help="with --sizes: also N = 1e7")
    ap.add_argument("--plot", default="out/granular_gas_scaling.png")
    ap.add_argument("--lmp", default=None, help="the LAMMPS binary (default: lmp on PATH)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.ncell < 2 or args.steps < 1 or args.threads < 1 or args.repeat < 1:
        raise SystemExit("--ncell >= 2, --steps >= 1, --threads >= 1 and --repeat >= 1")
    if args.worker:
        print(json.dumps(worker(args.ncell, args.steps, args.model)))
        return 0
    lmp = args.lmp or find_lammps()
    if lmp and not LAMMPS_SCENE.exists():
        print(f"granular_gas: the LAMMPS scene {LAMMPS_SCENE} is missing: kinema alone")
        lmp = None
    return sizes(args, lmp) if args.sizes else compare(args, lmp)


if __name__ == "__main__":
    raise SystemExit(main())
