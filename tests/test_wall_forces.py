"""What the particles gave each collider (issue 47's wall forces): `World.collider_books()`
goes on in a world read from a checkpoint as in the world that wrote it."""

from __future__ import annotations

import numpy as np

import kinema


def bin_of_balls(model="impulse"):
    """Eighteen balls thrown sideways in a box on a floor: they strike the box's walls and rest
    on the floor, so that both colliders take momentum, pressure and shear."""
    w = kinema.World(dt=1e-3 if model == "impulse" else 2e-4, spin=True)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add(kinema.Box([-0.2, -0.2, -0.5], [0.2, 0.2, 1.0]))
    x = [[-0.1 + 0.1 * a, -0.1 + 0.1 * b, 0.05 + 0.12 * c] for a in range(3) for b in range(3) for c in range(2)]
    w.add_particles(x, radius=0.04, mass=0.1, velocity=[[1.5 - 0.3 * k, 0.7 * (-1) ** k, 0.0] for k in range(18)])
    w.set_collisions(restitution=0.5, friction=0.4, **({"model": "spring_dashpot", "stiffness": 2e4} if model != "impulse" else {}))
    return w


def test_a_world_read_from_a_checkpoint_goes_on_with_the_books_of_the_one_that_wrote_it(tmp_path):
    w = bin_of_balls()
    w.step(150)
    w.save_checkpoint(tmp_path / "w.ckpt")
    again = kinema.World.load_checkpoint(tmp_path / "w.ckpt")
    for last in (False, True):  # the same bits until it steps
        mine, read = w.collider_books(last=last), again.collider_books(last=last)
        for key in mine:
            np.testing.assert_array_equal(read[key], mine[key], err_msg=f"{key} (last={last})")
    w.step(100)
    again.step(100)
    mine, read = w.collider_books(), again.collider_books()
    for key in mine:
        np.testing.assert_allclose(read[key], mine[key], rtol=0, atol=1e-14 * np.abs(mine[key]).max(), err_msg=key)
    for key, a in w.collider_books(last=True).items():  # its own last step's, the engine's
        np.testing.assert_array_equal(again.collider_books(last=True)[key], a, err_msg=key)
