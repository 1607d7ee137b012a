"""sim.grid.raster stamps circles onto their bounding boxes: it must equal the dense reference.

The reference (tests/reference_raster.py) is the O(cells x circles) code it
replaced; on random scenarios (cell sizes, robot sizes, circles on and over the
walls, map cells) the blocked cells and the passable moves agree bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest

from sim.grid import build_model
from sim.grid.planning import bfs_distances
from sim.grid.raster import occupancy, passable_moves
from sim.scenario import Circle, Robot, Scenario
from sim.scenario_io import builtin_names, resolve_scenario
from tests.reference_raster import dense_occupancy, dense_passable_moves


def random_scenario(seed: int) -> Scenario:
    rng = np.random.default_rng(seed)
    cell = float(rng.choice([0.5, 1.0, 2.0]))
    nx, ny = (int(v) for v in rng.integers(4, 40, size=2))
    w, h = nx * cell, ny * cell
    k = int(rng.integers(0, 40))
    circles = tuple(Circle(float(rng.uniform(-1, w + 1)), float(rng.uniform(-1, h + 1)),
                           float(rng.uniform(0.05, 4.0) * cell)) for _ in range(k))
    cells = tuple({(int(rng.integers(nx)), int(rng.integers(ny)))
                   for _ in range(int(rng.integers(0, 20)))})
    robot = Robot(radius_m=float(rng.uniform(0.05, 0.3)) * cell,
                  clearance_m=float(rng.uniform(0.0, 0.15)) * cell)
    return Scenario(name=f"r{seed}", width_m=w, height_m=h, start=(0, 0), goal=(nx - 1, ny - 1),
                    cell_size_m=cell, obstacles=circles, blocked_cells=cells, robot=robot)


@pytest.mark.parametrize("seed", range(60))
def test_matches_the_dense_reference_on_random_scenarios(seed):
    sc = random_scenario(seed)
    blocked = occupancy(sc)
    np.testing.assert_array_equal(blocked, dense_occupancy(sc))
    np.testing.assert_array_equal(passable_moves(sc, blocked), dense_passable_moves(sc, blocked))


@pytest.mark.parametrize("name", builtin_names())
def test_builtins_unchanged(name):
    sc = resolve_scenario(name)
    blocked = occupancy(sc)
    np.testing.assert_array_equal(blocked, dense_occupancy(sc))
    ok = passable_moves(sc, blocked)
    np.testing.assert_array_equal(ok, dense_passable_moves(sc, blocked))
    model = build_model(sc)
    assert model.optimal_route_length == int(bfs_distances(ok, sc.nx, sc.goal)[model.start])


def test_bfs_matches_a_plain_queue_bfs():
    from collections import deque

    sc = resolve_scenario("zigzag-50")
    ok = passable_moves(sc, occupancy(sc))
    nx = sc.nx
    steps = (nx, -nx, -1, 1)
    ref = np.full(ok.shape[0], -1)
    g = sc.goal[1] * nx + sc.goal[0]
    ref[g] = 0
    queue = deque([g])
    while queue:
        u = queue.popleft()
        for a in range(4):
            v = u + steps[a]
            if ok[u, a] and ref[v] < 0:
                ref[v] = ref[u] + 1
                queue.append(v)
    np.testing.assert_array_equal(bfs_distances(ok, nx, sc.goal), ref)
