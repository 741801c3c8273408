"""What a granular researcher measures on a poured bed, kinema beside LAMMPS GRANULAR: the
coordination number, the fabric, the pressure on the floor over time and the vertical stress
profile of the same bed, each engine measured by its own tools, and a force-chain picture of
kinema's bed (its VTK frame, opened by OVITO and drawn by VTK).

The scene: N glass spheres (2500 kg/m³, radii uniform in [0.9, 1.1] × 1.5 mm, seed 0) start
on a jittered lattice, 6 × 6 a layer 3.6 mm apart, layers 4 mm apart, with random velocities
(σ = 5 cm/s a component), in a cell periodic along x and y (21.6 mm square) above a floor
z = 0, and rain onto it under gravity (9.81 m/s²) for `--time` seconds: a bed some ten
diameters deep, at rest by the end. The contacts, between spheres and with the floor, are
LAMMPS GRANULAR's

  normal      hertz/material E = 10 MPa, ν = 0.3; damping from e = 0.5
              (kinema: model="hertz", youngs_modulus, poisson_ratio, restitution)
  tangential  mindlin (k_t = 8 G* √(R* δ)), x_γt = 1, μ = 0.5
              (kinema: tangential="mindlin", tangential_damping=1, friction)

  kinema  World(dt, spin=True) (velocity Verlet), Box(0, (L, L, ∞)) with x and y periodic,
          World.run(..., record_contacts=True) at 20 frames a second
  LAMMPS  atom_style sphere, boundary p p f, pair_style granular, fix wall/gran granular ...
          zplane 0 NULL contacts, fix nve/sphere, one `run`, dt the same

kinema's Hertz damping is c_n = √5 |ln e| / √(π² + ln² e) · √(k_n m_eff) (docs/collisions.md);
LAMMPS 29 Sep 2021's `damping tsuji` is c_n = α(e') √(k_n m_eff) with Tsuji's polynomial α,
so LAMMPS is given the e' whose α is kinema's coefficient (e' = 0.3667 for e = 0.5; both give
e = 0.500 for a head-on pair and a floor impact, checked). That LAMMPS's fix wall/gran differs
from its pair style in three ways, each worked around here so that the floor is the same
contact as in kinema (measured with one sphere at rest, pushed, and bouncing):
- hertz/material takes E* = E / (2 (1 − ν)) for the wall (the pair style: E / (2 (1 − ν²))):
  the wall is given E / (1 + ν), which makes it E / (2 (1 − ν²));
- `mindlin NULL` takes the wall's k_t / a = E (2 − ν)(1 + ν) / 4 (the pair style: 8 G*): the
  wall is given 8 G* = 2 E / ((2 − ν)(1 + ν)) explicitly;
- `damping tsuji` turns e' into α(e') in the fix's init(), which runs at every `run` command,
  so a second `run` damps with α(α(e')): the script runs once.

Measured on both at the end (and the floor's pressure over every 0.05 s of the pour):

  Z raw        contacts between spheres per sphere, 2 C / N (LAMMPS: mean of compute
               contact/atom; kinema: World.contacts())
  Z, rattlers  kinema.analysis.coordination(colliders=True, min_contacts=2): the floor
               counted, rattlers taken out iteratively (Thornton's mechanical Z)
  fabric       kinema.analysis.fabric over the sphere pairs: eigenvalues, F_zz, anisotropy
               (LAMMPS's pairs from compute pair/local p10 p11 p12 (the branch x_i − x_j),
               fx fy fz (the normal force), p1 p2 p3 (the tangential) with dump local)
  floor        kinema: the Box's collider_books()["normal"] (N·s) differenced over each
               interval / interval / area; LAMMPS: compute reduce sum of fix wall/gran's
               contacts array (column 4, the z force on each sphere), fix ave/time over
               every step of the interval
  σ_zz(z)      in slabs one mean diameter (3 mm) high: kinema's particle_stress() and
               LAMMPS's compute stress/atom + fix ave/chunk (per-sphere virials, pairs only,
               binned by the sphere's centre; LAMMPS's sign flipped: compression is positive
               here); and kinema.analysis.slab_fields on each engine's contacts (each
               contact's force spread along its branch, the floor's contacts included),
               beside the hydrostatic ρ_b g (H − z), ρ_b the measured bulk density and
               H = M / (ρ_b A), and the closed form at rest: the weight of the spheres whose
               centres lie above z, over A (what the contacts crossing z carry)

Closed forms at rest: the floor's force is the weight M g (to 1e-3 or better), and the
stress through the plane z → 0 is M g / A. Printed: the tables, kinema beside LAMMPS, with
each engine's wall-clock time (kinema on one thread: RAYON_NUM_THREADS=1; LAMMPS one
process). The picture, out/pile_measures/force_chains.png (`--picture` for another path):
kinema's last frame exported as VTK (spheres and one line per contact), opened by OVITO's
Python module (checked against World.contacts()) and drawn off screen by VTK as ParaView
draws it (OVITO 3.17 renders only through Vulkan), tubes whose width and colour follow the
normal force. docs/analysis.md shows and discusses the output. LAMMPS missing: kinema
alone, status 0; OVITO or VTK missing: said, no picture.

    python benchmarks/pile_measures.py [--n 600] [--time 1.0] [--seed 0] [--out out/pile_measures]
                                       [--picture PNG]
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "python"))

from angle_of_repose import masses  # noqa: E402  (glass spheres, the same RHO)
from collisions_lammps import find_lammps, write_data  # noqa: E402

G = 9.81
R0, POLY = 1.5e-3, 0.1  # m; radii uniform in [1 − POLY, 1 + POLY] R0
E, NU, E_REST, MU, X_GT = 1e7, 0.3, 0.5, 0.5, 1.0
SIDE, SPACING, LAYER = 6, 3.6e-3, 4e-3  # spheres a row, m between them, m between layers
L = SIDE * SPACING  # the periodic cell's side, m
AREA = L * L
DT = 1e-5  # s: under kinema's safe step (t_c/20 = 11 µs at the fastest impact here)
EVERY = 0.05  # s between the floor's pressure samples
BIN = 2 * R0  # m, the stress profile's slabs
TOP = 0.1  # m, LAMMPS's box top (nothing gets there)


def scene(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """The starting lattice: positions (n, 3), velocities (n, 3), radii and masses (n,)."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    ix, iy, iz = k % SIDE, (k // SIDE) % SIDE, k // (SIDE * SIDE)
    x = np.column_stack([(ix + 0.5) * SPACING, (iy + 0.5) * SPACING, 1.2 * R0 * (1 + POLY) + iz * LAYER])
    x[:, :2] += rng.uniform(-0.04, 0.04, (n, 2)) * SPACING  # pairs stay apart: 3.6 − 0.29 > 3.3 mm
    r = R0 * rng.uniform(1 - POLY, 1 + POLY, n)
    v = rng.normal(0.0, 0.05, (n, 3))
    return {"x": x, "v": v, "r": r, "m": masses(r)}


def tsuji_cor(e: float) -> float:
    """e' with Tsuji's α(e') (LAMMPS's `damping tsuji` polynomial) equal to kinema's Hertz
    coefficient √5 |ln e| / √(π² + ln² e), by bisection (α falls from 1.27 at 0 to 0 at 1)."""
    ln = math.log(e)
    target = math.sqrt(5) * abs(ln) / math.hypot(math.pi, ln)
    coeffs = (1.2728, -4.2783, 11.087, -22.348, 27.467, -18.022, 4.8218)

    def alpha(c: float) -> float:
        return sum(a * c**p for p, a in enumerate(coeffs))

    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if alpha(mid) > target else (lo, mid)
    return (lo + hi) / 2


# -- kinema ------------------------------------------------------------------------------------
def run_kinema(s: dict, duration: float, out: Path) -> dict:
    import kinema
    import kinema.analysis

    w = kinema.World(dt=DT, spin=True)
    w.add(kinema.Box([0.0, 0.0, 0.0], [L, L, math.inf]))
    w.periodic = (True, True, False)
    w.add(kinema.Gravity([0.0, 0.0, -G]))
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=E_REST, friction=MU, tangential="mindlin", tangential_damping=X_GT)
    w.add_particles(s["x"], velocity=s["v"], mass=s["m"], radius=s["r"])
    books = [(w.time, 0.0)]  # (t, the floor's normal momentum so far, N·s, up), at each frame

    def sample(world: kinema.World) -> None:
        books.append((world.time, -float(world.collider_books()["normal"][0, 2])))

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        start = time.perf_counter()
        traj = w.run(duration, fps=1 / EVERY, callback=sample, record_contacts=True)
        wall = time.perf_counter() - start
    for warning in caught:
        print(f"kinema warned: {warning.category.__name__}: {warning.message}")
    t, p = np.array(books).T
    out.mkdir(parents=True, exist_ok=True)
    last = traj.export(out / "kinema.pvd")
    snap = kinema.analysis.Snapshot.of_world(w)
    x = snap.positions.copy()
    x[:, :2] %= L  # into the cell [0, L) along x and y, as LAMMPS dumps them
    return {
        "wall": wall,
        "t": t[1:],
        "pressure": np.diff(p) / np.diff(t) / AREA,
        "floor_last": -float(w.collider_books(last=True)["normal"][0, 2]) / w.dt,
        "x": x,
        "m": snap.masses,
        "r": snap.radii,
        "contacts": snap.contacts,
        "atom_szz": w.particle_stress(kinetic=False)[:, 2, 2].copy(),
        "vmax": float(np.abs(w.velocities).max()),
        "vtm": sorted(p for p in last if p.suffix == ".vtm")[-1],
    }


# -- LAMMPS ------------------------------------------------------------------------------------
LAMMPS_INPUT = """
units si
atom_style sphere
atom_modify map array
boundary p p f
comm_modify vel yes
read_data data.txt
pair_style granular
pair_coeff * * hertz/material {E!r} {cor!r} {nu!r} tangential mindlin NULL {xgt!r} {mu!r} damping tsuji
fix wall all wall/gran granular hertz/material {E_wall!r} {cor!r} {nu!r} tangential mindlin {kt_wall!r} {xgt!r} {mu!r} damping tsuji zplane 0.0 NULL contacts
fix grav all gravity {g!r} vector 0 0 -1
fix integrate all nve/sphere
neighbor {skin!r} bin
neigh_modify delay 0
timestep {dt!r}
compute ca all contact/atom
compute st all stress/atom NULL virial
compute fz all reduce sum f_wall[4]
compute layers all chunk/atom bin/1d z lower {bin!r} units box
fix base all ave/time 1 {every} {every} c_fz file base.txt format " %.17g"
fix profile all ave/chunk {steps} 1 {steps} layers c_st[3] density/mass file profile.txt format " %.17g"
compute pl all pair/local p10 p11 p12 fx fy fz p1 p2 p3
compute pp all property/local patom1 patom2
dump pairs all local {steps} pairs.dump index c_pp[1] c_pp[2] c_pl[1] c_pl[2] c_pl[3] c_pl[4] c_pl[5] c_pl[6] c_pl[7] c_pl[8] c_pl[9]
dump_modify pairs format float %.17g
dump atoms all custom {steps} atoms.dump id radius mass x y z c_ca c_st[3] f_wall[1] f_wall[2] f_wall[3] f_wall[4] f_wall[5] f_wall[6] f_wall[7] vx vy vz
dump_modify atoms sort id format float %.17g
thermo_style custom step time c_fz ke
thermo {every}
run {steps}
"""


def last_frame(path: Path) -> np.ndarray:
    """The rows of a LAMMPS dump's (custom or local) last frame."""
    text = path.read_text()
    body = text.rsplit("ITEM: TIMESTEP", 1)[1]
    rows = body.split("ITEM: ATOMS" if "ITEM: ATOMS" in body else "ITEM: ENTRIES", 1)[1].splitlines()[1:]
    return np.array([[float(c) for c in line.split()] for line in rows if line.strip()])


def run_lammps(lmp: str, s: dict, duration: float, out: Path) -> dict | None:
    work = out / "lammps"
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)
    write_data(str(work / "data.txt"), s["x"], s["v"], (0.0, L, 0.0, L, 0.0, TOP), diameters=2 * s["r"])
    steps = int(round(duration / DT))
    every = int(round(EVERY / DT))
    (work / "in.lammps").write_text(
        LAMMPS_INPUT.format(
            E=E,
            cor=tsuji_cor(E_REST),
            nu=NU,
            xgt=X_GT,
            mu=MU,
            E_wall=E / (1 + NU),
            kt_wall=2 * E / ((2 - NU) * (1 + NU)),
            g=G,
            skin=0.3 * R0,
            dt=DT,
            bin=BIN,
            every=every,
            steps=steps,
        )
    )
    env = dict(os.environ, OMP_NUM_THREADS="1")
    start = time.perf_counter()
    res = subprocess.run([lmp, "-in", "in.lammps", "-log", "log.lammps", "-screen", "none"], cwd=work, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    log = (work / "log.lammps").read_text() if (work / "log.lammps").exists() else ""
    if res.returncode != 0:
        print(f"LAMMPS failed ({res.returncode}): {(res.stderr + log)[-800:]}")
        return None
    atoms = last_frame(work / "atoms.dump")  # id radius mass x y z ca szz wall[1..7] vx vy vz
    x = atoms[:, 3:6]
    pairs = last_frame(work / "pairs.dump")  # index id1 id2 branch(3) f_n(3) f_t(3)
    pairs = pairs[np.linalg.norm(pairs[:, 3:6], axis=1) > 0]  # neighbours not touching: zeros
    i, j = pairs[:, 1].astype(int) - 1, pairs[:, 2].astype(int) - 1
    branch = pairs[:, 3:6]
    dist = np.linalg.norm(branch, axis=1)
    normal = branch / dist[:, None]
    on = atoms[:, 8] > 0  # touching the floor (fix wall/gran's contacts: 1, force, point, radius)
    f_wall = atoms[on, 9:12]
    table = {
        "i": np.concatenate([i, np.flatnonzero(on)]),
        "j": np.concatenate([j, np.full(on.sum(), -1)]),
        "collider": np.concatenate([np.full(len(i), -1), np.zeros(on.sum(), dtype=int)]),
        "normal": np.concatenate([normal, np.tile([0.0, 0.0, 1.0], (on.sum(), 1))]),
        "point": np.concatenate([x[i] - normal * (atoms[i, 1] - (atoms[i, 1] + atoms[j, 1] - dist) / 2)[:, None], atoms[on, 12:15]]),
        "force_n": np.concatenate([pairs[:, 6:9], f_wall * [0.0, 0.0, 1.0]]),
        "force_t": np.concatenate([pairs[:, 9:12], f_wall * [1.0, 1.0, 0.0]]),
    }
    base = np.loadtxt(work / "base.txt", comments="#", ndmin=2)
    rows = [line.split() for line in (work / "profile.txt").read_text().splitlines() if line.strip() and not line.startswith("#")]
    head = max(k for k, row in enumerate(rows) if len(row) == 3)  # "step chunks count" of the last block
    prof = np.array(rows[head + 1 : head + 1 + int(rows[head][1])], dtype=float)  # chunk z count szz rho
    loop = [float(line.split()[3]) for line in log.splitlines() if line.startswith("Loop time of")]
    return {
        "wall": wall,
        "loop": loop[-1] if loop else float("nan"),
        "t": base[:, 0] * DT,
        "pressure": base[:, 1] / AREA,
        "floor_last": float(f_wall[:, 2].sum()),
        "x": x,
        "m": atoms[:, 2],
        "r": atoms[:, 1],
        "contacts": table,
        "contact_atom": atoms[:, 6],
        "atom_szz": -atoms[:, 7],  # stress/atom is −(virial); compression positive here
        "chunk_szz": -prof[:, 2] * prof[:, 3] / (AREA * BIN),
        "chunk_rho": prof[:, 4],
        "vmax": float(np.abs(atoms[:, 15:18]).max()),
    }


# -- the measures ------------------------------------------------------------------------------
def measures(run: dict) -> dict:
    """The bed's measures from one engine's final state (`run`), by kinema.analysis; ± the
    standard error of a mean over the spheres (Z) or the contacts (F_zz)."""
    from kinema import analysis

    x, m, r, c = run["x"], run["m"], run["r"], run["contacts"]
    n = len(x)
    pair = c["j"] >= 0
    coord = analysis.coordination(c, n, colliders=True, min_contacts=2)
    held = coord.per_particle[~coord.rattler]
    fab = analysis.fabric(c)
    nz2 = c["normal"][pair, 2] ** 2
    f_n = np.linalg.norm(c["force_n"][pair], axis=1)
    top = float((x[:, 2] + r).max())
    edges = np.arange(0.0, top + BIN, BIN)
    period = np.array([L, L, 0.0])
    slabs = analysis.slab_fields(x, m, edges=edges, cross_section=AREA, contacts=c, period=period)
    plane = analysis.slab_fields(x, m, edges=[0.0, 1e-3 * R0], cross_section=AREA, contacts=c, period=period)
    which = np.minimum((x[:, 2] // BIN).astype(int), len(edges) - 2)
    atoms = np.bincount(which, weights=run["atom_szz"], minlength=len(edges) - 1) / (AREA * BIN)
    # At rest the contacts crossing the plane z carry the weight of the spheres whose centres
    # lie above it; a slab's mean of that: g/A Σ m_i clip(z_i − a, 0, Δ)/Δ.
    above = G / AREA * (m[:, None] * np.clip(x[:, 2:3] - edges[None, :-1], 0.0, BIN) / BIN).sum(axis=0)
    inside = (edges[:-1] >= BIN) & (edges[1:] <= top - 2 * BIN)  # the bulk: no floor, no surface
    if not inside.any():  # a bed too shallow for a bulk: its full slabs
        inside = edges[1:] <= top
    rho_b = float(slabs.density[inside].mean())
    bulk = slabs.contact_stress[inside]
    height = float(m.sum()) / (rho_b * AREA)
    mid = (edges[:-1] + edges[1:]) / 2
    return {
        "z_raw": 2 * pair.sum() / n,
        "z_raw_se": float(np.bincount(np.concatenate([c["i"][pair], c["j"][pair]]), minlength=n).std() / math.sqrt(n)),
        "z_mech": coord.mean,
        "z_mech_se": float(held.std() / math.sqrt(len(held))),
        "rattlers": coord.rattler_fraction,
        "floor_contacts": int((~pair).sum()),
        "fabric": fab.eigenvalues,
        "fabric_zz": float(fab.tensor[2, 2]),
        "fabric_zz_se": float(nz2.std() / math.sqrt(len(nz2))),
        "anisotropy": fab.anisotropy,
        "k_ratio": float((bulk[:, 0, 0] + bulk[:, 1, 1]).sum() / (2 * bulk[:, 2, 2].sum())),
        "f_mean": float(f_n.mean()),
        "f_ratio": float(f_n.max() / f_n.mean()),
        "weight": float(m.sum()) * G,
        "top": top,
        "rho_b": rho_b,
        "height": height,
        "mid": mid,
        "density": slabs.density,
        "slab_szz": slabs.contact_stress[:, 2, 2],
        "atom_szz": atoms,
        "above": above,
        "hydro": rho_b * G * np.clip(height - mid, 0.0, None),
        "base_ratio": float(plane.contact_stress[0, 2, 2]) * AREA / (float(m.sum()) * G) - 1,
    }


def table(k: dict, mk: dict, lam: dict | None, ml: dict | None, n: int, duration: float, seed: int) -> None:
    """The side-by-side tables ('-' where LAMMPS did not run)."""

    def row(name: str, a: str, b: str = "-", note: str = "") -> None:
        print(f"{name:<40s} {a:>18s} {b:>18s}  {note}".rstrip())

    def both(name: str, key: str, fmt: str, note: str = "", scale: float | None = None, se: str | None = None) -> None:
        def one(m: dict) -> str:
            text = format(m[key] if scale is None else m[key] * scale, fmt)
            return text + (f" ± {format(m[se] if scale is None else m[se] * scale, fmt)}" if se else "")

        row(name, one(mk), one(ml) if ml else "-", note)

    w = mk["weight"]
    print(
        f"N = {n} spheres (seed {seed}), r = {R0 * 1e3:g} mm ± {POLY:.0%}, cell {L * 1e3:.1f} mm square periodic in x, y; Hertz E = {E:g} Pa, "
        f"ν = {NU}, e = {E_REST} (LAMMPS tsuji e' = {tsuji_cor(E_REST):.6f}), Mindlin, x_γt = {X_GT}, μ = {MU}; dt = {DT:g} s, {duration:g} s"
    )
    row("", "kinema", "LAMMPS")
    row(
        f"wall-clock time (s), kinema threads: {os.environ.get('RAYON_NUM_THREADS', 'all')}",
        f"{k['wall']:.1f}",
        f"{lam['wall']:.1f}" if lam else "-",
        f"(LAMMPS's loop {lam['loop']:.1f} s)" if lam else "",
    )
    row("largest speed at the end (m/s)", f"{k['vmax']:.1e}", f"{lam['vmax']:.1e}" if lam else "-")
    row(
        "floor force / M g − 1, the last step",
        f"{k['floor_last'] / w - 1:+.1e}",
        f"{lam['floor_last'] / w - 1:+.1e}" if lam else "-",
        f"M g = {w:.6f} N",
    )
    row(
        "... mean over the last 0.05 s",
        f"{k['pressure'][-1] * AREA / w - 1:+.1e}",
        f"{lam['pressure'][-1] * AREA / w - 1:+.1e}" if lam else "-",
    )
    both("σ_zz(z → 0) / (M g / A) − 1", "base_ratio", "+.1e", "slab_fields, a slab 1.5 µm thick on the floor")
    row(
        "Z raw, contacts between spheres",
        f"{mk['z_raw']:.3f} ± {mk['z_raw_se']:.3f}",
        f"{lam['contact_atom'].mean():.3f} ± {lam['contact_atom'].std() / math.sqrt(n):.3f}" if lam else "-",
        "kinema: 2 C / N from contacts(); LAMMPS: mean of compute contact/atom",
    )
    row("... 2 C / N from compute pair/local", "", f"{ml['z_raw']:.3f}" if ml else "-")
    both("Z mechanical (floor in, rattlers out)", "z_mech", ".3f", "coordination(colliders=True, min_contacts=2)", se="z_mech_se")
    both("rattler fraction", "rattlers", ".3f")
    both("contacts with the floor", "floor_contacts", "d")
    row("fabric eigenvalues", " ".join(f"{v:.3f}" for v in mk["fabric"]), " ".join(f"{v:.3f}" for v in ml["fabric"]) if ml else "-", "fabric(), pairs")
    both("fabric F_zz", "fabric_zz", ".3f", "isotropic: 1/3", se="fabric_zz_se")
    both("fabric anisotropy a", "anisotropy", ".3f", "√(3/2 a:a), a = 15/2 (F − I/3)")
    both("stress ratio K = σ_xx,yy / σ_zz", "k_ratio", ".3f", "slab_fields over the bulk's slabs (Janssen's K)")
    both("mean normal force, pairs (mN)", "f_mean", ".3f", scale=1e3)
    both("largest / mean normal force", "f_ratio", ".2f")
    both("bed top, max(z + r) (mm)", "top", ".2f", scale=1e3)
    both("bulk density ρ_b (kg/m³)", "rho_b", ".0f", f"solid fraction ρ_b / {2500:g}")
    both("H = M / (ρ_b A) (mm)", "height", ".2f", scale=1e3)

    print(f"\nthe floor's pressure, mean over each {EVERY:g} s up to t (Pa); at rest M g / A = {w / AREA:.3f} Pa")
    print(f"{'t (s)':>6s} {'kinema':>9s} {'LAMMPS':>9s}")
    for q, (t, p) in enumerate(zip(k["t"], k["pressure"], strict=True)):
        other = f"{lam['pressure'][q]:9.3f}" if lam and q < len(lam["pressure"]) else f"{'-':>9s}"
        print(f"{t:6.2f} {p:9.3f} {other}")

    print(f"\nσ_zz (Pa, compression positive) in slabs {BIN * 1e3:g} mm high, z their middle; kinema | LAMMPS in each column")
    print(f"{'z (mm)':>6s}  {'per-sphere virials':>19s}  {'contacts along':>19s}  {'weight above / A':>19s}  {'ρ_b g (H − z)':>19s}  {'density (kg/m³)':>19s}")
    print(f"{'':>6s}  {'by centre (*)':>19s}  {'branches (**)':>19s}  {'':>19s}  {'':>19s}  {'':>19s}")
    pick = {"atom": ("atom_szz", "chunk_szz"), "slab": ("slab_szz", "slab_szz"), "above": ("above", "above"), "hydro": ("hydro", "hydro")}
    for b, z in enumerate(mk["mid"]):
        cells = []
        for ours, theirs in pick.values():
            source = lam if theirs == "chunk_szz" else ml
            other = f"{source[theirs][b]:9.2f}" if source and b < len(source[theirs]) else f"{'-':>9s}"
            cells.append(f"{mk[ours][b]:9.2f} {other}")
        other = f"{lam['chunk_rho'][b]:9.0f}" if lam and b < len(lam["chunk_rho"]) else f"{'-':>9s}"
        cells.append(f"{mk['density'][b]:9.0f} {other}")
        print(f"{z * 1e3:6.1f}  " + "  ".join(cells))
    print("(*) kinema: particle_stress(); LAMMPS: compute stress/atom + fix ave/chunk (its density too); pairs only, the floor's contacts left out")
    print("(**) kinema.analysis.slab_fields on each engine's contacts, the floor's included")
    if lam and ml:
        gap = np.abs(ml["atom_szz"][: len(lam["chunk_szz"])] - lam["chunk_szz"][: len(ml["atom_szz"])]).max()
        print(f"LAMMPS's stress/atom binned here equals its fix ave/chunk to {gap:.1e} Pa")


# -- the picture -------------------------------------------------------------------------------
def open_in_ovito(vtm: Path, contacts: dict) -> str:
    """kinema's last VTK frame opened by OVITO's Python module: its particles and its lines
    (one per contact between spheres, with `force_n_magnitude`), checked against the world's
    contacts. (OVITO 3.17 renders through Vulkan only, Tachyon and OSPRay included, which a
    machine without libvulkan lacks: the picture is VTK's, as ParaView would draw it.)"""
    try:
        import ovito
        from ovito.io import import_file
    except ImportError:
        return "OVITO not installed (pip install ovito): not opened"
    data = import_file(str(vtm)).compute()
    lines = next(o for o in data.objects if type(o).__name__ == "Lines")
    got = np.sort(np.asarray(lines["force_n_magnitude"])[::2])  # (each line's two points)
    pair = contacts["j"] >= 0
    want = np.sort(np.linalg.norm(contacts["force_n"][pair], axis=1))
    same = len(got) == len(want) and np.allclose(got, want, rtol=1e-12, atol=0)
    return (
        f"OVITO {ovito.version_string} opened {vtm.name}: {data.particles.count} particles, {len(got)} contact lines, "
        f"their forces {'equal' if same else 'NOT equal'} to World.contacts()'s"
    )


def render_force_chains(vtm: Path, png: Path) -> None:
    """The force chains of kinema's VTK frame, drawn as ParaView draws them (its VTK readers,
    a Tube filter whose radius and colour follow `force_n_magnitude`), the spheres faint,
    rendered off screen by VTK."""
    import vtk
    from matplotlib import colormaps
    from PIL import Image
    from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy

    reader = vtk.vtkXMLMultiBlockDataReader()
    reader.SetFileName(str(vtm))
    reader.Update()
    blocks = reader.GetOutput()
    named = {blocks.GetMetaData(k).Get(vtk.vtkCompositeDataSet.NAME()): blocks.GetBlock(k) for k in range(blocks.GetNumberOfBlocks())}
    spheres, lines = named["particles"], named["contacts"]
    force = vtk_to_numpy(lines.GetCellData().GetArray("force_n_magnitude")) * 1e3  # mN
    top = float(np.percentile(force, 99))
    per_point = numpy_to_vtk(np.repeat(force, 2), deep=True)  # (each line has its own two points)
    per_point.SetName("force (mN)")
    lines.GetPointData().SetScalars(per_point)
    tubes = vtk.vtkTubeFilter()
    tubes.SetInputData(lines)
    tubes.SetVaryRadiusToVaryRadiusByScalar()
    tubes.SetRadius(0.04 * R0)
    tubes.SetRadiusFactor(12.0)
    tubes.SetNumberOfSides(12)
    lut = vtk.vtkLookupTable()
    lut.SetNumberOfTableValues(256)
    for q, rgba in enumerate(colormaps["inferno_r"](np.linspace(0.1, 1.0, 256))):
        lut.SetTableValue(q, *rgba)
    lut.SetRange(0.0, top)
    lut.Build()
    chain_map = vtk.vtkPolyDataMapper()
    chain_map.SetInputConnection(tubes.GetOutputPort())
    chain_map.SetLookupTable(lut)
    chain_map.SetScalarRange(0.0, top)
    chains = vtk.vtkActor()
    chains.SetMapper(chain_map)

    spheres.GetPointData().SetActiveScalars("radius")
    ball = vtk.vtkSphereSource()
    ball.SetRadius(1.0)
    ball.SetThetaResolution(16)
    ball.SetPhiResolution(12)
    glyphs = vtk.vtkGlyph3D()
    glyphs.SetInputData(spheres)
    glyphs.SetSourceConnection(ball.GetOutputPort())
    glyphs.SetScaleModeToScaleByScalar()
    glyphs.SetScaleFactor(1.0)
    glyphs.SetColorModeToColorByScale()
    ball_map = vtk.vtkPolyDataMapper()
    ball_map.SetInputConnection(glyphs.GetOutputPort())
    ball_map.ScalarVisibilityOff()
    balls = vtk.vtkActor()
    balls.SetMapper(ball_map)
    balls.GetProperty().SetColor(0.55, 0.62, 0.72)
    balls.GetProperty().SetOpacity(0.10)

    floor = vtk.vtkPlaneSource()
    floor.SetOrigin(0.0, 0.0, 0.0)
    floor.SetPoint1(L, 0.0, 0.0)
    floor.SetPoint2(0.0, L, 0.0)
    floor_map = vtk.vtkPolyDataMapper()
    floor_map.SetInputConnection(floor.GetOutputPort())
    ground = vtk.vtkActor()
    ground.SetMapper(floor_map)
    ground.GetProperty().SetColor(0.85, 0.85, 0.85)
    ground.GetProperty().LightingOff()

    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle("force (mN)")
    bar.SetNumberOfLabels(5)
    bar.SetLabelFormat("%.1f")
    bar.SetWidth(0.09)
    bar.SetHeight(0.45)
    bar.SetPosition(0.87, 0.3)
    bar.UnconstrainedFontSizeOn()
    for text, size in ((bar.GetTitleTextProperty(), 16), (bar.GetLabelTextProperty(), 16)):
        text.SetColor(0.1, 0.1, 0.1)
        text.SetFontSize(size)
        text.ItalicOff()
        text.BoldOff()
        text.ShadowOff()
    caption = vtk.vtkTextActor()
    caption.SetInput(
        f"kinema: {spheres.GetNumberOfPoints()} spheres at rest on a floor, {lines.GetNumberOfCells()} contacts between them;"
        "\ntube width and colour: the contact's normal force (the floor's contacts not drawn)"
    )
    caption.GetTextProperty().SetFontSize(18)
    caption.GetTextProperty().SetColor(0.1, 0.1, 0.1)
    caption.SetPosition(12, 12)

    ren = vtk.vtkRenderer()
    ren.SetBackground(1.0, 1.0, 1.0)
    ren.SetUseDepthPeeling(True)
    for actor in (ground, balls, chains, bar, caption):
        ren.AddViewProp(actor)
    height = float(vtk_to_numpy(spheres.GetPoints().GetData())[:, 2].max())
    camera = ren.GetActiveCamera()
    camera.SetFocalPoint(L / 2, L / 2, 0.45 * height)
    camera.SetPosition(L / 2 + 0.9 * L, L / 2 - 3.2 * L, 0.45 * height + 1.1 * L)
    camera.SetViewUp(0.0, 0.0, 1.0)
    camera.SetViewAngle(30.0)
    ren.ResetCameraClippingRange()
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(True)
    window.SetMultiSamples(0)
    window.SetSize(850, 850)
    window.AddRenderer(ren)
    window.Render()
    shot = vtk.vtkWindowToImageFilter()
    shot.SetInput(window)
    shot.SetInputBufferTypeToRGB()
    shot.Update()
    image = shot.GetOutput()
    width, height_px, _ = image.GetDimensions()
    pixels = vtk_to_numpy(image.GetPointData().GetScalars()).reshape(height_px, width, 3)[::-1]
    png.parent.mkdir(parents=True, exist_ok=True)
    # 256 colours, no dithering: a fifth of the bytes of VTK's own PNG, for the docs
    Image.fromarray(np.ascontiguousarray(pixels)).quantize(256, dither=Image.Dither.NONE).save(png, optimize=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=600, help="spheres")
    ap.add_argument("--time", type=float, default=1.0, help="simulated seconds")
    ap.add_argument("--seed", type=int, default=0, help="the lattice's jitter, the radii and the velocities")
    ap.add_argument("--out", type=Path, default=Path("out/pile_measures"), help="folder for the runs' files and the picture")
    ap.add_argument("--picture", type=Path, default=None, help="the force-chain PNG (default OUT/force_chains.png)")
    args = ap.parse_args()
    os.environ.setdefault("RAYON_NUM_THREADS", "1")  # before kinema's thread pool starts
    s = scene(args.n, args.seed)
    k = run_kinema(s, args.time, args.out)
    lmp = find_lammps()
    lam = run_lammps(lmp, s, args.time, args.out) if lmp else None
    if lmp is None:
        print("LAMMPS (lmp) not installed: apt-get install -y lammps; kinema alone below")
    mk = measures(k)
    ml = measures(lam) if lam is not None else None
    table(k, mk, lam, ml, args.n, args.time, args.seed)
    print("\n" + open_in_ovito(k["vtm"], k["contacts"]))
    png = args.picture or args.out / "force_chains.png"
    try:
        render_force_chains(k["vtm"], png)
        print(f"force chains of kinema's last frame ({k['vtm']}), drawn by VTK: {png}")
    except ImportError as missing:
        print(f"no picture: {missing} (pip install vtk matplotlib)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
