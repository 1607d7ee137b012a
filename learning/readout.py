"""Read a learner's state out as plain tables, for plots and recordings (not training).

Every method is viewed the same way: Q over all states (RN-QL's nets
evaluated per state, scaled back to reward units), the exploitation action of
every state, and RNH-QL's potential V_NN = phi . w.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from learning import kinds as K
from learning.dispatch import exploit_action
from learning.mlp import net_row
from learning.state import AgentState


@njit(cache=True)
def _greedy_all(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, out):
    for s in range(out.shape[0]):
        out[s] = exploit_action(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s)


@njit(cache=True)
def _net_table(w, feat, scratch, out):
    for s in range(out.shape[0]):
        net_row(w, feat, s, scratch)
        out[s, :] = scratch[0, :]


def greedy_actions(st: AgentState) -> np.ndarray:
    """int64[nS]: the method's exploitation action in every state (ties: lowest index)."""
    out = np.zeros(st.feat.shape[0], dtype=np.int64)
    _greedy_all(int(st.ivar[K.I_KIND]), *st, out)
    return out


def q_table(st: AgentState) -> np.ndarray:
    """float64[nS, nA]: Q(s, a) for every state, whatever holds it."""
    if int(st.ivar[K.I_KIND]) != K.RNQL:
        return st.q.copy()
    n_actions = st.q.shape[1]
    out = np.zeros((st.feat.shape[0], n_actions))
    _net_table(st.w, st.feat, np.zeros((1, n_actions)), out)
    return out * st.par[K.P_QSCALE]


def potential(st: AgentState) -> np.ndarray | None:
    """float64[nS]: the shaping potential over every state: V_NN(s) of RNH-QL, Phi(s) of
    RNH-QL+ (the value its rules shape with, :func:`learning.rules_plus.potential`);
    None for other methods."""
    kind = int(st.ivar[K.I_KIND])
    if kind == K.RNHQL:
        return st.feat @ st.w
    if kind == K.RNHQLP:
        from learning.rules_plus import potential_table

        out = np.zeros(st.q.shape[0])
        potential_table(st.fvar, st.par, st.w, st.e, st.feat, st.imap, st.ilist, out)
        return out
    return None
