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

from learning.geometry import Geometry

ACTION_DELTAS = ((0, 1), (0, -1), (-1, 0), (1, 0))  # the learners' actions: up, down, left, right


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
    a named tuple's fields once, at their top; see :mod:`learning.rnh_ql_plus.rules`)."""
    for s in range(dist.shape[0]):
        dist[s] = -1
    dist[goal] = 0
    queue[0] = goal
    head, tail = 0, 1
    while head < tail:
        v = queue[head]
        head += 1
        for a in range(nb.shape[1]):
            u = nb[v, a]  # v's neighbour; u reaches v by the opposite move
            if u < 0 or dist[u] >= 0:
                continue
            if blocked[u, back_move(a)]:
                continue
            dist[u] = dist[v] + 1
            queue[tail] = u
            tail += 1


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
