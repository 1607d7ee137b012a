"""Tabular Q-learning (Watkins 1989): ``st-ql`` (Q0 = 0) and ``q-opt`` (optimistic Q0).

The smallest method, and the template of the others: a frozen config, a named
state, and the four hooks every method has (``act``, ``update``, ``begin``,
``exploit``), all ``inline="always"`` so the kernels fuse them into one loop.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import BaseParams, MethodConfig
from learning.geometry import Geometry
from learning.parts.tabular import begin_plain, eps_greedy, exploit_q, q_learning
from learning.parts.tally import Tally, new_tally

HOOK = dict(cache=True, inline="always")


@dataclass(frozen=True)
class STQL(MethodConfig):
    """Tabular Q-learning, Q0 = 0 (Watkins 1989)."""

    name: ClassVar[str] = "ST-QL"
    cli: ClassVar[str] = "st-ql"
    q0: float = 0.0  # initial Q for every (s, a) [reward units]


@dataclass(frozen=True)
class QOpt(STQL):
    """Q-learning with optimistic initial values: Q0 = the goal reward."""

    name: ClassVar[str] = "Q-OPT"
    cli: ClassVar[str] = "q-opt"
    q0: float = 100.0  # initial Q [reward units]; the paper's goal reward


class State(NamedTuple):
    par: BaseParams
    tally: Tally
    q: np.ndarray  # float64[nS, nA]


def init_state(cfg: STQL, geom: Geometry, rng: np.random.Generator) -> State:
    return State(cfg.params(), new_tally(), np.full((geom.n_states, geom.n_actions), cfg.q0))


@njit(**HOOK)
def act(st, s, rng):
    return eps_greedy(st.q, s, st.par.eps, rng)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    q_learning(st.q, s, a, r, s2, terminated, st.par.alpha, st.par.gamma, 0.0)


begin = begin_plain
exploit = exploit_q
