"""Each rule family's agent events (act, update, episode start, exploitation), one function each.

:mod:`learning.dispatch` routes an event to the family's function here, both
for the kernels (chosen while compiling, from the family id as a constant) and
for the step agent (a run-time switch). All take the agent state as its ten
arrays, in :class:`learning.state.AgentState` order, then the event's values.
"""

from __future__ import annotations

from numba import njit

from learning import kinds as K
from learning.explored import observe
from learning.mlp import net_row, q_lambda_net
from learning.rbf import td_lambda, value
from learning.rules import (
    argmax_first,
    clear_traces,
    dyna_q,
    eps_greedy,
    haql_first,
    haql_greedy,
    is_greedy,
    q_lambda,
    q_learning,
    record_shaping,
)
from learning.shaping import sarsa_rs, static_shaping

INLINE = dict(cache=True, inline="always")

# ---------------------------------------------------------------- act: behaviour policy


@njit(**INLINE)
def act_eps_greedy(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng):
    """Epsilon-greedy on the Q-table (QL, PFH, RNHQL, QLAMBDA, DYNA)."""
    return eps_greedy(q, s, par[K.P_EPS], rng)


@njit(**INLINE)
def act_sarsars(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng):
    """Replay the action SARSA chose at its last update (no draws), else epsilon-greedy."""
    a = ivar[K.I_PENDING]
    if a >= 0:
        ivar[K.I_PENDING] = -1
        return a
    return eps_greedy(q, s, par[K.P_EPS], rng)


@njit(**INLINE)
def act_haql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng):
    """Epsilon-greedy around argmax[Q + xi * H^beta]."""
    if rng.random() < par[K.P_EPS]:
        return rng.integers(0, q.shape[1])
    return haql_greedy(q, s, imap[s, 0], par[K.P_XI], par[K.P_BETA_H], par[K.P_ETA], rng)


@njit(**INLINE)
def act_rnql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng):
    """Epsilon-greedy on the nets' Q(s, .) (evaluated into the scratch row fmap[0])."""
    net_row(w, feat, s, fmap)
    return eps_greedy(fmap, 0, par[K.P_EPS], rng)


# ---------------------------------------------------------------- exploitation (tests)


@njit(**INLINE)
def exploit_q(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s):
    return argmax_first(q, s)


@njit(**INLINE)
def exploit_haql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s):
    return haql_first(q, s, imap[s, 0], par[K.P_XI], par[K.P_BETA_H], par[K.P_ETA])


@njit(**INLINE)
def exploit_rnql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s):
    net_row(w, feat, s, fmap)
    return argmax_first(fmap, 0)


# ---------------------------------------------------------------- update


@njit(**INLINE)
def update_ql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated, rng):
    q_learning(q, s, a, r, s2, terminated, par[K.P_ALPHA], par[K.P_GAMMA], 0.0)


@njit(**INLINE)
def update_haql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                rng):
    """Q-learning, and the heuristic from exploration learns from a bump (learning.explored)."""
    q_learning(q, s, a, r, s2, terminated, par[K.P_ALPHA], par[K.P_GAMMA], 0.0)
    observe(imap, ilist, s, a, s2, terminated, par[K.P_EXPLORED] != 0.0)


@njit(**INLINE)
def update_pfh(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated, rng):
    gamma = par[K.P_GAMMA]
    f = static_shaping(feat, s, s2, terminated, gamma)
    record_shaping(ivar, fvar, f)
    q_learning(q, s, a, r, s2, terminated, par[K.P_ALPHA], gamma, f)


@njit(**INLINE)
def update_rnhql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                 rng):
    """RNH-QL: TD(lambda) on V_NN, then Q-learning + F = gamma*Phi(s') - Phi(s).

    Phi(s') is V_NN(s') evaluated as s' is entered, with the weights before this
    step's V_NN update, and cached (fvar[F_PHI]) until s' is left; Phi(goal) = 0.
    """
    gamma = par[K.P_GAMMA]
    greedy = is_greedy(q, s, a)
    phi_s2 = 0.0 if terminated else value(feat, s2, w)
    if ivar[K.I_TRAIN_V] != 0:
        td_lambda(w, e, feat, s, r, phi_s2, greedy, gamma, par[K.P_LAMBDA], fvar[K.F_STEP_V])
    f = 0.0
    if ivar[K.I_SHAPING] != 0:
        f = gamma * phi_s2 - fvar[K.F_PHI]
        record_shaping(ivar, fvar, f)
    q_learning(q, s, a, r, s2, terminated, par[K.P_ALPHA], gamma, f)
    fvar[K.F_PHI] = phi_s2


@njit(**INLINE)
def update_sarsars(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                   rng):
    """Draw a' at s' first (unless terminated); SARSA-RS learns with it; act() replays it."""
    a2 = -1
    if not terminated:
        a2 = eps_greedy(q, s2, par[K.P_EPS], rng)
    sarsa_rs(q, w, imap, ivar, fvar, s, a, r, s2, a2, terminated, par[K.P_ALPHA],
             par[K.P_GAMMA], par[K.P_OMEGA], par[K.P_ALPHA_V])
    ivar[K.I_PENDING] = a2


@njit(**INLINE)
def update_qlambda(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                   rng):
    q_lambda(q, fmap, ilist, ivar, s, a, r, s2, terminated, par[K.P_ALPHA], par[K.P_GAMMA],
             par[K.P_LAMBDA], par[K.P_TRACE_MIN], 0.0)


@njit(**INLINE)
def update_dyna(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated, rng):
    dyna_q(q, imap, fmap, ilist, ivar, fvar, s, a, r, s2, terminated, par[K.P_ALPHA],
           par[K.P_GAMMA], int(par[K.P_NPLAN]), rng)


@njit(**INLINE)
def update_rnql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated, rng):
    q_lambda_net(w, e, feat, s, a, r, s2, terminated, par[K.P_ALPHA], par[K.P_GAMMA],
                 par[K.P_LAMBDA], par[K.P_QSCALE], fmap)


# ---------------------------------------------------------------- episode start


@njit(**INLINE)
def begin_common(ivar, fvar):
    """Per-episode resets every family shares: pending action, shaping sums, SMDP sums."""
    ivar[K.I_PENDING] = -1
    ivar[K.I_NF] = 0
    fvar[K.F_FSUM] = 0.0
    fvar[K.F_FSQ] = 0.0
    fvar[K.F_R] = 0.0
    fvar[K.F_GK] = 1.0


@njit(**INLINE)
def begin_plain(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0):
    begin_common(ivar, fvar)


@njit(**INLINE)
def begin_qlambda(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0):
    begin_common(ivar, fvar)
    clear_traces(fmap, ilist, ivar)


@njit(**INLINE)
def begin_rnql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0):
    begin_common(ivar, fvar)
    e[:] = 0.0


@njit(**INLINE)
def begin_rnhql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0):
    """Clear V_NN traces; shaping on from episode ``warmup``; V_NN frozen from ``freeze``;
    cache Phi(s0)."""
    begin_common(ivar, fvar)
    e[:] = 0.0
    ep = ivar[K.I_EPISODE]
    ivar[K.I_SHAPING] = 1 if ep >= par[K.P_WARMUP] else 0
    ivar[K.I_TRAIN_V] = 1 if ep < par[K.P_FREEZE] else 0
    fvar[K.F_PHI] = value(feat, s0, w)
