"""The library's own inputs, from Python: refused in one InputError naming the argument,
never coerced into something else (issue 66's probe: 3.7, '2', True, an array of two, 2**70
as an action; a float cell; a fidelity knob given twice)."""

from __future__ import annotations

import numpy as np
import pytest

from learning.plain.learner import LearnerError, checked_action
from scenarios import api
from sim.errors import InputError


@pytest.mark.parametrize("answer", [3.7, 2.0, "2", "1", True, np.array([1, 2]), 2**70, 4])
def test_a_policy_function_must_answer_an_int_action(answer):
    with pytest.raises(InputError, match=r"policy: returned .* not an action"):
        api.grade(lambda s: answer, "paper-40", with_optimum=False)


def test_an_integer_or_an_array_of_one_integer_is_an_action():
    """What Stable-Baselines3's predict gives (an array of one) is accepted as it is."""
    a = api.grade(lambda s: 1, "paper-40", with_optimum=False)
    b = api.grade(lambda s: np.array([1]), "paper-40", with_optimum=False)
    c = api.grade(lambda s: np.int64(1), "paper-40", with_optimum=False)
    assert a == b == c


@pytest.mark.parametrize("answer", [3.7, 2.0, "2", True, np.array([1, 2])])
def test_a_plain_learners_answer_is_not_coerced(answer):
    with pytest.raises(LearnerError, match="not an action"):
        checked_action(object(), 0, answer, 4)
    assert checked_action(object(), 0, np.int64(3), 4) == 3


def test_a_cell_is_two_whole_numbers():
    with pytest.raises(InputError, match=r"start: .* whole numbers"):
        api.train("paper-40", "st-ql", episodes=2, start=(2.7, 2))
    with pytest.raises(InputError, match=r"goal: .* whole numbers"):
        api.train("paper-40", "st-ql", episodes=2, goal=(True, 2))


def test_a_fidelity_knob_given_twice_is_refused():
    with pytest.raises(InputError, match="lag_tau_s: is given twice"):
        api.grade(lambda s: 0, "paper-40", fidelity="noisy,lag_tau_s=0.1,lag_tau_s=0.3",
                  with_optimum=False)
