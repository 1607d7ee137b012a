"""The free-space model: the arena's cells, the moves the learner believes blocked, and
every cell's distance to G over the rest (the free-space assumption of D* Lite).

HAQL's heuristic from exploration and RNH-QL+'s optimistic potential both keep
one. The agent knows the arena's cells and where G is (its
:class:`learning.geometry.Geometry`), not the obstacles: every move it has not
learned to be blocked is assumed free. *Which* moves are blocked is the method's
rule (HAQL: more bumps than arrivals; RNH-QL+: never seen to work), written into
``blocked``; the distances are one BFS from G, re-run by the method when a
blocked move changes a distance: O(states) then, nothing otherwise.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from learning.geometry import ACTION_DELTAS, Geometry


class FreeSpace(NamedTuple):
    neighbour: np.ndarray  # int32[nS, nA]; the arena cell each move heads for (-1: off the arena)
    blocked: np.ndarray  # bool[nS, nA]; moves the method's rule calls walls
    distance: np.ndarray  # int32[nS]; moves to G over the unblocked moves (-1: no route)
    queue: np.ndarray  # int32[nS]; the BFS order (the reachable states, G first)
    goal: np.ndarray  # int64[1]; G, the BFS root


def arena_neighbours(geom: Geometry) -> np.ndarray:
    """int32[nS, nA]: the state each move heads for on the arena's grid (-1 off the arena)."""
    n = geom.n_states
    cells = geom.cells
    nx = int(cells[:, 0].max()) + 1
    ny = int(cells[:, 1].max()) + 1
    index = np.full((nx, ny), -1, dtype=np.int64)
    index[cells[:, 0], cells[:, 1]] = np.arange(n)
    out = np.zeros((n, len(ACTION_DELTAS)), dtype=np.int32)
    for a, (dx, dy) in enumerate(ACTION_DELTAS):
        tx, ty = cells[:, 0] + dx, cells[:, 1] + dy
        inside = (tx >= 0) & (tx < nx) & (ty >= 0) & (ty < ny)
        out[:, a] = np.where(inside, index[np.clip(tx, 0, nx - 1), np.clip(ty, 0, ny - 1)], -1)
    return out


def new_free_space(geom: Geometry) -> FreeSpace:
    """Nothing blocked yet; distances from one BFS (the arena's own)."""
    n = geom.n_states
    fs = FreeSpace(arena_neighbours(geom), np.zeros((n, len(ACTION_DELTAS)), np.bool_),
                   np.zeros(n, np.int32), np.zeros(n, np.int32),
                   np.array([geom.goal], dtype=np.int64))
    bfs_to_goal(fs)
    return fs


@njit(cache=True, inline="always")
def back_move(a):
    """The move that undoes a (actions: up, down, left, right)."""
    return 1 if a == 0 else (0 if a == 1 else (3 if a == 2 else 2))


@njit(cache=True)
def bfs_to_goal(fs):
    """Distances to G over the moves not blocked, and the BFS order in ``queue``."""
    bfs_distances(fs.neighbour, fs.blocked, fs.distance, fs.queue, fs.goal[0])


@njit(cache=True)
def bfs_distances(nb, blocked, dist, queue, goal):
    """:func:`bfs_to_goal` on the free space's arrays: what compiled hooks call (they read
    a named tuple's fields once, at their top; see :mod:`learning.methods.rnh_ql_plus.rules`)."""
    for s in range(dist.shape[0]):
        dist[s] = -1
    dist[goal] = 0
    queue[0] = goal
    lower_distances(nb, blocked, dist, queue, 1)


@njit(cache=True, inline="always")
def lower_distances(nb, blocked, dist, order, tail):
    """Distances lowered breadth first from the states ``order[:tail]`` (theirs set, rising
    along ``order``): a state with an unblocked move into a state v of ``order``, and a
    distance unset (-1) or above dist[v] + 1, takes dist[v] + 1 and joins ``order``. Returns
    how many states ``order`` then holds. From G alone, every other distance unset, it is
    the BFS (a state is first reached at its least distance, so none is lowered twice)."""
    head = 0
    while head < tail:
        v = order[head]
        head += 1
        for a in range(nb.shape[1]):
            u = nb[v, a]  # v's neighbour; u reaches v by the opposite move
            if u < 0 or 0 <= dist[u] <= dist[v] + 1 or blocked[u, back_move(a)]:
                continue
            dist[u] = dist[v] + 1
            order[tail] = u
            tail += 1
    return tail


@njit(cache=True, inline="always")
def distances_change(nb, dist, blocked, s, a):
    """Whether the move s -a-> just blocked changes any distance. The distances solve
    d(s) = 1 + min d(u) over s's unblocked moves, a solution that is unique; the blocked
    move matters only if it was s's one move to a neighbour u with d(u) = d(s) - 1.
    Otherwise every old distance still solves the equations and the O(states) BFS is
    skipped (on most new walls: a cell usually has two moves towards G). Takes the free
    space's arrays (``neighbour``, ``distance``, ``blocked``), read once by the caller."""
    ds = dist[s]
    u = nb[s, a]
    if ds <= 0 or u < 0 or dist[u] != ds - 1:
        return False
    for b in range(nb.shape[1]):
        if b == a:
            continue
        v = nb[s, b]
        if v >= 0 and dist[v] == ds - 1 and not blocked[s, b]:
            return False
    return True


@njit(cache=True)
def stable_order(keys):
    """The indices that sort the integer ``keys`` ascending, equal keys in index order: what
    ``np.argsort(keys, kind="mergesort")`` gives. Keys here are distances, spread over a
    range about as wide as their number, so a counting sort does it in O(n + range); a
    range much wider than that falls back to a merge sort (:func:`_merge_order`). The
    repair's sort was its largest cost: on a 512² maze a merge sort here took as long as
    the rest of the repair (sampled with perf, BENCHMARKS.md)."""
    n = keys.shape[0]
    if n == 0:
        return np.arange(0)
    lo = keys[0]
    hi = keys[0]
    for i in range(1, n):
        k = keys[i]
        if k < lo:
            lo = k
        elif k > hi:
            hi = k
    span = hi - lo + 1
    if span > 4 * n + 1024:
        return _merge_order(keys)
    count = np.zeros(span + 1, np.int64)
    for i in range(n):
        count[keys[i] - lo + 1] += 1
    for j in range(1, span + 1):
        count[j] += count[j - 1]  # count[k - lo]: where key k's run starts
    idx = np.empty(n, np.int64)
    for i in range(n):
        j = keys[i] - lo
        idx[count[j]] = i
        count[j] += 1
    return idx


@njit(cache=True)
def _merge_order(keys):
    """:func:`stable_order` as a plain bottom-up merge sort (numba's generic one costs
    ~1.3 s of compilation)."""
    n = keys.shape[0]
    idx = np.arange(n)
    buf = np.empty(n, np.int64)
    width = 1
    while width < n:
        for lo in range(0, n, 2 * width):
            mid = min(lo + width, n)
            hi = min(lo + 2 * width, n)
            i, j, k = lo, mid, lo
            while i < mid and j < hi:
                if keys[idx[j]] < keys[idx[i]]:
                    buf[k] = idx[j]
                    j += 1
                else:
                    buf[k] = idx[i]
                    i += 1
                k += 1
            while i < mid:
                buf[k] = idx[i]
                i += 1
                k += 1
            while j < hi:
                buf[k] = idx[j]
                j += 1
                k += 1
        idx, buf = buf, idx
        width *= 2
    return idx


@njit(cache=True)
def repair_distances(nb, blocked, dist, queue, goal, s):
    """The distances after s's move was newly blocked (``blocked`` already says so), repaired
    where they change instead of re-run over every state; returns the states whose
    distance changed, or ``[-1]`` after a full BFS (a state lost its last route, so the set
    of reachable states, and with it ``queue``, changed).

    Unit-weight LPA*-style repair: (1) the states whose distance must grow are found level
    by level from s: a state one move further than an affected one, whose every move to a
    neighbour at its distance minus one leads into the affected set; (2) their new
    distances come from a multi-source search inside the set, each seeded by its best
    unaffected neighbour, merged in distance order (sorted seeds, then a FIFO). Cost:
    O(affected states), not O(states) (measured on mazes, where most new walls changed
    distances: see BENCHMARKS.md). ``queue`` keeps the reachable states, in an order no
    longer sorted by distance (:func:`learning.methods.rnh_ql_plus.optimism.refresh_values` needs
    only the set).

    The affected set is marked in ``dist`` itself, not in an array over every state (whose
    allocation and zeroing at each repair made the repair O(states) again: 9 us at 512²,
    39 us at 1024²): while it is found, an affected state holds ``-2 - its old distance``
    (at most -2; a state without a route holds -1, a routed one its distance >= 0); while
    it waits for its new distance, -2."""
    n_a = nb.shape[1]
    order = np.empty(64, np.int32)
    order[0] = s
    dist[s] = -2 - dist[s]
    n_aff = 1
    head = 0
    while head < n_aff:
        x = order[head]
        head += 1
        dx = -2 - dist[x]  # its old distance
        for b in range(n_a):
            v = nb[x, b]  # v reaches x by the opposite move
            if v < 0 or dist[v] != dx + 1 or blocked[v, back_move(b)]:
                continue  # (an affected v holds at most -2, never dx + 1)
            keep = False
            for c in range(n_a):
                w = nb[v, c]
                if w >= 0 and not blocked[v, c] and dist[w] == dx:  # unaffected, at dx
                    keep = True
                    break
            if not keep:
                dist[v] = -2 - dist[v]
                if n_aff == order.shape[0]:
                    grown = np.empty(2 * n_aff, np.int32)
                    for i in range(n_aff):  # a loop: a slice copy compiles numba's
                        grown[i] = order[i]  # shape-error formatting (~2 s cold)
                    order = grown
                order[n_aff] = v
                n_aff += 1
    order = order[:n_aff]
    seed_d = np.full(n_aff, -1, np.int64)
    for i in range(n_aff):
        v = order[i]
        best = -1
        for c in range(n_a):
            w = nb[v, c]
            if w >= 0 and not blocked[v, c] and dist[w] >= 0:  # routed and unaffected
                if best < 0 or dist[w] + 1 < best:
                    best = dist[w] + 1
        seed_d[i] = best
    for i in range(n_aff):
        dist[order[i]] = -2  # waiting for its new distance
    by_d = stable_order(seed_d)
    p = 0
    while p < n_aff and seed_d[by_d[p]] < 0:
        p += 1
    fifo = np.empty(n_a * n_aff + 1, np.int32)
    fifo_d = np.empty(n_a * n_aff + 1, np.int64)
    f_head, f_tail = 0, 0
    left = n_aff
    while left > 0 and (p < n_aff or f_head < f_tail):
        if f_head == f_tail or (p < n_aff and seed_d[by_d[p]] <= fifo_d[f_head]):
            v = order[by_d[p]]
            d = seed_d[by_d[p]]
            p += 1
        else:
            v = fifo[f_head]
            d = fifo_d[f_head]
            f_head += 1
        if dist[v] != -2:
            continue  # settled already, at a distance no larger
        dist[v] = d
        left -= 1
        for b in range(n_a):
            u = nb[v, b]
            if u >= 0 and dist[u] == -2 and not blocked[u, back_move(b)]:
                fifo[f_tail] = u
                fifo_d[f_tail] = d + 1
                f_tail += 1
    if left > 0:  # some state has no route left: rebuild the distances and the queue
        bfs_distances(nb, blocked, dist, queue, goal)
        return np.full(1, -1, np.int32)
    return order
