"""Tabular action choice and update rules (numba), shared by the kernels and the step agent.

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

from learning import kinds as K
from learning.move_model import observe_outcome, replay_fails


@njit(cache=True, inline="always")
def row_max(q, s):
    m = q[s, 0]
    for b in range(1, q.shape[1]):
        if q[s, b] > m:
            m = q[s, b]
    return m


@njit(cache=True, inline="always")
def argmax_first(q, s):
    """Greedy action at s, ties to the lowest index (deterministic, for tests)."""
    a = 0
    for b in range(1, q.shape[1]):
        if q[s, b] > q[s, a]:
            a = b
    return a


@njit(cache=True, inline="always")
def argmax_random(q, s, rng):
    """Greedy action at s; draws ``rng.integers(0, n_ties)`` only when there is a tie."""
    best = q[s, 0]
    a = 0
    ties = 1
    for b in range(1, q.shape[1]):
        v = q[s, b]
        if v > best:
            best = v
            a = b
            ties = 1
        elif v == best:
            ties += 1
    if ties == 1:
        return a
    k = rng.integers(0, ties)
    for b in range(q.shape[1]):
        if q[s, b] == best:
            if k == 0:
                return b
            k -= 1
    return a


@njit(cache=True, inline="always")
def draw_below(rng, n):
    """A uniform index in [0, n) from one ``rng.random()``: ~15x cheaper than numba's
    ``rng.integers`` (which re-draws bounded integers), for hot loops that draw per update."""
    k = int(rng.random() * n)
    return k if k < n else n - 1


@njit(cache=True, inline="always")
def argmax_drawn(q, s, rng):
    """:func:`argmax_random` with its tie drawn by :func:`draw_below`."""
    best = q[s, 0]
    a = 0
    ties = 1
    for b in range(1, q.shape[1]):
        v = q[s, b]
        if v > best:
            best = v
            a = b
            ties = 1
        elif v == best:
            ties += 1
    if ties == 1:
        return a
    k = draw_below(rng, ties)
    for b in range(q.shape[1]):
        if q[s, b] == best:
            if k == 0:
                return b
            k -= 1
    return a


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


@njit(cache=True)
def record_shaping(ivar, fvar, f):
    fvar[K.F_FSUM] += f
    fvar[K.F_FSQ] += f * f
    ivar[K.I_NF] += 1


# ---------------------------------------------------------------- Watkins Q(lambda)
@njit(cache=True)
def clear_traces(e, tl, ivar):
    n_a = e.shape[1]
    for i in range(ivar[K.I_NTRACE]):
        e[tl[i] // n_a, tl[i] % n_a] = 0.0
    ivar[K.I_NTRACE] = 0


@njit(cache=True)
def q_lambda(q, e, tl, ivar, s, a, r, s2, terminated, alpha, gamma, lam, trace_min, f):
    """Tabular Watkins Q(lambda), replacing traces ``e[nS, nA]``; ``f`` is a shaping term.

    Cutting the traces when the action *taken* is non-greedy (before its trace
    is set) is Sutton & Barto's "cut when the next action is exploratory".
    Only the touched pairs ``tl[:n]`` (flat s*nA + a) are visited; traces below
    trace_min are dropped.
    """
    n_a = q.shape[1]
    n = ivar[K.I_NTRACE]
    if not is_greedy(q, s, a):
        clear_traces(e, tl, ivar)
        n = 0
    else:
        gl = gamma * lam
        m = 0
        for i in range(n):
            j = tl[i]
            v = e[j // n_a, j % n_a] * gl
            if v < trace_min:
                e[j // n_a, j % n_a] = 0.0
            else:
                e[j // n_a, j % n_a] = v
                tl[m] = j
                m += 1
        n = m
    if e[s, a] == 0.0:
        tl[n] = s * n_a + a
        n += 1
    e[s, a] = 1.0
    target = r + f
    if not terminated:
        target += gamma * row_max(q, s2)
    step = alpha * (target - q[s, a])
    for i in range(n):
        j = tl[i]
        q[j // n_a, j % n_a] += step * e[j // n_a, j % n_a]
    ivar[K.I_NTRACE] = n


# ---------------------------------------------------------------- Dyna-Q
@njit(cache=True)
def dyna_q(q, imap, fmap, ilist, ivar, fvar, s, a, r, s2, terminated, alpha, gamma, n_plan,
           rng):
    """Q-learning, then record (s,a) -> (r, s', terminated) in the model, then ``n_plan``
    Q updates on pairs drawn with ``draw_below(rng, n_seen)`` (Sutton & Barto 8.2), each
    replaying an outcome drawn from the model (:mod:`learning.move_model`).

    Model: ``imap[s, a]`` = s' (-1 unseen), ``imap[s, nA + a]`` = terminated,
    ``fmap[s, a]`` = r; ``ilist[:n_seen]`` lists the seen flat pairs, ``ilist[nS nA:]``
    the outcome counts.
    """
    q_learning(q, s, a, r, s2, terminated, alpha, gamma, 0.0)
    n_a = q.shape[1]
    c0 = q.shape[0] * n_a
    if imap[s, a] < 0:
        ilist[ivar[K.I_NSEEN]] = s * n_a + a
        ivar[K.I_NSEEN] += 1
    observe_outcome(imap, fmap, ilist, c0, fvar, n_a, s, a, r, s2, terminated,
                    s2 != s or terminated)
    n_seen = ivar[K.I_NSEEN]
    for _ in range(n_plan):
        j = ilist[draw_below(rng, n_seen)]
        ps = j // n_a
        pa = j % n_a
        if replay_fails(ilist, c0, n_a, ps, pa, rng):
            q_learning(q, ps, pa, fvar[K.F_RFAIL], ps, False, alpha, gamma, 0.0)
        else:
            q_learning(q, ps, pa, fmap[ps, pa], imap[ps, pa], imap[ps, n_a + pa] != 0,
                       alpha, gamma, 0.0)


# ---------------------------------------------------------------- HAQL
@njit(cache=True)
def haql_score(q, s, b, m, pi_h, xi, beta, eta):
    """Q(s,b) + xi * H(s,b)^beta, H = max Q - Q(s,b) + eta on the heuristic move, else 0."""
    if b != pi_h:
        return q[s, b]
    return q[s, b] + xi * (m - q[s, b] + eta) ** beta


@njit(cache=True)
def haql_first(q, s, pi_h, xi, beta, eta):
    """argmax of the HAQL scores, ties to the lowest index (the deterministic test policy)."""
    m = row_max(q, s)
    best = haql_score(q, s, 0, m, pi_h, xi, beta, eta)
    a = 0
    for b in range(1, q.shape[1]):
        v = haql_score(q, s, b, m, pi_h, xi, beta, eta)
        if v > best:
            best = v
            a = b
    return a


@njit(cache=True, inline="always")
def haql_greedy(q, s, pi_h, xi, beta, eta, rng):
    """argmax of the HAQL scores; ties broken with ``rng.integers(0, n_ties)``."""
    m = row_max(q, s)
    best = haql_score(q, s, 0, m, pi_h, xi, beta, eta)
    a = 0
    ties = 1
    for b in range(1, q.shape[1]):
        v = haql_score(q, s, b, m, pi_h, xi, beta, eta)
        if v > best:
            best = v
            a = b
            ties = 1
        elif v == best:
            ties += 1
    if ties == 1:
        return a
    k = rng.integers(0, ties)
    for b in range(q.shape[1]):
        if haql_score(q, s, b, m, pi_h, xi, beta, eta) == best:
            if k == 0:
                return b
            k -= 1
    return a
