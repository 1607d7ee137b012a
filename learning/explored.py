"""HAQL's heuristic from exploration: the move toward G over the moves not yet known to fail.

Bianchi's HAQL acts on argmax[Q + xi * H], H favouring the heuristic move
pi_H(s). With a static heuristic (the Manhattan move) pi_H never changes, and
with xi = beta = 1 the heuristic move always wins the argmax, so the route is
fixed before learning starts. Here pi_H comes from the agent's own experience,
as "heuristics from exploration" do (Bianchi, Ribeiro & Costa 2008): the agent
knows the arena's cells (its :class:`learning.geometry.Geometry`) but not the
obstacles, assumes every move it has not seen fail is free (the free-space
assumption of D* Lite), and takes the move that starts a shortest route to G in
that optimistic map. Each bump it observes for the first time (the move left it
in its state) marks that move blocked and re-derives pi_H for every state by
one BFS from G: O(states) per *new* blocked move, nothing otherwise. The route
the agent follows therefore changes as it learns where the walls are.

Layout (HAQL's slots of :class:`learning.state.AgentState`):
``imap[s, 0]`` pi_H(s); ``imap[s, 1 + a]`` 1 when move a from s is known to fail;
``imap[s, 5 + a]`` the neighbour state of move a (-1 outside the arena);
``ilist[:nS]`` BFS distances, ``ilist[nS:2nS]`` the BFS queue, ``ilist[2nS]`` G.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from learning.geometry import Geometry

COL_PI, COL_BLOCKED, COL_NEXT = 0, 1, 5


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
                if imap[u, COL_BLOCKED + back] == 0:
                    ilist[u] = ilist[v] + 1
                    ilist[tail] = u
                    tail += 1
    for s in range(n):
        best, best_d = 0, -1
        for a in range(4):
            t = imap[s, COL_NEXT + a]
            if t < 0 or imap[s, COL_BLOCKED + a] != 0 or ilist[t] < 0:
                continue
            if best_d < 0 or ilist[t] < best_d:
                best, best_d = a, ilist[t]
        imap[s, COL_PI] = best


@njit(cache=True, inline="always")
def observe(imap, ilist, s, a, s2, terminated, explored):
    """After a move: a first bump (stayed in s) marks the move blocked and re-derives pi_H."""
    if explored and s2 == s and not terminated and imap[s, COL_BLOCKED + a] == 0:
        imap[s, COL_BLOCKED + a] = 1
        rederive(imap, ilist)
