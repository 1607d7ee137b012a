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

Planning: every cell's cost to G is kept exact for the current model, incrementally.
One multi-source Dijkstra over the known moves backwards (seeded by the untried moves and
G) sets them at a run's first move (and after a resume, or a warm start's switch of Φ).
After that, a move that becomes known changes one cell's look-ahead, and an LPA*-style
repair (Koenig, Likhachev & Furcy 2004) re-settles only the cells whose cost it changes,
lazily: up to the agent's own cost (D* Lite's stop), everywhere only when a reader needs
every cell (the greedy test's table, a warm start's switch). Most newly known moves change
nothing: a free move into ground not yet visited costs 1 + Φ both ways. So the work a
run spends planning grows with the walls it finds, not with the moves it learns (an A*
from scratch at every newly known move, the first version here, took minutes a 512²
run). The behaviour is then greedy on these costs, one look-ahead a step. Its rule for
ties: among moves of equal cost, the first untried one (so of equally cheap unknowns the
nearest is tried now), else the greedy test's rule, the first known to work, else the
first in action order. The costs are the one fixed point of the model's Bellman
equation, so the field settled everywhere equals a Dijkstra's from scratch number for
number (a test checks it), and every cost the behaviour reads is already exact; a resumed
run (which rebuilds the field from scratch) acts as the uninterrupted one does.
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
from learning.parts.priority_queue import PairQueue, drop, new_pair_queue, place, pop, push
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


class Field(NamedTuple):
    """Scratch of the cost field's upkeep (derived: rebuilt empty, never stored)."""

    rhs: np.ndarray  # float64[nS]; each cell's one-move look-ahead cost (LPA*'s rhs)
    closed: np.ndarray  # int64[nS]; the Dijkstra from scratch that last closed the cell
    epoch: np.ndarray  # int64[1]; Dijkstras from scratch made
    open: PairQueue  # the cells to settle, the least min(cost, rhs) first (key: minus it)


class State(NamedTuple):
    par: Params
    tally: Tally
    neighbour: np.ndarray  # int32[nS, nA]; the arena cell each move heads for (-1: off)
    phi: np.ndarray  # float64[nS]; the free-space distance to G (no wall known) [moves]
    tries: np.ndarray  # int32[nS, nA]; tries of each move, up to m (then known)
    clean: np.ndarray  # int32[nS, nA]; clean arrivals among those tries (the rest bumped)
    version: np.ndarray  # int64[1]; moves that became known (the model's version)
    reading: MoveReading  # the rewards of a stay and of a clean arrival
    cost: np.ndarray  # float64[nS]; every cell's cost to G at ``cost_version`` (scratch)
    cost_version: np.ndarray  # int64[1]; the version ``cost`` is exact for (-1: none)
    field: Field
    keys: np.ndarray  # float64[nA]; scratch: each move's cost at the state in hand


DERIVED = ("cost", "cost_version", "field.rhs", "field.closed", "field.epoch",
           "field.open.key", "field.open.pair", "field.open.where", "field.open.size")


def init_state(cfg: RMax, geom: Geometry, rng: np.random.Generator) -> State:
    n_s, n_a = geom.n_states, geom.n_actions
    free = new_free_space(geom)  # nothing blocked: the arena's own distances
    phi = np.where(free.distance >= 0, free.distance, n_s).astype(np.float64)
    field = Field(np.zeros(n_s), np.zeros(n_s, np.int64), np.zeros(1, np.int64),
                  new_pair_queue(n_s))
    return State(cfg.params(), new_tally(), free.neighbour, phi,
                 np.zeros((n_s, n_a), np.int32), np.zeros((n_s, n_a), np.int32),
                 np.zeros(1, np.int64), new_move_reading(), np.zeros(n_s),
                 np.full(1, -1, np.int64), field, np.zeros(n_a))


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
    fd = st.field
    q = fd.open
    closed = fd.closed
    _clear(q)  # repairs still pending: the costs are recomputed from scratch
    fd.epoch[0] += 1
    ep = fd.epoch[0]
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
    fd.rhs[:] = cost  # settled: every cell's look-ahead is its cost
    st.cost_version[0] = st.version[0]


@njit(cache=True)
def look_ahead(st, x):
    """Cell x's cost through its best move under the model (LPA*'s rhs): an untried move
    1 + Φ of where it heads, a known one its expected tries plus the cost of where it
    leads; 0 at G."""
    if st.phi[x] == 0.0:
        return 0.0
    nb = st.neighbour
    c = np.inf
    for a in range(nb.shape[1]):
        u = nb[x, a]
        if u < 0:
            continue
        if st.tries[x, a] < st.par.m:
            k = 1.0 + st.phi[u]
        else:
            w = known_weight(st.tries, st.clean, x, a)
            if w < 0.0:
                continue
            k = w + st.cost[u]
        if k < c:
            c = k
    return c


@njit(cache=True)
def _touch(st, x):
    """Queue x at the lesser of its cost and look-ahead if they differ, else unqueue it."""
    q = st.field.open
    g, rhs = st.cost[x], st.field.rhs[x]
    if g == rhs:
        drop(q.key, q.pair, q.where, q.size, x)
    else:
        place(q.key, q.pair, q.where, q.size, x, -min(g, rhs))


@njit(cache=True)
def settle(st, target):
    """Settle queued repairs until ``target``'s cost is exact (-1: every cell's): LPA*'s
    loop, with D* Lite's stop (Koenig & Likhachev 2002) for a target. A cell whose
    look-ahead fell takes it and lowers its predecessors'; one whose look-ahead rose
    forgets its cost, and the predecessors that counted on it look again. With a target
    the loop stops once no queued cell is cheaper than it and it is consistent: every cell
    cheaper than the target is then exact, and so is every move's cost that can tie the
    target's best (a cell still queued is at least as dear as the target, so a move into
    it costs more). Rises behind the agent (the cells that reach G through it) wait, and
    many of them merge before anything reads them."""
    nb = st.neighbour
    n_a = nb.shape[1]
    phi, tries, clean, m = st.phi, st.tries, st.clean, st.par.m
    g, rhs = st.cost, st.field.rhs
    q = st.field.open
    while q.size[0] > 0:
        if target >= 0 and g[target] == rhs[target] and -q.key[0] >= g[target]:
            return
        x = pop(q.key, q.pair, q.where, q.size)
        gx = g[x]
        lowered = gx > rhs[x]
        if lowered:
            g[x] = rhs[x]
        else:
            g[x] = np.inf
            _touch(st, x)
        for b in range(n_a):
            y = nb[x, back_move(b)]  # y reaches x by move b
            if y < 0 or nb[y, b] != x or tries[y, b] < m or phi[y] == 0.0:
                continue
            w = known_weight(tries, clean, y, b)
            if w < 0.0:
                continue
            if lowered:
                if w + g[x] < rhs[y]:
                    rhs[y] = w + g[x]
                    _touch(st, y)
            elif rhs[y] == w + gx:  # y's look-ahead went through x's old cost
                rhs[y] = look_ahead(st, y)
                _touch(st, y)


@njit(cache=True, inline="always")
def model_changed(st, s):
    """The model of a move at s changed (``version`` already raised): queue s's new
    look-ahead for :func:`settle` if the costs were current for the version before, else
    leave them to the next full refresh."""
    if st.cost_version[0] == st.version[0] - 1:
        st.field.rhs[s] = look_ahead(st, s)
        _touch(st, s)
        st.cost_version[0] = st.version[0]


@njit(cache=True)
def current_costs(st, target):
    """Make ``st.cost`` exact at ``target`` (-1: everywhere) for the current model."""
    refresh_costs(st)
    settle(st, target)


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
def greedy_move(st, s):
    """The move of least cost under the model; among ties, a known move that has worked
    first (:func:`learning.parts.tabular.least_seen_to_work`'s rule); -1 when no move leads
    anywhere (every way out is known to bump)."""
    current_costs(st, s)
    move_costs(st, s, st.keys)
    a = least_seen_to_work(st.keys, st.clean[s], 1)
    return a if st.keys[a] >= 0.0 else -1


@njit(**HOOK)
def act(st, s, rng):
    """Greedy on the costs; among tied moves an untried one first (the nearest of the
    equally cheap unknowns is tried now, R-max's optimism), else the greedy test's rule."""
    n_a = st.neighbour.shape[1]
    if st.par.eps > 0.0 and rng.random() < st.par.eps:
        return rng.integers(0, n_a)
    a = greedy_move(st, s)
    if a < 0:  # nowhere to go (every way out bumped): any move, a bump will tell
        return rng.integers(0, n_a)
    keys, tries, m = st.keys, st.tries, st.par.m
    for b in range(n_a):
        if keys[b] == keys[a] and tries[s, b] < m:
            return b
    return a


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """Count the try; the m-th freezes the move's model, makes the model a new version and
    repairs the costs it changed."""
    clean = read_move(st.reading.r_stay, st.reading.r_clean, s, r, s2, terminated)
    if st.tries[s, a] < st.par.m:
        st.tries[s, a] += 1
        if clean:
            st.clean[s, a] += 1
        if st.tries[s, a] == st.par.m:
            st.version[0] += 1
            model_changed(st, s)


begin = begin_plain


@njit(**HOOK)
def exploit(st, s):
    """The greedy test's move: the behaviour's without ε (0 when no move leads anywhere)."""
    return max(greedy_move(st, s), 0)


def q_table(st: State) -> np.ndarray:
    """float64[nS, nA]: minus each move's cost to G under the model (a move that always
    bumps or leads nowhere: minus the number of cells)."""
    current_costs(st, -1)
    n_s, n_a = st.neighbour.shape
    keys = np.zeros(n_a)
    out = np.empty((n_s, n_a))
    for s in range(n_s):
        move_costs(st, s, keys)
        out[s] = np.where(keys >= 0.0, -keys, -float(n_s))
    return out


def n_states(st: State) -> int:
    return int(st.phi.shape[0])
