from __future__ import annotations

import numpy as np

from sim.grid import build_model
from sim.scenario import Circle, Rewards, Scenario


def corridor():
    # 4 x 2 arena; a circle blocks cell (1, 1)
    return Scenario(name="c", width_m=4, height_m=2, start=(0, 0), goal=(3, 0),
                    obstacles=(Circle(1.5, 1.5, 0.2),), rewards=Rewards(goal=10, bump=-2, step=0.5))


def test_paper_dynamics_on_a_tiny_world():
    m = build_model(corridor())
    up, down, left, right = range(4)
    s00, s10, s01, s11 = 0, 1, 4, 5
    assert m.blocked[1, 1] and not m.blocked[0, 1]
    # free move
    assert m.next_state[s00, right] == s10 and m.reward[s00, right] == 0.5
    # walls: stay, bump
    assert m.next_state[s00, left] == s00 and m.reward[s00, left] == -2
    assert m.next_state[s00, down] == s00 and m.reward[s00, down] == -2
    # into a blocked cell: stay, bump
    assert m.next_state[s10, up] == s10 and m.reward[s10, up] == -2
    assert m.next_state[s01, right] == s01
    # entering the goal: +goal, terminal
    assert m.next_state[2, right] == 3 and m.reward[2, right] == 10
    assert m.terminal[3] and m.terminal.sum() == 1
    assert (m.next_state[3] == 3).all() and (m.reward[3] == 0).all()
    # start cells: free, reach the goal, goal excluded; blocked cells never
    assert s11 not in m.start_states and 3 not in m.start_states and s00 in m.start_states
    assert m.distance_to_goal[s00] == 3 and m.distance_to_goal[s11] == -1
    assert m.optimal_route_length == 3
    np.testing.assert_allclose(m.coords[s11], [1.5, 1.5])


def test_swept_disc_between_free_centres_is_a_bump():
    # A small circle between two free cell centres: both cells free, move blocked.
    sc = Scenario(name="g", width_m=4, height_m=3, start=(0, 1), goal=(3, 1),
                  obstacles=(Circle(2.0, 1.5, 0.1),))
    m = build_model(sc)
    assert not m.blocked[1, 1] and not m.blocked[1, 2]
    s11, s21 = 1 * 4 + 1, 1 * 4 + 2
    assert m.next_state[s11, 3] == s11 and m.next_state[s21, 2] == s21


def test_model_arrays_are_read_only(paper50_model):
    assert not paper50_model.next_state.flags.writeable
    assert paper50_model.next_state.dtype == np.int32
    assert paper50_model.n_states == 2500


def test_the_action_table_agrees_with_itself():
    """sim.grid.actions is the one action table: names, moves, headings and reverses agree."""
    import math

    from sim.grid.actions import (
        ACTION_DELTAS,
        ACTION_HEADINGS,
        ACTION_NAMES,
        N_ACTIONS,
        OPPOSITE,
    )

    assert ACTION_NAMES == ("up", "down", "left", "right") and N_ACTIONS == 4
    from learning.geometry import ACTION_DELTAS as LEARNERS_ORDER

    assert ACTION_DELTAS == LEARNERS_ORDER  # the world's order is the learners'
    for a, (dx, dy) in enumerate(ACTION_DELTAS):
        assert ACTION_HEADINGS[a] == math.atan2(dy, dx)
        assert ACTION_DELTAS[OPPOSITE[a]] == (-dx, -dy) and OPPOSITE[OPPOSITE[a]] == a


def test_a_model_whose_actions_run_in_another_order_is_refused_by_the_learners():
    import dataclasses

    import pytest

    from learning.geometry import geometry_of
    from sim.grid import build_model
    from sim.scenario_io import resolve_scenario

    model = build_model(resolve_scenario("paper-40"))
    geometry_of(model)  # the world's own order: accepted

    class Swapped:
        def __init__(self, m):
            self.__dict__.update({f.name: getattr(m, f.name) for f in dataclasses.fields(m)})
            self.action_deltas = ((0, 1), (0, -1), (1, 0), (-1, 0))

    with pytest.raises(ValueError, match="not the learners' order"):
        geometry_of(Swapped(model))
