"""R-max with Φ = the free-space distance (``r-max``; Brafman & Tennenholtz 2002, shaped as
Asmuth, Littman & Zinkov 2008 shape it).

Model-based RL with optimism in the face of the unknown. A move (s, a) is *known* once
tried ``m`` times; its model is then frozen: the share of those tries that bumped,
p̂ (the move reading of :mod:`learning.parts.move_reading`, so a noisy world's bump that
still arrives counts as a bump). An untried move is valued optimistically by a potential:
Asmuth et al. replace R-max's ``R_max / (1 - gamma)`` by an admissible Φ, here the
free-space distance of the cell it heads for (the arena's BFS distance to G with no wall
known: Manhattan's on a rectangle). The agent acts greedily on the costs to G of that
model, in moves:

    cost(s) = min over moves a of   1 + Φ(s')                  (a untried: tried < m)
                                    1 / (1 - p̂) + cost(s')     (a known, p̂ < 1)

(``1 / (1 - p̂)``: the expected tries of a move that bumps with probability p̂; a move
known to bump every time is no move), and replans when a move becomes known, as R-max
does. With rewards +100 at G and nothing else (goal-only) these costs order the moves as
R-max's discounted values do; the costs keep the planner free of ``gamma`` (IGNORED).

How it differs from :mod:`.fsa_replan`: the free-space replanner assumes every move it has
not seen fail is free and plans through the walls it knows everywhere; R-max trusts only
the moves it has tried and values the unknown by Φ alone, so beyond its known region it
sees no wall at all. It explores more and plans less. And a noisy world's stray bump
blocks a move for good when ``m = 1`` (the model is frozen once known); larger ``m``
averages, at ``m`` tries of every blocked move.

Planning: an A* search from the agent's cell over the known moves, whose leaves are the
untried moves (key: the cost through them) and G (consistent: Φ changes by at most one a
move, and every known move costs at least one). The route found is followed until a move
becomes known or the agent is not where the route said: one search per newly known move,
each as large as the known region the route has to leave. The greedy test and the
readers use every cell's cost at once, from one multi-source Dijkstra over the known
moves backwards (seeded by the untried moves and G), recomputed when the model changed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import MethodConfig, params_tuple
from learning.geometry import Geometry
from learning.parts.free_space import back_move, new_free_space
from learning.parts.move_reading import MoveReading, new_move_reading, read_move
from learning.parts.priority_queue import PairQueue, new_pair_queue, pop, push
from learning.parts.tabular import begin_plain, least_seen_to_work
from learning.parts.tally import Tally, new_tally

HOOK = dict(cache=True, inline="always")
NO_MOVE = -1.0  # a key marking a move that is no candidate (off the arena, or always bumps)

Params = params_tuple("Params", __name__, m=int)


@dataclass(frozen=True)
class RMax(MethodConfig):
    """R-max: greedy on the costs of the known moves' model, an untried move valued by the
    free-space distance of the cell it heads for (Asmuth et al.'s admissible Φ)."""

    name: ClassVar[str] = "R-max"
    cli: ClassVar[str] = "r-max"
    eps: float = 0.0  # probability of a uniformly random move (0: R-max's own)
    m: int = 1  # tries after which a move's outcome is known and its model frozen [tries]
    IGNORED: ClassVar[tuple[str, ...]] = ("alpha", "gamma")  # a model is learned, not Q

    params_type: ClassVar[type] = Params


class Plan(NamedTuple):
    moves: np.ndarray  # int8[nS]; the route being followed, first move first
    length: np.ndarray  # int64[1]; its moves
    next: np.ndarray  # int64[1]; the index of the next move to take
    at: np.ndarray  # int64[1]; the cell the route expects the agent in (-1: no route)
    version: np.ndarray  # int64[1]; the model's version the route was planned on


class Search(NamedTuple):
    """Scratch of the searches (derived: rebuilt empty, never stored)."""

    g: np.ndarray  # float64[nS]; cost from the search's root (A*) or to G (Dijkstra)
    stamp: np.ndarray  # int64[nS]; the search that last set g (older: unset)
    closed: np.ndarray  # int64[nS]; the search that last closed the cell
    parent: np.ndarray  # int32[nS]; the cell the best route came from
    via: np.ndarray  # int8[nS]; the move from the parent
    epoch: np.ndarray  # int64[1]; searches made
    open: PairQueue  # the open cells, largest -f first


class State(NamedTuple):
    par: Params
    tally: Tally
    neighbour: np.ndarray  # int32[nS, nA]; the arena cell each move heads for (-1: off)
    phi: np.ndarray  # float64[nS]; the free-space distance to G (no wall known) [moves]
    tries: np.ndarray  # int32[nS, nA]; tries of each move, up to m (then known)
    clean: np.ndarray  # int32[nS, nA]; clean arrivals among those tries (the rest bumped)
    version: np.ndarray  # int64[1]; moves that became known (the model's version)
    plan: Plan  # the route the behaviour follows (stored: a resumed run follows it too)
    reading: MoveReading  # the rewards of a stay and of a clean arrival
    cost: np.ndarray  # float64[nS]; every cell's cost to G at ``cost_version`` (scratch)
    cost_version: np.ndarray  # int64[1]; the version ``cost`` was computed at (-1: none)
    search: Search
    keys: np.ndarray  # float64[nA]; scratch: each move's cost at the state in hand


DERIVED = ("cost", "cost_version", "search.g", "search.stamp", "search.closed",
           "search.parent", "search.via", "search.epoch", "search.open.key",
           "search.open.pair", "search.open.where", "search.open.size")


def init_state(cfg: RMax, geom: Geometry, rng: np.random.Generator) -> State:
    n_s, n_a = geom.n_states, geom.n_actions
    free = new_free_space(geom)  # nothing blocked: the arena's own distances
    phi = np.where(free.distance >= 0, free.distance, n_s).astype(np.float64)
    plan = Plan(np.zeros(n_s, np.int8), np.zeros(1, np.int64), np.zeros(1, np.int64),
                np.full(1, -1, np.int64), np.full(1, -1, np.int64))
    search = Search(np.zeros(n_s), np.zeros(n_s, np.int64), np.zeros(n_s, np.int64),
                    np.zeros(n_s, np.int32), np.zeros(n_s, np.int8), np.zeros(1, np.int64),
                    new_pair_queue(n_s))
    return State(cfg.params(), new_tally(), free.neighbour, phi,
                 np.zeros((n_s, n_a), np.int32), np.zeros((n_s, n_a), np.int32),
                 np.zeros(1, np.int64), plan, new_move_reading(), np.zeros(n_s),
                 np.full(1, -1, np.int64), search, np.zeros(n_a))


@njit(cache=True, inline="always")
def known_weight(tries, clean, s, a):
    """The expected cost of known move (s, a), tries over clean arrivals [moves]; NO_MOVE
    when it always bumps."""
    c = clean[s, a]
    return NO_MOVE if c == 0 else tries[s, a] / c


@njit(cache=True)
def _clear(q):
    """Empty the open queue (the cells left in it are unmarked)."""
    for i in range(q.size[0]):
        q.where[q.pair[i]] = -1
    q.size[0] = 0


@njit(cache=True)
def plan_route(st, s0):
    """A* from ``s0`` to the cheapest leaf (an untried move, or G); writes the route into
    ``st.plan`` and returns its first move (-1: no leaf is reachable)."""
    nb = st.neighbour
    phi = st.phi
    tries = st.tries
    clean = st.clean
    m = st.par.m
    se = st.search
    q = se.open
    g, stamp, closed, parent, via = se.g, se.stamp, se.closed, se.parent, se.via
    se.epoch[0] += 1
    ep = se.epoch[0]
    g[s0] = 0.0
    stamp[s0] = ep
    push(q.key, q.pair, q.where, q.size, s0, -phi[s0])
    best, leaf, leaf_move = np.inf, -1, -1  # the cheapest leaf found: cost, cell, move
    while q.size[0] > 0 and -q.key[0] < best:
        x = pop(q.key, q.pair, q.where, q.size)
        closed[x] = ep
        if phi[x] == 0.0:  # G, the one cell at free-space distance 0
            if g[x] < best:
                best, leaf, leaf_move = g[x], x, -1
            continue
        for a in range(nb.shape[1]):
            u = nb[x, a]
            if u < 0:
                continue
            if tries[x, a] < m:
                c = g[x] + 1.0 + phi[u]
                if c < best:
                    best, leaf, leaf_move = c, x, a
                continue
            w = known_weight(tries, clean, x, a)
            if w < 0.0 or closed[u] == ep:
                continue
            c = g[x] + w
            if stamp[u] != ep or c < g[u]:
                g[u] = c
                stamp[u] = ep
                parent[u] = x
                via[u] = a
                push(q.key, q.pair, q.where, q.size, u, -(c + phi[u]))
    _clear(q)
    plan = st.plan
    if leaf < 0:
        plan.at[0] = -1
        return -1
    n = 0
    x = leaf
    while x != s0:
        n += 1
        x = parent[x]
    total = n + (1 if leaf_move >= 0 else 0)
    if total == 0:  # s0 is G: nothing to do (an episode ends there)
        plan.at[0] = -1
        return -1
    if leaf_move >= 0:
        plan.moves[n] = leaf_move
    x = leaf
    for i in range(n - 1, -1, -1):
        plan.moves[i] = via[x]
        x = parent[x]
    plan.length[0] = total
    plan.next[0] = 0
    plan.version[0] = st.version[0]
    plan.at[0] = s0
    return plan.moves[0]


@njit(cache=True)
def refresh_costs(st):
    """Every cell's cost to G under the current model, when the model changed since the
    last call: a multi-source Dijkstra backwards over the known moves, each cell seeded by
    its cheapest untried move (1 + Φ of the cell it heads for) and G by 0."""
    if st.cost_version[0] == st.version[0]:
        return
    nb = st.neighbour
    phi = st.phi
    tries = st.tries
    clean = st.clean
    m = st.par.m
    cost = st.cost
    se = st.search
    q = se.open
    closed = se.closed
    se.epoch[0] += 1
    ep = se.epoch[0]
    n_s, n_a = nb.shape
    for x in range(n_s):
        c = 0.0 if phi[x] == 0.0 else np.inf
        for a in range(n_a):
            u = nb[x, a]
            if u >= 0 and tries[x, a] < m and 1.0 + phi[u] < c:
                c = 1.0 + phi[u]
        cost[x] = c
        if c < np.inf:
            push(q.key, q.pair, q.where, q.size, x, -c)
    while q.size[0] > 0:
        x = pop(q.key, q.pair, q.where, q.size)
        closed[x] = ep
        for b in range(n_a):
            y = nb[x, back_move(b)]  # y reaches x by move b
            if y < 0 or closed[y] == ep or nb[y, b] != x or tries[y, b] < m:
                continue
            w = known_weight(tries, clean, y, b)
            if w < 0.0:
                continue
            c = cost[x] + w
            if c < cost[y]:
                cost[y] = c
                push(q.key, q.pair, q.where, q.size, y, -c)
    _clear(q)
    st.cost_version[0] = st.version[0]


@njit(cache=True, inline="always")
def move_costs(st, s, keys):
    """keys[a]: the cost to G through move a at s under the model (NO_MOVE: none)."""
    nb = st.neighbour
    for a in range(nb.shape[1]):
        u = nb[s, a]
        if u < 0:
            keys[a] = NO_MOVE
        elif st.tries[s, a] < st.par.m:
            keys[a] = 1.0 + st.phi[u]
        else:
            w = known_weight(st.tries, st.clean, s, a)
            keys[a] = NO_MOVE if w < 0.0 or st.cost[u] == np.inf else w + st.cost[u]


@njit(**HOOK)
def act(st, s, rng):
    n_a = st.neighbour.shape[1]
    if st.par.eps > 0.0 and rng.random() < st.par.eps:
        return rng.integers(0, n_a)
    plan = st.plan
    if (plan.at[0] == s and plan.version[0] == st.version[0]
            and plan.next[0] < plan.length[0]):
        a = plan.moves[plan.next[0]]
    else:
        a = plan_route(st, s)
        if a < 0:  # no leaf reachable (every way out bumped): any move, a bump will tell
            return rng.integers(0, n_a)
    plan.next[0] += 1
    u = st.neighbour[s, a]
    plan.at[0] = u if u >= 0 else s
    return a


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """Count the try; the m-th freezes the move's model and makes the model a new version
    (the route is replanned at the next act)."""
    clean = read_move(st.reading.r_stay, st.reading.r_clean, s, r, s2, terminated)
    if st.tries[s, a] < st.par.m:
        st.tries[s, a] += 1
        if clean:
            st.clean[s, a] += 1
        if st.tries[s, a] == st.par.m:
            st.version[0] += 1


begin = begin_plain


@njit(**HOOK)
def exploit(st, s):
    """The move of least cost under the model; among ties, a known move that has worked
    first (:func:`learning.parts.tabular.least_seen_to_work`'s rule)."""
    refresh_costs(st)
    move_costs(st, s, st.keys)
    return least_seen_to_work(st.keys, st.clean[s], 1)


def q_table(st: State) -> np.ndarray:
    """float64[nS, nA]: minus each move's cost to G under the model (a move that always
    bumps or leads nowhere: minus the number of cells)."""
    refresh_costs(st)
    n_s, n_a = st.neighbour.shape
    keys = np.zeros(n_a)
    out = np.empty((n_s, n_a))
    for s in range(n_s):
        move_costs(st, s, keys)
        out[s] = np.where(keys >= 0.0, -keys, -float(n_s))
    return out


def n_states(st: State) -> int:
    return int(st.phi.shape[0])
