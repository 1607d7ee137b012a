"""Each ranking figure pinned on hand-made examples (learning.metrics)."""

from __future__ import annotations

import numpy as np
import pytest

from learning.metrics import (
    episodes_to_first_optimal,
    episodes_to_stable_optimal,
    optimal_test_fraction,
    reward_per_step,
    windowed_reward_per_step,
)


def test_reward_per_step_is_a_ratio_of_sums_not_a_mean_of_ratios():
    # a 1-step episode that starts next to G (+100) and a 600-step one earning +1 a step
    returns, steps = np.array([100.0, 600.0]), np.array([1, 600])
    assert reward_per_step(returns, steps) == pytest.approx(700 / 601)
    assert np.mean(returns / steps) == pytest.approx(50.5)  # what the old figure said
    assert reward_per_step(np.array([]), np.array([])) == 0.0


def test_windowed_reward_per_step():
    returns, steps = np.array([100.0, 600.0, 0.0]), np.array([1, 600, 600])
    w = windowed_reward_per_step(returns, steps, 2)
    np.testing.assert_allclose(w, [100.0, 700 / 601, 600 / 1200])
    np.testing.assert_allclose(windowed_reward_per_step(returns, steps, 1), returns / steps)
    with pytest.raises(ValueError):
        windowed_reward_per_step(returns, steps, 0)


EPISODES = np.array([10, 20, 30, 40, 50])


@pytest.mark.parametrize(("lengths", "first", "stable"), [
    ([-1, 80, 92, 80, 80], 20, 40),    # found, lost again, found for good
    ([80, 80, 80, 80, 80], 10, 10),    # optimal from the first test
    ([-1, 80, 80, 80, 84], 20, None),  # lost at the end: not stable
    ([-1, -1, -1, -1, 80], 50, 50),    # only the last test
    ([-1, -1, -1, -1, -1], None, None),
])
def test_first_hit_and_stable_optimal(lengths, first, stable):
    lengths = np.array(lengths)
    assert episodes_to_first_optimal(EPISODES, lengths, 80) == first
    assert episodes_to_stable_optimal(EPISODES, lengths, 80) == stable


def test_no_tests():
    empty = np.array([], dtype=int)
    assert episodes_to_stable_optimal(empty, empty, 80) is None
    assert optimal_test_fraction(empty, 80) is None


def test_optimal_test_fraction_over_the_last_tenth():
    lengths = np.array([80] * 80 + [-1] * 10 + [80, 84] * 5)  # 100 tests
    assert optimal_test_fraction(lengths, 80) == pytest.approx(0.5)  # last 10: 80, 84, ...
    assert optimal_test_fraction(np.array([84, 80]), 80) == 1.0  # at least one test
