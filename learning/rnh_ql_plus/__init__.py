"""RNH-QL+ (``rnh-ql+``): RNH-QL's two layers, fixed where the ablation's measurements show
them breaking; the upper layer by default is an optimistic model of the map.

``config`` (every ingredient a field), ``state`` (named arrays), ``features``
(sparse, leak-free), ``optimism`` (the optimistic value y), ``rules`` (the hooks).
"""

from __future__ import annotations

import numpy as np

from learning.rnh_ql_plus.config import LeanParams, Params, Potential, RNHQLPlus
from learning.rnh_ql_plus.rules import act, begin, exploit, lean_hooks, potential_table, update
from learning.rnh_ql_plus.state import DERIVED, State, init_state


def potential(st: State) -> np.ndarray:
    """float64[nS]: Phi(s) over every state, the value the rules shape with."""
    out = np.zeros(st.q.shape[0])
    potential_table(st, out)
    return out


# a state whose ``par`` is a LEAN_PARAMS compiles LEAN_HOOKS (learning.hooks)
LEAN_PARAMS = LeanParams
LEAN_HOOKS = lean_hooks()

__all__ = ["DERIVED", "LEAN_HOOKS", "LEAN_PARAMS", "LeanParams", "Params", "Potential",
           "RNHQLPlus", "State", "act", "begin", "exploit", "init_state", "potential", "update"]
