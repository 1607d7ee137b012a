"""HAQL's heuristic from exploration kept up to date wall by wall
(:func:`learning.methods.haql.rederive_after_wall`) equals the full re-derivation it replaced
(:func:`learning.methods.haql.rederive`: one BFS from G and every state's move), walls that
leave states without a route included."""

from __future__ import annotations

import numpy as np
import pytest

from learning.geometry import ACTION_DELTAS
from learning.methods.haql import rederive, rederive_after_wall
from learning.methods.haql.least_bumped import (
    BUMP_COST_CAP,
    edge_changed,
    least_bumped_costs,
    step_cost,
)


def grid_neighbours(nx: int, ny: int) -> np.ndarray:
    """The arena's moves (up, down, left, right) of an nx x ny grid, state = x * ny + y."""
    nb = np.full((nx * ny, 4), -1, np.int32)
    for x in range(nx):
        for y in range(ny):
            for a, (dx, dy) in enumerate(ACTION_DELTAS):
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
                            fast["queue"], goal, s, a, np.zeros(n, np.int64),
                            np.zeros(1, np.bool_))
        rederive(full["pi_h"], nb, full["blocked"], bal, full["dist"], full["queue"], goal)
        np.testing.assert_array_equal(fast["dist"], full["dist"])
        np.testing.assert_array_equal(fast["pi_h"], full["pi_h"])
        cut = bool((full["dist"] < 0).any())
        cuts += cut
        uncut += not cut
    assert uncut > 0  # the repair itself was exercised
    if share > 0.3:
        assert cuts > 0  # and the fallback for states without a route


def observe_by_full_rederivation(bal, pi_h, nb, blocked, dist, queue, goal, s, a, s2, clean):
    """learning.methods.haql.observe as it was: every change re-derives the whole heuristic."""
    from learning.methods.haql import COUNT_CAP

    if s2 == nb[s, a] and clean:
        bal[s, a] = max(bal[s, a] - 1, -COUNT_CAP)
    elif not clean:
        bal[s, a] = min(bal[s, a] + 1, COUNT_CAP)
    else:
        return
    now = bal[s, a] > 0
    if now != blocked[s, a]:
        blocked[s, a] = now
        rederive(pi_h, nb, blocked, bal, dist, queue, goal)
    elif now and dist[s] < 0 and pi_h[s] == a:
        rederive(pi_h, nb, blocked, bal, dist, queue, goal)


@pytest.mark.parametrize("seed", range(6))
def test_noisy_bumps_and_unblocks_equal_the_full_rederivation(seed):
    """A noisy world: moves into wall cells mostly bump, other moves sometimes do, so walls
    appear, move after all (unblocks) and cut states off; the heuristic kept up by
    :func:`learning.methods.haql.observe` (repairs, lowered distances, cut-off states alone) equals
    a full re-derivation after every change."""
    from learning.methods.haql import observe

    rng = np.random.default_rng(seed)
    nx, ny = 9, 8
    nb = grid_neighbours(nx, ny)
    n = nx * ny
    goal = int(rng.integers(n))
    walls = rng.random(n) < 0.3
    walls[goal] = False
    moves = [(s, a) for s in range(n) for a in range(4) if nb[s, a] >= 0]
    fast = dict(bal=np.zeros((n, 4), np.int32), blocked=np.zeros((n, 4), np.bool_),
                dist=np.zeros(n, np.int32), queue=np.zeros(n, np.int32),
                pi_h=np.zeros(n, np.int32), cost=np.zeros(n, np.int64),
                cost_ok=np.zeros(1, np.bool_))
    full = {k: v.copy() for k, v in fast.items()}
    for st in (fast, full):
        rederive(st["pi_h"], nb, st["blocked"], st["bal"], st["dist"], st["queue"], goal)
    kinds = {"unblock": 0, "cut": 0, "uncut": 0}
    for _ in range(4000):
        s, a = moves[rng.integers(len(moves))]
        if full["dist"][s] < 0 and rng.random() < 0.5:
            a = int(full["pi_h"][s])  # cut off: push the heuristic's own move (its branch)
            if nb[s, a] < 0:
                continue
        bump = rng.random() < (0.8 if walls[nb[s, a]] else 0.15)
        s2 = s if bump else int(nb[s, a])
        was = bool(full["blocked"][s, a])
        observe(fast["bal"], fast["pi_h"], nb, fast["blocked"], fast["dist"], fast["queue"],
                goal, s, a, s2, False, not bump, fast["cost"], fast["cost_ok"])
        observe_by_full_rederivation(full["bal"], full["pi_h"], nb, full["blocked"],
                                     full["dist"], full["queue"], goal, s, a, s2, not bump)
        for k in ("bal", "blocked", "dist", "pi_h"):
            np.testing.assert_array_equal(fast[k], full[k], err_msg=k)
        if fast["cost_ok"][0]:  # the kept costs are a full Dijkstra's after every count
            np.testing.assert_array_equal(fast["cost"],
                                          least_bumped_costs(nb, fast["bal"], goal))
        kinds["unblock"] += was and not full["blocked"][s, a]
        cut = bool((full["dist"] < 0).any())
        kinds["cut" if cut else "uncut"] += 1
    assert min(kinds.values()) > 20, kinds  # every branch was exercised
    assert fast["cost_ok"][0]  # the costs were kept, not only computed


@pytest.mark.parametrize("seed", range(4))
def test_least_bumped_costs_are_dijkstra_s_over_every_move(seed):
    """The compiled search (moves into a state found as its neighbours' opposite moves)
    against a plain Dijkstra over every (state, move) pair, on random bump counts."""
    import heapq


    rng = np.random.default_rng(seed)
    nb = grid_neighbours(11, 7)
    n = nb.shape[0]
    bal = rng.integers(-3, 4, size=(n, 4)).astype(np.int32)
    goal = int(rng.integers(n))
    want = {goal: 0}
    heap = [(0, goal)]
    while heap:
        c, v = heapq.heappop(heap)
        if c > want[v]:
            continue
        for u in range(n):
            for a in range(4):
                if nb[u, a] == v:
                    cu = c + min(max(int(bal[u, a]), 0), BUMP_COST_CAP) * (n + 1) + 1
                    if cu < want.get(u, cu + 1):
                        want[u] = cu
                        heapq.heappush(heap, (cu, u))
    got = least_bumped_costs(nb, bal, goal)
    assert got.tolist() == [want.get(s, -1) for s in range(n)]


@pytest.mark.parametrize("seed", range(6))
def test_kept_costs_equal_a_full_dijkstra_after_every_count(seed):
    """learning.methods.haql.least_bumped.edge_changed after each +1 or -1 on one move's count
    (weights that rise on least routes, with and without another tight move, and that fall)
    equals least_bumped_costs from scratch."""
    rng = np.random.default_rng(seed)
    nb = grid_neighbours(10, 9)
    n = nb.shape[0]
    goal = int(rng.integers(n))
    bal = rng.integers(-2, 3, size=(n, 4)).astype(np.int32)
    cost = least_bumped_costs(nb, bal, goal)
    moves = [(s, a) for s in range(n) for a in range(4) if nb[s, a] >= 0]
    changed = 0
    for _ in range(3000):
        s, a = moves[rng.integers(len(moves))]
        w_old = step_cost(bal, s, a, n)
        bal[s, a] += 1 if rng.random() < 0.55 else -1
        edge_changed(cost, nb, bal, s, a, w_old)
        want = least_bumped_costs(nb, bal, goal)
        changed += int(step_cost(bal, s, a, n) != w_old)
        np.testing.assert_array_equal(cost, want)
    assert changed > 500
