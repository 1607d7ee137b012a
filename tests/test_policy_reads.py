"""The four read-outs of a learner's greedy policy (one compiled loop with one call of the
method's ``exploit``, :func:`learning.compiled.kernels._read_policy`) against plain-Python
reads of the same policy through the step agent's own compiled ``exploit``."""

from __future__ import annotations

import numpy as np
import pytest

from learning.compiled.kernels import (
    epsilon_rollouts,
    greedy_route,
    on_shortest_fraction,
    policy_table,
    run_episodes,
)
from learning.drivers.agent import StepAgent
from learning.geometry import geometry_of
from learning.methods.registry import METHODS
from scenarios.runs.spec import load


def _trained(method: str, episodes: int):
    _, model = load("paper-40", None, None, "goal-only")[:2]
    agent = StepAgent(METHODS[method](), geometry_of(model), np.random.default_rng(5))
    n = max(episodes, 1)
    out = (np.zeros(n, np.int32), np.zeros(n), np.zeros(n, np.bool_), np.zeros(n), np.zeros(n))
    run_episodes(agent.state, model, episodes, np.random.default_rng(6), out)
    agent.state = agent.state  # re-box after training in place
    return model, agent


def _route(agent, model, start, max_steps):
    route, seen, s = [start], {start}, start
    for t in range(max_steps):
        s = int(model.next_state[s, agent.greedy_action(s)])
        route.append(s)
        if model.terminal[s]:
            return t + 1, route
        if s in seen:
            return -1, route
        seen.add(s)
    return -1, route


def _rollouts(agent, model, start, max_steps, eps, n, rng):
    out = []
    for _ in range(n):
        s, length = start, -1
        for t in range(max_steps):
            if rng.random() < eps:
                a = int(rng.integers(0, model.next_state.shape[1]))
            else:
                a = agent.greedy_action(s)
            s = int(model.next_state[s, a])
            if model.terminal[s]:
                length = t + 1
                break
        out.append(length)
    return out


@pytest.mark.parametrize(("method", "episodes"), [("st-ql", 0), ("st-ql", 300),
                                                  ("rnh-ql+", 40), ("rn-ql", 20)])
def test_the_reads_equal_plain_reads_of_the_same_policy(method, episodes):
    model, agent = _trained(method, episodes)
    st, n_s = agent.state, model.next_state.shape[0]
    start = int(model.start)
    for max_steps in (0, 1, 7, int(model.max_steps)):
        route = np.full(max_steps + 1, -7, dtype=np.int32)
        length, written = greedy_route(st, model.next_state, model.terminal, start, max_steps,
                                       route)
        want_length, want_route = _route(agent, model, start, max_steps)
        assert (length, written) == (want_length, len(want_route))
        assert route[:written].tolist() == want_route
    want_table = [agent.greedy_action(s) for s in range(n_s)]
    assert policy_table(st, n_s).tolist() == want_table
    distance = model.distance_to_goal
    states = np.arange(0, n_s, 3, dtype=np.int32)
    good = sum(distance[model.next_state[s, want_table[s]]] == distance[s] - 1 for s in states)
    assert on_shortest_fraction(st, model.next_state, distance, states) == good / len(states)
    assert on_shortest_fraction(st, model.next_state, distance, states[:0]) == 0.0
    for eps, n, max_steps in ((0.0, 3, 50), (0.3, 5, 120), (0.3, 0, 50), (0.3, 4, 0)):
        got_rng, want_rng = np.random.default_rng(11), np.random.default_rng(11)
        got = epsilon_rollouts(st, model.next_state, model.terminal, start, max_steps, eps, n,
                               got_rng)
        assert got.tolist() == _rollouts(agent, model, start, max_steps, eps, n, want_rng)
        assert got_rng.random() == want_rng.random()  # the same draws, no more
