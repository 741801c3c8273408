"""The state's views (`w.positions`, `w.velocities`, `w.masses`, `w.angular_velocities`):
live while somebody holds them, absent while nobody does (issue 51: 56 B per particle of
copies that nobody read, kept and refreshed after every step).

The views are NumPy arrays that numpy's allocator reports to `tracemalloc`, so the memory the
world keeps in them is measured, not assumed."""

from __future__ import annotations

import gc
import tracemalloc

import numpy as np

import kinema


def _gas(n: int = 20_000, spin: bool = False) -> kinema.World:
    rng = np.random.default_rng(7)
    w = kinema.World(dt=1e-3, method="verlet", spin=spin)
    w.add_particles(rng.uniform(0.0, 1.0, (n, 3)), velocity=rng.normal(0.0, 1.0, (n, 3)), mass=1.0)
    return w


def test_a_world_nobody_looks_at_keeps_no_copy_of_its_state():
    # Before: two (N, 3) arrays and the masses, 56 B per particle, held and refreshed.
    # (traced from before the world is made: the engine's memory is Rust's and not traced,
    # the views' is numpy's and is; a small world first, so that what importing and first
    # calls keep is not counted)
    _gas(10).step(3)
    tracemalloc.start()
    try:
        w = _gas()
        x = w.positions  # a look: the view is made ...
        assert x.shape == (20_000, 3)
        del x
        w.step(3)  # ... and, held by nobody, dropped after the steps
        gc.collect()
        kept, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert kept < 8 * 20_000, f"{kept} B of arrays kept after the steps"
    # a look now reads the state the steps left: the engine's, bit for bit
    x, v = w.positions.copy(), w.velocities.copy()
    t = w.run(1e-3, fps=1000.0)  # (a trajectory's frames are read from the engine)
    assert np.array_equal(t.positions[0], x) and np.array_equal(t.velocities[0], v)
    assert np.array_equal(t.positions[-1], w.positions) and np.array_equal(t.velocities[-1], w.velocities)


def test_a_passing_look_is_let_go_before_the_steps_not_after_them():
    # `temperature(w.velocities)` between two runs of steps: the view nobody holds any more is
    # dropped when the world starts stepping, so it is not resident while the engine works
    # (it was until the steps ended: 24 MB at 10⁶ particles beside the step's own peak). The
    # arrays traced while the engine steps are read by a force it calls.
    _gas(10).step(3)
    w = _gas()
    during = []

    def look(t, x, v):
        during.append(tracemalloc.get_traced_memory()[0])
        return np.zeros_like(x)

    w.add(kinema.PythonForce(look))
    w.step(1)
    tracemalloc.start()
    try:
        speed2 = float(np.einsum("ij,ij->", w.velocities, w.velocities))
        assert speed2 > 0.0
        during.clear()
        w.step(2)
    finally:
        tracemalloc.stop()
    # (the force's own arguments, x and v lent to it, are the engine's: 2 × 480 kB, traced
    # when NumPy makes them; the view was a third)
    assert during and max(during) < 2 * 24 * 20_000 + 8 * 20_000, f"{during} B of arrays while the engine steps"
    # a view that is held is not let go: it follows the steps
    v = w.velocities
    w.step(1)
    assert np.array_equal(v, w.velocities) and np.shares_memory(v, w.velocities)


def test_a_view_that_is_held_is_live_and_so_is_a_slice_of_it():
    w = _gas(1000, spin=True)
    x, v, m, omega = w.positions, w.velocities, w.masses, w.angular_velocities
    z = w.positions[:, 2]  # a slice holds its base: the view stays live through it
    del x
    x0 = z.copy()
    w.step(5)
    # free flight (no forces): x(t) = x0 + v t exactly as the engine's Verlet adds it
    assert not np.array_equal(z, x0)
    assert np.array_equal(z, w.positions[:, 2])
    assert np.shares_memory(z, w.positions)
    assert v is w.velocities and m is w.masses and omega is w.angular_velocities
    # a write through a held view moves the particle; one through a view nobody held too
    v[0] = [0.0, 0.0, 0.0]
    w.velocities[1] = [0.0, 0.0, 0.0]
    before = w.positions[:2].copy()
    w.step(1)
    assert np.array_equal(w.positions[:2], before)


def test_a_write_into_a_view_then_dropped_reaches_the_engine():
    # The view is dropped after the next step only: what was written into it was pushed by then.
    w = _gas(100)
    w.positions[3] = [5.0, 6.0, 7.0]
    w.velocities[3] = [0.0, 0.0, 0.0]
    w.step(2)
    assert w.positions[3].tolist() == [5.0, 6.0, 7.0]
    # Σ ½ m v² (the engine's sum in its own order: to rounding)
    assert abs(w.diagnostics()["kinetic"] - 0.5 * float(np.sum(w.masses[:, None] * w.velocities**2))) < 1e-12 * w.diagnostics()["kinetic"]
