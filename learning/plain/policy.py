"""A fixed policy as a learner's state: what the compiled readers grade when the policy was not
learned by a compiled method (a plain-Python learner's greedy choices, a policy trained
elsewhere).

Every reader of a policy (the greedy walk from S, the share of cells whose move is on a
shortest route, the epsilon-greedy rollouts, the greedy table a physics drive follows)
takes a learner's named state and calls its ``exploit`` hook. A :class:`State` here holds
an action per cell (``table``) and, for recordings, the Q-table the policy came from when
there is one, so those readers grade any policy with the code they grade the compiled
methods with. It learns nothing: ``update`` and ``begin`` leave it as it is.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from learning.config import BaseParams
from learning.parts.tally import Tally, new_tally

HOOK = dict(cache=True, inline="always")


class State(NamedTuple):
    par: BaseParams
    tally: Tally
    q: np.ndarray  # float64[nS, nA]; the values the policy is greedy in (zeros if none)
    table: np.ndarray  # int64[nS]; the action in each cell


def policy_state(table: np.ndarray, q: np.ndarray | None = None, n_actions: int = 4,
                 eps: float = 0.1) -> State:
    """The state of the policy ``table`` (an action per cell); ``q`` shown by recordings."""
    table = np.ascontiguousarray(table, dtype=np.int64)
    if q is None:
        q = np.zeros((table.shape[0], n_actions))
    q = np.ascontiguousarray(q, dtype=np.float64)
    return State(BaseParams(float(eps), 0.0, 1.0), new_tally(), q, table)


@njit(**HOOK)
def act(st, s, rng):
    if rng.random() < st.par.eps:
        return rng.integers(0, st.q.shape[1])
    return st.table[s]


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    pass


@njit(**HOOK)
def begin(st, s0):
    pass


@njit(**HOOK)
def exploit(st, s):
    return st.table[s]


def n_states(st: State) -> int:
    return int(st.table.shape[0])


def q_table(st: State) -> np.ndarray:
    return st.q.copy()
