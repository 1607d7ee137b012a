"""Least-bumped routes to G, kept up to date move by move.

HAQL's heuristic (:mod:`learning.methods.haql`) points a state without a route of unblocked
moves along the route that crosses the least excess of bumps over arrivals, then the
fewest moves: ``cost[s]`` = the least sum of :func:`step_cost` over a route from s to G
through every arena move. A Dijkstra over the whole map each time it was needed cost
~20 us on 40 x 40; where the robot itself is cut off (a noisy or open-loop world walls it
in: see BENCHMARKS.md) that was almost every step. The costs change only through one
move's weight at a time (one move's count changes per outcome), so they are kept here:

- a weight that fell (:func:`edge_changed`): costs can only fall, and only through that
  move's state; a Dijkstra from it over the moves into each lowered state;
- a weight that rose on a move some least route used (it was *tight*) and the state has no
  other tight move: the states whose every least route runs through it (decided in order
  of cost: a tight move always leads to a lower cost) are re-costed from their other
  neighbours, then a Dijkstra among them (Ramalingam & Reps 1996, for one edge).

Costs are unique, so these equal a full Dijkstra's after every change (tested against
:func:`least_bumped_costs` on random count sequences).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from learning.parts.free_space import back_move

BUMP_COST_CAP = 1 << 20  # a move's excess bumps in a route's cost (int64 sums stay finite)
_FAR = np.int64(1) << 62  # no route yet (while a Dijkstra runs)


@njit(cache=True, inline="always")
def step_cost(bal, s, a, n_s):
    """A move's cost: its excess of bumps over arrivals, in units worth more than any
    route's length, plus one move."""
    return np.int64(min(max(bal[s, a], 0), BUMP_COST_CAP)) * np.int64(n_s + 1) + 1


@njit(cache=True, inline="always")
def _push(keys, vals, size, key, val):
    j = size
    keys[j], vals[j] = key, val
    while j > 0:  # sift up
        p = (j - 1) // 2
        if keys[p] <= keys[j]:
            break
        keys[p], keys[j] = keys[j], keys[p]
        vals[p], vals[j] = vals[j], vals[p]
        j = p
    return size + 1


@njit(cache=True, inline="always")
def _pop(keys, vals, size):
    """(key, value, new size) of the least entry."""
    c, v = keys[0], vals[0]
    size -= 1
    keys[0], vals[0] = keys[size], vals[size]
    i = 0
    while True:  # sift down
        left, right, m = 2 * i + 1, 2 * i + 2, i
        if left < size and keys[left] < keys[m]:
            m = left
        if right < size and keys[right] < keys[m]:
            m = right
        if m == i:
            break
        keys[i], keys[m] = keys[m], keys[i]
        vals[i], vals[m] = vals[m], vals[i]
        i = m
    return c, v, size


@njit(cache=True)
def _lower(cost, nb, bal, keys, vals, size, member):
    """Dijkstra from the entries queued: each popped state's cost is final; the moves into
    it (its neighbours' opposite moves: the arena's moves are symmetric) relax their
    states' costs. ``member`` (or None): only those states may change."""
    n_s, n_a = nb.shape
    while size > 0:
        c, v, size = _pop(keys, vals, size)
        if c != cost[v]:
            continue  # stale
        for b in range(n_a):
            u = nb[v, b]
            if u < 0 or (member is not None and not member[u]):
                continue
            cu = c + step_cost(bal, u, back_move(b), n_s)
            if cu < cost[u]:
                cost[u] = cu
                size = _push(keys, vals, size, cu, u)


@njit(cache=True)
def least_bumped_costs(nb, bal, goal):
    """cost[s] from scratch: Dijkstra from G over the moves reversed (-1: no route)."""
    n_s, n_a = nb.shape
    cost = np.full(n_s, _FAR, np.int64)
    keys = np.empty(n_s * n_a + 1, np.int64)  # a push per move at most, and G
    vals = np.empty(n_s * n_a + 1, np.int64)
    cost[goal] = 0
    keys[0], vals[0] = 0, goal
    _lower(cost, nb, bal, keys, vals, 1, None)
    for s in range(n_s):
        if cost[s] == _FAR:
            cost[s] = -1
    return cost


@njit(cache=True)
def edge_changed(cost, nb, bal, s, a, w_old):
    """``cost`` after move (s, a)'s weight changed from ``w_old`` to its
    :func:`step_cost` now (``bal`` already counts the outcome)."""
    n_s, n_a = nb.shape
    w = step_cost(bal, s, a, n_s)
    t = nb[s, a]
    if w == w_old or t < 0 or cost[t] < 0:
        return
    if w < w_old:  # costs fall through s, if at all
        c = cost[t] + w
        if c < cost[s]:
            cost[s] = c
            keys = np.empty(n_s * n_a + 1, np.int64)
            vals = np.empty(n_s * n_a + 1, np.int64)
            keys[0], vals[0] = c, s
            _lower(cost, nb, bal, keys, vals, 1, None)
        return
    if cost[s] != cost[t] + w_old:
        return  # no least route used the move
    for b in range(n_a):
        u = nb[s, b]
        if b != a and u >= 0 and cost[u] >= 0 and cost[u] + step_cost(bal, s, b, n_s) == \
                cost[s]:
            return  # s keeps its cost through another move: nothing changes
    _raise_from(cost, nb, bal, s)


@njit(cache=True)
def _raise_from(cost, nb, bal, s):
    """s's cost rose: find the states whose every least route ran through s (in order of
    their old cost, so a state is decided after every state its tight moves lead to), then
    cost them from their other neighbours and settle them among themselves."""
    n_s, n_a = nb.shape
    member = np.zeros(n_s, np.bool_)
    queued = np.zeros(n_s, np.bool_)
    keys = np.empty(n_s * n_a + 1, np.int64)
    vals = np.empty(n_s * n_a + 1, np.int64)
    found = np.empty(n_s, np.int64)
    n_found = 0
    size = _push(keys, vals, 0, cost[s], s)
    queued[s] = True
    while size > 0:
        _, v, size = _pop(keys, vals, size)
        if v != s:  # a candidate: out if some tight move leads outside the set
            out = False
            for c in range(n_a):
                t = nb[v, c]
                if t >= 0 and not member[t] and cost[t] >= 0 and \
                        cost[t] + step_cost(bal, v, c, n_s) == cost[v]:
                    out = True
                    break
            if out:
                continue
        member[v] = True
        found[n_found] = v
        n_found += 1
        for b in range(n_a):  # the states with a tight move into v are candidates
            u = nb[v, b]
            if u >= 0 and not queued[u] and cost[u] > 0 and \
                    cost[u] == cost[v] + step_cost(bal, u, back_move(b), n_s):
                queued[u] = True
                size = _push(keys, vals, size, cost[u], u)
    size = 0
    for i in range(n_found):
        v = found[i]
        best = _FAR
        for c in range(n_a):
            t = nb[v, c]
            if t >= 0 and not member[t] and cost[t] >= 0:
                best = min(best, cost[t] + step_cost(bal, v, c, n_s))
        cost[v] = best
        if best < _FAR:
            size = _push(keys, vals, size, best, v)
    _lower(cost, nb, bal, keys, vals, size, member)
