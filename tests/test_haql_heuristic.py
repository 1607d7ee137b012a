"""HAQL's heuristic from exploration kept up to date wall by wall
(:func:`learning.haql.rederive_after_wall`) equals the full re-derivation it replaced
(:func:`learning.haql.rederive`: one BFS from G and every state's move), walls that
leave states without a route included."""

from __future__ import annotations

import numpy as np
import pytest

from learning.haql import rederive, rederive_after_wall


def grid_neighbours(nx: int, ny: int) -> np.ndarray:
    """The arena's moves (up, down, left, right) of an nx x ny grid, state = x * ny + y."""
    nb = np.full((nx * ny, 4), -1, np.int32)
    for x in range(nx):
        for y in range(ny):
            for a, (dx, dy) in enumerate(((0, 1), (0, -1), (-1, 0), (1, 0))):
                if 0 <= x + dx < nx and 0 <= y + dy < ny:
                    nb[x * ny + y, a] = (x + dx) * ny + y + dy
    return nb


@pytest.mark.parametrize("share", [0.1, 0.35])
@pytest.mark.parametrize("seed", range(4))
def test_wall_by_wall_equals_the_full_rederivation(seed, share):
    rng = np.random.default_rng(seed)
    nx, ny = 14, 11
    nb = grid_neighbours(nx, ny)
    n = nx * ny
    goal = int(rng.integers(n))
    # a wall is a cell whose every move in is blocked, found one move at a time, as an agent
    # bumping into it finds it; at 35 % walls some states are cut off G
    walls = rng.random(n) < share
    walls[goal] = False
    moves = [(s, a) for s in range(n) for a in range(4) if nb[s, a] >= 0 and walls[nb[s, a]]]
    order = rng.permutation(len(moves))
    bal = rng.integers(0, 3, size=(n, 4)).astype(np.int32)  # least-bumped routes' counts

    fast = dict(blocked=np.zeros((n, 4), np.bool_), dist=np.zeros(n, np.int32),
                queue=np.zeros(n, np.int32), pi_h=np.zeros(n, np.int32))
    full = {k: v.copy() for k, v in fast.items()}
    for st in (fast, full):
        rederive(st["pi_h"], nb, st["blocked"], bal, st["dist"], st["queue"], goal)
    cuts = uncut = 0
    for i in order:
        s, a = moves[i]
        for st in (fast, full):
            st["blocked"][s, a] = True
        rederive_after_wall(fast["pi_h"], nb, fast["blocked"], bal, fast["dist"],
                            fast["queue"], goal, s, a)
        rederive(full["pi_h"], nb, full["blocked"], bal, full["dist"], full["queue"], goal)
        np.testing.assert_array_equal(fast["dist"], full["dist"])
        np.testing.assert_array_equal(fast["pi_h"], full["pi_h"])
        cut = bool((full["dist"] < 0).any())
        cuts += cut
        uncut += not cut
    assert uncut > 0  # the repair itself was exercised
    if share > 0.3:
        assert cuts > 0  # and the fallback for states without a route
