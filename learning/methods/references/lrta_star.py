"""LRTA* (``lrta-star``, Korf 1990): real-time search that learns a heuristic over trials.

The classic way to learn a route by repeated trials in a map that is not known: each cell
holds an estimate h(s) of its moves to G, first the Manhattan distance (admissible on the
4-connected grid); at each step the agent takes the move that minimises 1 + h(s') over the
moves it believes free (ties at random) and raises h(s) to that minimum (never lowers
it). The estimates rise towards the true distances along the routes tried, and the greedy
route converges to a shortest one after enough trials from the same start (Korf's
theorem, for admissible initial values and a safely explorable map).

Which moves are free is learned as :mod:`learning.methods.fsa_replan` learns it: the
balance of bumps and clean arrivals, read from the rewards
(:mod:`learning.parts.move_reading`). Without a free-space map's distances, LRTA* pays its
way out of every dead end one update at a time: it is the learning-by-trials reference, the
free-space replanner the planning one. ``eps`` adds random moves (0 by default).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import BaseParams, MethodConfig
from learning.geometry import Geometry
from learning.parts.free_space import arena_neighbours
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
class LRTAStar(MethodConfig):
    """Korf's LRTA*: greedy on 1 + h(s'), h(s) raised to that minimum after each move."""

    name: ClassVar[str] = "LRTA*"
    cli: ClassVar[str] = "lrta-star"
    eps: float = 0.0  # probability of a uniformly random move (0: LRTA*'s own)
    IGNORED: ClassVar[tuple[str, ...]] = ("alpha", "gamma")  # h is learned, not Q


class State(NamedTuple):
    par: BaseParams
    tally: Tally
    h: np.ndarray  # float64[nS]; the estimated moves to G (Manhattan at first; never lowered)
    neighbour: np.ndarray  # int32[nS, nA]; the arena cell each move heads for (-1: off)
    blocked: np.ndarray  # bool[nS, nA]; moves believed blocked (balance > 0)
    balance: np.ndarray  # int32[nS, nA]; bumps minus clean arrivals
    reading: MoveReading  # the rewards of a stay and of a clean arrival
    keys: np.ndarray  # float64[nA]; scratch: each move's 1 + h(s') at the state in hand


def init_state(cfg: LRTAStar, geom: Geometry, rng: np.random.Generator) -> State:
    cells = geom.cells
    h = np.abs(cells - cells[geom.goal]).sum(axis=1).astype(np.float64)
    n_s, n_a = geom.n_states, geom.n_actions
    return State(cfg.params(), new_tally(), h, arena_neighbours(geom),
                 np.zeros((n_s, n_a), np.bool_), np.zeros((n_s, n_a), np.int32),
                 new_move_reading(), np.zeros(n_a))


@njit(cache=True, inline="always")
def lookaheads(nb, blocked, h, s, keys):
    """keys[a] = 1 + h(s') through move a; -1 for a move believed blocked or off the arena."""
    for a in range(nb.shape[1]):
        u = nb[s, a]
        keys[a] = -1.0 if u < 0 or blocked[s, a] else 1.0 + h[u]


@njit(**HOOK)
def act(st, s, rng):
    nb = st.neighbour
    blocked = st.blocked
    h = st.h
    keys = st.keys
    if st.par.eps > 0.0 and rng.random() < st.par.eps:
        return rng.integers(0, nb.shape[1])
    lookaheads(nb, blocked, h, s, keys)
    best, ties = least_key(keys)
    if ties == 0:  # every move believed blocked: any move (a bump will tell)
        return rng.integers(0, nb.shape[1])
    return nth_least(keys, best, draw_below(rng, ties) if ties > 1 else 0)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """Learn whether the move is blocked, then LRTA*'s rule: h(s) = max(h(s), min_a 1 +
    h(s')) over the moves believed free (after this move's lesson)."""
    nb = st.neighbour
    blocked = st.blocked
    bal = st.balance
    h = st.h
    keys = st.keys
    clean = read_move(st.reading.r_stay, st.reading.r_clean, s, r, s2, terminated)
    flip = count_outcome(bal, nb, s, a, s2, clean)
    if flip != 0:
        blocked[s, a] = flip > 0
    lookaheads(nb, blocked, h, s, keys)
    best, ties = least_key(keys)
    if ties > 0 and best > h[s]:
        h[s] = best


begin = begin_plain


@njit(**HOOK)
def exploit(st, s):
    nb = st.neighbour
    blocked = st.blocked
    h = st.h
    keys = st.keys
    lookaheads(nb, blocked, h, s, keys)
    return least_seen_to_work(keys, st.balance[s], -1)


def q_table(st: State) -> np.ndarray:
    """float64[nS, nA]: minus 1 + h(s') of each move (a blocked move: minus 1 + h(s), a
    move that stays)."""
    nb = st.neighbour
    through = st.h[np.maximum(nb, 0)]
    stay = np.broadcast_to(st.h[:, None], nb.shape)
    return -(1.0 + np.where((nb >= 0) & ~st.blocked, through, stay))



def n_states(st: State) -> int:
    return int(st.h.shape[0])
