"""What the world refuses before it works, each found by an outside fuzz run (issue 26):
particles placed inside each other or inside a collider (both contact models, one
``ValueError``); a run over its work limit; booleans returned as forces or derivatives; writes
into the world from inside one of its forces. Each is refused with one line and the world is
left as it was."""

from __future__ import annotations

import numpy as np
import pytest

import kinema

MODELS = [{"model": "impulse"}, {"model": "spring_dashpot", "stiffness": 1e4}]


def world(**collisions) -> kinema.World:
    w = kinema.World(dim=3, dt=1e-3)
    w.set_collisions(**collisions)
    return w


# -- placements the contacts cannot resolve (crates/kinema/src/collide/placement.rs) -------------
@pytest.mark.parametrize("collisions", MODELS, ids=lambda c: c["model"])
def test_coincident_particles_are_one_value_error_naming_the_count_and_the_deepest_pair(collisions):
    # 3,000 at one point: 4.5 million pairs (one step took 102 s and threw them 4.8 m apart;
    # 30,000 aborted the process for memory). The count stops at 100,000.
    w = world(**collisions)
    w.add_particles(position=np.zeros((3000, 3)), radius=0.1)
    with pytest.raises(ValueError) as e:
        w.step()
    text = str(e.value)
    assert "\n" not in text
    assert text.startswith("positions: particles 0 and 1 are 0 m apart (radii 0.1 and 0.1 m), the deepest of at least 100000 placements"), text
    assert w.time == 0.0 and np.all(w.positions == 0.0)


@pytest.mark.parametrize("collisions", MODELS, ids=lambda c: c["model"])
def test_a_particle_inside_a_sphere_obstacle_is_refused_where_it_jumped_20_m(collisions):
    w = world(**collisions)
    w.add_particles(position=[[0.0, 0.0, 1.0]], radius=0.1)
    w.add(kinema.SphereObstacle(center=[0, 0, 0], radius=100.0))
    with pytest.raises(ValueError, match=r"particle 0's centre lies inside colliders\[0\] \(1 m from its centre, radius 100 m\)"):
        w.step()
    assert w.positions[0, 2] == 1.0


def test_overlaps_short_of_a_centre_inside_step_and_the_cli_refuses_a_deep_one(tmp_path):
    # Half a radius of overlap (r = 0.1, 0.15 apart) is pushed apart as ever (0.194 m apart
    # after 10 steps).
    w = world()
    w.add_particles(position=[[0, 0, 0], [0.15, 0, 0]], radius=0.1)
    w.step(10)
    assert np.linalg.norm(w.positions[1] - w.positions[0]) > 0.19
    # A scene of particles at one point: exit 2, one line.
    from typer.testing import CliRunner

    from kinema.cli import app

    scene = tmp_path / "pile.toml"
    scene.write_text(
        "[world]\ndim = 3\ndt = 0.001\nduration = 0.1\n[collisions]\nrestitution = 0.5\n"
        '[[particles]]\ntype = "list"\npositions = [[0, 0, 0], [0, 0, 0], [0, 0, 0]]\nradius = 0.1\n'
    )
    result = CliRunner().invoke(app, ["run", str(scene), "--out", str(tmp_path / "out"), "--no-video"])
    assert result.exit_code == 2, result.output
    assert "particles 0 and 1 are 0 m apart" in result.output


# -- speeds no step can follow ----------------------------------------------------------------
def test_a_speed_that_crosses_the_box_thousands_of_times_a_step_is_a_divergence_at_once():
    # 1,000 particles at 2.3e16 m/s in a 10 m box: each would cross it 2.3e12 times a step;
    # 20 steps took 103 s, bouncing to the cap of continuous detection in each.
    rng = np.random.default_rng(0)
    w = world(restitution=0.9)
    w.add(kinema.Box(lo=[0, 0, 0], hi=[10, 10, 10]))
    w.add_particles(position=rng.uniform(0.5, 9.5, (1000, 3)), velocity=rng.normal(0, 2.3e16, (1000, 3)), radius=0.01)
    with pytest.raises(kinema.SimulationDiverged, match=r"at step 1 .*: a particle would travel .* over 1000 times the scene's extent") as e:
        w.step(20)
    assert e.value.reason == "too fast"
    assert w.time == 0.0
    # 1,000 box widths a step is the edge: 100 m/s in the same box at dt = 1 ms steps
    w = world(restitution=0.9)
    w.add(kinema.Box(lo=[0, 0, 0], hi=[10, 10, 10]))
    w.add_particles(position=rng.uniform(0.5, 9.5, (100, 3)), velocity=rng.normal(0, 100.0, (100, 3)), radius=0.01)
    w.step(20)


# -- World.run's work limit -------------------------------------------------------------------
def test_run_over_its_work_limit_is_refused_before_any_step_and_max_work_lifts_it():
    w = kinema.World(dim=3, dt=1e-3)
    w.add_particles(position=np.arange(30.0).reshape(10, 3))
    with pytest.raises(
        ValueError,
        match=r"1\.0e\+13 particle-steps \(10 particles × 1,020,000,000,000 steps of dt = 0\.001 s for duration = 1e\+09 s\), over max_work = 1\.0e\+11",
    ):
        w.run(1e9)
    assert w.time == 0.0
    with pytest.raises(ValueError, match="over max_work = 5.0e"):
        w.run(1.0, max_work=5e3)  # 10 × 1,020 steps
    assert len(w.run(1.0, max_work=1.02e4).t) == 61  # 60 frames of 17 steps after the first: 10,200 particle-steps
    assert len(w.run(0.1, max_work=None).t) == 7
    with pytest.raises(ValueError, match="max_work = -1 is invalid"):
        w.run(0.1, max_work=-1)
    with pytest.raises(TypeError, match="max_work = True is invalid"):
        w.run(0.1, max_work=True)


# -- booleans are not numbers -----------------------------------------------------------------
def test_a_force_returning_booleans_is_a_type_error_and_moves_nothing():
    w = kinema.World(dim=3, dt=1e-3)
    w.add_particles(position=[[0.0, 0.0, 0.0]])
    w.add(kinema.PythonForce(lambda t, x, v: np.ones_like(x, dtype=bool)))
    with pytest.raises(TypeError, match="it returned booleans"):
        w.step()
    assert np.all(w.positions == 0.0) and w.time == 0.0


def test_solve_with_a_boolean_right_hand_side_is_a_type_error():
    with pytest.raises(TypeError, match="it returned booleans"):
        kinema.solve(lambda t, y: np.ones(1, dtype=bool), [1.0], (0.0, 1.0), method="rk4", h=0.1)


# -- a force leaves its world alone -----------------------------------------------------------
@pytest.mark.parametrize("held", [True, False])
@pytest.mark.parametrize("entry", ["step", "rates", "accelerations"])
def test_a_write_from_inside_a_force_is_refused_and_nothing_is_kept(entry, held):
    # world.md: writing w.positions from a force raises RuntimeError. An item write into the
    # live view raised nothing: it was dropped after `step` and kept after `rates`. Into a
    # view held from before, numpy's read-only ValueError; where no view existed (nobody
    # looked: the world keeps none), making one meets the engine at work: RuntimeError.
    w = kinema.World(dim=3, dt=1e-3)
    w.add_particles(position=[[1.0, 2.0, 3.0]])
    before = w.positions if held else None
    seen = []

    def force(t, x, v):
        for write in (lambda: setattr(w, "positions", [[9.0, 9.0, 9.0]]), lambda: w.positions.__setitem__(0, 9.0)):
            try:
                write()
                seen.append("written")
            except (RuntimeError, ValueError) as e:
                seen.append(type(e).__name__)
        return np.zeros_like(x)

    w.add(kinema.PythonForce(force))
    getattr(w, entry)() if entry != "accelerations" else w.accelerations
    assert seen[:2] == ["RuntimeError", "ValueError" if held else "RuntimeError"], seen  # (ValueError: numpy's "read-only")
    assert w.positions.tolist() == [[1.0, 2.0, 3.0]]
    assert before is None or before.tolist() == [[1.0, 2.0, 3.0]]
    w.positions[0] = 5.0  # writable again after
    assert w.positions[0, 0] == 5.0


# -- one mistake, one line --------------------------------------------------------------------
def test_a_wrong_table_is_one_line_naming_its_unknown_and_missing_keys():
    # `radius = {a = 1}` gave three lines (min missing, max missing, a unknown).
    from kinema.scene import Scene, SceneError

    text = '[world]\ndim = 3\ndt = 0.001\n[[particles]]\ntype = "list"\npositions = [[0, 0, 0]]\nradius = {a = 1}\n'
    with pytest.raises(SceneError) as e:
        Scene.from_string(text, "r.toml")
    assert str(e.value) == "r.toml: particles[0].radius: unknown key a; missing min, max (allowed keys here: max, min)"


# -- one bad input, one exception type under both contact models --------------------------------
@pytest.mark.parametrize("collisions", MODELS, ids=lambda c: c["model"])
def test_particles_too_large_for_their_box_are_a_value_error_under_both_models(collisions):
    # Spring–dashpot contacts are a force, whose errors went through the callback's path:
    # a RuntimeError there (the CLI's "unexpected", exit 1), a ValueError with impulses.
    w = world(**collisions)
    w.add(kinema.Box(lo=[0, 0, 0], hi=[1, 1, 1]))
    w.add_particles(position=np.random.default_rng(1).uniform(0, 1, (300, 3)), radius=0.2)
    with pytest.raises(ValueError) as e:
        w.step(2)
    assert not isinstance(e.value, RuntimeError), repr(e.value)


# -- emitters (found by make fuzz at 2,000 cases a test) ----------------------------------------
def test_an_emitters_extreme_values_are_refused_or_bounded():
    # a normal of [1e300, 0, -1]: |n|² overflowed and the births were NaN
    w = kinema.World(dt=1e-3)
    w.add(kinema.Emitter(shape="disc", radius=0.1, normal=[1e300, 0, -1], rate=1000, particle_radius=0.01))
    w.step(5)
    assert len(w) == 5 and np.all(np.isfinite(w.positions))
    # masses from the density must be finite and > 0
    with pytest.raises(ValueError, match=r"density = 1e\+300 is invalid: .* masses must be finite and > 0 kg"):
        kinema.Emitter(rate=10, particle_radius=1e3, density=1e300)
    with pytest.raises(ValueError, match="the emitter reaches .* at most 1e\\+150 m"):
        kinema.Emitter(rate=10, center=[1e300, 0, 0], particle_radius=0.01)
    # rate = 1e300: numpy was asked for 1e297 births (a ValueError, then an OverflowError)
    w = kinema.World(dt=1e-3)
    w.add(kinema.Emitter(rate=1e300, start=-1e10, particle_radius=0.01))
    with pytest.raises(MemoryError, match="particles due by t = 0 s, more than 1e\\+08 at once"):
        w.step()


def test_a_birth_inside_a_collider_waits_as_one_whose_place_is_taken():
    w = kinema.World(dt=1e-3)
    w.add(kinema.Plane(point=[0, 0, 0], normal=[0, 0, 1]))
    w.add(kinema.Emitter(center=[0, 0, -1], rate=1000, particle_radius=0.01))  # below the floor
    w.step(10)
    assert len(w) == 0


def test_a_scene_of_coincident_particles_is_a_scene_error_when_built():
    from kinema.scene import Scene, SceneError

    text = '[world]\ndim = 3\ndt = 0.001\n[collisions]\n[[particles]]\ntype = "list"\npositions = [[0, 0, 0], [0, 0, 0]]\nradius = 0.1\n'
    with pytest.raises(SceneError, match=r"^s\.toml: particles: positions: particles 0 and 1 are 0 m apart"):
        Scene.from_string(text, "s.toml").build("s.toml")
