from __future__ import annotations

import numpy as np
import pytest

from sim.grid import build_model
from sim.grid.planning import (
    astar,
    bfs_route,
    breadth_first,
    distances_to,
    grid_distances,
    value_iteration,
)
from sim.maps.movingai import load_map, load_scen, movingai_to_cell
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


def test_one_bfs_serves_grids_transition_tables_and_free_cell_maps(paper50_model):
    """distances_to (directed transitions) and grid_distances (a free-cell map) are the
    same BFS as the model's distances where they describe the same moves."""
    m = paper50_model
    np.testing.assert_array_equal(distances_to(m.next_state, m.goal), m.distance_to_goal)
    free = np.ones((3, 4), dtype=bool)
    free[1, 1:3] = False  # a wall in the middle row
    d = grid_distances(free, (0, 1))
    assert d.dtype == np.int32 and d[1, 0] == 0 and d[1, 3] == 5 and d[1, 1] == -1
    # a one-way door: 0 -> 1 -> 2 and 2 -> 0; nothing leads back from 2 to 1
    nxt = np.array([[1, 0], [2, 1], [0, 2]])
    np.testing.assert_array_equal(distances_to(nxt, 1), [1, 0, 2])


def test_breadth_first_expands_each_layer_in_discovery_order():
    """A caller that acts per state (the physics model drives each one) sees FIFO order."""
    succ = {0: [3, 1, 3], 1: [2], 3: [4, 2], 2: [], 4: []}
    seen = []

    def expand(frontier):
        seen.extend(frontier.tolist())
        return np.array([t for s in frontier.tolist() for t in succ[s]], dtype=np.int64)

    np.testing.assert_array_equal(breadth_first(5, 0, expand), [0, 1, 2, 1, 2])
    assert seen == [0, 3, 1, 4, 2]
