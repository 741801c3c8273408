"""Collision groups (docs/collisions.md, "Collision groups"): per-particle groups, the
symmetric matrix of which groups collide, colliders' ``collides_with`` and
``set_collisions(self_collisions=False)``, in every contact path, in scenes, checkpoints and
emitters."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import kinema

SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"
R = 0.1

MODELS = {
    "impulse": ({}, 1e-3, 1000),
    "hertz": ({"model": "hertz", "youngs_modulus": 1e7}, 1e-4, 10_000),
    "events": ({"event_driven": True}, 1e-2, 100),
}


def _pair(settings: dict, dt: float, which: tuple[int, ...], collide: bool) -> kinema.World:
    """Balls of groups 0 (from x = -1, moving +x) and 1 (from x = +1, moving -x) over a floor,
    which cross at x = 0 after a bounce."""
    w = kinema.World(dt=dt)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(**settings)
    w.set_group_collisions(0, 1, collide)
    balls = [([-1.0, 0.0, 0.35], [2.0, 0.0, 0.0]), ([1.0, 0.0, 0.35], [-2.0, 0.0, 0.0])]
    for k in which:
        w.add_particles(balls[k][0], velocity=balls[k][1], radius=R, group=k)
    return w


@pytest.mark.parametrize("name", list(MODELS))
def test_groups_that_do_not_collide_cross_as_if_alone(name):
    settings, dt, steps = MODELS[name]
    w = _pair(settings, dt, (0, 1), collide=False)
    w.step(steps)
    for k in (0, 1):
        alone = _pair(settings, dt, (k,), collide=False)
        alone.step(steps)
        # to the bit: the other ball changed nothing, through the crossing and the bounces
        assert np.array_equal(w.positions[k], alone.positions[0]) and np.array_equal(w.velocities[k], alone.velocities[0])
    assert w.positions[0, 0] > 0.5 and w.positions[1, 0] < -0.5  # they crossed
    assert w.collision_stats()["total"]["impacts"] + w.collision_stats()["total"]["contacts"] > 0  # and met the floor
    colliding = _pair(settings, dt, (0, 1), collide=True)
    colliding.step(steps)
    assert colliding.positions[0, 0] < 0 < colliding.positions[1, 0]  # the same balls bounce off each other


@pytest.mark.parametrize("model", [{}, {"model": "spring_dashpot", "stiffness": 1e5}])
def test_moving_particles_to_another_group_forgets_the_contact_lists(model):
    # a ball resting on another: put into groups that do not collide, the top one falls through
    w = kinema.World(dt=1e-4)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(restitution=0.0, **model)
    w.add_particles([[0, 0, R], [0, 0, 3 * R]], radius=R)
    w.set_group_collisions(1, 0, False)
    w.step(2000)
    assert w.positions[1, 2] > 2.5 * R  # held up by the lower ball
    w.groups = [0, 1]
    w.step(3000)
    assert w.positions[1, 2] < 1.5 * R  # fell through it onto the floor
    assert np.array_equal(w.groups, [0, 1])


def test_the_fountain_keeps_its_jet():
    # examples/scenes/fountain.toml has self_collisions = false: no pair of droplets ever
    # touches, the floor still holds them, and no droplet in flight leaves the nozzle's cone
    # (|v_horizontal| <= 4.3 m/s * sin 12 deg = 0.894 m/s). With self collisions the rising and
    # falling droplets meet and spray out of it.
    text = (SCENES / "fountain.toml").read_text()
    assert "self_collisions = false" in text
    spread = {}
    for on in (False, True):
        w = kinema.scene.Scene.from_string(text.replace("self_collisions = false", f"self_collisions = {str(on).lower()}"), "fountain.toml").build()
        pairs = []
        traj = w.run(1.5, fps=30, callback=lambda w, pairs=pairs: pairs.append(int((w.contacts()["j"] >= 0).sum())))
        fastest = 0.0
        for k in range(len(traj.t)):
            x, v = traj.positions[k][traj.alive[k]], traj.velocities[k][traj.alive[k]]
            flying = x[:, 2] > 0.05
            fastest = max(fastest, float(np.hypot(v[flying, 0], v[flying, 1]).max(initial=0.0)))
        spread[on] = fastest
        assert traj.positions[traj.alive][:, 2].min() > 0.5 * 0.008  # on the floor, not through it
        if not on:
            assert sum(pairs) == 0 and w.collisions["self_collisions"] is False
            assert w.collision_stats()["total"]["impacts"] > 0  # the floor's
    assert spread[False] <= 4.3 * np.sin(np.radians(12)) < spread[True]


def test_a_dense_jet_without_self_collisions_passes_through_itself_and_lands():
    w = kinema.World(dt=1e-3)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(self_collisions=False, restitution=0.3)
    # births overlapping each other are not held back: the group does not collide with itself
    w.add(kinema.Emitter(rate=2000, speed=3.0, particle_radius=0.02, mass=0.01, end=0.2, center=(0, 0, 0.5)))
    w.step(1500)
    assert len(w) == 400  # none waited for its place
    stats = w.collision_stats()
    assert (w.contacts()["j"] < 0).all() and w.positions[:, 2].min() > 0.01
    assert stats["total"]["impacts"] > 0


def test_a_colliders_mask_lets_one_group_through():
    w = kinema.World(dt=1e-2)
    w.add(kinema.Gravity())
    floor = w.add(kinema.Plane([0, 0, 0], [0, 0, 1], collides_with=[0]))
    assert floor.collides_with == (0,) and kinema.Plane([0, 0, 0], [0, 0, 1]).collides_with is None
    w.add_particles([[-1, 0, 0.5], [1, 0, 0.5]], radius=R, group=[0, 1])
    w.step(100)
    assert w.positions[0, 2] > 0 and w.positions[1, 2] < -1
    # a particle behind a collider that lets its group through is no bad placement
    w.add_particles([0, 0, -0.5], radius=R, group=1)
    w.step(1)


def test_the_matrix_is_symmetric_and_checked():
    w = kinema.World()
    m = w.collision_matrix
    assert m.shape == (32, 32) and m.all()
    w.set_group_collisions([1, 2], 5, False)
    m = w.collision_matrix
    assert not m[1, 5] and not m[5, 1] and not m[2, 5] and not m[5, 2] and m[5, 5] and (m == m.T).all()
    m[3, 4] = False
    with pytest.raises(ValueError, match=r"collision_matrix\[3\]\[4\] = False is invalid: the matrix must be symmetric"):
        w.collision_matrix = m
    m[4, 3] = False
    w.collision_matrix = m
    assert not w.collision_matrix[4, 3]
    with pytest.raises(ValueError, match=r"shape \(3, 3\)"):
        w.collision_matrix = np.ones((3, 3), bool)


@pytest.mark.parametrize(
    "call, error, message",
    [
        (lambda w: w.add_particles([0, 0, 1], group=32), ValueError, r"group = 32 is invalid: a collision group is an integer in 0\.\.31"),
        (lambda w: w.add_particles([[0, 0, 1], [1, 0, 1]], group=[0, -1]), ValueError, r"group\[1\] = -1 is invalid"),
        (lambda w: w.add_particles([[0, 0, 1], [1, 0, 1]], group=[0, 1, 2]), ValueError, r"group has shape \(3,\); it must be .* one per particle, \(2,\)"),
        (lambda w: w.add_particles([0, 0, 1], group=1.0), TypeError, r"group = 1\.0 is invalid: .* not a float"),
        (lambda w: setattr(w, "groups", [0, 1]), ValueError, r"groups has shape \(2,\)"),
        (lambda w: w.set_group_collisions(0, 40, False), ValueError, r"b = 40 is invalid"),
        (lambda w: kinema.Plane([0, 0, 0], [0, 0, 1], collides_with=[0, 33]), ValueError, r"collides_with\[1\] = 33 is invalid"),
        (lambda w: kinema.Emitter(rate=1, mass=1, group=32), ValueError, r"group = 32 is invalid"),
    ],
)
def test_bad_groups_are_refused_by_name(call, error, message):
    w = kinema.World()
    w.add_particles([0, 0, 0])
    with pytest.raises(error, match=message):
        call(w)
    assert len(w) == 1  # nothing added


def _grouped_world() -> kinema.World:
    w = kinema.World(dt=1e-3)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], collides_with=[0, 1]))
    w.set_collisions(restitution=0.5)
    w.set_group_collisions(0, 1, False)
    rng = np.random.default_rng(3)
    grid = np.stack(np.meshgrid(np.arange(4), np.arange(5), np.arange(3), indexing="ij"), axis=-1).reshape(-1, 3)
    x = grid * 0.1 + [-0.15, -0.2, 0.1] + rng.uniform(-0.005, 0.005, (60, 3))
    w.add_particles(x, velocity=rng.normal(0, 0.3, (60, 3)), radius=0.04, group=rng.integers(0, 3, 60))
    w.add(kinema.Emitter(rate=50, speed=1.0, particle_radius=0.03, mass=0.1, center=(0, 0, 1.2), group=2, seed=4))
    return w


def test_a_checkpoint_goes_on_bit_for_bit(tmp_path):
    w = _grouped_world()
    w.step(300)
    path = w.save_checkpoint(tmp_path / "g.ckpt")
    back = kinema.World.load_checkpoint(path)
    assert np.array_equal(back.groups, w.groups) and (back.collision_matrix == w.collision_matrix).all()
    assert back.colliders[0].collides_with == (0, 1) and back.collisions == w.collisions
    w.step(400)
    back.step(400)
    assert np.array_equal(back.positions, w.positions) and np.array_equal(back.velocities, w.velocities)
    assert np.array_equal(back.groups, w.groups) and (w.groups[60:] == 2).all() and len(w) > 60


def test_a_scene_round_trips(tmp_path):
    w = _grouped_world()
    w.set_collisions(**{**w.collisions, "self_collisions": False})
    w.set_group_collisions(0, 1, False)
    scene = w.to_scene()
    text = scene.to_toml_string()
    assert "ignore_groups = [" in text and "collides_with = [" in text and "self_collisions = false" in text
    again = kinema.scene.Scene.from_string(text, "g.toml").build()
    assert np.array_equal(again.groups, w.groups) and (again.collision_matrix == w.collision_matrix).all()
    assert again.collisions == w.collisions and again.colliders[0].collides_with == (0, 1)
    assert again._emitters[0].c["group"] == 2
