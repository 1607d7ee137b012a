"""ST-QL (Watkins' Q-learning, Q0 = 0) written to the plain-learner protocol, drawing what the
compiled ``st-ql`` draws in the same order: one ``random()`` per act, then
``integers(0, 4)`` when exploring or ``integers(0, ties)`` on a greedy tie."""

from __future__ import annotations

import numpy as np


class STQLPort:
    name = "ST-QL (Python)"
    eps = 0.1

    def __init__(self, n_states: int, n_actions: int, rng: np.random.Generator) -> None:
        self.q = np.zeros((n_states, n_actions))
        self.rng = rng
        self.alpha, self.gamma = 0.1, 0.95

    def act(self, s: int) -> int:
        if self.rng.random() < self.eps:
            return int(self.rng.integers(0, self.q.shape[1]))
        row = self.q[s]
        best = np.flatnonzero(row == row.max())
        if best.size == 1:
            return int(best[0])
        return int(best[self.rng.integers(0, best.size)])

    def update(self, s: int, a: int, r: float, s2: int, terminal: bool) -> None:
        target = r if terminal else r + self.gamma * self.q[s2].max()
        self.q[s, a] += self.alpha * (target - self.q[s, a])

    def greedy(self, s: int) -> int:
        return int(np.argmax(self.q[s]))
