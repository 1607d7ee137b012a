"""RNH-QL+ (``rnh-ql+``): RNH-QL's two layers, fixed where the ablation's measurements show
them breaking; the upper layer is an optimistic model of the map.

``config`` (the method's knobs), ``state`` (named arrays), ``optimism`` (the optimistic
value y), ``planning`` (the shaped model updates), ``rules`` (the hooks). The ablation's
variants are the method ``rnh-ql+ablation`` (:mod:`learning.methods.rnh_ql_plus_ablation`).
"""

from __future__ import annotations

import numpy as np

from learning.methods.rnh_ql_plus.config import Params, RNHQLPlus, RNHQLPlusExplore
from learning.methods.rnh_ql_plus.rules import act, begin, exploit, potential_table, update
from learning.methods.rnh_ql_plus.state import ADDED, DERIVED, State, init_state


def potential(st: State) -> np.ndarray:
    """float64[nS]: Phi(s) over every state, the value the rules shape with."""
    out = np.zeros(st.q.shape[0])
    potential_table(st, out)
    return out


__all__ = ["ADDED", "DERIVED", "Params", "RNHQLPlus", "RNHQLPlusExplore", "State", "act",
           "begin", "exploit", "init_state", "potential", "update"]
