"""RNH-QL+ (``rnh-ql+``): RNH-QL's two layers, fixed where the ablation's measurements show
them breaking; the upper layer by default is an optimistic model of the map.

``config`` (every ingredient a field), ``state`` (named arrays), ``features``
(sparse, leak-free), ``optimism`` (the optimistic value y), ``rules`` (the hooks).
"""

from __future__ import annotations

import numpy as np

from learning.rnh_ql_plus.config import Params, Potential, RNHQLPlus
from learning.rnh_ql_plus.rules import act, begin, exploit, potential_table, update
from learning.rnh_ql_plus.state import DERIVED, State, init_state


def potential(st: State) -> np.ndarray:
    """float64[nS]: Phi(s) over every state, the value the rules shape with."""
    out = np.zeros(st.q.shape[0])
    potential_table(st, out)
    return out


__all__ = ["DERIVED", "Params", "Potential", "RNHQLPlus", "State", "act", "begin", "exploit",
           "init_state", "potential", "update"]
