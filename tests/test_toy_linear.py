"""The toy normal law ``set_collisions(model="toy_linear", stiffness=k)``: F_n = k δ, no
dashpot. Two equal balls meeting head on bounce back elastically, whatever e is set."""

import math

import pytest

import kinema

K, R, M = 1e4, 0.01, 1e-3
M_STAR = M / 2


@pytest.mark.parametrize("e", [1.0, 0.5])
def test_two_balls_meeting_head_on_bounce_back_elastically(e):
    u = 1.0
    t_c = math.pi * math.sqrt(M_STAR / K)
    dt = t_c / 2000
    w = kinema.World(dt=dt)
    w.set_collisions(model="toy_linear", stiffness=K, restitution=e)
    assert w.collisions["model"] == "toy_linear" and w.collisions["stiffness"] == K
    gap = 3 * u * dt
    w.add_particles([[-R - gap / 2, 0, 0], [R + gap / 2, 0, 0]], velocity=[[u / 2, 0, 0], [-u / 2, 0, 0]], mass=M, radius=R)
    w.step(int(1.5 * t_c / dt) + 10)
    assert w.positions[1, 0] - w.positions[0, 0] > 2 * R  # apart again
    relative = w.velocities[1, 0] - w.velocities[0, 0]
    assert relative == pytest.approx(u, abs=1e-6)


def test_the_toy_takes_a_stiffness_and_no_damping():
    w = kinema.World(dt=1e-5)
    with pytest.raises(ValueError, match="stiffness"):
        w.set_collisions(model="toy_linear")
    with pytest.raises(ValueError, match="damping"):
        w.set_collisions(model="toy_linear", stiffness=K, damping=1.0)
