"""HAQL's heuristic from exploration: the move toward G over the moves not yet known to fail.

Bianchi's HAQL acts on argmax[Q + xi * H], H favouring the heuristic move
pi_H(s). With a static heuristic (the Manhattan move) pi_H never changes, and
with xi = beta = 1 the heuristic move always wins the argmax, so the route is
fixed before learning starts. Here pi_H comes from the agent's own experience,
as "heuristics from exploration" do (Bianchi, Ribeiro & Costa 2008): the agent
knows the arena's cells (its :class:`learning.geometry.Geometry`) but not the
obstacles, assumes every move it has not seen fail is free (the free-space
assumption of D* Lite), and takes the move that starts a shortest route to G in
that optimistic map. When a move becomes blocked (below) pi_H is re-derived for
every state by one BFS from G: O(states) per change, nothing otherwise. The route
the agent follows therefore changes as it learns where the walls are.

A move is blocked while bumps are its most likely outcome: more bumps than
arrivals at its neighbour have been seen (the most-likely-outcome
determinization of a stochastic move, as FF-Replan's). With wheel noise and
carried pose (the physics world's ``noisy`` fidelity) a free move can fail now
and then, and a move past an obstacle's edge can get through now and then: one
unlucky bump does not wall off a route, one lucky pass does not open a wall. In
a deterministic world a move's outcome never changes, and this is the original
rule (blocked from its first bump, re-derived once per new blocked move).

Layout (HAQL's slots of :class:`learning.state.AgentState`):
``imap[s, 0]`` pi_H(s); ``imap[s, 1 + a]`` bumps minus arrivals seen for move a
from s (blocked when > 0);
``imap[s, 5 + a]`` the neighbour state of move a (-1 outside the arena);
``ilist[:nS]`` BFS distances, ``ilist[nS:2nS]`` the BFS queue, ``ilist[2nS]`` G.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from learning.geometry import Geometry

COL_PI, COL_BLOCKED, COL_NEXT = 0, 1, 5
COUNT_CAP = 1 << 30  # bumps minus arrivals saturate here (int32)


def init_explored(geom: Geometry, explored: bool) -> tuple[np.ndarray, np.ndarray]:
    """(imap int32[nS, 9], ilist int32[2 nS + 1]) of a fresh HAQL agent.

    ``explored``: pi_H from the free-space BFS (re-derived as bumps are seen);
    otherwise the static Manhattan move (Bianchi's original heuristic), filled in
    by the caller and never changed.
    """
    n = geom.n_states
    cells = geom.cells
    nx = int(cells[:, 0].max()) + 1
    ny = int(cells[:, 1].max()) + 1
    index = np.full((nx, ny), -1, dtype=np.int64)
    index[cells[:, 0], cells[:, 1]] = np.arange(n)
    imap = np.zeros((n, 9), dtype=np.int32)
    for a, (dx, dy) in enumerate(((0, 1), (0, -1), (-1, 0), (1, 0))):
        tx, ty = cells[:, 0] + dx, cells[:, 1] + dy
        inside = (tx >= 0) & (tx < nx) & (ty >= 0) & (ty < ny)
        imap[:, COL_NEXT + a] = np.where(inside, index[np.clip(tx, 0, nx - 1),
                                                       np.clip(ty, 0, ny - 1)], -1)
    ilist = np.zeros(2 * n + 1, dtype=np.int32)
    ilist[2 * n] = geom.goal
    if explored:
        rederive(imap, ilist)
    return imap, ilist


@njit(cache=True)
def rederive(imap, ilist):
    """pi_H for every state from one BFS from G over the moves not known to fail."""
    n = imap.shape[0]
    goal = ilist[2 * n]
    for s in range(n):
        ilist[s] = -1
    ilist[goal] = 0
    head, tail = n, n + 1
    ilist[n] = goal
    while head < tail:
        v = ilist[head]
        head += 1
        for a in range(4):
            u = imap[v, COL_NEXT + a]  # u is v's neighbour; u reaches v by the opposite move
            if u >= 0 and ilist[u] < 0:
                back = 1 if a == 0 else (0 if a == 1 else (3 if a == 2 else 2))
                if imap[u, COL_BLOCKED + back] <= 0:
                    ilist[u] = ilist[v] + 1
                    ilist[tail] = u
                    tail += 1
    for s in range(n):
        best, best_d = 0, -1
        for a in range(4):
            t = imap[s, COL_NEXT + a]
            if t < 0 or imap[s, COL_BLOCKED + a] > 0 or ilist[t] < 0:
                continue
            if best_d < 0 or ilist[t] < best_d:
                best, best_d = a, ilist[t]
        imap[s, COL_PI] = best


@njit(cache=True, inline="always")
def observe(imap, ilist, s, a, s2, terminated, explored):
    """After a move: count a bump (stayed in s) up and a move that reached its neighbour
    down; when the count's sign flips (the move's most likely outcome changed), re-derive
    pi_H. (A move that drifted into another cell tells nothing about this one.)"""
    if not explored:
        return
    col = COL_BLOCKED + a
    was = imap[s, col] > 0
    if s2 == imap[s, COL_NEXT + a]:
        if imap[s, col] > -COUNT_CAP:  # int32: a long run must not wrap round
            imap[s, col] -= 1
    elif s2 == s and not terminated:
        if imap[s, col] < COUNT_CAP:
            imap[s, col] += 1
    else:
        return
    if (imap[s, col] > 0) != was:
        rederive(imap, ilist)
