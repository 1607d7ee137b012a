"""The free-space model's distances: a repair after a new wall equals a full BFS."""

from __future__ import annotations

import numpy as np
import pytest

from learning.geometry import ACTION_DELTAS
from learning.parts.free_space import (
    back_move,
    bfs_distances,
    distances_change,
    repair_distances,
    stable_order,
)


def grid_neighbours(n: int) -> np.ndarray:
    nb = np.full((n * n, 4), -1, np.int32)
    for s in range(n * n):
        x, y = s % n, s // n
        for a, (dx, dy) in enumerate(ACTION_DELTAS):
            if 0 <= x + dx < n and 0 <= y + dy < n:
                nb[s, a] = (y + dy) * n + x + dx
    return nb


@pytest.mark.parametrize("seed", range(6))
def test_repair_after_each_new_wall_equals_a_full_bfs(seed):
    rng = np.random.default_rng(seed)
    n = 12
    nb = grid_neighbours(n)
    blocked = np.zeros((n * n, 4), np.bool_)
    goal = int(rng.integers(n * n))
    dist = np.zeros(n * n, np.int32)
    queue = np.zeros(n * n, np.int32)
    bfs_distances(nb, blocked, dist, queue, goal)
    ref_d = dist.copy()
    ref_q = queue.copy()
    repaired = fallbacks = 0
    for _ in range(400):  # walls appear one move at a time, both directions, as bumps find them
        s = int(rng.integers(n * n))
        a = int(rng.integers(4))
        if nb[s, a] < 0 or blocked[s, a]:
            continue
        change = distances_change(nb, dist, blocked, s, a)
        blocked[s, a] = True
        bfs_distances(nb, blocked, ref_d, ref_q, goal)
        if change:
            before = dist.copy()
            changed = repair_distances(nb, blocked, dist, queue, goal, s)
            if changed[0] < 0:
                fallbacks += 1
            else:
                repaired += 1
                moved = set(np.flatnonzero(before != ref_d).tolist())
                assert moved <= set(changed.tolist())  # it reports every state it changed
        np.testing.assert_array_equal(dist, ref_d)
        reach = np.flatnonzero(ref_d >= 0)
        np.testing.assert_array_equal(np.sort(queue[:len(reach)]), reach)
    assert repaired > 10, (repaired, fallbacks)


def test_back_move_undoes_each_move():
    assert [back_move(back_move(a)) for a in range(4)] == [0, 1, 2, 3]
    assert [back_move(a) for a in range(4)] == [1, 0, 3, 2]


@pytest.mark.parametrize("n", [0, 1, 2, 3, 7, 64, 1000, 4097])
@pytest.mark.parametrize("spread", [20, 100_000])  # a counting sort; a merge sort's range
def test_stable_order_is_numpys_stable_argsort(n, spread):
    keys = np.random.default_rng(n).integers(-1, spread, n)
    assert np.array_equal(stable_order(keys), np.argsort(keys, kind="mergesort"))
