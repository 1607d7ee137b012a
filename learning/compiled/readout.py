"""Read a learner's state out as plain tables, for plots and recordings (not training).

Every method is viewed the same way: Q over all states (a method whose Q is not a
table says how, e.g. RN-QL's nets evaluated per state), the exploitation action of
every state, and the shaping potential of the methods that learn one.
"""

from __future__ import annotations

import numpy as np

from learning.compiled.kernels import policy_table
from learning.methods.registry import family_of_state, n_states_of


def greedy_actions(st) -> np.ndarray:
    """int64[nS]: the method's exploitation action in every state (ties: lowest index); read
    through the kernels' one policy-reading entry point (no compilation of its own)."""
    return policy_table(st, n_states_of(st))


def q_table(st) -> np.ndarray:
    """float64[nS, nA]: Q(s, a) for every state, whatever holds it."""
    fam = family_of_state(st)
    if hasattr(fam, "q_table"):
        return fam.q_table(st)
    return st.q.copy()


def potential(st) -> np.ndarray | None:
    """float64[nS]: the potential the method shapes with (V_NN of RNH-QL, Phi of RNH-QL+);
    None for methods without a learned one."""
    fam = family_of_state(st)
    return fam.potential(st) if hasattr(fam, "potential") else None
