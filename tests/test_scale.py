"""The granular gas at scale: results independent of the thread count (spring–dashpot and
impulse contacts), and the
engine's space-filling-curve order of the particles invisible from outside."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np

# The granular gas of benchmarks/granular_gas.py (LAMMPS's granular_gas.in), small: 17³ = 4,913
# particles, more than the 4,096 from which the engine sorts them and more than two chunks
# of its parallel passes.
GAS = textwrap.dedent(
    """
    import hashlib, math, sys
    import numpy as np
    import kinema

    def gas(ncell, extra_force=False, model="spring_dashpot"):
        a = (1 / 0.3) ** (1 / 3)
        i, j, k = np.meshgrid(*[np.arange(ncell)] * 3, indexing="ij")
        x = np.stack([i, j, k], axis=-1).reshape(-1, 3) * a
        v = np.random.default_rng(1).uniform(-0.5, 0.5, x.shape)
        v -= v.mean(axis=0)
        w = kinema.World(dt=1e-3, method="verlet")
        n = len(x)
        w.add_particles(x, velocity=v * 3.4, mass=1.0 + (np.arange(n) % 3) * 0.25, radius=0.5 - (np.arange(n) % 2) * 0.05)
        w.add(kinema.Box([0, 0, 0], [ncell * a] * 3))
        w.periodic = (True, True, True)
        if model == "impulse":
            w.set_collisions(model="impulse", restitution=0.2588)
        else:
            w.set_collisions(model="spring_dashpot", stiffness=2000.0, damping=50.0)
        if extra_force:  # a Python force (zero) cannot follow a renumbering: no sorting
            w.add(kinema.PythonForce(lambda t, x, v: np.zeros_like(x)))
        return w
    """
)


def _run(code: str, threads: int) -> str:
    env = {**os.environ, "RAYON_NUM_THREADS": str(threads)}
    res = subprocess.run([sys.executable, "-c", GAS + textwrap.dedent(code)], env=env, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    return res.stdout.strip()


def test_one_two_and_three_threads_give_the_same_gas_bit_for_bit():
    # 1,000 steps of the gas: every pass of the step (drift, neighbour list, forces, kick,
    # sorting) splits its work into fixed chunks and reduces them in a fixed order, so the
    # thread count cannot change a bit of the state.
    code = """
    w = gas(17)
    w.step(1000)
    h = hashlib.sha256(w.positions.tobytes() + w.velocities.tobytes()).hexdigest()
    ke = 0.5 * float(np.sum(w.masses[:, None] * w.velocities**2))
    print(h, ke)
    """
    out = {t: _run(code, t) for t in (1, 2, 3)}
    assert out[1] == out[2] == out[3], out


def test_the_impulse_gas_is_the_same_for_any_thread_count():
    # The impulse model: every pair's first impact is found on all threads (chunks of the
    # neighbour list), then sorted by (particle, time, partner) before the queue takes them;
    # the impacts run in time order on one thread. Bit for bit the same for 1, 2 and 3 threads.
    code = """
    w = gas(17, model="impulse")
    w.step(300)
    h = hashlib.sha256(w.positions.tobytes() + w.velocities.tobytes()).hexdigest()
    print(h, w.collision_stats()["total"]["impacts"])
    """
    out = {t: _run(code, t) for t in (1, 2, 3)}
    assert out[1] == out[2] == out[3], out
    assert int(out[1].split()[1]) > 100, out  # the gas collides


def sorted_and_unsorted_agree(printed: str) -> None:
    """The runs a test printed as JSON, {"False": sorted, "True": unsorted} each [positions,
    velocities], agree to rounding: 1e-9 m and 1e-8 m/s."""
    import json

    res = json.loads(printed)
    xs, vs = np.array(res["False"][0]), np.array(res["False"][1])
    xu, vu = np.array(res["True"][0]), np.array(res["True"][1])
    np.testing.assert_allclose(xs, xu, rtol=0, atol=1e-9)
    np.testing.assert_allclose(vs, vu, rtol=0, atol=1e-8)


def test_the_sorted_order_is_invisible():
    # The same gas twice: plainly, where the engine sorts its particles along a Morton curve,
    # and with a Python force (zero) that cannot follow a renumbering, where it keeps the
    # user's order (`sorts` counts the engine's sorts: some in the first, none in the
    # second). From outside both are the same particles in the same order: masses and radii
    # as given, positions and velocities the same to rounding (the sorted run may sum a
    # particle's contact forces in another order; in a dilute gas, with rarely two contacts
    # on one particle at once, they mostly agree to the bit).
    code = """
    import json
    out = {}
    for extra in (False, True):
        w = gas(17, extra_force=extra)
        m0, r0 = w.masses.copy(), np.array(w._core.radii)
        w.step(150)
        w.step(150)
        assert np.array_equal(w.masses, m0) and np.array_equal(np.array(w._core.radii), r0)
        assert (w._core.sorts > 0) != extra, (extra, w._core.sorts)
        out[str(extra)] = [w.positions.tolist(), w.velocities.tolist()]
    print(json.dumps(out))
    """
    sorted_and_unsorted_agree(_run(code, 2))


def test_particles_with_their_own_materials_are_sorted_with_them():
    # Particles with their own restitution and friction: the engine sorted none of them (the
    # stage's per-particle materials were not moved by the sort, so it was turned off). Now
    # the materials move with their particles: the sorted gas (sorts > 0) is the unsorted one
    # (a Python force keeps the user's order) to rounding, each particle with its own e and μ
    # (were a material left at its old place, pairs would be damped by other particles' e).
    code = """
    import json
    out = {}
    for extra in (False, True):
        w = gas(17, extra_force=extra)
        n = len(w)
        e = 0.3 + 0.6 * (np.arange(n) % 5) / 4  # 0.3 … 0.9
        mu = 0.1 * (np.arange(n) % 3)
        x, v, m, r = w.positions.copy(), w.velocities.copy(), w.masses.copy(), np.array(w._core.radii)
        w = kinema.World(dt=1e-3, method="verlet")
        w.add_particles(x, velocity=v, mass=m, radius=r, restitution=e, friction=mu)
        w.add(kinema.Box([0, 0, 0], [17 * (1 / 0.3) ** (1 / 3)] * 3))
        w.periodic = (True, True, True)
        w.set_collisions(model="spring_dashpot", stiffness=2000.0, damping=50.0)
        if extra:
            w.add(kinema.PythonForce(lambda t, x, v: np.zeros_like(x)))
        w.step(150)
        w.step(150)
        assert (w._core.sorts > 0) != extra, (extra, w._core.sorts)
        assert w._core.particle_materials() == [(a, b) for a, b in zip(e.tolist(), mu.tolist())]
        out[str(extra)] = [w.positions.tolist(), w.velocities.tolist()]
    print(json.dumps(out))
    """
    sorted_and_unsorted_agree(_run(code, 2))


def test_a_heap_solved_on_threads_is_the_same_for_any_thread_count():
    # A block of 12·12·6 touching balls resting on a floor under gravity (e = 0.5, μ = 0.3):
    # its end-of-step contacts are one island of about 2,450 contacts, which the solver
    # colours and sweeps colour by colour on all threads (collide/islands.rs, sweeps.rs).
    # Bit for bit the same for 1, 2 and 3 threads, and the block stays put (it rests).
    code = """
    n = 12 * 12 * 6
    q = np.arange(n)
    x = np.stack([q % 12, q // 12 % 12, q // 144], axis=1) * 0.02 + [0, 0, 0.01]
    w = kinema.World(dt=1e-3, method="verlet")
    w.add_particles(x, radius=0.01, mass=0.005)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(restitution=0.5, friction=0.3)
    w.step(40)
    last = w.collision_stats()["last"]
    h = hashlib.sha256(w.positions.tobytes() + w.velocities.tobytes()).hexdigest()
    print(h, last["contacts"], last["islands"], float(np.abs(w.velocities).max()), float(np.abs(w.positions - x).max()))
    """
    out = {t: _run(code, t) for t in (1, 2, 3)}
    assert out[1] == out[2] == out[3], out
    _, contacts, islands, vmax, moved = out[1].split()
    assert int(contacts) >= 2400 and int(islands) == 1, out[1]
    assert float(vmax) < 1e-3 and float(moved) < 1e-4, out[1]  # at rest: it never fell


def test_the_engine_keeps_its_order_between_calls_and_python_reads_the_users():
    # Between calls of `step` the engine keeps the particles sorted along space (no
    # permutation back and forth per call, as LAMMPS keeps its sorted atoms and a tag → index
    # map): every read goes through the map. Checked: the order survives the calls; stepping
    # in 1, 2 or 10 calls gives the same bits; what Python reads is in the user's order (ids
    # ascending, masses and radii as given, the state the same as after putting the particles
    # back); a write lands on the particle written (the kinetic energy the engine then
    # measures is the one of the written arrays); a time of death reaches the particle it
    # was given for.
    code = """
    import json
    runs = {}
    for calls in (1, 2, 10):
        w = gas(17)
        m0, r0 = w.masses.copy(), np.array(w._core.radii)
        for _ in range(calls):
            w.step(300 // calls)
        assert w._core.in_engine_order, calls
        ids = w.ids
        assert np.all(np.diff(ids) > 0) and np.array_equal(w.masses, m0) and np.array_equal(np.array(w._core.radii), r0)
        runs[calls] = hashlib.sha256(w.positions.tobytes() + w.velocities.tobytes()).hexdigest()
    assert runs[1] == runs[2] == runs[10], runs
    x, v = w.positions.copy(), w.velocities.copy()
    w.contacts()  # (given particle indices: it puts the particles back in the user's order)
    assert not w._core.in_engine_order
    assert np.array_equal(np.asarray(w._core.positions), x) and np.array_equal(np.asarray(w._core.velocities), v)
    w.step(50)
    assert w._core.in_engine_order
    w.velocities[7] = [3.0, -2.0, 1.0]  # a particle of mass 1.25 (masses cycle 1, 1.25, 1.5)
    ke = 0.5 * float(np.sum(w.masses[:, None] * w.velocities**2))
    print(json.dumps({"ke": ke, "engine": w.diagnostics()["kinetic"]}))
    assert np.array_equal(np.asarray(w._core.velocities)[7], [3.0, -2.0, 1.0])
    # times of death, given in the user's order while the engine keeps its own
    w.step(50)
    assert w._core.in_engine_order
    doomed = np.array([5, 600, 4000])
    death = np.full(len(w), np.inf)
    death[doomed] = w.time + 0.0105
    w._core.set_times_of_death(0, death)  # (the engine keeps the times of death: issue 50)
    gone = set(w.ids[doomed].tolist())
    w.step(20)
    assert len(w) == 17**3 - 3 and not gone & set(w.ids.tolist()), gone
    """
    import json

    res = json.loads(_run(code, 2))
    assert abs(res["engine"] - res["ke"]) <= 1e-12 * res["ke"], res
