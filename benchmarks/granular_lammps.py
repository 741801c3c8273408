"""Grains that roll, kinema beside LAMMPS GRANULAR: a sphere thrown along a floor slides into
rolling, and then rolling resistance slows it.

The scene: a glass sphere (d = 1 cm, 2500 kg/m³) resting on a floor under gravity (9.81 m/s²)
is given v₀ = 1 m/s along x and no spin. Coulomb friction μ = 0.3 slows its centre
(v = v₀ − μ g t) and spins it up against rolling resistance μ_r = 0.002 (a torque μ_r r F_n
against the turning: ω r = 5/2 (μ − μ_r) g t, I = 2/5 m r²) until its contact point stops
slipping: closed form t* = 2 v₀ / ((7 μ − 5 μ_r) g) = 97.55 ms at v* = v₀ − μ g t* (5/7 v₀ for
μ_r = 0). From there rolling resistance slows it at 5/7 μ_r g.

  kinema   World(spin=True), the impulse model: set_collisions(restitution=0.5, friction=μ,
           rolling_friction=μ_r), Plane z = 0, dt = 10 µs; and LAMMPS's contact in kinema's
           force model: set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=ν,
           friction=μ, rolling_friction=μ_r, tangential="linear_history",
           tangential_stiffness=k_t, tangential_damping=1, rolling_stiffness=k_r,
           rolling_damping=0), started at its static overlap
  LAMMPS   atom_style sphere, fix nve/sphere, fix gravity; fix wall/gran granular
           hertz/material E e ν tangential linear_history k_t 1 μ rolling sds k_r γ_r μ_r
           damping tsuji on zplane 0 (E = 10 MPa, ν = 0.3, k_t = 200 N/m, k_r = 200 N/m,
           γ_r = 0), dt = 10 µs, the sphere started at its static overlap

Printed: each engine's slip-to-roll time (the slip velocity v − ω r reaching 1e-3 v₀,
interpolated), the speed when rolling begins and the rolling deceleration, beside the closed
forms. The LAMMPS contact is a spring (k_t) with damping, so its stick begins with a short
elastic ring, and so does kinema's force model; kinema's impulse contact has none (it is exact
to rounding: tests/test_spin.py).
No timings: this is about the same physics. LAMMPS missing: one line, status 0.

    python benchmarks/granular_lammps.py
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

G, D, RHO = 9.81, 0.01, 2500.0
R = D / 2
M = RHO * math.pi / 6 * D**3
V0, MU, MU_R = 1.0, 0.3, 0.002
DT, T_END = 1e-5, 0.3
E, NU, E_REST = 1e7, 0.3, 0.5
K_T, K_ROLL = 200.0, 200.0


def closed_forms() -> dict[str, float]:
    t_star = 2 * V0 / ((7 * MU - 5 * MU_R) * G)
    return {"t_star": t_star, "v_star": V0 - MU * G * t_star, "decel": 5 / 7 * MU_R * G}


def measured(t: np.ndarray, v: np.ndarray, w: np.ndarray) -> dict[str, float]:
    """The slip-to-roll time (the slip v − ω r, linear in time while the ball slides, carried
    to 0 from its last two samples above 1e-3 v₀), the speed then, and the mean deceleration
    over the rolling that follows (from 20 ms after it)."""
    slip = v - w * R
    k = int(np.argmax(slip < 1e-3 * V0))
    t_star = t[k - 1] + (t[k - 1] - t[k - 2]) * slip[k - 1] / (slip[k - 2] - slip[k - 1])
    later = t > t_star + 0.02
    decel = -np.polyfit(t[later], v[later], 1)[0]
    v_star = v[k - 1] + (t_star - t[k - 1]) * (v[k - 1] - v[k - 2]) / (t[k - 1] - t[k - 2])  # (still sliding)
    return {"t_star": t_star, "v_star": float(v_star), "decel": decel}


def run_kinema(force_model: bool = False) -> dict[str, float]:
    """The impulse model, or (`force_model`) LAMMPS's own contact: Hertz with the tangential
    spring and rolling sds of the same constants, the sphere started at its static overlap."""
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "python"))
    import kinema

    w = kinema.World(dt=DT, spin=True)
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.add(kinema.Gravity([0, 0, -G]))
    if force_model:
        w.set_collisions(
            model="hertz",
            youngs_modulus=E,
            poisson_ratio=NU,
            restitution=E_REST,
            friction=MU,
            rolling_friction=MU_R,
            tangential="linear_history",
            tangential_stiffness=K_T,
            tangential_damping=1.0,
            rolling_stiffness=K_ROLL,
            rolling_damping=0.0,
        )
        e_star = E / (2 * (1 - NU * NU))
        z0 = R - (M * G / (4 / 3 * e_star * math.sqrt(R))) ** (2 / 3)
    else:
        w.set_collisions(restitution=E_REST, friction=MU, rolling_friction=MU_R)
        z0 = R
    w.add_particles([0, 0, z0], velocity=[V0, 0, 0], mass=M, radius=R)
    every = 10
    t, v, om = [], [], []
    for _ in range(int(T_END / DT) // every):
        w.step(every)
        t.append(w.time)
        v.append(w.velocities[0, 0])
        om.append(w.angular_velocities[0, 1])
    return measured(np.array(t), np.array(v), np.array(om))


LAMMPS_INPUT = """
units si
atom_style sphere
boundary p p f
region box block -1 1 -0.1 0.1 0 0.1 units box
atom_modify map array
create_box 1 box
comm_modify vel yes
create_atoms 1 single 0 0 {z0} units box
set atom 1 diameter {d} density {rho}
velocity all set {v0} 0 0 units box
fix grav all gravity {g} vector 0 0 -1
fix wall all wall/gran granular hertz/material {E} {e} {nu} tangential linear_history {kt} 1.0 {mu} rolling sds {kr} 0.0 {mur} damping tsuji zplane 0.0 NULL
fix integrate all nve/sphere
timestep {dt}
compute om all property/atom omegay
variable vx equal vx[1]
variable wy equal c_om[1]
thermo_style custom step time v_vx v_wy
thermo_modify format float %.12g
thermo 10
run {steps}
"""


def run_lammps(lmp: str) -> dict[str, float] | None:
    e_star = E / (2 * (1 - NU * NU))
    static = (M * G / (4 / 3 * e_star * math.sqrt(R))) ** (2 / 3)  # m g = 4/3 E* √r δ^(3/2)
    with tempfile.TemporaryDirectory() as work:
        with open(os.path.join(work, "in.lammps"), "w") as f:
            f.write(
                LAMMPS_INPUT.format(
                    z0=R - static, d=D, rho=RHO, v0=V0, g=G, E=E, e=E_REST, nu=NU, kt=K_T, mu=MU, kr=K_ROLL, mur=MU_R, dt=DT, steps=int(T_END / DT)
                )
            )
        env = dict(os.environ, OMP_NUM_THREADS="1")
        res = subprocess.run([lmp, "-in", "in.lammps", "-log", "log.lammps", "-screen", "none"], cwd=work, env=env, capture_output=True, text=True)
        log = open(os.path.join(work, "log.lammps")).read() if os.path.exists(os.path.join(work, "log.lammps")) else ""
        if res.returncode != 0:
            print(f"LAMMPS failed ({res.returncode}): {(res.stderr or log)[-600:]}")
            return None
    rows = [list(map(float, m.groups())) for m in re.finditer(r"^\s*\d+\s+(\S+)\s+(\S+)\s+(\S+)\s*$", log, re.M)]
    a = np.array(rows)
    return measured(a[:, 0], a[:, 1], a[:, 2])


def main() -> int:
    lmp = shutil.which("lmp") or shutil.which("lmp_serial")
    closed = closed_forms()
    rows = [
        ("closed form", closed),
        ("kinema (impulses)", run_kinema()),
        ("kinema (hertz, linear_history, rolling sds)", run_kinema(force_model=True)),
    ]
    if lmp is None:
        print("LAMMPS (lmp) not installed: apt-get install -y lammps; kinema alone below")
    else:
        got = run_lammps(lmp)
        if got is not None:
            rows.append(("LAMMPS (hertz/material, linear_history, rolling sds)", got))
    print(f"{'':55s} {'t* (ms)':>10s} {'v*/v0':>10s} {'rolling decel (m/s²)':>22s}")
    for name, r in rows:
        print(f"{name:55s} {1e3 * r['t_star']:10.4f} {r['v_star'] / V0:10.6f} {r['decel']:22.6f}")
    for name, r in rows[1:]:
        print(
            f"{name}: t* {r['t_star'] / closed['t_star'] - 1:+.2e}, v* {r['v_star'] / closed['v_star'] - 1:+.2e}, "
            f"deceleration {r['decel'] / closed['decel'] - 1:+.2e} against the closed forms"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
