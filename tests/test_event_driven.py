"""Event-driven dynamics of the impulse model (``set_collisions(event_driven=True)``,
crates/kinema/src/collide/event_driven/) against closed forms, kinetic theory and the stepped
model on the same scenes."""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest

import kinema


def fcc_gas(ncell: int, phi: float, seed: int = 7, event_driven: bool = True, restitution: float = 1.0, dt: float = 0.01):
    """4·ncell³ unit spheres (σ = 1, m = 1) on an FCC lattice in a periodic cube at packing
    fraction φ, Maxwell velocities at kT = 1 with no net momentum."""
    n = 4 * ncell**3
    side = (n * math.pi / 6.0 / phi) ** (1.0 / 3.0)
    basis = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]])
    cells = np.stack(np.meshgrid(*[np.arange(ncell)] * 3, indexing="ij"), -1).reshape(-1, 3)
    x = ((cells[:, None, :] + basis[None]).reshape(-1, 3) + 0.25) * side / ncell
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v -= v.mean(axis=0)
    v *= math.sqrt((3 * n - 3) / (v**2).sum())
    w = kinema.World(dt=dt, method="verlet")
    w.add_particles(x, velocity=v, mass=1.0, radius=0.5)
    w.add(kinema.Box([0.0] * 3, [side] * 3))
    w.periodic = (True, True, True)
    w.set_collisions(restitution=restitution, event_driven=event_driven)
    return w, side


def enskog_rate(n: int, side: float) -> float:
    """Collisions per unit time in a hard-sphere gas (σ = m = kT = 1): N ω_E / 2 with Enskog's
    ω_E = 4 √π n σ² χ √(kT/m) and Carnahan–Starling's χ = (1 − φ/2)/(1 − φ)³."""
    density = n / side**3
    phi = math.pi * density / 6
    chi = (1 - phi / 2) / (1 - phi) ** 3
    return 0.5 * n * 4 * math.sqrt(math.pi) * density * chi


def min_distance(x: np.ndarray, side: float) -> float:
    d = x[:, None, :] - x[None, :, :]
    d -= side * np.round(d / side)
    r = np.sqrt((d**2).sum(-1))
    np.fill_diagonal(r, np.inf)
    return float(r.min())


def test_a_head_on_impact_is_at_its_exact_time_with_newtons_law():
    # Two spheres (r = 0.1, masses 1 and 3) approach at 2 m/s from a gap of 0.3 m: they touch
    # at t = 0.15 s exactly; Newton's law with e = 0.5 gives v1' = (m1 − e m2) v/(m1 + m2) + ...
    # in closed form: u' = −e u, momentum kept. After t = 0.4 s each has flown 0.25 s apart.
    w = kinema.World(dt=0.1, method="verlet")
    w.add_particles([[0.0, 0, 0], [0.5, 0, 0]], velocity=[[1.0, 0, 0], [-1.0, 0, 0]], mass=[1.0, 3.0], radius=0.1)
    w.set_collisions(restitution=0.5, event_driven=True)
    w.step(4)
    m1, m2, e = 1.0, 3.0, 0.5
    p = m1 * 1.0 + m2 * -1.0
    # u' = v2' − v1' = e (v1 − v2) = 1.0; m1 v1' + m2 v2' = p
    v1 = (p - m2 * e * 2.0) / (m1 + m2)
    v2 = v1 + e * 2.0
    np.testing.assert_allclose(w.velocities[:, 0], [v1, v2], rtol=0, atol=1e-15)
    t_hit = 0.15
    x_hit = [0.0 + 1.0 * t_hit, 0.5 - 1.0 * t_hit]
    np.testing.assert_allclose(w.positions[:, 0], [x_hit[0] + v1 * 0.25, x_hit[1] + v2 * 0.25], rtol=0, atol=1e-15)
    s = w.collision_stats()["total"]
    assert s["impacts"] == 1
    # ½ (1 − e²) μ u² lost, μ the reduced mass
    assert s["energy_lost"] == pytest.approx(0.5 * (1 - e * e) * (m1 * m2 / (m1 + m2)) * 4.0, rel=1e-14)
    assert w.time == pytest.approx(0.4, abs=1e-15)


def test_the_cradle_passes_the_momentum_down_the_row_as_the_stepped_model_does():
    # Five touching equal balls, the first hit at 1 m/s (e = 1): by Newton's law each touching
    # pair exchanges velocities in turn; the last ball leaves at 1 m/s and the others stand.
    # The stepped model does the same (issue 29: the same results as today's model).
    finals = []
    for event_driven in (True, False):
        w = kinema.World(dt=1e-3, method="verlet")
        x = [[-0.5, 0, 0]] + [[0.2 * k, 0, 0] for k in range(5)]
        v = [[1.0, 0, 0]] + [[0.0, 0, 0]] * 5
        w.add_particles(x, velocity=v, mass=1.0, radius=0.1)
        w.set_collisions(restitution=1.0, event_driven=event_driven)
        w.step(1000)
        finals.append(w.velocities[:, 0].copy())
    np.testing.assert_allclose(finals[0], [0, 0, 0, 0, 0, 1.0], rtol=0, atol=1e-14)
    np.testing.assert_allclose(finals[0], finals[1], rtol=0, atol=1e-14)


def test_an_elastic_gas_keeps_energy_and_momentum_and_never_overlaps():
    w, side = fcc_gas(5, 0.35)  # 500 spheres, moderately dense
    d0 = w.diagnostics()
    w.step(200)  # t = 2: ~20 collisions a sphere
    d1 = w.diagnostics()
    assert w.collision_stats()["total"]["impacts"] > 5000
    assert abs(d1["kinetic"] - d0["kinetic"]) <= 1e-12 * d0["kinetic"]
    np.testing.assert_allclose(d1["momentum"], d0["momentum"], rtol=0, atol=1e-11)
    assert w.collision_stats()["total"]["energy_lost"] == 0.0
    assert min_distance(w.positions, side) > 1.0 - 1e-9
    assert np.all((w.positions >= 0) & (w.positions < side))


def test_the_collision_rate_is_enskogs_and_the_stepped_models():
    # Enskog's rate with Carnahan–Starling's χ holds to ~1 % at φ = 0.25 (Alder, Gass and
    # Wainwright's MD); the event-driven and the stepped gas from the same start count the
    # same collisions to within the noise (~1 % for ~30,000 collisions of a gas this small).
    counts = {}
    for event_driven in (True, False):
        w, side = fcc_gas(8, 0.25, event_driven=event_driven)  # 2048 spheres
        w.step(100)  # settle from the lattice
        before = w.collision_stats()["total"]["impacts"]
        w.step(200)
        counts[event_driven] = w.collision_stats()["total"]["impacts"] - before
    expected = enskog_rate(len(w), side) * 2.0
    assert counts[True] / expected == pytest.approx(1.0, abs=0.03)
    assert counts[True] / counts[False] == pytest.approx(1.0, abs=0.02)


def test_haffs_law_with_enskogs_time_in_a_dilute_inelastic_gas():
    # Haff's law T = T₀/(1 + t/τ)², Enskog's 1/τ = (1 − e²) ω_E(T₀)/6 (examples/sweeps/haff.py
    # derives it): at n σ³ = 0.05, e = 0.9, τ fitted from √(T_s/T) after the lattice is
    # forgotten, within 4 % as the stepped model's test (tests/test_sweeps.py).
    ncell, density, e = 8, 0.05, 0.9  # 2048 spheres, simple cubic would be the sweep's; FCC here
    phi = math.pi * density / 6
    w, side = fcc_gas(ncell, phi, restitution=e, dt=0.5)
    n = len(w)
    chi = (1 - phi / 2) / (1 - phi) ** 3
    tau_theory = 6.0 / ((1 - e * e) * 4 * math.sqrt(math.pi) * density * chi)
    t, temp = [], []
    for _ in range(120):  # t = 0 … 60
        t.append(w.time)
        temp.append((w.velocities**2).sum() / (3 * n))
        w.step(1)
    t, temp = np.array(t), np.array(temp)
    late = t >= 10.0
    t_s, temp_s = t[late][0], temp[late][0]
    slope = np.polyfit(t[late] - t_s, np.sqrt(temp_s / temp[late]), 1)[0]
    tau = math.sqrt(temp_s / temp[0]) / slope
    assert tau / tau_theory == pytest.approx(1.0, abs=0.04)
    # the books: the energy the impacts removed is what the gas lost
    lost = w.collision_stats()["total"]["energy_lost"]
    assert lost == pytest.approx(1.5 * n * (temp[0] - (w.velocities**2).sum() / (3 * n)), rel=1e-9)


def test_walls_keep_the_gas_in_and_book_the_momentum_they_took():
    # A gas in a closed box (no periodic axes): every sphere stays inside, energy is kept
    # (e = 1), and the momentum the particles gained is what the walls' books gave away.
    rng = np.random.default_rng(3)
    x = np.stack(np.meshgrid(*[np.arange(6) * 0.15 + 0.1] * 3, indexing="ij"), -1).reshape(-1, 3)
    v = rng.normal(size=x.shape)
    w = kinema.World(dt=0.01, method="verlet")
    w.add_particles(x, velocity=v, mass=2.0, radius=0.05)
    w.add(kinema.Box([0.0] * 3, [1.0] * 3))
    w.set_collisions(event_driven=True)
    p0, e0 = w.diagnostics()["momentum"], w.diagnostics()["kinetic"]
    w.step(300)
    d = w.diagnostics()
    assert np.all(w.positions >= 0.05 - 1e-12) and np.all(w.positions <= 0.95 + 1e-12)
    assert abs(d["kinetic"] - e0) <= 1e-12 * e0
    books = w.collider_books()
    np.testing.assert_allclose(np.array(d["momentum"]) - p0, -books["momentum"][0], rtol=0, atol=1e-10)


def test_a_2d_gas_stays_in_its_plane():
    rng = np.random.default_rng(4)
    g = np.stack(np.meshgrid(np.arange(20) * 0.05 + 0.025, np.arange(20) * 0.05 + 0.025, indexing="ij"), -1).reshape(-1, 2)
    x = np.column_stack([g, np.zeros(len(g))])
    v = np.column_stack([rng.normal(size=(len(g), 2)), np.zeros(len(g))])
    w = kinema.World(dt=0.01, method="verlet", dim=2)
    w.add_particles(x, velocity=v, mass=1.0, radius=0.015)
    w.add(kinema.Box([0.0, 0.0], [1.0, 1.0]))
    w.periodic = (True, True)
    w.set_collisions(event_driven=True)
    e0 = w.diagnostics()["kinetic"]
    w.step(100)
    assert w.collision_stats()["total"]["impacts"] > 1000
    assert np.all(w.positions[:, 2] == 0) and np.all(w.velocities[:, 2] == 0)
    assert abs(w.diagnostics()["kinetic"] - e0) <= 1e-12 * e0


@pytest.mark.parametrize("cuts", [[10] * 10, [1] * 100, [37, 63], [99, 1]])
@pytest.mark.parametrize("gravity", [False, True])
def test_a_run_is_the_same_bits_however_it_is_cut_into_calls(cuts, gravity):
    # The state is kept between calls, each particle at its own time: ten calls of 10 steps,
    # a hundred of 1, or any cut follow the same events as one call of 100, to the bit (as the
    # stepped model does). Before, each call moved every particle to its end, rounding there,
    # and 200 calls of 1 step, 20 of 10 and one of 200 gave three different runs.
    a, _ = fcc_gas(3, 0.3)
    b, _ = fcc_gas(3, 0.3)
    if gravity:
        for w in (a, b):
            w.add(kinema.Gravity(g=(0.0, 0.0, -2.0)))
    a.step(sum(cuts))
    for n in cuts:
        b.step(n)
    assert a.collision_stats()["total"]["impacts"] == b.collision_stats()["total"]["impacts"] > 0
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.velocities, b.velocities)


def test_an_elastic_ball_bounces_on_the_exact_parabola_under_gravity():
    # Dropped from rest with its bottom h = 0.5 m above a floor, e = 1: it falls for
    # √(2h/g), bounces, and repeats with period T = 2√(2h/g); between bounces
    # z(t) = r + h − ½ g s², s the time from the nearest apex. Events fly the parabola exactly
    # and find each bounce by its quadratic, so after ten bounces the closed form holds to
    # rounding; the stepped model (velocity Verlet, exact on parabolas) agrees.
    g, h, r = 9.81, 0.5, 0.05
    period = 2 * math.sqrt(2 * h / g)
    worlds = []
    for event_driven in (True, False):
        w = kinema.World(dt=1e-3, method="verlet")
        w.add_particles([[0.0, 0.0, r + h]], radius=r)
        w.add(kinema.Gravity([0, 0, -g]))
        w.add(kinema.Plane([0, 0, 0], [0, 0, 1], restitution=1.0))
        w.set_collisions(restitution=1.0, event_driven=event_driven)
        worlds.append(w)
    zs = []
    for _ in range(34):  # to t = 10.2 s: 16 bounces
        for w in worlds:
            w.step(300)
        t = worlds[0].time
        s = (t + period / 2) % period - period / 2
        expected = r + h - 0.5 * g * s * s
        assert worlds[0].positions[0, 2] == pytest.approx(expected, abs=1e-11)
        zs.append((worlds[0].positions[0, 2], worlds[1].positions[0, 2]))
    assert worlds[0].collision_stats()["total"]["impacts"] == 16
    np.testing.assert_allclose(*np.array(zs).T, rtol=0, atol=1e-9)


def test_an_elastic_gas_under_gravity_keeps_its_energy():
    # 512 spheres in a box periodic across, floored and lidded, under g: kinetic plus
    # gravitational energy is kept to rounding through thousands of impacts and bounces (3,622 in 5 s).
    w, side = fcc_gas(5, 0.1)
    w.periodic = (True, True, False)
    w.add(kinema.Gravity([0, 0, -0.5]))
    w.set_collisions(restitution=1.0, event_driven=True)
    energy = lambda d: d["kinetic"] + sum(d["potential"].values())  # noqa: E731
    e0 = energy(w.diagnostics())
    w.step(500)
    d = w.diagnostics()
    assert w.collision_stats()["total"]["impacts"] > 3000
    assert abs(energy(d) - e0) <= 1e-11 * abs(e0)
    assert np.all(w.positions[:, 2] >= 0.5 - 1e-9) and np.all(w.positions[:, 2] <= side - 0.5 + 1e-9)


def one_ball(z: float, restitution: float = 1.0, gravity: bool = True, floor: bool = True, pinned: bool = False):
    """A ball of r = 0.1 m at height z (m), under gravity over a floor, with a second ball
    beside it (pinned when `pinned`), event-driven."""
    w = kinema.World(dt=0.01)
    w.add_particles([[0.0, 0, z], [1.0, 0, z]], radius=0.1, pinned=[False, pinned])
    if gravity:
        w.add(kinema.Gravity())
    if floor:
        w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(restitution=restitution, event_driven=True)
    return w


def plus(w, thing):
    w.add(thing)
    return w


@pytest.mark.parametrize(
    "world, why",
    [
        # a force that is not a uniform field
        (lambda: plus(fcc_gas(2, 0.2)[0], kinema.Drag(0.1)), r"event_driven = True is invalid: .*force 'drag'"),
        # under a field: a pinned particle would not fall with the others, a dissipative floor
        # would end in resting contact, and a ball placed at rest on the floor is one
        (lambda: one_ball(1.0, floor=False, pinned=True), "particle 1 is pinned"),
        (lambda: one_ball(1.0, restitution=0.9), "every restitution must be 1"),
        (lambda: one_ball(0.1), "particle 0 rests on collider 0 under the field"),
        # colliders other than planes and boxes
        (lambda: plus(one_ball(0.0, gravity=False, floor=False), kinema.SphereObstacle([0.0, 2.0, 0], 0.5)), "collider 0 is a sphere obstacle"),
    ],
)
def test_what_it_cannot_run_is_refused_naming_why(world, why):
    w = world()
    before = w.positions.copy()
    with pytest.raises(ValueError, match=why):
        w.step(1)
    np.testing.assert_array_equal(w.positions, before)  # the world as it was


def test_the_setting_round_trips_and_scenes_take_it():
    w, _ = fcc_gas(2, 0.2)
    assert w.collisions["event_driven"] is True
    w.set_collisions(**w.collisions)
    assert w.collisions["event_driven"] is True
    scene = """
[world]
dt = 0.01
duration = 0.5
[[particles]]
type = "lattice"
origin = [0.5, 0.5, 0.5]
counts = [4, 4, 4]
spacing = 1.5
radius = 0.5
velocity = { kT = 1.0, zero_momentum = true }
seed = 1
[[colliders]]
type = "box"
lo = [0, 0, 0]
hi = [6, 6, 6]
[collisions]
event_driven = true
periodic = [true, true, true]
"""
    built = kinema.Scene.from_string(scene).build()
    assert built.collisions["event_driven"] is True
    e0 = built.diagnostics()["kinetic"]
    built.step(50)
    assert built.collision_stats()["total"]["impacts"] > 10
    assert built.diagnostics()["kinetic"] == pytest.approx(e0, rel=1e-12)
    assert kinema.Scene.from_string(kinema.Scene.from_string(scene).to_toml_string()).collisions.event_driven is True


def test_a_run_is_the_same_bits_on_any_number_of_threads(on_threads):
    # The lists and shells are built on all threads; the events run in one calendar order:
    # 1, 2 and 3 threads give the same bits, cut into calls or not.
    out = on_threads(
        "import sys, hashlib; sys.path.insert(0, 'tests'); import test_event_driven as t; "
        "w, _ = t.fcc_gas(4, 0.3); [w.step(n) for n in (13, 50, 37)]; "
        "print(hashlib.sha256(w.positions.tobytes() + w.velocities.tobytes()).hexdigest())"
    )
    assert out[1] == out[2] == out[3], out


def test_a_run_is_the_same_bits_on_either_instruction_set():
    # The event loop runs compiled for x86-64-v3 where the CPU has it, and for the baseline
    # with KINEMA_SIMD=baseline (crates/kinema/src/simd.rs): an inelastic gas with friction
    # and one under gravity between walls come out the same to the bit. (On a CPU without
    # x86-64-v3 both runs take the baseline.)
    script = (
        "import sys, hashlib; sys.path.insert(0, 'tests'); import test_event_driven as t, kinema; "
        "w, _ = t.fcc_gas(4, 0.3, restitution=0.8); w.step(120); "
        "g = kinema.World(dt=0.01); g.add_particles(w.positions, velocity=w.velocities, mass=1.0, radius=0.5); "
        "g.add(kinema.Box([0, 0, 0], [w.positions.max() + 1] * 3)); g.add(kinema.Gravity((0, 0, -1.0))); "
        "g.set_collisions(restitution=1.0, friction=0.3, event_driven=True); g.step(100); "
        "print(kinema._core.simd_level(), w.collision_stats()['total']['impacts'], g.collision_stats()['total']['impacts'], "
        "hashlib.sha256(w.positions.tobytes() + w.velocities.tobytes() + g.positions.tobytes() + g.velocities.tobytes()).hexdigest())"
    )
    out = {}
    for simd in ("baseline", "auto"):
        env = {**os.environ, "KINEMA_SIMD": simd}
        out[simd] = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True).stdout.strip()
    assert out["baseline"].split()[0] == "baseline", out  # the switch is honoured
    impacts = [int(k) for k in out["auto"].split()[1:3]]
    assert min(impacts) > 100, out
    assert out["baseline"].split()[1:] == out["auto"].split()[1:], out


def _folded(x0: np.ndarray, v: np.ndarray, t: float, lo: float, hi: float) -> np.ndarray:
    """Free flight between two walls at lo and hi, reflected elastically: the unfolded line
    x0 + v t folded back into [lo, hi] (period 2 (hi − lo))."""
    span = hi - lo
    u = np.mod(x0 + v * t - lo, 2 * span)
    return lo + np.where(u > span, 2 * span - u, u)


@pytest.mark.parametrize("radius", [0.0, 1e-9])
def test_point_particles_bounce_in_a_box_on_their_closed_form_paths(radius):
    # Points meet nothing but the walls: each coordinate is the free flight folded back into
    # the box. Before, their shells were of no size (0.7 of a diameter of 0): every move left
    # one, and 20 steps of 1 ms never ended.
    rng = np.random.default_rng(1)
    x0, v = rng.uniform(0.1, 0.9, (200, 3)), rng.normal(0, 1, (200, 3))
    w = kinema.World(dt=1e-3)
    w.add_particles(x0, velocity=v, radius=radius, mass=1.0)
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.set_collisions(restitution=1.0, event_driven=True)
    w.step(1000)
    assert w.collision_stats()["total"]["impacts"] > 400
    np.testing.assert_allclose(w.positions, _folded(x0, v, 1.0, radius, 1.0 - radius), rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.abs(w.velocities), np.abs(v), rtol=1e-12, atol=0)


@pytest.mark.parametrize("speed", [1e10, 1e151, 1e200])
def test_speeds_the_events_cannot_follow_are_refused_as_a_step_refuses_them(speed):
    # 1e10 m/s in a 1 m box is 1e7 wall events a millisecond: the stepped model stops such a
    # step (SimulationDiverged, "would travel ... over 1000 times the scene's extent"), and so
    # do the events now, before any event, the world left as it was. Before, 1e10–1e151 m/s
    # never returned and 1e200 m/s returned at once with every ball outside the box.
    w = kinema.World(dt=1e-3)
    w.add_particles([[0.5, 0.5, 0.5], [0.2, 0.2, 0.2]], velocity=[[speed, 0, 0], [0, 0, 0]], radius=0.05, mass=1.0)
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.set_collisions(restitution=1.0, event_driven=True)
    with pytest.raises(kinema.SimulationDiverged, match=r"at step 1 \(t = 0 s.*particle 0: a particle would travel .* over 1000 times the scene's extent"):
        w.step(1)
    assert w.time == 0.0
    np.testing.assert_array_equal(w.positions, [[0.5, 0.5, 0.5], [0.2, 0.2, 0.2]])
