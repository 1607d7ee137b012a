"""ST-QL written as a batched plain learner the way one writes numpy for speed: each run
draws its random numbers in blocks from its own stream, so a step of the whole batch is a
dozen array operations and no Python loop over runs.

The algorithm is ST-QL's (ε-greedy with ε = 0.1, ties broken uniformly at random, α = 0.1,
γ = 0.95); what differs from :mod:`tests.plain_learners.st_ql_batched` is only how the
numbers are drawn: one row of ``1 + n_actions`` uniforms a decision (the first says
whether to explore, the others are random keys, and the action is the tied or, exploring,
any action with the largest key), taken from a block of ``BLOCK`` rows the run draws at
once. Its runs are therefore not ``st-ql``'s draw for draw, but each run's are its own:
run i of a batch equals run i trained alone (a batch of one), whatever else is in the batch.
"""

from __future__ import annotations

import numpy as np

from tests.plain_learners.st_ql_batched import STQLBatched

BLOCK = 4096  # decisions per draw from a run's stream


class STQLBlocks(STQLBatched):
    """The draw-for-draw port with its acting drawn in blocks; its update and greedy policy
    are the port's own."""

    name = "ST-QL (numpy, batched, block draws)"

    def __init__(self, n_states: int, n_actions: int, rngs: list[np.random.Generator]) -> None:
        super().__init__(n_states, n_actions, rngs)
        k = len(rngs)
        self.draws = np.empty((k, BLOCK, 1 + n_actions))
        self.pos = np.zeros(k, np.int64)
        for i in range(k):
            self._refill(i)

    def _refill(self, run: int) -> None:
        self.draws[run] = self.rngs[run].random(self.draws.shape[1:])
        self.pos[run] = 0

    def act_batch(self, runs: np.ndarray, states: np.ndarray) -> np.ndarray:
        pos = self.pos[runs]
        if pos.max() >= BLOCK:  # once every BLOCK decisions of a run
            for i in runs[pos >= BLOCK].tolist():
                self._refill(i)
            pos = self.pos[runs]
        d = self.draws[runs, pos]
        self.pos[runs] = pos + 1
        rows = self.q[runs, states]
        tied = rows == rows.max(axis=1, keepdims=True)
        keys = np.where(tied | (d[:, :1] < self.eps), d[:, 1:], -1.0)
        return keys.argmax(axis=1)

    def greedy_all(self, run: int) -> np.ndarray:
        return self.q[run].argmax(axis=1)
