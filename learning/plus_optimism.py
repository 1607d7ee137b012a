"""RNH-QL+'s optimistic model: what the agent assumes about the moves it has not tried.

The agent knows the arena's cells and where G is (as HAQL's heuristic from
exploration does, :mod:`learning.explored`), not the obstacles. It assumes
every move it has not seen fail is free (the free-space assumption of D* Lite)
and values a state by the route to G that assumption allows:

    y(s) = r_free * (1 - gamma^(d-1)) / (1 - gamma) + gamma^(d-1) * r_goal,

d = the BFS distance from s to G over the moves not known to fail, r_goal the
reward seen on entering G (until G is first reached, :func:`goal_reward`'s optimistic
stand-in), r_free the reward seen on the last free move (0 under goal-only
rewards). A state with no such route
is worth wandering forever, r_free / (1 - gamma) (0 if that is not positive).

V_NN learns this value (``v_target = 3``, in the log domain, where it is
linear in d and a smooth Gaussian network fits it far better than the
exponential itself) and the untried actions are valued by one step of look-ahead
on the potential (``lookahead = 1``): Wiewiora's look-ahead advice, with the
arena's neighbour as the assumed successor. The BFS is re-run only when a move
is newly known to fail and :func:`distances_change` says some distance moves (or,
in a noisy physics world, when a move known to fail works after all): O(states) then.

Slots (appended to :mod:`learning.rules_plus`'s ``ilist``, K centres, nS
states, nA actions): ``[2 nS nA + K, + nS nA)`` the arena neighbour of each
move (-1 off the arena), then ``nS`` BFS distances (-1: no route), then an
``nS`` BFS queue, then the move model's ``2 nS nA`` outcome counts; ``fmap[2 nS]``
is a scratch row for the action values. ``e``
(after the K traces and nS cached potentials of the rows) holds y of every state and,
last, the two rewards it was computed with (the first -1 after a new BFS: stale).
"""

from __future__ import annotations

from numba import njit

from learning import kinds as K
from learning.move_model import never_worked

INLINE = dict(cache=True, inline="always")


@njit(**INLINE)
def neighbour_base(n_s, n_a, n_c):
    """Offset of the neighbour table in ilist (the BFS distances follow it)."""
    return 2 * n_s * n_a + n_c


@njit(**INLINE)
def counts_base(n_s, n_a, n_c):
    """Offset of the move model's outcome counts in ilist (after the BFS queue;
    :mod:`learning.move_model`)."""
    return neighbour_base(n_s, n_a, n_c) + n_s * n_a + 2 * n_s


@njit(**INLINE)
def back_move(a):
    """The move that undoes a (actions: up, down, left, right)."""
    return 1 if a == 0 else (0 if a == 1 else (3 if a == 2 else 2))


@njit(**INLINE)
def known_to_fail(imap, ilist, n_s, n_a, n_c, s, a):
    """The move s -a-> was tried and never seen to reach its neighbour (a wall): the move
    model (:mod:`learning.move_model`) counts the times it did, so under noise a move that
    works sometimes is free, and a wall stays a wall."""
    return never_worked(imap, ilist, counts_base(n_s, n_a, n_c), n_a, s, a)


@njit(cache=True)
def optimistic_bfs(imap, ilist, n_s, n_a, n_c, goal):
    """BFS distances to G over the moves not known to fail (seen to leave the agent put)."""
    nb0 = neighbour_base(n_s, n_a, n_c)
    d0 = nb0 + n_s * n_a
    q0 = d0 + n_s
    for s in range(n_s):
        ilist[d0 + s] = -1
    ilist[d0 + goal] = 0
    ilist[q0] = goal
    head, tail = 0, 1
    while head < tail:
        v = ilist[q0 + head]
        head += 1
        for a in range(n_a):
            u = ilist[nb0 + v * n_a + a]  # v's neighbour; u reaches v by the opposite move
            if u < 0 or ilist[d0 + u] >= 0:
                continue
            b = back_move(a)
            if known_to_fail(imap, ilist, n_s, n_a, n_c, u, b):
                continue
            ilist[d0 + u] = ilist[d0 + v] + 1
            ilist[q0 + tail] = u
            tail += 1


@njit(**INLINE)
def distances_change(imap, ilist, n_s, n_a, n_c, s, a):
    """Whether a move s -a-> just seen to fail changes any BFS distance. The distances
    solve d(s) = 1 + min d(u) over s's moves not known to fail, a solution that is
    unique; the failed move matters only if it was s's one move to a neighbour u with
    d(u) = d(s) - 1. Otherwise every old distance still solves the equations, and the
    O(states) BFS is skipped (on most new walls: a cell usually has two moves towards G)."""
    nb0 = neighbour_base(n_s, n_a, n_c)
    d0 = nb0 + n_s * n_a
    ds = ilist[d0 + s]
    u = ilist[nb0 + s * n_a + a]
    if ds <= 0 or u < 0 or ilist[d0 + u] != ds - 1:
        return False
    for b in range(n_a):
        if b == a:
            continue
        v = ilist[nb0 + s * n_a + b]
        if v >= 0 and ilist[d0 + v] == ds - 1 and not known_to_fail(imap, ilist, n_s, n_a,
                                                                     n_c, s, b):
            return False
    return True


@njit(**INLINE)
def goal_reward(fvar, par):
    """r_G of the model: the reward seen on entering G; until then an optimistic stand-in,
    one more than wandering forever on free moves (r_free / (1 - gamma) + 1; 1 when a free
    move earns nothing or less), so that y falls with the distance to G under any reward
    scheme. (A stand-in of 1 under the paper's +1 per free move made y *rise* with the
    distance and drove the agent away from a G it had not reached yet.)"""
    if fvar[K.F_RGOAL] > 0.0:
        return fvar[K.F_RGOAL]
    r_free = fvar[K.F_RFREE]
    return r_free / (1.0 - par[K.P_GAMMA]) + 1.0 if r_free > 0.0 else 1.0


@njit(cache=True)
def refresh_values(fvar, par, ilist, e, n_s, n_a, n_c):
    """Fill the cache of y (``e[nK + nS + s]``) from the BFS distances and the rewards
    seen, and stamp it with those rewards. O(states); runs after a BFS and when a
    reward of the model changes, so a read of y is a load, not a power. The reachable
    states are walked in the BFS queue's order, where the distance never falls, so the
    power gamma^(d-1) is taken once per distance, not once per state (it was 60% of
    the cost: 40 us a refresh on paper-50)."""
    d0 = neighbour_base(n_s, n_a, n_c) + n_s * n_a
    q0 = d0 + n_s
    y0 = n_c + n_s
    g = par[K.P_GAMMA]
    r_free = fvar[K.F_RFREE]
    r_goal = goal_reward(fvar, par)
    wander = r_free / (1.0 - g) if r_free > 0.0 else 0.0
    n_reach = 0
    for s in range(n_s):
        if ilist[d0 + s] < 0:
            e[y0 + s] = wander
        else:
            n_reach += 1
    d_prev = -1
    y = 0.0
    for i in range(n_reach):  # the queue holds the reachable states, G first
        s = ilist[q0 + i]
        d = ilist[d0 + s]
        if d != d_prev:
            d_prev = d
            if d == 0:
                y = 0.0
            else:
                gd = g ** (d - 1)
                y = r_free * (1.0 - gd) / (1.0 - g) + gd * r_goal
        e[y0 + s] = y
    e[y0 + n_s] = r_goal
    e[y0 + n_s + 1] = r_free


@njit(cache=True)
def ensure_values(fvar, par, ilist, e, feat, imap, n_c):
    """Refresh the cache of y if it is stale: computed with other rewards than those now
    in force, or stamped -1 by a new BFS. Runs where the model can change (a real step,
    the start of an episode, a read-out), never in the reads themselves: a call with
    arrays inside a hot read cost it ~15x (measured: 37 ns against 2.3 ns a read)."""
    n_s = imap.shape[0]
    y0 = n_c + n_s
    if e[y0 + n_s + 1] != fvar[K.F_RFREE] or e[y0 + n_s] != goal_reward(fvar, par):
        n_a = (imap.shape[1] - feat.shape[1] // 2) // 3
        refresh_values(fvar, par, ilist, e, n_s, n_a, n_c)


@njit(**INLINE)
def mark_stale(e, n_s, n_c):
    """The BFS distances changed: the next :func:`ensure_values` refreshes the cache."""
    e[n_c + 2 * n_s] = -1.0  # never a goal reward in force (those are > 0)


@njit(**INLINE)
def optimistic_value(e, n_c, n_s, s):
    """y(s), the value of s in the optimistic model (see the module docs): a load from the
    cache, which :func:`ensure_values` keeps fresh."""
    return e[n_c + n_s + s]


@njit(**INLINE)
def observe_rewards(fvar, s, r, s2, terminated):
    """Remember the reward of entering G and of a free move (the optimistic model's
    rewards); True if either changed (the cache of y is then stale)."""
    if terminated:
        if r > fvar[K.F_RGOAL]:
            fvar[K.F_RGOAL] = r
            return True
    elif s2 != s and fvar[K.F_RFREE] != r:
        fvar[K.F_RFREE] = r
        return True
    return False
