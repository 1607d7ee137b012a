"""train_tabular's metrics, greedy tests, and Q-learning's convergence to value iteration's Q*."""

from __future__ import annotations

from itertools import pairwise
from types import SimpleNamespace

import numpy as np
import pytest

from learning import HAQL, METHODS, RNHQL, STQL, geometry_of, init_state, train_tabular
from learning.drivers.train import greedy_test, shortest_fraction
from sim.grid.actions import ACTION_DELTAS
from sim.grid.planning import value_iteration


def tiny_grid():
    """A 3 x 3 grid, centre blocked, goal at the top-right corner (8); the paper's rewards."""
    nx = 3
    blocked = {4}
    nxt = np.zeros((9, 4), dtype=np.int32)
    rew = np.zeros((9, 4))
    for s in range(9):
        x, y = s % nx, s // nx
        for a, (dx, dy) in enumerate(ACTION_DELTAS):
            tx, ty = x + dx, y + dy
            t = ty * nx + tx
            ok = 0 <= tx < nx and 0 <= ty < nx and t not in blocked and s not in blocked
            nxt[s, a] = t if ok else s
            rew[s, a] = (100.0 if t == 8 else 1.0) if ok else -1.0
    nxt[8], rew[8] = 8, 0.0
    dist = np.array([4, 3, 2, 3, -1, 1, 2, 1, 0], dtype=np.int32)
    coords = np.array([[s % nx + 0.5, s // nx + 0.5] for s in range(9)])
    return SimpleNamespace(next_state=nxt, reward=rew, terminal=np.arange(9) == 8, coords=coords,
                           start_states=np.array([0, 1, 2, 3, 5, 6, 7], dtype=np.int32),
                           start=0, goal=8, distance_to_goal=dist, cell_size_m=1.0,
                           bounds_m=(0.0, 0.0, 3.0, 3.0), max_steps=50)


def test_q_learning_converges_to_value_iteration():
    m = tiny_grid()
    r = train_tabular(STQL(eps=0.5), m, 4000, np.random.default_rng(0), test_every=500)
    _, q_star = value_iteration(m.next_state, m.reward, m.terminal, 0.95)
    free = m.start_states
    np.testing.assert_allclose(r.state.q[free], q_star[free], atol=1e-3)
    assert r.final_route_length == 4 and r.final_route_excess == 0
    assert r.optimal_action_fraction == 1.0


def test_metrics_are_consistent(paper50_model):
    m = paper50_model
    r = train_tabular(STQL(), m, 45, np.random.default_rng(1), test_every=10)
    assert r.episodes == 45 and r.steps.shape == (45,)
    assert r.env_steps == int(r.steps.sum())
    assert np.all(r.steps[~r.success] == m.max_steps) and np.all(r.steps[r.success] <= m.max_steps)
    assert r.test_episodes.tolist() == [10, 20, 30, 40, 45]
    assert np.all(r.wall_time_s > 0)
    assert np.all(r.shaping_mean == 0) and np.all(r.shaping_std == 0)
    assert r.reward_per_step == pytest.approx(r.returns.sum() / r.steps.sum())
    assert r.optimal_length == m.optimal_route_length
    assert r.final_route[0] == m.start
    assert 0.0 <= r.optimal_action_fraction <= 1.0


def test_rnh_ql_reports_shaping_after_warmup(paper50_model):
    r = train_tabular(RNHQL(warmup_episodes=10), paper50_model, 20, np.random.default_rng(2))
    assert np.all(r.shaping_mean[:10] == 0)
    assert np.all(r.shaping_std[10:] > 0)


def test_greedy_test_on_q_star_is_optimal(paper50_model):
    m = paper50_model
    _, q_star = value_iteration(m.next_state, m.reward, m.terminal, 0.95)
    st = init_state(STQL(), geometry_of(m), np.random.default_rng(0))
    st.q[:] = q_star
    length, route = greedy_test(st, m)
    assert length == m.optimal_route_length and route[-1] == m.goal
    assert all(m.distance_to_goal[b] == m.distance_to_goal[a] - 1 for a, b in pairwise(route))
    assert shortest_fraction(st, m) == 1.0


def test_greedy_test_stops_on_a_loop():
    m = tiny_grid()
    st = init_state(STQL(), geometry_of(m), np.random.default_rng(0))
    st.q[:, 1] = 1.0  # always "down": bumps at the bottom row
    assert greedy_test(st, m) == (-1, [0, 0])


def test_haql_is_tested_on_its_own_policy():
    m = tiny_grid()
    st = init_state(HAQL(), geometry_of(m), np.random.default_rng(0))
    length, route = greedy_test(st, m, start=6)  # (0,2): heuristic says right, right
    assert (length, route) == (2, [6, 7, 8])


def test_episodes_to_optimal(paper50_model):
    r = train_tabular(METHODS["dyna-q"](), paper50_model, 10, np.random.default_rng(0))
    r.test_route_length[:] = [-1]
    assert r.episodes_to_optimal is None
    r.test_episodes = np.array([10, 20, 30])
    r.test_route_length = np.array([-1, r.optimal_length, r.optimal_length + 2])
    assert r.episodes_to_optimal == 20


def test_bad_test_every():
    with pytest.raises(ValueError, match="test_every"):
        train_tabular(STQL(), tiny_grid(), 5, np.random.default_rng(0), test_every=0)


def test_paper_protocol_learning_sanity(paper50_model):
    """Loose regression bounds on one seed of the paper protocol (paper-50, 3000 episodes)."""
    r = train_tabular(RNHQL(), paper50_model, 3000, np.random.default_rng(0))
    assert r.success[-300:].mean() > 0.9  # reaches G from random starts
    assert r.optimal_action_fraction > 0.6
    assert np.all(r.shaping_mean[:300] == 0) and np.any(r.shaping_std[300:] > 0)
    st = train_tabular(STQL(), paper50_model, 3000, np.random.default_rng(0))
    assert st.success[-300:].mean() < r.success[-300:].mean()  # shaping helps
