"""Orientations of turning particles (issue 47): in a world with spin each particle carries a
unit quaternion (w, x, y, z), the identity when added, turned at every step by the rotation of
the step's mean angular velocity.

Closed forms: a ball rolling without slipping at v on a floor turns by v t / ρ about n × v̂
(ρ the lever arm to the contact point: the centre's height); a disc in 2D turns about z by
ω t; a quaternion of a spin held constant is exact to rounding however the time is cut.
"""

import numpy as np
import pytest

import kinema

R, M = 0.005, 1e-3


def quat_mul(a, b):
    """The Hamilton product a ⊗ b of quaternions (w, x, y, z)."""
    return np.array(
        [
            a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
        ]
    )


def rotate(q, p):
    """p turned by the unit quaternion q: q ⊗ (0, p) ⊗ q*."""
    return quat_mul(quat_mul(q, np.concatenate([[0.0], p])), q * [1, -1, -1, -1])[1:]


def rolling_ball(dt=1e-3):
    w = kinema.World(dim=3, dt=dt, spin=True)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.set_collisions(restitution=0.3, friction=0.3)
    w.add_particles([0.0, 0.0, R], radius=R, mass=M)
    return w


def test_particles_start_unturned_and_worlds_without_spin_have_no_orientation():
    w = rolling_ball()
    np.testing.assert_array_equal(w.orientations, [[1.0, 0.0, 0.0, 0.0]])
    w.add_particles([0.1, 0.0, R], radius=R, mass=M)
    np.testing.assert_array_equal(w.orientations, [[1.0, 0.0, 0.0, 0.0]] * 2)
    plain = kinema.World()
    plain.add_particles([0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="orientations: this world has no spin"):
        plain.orientations  # noqa: B018


def test_a_rolling_ball_turns_by_its_distance_over_its_radius():
    # Thrown at 1 m/s without spin it slides, then rolls at 5/7 m/s (ω = v / R about +y for
    # motion along +x: ω = n × v / R). From then on, a point of the ball turns by the angle
    # (x₁ − x₀) / R about +y: a mark at the bottom comes round to the front and the top.
    w = rolling_ball()
    w.velocities = [[1.0, 0.0, 0.0]]
    w.step(500)  # rolling after 2 v₀ / (7 μ g) = 0.068 s
    assert w.angular_velocities[0, 1] * R == pytest.approx(w.velocities[0, 0], rel=1e-9)
    q0, x0 = w.orientations[0].copy(), w.positions[0, 0]
    w.step(300)
    q1, x1 = w.orientations[0], w.positions[0, 0]
    turn = quat_mul(q1, q0 * [1, -1, -1, -1])  # the rotation from q0 to q1
    angle = (x1 - x0) / R
    closed = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * np.array([0.0, 1.0, 0.0])])
    # (q and −q are the same rotation)
    assert abs(np.dot(turn, closed)) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(rotate(turn, [0.0, 0.0, -R]), rotate(closed, [0.0, 0.0, -R]), atol=1e-9 * R)
    assert np.linalg.norm(q1) == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("calls", [[100], [1] * 100, [30, 70]])
def test_a_steady_spin_turns_by_omega_t_however_the_time_is_cut(calls):
    # A free disc in 2D spinning at ω = 7 rad/s turns by ω t about z (no force changes ω), the
    # same bits whether the steps come in one call or many.
    w = kinema.World(dim=2, dt=1e-3, spin=True)
    w.add_particles([0.0, 0.0, 0.0], radius=R, mass=M, angular_velocity=[0.0, 0.0, 7.0])
    for n in calls:
        w.step(n)
    angle = 7.0 * 0.1
    np.testing.assert_allclose(w.orientations[0], [np.cos(angle / 2), 0.0, 0.0, np.sin(angle / 2)], atol=1e-14)
    np.testing.assert_allclose(rotate(w.orientations[0], [1.0, 0.0, 0.0]), [np.cos(angle), np.sin(angle), 0.0], atol=1e-14)


def test_orientations_are_set_normalised_and_refused_by_name():
    w = rolling_ball()
    w.orientations = [[2.0, 0.0, 0.0, 0.0]]
    np.testing.assert_array_equal(w.orientations, [[1.0, 0.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match=r"orientations\[0\]"):
        w.orientations = [[0.0, 0.0, 0.0, 0.0]]
    with pytest.raises(ValueError, match=r"orientations of shape"):
        w.orientations = [[1.0, 0.0, 0.0]]
    assert not w.orientations.flags.writeable


def test_a_checkpoint_resumes_the_orientations_bit_for_bit(tmp_path):
    w = rolling_ball()
    w.velocities = [[1.0, 0.0, 0.0]]
    w.step(200)
    path = w.save_checkpoint(tmp_path / "c.h5")
    w.step(200)
    back = kinema.World.load_checkpoint(path)
    assert not np.array_equal(back.orientations, [[1.0, 0.0, 0.0, 0.0]])
    back.step(200)
    np.testing.assert_array_equal(back.orientations, w.orientations)
    np.testing.assert_array_equal(back.positions, w.positions)
