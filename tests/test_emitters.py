"""Emitters, lifetimes, kill volumes and worlds whose particle count changes, against what
each must be exactly: births at start + k/rate, deaths at birth + lifetime, free flight in
closed form across births, the same particles for any step, seed and thread count."""

import hashlib
import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest

import kinema
from kinema import Emitter, KillBox, KillPlane, KillSphere

SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"


def births_by(t, rate, start=0.0, end=np.inf):
    """Particles born by time t: k = 0, 1, ... with start + k/rate <= t and < end."""
    if t < start:
        return 0
    count = int(np.floor((t - start) * rate + 1e-9)) + 1
    return min(count, int(np.ceil((end - start) * rate))) if np.isfinite(end) else count


def test_births_come_at_start_plus_k_over_rate_until_end():
    w = kinema.World(dt=1e-3)
    w.add(Emitter(rate=50.0, start=0.1, end=0.5, speed=1.0, mass=1.0))
    traj = w.run(0.8, fps=50)
    # frames at t = 0.02 k; births up to the frame's last step start, t - dt
    expected = [births_by(t - 1e-3, 50.0, 0.1, 0.5) if t > 0 else 0 for t in traj.t]
    assert traj.alive.sum(axis=1).tolist() == expected
    assert traj.alive.sum(axis=1)[-1] == 20  # 0.4 s × 50/s
    assert traj.ids.tolist() == list(range(20))


def test_ids_are_never_reused_and_each_particle_lives_once():
    w = kinema.World(dt=1e-3)
    w.add(Emitter(rate=200.0, speed=1.0, mass=1.0, lifetime=0.1, lifetime_spread=0.05, seed=4))
    traj = w.run(0.5, fps=100)
    assert len(np.unique(traj.ids)) == traj.ids.size
    # alive over one contiguous run of frames per particle: born once, dead once
    changes = np.abs(np.diff(traj.alive.astype(int), axis=0)).sum(axis=0)
    assert changes.max() <= 2
    assert np.all(np.isnan(traj.positions[~traj.alive]))
    assert np.all(np.isfinite(traj.positions[traj.alive]))


@pytest.mark.parametrize("method", ["verlet", "rk4", "midpoint", "rk45"])
def test_free_flight_across_births_is_the_closed_form(method):
    # Under gravity alone, a particle that joins at step boundary t_j at x_j with v0 moves on
    # x(t) = x_j + v0 (t - t_j) + ½ g (t - t_j)², v = v0 + g (t - t_j): exact for every method
    # of order >= 2 (the parabola is a quadratic), whatever was born before or after it.
    dt, rate, g = 2e-3, 70.0, np.array([0.0, 0.0, -9.81])
    w = kinema.World(dt=dt, method=method)
    w.add(kinema.Gravity())
    w.add(Emitter(rate=rate, shape="sphere", radius=0.1, speed=2.0, speed_spread=0.5, spread=30, mass=1.0, seed=9))
    traj = w.run(0.4, fps=50)
    born = np.arange(traj.ids.size) / rate  # id k is the k-th birth
    joined = np.ceil(born / dt - 1e-9) * dt  # the first step boundary at or after it
    # where each joined: the first frame it is alive, stepped back to its joining time
    first = traj.alive.argmax(axis=0)
    t_first = traj.t[first]
    v0 = traj.velocities[first, np.arange(traj.ids.size)] - g * (t_first - joined)[:, None]
    x_j = traj.positions[first, np.arange(traj.ids.size)] - v0 * (t_first - joined)[:, None] - 0.5 * g * ((t_first - joined) ** 2)[:, None]
    for f, t in enumerate(traj.t):
        live = traj.alive[f]
        tau = (t - joined[live])[:, None]
        np.testing.assert_allclose(traj.positions[f, live], x_j[live] + v0[live] * tau + 0.5 * g * tau**2, atol=1e-11)
        np.testing.assert_allclose(traj.velocities[f, live], v0[live] + g * tau, atol=1e-11)
    # the joining state is the birth carried by v0 from the birth time: on the sphere there
    r = np.linalg.norm(x_j - v0 * (joined - born)[:, None], axis=1)
    np.testing.assert_allclose(r, 0.1, rtol=1e-12)


def test_the_kth_particle_is_the_same_for_any_step():
    # Each quantity has its own random stream consumed particle by particle, and births are
    # carried from their exact time: in free flight (no force) the k-th particle is at the same
    # place at a common time whatever dt (to rounding).
    def run(dt):
        w = kinema.World(dt=dt)
        w.add(Emitter(rate=40.0, shape="box", size=(0.2, 0.1, 0.3), speed=1.5, speed_spread=0.5, spread=45, particle_radius=0.01, radius_spread=0.004, seed=11))
        traj = w.run(0.5, fps=10)
        return traj

    a, b = run(1e-3), run(2.5e-4)
    live = a.alive[-1] & b.alive[-1]
    assert live.sum() >= 19
    np.testing.assert_allclose(a.positions[-1, live], b.positions[-1, live], atol=1e-12)
    np.testing.assert_array_equal(a.velocities[-1, live], b.velocities[-1, live])
    np.testing.assert_array_equal(a.radii[live], b.radii[live])
    c = kinema.World(dt=1e-3)
    c.add(Emitter(rate=40.0, shape="box", size=(0.2, 0.1, 0.3), speed=1.5, speed_spread=0.5, spread=45, particle_radius=0.01, radius_spread=0.004, seed=12))
    other = c.run(0.5, fps=10)
    assert not np.allclose(other.velocities[-1, live], a.velocities[-1, live])  # another seed, other particles


def test_shapes_place_their_births_where_they_say():
    def births(dim=3, **kw):
        w = kinema.World(dim=dim, dt=1e-3)
        w.add(Emitter(rate=5000.0, mass=1.0, end=0.1, **kw))
        w.step(100)
        return w.positions, w.velocities

    x, v = births(shape="box", center=(1, 2, 3), size=(0.2, 0.4, 0.6))  # v = 0: they stay where born
    assert np.all(np.abs(x - [1, 2, 3]) <= [0.1, 0.2, 0.3]) and np.all(np.ptp(x, axis=0) > [0.19, 0.38, 0.57])
    x, _ = births(shape="disc", center=(0, 0, 1), radius=0.5, normal=(0, 0, 1))
    assert np.allclose(x[:, 2], 1.0) and np.linalg.norm(x[:, :2], axis=1).max() <= 0.5
    # uniform over the area: half of the births within r/√2
    assert abs(np.mean(np.linalg.norm(x[:, :2], axis=1) < 0.5 / np.sqrt(2)) - 0.5) < 0.05
    x, _ = births(shape="sphere", center=(0, 0, 0), radius=2.0)
    np.testing.assert_allclose(np.linalg.norm(x, axis=1), 2.0, rtol=1e-12)
    assert abs(np.mean(x[:, 2] > 1.0) - 0.25) < 0.04  # Archimedes: a cap of height 1 of 4 holds a quarter
    x, v = births(dim=2, shape="sphere", center=(0, 0, 0), radius=1.0, speed=1.0)
    assert np.all(x[:, 2] == 0) and np.all(v[:, 2] == 0)
    # 2D sphere: born on the unit circle moving out along its normal, so radial and at
    # distance 1 + age (speed 1 m/s; ages from 0 to 0.1 s)
    speed_dir = v / np.linalg.norm(v, axis=1, keepdims=True)
    r = np.linalg.norm(x, axis=1)
    np.testing.assert_allclose(np.sum(speed_dir * x, axis=1), r, rtol=1e-12)
    assert r.min() >= 1.0 - 1e-12 and r.max() <= 1.1 + 1e-12


def test_velocities_fill_the_cone_and_the_speed_range():
    w = kinema.World(dt=1e-3)
    w.add(Emitter(rate=20000.0, end=0.1, direction=(1, 1, 0), speed=3.0, speed_spread=1.0, spread=20.0, mass=1.0))
    w.step(100)
    v = w.velocities
    speed = np.linalg.norm(v, axis=1)
    assert speed.min() >= 2.0 - 1e-12 and speed.max() <= 4.0 + 1e-12
    axis = np.array([1, 1, 0]) / np.sqrt(2)
    angle = np.degrees(np.arccos(np.clip(v @ axis / speed, -1, 1)))
    assert angle.max() <= 20.0 + 1e-9
    # uniform over the cap: P(θ < α) = (1 − cos α) / (1 − cos 20°)
    frac = np.mean(angle < 10.0)
    assert abs(frac - (1 - np.cos(np.radians(10))) / (1 - np.cos(np.radians(20)))) < 0.03


def test_particles_die_at_birth_plus_lifetime():
    dt, rate, life = 1e-3, 100.0, 0.25
    w = kinema.World(dt=dt)
    w.add(Emitter(rate=rate, speed=1.0, mass=1.0, lifetime=life))
    traj = w.run(1.0, fps=20)
    born = traj.ids / rate
    for f, t in enumerate(traj.t):
        # alive: born by the last step's start, and the first boundary >= birth + life not yet passed
        expect = (born <= t - dt + 1e-9) & (born + life > t + 1e-9)
        assert traj.alive[f].tolist() == expect.tolist(), t
    # at most the births in (t − life, t − dt]: rate × (life − dt), 24 of them
    assert traj.alive.sum(axis=1).max() == 24


def test_kill_volumes_remove_what_enters_them():
    w = kinema.World(dt=1e-3)
    w.add(kinema.Gravity())
    w.add(Emitter(rate=300.0, shape="disc", radius=0.2, center=(0, 0, 1), normal=(0, 0, 1), speed=1.0, mass=1.0, seed=2))
    w.add(KillPlane(point=(0, 0, 0), normal=(0, 0, 1)))
    w.add(KillSphere(center=(0.15, 0, 0.5), radius=0.1))
    w.add(KillBox(lo=(-1, -1, 0.8), hi=(-0.1, 1, 0.9)))
    traj = w.run(1.5, fps=100)
    x = traj.positions[traj.alive]
    assert np.all(x[:, 2] >= 0)
    assert np.all(np.linalg.norm(x - [0.15, 0, 0.5], axis=1) > 0.1)
    in_box = (x[:, 0] <= -0.1) & (x[:, 2] >= 0.8) & (x[:, 2] <= 0.9)
    assert not in_box.any()
    assert traj.alive.sum(axis=1)[-1] < traj.ids.size / 2  # most have fallen through the floor


def test_springs_die_with_an_end():
    # A chain hung from a pinned particle: 0 (pinned) – 1 – 2. Remove 1: both springs die, and
    # particle 2 (now index 1) falls freely, a = g exactly.
    w = kinema.World(dt=1e-3)
    w.add_particles([[0, 0, 0], [0, 0, -1], [0, 0, -2]], pinned=[True, False, False])
    w.add(kinema.Gravity())
    w.add(kinema.Spring([0, 1], [1, 2], k=100.0))
    w.step(10)
    w.remove_particles([1])
    assert w.ids.tolist() == [0, 2]
    np.testing.assert_array_equal(w.accelerations[1], [0, 0, -9.81])
    # a spring between survivors stays: re-add one between 0 and 2 and it pulls
    w.add(kinema.Spring(0, 1, k=100.0, rest_length=1.0))
    assert w.accelerations[1][2] > 0
    traj = w.run(0.1, fps=50)
    assert traj.springs.tolist() == [[0, 1], [1, 2], [0, 2]]  # by id, dead ones included (drawn while both ends live)


def test_remove_particles_checks_and_keeps_the_rest():
    w = kinema.World()
    w.add_particles(np.arange(12.0).reshape(4, 3), velocity=np.ones((4, 3)), mass=[1, 2, 3, 4], species=["a", "b", "c", "d"])
    with pytest.raises(ValueError, match=r"indices\[0\] = 7"):
        w.remove_particles([7])
    with pytest.raises(ValueError, match=r"bool mask of shape \(3,\)"):
        w.remove_particles(np.array([True, False, False]))
    w.remove_particles(np.array([False, True, False, True]))
    assert w.ids.tolist() == [0, 2] and w.masses.tolist() == [1, 3] and w.species.tolist() == ["a", "c"]
    np.testing.assert_array_equal(w.positions, [[0, 1, 2], [6, 7, 8]])
    w.add_particles([0, 0, 0])
    assert w.ids.tolist() == [0, 2, 4]


@pytest.mark.parametrize("model", ["impulse", "spring_dashpot"])
@pytest.mark.parametrize("method", ["verlet", "rk4", "implicit_euler"])
def test_every_model_and_method_steps_across_births_and_deaths(model, method):
    w = kinema.World(dt=5e-4, method=method)
    w.add(kinema.Gravity())
    w.add(kinema.Box([-0.3, -0.3, 0], [0.3, 0.3, np.inf]))
    extra = {"stiffness": 2e4} if model == "spring_dashpot" else {}
    w.set_collisions(model=model, restitution=0.5, **extra)
    w.add(Emitter(rate=400.0, shape="disc", radius=0.1, center=(0, 0, 0.5), normal=(0, 0, -1), speed=0.5, particle_radius=0.01, density=1000, lifetime=0.3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kinema.StabilityWarning)
        traj = w.run(0.6, fps=50)
    live = traj.positions[traj.alive]
    assert np.all(np.isfinite(live)) and traj.alive.sum(axis=1)[-1] == pytest.approx(120, abs=2)
    # nothing leaves the box through its floor or walls (radius 1 cm). Impulses leave no
    # overlap to speak of (1 mm allowed); soft contacts overlap by about v √(m/k) per impact,
    # 1.4 mm at 3 m/s for these 4 g droplets, more under a pile (3 mm allowed)
    # (implicit Euler's step softens stiff contacts further: R(z) → 0 as z → ∞; centres stay in)
    slack = 1e-3 if model == "impulse" else 3e-3 if method != "implicit_euler" else 1e-2
    assert live[:, 2].min() > 0.01 - slack and np.abs(live[:, :2]).max() < 0.3 - 0.01 + slack


def test_the_advisor_warns_about_newborn_contacts():
    # Contacts of k = 1e7 N/m between 1 g droplets: ω = √(k/m_eff) ≈ 1.4e5 rad/s, far beyond
    # what dt = 1e-3 s can follow. The world has no particle at first; the warning comes once
    # the emitter has given some.
    w = kinema.World(dt=1e-3)
    w.set_collisions(model="spring_dashpot", stiffness=1e7)
    w.add(Emitter(rate=100.0, mass=1e-3, particle_radius=0.01, speed=5.0))  # 5 cm apart: no contact yet
    with pytest.warns(kinema.StabilityWarning, match="exceeds the stable-step advisor's limit"):
        w.run(0.1, fps=30)


def test_the_same_particles_for_any_thread_count():
    code = textwrap.dedent(
        """
        import hashlib, kinema
        w = kinema.load_scene(r"%s")
        traj = w.run(0.5, fps=30)
        print(hashlib.sha256(traj.positions.tobytes() + traj.velocities.tobytes() + traj.alive.tobytes()).hexdigest())
        """
        % (SCENES / "fountain.toml")
    )
    out = {}
    for threads in (1, 2):
        env = {**os.environ, "RAYON_NUM_THREADS": str(threads)}
        res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
        assert res.returncode == 0, res.stderr
        out[threads] = res.stdout.strip()
    assert out[1] == out[2]
    again = kinema.load_scene(SCENES / "fountain.toml").run(0.5, fps=30)
    assert hashlib.sha256(again.positions.tobytes() + again.velocities.tobytes() + again.alive.tobytes()).hexdigest() == out[1]


def test_the_fountain_scene_keeps_its_promises():
    # examples/scenes/fountain.toml: 250 droplets/s for 5 s, each dying 3 ± 0.3 s after birth,
    # bouncing on the floor at z = 0.
    w = kinema.load_scene(SCENES / "fountain.toml")
    traj = w.run(w.scene.world.duration, fps=w.scene.world.fps)
    assert traj.ids.size == 1250
    born = traj.ids / 250.0
    first, last = traj.alive.argmax(axis=0), traj.alive.shape[0] - 1 - traj.alive[::-1].argmax(axis=0)
    died = last < traj.alive.shape[0] - 1
    age_at_last = traj.t[last] - born
    assert np.all(age_at_last[died] <= 3.3 + 1e-9)  # never alive past its lifetime
    assert np.all(traj.t[np.minimum(last + 1, len(traj.t) - 1)][died] - born[died] >= 2.7 - 1e-9)
    live = traj.positions[traj.alive]
    radius = np.broadcast_to(traj.radii, traj.alive.shape)[traj.alive]
    assert live[:, 2].min() > 0.5 * radius.min()  # on the floor, not through it
    assert traj.species is not None and set(traj.species) == {"water"}
    np.testing.assert_allclose(traj.colors[0], [0x2F / 255, 0x7F / 255, 0xD8 / 255])
    assert first.min() >= 1


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"rate": 0}, "rate = 0.0 is invalid"),
        ({"rate": 10, "shape": "cone"}, "shape = 'cone' is invalid"),
        ({"rate": 10, "spread": 200}, "spread = 200.0 is invalid"),
        ({"rate": 10, "mass": 1, "lifetime": 1, "lifetime_spread": 1}, "lifetime_spread = 1.0 is invalid"),
        ({"rate": 10}, "mass = None is invalid for particles of radius 0"),
        ({"rate": 10, "mass": 1, "color": "blue"}, "color = 'blue' is invalid"),
        ({"rate": 10, "mass": 1, "start": 2, "end": 1}, "end > start"),
        ({"rate": 10, "mass": 1, "direction": (0, 0, 0)}, "direction = .* non-zero"),
    ],
)
def test_bad_emitters_are_refused_by_name(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Emitter(**kwargs)


def test_scene_emitters_are_checked_and_written_back(tmp_path):
    text = (SCENES / "fountain.toml").read_text().replace("spread = 12 ", "spread = 240 ")
    with pytest.raises(kinema.SceneError, match=r"emitters\.0\.spread|emitters\[0\].*spread"):
        kinema.scene.Scene.from_string(text, "f.toml")
    w = kinema.load_scene(SCENES / "fountain.toml")
    again = kinema.load_scene(w.to_scene().to_toml(tmp_path / "f.toml"))
    a = w.run(0.3, fps=30)
    b = again.run(0.3, fps=30)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.alive, b.alive)


def test_a_run_with_births_and_deaths_goes_through_the_files(tmp_path):
    # End to end: a world with an emitter and lifetimes, saved to H5MD and read back by kinema,
    # and written as GSD read by the gsd package: each frame holds exactly its live particles.
    import gsd.hoomd

    w = kinema.World(dt=1e-3)
    w.add(kinema.Gravity())
    w.add(Emitter(rate=100.0, speed=2.0, spread=20, particle_radius=0.01, lifetime=0.2, species="drop", seed=5))
    traj = w.run(0.5, fps=20)
    assert traj.changes_count
    back = kinema.load_trajectory(traj.save(tmp_path / "t.h5"))
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.ids, traj.ids)
    np.testing.assert_array_equal(back.positions[back.alive], traj.positions[traj.alive])
    (path,) = traj.export(tmp_path / "t.gsd")
    with gsd.hoomd.open(path) as frames:
        assert [f.particles.N for f in frames] == traj.alive.sum(axis=1).tolist()
        k = 6
        assert frames[k].log["particles/kinema/id"].tolist() == traj.frame(k)["ids"].tolist()
        x = frames[k].particles.position + frames[k].log["kinema/origin"]  # GSD's box is centred at 0
        np.testing.assert_allclose(x, traj.frame(k)["positions"], atol=1e-6)


def test_a_python_force_sees_the_particles_alive_now():
    # F(t, x, v) = −k x on every live particle: its arrays grow with the births and shrink with
    # the deaths, and each particle moves as a harmonic oscillator from its birth (closed form
    # checked loosely: it stays within its amplitude).
    seen = []

    def pull(t, x, v):
        seen.append(len(x))
        return -4.0 * x

    w = kinema.World(dt=1e-3, method="rk4")
    w.add(kinema.PythonForce(pull))
    w.add(Emitter(rate=50.0, shape="sphere", radius=0.5, mass=1.0, lifetime=0.2))
    traj = w.run(0.5, fps=50)
    # rate × lifetime = 10 at once, 11 where a birth and a death fall on the same step boundary
    # (the death at t_k + 0.2 is due there up to the rounding of the summed time)
    assert max(seen) in (10, 11) and min(seen) >= 1
    x = traj.positions[traj.alive]
    assert np.linalg.norm(x, axis=1).max() <= 0.5 + 1e-9  # |x| <= the amplitude 0.5 m (at rest at birth)


def test_each_particle_is_drawn_in_its_own_colour():
    # color_by="color": an emitter's colour is the particle's; one without a colour keeps the
    # renderer's NO_OWN_COLOR. 2D discs are flat: their pixels are exactly the colour.
    from kinema.render import NO_OWN_COLOR, own_colours

    w = kinema.World(dim=2, dt=1e-3)
    w.add(Emitter(rate=20.0, shape="sphere", radius=0.5, mass=1.0, particle_radius=0.05, color="#ff2000", end=0.2))
    w.add_particles([0.0, 0.0, 0.0], radius=0.05)
    traj = w.run(0.3, fps=10)
    rgb = own_colours(traj)
    assert {tuple(c) for c in rgb} == {(255, 32, 0), NO_OWN_COLOR}
    (frame,) = kinema.render_frames(traj.positions[-1:], traj.radii, traj.t[-1:], dim=2, color_by=rgb, width=200, height=200, legend=False)
    pixels = {tuple(p) for p in np.asarray(frame).reshape(-1, 3)}
    assert (255, 32, 0) in pixels and NO_OWN_COLOR in pixels


def test_an_emitter_never_places_a_particle_inside_another():
    # A point emitter (every particle born at one point) at 200 a second until 0.8 s, 1 cm
    # balls leaving at 0.5 m/s: each needs 40 ms to clear the point for the next, so most
    # births must wait, and those still waiting at end are dropped (issue 48: never a birth
    # after end): 20 born (at 0, 40, ..., 760 ms), 140 dropped. No two particles ever overlap
    # by more than the contact solver's slop at a step's end (0.2 % of r, docs/collisions.md),
    # the particles born come in order, with what they were drawn with, none before its time
    # start + k/rate nor after end.
    w = kinema.World(dt=1e-3)
    w.add(kinema.Emitter(shape="point", center=[0, 0, 0], rate=200, end=0.8, speed=0.5, direction=[1, 0, 0], particle_radius=0.01, seed=4))
    w.set_collisions(restitution=0.5)
    with pytest.warns(kinema.EmitterWarning, match=r"emitter 0: 20 of 160 particles born by t = 0\.8 s \(25/s of the 200/s asked\)"):
        for step in range(1000):
            w.step()
            if step == 599:
                assert 14 <= len(w) <= 16
            x = w.positions
            if len(x) > 1:
                d = np.linalg.norm(x[:, None] - x[None], axis=2) + np.eye(len(x))
                assert d.min() >= 0.02 * (1 - 1e-3), (w.time, d.min())
    assert len(w) == 20 and (np.diff(w.ids) > 0).all()
    assert w.emitter_stats()[0]["dropped"] == 140
    # the k-th particle's speed is what it was drawn with: 0.5 m/s along x (nothing touches
    # them once they leave in a row)
    np.testing.assert_allclose(w.velocities[:, 0], 0.5, rtol=1e-12)


def _fountain(seed=9):
    """Sparse births (10 per second at dt = 1 ms: one every 100 steps), lifetimes, a kill box
    and a kill plane: a world whose count changes by births and by both kinds of death."""
    w = kinema.World(dt=1e-3)
    w.add(kinema.Gravity())
    w.add(Emitter(rate=10.0, speed=2.0, spread=30.0, mass=1.0, lifetime=0.35, lifetime_spread=0.1, seed=seed))
    w.add(KillBox([0.05, -1.0, -1.0], [1.0, 1.0, 1.0]))
    w.add(KillPlane([0.0, 0.0, -0.05], [0.0, 0.0, 1.0]))
    return w


def test_deaths_in_the_engine_and_batched_births_are_the_same_as_one_step_at_a_time():
    # The engine carries out deaths after each step and the Python world runs the steps
    # between births in one call: the same particles must live and die at the same step
    # boundaries, to the bit, as when every step is its own call.
    whole, single = _fountain(), _fountain()
    whole.step(1500)
    for _ in range(1500):
        single.step(1)
    assert whole.time == single.time
    assert whole.ids.tolist() == single.ids.tolist()
    np.testing.assert_array_equal(whole.positions, single.positions)
    np.testing.assert_array_equal(whole.velocities, single.velocities)
    # and both kinds of death happened: ids below the last one are gone
    assert 0 < len(whole) < 15 and whole.ids.min() > 0


def test_the_steps_between_births_run_in_one_engine_call(monkeypatch):
    # 10 births a second at dt = 1 ms: between two births the engine takes ~100 steps in one
    # call (the emitter's own due() decides the boundary), not one call a step.
    w = _fountain()
    calls = []
    monkeypatch.setattr(w, "_core", _Counting(w._core, calls))
    w.step(1000)
    assert w._core.steps == 1000
    assert len(calls) <= 12, f"{len(calls)} engine calls for 1000 steps with 10 births"
    assert sum(calls) == 1000


class _Counting:
    """The engine, with each step(n) call's n noted."""

    def __init__(self, core, calls):
        self._core, self._calls = core, calls

    def step(self, n):
        self._calls.append(n)
        return self._core.step(n)

    def __getattr__(self, name):
        return getattr(self._core, name)


def test_the_engine_refuses_bad_deaths_with_the_parameter_named():
    w = kinema.World(dt=1e-3)
    w.add_particles([[0.0, 0.0, 0.0]], mass=1.0)
    with pytest.raises(ValueError, match=r"time_of_death.*one per particle"):
        w._core.set_deaths(np.array([1.0, 2.0]), [])
    with pytest.raises(ValueError, match=r"time_of_death\[0\]"):
        w._core.set_deaths(np.array([np.nan]), [])
    with pytest.raises(ValueError, match=r"radius"):
        w._core.set_deaths(None, [("sphere", [0.0, 0.0, 0.0], -1.0)])
    with pytest.raises(ValueError, match=r"unknown"):
        w._core.set_deaths(None, [("cone", [0.0, 0.0, 0.0], 1.0)])


def test_the_work_limit_of_run_counts_what_the_emitters_will_add():
    # An empty world with an emitter: the work of a run is the births over it, each counted
    # from the start as the command line counts a scene's (10,001 births × 100 steps = 1e6
    # particle-steps at most). Before, World.run counted the particles now (none) and ran
    # whatever the emitters made, until memory ran out for a fast one.
    w = kinema.World(dt=1e-2)
    w.add(Emitter(rate=1e4, center=(0, 0, 0), speed=1.0, mass=1.0, seed=1))
    with pytest.raises(ValueError, match=r"1\.0e\+06 particle-steps \(0 particles and up to 10,001 from the emitters × 100 steps.*over max_work = 1\.0e\+05"):
        w.run(1.0, fps=100, max_work=1e5)
    assert len(w) == 0 and w.time == 0.0  # refused before any step
    # within the limit it runs, and its births are at most those counted (501 by t = 0.05 s)
    traj = w.run(0.05, fps=100, max_work=1e6)
    assert 0 < len(w) <= 501 and len(traj.t) == 6


# -- emitters that keep their word (issue 48) ---------------------------------------------------

CROWDED = """
[world]
dim = 3
dt = 0.001
duration = 2.5
fps = 50

[[emitters]]
shape = "box"
center = [0.25, 0.25, 0.25]
size = [0.3, 0.3, 0.3]
rate = 200
end = 1.5
particle_radius = 0.05
mass = 1.0
seed = 1

[[colliders]]
type = "box"
lo = [0, 0, 0]
hi = [0.5, 0.5, 0.5]

[output]
plot = false
video = false
"""


def test_an_emitter_that_finds_no_room_never_gives_a_birth_after_end_and_says_so():
    # 10 cm balls asked at 200/s into a 30 cm box inside a closed 50 cm box, no gravity, at
    # rest: it fills within a few dozen and no ball ever moves out of the way. Births due
    # (t_k = k/200 < 1.5 s: 300) that find no room wait; at end they are dropped, so not one
    # is born after end (before, the backlog was born whenever room came, past end).
    w = kinema.Scene.from_string(CROWDED).build()
    born_at: dict[int, float] = {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(2500):
            before = w.time
            w.step()
            for i in w.ids.tolist():
                born_at.setdefault(i, before)  # added at the step boundary before this step
    assert max(born_at.values()) < 1.5  # the last due, t_299 = 1.495 s, joins at its boundary
    st = w.emitter_stats()[0]
    assert st["due"] == 300 and st["born"] == len(w) == len(born_at) and st["waiting"] == 0
    assert st["born"] + st["dropped"] == 300 and 0 < st["born"] < 100
    assert st["achieved_rate"] == st["born"] / 1.5
    told = [c for c in caught if issubclass(c.category, kinema.EmitterWarning)]
    assert len(told) == 1  # once per emitter, not once a step
    assert str(told[0].message).startswith(
        f"emitter 0: {st['born']} of 300 particles born by t = 1.5 s ({st['born'] / 1.5:.4g}/s of the 200/s asked): no room at the source; "
        f"{300 - st['born']} found none before end = 1.5 s and were dropped"
    )


def test_a_run_still_behind_at_its_end_says_so_once(tmp_path):
    w = kinema.Scene.from_string(CROWDED.replace("end = 1.5", "end = inf")).build()
    with pytest.warns(
        kinema.EmitterWarning, match=r"emitter 0: \d+ of 201 particles born by t = 1 s .*of the 200/s asked\): no room at the source; \d+ wait"
    ) as told:
        w.run(1.0, fps=50)
    assert len([c for c in told if issubclass(c.category, kinema.EmitterWarning)]) == 1
    # an emitter that keeps up says nothing
    calm = kinema.World(dt=1e-3)
    calm.add(Emitter(rate=100.0, speed=1.0, particle_radius=0.001, mass=1.0, end=0.5))
    with warnings.catch_warnings():
        warnings.simplefilter("error", kinema.EmitterWarning)
        calm.run(1.0, fps=50)
    assert calm.emitter_stats()[0] == {"rate": 100.0, "start": 0.0, "until": 0.5, "due": 50, "born": 50, "waiting": 0, "dropped": 0, "achieved_rate": 100.0}


def test_the_run_summary_gives_each_emitters_achieved_rate(tmp_path):
    from typer.testing import CliRunner

    from kinema.cli import app

    (tmp_path / "crowded.toml").write_text(CROWDED)
    res = CliRunner().invoke(app, ["run", str(tmp_path / "crowded.toml"), "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    traj = kinema.load_trajectory(tmp_path / "out" / "trajectory.h5")
    born = traj.ids.size  # every particle ever alive: the births counted
    assert born == traj.alive[-1].sum() and born == traj.alive[int(1.52 * 50)].sum()  # none after end
    text = " ".join(res.output.split())
    assert (
        f"emitter 0: {born:,} of 300 particles born from t = 0 to 1.5 s, {born / 1.5:.4g}/s of the 200/s asked ({300 - born:,} dropped for lack of room)"
        in text
    )
    assert f"warning: emitter 0: {born} of 300 particles born by t = 1.5 s" in text
