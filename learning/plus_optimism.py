"""RNH-QL+'s optimistic model: what the agent assumes about the moves it has not tried.

The agent knows the arena's cells and where G is (as HAQL's heuristic from
exploration does, :mod:`learning.explored`), not the obstacles. It assumes
every move it has not seen fail is free (the free-space assumption of D* Lite)
and values a state by the route to G that assumption allows:

    y(s) = r_free * (1 - gamma^(d-1)) / (1 - gamma) + gamma^(d-1) * r_goal,

d = the BFS distance from s to G over the moves not known to fail, r_goal the
reward seen on entering G (1 until G is first reached), r_free the reward seen
on the last free move (0 under goal-only rewards). A state with no such route
is worth wandering forever, r_free / (1 - gamma) (0 if that is not positive).

V_NN learns this value (``v_target = 3``, in the log domain, where it is
linear in d and a smooth Gaussian network fits it far better than the
exponential itself) and the untried actions are valued by one step of look-ahead
on the potential (``lookahead = 1``): Wiewiora's look-ahead advice, with the
arena's neighbour as the assumed successor. The BFS is re-run only when a move
is seen to fail for the first time: O(states) per new blocked move.

Slots (appended to :mod:`learning.rules_plus`'s ``ilist``, K centres, nS
states, nA actions): ``[2 nS nA + K, + nS nA)`` the arena neighbour of each
move (-1 off the arena), then ``nS`` BFS distances (-1: no route), then an
``nS`` BFS queue; ``fmap[2 nS]`` is a scratch row for the action values. ``e``
(after the K traces and nS cached potentials of the rows) holds y of every state and,
last, the two rewards it was computed with (the first -1 after a new BFS: stale).
"""

from __future__ import annotations

from numba import njit

from learning import kinds as K

INLINE = dict(cache=True, inline="always")


@njit(**INLINE)
def neighbour_base(n_s, n_a, n_c):
    """Offset of the neighbour table in ilist (the BFS distances follow it)."""
    return 2 * n_s * n_a + n_c


@njit(**INLINE)
def back_move(a):
    """The move that undoes a (actions: up, down, left, right)."""
    return 1 if a == 0 else (0 if a == 1 else (3 if a == 2 else 2))


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
            if imap[u, b] == u and imap[u, n_a + b] == 0:
                continue  # u -> v is known to fail
            ilist[d0 + u] = ilist[d0 + v] + 1
            ilist[q0 + tail] = u
            tail += 1


@njit(cache=True)
def refresh_values(fvar, par, ilist, e, n_s, n_a, n_c):
    """Fill the cache of y (``e[nK + nS + s]``) from the BFS distances and the rewards
    seen, and stamp it with those rewards. O(states); runs after a BFS and when a
    reward of the model changes, so a read of y is a load, not a power."""
    d0 = neighbour_base(n_s, n_a, n_c) + n_s * n_a
    y0 = n_c + n_s
    g = par[K.P_GAMMA]
    r_free = fvar[K.F_RFREE]
    r_goal = fvar[K.F_RGOAL] if fvar[K.F_RGOAL] > 0.0 else 1.0
    wander = r_free / (1.0 - g) if r_free > 0.0 else 0.0
    for s in range(n_s):
        d = ilist[d0 + s]
        if d < 0:
            e[y0 + s] = wander
        elif d == 0:
            e[y0 + s] = 0.0
        else:
            gd = g ** (d - 1)
            e[y0 + s] = r_free * (1.0 - gd) / (1.0 - g) + gd * r_goal
    e[y0 + n_s] = r_goal
    e[y0 + n_s + 1] = r_free


@njit(**INLINE)
def mark_stale(e, n_s, n_c):
    """The BFS distances changed: the next read of y refreshes the cache."""
    e[n_c + 2 * n_s] = -1.0  # never a goal reward in force (those are > 0)


@njit(**INLINE)
def optimistic_value(fvar, par, ilist, e, n_s, n_a, n_c, s):
    """y(s), the value of s in the optimistic model (see the module docs), from the cache."""
    y0 = n_c + n_s
    r_goal = fvar[K.F_RGOAL] if fvar[K.F_RGOAL] > 0.0 else 1.0
    if e[y0 + n_s] != r_goal or e[y0 + n_s + 1] != fvar[K.F_RFREE]:  # -1: stale
        refresh_values(fvar, par, ilist, e, n_s, n_a, n_c)
    return e[y0 + s]


@njit(**INLINE)
def observe_rewards(fvar, s, r, s2, terminated):
    """Remember the reward of entering G and of a free move (the optimistic model's rewards)."""
    if terminated:
        if r > fvar[K.F_RGOAL]:
            fvar[K.F_RGOAL] = r
    elif s2 != s:
        fvar[K.F_RFREE] = r
