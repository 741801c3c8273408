"""kinema.World: particles moved by forces, against closed forms and conservation laws."""

import warnings

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
    # Forward Euler on an undamped spring multiplies its energy by 1 + (hω)² per step (here
    # hω = 14): the energy runs away and the world refuses the step that would take it beyond
    # 1000 times its scale, long before it overflows.
    w = kinema.World(dt=0.01, method="euler")
    w.add_particles([[0, 0, 0], [1, 0, 0]])
    w.add(kinema.Spring(0, 1, k=1e6, rest_length=0.5))
    before = None
    with pytest.warns(kinema.StabilityWarning), pytest.raises(kinema.SimulationDiverged, match="diverged at step") as info:
        for _ in range(10_000):
            before = (w.positions.copy(), w.velocities.copy(), w.time)
            w.step()
    err = info.value
    np.testing.assert_array_equal(w.positions, before[0])
    np.testing.assert_array_equal(w.velocities, before[1])
    assert w.time == before[2] and np.all(np.isfinite(w.positions))
    assert err.reason == "runaway energy" and err.step == w._core.steps + 1 and err.time == w.time
    assert err.particle in (0, 1) and err.dt == 0.01
    # Euler is unstable on an undamped oscillator at every step: the advisor says 0 s.
    assert err.advised_dt == 0.0


def test_free_fall_from_rest_at_the_origin_is_not_a_runaway():
    # Forward Euler adds ½ m g² h² per step in free fall (a first-order error, not a blow-up):
    # from rest at z = 0 the reference energy scale is 0, and the world must not refuse it.
    for method in ("euler", "verlet", "symplectic_euler"):
        w = kinema.World(dt=0.01, method=method)
        w.add_particles([0.0, 0.0, 0.0])
        w.add(kinema.Gravity())
        w.step(1000)
        assert w.positions[0, 2] == pytest.approx(-0.5 * 9.81 * 10.0**2, rel=2e-3)


def test_a_nan_force_is_named_as_a_non_finite_divergence():
    w = kinema.World(dt=0.01, method="rk4")
    w.add_particles([[0, 0, 0], [1, 0, 0]])
    w.add(kinema.PythonForce(lambda t, x, v: np.where(np.arange(len(x))[:, None] == 1, np.nan, 0.0) * np.ones_like(x)))
    with pytest.raises(kinema.SimulationDiverged, match="non-finite") as info:
        w.step()
    assert info.value.reason == "non-finite" and info.value.particle == 1 and info.value.step == 1


@pytest.mark.parametrize("bad", [0, 4999])
def test_verlet_finds_a_non_finite_state_in_any_chunk_of_many_particles(bad):
    # Velocity Verlet checks the new state for NaN/inf chunk by chunk on all threads (2,048
    # particles a chunk). Regression: the chunks' findings were combined with Option's own
    # order, in which "nothing found" comes first, so with more than one chunk an infinite
    # force went through unnoticed.
    w = kinema.World(dt=1e-3, method="verlet")
    n = 5000
    w.add_particles(np.random.default_rng(0).uniform(0, 10, (n, 3)), radius=0.01)
    w.add(kinema.PythonForce(lambda t, x, v: np.where(np.arange(len(x))[:, None] == bad, np.inf, 0.0) * np.ones_like(x)))
    with pytest.warns(kinema.StabilityWarning), pytest.raises(kinema.SimulationDiverged, match="non-finite") as info:
        w.step(2)
    assert info.value.particle == bad and info.value.step == 1


def test_stable_step_of_two_masses_on_a_spring_is_the_closed_form():
    # Two masses m on a spring k: the stretch oscillates at ω² = k (1/m + 1/m). Theory:
    # Verlet and symplectic Euler are stable for hω ≤ 2, RK4 for hω ≤ 2√2 (its imaginary
    # interval), forward Euler never (|1 + ihω| > 1), implicit Euler always.
    m, k = 0.5, 200.0
    w = kinema.World(dt=1e-3)
    w.add_particles([[0, 0, 0], [1, 0, 0]], mass=m)
    w.add(kinema.Spring(0, 1, k=k))
    omega = np.sqrt(2 * k / m)
    limits = w.stable_step()
    assert set(limits) == set(kinema.method_names())
    assert limits["verlet"] == pytest.approx(2 / omega, rel=1e-6)
    assert limits["symplectic_euler"] == pytest.approx(2 / omega, rel=1e-6)
    assert limits["rk4"] == pytest.approx(2 * np.sqrt(2) / omega, rel=1e-6)
    assert limits["euler"] == 0.0
    assert limits["implicit_euler"] == np.inf and limits["rk45"] == np.inf
    assert w.stable_step("verlet") == limits["verlet"]
    rates = w.rates()
    assert rates["omega"] == pytest.approx(omega, rel=1e-9) and rates["omega_bound"] == pytest.approx(omega, rel=1e-12)


def test_the_stability_warning_comes_once():
    # ω² = k (1/m + 1/m) = 200/s²: Verlet's limit is 2/ω = 0.1414 s.
    w = kinema.World(dt=0.2, method="verlet")
    w.add_particles([[0, 0, 0], [1, 0, 0]], mass=0.5)
    w.add(kinema.Spring(0, 1, k=50.0))
    with pytest.warns(kinema.StabilityWarning, match="exceeds the stable-step advisor's limit 0.1414 s"):
        w.step()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        w.step()
        w.add(kinema.Spring(0, 1, k=500.0))
        w.step()  # once in a world's lifetime
    quiet = kinema.World(dt=0.1, method="verlet")
    quiet.add_particles([[0, 0, 0], [1, 0, 0]], mass=0.5)
    quiet.add(kinema.Spring(0, 1, k=50.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        quiet.step(10)


def test_forward_euler_on_an_undamped_spring_is_unstable_at_any_step():
    # R(z) = 1 + z on z = ±iωh: |R|² = 1 + ω²h² > 1 for every h > 0, so the advisor's limit is
    # 0 and the warning says no step is small enough, rather than "limit 0 s".
    w = kinema.World(dt=1e-4, method="euler")
    w.add_particles([[0, 0, 0], [1.2, 0, 0]], mass=0.5)  # stretched by 0.2 m: the spring stays linear
    w.add(kinema.Spring(0, 1, k=50.0, rest_length=1.0))
    assert w.stable_step("euler") == 0.0
    with pytest.warns(kinema.StabilityWarning, match=r"'euler' is unstable at every step.*omega = 14.14 rad/s"):
        w.step()
    e0 = w.diagnostics()["kinetic"] + sum(w.diagnostics()["potential"].values())
    w.step(20_000)
    e1 = w.diagnostics()["kinetic"] + sum(w.diagnostics()["potential"].values())
    # for x' = v, v' = −ω²x each Euler step multiplies the energy by exactly |R|² = 1 + (ωh)²
    assert e1 / e0 == pytest.approx((1 + (14.142135623730951 * 1e-4) ** 2) ** 20_000, rel=1e-9)


def test_state_arrays_are_live_views():
    w = kinema.World(dt=0.01, method="verlet")
    w.add_particles([[0, 0, 0], [1, 0, 0]], velocity=[[1, 0, 0], [0, 0, 0]], mass=[1.0, 2.0])
    x, v, m = w.positions, w.velocities, w.masses
    w.step(10)
    assert x is w.positions and x[0, 0] == pytest.approx(0.1, abs=1e-12)  # updated in place
    x[1] = [5.0, 0.0, 0.0]  # a write moves the particle
    v[1, 1] = 2.0
    w.step(1)
    np.testing.assert_allclose(w.positions[1], [5.0, 0.02, 0.0], atol=1e-12)
    m[1] = 4.0
    np.testing.assert_allclose(w.momenta[1], [0.0, 8.0, 0.0])
    assert not w.momenta.flags.writeable and not w.accelerations.flags.writeable
    # a bad write is refused whole, named, and the views show the world's state again
    x[0, 2] = np.nan
    with pytest.raises(ValueError, match=r"positions\[0\]\[2\] = NaN is invalid"):
        w.step()
    assert np.all(np.isfinite(w.positions)) and w.positions[1, 0] == pytest.approx(5.0)
    with pytest.raises(ValueError, match=r"masses\[0\] = -1"):
        w.masses = [-1.0, 1.0]
    np.testing.assert_array_equal(w.masses, [1.0, 4.0])


def test_implicit_euler_holds_a_stiff_hanging_chain_at_a_large_step():
    # 20 masses of 10 g on k = 1e4 N/m springs hanging from a pin, h = 1/60 s: hω ≈ 30 is far
    # beyond every explicit method, but Baraff–Witkin's implicit Euler settles at Hooke's
    # equilibrium (each spring stretched by the weight below it over k).
    n, m, k, g = 20, 0.01, 1e4, 9.81
    w = kinema.World(dt=1 / 60, method="implicit_euler")
    w.add_particles([[0, 0, -0.05 * i] for i in range(n + 1)], mass=m, pinned=[i == 0 for i in range(n + 1)])
    w.add(kinema.Gravity())
    w.add(kinema.Spring(np.arange(n), np.arange(1, n + 1), k=k))
    assert w.stable_step("rk4") < w.dt / 10
    w.step(600)
    stretch = m * g * np.arange(n, 0, -1) / k
    np.testing.assert_allclose(-np.diff(w.positions[:, 2]) - 0.05, stretch, rtol=1e-6)
    iterations, converged = w._core.linear_solve()
    assert converged and iterations <= n * 3


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


@pytest.mark.filterwarnings("ignore::kinema.StabilityWarning")
def test_frames_written_by_the_steps_are_the_frames_read_after_them(monkeypatch):
    # World.run's steps write each frame's positions and velocities into the recorder's block
    # as they measure the frame's diagnostics (one pass over the engine's order, a scatter
    # into the user's: `Recorder.room`); without the room they are read after the steps (a
    # gather, `read_state`). A gas of spring-dashpot spheres, which the engine sorts along
    # space: every frame the same, bit for bit, both ways.
    from kinema._recorder import Recorder

    def gas() -> kinema.World:
        n = 16
        i, j, k = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
        w = kinema.World(dt=1e-3, method="verlet")
        v = np.random.default_rng(3).uniform(-0.5, 0.5, (n**3, 3))
        w.add_particles(np.stack([i, j, k], axis=-1).reshape(-1, 3) * 1.1, velocity=v, mass=1.0, radius=0.5)
        w.add(kinema.Box([0.0, 0.0, 0.0], [n * 1.1] * 3))
        w.periodic = (True, True, True)
        w.set_collisions(model="spring_dashpot", stiffness=2000.0, damping=50.0)
        return w

    rooms = []
    room = Recorder.room
    monkeypatch.setattr(Recorder, "room", lambda self, n: rooms.append(room(self, n)) or rooms[-1])
    written = gas().run(0.4, fps=25.0)
    assert sum(r is not None for r in rooms) >= 10, "each frame after the first had its room"
    monkeypatch.setattr(Recorder, "room", lambda self, n: None)
    w = gas()
    read = w.run(0.4, fps=25.0)
    assert w._core.sorts > 0, "the engine's order is not the user's"
    for name in ("t", "positions", "velocities", "kinetic", "momentum", "angular_momentum"):
        np.testing.assert_array_equal(getattr(written, name), getattr(read, name), err_msg=name)
    np.testing.assert_array_equal(written.potential["contact"], read.potential["contact"])


def test_a_large_run_records_into_a_block_the_kernel_mapped_at_once():
    # A run's frames go into one block (World.run knows how many); from 4 MiB on it is
    # mapped with MAP_POPULATE (trajectory._prefaulted) where the system has the flag. The
    # frames must be the states the world passed through, whichever memory holds them:
    # particles without collisions under gravity, x(t) = x0 + v0 t + g t^2 / 2 (Verlet is
    # exact for a constant force) to rounding.
    import mmap

    from kinema.trajectory import _prefaulted

    small = _prefaulted((2, 10, 3))
    assert small.shape == (2, 10, 3) and small.dtype == np.float64 and small.flags.writeable
    big = _prefaulted((3, 200_000, 3))
    assert big.shape == (3, 200_000, 3) and big.flags.writeable
    if getattr(mmap, "MAP_POPULATE", 0):
        owner = big
        while isinstance(owner, (np.ndarray, memoryview)):
            owner = owner.base if isinstance(owner, np.ndarray) else owner.obj
        assert isinstance(owner, mmap.mmap), "populated at once on Linux"
    n = 180_000  # 2 frames x 180,000 x 3 x 8 B > 4 MiB
    rng = np.random.default_rng(5)
    x0, v0 = rng.uniform(-1, 1, (n, 3)), rng.uniform(-1, 1, (n, 3))
    w = kinema.World(dt=0.01, method="verlet")
    w.add_particles(x0, velocity=v0, mass=1.0, radius=0.01)
    w.add(kinema.Gravity(g=(0.0, 0.0, -9.81)))
    traj = w.run(0.1, fps=20.0)
    assert len(traj.t) == 3
    for k, t in enumerate(traj.t):
        expected = x0 + v0 * t + 0.5 * np.array([0.0, 0.0, -9.81]) * t * t
        np.testing.assert_allclose(traj.positions[k], expected, rtol=0, atol=1e-12)
        np.testing.assert_allclose(traj.velocities[k], v0 + np.array([0.0, 0.0, -9.81]) * t, rtol=0, atol=1e-12)
