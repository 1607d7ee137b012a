"""ST-QL written as a batched plain learner (:mod:`learning.plain.batched`): one numpy call
per step for every run of a lock-step batch, each run drawing from its own stream what
the compiled ``st-ql`` draws (one ``random()`` per act, then ``integers(0, 4)`` when
exploring or ``integers(0, ties)`` on a greedy tie), so its runs equal ``st-ql``'s."""

from __future__ import annotations

import numpy as np


class STQLBatched:
    name = "ST-QL (numpy, batched)"
    eps = 0.1
    batched = True

    def __init__(self, n_states: int, n_actions: int, rngs: list[np.random.Generator]) -> None:
        self.q = np.zeros((len(rngs), n_states, n_actions))
        self.rngs = list(rngs)
        self.alpha, self.gamma = 0.1, 0.95

    def act_batch(self, runs: np.ndarray, states: np.ndarray) -> np.ndarray:
        rows = self.q[runs, states]  # (k, n_actions)
        rngs = self.rngs
        u = np.fromiter((rngs[i].random() for i in runs.tolist()), float, runs.size)
        tied = rows == rows.max(axis=1, keepdims=True)
        out = tied.argmax(axis=1)
        n_ties = tied.sum(axis=1)
        explore = u < self.eps
        need = np.flatnonzero(explore | (n_ties > 1))  # runs that draw a second number
        if need.size:
            bound = np.where(explore[need], rows.shape[1], n_ties[need])
            draws = np.fromiter((rngs[i].integers(0, b) for i, b in
                                 zip(runs[need].tolist(), bound.tolist(), strict=True)),
                                np.int64, need.size)
            # a tie: the draws-th of the tied actions, in action order
            nth = (np.cumsum(tied[need], axis=1) == (draws + 1)[:, None]) & tied[need]
            out[need] = np.where(explore[need], draws, nth.argmax(axis=1))
        return out

    def update_batch(self, runs, states, actions, rewards, next_states, terminal) -> None:
        q = self.q
        target = rewards + np.where(terminal, 0.0, self.gamma * q[runs, next_states].max(axis=1))
        q[runs, states, actions] += self.alpha * (target - q[runs, states, actions])

    def greedy(self, run: int, state: int) -> int:
        return int(np.argmax(self.q[run, state]))
