"""Reading a bump from a move's reward (:mod:`learning.parts.move_reading`)."""

from __future__ import annotations

import numpy as np
import pytest

from learning.parts.move_reading import UNSEEN, new_move_reading, read_move
from sim.scenario import REWARD_SCHEMES
from tests.conftest import corridor_moves, open_geometry_3x3


def steps(reading, moves):
    """read_move over (s, r, s2, terminated) tuples; the clean flags."""
    return [read_move(reading.r_stay, reading.r_clean, s, r, s2, t) for s, r, s2, t in moves]


@pytest.mark.parametrize("scheme", ["paper", "goal-only"])
def test_an_arrival_paid_the_bump_is_not_clean_where_bump_and_step_differ(scheme):
    goal, bump, step = REWARD_SCHEMES[scheme]
    rd = new_move_reading()
    flags = steps(rd, [(0, bump, 0, False),   # a bump: stayed
                       (0, step, 1, False),   # a free move
                       (1, bump, 2, False),   # grazed, still arrived: not clean
                       (2, step, 3, False),   # free again
                       (3, goal, 4, True)])   # entered G
    assert flags == [False, True, False, True, True]
    assert (rd.r_stay[0], rd.r_clean[0]) == (bump, step)


def test_step_cost_cannot_tell_a_grazing_arrival_and_counts_every_arrival_clean():
    _goal, bump, step = REWARD_SCHEMES["step-cost"]
    assert bump == step
    rd = new_move_reading()
    flags = steps(rd, [(0, bump, 0, False), (0, step, 1, False), (1, bump, 2, False)])
    assert flags == [False, True, True]


def test_a_first_arrival_paid_the_bump_is_corrected_by_the_next_free_move():
    """Before any free move is seen, nothing says which reward is the free one: the first
    arrival counts as clean, and the reading settles as soon as a free move is paid."""
    rd = new_move_reading()
    assert rd.r_stay[0] == UNSEEN and rd.r_clean[0] == UNSEEN
    flags = steps(rd, [(0, -1.0, 0, False), (0, -1.0, 1, False), (1, 0.0, 2, False),
                       (2, -1.0, 3, False)])
    assert flags == [False, True, True, False]


def test_a_stay_paid_like_a_free_move_does_not_become_the_bump_reward():
    rd = new_move_reading()
    steps(rd, [(0, -1.0, 0, False), (0, 0.0, 1, False), (1, 0.0, 1, False)])
    assert rd.r_stay[0] == -1.0
    assert steps(rd, [(1, -1.0, 2, False)]) == [False]


def test_a_grazing_arrival_is_a_failure_in_the_move_model_and_off_the_known_routes():
    """RNH-QL+'s real step: an arrival paid the bump counts as a failure of the move (the
    model's and the known route's), and does not move the free-move reward."""
    from learning.methods.rnh_ql_plus import RNHQLPlus, init_state, update

    geom = open_geometry_3x3()
    st = init_state(RNHQLPlus(n_planning=0), geom, np.random.default_rng(0))
    rng = np.random.default_rng(0)
    nb = st.free.neighbour
    a = int(np.flatnonzero(nb[0] >= 0)[0])
    s2 = int(nb[0, a])
    update(st, 0, a, -1.0, 0, False, rng)  # a bump
    update(st, 0, a, 0.0, s2, False, rng)  # a free arrival
    update(st, 0, a, -1.0, s2, False, rng)  # a grazing arrival
    assert (st.model.works[0, a], st.model.fails[0, a]) == (1, 2)
    assert st.opt.r_free[0] == 0.0


def test_dyna_q_stores_a_grazing_arrival_as_a_failure_not_as_the_moves_reward():
    """Dyna-Q's model: the move's success outcome keeps the free reward; a grazing arrival
    (paid the bump) is counted among the failures it replays with their frequency."""
    from learning.methods.dyna_q import DynaQ, init_state, update

    geom = open_geometry_3x3()
    st = init_state(DynaQ(n_planning=0), geom, np.random.default_rng(0))
    rng = np.random.default_rng(0)
    update(st, 0, 0, -1.0, 0, False, rng)  # a bump
    update(st, 0, 1, 0.0, 1, False, rng)  # a free arrival
    update(st, 0, 1, -1.0, 1, False, rng)  # a grazing arrival
    assert (st.model.works[0, 1], st.model.fails[0, 1]) == (1, 1)
    assert st.model.reward[0, 1] == 0.0


def test_haql_points_along_the_least_bumped_route_when_bumps_cut_every_route():
    """A 1 x 4 corridor 0-1-2-3 with G = 3: the move 1 -> 2 bumped more often than it
    arrived (blocked), so no route of unblocked moves is left from 0 and 1. The heuristic
    still points right, along the only route, instead of at move 0 (up, off the arena)."""
    from learning.methods.haql import rederive

    nb = corridor_moves(4)
    blocked = np.zeros((4, 4), np.bool_)
    bal = np.zeros((4, 4), np.int32)
    blocked[1, 3], bal[1, 3] = True, 2
    bal[0, 3] = bal[2, 3] = -3
    pi_h = np.zeros(4, np.int32)
    dist = np.zeros(4, np.int32)
    rederive(pi_h, nb, blocked, bal, dist, np.zeros(4, np.int32), 3)
    assert dist.tolist() == [-1, -1, 1, 0]
    assert pi_h[:3].tolist() == [3, 3, 3]
