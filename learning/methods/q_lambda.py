"""Tabular Watkins Q(lambda) (``q-lambda``), replacing traces cut on non-greedy actions."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import MethodConfig, params_tuple
from learning.geometry import Geometry
from learning.parts.tabular import eps_greedy, exploit_q
from learning.parts.tally import Tally, begin_tally, new_tally
from learning.parts.traces import QTraces, clear_traces, new_traces, q_lambda

HOOK = dict(cache=True, inline="always")


Params = params_tuple("Params", __name__, lam=float, trace_min=float)


@dataclass(frozen=True)
class QLambda(MethodConfig):
    """Tabular Watkins Q(lambda), replacing traces, cut when a non-greedy action is taken.

    Replacing (not accumulating) traces: a bump keeps the agent in its cell, and
    accumulating traces on such self-loops grow to 1/(1-gamma*lambda) ~ 5.
    """

    name: ClassVar[str] = "Q(lambda)"
    cli: ClassVar[str] = "q-lambda"
    lam: float = 0.85  # trace decay lambda
    trace_min: float = 1e-8  # traces below this are dropped (keeps the trace list short)

    params_type: ClassVar[type] = Params


class State(NamedTuple):
    par: Params
    tally: Tally
    q: np.ndarray  # float64[nS, nA]
    traces: QTraces


def init_state(cfg: QLambda, geom: Geometry, rng: np.random.Generator) -> State:
    n_s, n_a = geom.n_states, geom.n_actions
    return State(cfg.params(), new_tally(), np.zeros((n_s, n_a)), new_traces(n_s, n_a))


@njit(**HOOK)
def act(st, s, rng):
    return eps_greedy(st.q, s, st.par.eps, rng)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    p = st.par
    q_lambda(st.q, st.traces.e, st.traces.pairs, st.traces.n, s, a, r, s2, terminated, p.alpha,
             p.gamma, p.lam, p.trace_min, 0.0)


@njit(**HOOK)
def begin(st, s0):
    begin_tally(st.tally)
    clear_traces(st.traces.e, st.traces.pairs, st.traces.n)


exploit = exploit_q
