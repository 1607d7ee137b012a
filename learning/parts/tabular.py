"""Tabular action choice and the one-step updates (numba), shared by every method's rules.

Conventions for every rule here:

* Bootstrap only when the transition did not *terminate*; a truncated step
  (time limit) still bootstraps from ``s'``.
* Greedy ties are broken uniformly at random with the injected generator during
  training (``argmax_random``) and by lowest index in greedy tests
  (``argmax_first``), so a test is deterministic.
* Rules take the table and the state (``q, s``), not a row view ``q[s]``, so
  no temporary array is made per call.
* The per-step rules are ``inline="always"`` (numba IR inlining): numba does
  not inline one compiled function into another, and a call that passes the
  ``Generator`` is particularly dear. Inlining the rules took the st-ql kernel
  from 23M to ~49M env steps/s on paper-50 (a bare single-function loop: 61M).
* "Greedy" for trace cutting means ``Q(s, a) == max_b Q(s, b)`` before the
  update of this step, i.e. the action could have been the greedy choice.
"""

from __future__ import annotations

from numba import njit

from learning.parts.tally import begin_tally


@njit(cache=True, inline="always")
def row_max(q, s):
    m = q[s, 0]
    for b in range(1, q.shape[1]):
        if q[s, b] > m:
            m = q[s, b]
    return m


@njit(cache=True, inline="always")
def raised(v, b, up, bonus):
    """Action b's value v = Q(s, b) as the argmax rules below rank it: plus ``bonus`` when b
    is the raised action ``up`` (-1: none is; HAQL raises its heuristic move)."""
    return v + bonus if b == up else v


@njit(cache=True, inline="always")
def argmax_first(q, s, up=-1, bonus=0.0):
    """Greedy action at s, ties to the lowest index (deterministic, for tests); action ``up``
    ranked by Q + ``bonus`` (:func:`raised`)."""
    a = 0
    for b in range(1, q.shape[1]):
        if raised(q[s, b], b, up, bonus) > raised(q[s, a], a, up, bonus):
            a = b
    return a


@njit(cache=True, inline="always")
def draw_below(rng, n):
    """A uniform index in [0, n) from one ``rng.random()``: ~15x cheaper than numba's
    ``rng.integers`` (which re-draws bounded integers), for hot loops that draw per update."""
    k = int(rng.random() * n)
    return k if k < n else n - 1


@njit(cache=True, inline="always")
def argmax_tied(q, s, rng, cheap_draw, up=-1, bonus=0.0):
    """Greedy action at s, a tie broken at random: ``rng.integers(0, n_ties)``, or with
    ``cheap_draw`` :func:`draw_below`; nothing is drawn without a tie. Action ``up`` is
    ranked by Q + ``bonus`` (:func:`raised`)."""
    best = raised(q[s, 0], 0, up, bonus)
    a = 0
    ties = 1
    for b in range(1, q.shape[1]):
        v = raised(q[s, b], b, up, bonus)
        if v > best:
            best = v
            a = b
            ties = 1
        elif v == best:
            ties += 1
    if ties == 1:
        return a
    k = draw_below(rng, ties) if cheap_draw else rng.integers(0, ties)
    for b in range(q.shape[1]):
        if raised(q[s, b], b, up, bonus) == best:
            if k == 0:
                return b
            k -= 1
    return a


@njit(cache=True, inline="always")
def argmax_random(q, s, rng):
    """Greedy action at s; draws ``rng.integers(0, n_ties)`` only when there is a tie."""
    return argmax_tied(q, s, rng, False)


@njit(cache=True, inline="always")
def argmax_drawn(q, s, rng):
    """:func:`argmax_random` with its tie drawn by :func:`draw_below` (hot loops)."""
    return argmax_tied(q, s, rng, True)


@njit(cache=True, inline="always")
def eps_greedy(q, s, eps, rng):
    """Draw order: one ``rng.random()``; then ``integers(0, nA)`` if exploring, else
    ``argmax_random``'s tie draw (if any)."""
    if rng.random() < eps:
        return rng.integers(0, q.shape[1])
    return argmax_random(q, s, rng)


@njit(cache=True, inline="always")
def is_greedy(q, s, a):
    return q[s, a] >= row_max(q, s)


@njit(cache=True, inline="always")
def q_learning(q, s, a, r, s2, terminated, alpha, gamma, f):
    """Q(s,a) += alpha * (r + f + gamma * max_b Q(s',b) [not terminated] - Q(s,a)).

    ``f`` is a shaping term added to the reward (0 for plain Q-learning).
    """
    target = r + f
    if not terminated:
        target += gamma * row_max(q, s2)
    q[s, a] += alpha * (target - q[s, a])


@njit(cache=True)
def sarsa(q, s, a, r, s2, a2, terminated, alpha, gamma, f):
    """Q(s,a) += alpha * (r + f + gamma * Q(s',a') [not terminated] - Q(s,a))."""
    target = r + f
    if not terminated:
        target += gamma * q[s2, a2]
    q[s, a] += alpha * (target - q[s, a])


# ---------------------------------------------------------------- hooks several methods share


@njit(cache=True, inline="always")
def begin_plain(st, s0):
    """The ``begin`` hook of a method with nothing to reset per episode but its tally."""
    begin_tally(st.tally)


@njit(cache=True, inline="always")
def exploit_q(st, s):
    """The ``exploit`` hook of a method whose policy is its Q-table's greedy action."""
    return argmax_first(st.q, s)


@njit(cache=True, inline="always")
def least_key(keys):
    """(the least non-negative key, how many moves share it); a negative key marks a move
    that is no candidate; (-1, 0) when none is. With :func:`nth_least`: a planner's choice
    among its tied best moves."""
    best, ties = -1.0, 0
    for a in range(keys.shape[0]):
        k = keys[a]
        if k < 0.0:
            continue
        if ties == 0 or k < best:
            best, ties = k, 1
        elif k == best:
            ties += 1
    return best, ties


@njit(cache=True, inline="always")
def least_seen_to_work(keys, evidence, sign):
    """The greedy test's move among a planner's tied best: the first seen to work
    (``sign * evidence[a] > 0``: a balance of bumps minus clean arrivals with ``sign`` -1, a
    count of clean arrivals with +1), else the first (0 when no move is a candidate).
    HAQL's and rnh-ql+explore's tests break ties the same way: of routes the model holds
    equally short, the one the agent has driven, not an unverified staircase through cells
    it never entered."""
    best, ties = least_key(keys)
    if ties == 0:
        return 0
    first = -1
    for a in range(keys.shape[0]):
        if keys[a] == best:
            if sign * evidence[a] > 0:
                return a
            if first < 0:
                first = a
    return first


@njit(cache=True, inline="always")
def nth_least(keys, best, n):
    """The ``n``-th (0-based, in action order) move whose key is ``best``."""
    for a in range(keys.shape[0]):
        if keys[a] == best:
            if n == 0:
                return a
            n -= 1
    return 0
