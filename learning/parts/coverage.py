"""Coverage: walk to the cells never visited, so the policy is learned where no start is.

Under the paper's protocol (every episode starts at a uniformly drawn free cell) an agent
that heads straight for G learns routes only on the cells between its starts and G. S,
the far end of the map's diameter, lies upstream of almost nothing: on the 256² tuning
maps a third of the cells were never entered in 2048 episodes, and the greedy test from
S walked through unvisited cells until the optimistic model's first unknown wall (a tie
between two moves the model held equally short, one of them into a wall the agent
never bumped).

A coverage walk spends the first ``explore_steps`` steps of each episode reaching cells
never visited (no move tried there yet, read from the move model, so nothing new is
stored): into an unvisited neighbour where there is one, else down a BFS field of
distances to the nearest unvisited cell over the moves not known to be blocked. Cells
the learner knows only as states include obstacle cells, so the walk also bumps every
obstacle cell it can reach from each free side: it maps the walls, which is what a test
through the region needs. The field is one multi-source BFS (O(states)), re-run only when
the walk finds it stale (it stands on a source, or no move goes one step down) and a
local search of ``NEARBY_CELLS`` cells finds no unvisited cell either; once no unvisited
cell is reachable the walk is over for good.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from learning.geometry import Geometry
from learning.parts.free_space import back_move
from learning.parts.tabular import draw_below

NEARBY_CELLS = 1024  # a local search's limit before the field is re-run [cells]
WALK_PER_SIDE = 4  # the walk's steps an episode per cell of the arena's longer side
AUTO_WALK = -1  # explore_steps = AUTO_WALK: WALK_PER_SIDE x the arena's longer side


def walk_budget(explore_steps: int, geom: Geometry) -> int:
    """The walk's steps an episode: ``explore_steps``, or for :data:`AUTO_WALK` one derived
    from the map, ``WALK_PER_SIDE`` x the arena's longer side in cells.

    Why the side: the held-out studies give a run ``8 x the side`` episodes, so the walk
    totals 32 x the side² steps over a run, a fixed multiple of the arena's cells at every
    size. A constant does not scale: 1000 steps were chosen at 256² (about 4 x the side);
    at 512² the caves settled sooner with 2000 than with 1000 (830 against 970 episodes,
    docs/results/heldout.walk-512.json), and 4000 never settled there, because a walk as
    long as the episode (4 x the 998-move route) left no step to reach G.
    """
    if explore_steps != AUTO_WALK:
        return int(explore_steps)
    xmin, ymin, xmax, ymax = geom.bounds_m
    side = max(xmax - xmin, ymax - ymin) / geom.cell_size_m
    return int(WALK_PER_SIDE * round(side))


class Coverage(NamedTuple):
    distance: np.ndarray  # int32[nS]; moves to the nearest unvisited cell (-1: none reachable)
    queue: np.ndarray  # int32[nS]; BFS scratch
    left: np.ndarray  # int64[1]; coverage steps left in this episode
    done: np.ndarray  # bool[1]; no unvisited cell is reachable any more
    mark: np.ndarray  # int64[nS]; the local search that last reached the cell
    first: np.ndarray  # int8[nS]; the local search's first move towards the cell
    searches: np.ndarray  # int64[1]; local searches made (the marks' epoch)


def new_coverage(n_s: int) -> Coverage:
    return Coverage(np.full(n_s, -1, np.int32),
                    np.zeros(n_s, np.int32), np.zeros(1, np.int64), np.zeros(1, np.bool_),
                    np.zeros(n_s, np.int64), np.zeros(n_s, np.int8), np.zeros(1, np.int64))


@njit(cache=True, inline="always")
def unvisited(succ, goal, s):
    """No move was ever tried from s (the move model's successor table is empty there), and
    s is not G (entered, never left: walking into it would end the episode's walk)."""
    if s == goal:
        return False
    for a in range(succ.shape[1]):
        if succ[s, a] >= 0:
            return False
    return True


@njit(cache=True)
def unvisited_distances(nb, blocked, succ, goal, dist, queue):
    """dist[s] = moves from s to the nearest unvisited cell over moves not blocked (-1: none
    reachable); one BFS back from every unvisited cell at once."""
    tail = 0
    for s in range(dist.shape[0]):
        if unvisited(succ, goal, s):
            dist[s] = 0
            queue[tail] = s
            tail += 1
        else:
            dist[s] = -1
    head = 0
    while head < tail:
        v = queue[head]
        head += 1
        for a in range(nb.shape[1]):
            u = nb[v, a]  # u reaches v by the opposite move
            if u < 0 or dist[u] >= 0 or blocked[u, back_move(a)]:
                continue
            dist[u] = dist[v] + 1
            queue[tail] = u
            tail += 1


@njit(cache=True, inline="always")
def _fresh_neighbour(nb, blocked, succ, goal, s, rng):
    """A move from s into an unvisited neighbour not known blocked, drawn among them (-1:
    none)."""
    n = 0
    for a in range(nb.shape[1]):
        u = nb[s, a]
        if u >= 0 and not blocked[s, a] and unvisited(succ, goal, u):
            n += 1
    if n == 0:
        return -1
    k = draw_below(rng, n)
    for a in range(nb.shape[1]):
        u = nb[s, a]
        if u >= 0 and not blocked[s, a] and unvisited(succ, goal, u):
            if k == 0:
                return a
            k -= 1
    return -1


@njit(cache=True, inline="always")
def _downhill(nb, blocked, dist, s):
    """A move from s one step down the field (-1: none, the field is stale here)."""
    d = dist[s]
    if d <= 0:
        return -1
    for a in range(nb.shape[1]):
        u = nb[s, a]
        if u >= 0 and not blocked[s, a] and dist[u] == d - 1:
            return a
    return -1


@njit(cache=True)
def _nearby(nb, blocked, succ, goal, queue, mark, first, searches, s, limit):
    """The first move of a shortest walk from s to an unvisited cell, found by a BFS forward
    from s that gives up after ``limit`` cells (-1). A bump next to the frontier leaves
    the field stale, and the next unvisited cell is then a few moves away: this finds it
    in O(those moves squared), not O(states)."""
    searches[0] += 1
    epoch = searches[0]
    mark[s] = epoch
    queue[0] = s
    head, tail = 0, 1
    while head < tail and tail < limit:
        v = queue[head]
        head += 1
        for a in range(nb.shape[1]):
            u = nb[v, a]
            if u < 0 or blocked[v, a] or mark[u] == epoch:
                continue
            mark[u] = epoch
            first[u] = a if v == s else first[v]
            if unvisited(succ, goal, u):
                return first[u]
            queue[tail] = u
            tail += 1
    return -1


@njit(cache=True)
def coverage_move(nb, blocked, succ, goal, dist, queue, done, mark, first, searches, s, rng):
    """The coverage walk's move from s (-1: nothing left to cover from here)."""
    a = _fresh_neighbour(nb, blocked, succ, goal, s, rng)
    if a >= 0:
        return a
    a = _downhill(nb, blocked, dist, s)
    if a >= 0:
        return a
    a = _nearby(nb, blocked, succ, goal, queue, mark, first, searches, s, NEARBY_CELLS)
    if a >= 0:
        return a
    unvisited_distances(nb, blocked, succ, goal, dist, queue)
    if dist[s] < 0:  # no unvisited cell is reachable from here: nor from anywhere the
        done[0] = True  # agent can be (it moves only within its component of the model)
        return -1
    return _downhill(nb, blocked, dist, s)
