"""The uniform vector forces take a 2-vector [x, y] as (x, y, 0), the scene file's rule
(issue 48: ``Gravity([0, -9.81])`` was refused in 2D while a scene's ``g = [0, -9.81]`` was
accepted), and refuse other lengths naming the parameter, the value and what is allowed."""

from __future__ import annotations

import numpy as np
import pytest

import kinema


def _world(dim: int) -> kinema.World:
    w = kinema.World(dim=dim, dt=1e-3, method="verlet")
    w.add_particles([[1.0, 2.0, 0.0]], mass=2.0)
    return w


@pytest.mark.parametrize("dim", [2, 3])
def test_gravity_of_a_2_vector_is_the_same_as_its_3_vector(dim):
    two, three = _world(dim), _world(dim)
    two.add(kinema.Gravity([0.5, -9.81]))
    three.add(kinema.Gravity([0.5, -9.81, 0.0]))
    np.testing.assert_array_equal(two.accelerations, [[0.5, -9.81, 0.0]])
    two.step(50)
    three.step(50)
    np.testing.assert_array_equal(two.positions, three.positions)
    np.testing.assert_array_equal(two.velocities, three.velocities)


def test_gravity_2_vector_in_a_2d_world_as_in_its_scene_file():
    w = _world(2)
    w.add(kinema.Gravity(np.array([0.0, -9.81])))
    assert kinema.Gravity([0, -9.81]).vector(2) == [0.0, -9.81, 0.0]
    np.testing.assert_array_equal(w.accelerations, [[0.0, -9.81, 0.0]])


@pytest.mark.parametrize("dim", [2, 3])
def test_wind_of_a_2_vector_is_the_same_as_its_3_vector(dim):
    w = _world(dim)
    w.add(kinema.Wind([3.0, -1.0], coefficient=4.0))
    # F = b (w − v) with v = 0, a = F / m
    np.testing.assert_allclose(w.accelerations, [[4.0 * 3.0 / 2.0, 4.0 * -1.0 / 2.0, 0.0]], rtol=1e-15)


@pytest.mark.parametrize("dim", [2, 3])
def test_attractor_point_of_a_2_vector_is_the_same_as_its_3_vector(dim):
    two, three = _world(dim), _world(dim)
    two.add(kinema.Attractor([4.0, -2.0], strength=3.0, softening=0.1))
    three.add(kinema.Attractor([4.0, -2.0, 0.0], strength=3.0, softening=0.1))
    assert np.abs(two.accelerations).max() > 0
    np.testing.assert_array_equal(two.accelerations, three.accelerations)


@pytest.mark.parametrize(
    "make, text",
    [
        (
            lambda: kinema.Gravity([9.81]),
            r"g = \[9\.81\] is invalid: it has 1 component; give \[x, y, z\] or, as in a scene file, \[x, y\] meaning \(x, y, 0\) \(m/s²\)",
        ),
        (lambda: kinema.Gravity([0, 0, -9.81, 0]), r"g = \[0, 0, -9\.81, 0\] is invalid: it has 4 components; give \[x, y, z\] or.*\[x, y\]"),
        (lambda: kinema.Wind(velocity=[1, 2, 3, 4]), r"velocity = \[1, 2, 3, 4\] is invalid: it has 4 components; give \[x, y, z\] or.*\(m/s\)"),
        (lambda: kinema.Wind(velocity=[]), r"velocity = \[\] is invalid: it has 0 components"),
        (lambda: kinema.Attractor(point=[1.0]), r"point = \[1\.0\] is invalid: it has 1 component; .*\(m\)"),
    ],
)
def test_other_lengths_are_refused_naming_the_parameter_the_value_and_what_is_allowed(make, text):
    with pytest.raises(ValueError, match=text):
        make()


def test_a_2d_scene_and_the_python_world_agree(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text('[world]\ndim = 2\ndt = 0.001\n[[particles]]\ntype = "list"\npositions = [[1.0, 2.0]]\n[[forces]]\ntype = "gravity"\ng = [0.5, -9.81]\n')
    from_file = kinema.load_scene(scene)
    w = kinema.World(dim=2, dt=1e-3)
    w.add_particles([[1.0, 2.0, 0.0]])
    w.add(kinema.Gravity([0.5, -9.81]))
    np.testing.assert_array_equal(from_file.accelerations, w.accelerations)
