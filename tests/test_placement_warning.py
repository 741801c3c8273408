"""Overlaps at the start that the collisions will push apart are said, with their count and
the deepest (issue 28: "warnings for impossible starts"): kinema.PlacementWarning, once per
placement check, from World.step / World.run and printed by `kinema run`. Deeper ones (a
centre inside another particle or a collider) are refused (tests/test_refusals.py)."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

import kinema


def caught(world: kinema.World, steps: int = 2) -> list[str]:
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        world.step(steps)
    return [str(w.message) for w in got if issubclass(w.category, kinema.PlacementWarning)]


@pytest.mark.parametrize("model", ["impulse", "spring_dashpot"])
def test_overlaps_are_counted_and_the_deepest_named_once(model):
    # a pair overlapping by 0.05 m (25 % of r_i + r_j), a ball 0.02 m into the floor, and a
    # touching pair (d = r_i + r_j exactly: no overlap, not counted)
    w = kinema.World(dim=3)
    w.set_collisions(model=model, **({"stiffness": 1e4} if model == "spring_dashpot" else {}))
    w.add(kinema.Plane((0, 0, 0), (0, 0, 1)))
    x = [[0, 0, 1], [0.15, 0, 1], [3, 0, 0.08], [6, 0, 1], [6.2, 0, 1]]
    w.add_particles(x, np.zeros((5, 3)), mass=1.0, radius=0.1)
    first = caught(w)
    assert len(first) == 1, first
    assert first[0].startswith("2 overlaps at the start that the collisions will push apart"), first[0]
    assert "the deepest: particles 0 and 1 overlap by 0.05 m (radii 0.1 and 0.1 m)" in first[0]
    assert caught(w) == []  # said once
    # new particles are checked again: one more pair, one warning
    w.add_particles([[9, 0, 1], [9.1, 0, 1]], np.zeros((2, 3)), mass=1.0, radius=0.1)
    again = caught(w)
    assert len(again) == 1 and again[0].startswith("1 overlap at the start"), again


def test_a_lattice_of_touching_balls_says_nothing():
    w = kinema.World(dim=3)
    w.add(kinema.Box((0, 0, 0), (1, 1, 1)))
    g = (np.arange(5) + 0.5) / 5
    x = np.stack(np.meshgrid(g, g, g), -1).reshape(-1, 3)
    w.add_particles(x, np.zeros_like(x), mass=1.0, radius=0.1)  # spacing 0.2 = 2 r: touching
    assert caught(w) == []


def test_kinema_run_prints_it(tmp_path):
    scene = tmp_path / "overlap.toml"
    scene.write_text(
        """[world]
dim = 3
dt = 0.001
duration = 0.01
fps = 100

[[particles]]
type = "list"
positions = [[0, 0, 1], [0.15, 0, 1]]
radius = 0.1
mass = 1.0

[[colliders]]
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]
"""
    )
    out = subprocess.run(
        [sys.executable, "-m", "kinema", "run", str(scene), "-o", str(tmp_path / "out"), "--no-video"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert "warning:" in out.stderr and "1 overlap at the start" in out.stderr, out.stderr


def test_a_periodic_side_is_no_wall():
    # a ball across the periodic face x = 0 of its cell overlaps no wall (the wall is not
    # there); the same ball against the closed face z = 0 is noticed
    w = kinema.World(dim=3)
    w.add(kinema.Box((0, 0, 0), (1, 1, 1)))
    w.periodic = (True, True, False)
    w.add_particles([[0.01, 0.5, 0.5]], np.zeros((1, 3)), mass=1.0, radius=0.02)
    assert caught(w) == []
    w.add_particles([[0.5, 0.5, 0.01]], np.zeros((1, 3)), mass=1.0, radius=0.02)
    (said,) = caught(w)
    assert "particle 1 overlaps colliders[0] by 0.01 m" in said, said
