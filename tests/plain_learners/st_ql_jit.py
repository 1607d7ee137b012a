"""ST-QL written as a numba ``@jitclass`` to the plain-learner protocol: the same draws as the
compiled ``st-ql`` (and as :mod:`tests.plain_learners.st_ql`), run inside a compiled loop."""

from __future__ import annotations

import numba
import numpy as np
from numba import types
from numba.experimental import jitclass

SPEC = [("q", types.float64[:, :]), ("rng", numba.typeof(np.random.default_rng(0))),
        ("eps", types.float64), ("alpha", types.float64), ("gamma", types.float64)]


@jitclass(SPEC)
class STQLJit:
    def __init__(self, n_states, n_actions, rng):
        self.q = np.zeros((n_states, n_actions))
        self.rng = rng
        self.eps, self.alpha, self.gamma = 0.1, 0.1, 0.95

    def act(self, s):
        q = self.q
        if self.rng.random() < self.eps:
            return self.rng.integers(0, q.shape[1])
        best, a, ties = q[s, 0], 0, 1
        for b in range(1, q.shape[1]):
            if q[s, b] > best:
                best, a, ties = q[s, b], b, 1
            elif q[s, b] == best:
                ties += 1
        if ties == 1:
            return a
        k = self.rng.integers(0, ties)  # a tie: which of them, as st-ql draws it
        for b in range(q.shape[1]):
            if q[s, b] == best:
                if k == 0:
                    return b
                k -= 1
        return a

    def update(self, s, a, r, s2, terminal):
        q = self.q
        target = r
        if not terminal:
            m = q[s2, 0]
            for b in range(1, q.shape[1]):
                m = max(m, q[s2, b])
            target += self.gamma * m
        q[s, a] += self.alpha * (target - q[s, a])

    def greedy(self, s):
        return np.argmax(self.q[s])
