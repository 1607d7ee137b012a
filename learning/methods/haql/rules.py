"""HAQL (``haql``, Bianchi 2008): heuristically accelerated Q-learning, act on
argmax[Q + xi * H^beta] with H favouring the heuristic move pi_H(s).

With a static heuristic (the Manhattan move) pi_H never changes, and with
xi = beta = 1 the heuristic move always wins the argmax, so the route is fixed
before learning starts. By default pi_H is a *heuristic from exploration*
(Bianchi, Ribeiro & Costa 2008): the first move of a shortest route to G in the
agent's free-space model (:mod:`learning.parts.free_space`), re-derived for every
state by one BFS from G when a move's blocked status changes. The route the
agent follows therefore changes as it learns where the walls are.

A move is blocked while bumps are its most likely outcome: more bumps than
arrivals at its neighbour have been seen (the most-likely-outcome
determinization of a stochastic move, as FF-Replan's). With wheel noise and
carried pose a free move can fail now and then, and a move past an obstacle's
edge can get through now and then: one unlucky bump does not wall off a route,
one lucky pass does not open a wall. In a deterministic world a move's outcome
never changes, and this is the original rule (blocked from its first bump).

An arrival paid the bump's reward (a grazing move with carried pose, read from the
reward by :mod:`learning.parts.move_reading`) counts as a bump, not as an arrival: a route
through moves that get through by scraping an obstacle is not a free route.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import MethodConfig, params_tuple
from learning.geometry import Geometry
from learning.methods.haql.least_bumped import edge_changed, least_bumped_costs, step_cost
from learning.parts.free_space import (
    FreeSpace,
    bfs_distances,
    distances_change,
    lower_distances,
    new_free_space,
    repair_distances,
)
from learning.parts.move_reading import MoveReading, new_move_reading, read_move
from learning.parts.tabular import argmax_first, argmax_tied, q_learning, row_max
from learning.parts.tally import Tally, begin_tally, new_tally

HOOK = dict(cache=True, inline="always")
COUNT_CAP = 1 << 30  # bumps minus arrivals saturate here (int32)
# Added after checkpoints were written: a file without them loads the fresh values (no reward
# seen yet), relearnt at the next stay and clean arrival (see learning.drivers.checkpoint).
ADDED = ("reading.r_stay", "reading.r_clean", "cost", "cost_ok")


Params = params_tuple("Params", __name__, xi=float, beta_h=float, eta=float, explored=bool)


@dataclass(frozen=True)
class HAQL(MethodConfig):
    """Heuristically accelerated Q-learning (Bianchi 2008): act on argmax[Q + xi * H^beta].

    H(s,a) = max_b Q(s,b) - Q(s,a) + eta for the heuristic move a = pi_H(s), else
    0; Q is learned off-policy. With xi = beta = 1 the heuristic move always wins
    the argmax, so what pi_H is decides everything:

    - ``explored = 1`` (default): pi_H is a heuristic from exploration
      (:mod:`learning.methods.haql`): the first move of a shortest route to G over the
      moves not yet seen to fail, re-derived at every new bump. The route follows
      what the agent has learned about the walls.
    - ``explored = 0``: Bianchi's static heuristic, the move that most reduces
      the Manhattan distance to G. It never changes, so the route is fixed before
      learning starts (kept to show exactly that).
    """

    name: ClassVar[str] = "HAQL"
    cli: ClassVar[str] = "haql"
    xi: float = 1.0  # heuristic weight xi
    beta_h: float = 1.0  # heuristic exponent beta
    eta: float = 0.1  # margin of the heuristic move over the current max [reward units]
    explored: int = 1  # 1: heuristic from exploration; 0: the static Manhattan move

    params_type: ClassVar[type] = Params


class State(NamedTuple):
    par: Params
    tally: Tally
    q: np.ndarray  # float64[nS, nA]
    pi_h: np.ndarray  # int32[nS]; the heuristic move of each state
    balance: np.ndarray  # int32[nS, nA]; bumps minus arrivals seen (blocked when > 0)
    free: FreeSpace  # the free-space model pi_H is derived from
    reading: MoveReading  # the rewards of a stay and of a clean arrival (bumps from rewards)
    cost: np.ndarray  # int64[nS]; least-bumped route costs (learning.methods.haql.least_bumped) ...
    cost_ok: np.ndarray  # bool[1]; ... kept up to date once first needed (False: not yet)


def heuristic_actions(geom: Geometry) -> np.ndarray:
    """int32[nS]: Bianchi's static pi_H(s), the move that most reduces the Manhattan distance
    to G. Both axes usually reduce it by one cell; the move is then along the axis with
    more cells left (x on equal), a straight-ish diagonal staircase. At the goal: 0."""
    d = geom.cells[geom.goal] - geom.cells  # cells still to go (dx, dy)
    dx, dy = d[:, 0], d[:, 1]
    along_x = np.abs(dx) >= np.abs(dy)
    act_x = np.where(dx > 0, 3, 2)
    act_y = np.where(dy > 0, 0, 1)
    pi = np.where(along_x, act_x, act_y)
    pi[(dx == 0) & (dy == 0)] = 0
    return np.ascontiguousarray(pi.astype(np.int32))


def init_state(cfg: HAQL, geom: Geometry, rng: np.random.Generator) -> State:
    n_s, n_a = geom.n_states, geom.n_actions
    st = State(cfg.params(), new_tally(), np.zeros((n_s, n_a)), np.zeros(n_s, np.int32),
               np.zeros((n_s, n_a), np.int32), new_free_space(geom), new_move_reading(),
               np.zeros(n_s, np.int64), np.zeros(1, np.bool_))
    if cfg.explored:
        fs = st.free
        rederive_kept(st.pi_h, fs.neighbour, fs.blocked, st.balance, fs.distance, fs.queue,
                      int(fs.goal[0]), st.cost, st.cost_ok)
    else:
        st.pi_h[:] = heuristic_actions(geom)
    return st


@njit(cache=True)
def rederive(pi_h, nb, blocked, bal, dist, queue, goal):
    """pi_H for every state: the unblocked move to the neighbour nearest G (lowest index on
    ties), after one BFS from G.

    Where no route of unblocked moves is left, the first move of the route that crosses the
    least excess of bumps over arrivals (``bal`` summed over its blocked moves), then the
    fewest moves (:func:`least_bumped_costs`). A noisy world can block a corridor move whose
    bumps outnumber its arrivals after a few tries, and a maze has no other way: the
    heuristic then still points along the route most likely to be open, as the optimal
    policy of a stochastic world must, instead of at move 0. In a deterministic world a
    state without a route of unblocked moves is walled off from G, so this changes nothing
    a run can reach. Takes the free space's arrays (hooks read a named tuple's fields once,
    at their top; see :mod:`learning.methods.rnh_ql_plus.rules`). The least-bumped costs
    from scratch: the reference :func:`rederive_kept` is tested against."""
    rederive_kept(pi_h, nb, blocked, bal, dist, queue, goal, np.zeros(pi_h.shape[0], np.int64),
                  np.zeros(1, np.bool_))


@njit(cache=True)
def rederive_kept(pi_h, nb, blocked, bal, dist, queue, goal, cost, cost_ok):
    """:func:`rederive` with the least-bumped costs kept in ``cost`` (computed here first
    when ``cost_ok[0]`` is False, then kept up to date by :func:`observe`)."""
    bfs_distances(nb, blocked, dist, queue, goal)
    cut = False
    for s in range(pi_h.shape[0]):
        if dist[s] >= 0:
            pi_h[s] = nearest_move(nb, blocked, dist, s)
        else:
            cut = True
    if cut:
        rederive_cut(pi_h, nb, bal, dist, goal, cost, cost_ok)


@njit(cache=True)
def rederive_cut(pi_h, nb, bal, dist, goal, cost, cost_ok):
    """The second half of :func:`rederive`: pi_H of the states without a route of unblocked
    moves (distance -1), from the least-bumped routes; on its own where only the counts
    changed (the distances, and so every other state's move, are as they were). ``cost``
    is kept up to date from the first call on (``cost_ok``)."""
    if not cost_ok[0]:
        cost[:] = least_bumped_costs(nb, bal, goal)
        cost_ok[0] = True
    for s in range(pi_h.shape[0]):
        if dist[s] < 0:
            best, best_c = 0, np.int64(-1)
            for a in range(nb.shape[1]):
                t = nb[s, a]
                if t < 0 or cost[t] < 0:
                    continue
                c = cost[t] + step_cost(bal, s, a, cost.shape[0])
                if best_c < 0 or c < best_c:
                    best, best_c = a, c
            pi_h[s] = best


@njit(cache=True)
def rederive_after_wall(pi_h, nb, blocked, bal, dist, queue, goal, s, a, cost, cost_ok):
    """pi_H after s's move a was newly blocked, equal to :func:`rederive`'s but in
    O(the states whose distance changed): only s (its own move) and the neighbours of a
    state whose distance changed can point another way. Distances are repaired
    (:func:`learning.parts.free_space.repair_distances`), or left alone when the wall was not s's
    only move towards G. Where a state has no route of unblocked moves (before or after),
    the whole of :func:`rederive` runs: the least-bumped routes depend on every count.

    A full re-derivation at every new wall cost O(walls x states): on a 512² map, hours
    a run (see BENCHMARKS.md)."""
    if any_cut(dist):
        rederive_kept(pi_h, nb, blocked, bal, dist, queue, goal, cost, cost_ok)
        return
    if not distances_change(nb, dist, blocked, s, a):
        pi_h[s] = nearest_move(nb, blocked, dist, s)
        return
    changed = repair_distances(nb, blocked, dist, queue, goal, s)
    if changed[0] < 0:  # a state lost its last route (the distances are a full BFS's now)
        rederive_kept(pi_h, nb, blocked, bal, dist, queue, goal, cost, cost_ok)
        return
    repoint(pi_h, nb, blocked, dist, s, changed, changed.shape[0])


@njit(cache=True)
def rederive_after_unblock(pi_h, nb, blocked, bal, dist, queue, goal, s, a, cost,
                           cost_ok):
    """pi_H after s's move a was unblocked (a wall that moved after all, in a noisy world),
    equal to :func:`rederive`'s: distances can only fall, and only through s; they are
    lowered by a BFS from s over the moves into it (each state at most once: the first visit
    is the fewest moves through s), then s and the neighbours of every lowered state take
    their nearest move again. Where a state has no route (before), the whole of
    :func:`rederive` runs (a cut-off state may have got one back)."""
    if any_cut(dist):
        rederive_kept(pi_h, nb, blocked, bal, dist, queue, goal, cost, cost_ok)
        return
    t = nb[s, a]
    if dist[t] + 1 >= dist[s]:  # no distance falls: only s's own move may change
        pi_h[s] = nearest_move(nb, blocked, dist, s)
        return
    lowered = np.empty(dist.shape[0], np.int32)  # (queue keeps the reachable states)
    dist[s] = dist[t] + 1
    lowered[0] = s
    tail = lower_distances(nb, blocked, dist, lowered, 1)  # (every distance is set: no cut)
    repoint(pi_h, nb, blocked, dist, s, lowered, tail)


@njit(cache=True, inline="always")
def repoint(pi_h, nb, blocked, dist, s, changed, n):
    """s and the neighbours of the states ``changed[:n]``, whose distances changed, take their
    nearest move again: no other state's can change (on the grid's symmetric moves, a
    neighbour u of v has a move into v)."""
    pi_h[s] = nearest_move(nb, blocked, dist, s)
    for i in range(n):
        v = changed[i]
        for b in range(nb.shape[1]):
            u = nb[v, b]
            if u >= 0:
                pi_h[u] = nearest_move(nb, blocked, dist, u)


@njit(cache=True)
def any_cut(dist):
    """Whether some state has no route of unblocked moves to G (distance -1)."""
    for s in range(dist.shape[0]):
        if dist[s] < 0:
            return True
    return False


@njit(cache=True, inline="always")
def nearest_move(nb, walls, dist, s):
    """The move from s not in ``walls`` to the neighbour with the least ``dist`` (lowest
    index on ties; 0 when no neighbour has a route)."""
    best, best_d = 0, -1
    for a in range(nb.shape[1]):
        t = nb[s, a]
        if t < 0 or walls[s, a] or dist[t] < 0:
            continue
        if best_d < 0 or dist[t] < best_d:
            best, best_d = a, dist[t]
    return best


@njit(cache=True, inline="always")
def observe(bal, pi_h, nb, blocked, dist, queue, goal, s, a, s2, terminated, clean, cost,
            cost_ok):
    """After a move: a bump (stayed in s, or arrived paid the bump's reward: ``clean`` is
    False) counts up, a move that reached its neighbour cleanly down; when the sign flips
    (the move's most likely outcome changed), re-derive pi_H; and where s has no route of
    unblocked moves, whenever pi_H's own move bumps (:func:`rederive`). (A move that
    drifted into another cell without a bump tells nothing about this one.) The least-bumped
    costs, once needed, follow every count
    (:func:`learning.methods.haql.least_bumped.edge_changed`)."""
    w_old = step_cost(bal, s, a, pi_h.shape[0])
    if s2 == nb[s, a] and clean:
        if bal[s, a] > -COUNT_CAP:  # int32: a long run must not wrap round
            bal[s, a] -= 1
    elif not clean:
        if bal[s, a] < COUNT_CAP:
            bal[s, a] += 1
    else:
        return
    if cost_ok[0]:
        edge_changed(cost, nb, bal, s, a, w_old)
    now = bal[s, a] > 0
    if now != blocked[s, a]:
        blocked[s, a] = now
        if now:  # a new wall: repair what it changed
            rederive_after_wall(pi_h, nb, blocked, bal, dist, queue, goal, s, a, cost, cost_ok)
        else:  # a wall that moved after all (noisy worlds): distances may fall
            rederive_after_unblock(pi_h, nb, blocked, bal, dist, queue, goal, s, a, cost,
                                   cost_ok)
    elif now and dist[s] < 0 and pi_h[s] == a:
        # cut off, and the least-bumped route's first move bumped again: its cost rose, so
        # the heuristic may now point another way (else it pushes one wall for ever); no
        # move was blocked or unblocked, so only the cut-off states' moves can change
        rederive_cut(pi_h, nb, bal, dist, goal, cost, cost_ok)


@njit(cache=True, inline="always")
def heuristic_bonus(q_pi, m, xi, beta, eta):
    """What the heuristic move adds to its Q, ``q_pi``, in the scores HAQL acts on: xi * H^beta,
    H = m - q_pi + eta, m = max_b Q(s, b) (every other move's score is its Q)."""
    return xi * (m - q_pi + eta) ** beta


@njit(**HOOK)
def act(st, s, rng):
    """Epsilon-greedy around argmax[Q + xi * H^beta], ties drawn. The heuristic move pi wins
    outright where its bonus lifts it above every Q (always at xi = beta = 1 and eta > 0):
    no other move is scored then."""
    p = st.par
    q = st.q
    pi_h = st.pi_h
    if rng.random() < p.eps:
        return rng.integers(0, q.shape[1])
    pi = pi_h[s]
    m = row_max(q, s)
    bonus = heuristic_bonus(q[s, pi], m, p.xi, p.beta_h, p.eta)
    if q[s, pi] + bonus > m:  # pi wins outright
        return pi
    return argmax_tied(q, s, rng, False, pi, bonus)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """Q-learning, and the heuristic from exploration learns from the move's outcome."""
    bal = st.balance
    pi_h = st.pi_h
    nb = st.free.neighbour
    blocked = st.free.blocked
    dist = st.free.distance
    queue = st.free.queue
    goal = st.free.goal[0]
    r_stay = st.reading.r_stay
    r_clean = st.reading.r_clean
    q_learning(st.q, s, a, r, s2, terminated, st.par.alpha, st.par.gamma, 0.0)
    if st.par.explored:
        clean = read_move(r_stay, r_clean, s, r, s2, terminated)
        observe(bal, pi_h, nb, blocked, dist, queue, goal, s, a, s2, terminated, clean,
                st.cost, st.cost_ok)


@njit(**HOOK)
def begin(st, s0):
    begin_tally(st.tally)


@njit(**HOOK)
def exploit(st, s):
    """argmax[Q + xi * H^beta], ties to the lowest index (pi outright as in :func:`act`)."""
    p = st.par
    q = st.q
    pi = st.pi_h[s]
    m = row_max(q, s)
    bonus = heuristic_bonus(q[s, pi], m, p.xi, p.beta_h, p.eta)
    if q[s, pi] + bonus > m:  # pi wins outright
        return pi
    return argmax_first(q, s, pi, bonus)
