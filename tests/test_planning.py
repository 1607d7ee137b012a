from __future__ import annotations

import numpy as np
import pytest

from sim.grid import build_model
from sim.maps import load_map, load_scen, movingai_to_cell
from sim.planning import astar, bfs_route, value_iteration
from sim.scenario_io import scenario_from_map
from tests.conftest import MAPS


@pytest.fixture(scope="module")
def arena():
    return load_map(MAPS / "arena.map"), load_scen(MAPS / "arena.map.scen")


def test_astar_octile_reproduces_all_arena_scen_lengths(arena):
    grid, problems = arena
    assert len(problems) == 130
    for p in problems:
        start = movingai_to_cell(*p.start_xy, grid.height)
        goal = movingai_to_cell(*p.goal_xy, grid.height)
        length, path = astar(grid.blocked, start, goal, connectivity=8)
        assert length == pytest.approx(p.optimal_length, abs=1e-6), p
        assert path[0] == start and path[-1] == goal


def test_bfs_and_4_connected_astar_agree_on_every_arena_problem(arena):
    grid, problems = arena
    for p in problems:
        length4, _ = astar(grid.blocked, movingai_to_cell(*p.start_xy, grid.height),
                           movingai_to_cell(*p.goal_xy, grid.height), connectivity=4)
        if p.start_xy == p.goal_xy:
            continue
        # the map's cells with a point robot: BFS over the grid model of a robot that
        # fits any free cell (the built-in robot does: radius + clearance < 0.5 m)
        sc = scenario_from_map(MAPS / "arena.map", p.start_xy, p.goal_xy)
        m = build_model(sc)
        assert m.optimal_route_length == length4
        route = bfs_route(m.next_state, m.distance_to_goal, m.start)
        assert len(route) - 1 == length4 and route[-1] == m.goal


def test_value_iteration_greedy_policy_follows_shortest_routes(paper50_model):
    m = paper50_model
    v, q = value_iteration(m.next_state, m.reward, m.terminal, gamma=0.95)
    greedy = q.argmax(axis=1)
    d = m.distance_to_goal
    for s in m.start_states:
        assert d[m.next_state[s, greedy[s]]] == d[s] - 1, s
    # the closed form of the paper rewards: 20 + 80 * gamma^(d-1) ... for the start
    ds = d[m.start]
    expected = sum(0.95**k for k in range(ds - 1)) + 100 * 0.95 ** (ds - 1)
    assert v[m.start] == pytest.approx(expected, rel=1e-9)


def test_astar_reports_unreachable():
    blocked = np.zeros((3, 3), dtype=bool)
    blocked[:, 1] = True
    length, path = astar(blocked, (0, 0), (2, 2), connectivity=8)
    assert length == np.inf and path == []
