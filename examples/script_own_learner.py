"""A learner of your own, in plain Python, against rnh-ql+ and st-ql: no numba, nothing added
to the installed package. The same seeds, start cells, greedy tests and records as the
compiled methods (docs/python-api.md).

The learner here is Q-learning with a count-based exploration bonus (an optimism of
``beta / sqrt(n(s, a))`` added to the greedy choice, Strehl & Littman 2008 in spirit):
some 30 lines. From the command line the same comparison is
``rnhql compare paper-40 --methods rnh-ql+,st-ql,mymodule:CountBonusQ --out out/count`` with
this class in ``mymodule.py`` on ``PYTHONPATH``.

Run as pasted: ``python examples/script_own_learner.py`` (about a minute);
``RNHQL_EXAMPLE_SCALE=0.01`` shrinks the budget (CI does).
"""

import os

import numpy as np

from scenarios import api

SCALE = float(os.environ.get("RNHQL_EXAMPLE_SCALE", "1"))


class CountBonusQ:
    """Q-learning whose behaviour is greedy in Q + beta / sqrt(1 + visits(s, a))."""

    name = "COUNT-Q"
    eps = 0.1  # only for the paper's epsilon-greedy test of the final policy

    def __init__(self, n_states: int, n_actions: int, rng: np.random.Generator) -> None:
        self.q = np.zeros((n_states, n_actions))
        self.visits = np.zeros((n_states, n_actions))
        self.rng = rng  # the run's learner stream: ties are broken with it
        self.alpha, self.gamma, self.beta = 0.1, 0.95, 1.0

    def act(self, s: int) -> int:
        scores = self.q[s] + self.beta / np.sqrt(1.0 + self.visits[s])
        best = np.flatnonzero(scores == scores.max())
        return int(best[self.rng.integers(best.size)]) if best.size > 1 else int(best[0])

    def update(self, s: int, a: int, r: float, s2: int, terminal: bool) -> None:
        self.visits[s, a] += 1
        target = r if terminal else r + self.gamma * self.q[s2].max()
        self.q[s, a] += self.alpha * (target - self.q[s, a])

    def greedy(self, s: int) -> int:
        return int(np.argmax(self.q[s]))


if __name__ == "__main__":  # the workers of a sweep may re-import this file
    cmp = api.compare("paper-40", ["rnh-ql+", "st-ql", CountBonusQ],
                      seeds=max(2, round(10 * SCALE)), episodes=max(20, round(1000 * SCALE)),
                      progress=True)
    print(cmp.summary())
    for method in cmp.methods:
        runs = cmp.of(method)
        found = sum(r.final_route_optimal for r in runs)
        seconds = np.median([r.wall_time_s for r in runs])
        print(f"{runs[0].method_name}: final route optimal in {found}/{len(runs)} seeds, "
              f"median {seconds:.2f} s of training per run")
