"""Dyna-Q (Sutton 1990, ``dyna-q``): Q-learning plus planning from a learned model of moves.

After each real step, ``n_planning`` Q updates on pairs drawn uniformly from the
pairs seen (Sutton & Barto 8.2), each replaying an outcome drawn from the move
model (:mod:`learning.move_model`; a move "works" when it moved at all).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import MethodConfig
from learning.geometry import Geometry
from learning.move_model import (
    MoveModel,
    draw_seen,
    new_move_model,
    note_pair,
    observe_outcome,
    replay_fails,
)
from learning.tabular import argmax_first, eps_greedy, q_learning
from learning.tally import Tally, begin_tally, new_tally

HOOK = dict(cache=True, inline="always")


@dataclass(frozen=True)
class DynaQ(MethodConfig):
    """Dyna-Q (Sutton 1990): Q-learning + planning from a learned deterministic model."""

    name: ClassVar[str] = "DYNA-Q"
    cli: ClassVar[str] = "dyna-q"
    n_planning: int = 5  # simulated Q updates per real step, (s, a) uniform over seen pairs

    def params(self) -> Params:
        return Params(float(self.eps), float(self.alpha), float(self.gamma),
                      int(self.n_planning))


class Params(NamedTuple):
    eps: float
    alpha: float
    gamma: float
    n_planning: int


class State(NamedTuple):
    par: Params
    tally: Tally
    q: np.ndarray  # float64[nS, nA]
    model: MoveModel


def init_state(cfg: DynaQ, geom: Geometry, rng: np.random.Generator) -> State:
    n_s, n_a = geom.n_states, geom.n_actions
    return State(cfg.params(), new_tally(), np.zeros((n_s, n_a)), new_move_model(n_s, n_a))


@njit(**HOOK)
def act(st, s, rng):
    return eps_greedy(st.q, s, st.par.eps, rng)


@njit(cache=True)
def _plan(q, m, n_plan, alpha, gamma, rng):
    for _ in range(n_plan):
        ps, pa = draw_seen(m, rng)
        if replay_fails(m, ps, pa, rng):
            q_learning(q, ps, pa, m.r_fail[0], ps, False, alpha, gamma, 0.0)
        else:
            q_learning(q, ps, pa, m.reward[ps, pa], m.successor[ps, pa], m.to_goal[ps, pa],
                       alpha, gamma, 0.0)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """Q-learning, then the model learns (s, a) -> (r, s', terminated), then planning."""
    p = st.par
    m = st.model
    q_learning(st.q, s, a, r, s2, terminated, p.alpha, p.gamma, 0.0)
    note_pair(m, s, a)
    observe_outcome(m, s, a, r, s2, terminated, s2 != s or terminated)
    _plan(st.q, m, p.n_planning, p.alpha, p.gamma, rng)


@njit(**HOOK)
def begin(st, s0):
    begin_tally(st.tally)


@njit(**HOOK)
def exploit(st, s):
    return argmax_first(st.q, s)
