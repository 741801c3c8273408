"""The README's pictures from `kinema demo` (docs/img/convergence.png, stability_regions.png):
every line can be seen (issue 48: midpoint's curve hid under Heun's, which has the same
errors on the linear oscillator), and Verlet's stable segment is drawn."""

from __future__ import annotations

import itertools

import matplotlib
import numpy as np

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from kinema import demo, stability  # noqa: E402


def test_every_convergence_line_has_its_own_marker_and_style():
    fig, _ = demo.convergence_figure()
    lines = {line.get_gid(): line for line in fig.axes[0].get_lines()}
    assert list(lines) == demo.CONVERGENCE
    looks = [(line.get_marker(), line.get_linestyle()) for line in lines.values()]
    assert len(set(looks)) == len(looks), looks
    plt.close(fig)


def test_a_line_under_another_with_the_same_data_shows_around_it():
    fig, _ = demo.convergence_figure()
    lines = fig.axes[0].get_lines()  # in drawing order: a later one is on top
    pairs = 0
    for under, over in itertools.combinations(lines, 2):
        if np.allclose(under.get_ydata(), over.get_ydata(), rtol=1e-3):
            pairs += 1
            assert under.get_linewidth() > 2 * over.get_linewidth(), (under.get_gid(), over.get_gid())
            assert under.get_markersize() > 1.5 * over.get_markersize(), (under.get_gid(), over.get_gid())
            assert under.get_markerfacecolor() == "none"  # open: the marker on top shows inside it
    assert pairs >= 1  # midpoint and Heun: R(z) = 1 + z + z²/2 for both
    plt.close(fig)


def test_the_demo_regions_include_a_stable_segment():
    assert any(stability.segments(m) for m in demo.REGIONS)
