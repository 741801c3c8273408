"""benchmarks/before_after.py's spread of the after / before ratio over interleaved pairs."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from before_after import pair_ratios  # noqa: E402


def test_the_pairs_ratios_median_and_quartiles_are_those_of_the_order_statistics():
    # ratios 0.5, 1, 1.5, 2, 3 (pairs given out of order): median 1.5, and the inclusive
    # quartiles sit exactly on the 2nd and 4th order statistics, (n − 1)/4 = 1 apart
    before = [2.0, 1.0, 1.0, 2.0, 1.0]
    after = [4.0, 0.5, 1.5, 2.0, 3.0]
    assert pair_ratios(before, after) == (1.5, 1.0, 2.0)


def test_two_pairs_give_their_ratios_as_quartiles_and_one_pair_its_ratio():
    assert pair_ratios([1.0, 1.0], [0.9, 1.1]) == pytest.approx((1.0, 0.95, 1.05))
    assert pair_ratios([2.0], [1.0]) == (0.5, 0.5, 0.5)


def test_pairs_are_after_over_before_of_the_same_run_not_of_the_medians():
    # each pair 10 % faster although the machine slowed between pairs by 3x: the medians of
    # the two columns alone would mix the minutes, the pairs do not
    before = [1.0, 3.0, 1.0, 3.0]
    after = [0.9, 2.7, 0.9, 2.7]
    med, q1, q3 = pair_ratios(before, after)
    assert med == pytest.approx(0.9) and q1 == pytest.approx(0.9) and q3 == pytest.approx(0.9)


def test_unequal_runs_are_refused():
    with pytest.raises(ValueError):
        pair_ratios([1.0, 2.0], [1.0])
