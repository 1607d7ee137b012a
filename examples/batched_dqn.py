"""A DQN in torch, written to the batched plain-learner protocol: one forward pass per step
for every run of a batch (seeds x robots), nothing added to the installed package.

Each run has its own network (the runs' weights are stacked and multiplied batch-wise,
``torch.bmm``), its own replay buffer and its own target network; every random number a
run uses (exploration, initial weights, replay samples) comes from that run's stream
(``rngs[run]``), so a run's figures do not depend on which other runs share its batch.
Plain SGD, not Adam: a run that sits out a step gets a zero gradient, and Adam's momentum
would still move its weights. The network reads the state's index through an embedding
(the protocol gives a learner states, not coordinates), then two layers.

From the command line: ``rnhql compare paper-40 --methods rnh-ql+,examples.batched_dqn:BatchedDQN
--world grid,physics --rewards goal-only --out out/dqn``. Run as pasted:
``python examples/batched_dqn.py`` (a few minutes); ``RNHQL_EXAMPLE_SCALE=0.01`` shrinks
the budget (CI does). docs/python-api.md gives the measured comparison.
"""

from __future__ import annotations

import os

import numpy as np
import torch

from scenarios import api

SCALE = float(os.environ.get("RNHQL_EXAMPLE_SCALE", "1"))


class BatchedDQN:
    """Deep Q-learning (Mnih et al. 2015): an epsilon-greedy behaviour on a Q-network, trained
    on minibatches from a replay buffer toward a target network's values."""

    name = "DQN (torch)"
    eps = 0.1
    batched = True
    embed, hidden = 16, 64  # network widths
    lr, gamma = 0.05, 0.95  # SGD step size; discount
    minibatch, capacity, warmup = 32, 20_000, 256  # [transitions]
    train_every, target_every = 4, 500  # a minibatch step every 4 moves of a run [moves]

    def __init__(self, n_states: int, n_actions: int, rngs: list[np.random.Generator]) -> None:
        torch.set_num_threads(1)  # a sweep runs one worker per core: no threads on top
        self.rngs = list(rngs)
        k = len(rngs)
        self.n_actions = n_actions

        def init(shape: tuple[int, ...], scale: float) -> torch.Tensor:
            w = np.stack([r.normal(0.0, scale, shape) for r in self.rngs])
            return torch.tensor(w, dtype=torch.float32, requires_grad=True)

        self.params = [init((n_states, self.embed), 1.0),
                       init((self.embed, self.hidden), self.embed ** -0.5),
                       init((1, self.hidden), 0.0),
                       init((self.hidden, n_actions), self.hidden ** -0.5),
                       init((1, n_actions), 0.0)]
        self.target = [p.detach().clone() for p in self.params]
        self.buf_s = np.zeros((k, self.capacity), np.int64)
        self.buf_a = np.zeros((k, self.capacity), np.int64)
        self.buf_r = np.zeros((k, self.capacity), np.float32)
        self.buf_s2 = np.zeros((k, self.capacity), np.int64)
        self.buf_done = np.zeros((k, self.capacity), np.float32)
        self.size = np.zeros(k, np.int64)
        self.steps = np.zeros(k, np.int64)

    def _q(self, params: list[torch.Tensor], runs: torch.Tensor,
           states: torch.Tensor) -> torch.Tensor:
        """Q of ``states`` (runs x n) under each run's own network: (runs, n, actions)."""
        emb, w1, b1, w2, b2 = params
        x = emb[runs[:, None], states]  # (m, n, embed)
        h = torch.relu(torch.bmm(x, w1[runs]) + b1[runs])
        return torch.bmm(h, w2[runs]) + b2[runs]

    def act_batch(self, runs: np.ndarray, states: np.ndarray) -> np.ndarray:
        u = np.fromiter((self.rngs[i].random() for i in runs.tolist()), float, runs.size)
        with torch.no_grad():
            q = self._q(self.params, torch.from_numpy(runs), torch.from_numpy(states)[:, None])
        out = q[:, 0].argmax(dim=1).numpy()
        for j in np.flatnonzero(u < self.eps):
            out[j] = self.rngs[runs[j]].integers(0, self.n_actions)
        return out

    def update_batch(self, runs, states, actions, rewards, next_states, terminal) -> None:
        at = self.steps[runs] % self.capacity
        self.buf_s[runs, at], self.buf_a[runs, at] = states, actions
        self.buf_r[runs, at], self.buf_s2[runs, at] = rewards, next_states
        self.buf_done[runs, at] = terminal
        self.steps[runs] += 1
        self.size[runs] = np.minimum(self.size[runs] + 1, self.capacity)
        ready = runs[(self.size[runs] >= self.warmup)
                     & (self.steps[runs] % self.train_every == 0)]
        if ready.size:
            self._learn(ready)
        due = runs[self.steps[runs] % self.target_every == 0]
        for p, t in zip(self.params, self.target, strict=True):
            t[due] = p.detach()[due]

    def _learn(self, runs: np.ndarray) -> None:
        idx = np.stack([self.rngs[i].integers(0, self.size[i], self.minibatch)
                        for i in runs.tolist()])
        rows = runs[:, None]
        r_t = torch.from_numpy(runs)
        s, a = torch.from_numpy(self.buf_s[rows, idx]), torch.from_numpy(self.buf_a[rows, idx])
        r, s2 = torch.from_numpy(self.buf_r[rows, idx]), torch.from_numpy(self.buf_s2[rows, idx])
        done = torch.from_numpy(self.buf_done[rows, idx])
        with torch.no_grad():
            target = r + self.gamma * (1.0 - done) * self._q(self.target, r_t, s2).max(dim=2)[0]
        q = self._q(self.params, r_t, s).gather(2, a[:, :, None])[:, :, 0]
        loss = torch.nn.functional.smooth_l1_loss(q, target, reduction="sum") / self.minibatch
        for p in self.params:
            p.grad = None
        loss.backward()
        with torch.no_grad():
            for p in self.params:
                p -= self.lr * p.grad

    def greedy(self, run: int, state: int) -> int:
        return int(self.greedy_all(run)[state])

    def greedy_all(self, run: int) -> np.ndarray:
        """Every state's greedy action of run ``run``: one forward pass."""
        n = self.params[0].shape[1]
        with torch.no_grad():
            q = self._q(self.params, torch.tensor([run]), torch.arange(n)[None, :])
        return q[0].argmax(dim=1).numpy()


if __name__ == "__main__":  # the workers of a sweep may re-import this file
    cmp = api.compare("paper-40", ["rnh-ql+", BatchedDQN], worlds=("grid", "physics"),
                      seeds=max(2, round(10 * SCALE)), episodes=max(4, round(300 * SCALE)),
                      rewards="goal-only", progress=True)
    print(cmp.summary())
