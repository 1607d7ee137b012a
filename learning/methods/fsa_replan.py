"""A free-space replanner (``fsa-replan``): the shortest route on the optimistic map,
replanned after every move.

The reference a route learner in an unknown map is judged against: the free-space
assumption of D* Lite (Koenig & Likhachev 2002). The agent knows the arena's cells and G,
assumes every move it has not found blocked to be free, and always takes the first move
of a shortest route to G over that optimistic map. A bump blocks the move (the balance of
bumps and clean arrivals, read from the rewards as :mod:`learning.parts.move_reading`
says, so a noisy world's stray bump is outvoted by the move's later arrivals), and the
distances are repaired where the new wall changes them
(:func:`learning.parts.free_space.repair_distances`): the route is replanned after every
move that changes it, at the cost of the states it changes. There is nothing to learn
but the map: no values, no rewards beyond what they say of bumps.

Where no route is left over the moves believed free (a noisy world can block the only
gap), the least-bumped move is taken. ``eps`` adds random moves (0 by default: the
planner's own route).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import BaseParams, MethodConfig
from learning.geometry import Geometry
from learning.parts.free_space import (
    FreeSpace,
    bfs_distances,
    distances_change,
    new_free_space,
    repair_distances,
)
from learning.parts.move_reading import MoveReading, count_outcome, new_move_reading, read_move
from learning.parts.tabular import begin_plain, draw_below
from learning.parts.tally import Tally, new_tally

HOOK = dict(cache=True, inline="always")


@dataclass(frozen=True)
class FSAReplan(MethodConfig):
    """The shortest route on the optimistic map, replanned after every move."""

    name: ClassVar[str] = "FSA-REPLAN"
    cli: ClassVar[str] = "fsa-replan"
    eps: float = 0.0  # probability of a uniformly random move (0: the planner's route)
    IGNORED: ClassVar[tuple[str, ...]] = ("alpha", "gamma")  # no values are learned


class State(NamedTuple):
    par: BaseParams
    tally: Tally
    balance: np.ndarray  # int32[nS, nA]; bumps minus clean arrivals (blocked when > 0)
    free: FreeSpace  # the optimistic map and every cell's distance to G over it
    reading: MoveReading  # the rewards of a stay and of a clean arrival


def init_state(cfg: FSAReplan, geom: Geometry, rng: np.random.Generator) -> State:
    return State(cfg.params(), new_tally(),
                 np.zeros((geom.n_states, geom.n_actions), np.int32), new_free_space(geom),
                 new_move_reading())


@njit(cache=True, inline="always")
def _key(nb, blocked, dist, bal, s, a, by_route):
    """A move's rank (lower is better), or -1 for a move that is not a candidate: its
    neighbour's distance to G over the believed-free moves (``by_route``), else its
    balance of bumps (any move that stays on the arena)."""
    u = nb[s, a]
    if u < 0:
        return -1
    if by_route:
        return -1 if blocked[s, a] or dist[u] < 0 else dist[u]
    return bal[s, a] + (1 << 30)  # >= 0: balances are capped at +-2^30


@njit(cache=True, inline="always")
def route_moves(nb, blocked, dist, bal, s):
    """(best rank, how many moves share it, by_route): the first moves of the shortest
    routes to G over the moves believed free; without such a route the least-bumped
    moves (``by_route`` False)."""
    by_route = True
    for _ in range(2):
        best, ties = -1, 0
        for a in range(nb.shape[1]):
            k = _key(nb, blocked, dist, bal, s, a, by_route)
            if k < 0:
                continue
            if best < 0 or k < best:
                best, ties = k, 1
            elif k == best:
                ties += 1
        if ties > 0:
            return best, ties, by_route
        by_route = False
    return 0, 0, False


@njit(cache=True, inline="always")
def nth_move(nb, blocked, dist, bal, s, best, by_route, n):
    """The ``n``-th (0-based, in action order) move of rank ``best``."""
    for a in range(nb.shape[1]):
        if _key(nb, blocked, dist, bal, s, a, by_route) == best:
            if n == 0:
                return a
            n -= 1
    return 0


@njit(**HOOK)
def act(st, s, rng):
    nb = st.free.neighbour
    blocked = st.free.blocked
    dist = st.free.distance
    bal = st.balance
    if st.par.eps > 0.0 and rng.random() < st.par.eps:
        return rng.integers(0, nb.shape[1])
    best, ties, by_route = route_moves(nb, blocked, dist, bal, s)
    if ties == 0:  # no move stays on the arena (a one-cell arena)
        return 0
    n = draw_below(rng, ties) if ties > 1 else 0
    return nth_move(nb, blocked, dist, bal, s, best, by_route, n)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """Read the move's outcome; a move newly blocked repairs the distances it changes, a
    move free again (a noisy world's stray bump outvoted) re-runs the BFS."""
    bal = st.balance
    nb = st.free.neighbour
    blocked = st.free.blocked
    dist = st.free.distance
    queue = st.free.queue
    goal = st.free.goal[0]
    clean = read_move(st.reading.r_stay, st.reading.r_clean, s, r, s2, terminated)
    flip = count_outcome(bal, nb, s, a, s2, clean)
    if flip > 0:
        blocked[s, a] = True
        if distances_change(nb, dist, blocked, s, a):
            repair_distances(nb, blocked, dist, queue, goal, s)
    elif flip < 0:
        blocked[s, a] = False
        bfs_distances(nb, blocked, dist, queue, goal)


begin = begin_plain


@njit(**HOOK)
def exploit(st, s):
    nb = st.free.neighbour
    blocked = st.free.blocked
    dist = st.free.distance
    bal = st.balance
    best, ties, by_route = route_moves(nb, blocked, dist, bal, s)
    return nth_move(nb, blocked, dist, bal, s, best, by_route, 0) if ties > 0 else 0


def q_table(st: State) -> np.ndarray:
    """float64[nS, nA]: minus the moves to G through each move over the optimistic map (a
    blocked move, or one into a cell with no route, minus the number of cells)."""
    nb, dist = st.free.neighbour, st.free.distance
    n = dist.shape[0]
    through = np.where(nb >= 0, dist[np.maximum(nb, 0)], -1)
    cost = np.where((through >= 0) & ~st.free.blocked, 1 + through, n)
    return -cost.astype(np.float64)


def n_states(st: State) -> int:
    return int(st.free.distance.shape[0])
