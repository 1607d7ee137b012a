"""The RNH-QL+ ablation (``rnh-ql+ablation``): rnh-ql+ with every switch the README's ablation
turned (network potentials, RBF features, leak-free supports, re-based rows, Q traces), each
a config field; at its defaults it runs as rnh-ql+ does.

``config`` (every switch a field), ``state`` (named arrays), ``features`` (sparse,
leak-free), ``potential`` (V_NN and the potentials), ``rules`` (the hooks). It builds on
:mod:`learning.methods.rnh_ql_plus` (the optimistic model, planning, the model's update).
"""

from __future__ import annotations

import numpy as np

from learning.methods.rnh_ql_plus_ablation.config import Params, Potential, RNHQLPlusAblation
from learning.methods.rnh_ql_plus_ablation.rules import act, begin, exploit, potential_table, update
from learning.methods.rnh_ql_plus_ablation.state import ADDED, DERIVED, State, init_state


def potential(st: State) -> np.ndarray:
    """float64[nS]: Phi(s) over every state, the value the rules shape with."""
    out = np.zeros(st.q.shape[0])
    potential_table(st, out)
    return out


__all__ = ["ADDED", "DERIVED", "Params", "Potential", "RNHQLPlusAblation", "State", "act", "begin",
           "exploit", "init_state", "potential", "update"]
