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
from learning.parts.tabular import (
    begin_plain,
    draw_below,
    least_key,
    least_seen_to_work,
    nth_least,
)
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
    keys: np.ndarray  # float64[nA]; scratch: each move's rank at the state in hand


def init_state(cfg: FSAReplan, geom: Geometry, rng: np.random.Generator) -> State:
    return State(cfg.params(), new_tally(),
                 np.zeros((geom.n_states, geom.n_actions), np.int32), new_free_space(geom),
                 new_move_reading(), np.zeros(geom.n_actions))


@njit(cache=True, inline="always")
def route_keys(nb, blocked, dist, bal, s, keys):
    """keys[a]: the rank of move a (lower is better; -1: no candidate): the distance to G of
    its neighbour over the moves believed free; where no move has such a route, its
    balance of bumps (any move that stays on the arena)."""
    found = False
    for a in range(nb.shape[1]):
        u = nb[s, a]
        keys[a] = -1.0 if u < 0 or blocked[s, a] or dist[u] < 0 else float(dist[u])
        found = found or keys[a] >= 0.0
    if not found:
        for a in range(nb.shape[1]):
            # >= 0: balances are capped at +-2^30
            keys[a] = -1.0 if nb[s, a] < 0 else float(bal[s, a] + (1 << 30))


@njit(**HOOK)
def act(st, s, rng):
    nb = st.free.neighbour
    blocked = st.free.blocked
    dist = st.free.distance
    bal = st.balance
    keys = st.keys
    if st.par.eps > 0.0 and rng.random() < st.par.eps:
        return rng.integers(0, nb.shape[1])
    route_keys(nb, blocked, dist, bal, s, keys)
    best, ties = least_key(keys)
    if ties == 0:  # no move stays on the arena (a one-cell arena)
        return 0
    return nth_least(keys, best, draw_below(rng, ties) if ties > 1 else 0)


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
    keys = st.keys
    route_keys(nb, blocked, dist, bal, s, keys)
    return least_seen_to_work(keys, bal[s], -1)


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
