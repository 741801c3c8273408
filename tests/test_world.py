"""kinema.World: particles moved by forces, against closed forms and conservation laws."""

import numpy as np
import pytest

import kinema


@pytest.mark.parametrize("method", ["verlet", "rk4"])
def test_projectile_matches_the_closed_form(method):
    # x(t) = x0 + v0 t + ½ g t²: integrated exactly (to rounding) by Verlet and RK4.
    w = kinema.World(dt=0.01, method=method)
    x0, v0 = np.array([0.0, 0.0, 1.0]), np.array([3.0, 1.0, 12.0])
    w.add_particles(x0, velocity=v0, mass=2.0)
    w.add(kinema.Gravity())
    tr = w.run(2.0, fps=50)
    g = np.array([0.0, 0.0, -9.81])
    t = tr.t[:, None]
    np.testing.assert_allclose(tr.positions[:, 0, :], x0 + v0 * t + 0.5 * g * t**2, rtol=0, atol=1e-11)
    np.testing.assert_allclose(tr.velocities[:, 0, :], v0 + g * t, rtol=0, atol=1e-11)
    assert tr.t.size == 101 and tr.t[-1] == pytest.approx(2.0)
    # energy: ½ m v² − m g·x is constant for the exact parabola
    np.testing.assert_allclose(tr.total, tr.total[0], rtol=1e-12)


def test_a_python_force_equals_the_engine_force_it_mimics():
    def gravity(t, x, v):
        return np.tile([0.0, 0.0, -9.81], (x.shape[0], 1)) * 2.0  # m = 2 kg

    a, b = kinema.World(dt=0.01), kinema.World(dt=0.01)
    for w in (a, b):
        w.add_particles([[0, 0, 0], [1, 1, 1]], velocity=[[1, 0, 0], [0, 1, 0]], mass=2.0)
    a.add(kinema.Gravity())
    b.add(kinema.PythonForce(gravity))
    a.step(100)
    b.step(100)
    np.testing.assert_array_equal(a.positions, b.positions)


def test_a_free_spring_network_conserves_momentum():
    rng = np.random.default_rng(3)
    n = 20
    w = kinema.World(dt=1e-3, method="verlet")
    w.add_particles(rng.random((n, 3)), velocity=rng.normal(size=(n, 3)), mass=rng.uniform(0.5, 2.0, n))
    i, j = np.triu_indices(n, 1)
    keep = rng.random(i.size) < 0.2
    w.add(kinema.Spring(i[keep], j[keep], k=50.0, damping=0.1))
    p0 = w.momenta.sum(axis=0)
    scale = np.sum(w.masses * np.linalg.norm(w.velocities, axis=1))
    w.step(10_000)
    np.testing.assert_allclose(w.momenta.sum(axis=0), p0, rtol=0, atol=1e-12 * scale)


def test_pinned_particles_and_a_hanging_spring():
    # A mass on a spring from a pinned anchor: equilibrium stretch m g / k (Hooke), reached
    # with damping.
    w = kinema.World(dt=1e-3, method="verlet")
    w.add_particles([[0, 0, 0], [0, 0, -1.0]], mass=[1.0, 0.5], pinned=[True, False])
    w.add(kinema.Gravity())
    w.add(kinema.Spring(0, 1, k=100.0, rest_length=1.0, damping=2.0))
    w.step(20_000)
    np.testing.assert_array_equal(w.positions[0], [0, 0, 0])
    assert w.positions[1, 2] == pytest.approx(-1.0 - 0.5 * 9.81 / 100.0, abs=1e-9)


def test_divergence_raises_and_keeps_the_state_before_it():
    w = kinema.World(dt=0.01, method="euler")
    w.add_particles([[0, 0, 0], [1, 0, 0]])
    w.add(kinema.Spring(0, 1, k=1e6, rest_length=0.5))
    before = None
    with pytest.raises(kinema.SimulationDiverged, match="diverged at step"):
        for _ in range(10_000):
            before = (w.positions, w.time)
            w.step()
    np.testing.assert_array_equal(w.positions, before[0])
    assert w.time == before[1] and np.all(np.isfinite(w.positions))


def test_two_dimensional_worlds_stay_in_the_plane():
    w = kinema.World(dim=2, dt=0.01, method="rk4")
    w.add_particles([[0, 0, 0]], velocity=[[1, 1, 0]])
    w.add(kinema.Gravity([0.0, -9.81, 3.0]))
    w.step(100)
    assert w.positions[0, 2] == 0.0 and w.velocities[0, 2] == 0.0
    with pytest.raises(ValueError, match="a 2D world keeps z = 0"):
        w.add_particles([[0, 0, 1.0]])


def test_diagnostics_and_energy_plot():
    w = kinema.World(dt=1e-3)
    w.add_particles([[1.0, 0, 0]], velocity=[[0, 1.0, 0]])
    w.add(kinema.Attractor(strength=1.0))
    tr = w.run(2 * np.pi, fps=10)  # a circular orbit: E = -1/2, |L| = 1
    np.testing.assert_allclose(tr.total, -0.5, rtol=1e-6)
    np.testing.assert_allclose(tr.angular_momentum[:, 2], 1.0, rtol=1e-12)
    ax = tr.plot_energy()
    assert len(ax.get_lines()) == 3
    import matplotlib.pyplot as plt

    plt.close(ax.figure)


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="dt = 0 is invalid"):
        kinema.World(dt=0.0)
    with pytest.raises(ValueError, match="unknown method 'leapfrog'"):
        kinema.World(method="leapfrog")
    w = kinema.World()
    with pytest.raises(ValueError, match=r"mass\[1\] = -1 is invalid"):
        w.add_particles([[0, 0, 0], [1, 1, 1]], mass=[1.0, -1.0])
    with pytest.raises(ValueError, match="must be \\(N, 3\\)"):
        w.add_particles([[0, 0]])
    with pytest.raises(TypeError, match="is not a kinema force"):
        w.add(42)
    w.add_particles([[0, 0, 0], [1, 0, 0]])
    with pytest.raises(ValueError, match="spring 0 joins particles 0 and 5"):
        w.add(kinema.Spring(0, 5, k=1.0))
    with pytest.raises(ValueError, match=r"k\[0\] = -1"):
        w.add(kinema.Spring(0, 1, k=-1.0))
    assert len(w) == 2 and len(w.forces) == 0


def test_a_python_force_that_raises_propagates_unchanged():
    class Oops(Exception):
        pass

    def bad(t, x, v):
        raise Oops("inside the force")

    w = kinema.World()
    w.add_particles([[0, 0, 0]])
    w.add(kinema.PythonForce(bad))
    with pytest.raises(Oops):
        w.step()
    assert w.time == 0.0
