"""Watkins Q(lambda) eligibility traces on a Q-table: what ``q-lambda`` and RNH-QL+'s
``lam_q`` share.

Replacing traces ``e[nS, nA]``; only the pairs touched since the last cut are
kept in a list, so a step costs the trace's length, not the table's size.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from learning.parts.tabular import is_greedy, row_max


class QTraces(NamedTuple):
    e: np.ndarray  # float64[nS, nA]; the traces
    pairs: np.ndarray  # int32[nS * nA]; touched flat pairs s * nA + a, the first n[0] in use
    n: np.ndarray  # int64[1]


def new_traces(n_s: int, n_a: int) -> QTraces:
    return QTraces(np.zeros((n_s, n_a)), np.zeros(n_s * n_a, dtype=np.int32),
                   np.zeros(1, dtype=np.int64))


@njit(cache=True)
def clear_traces(e, pairs, n):
    """Zero the touched traces. Takes :class:`QTraces`' arrays (compiled hooks read a
    named tuple's fields once, at their top; see :mod:`learning.methods.rnh_ql_plus.rules`)."""
    n_a = e.shape[1]
    for i in range(n[0]):
        e[pairs[i] // n_a, pairs[i] % n_a] = 0.0
    n[0] = 0


@njit(cache=True)
def q_lambda(q, e, tl, n_used, s, a, r, s2, terminated, alpha, gamma, lam, trace_min, f):
    """Tabular Watkins Q(lambda) with replacing traces; ``f`` is a shaping term.

    Cutting the traces when the action *taken* is non-greedy (before its trace
    is set) is Sutton & Barto's "cut when the next action is exploratory".
    Only the touched pairs are visited; traces below trace_min are dropped. ``e``,
    ``tl``, ``n_used``: :class:`QTraces`' ``e``, ``pairs`` and ``n``.
    """
    n_a = q.shape[1]
    n = n_used[0]
    if not is_greedy(q, s, a):
        clear_traces(e, tl, n_used)
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
    n_used[0] = n
