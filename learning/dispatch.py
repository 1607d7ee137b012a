"""One entry point per agent event, switching on the rule family: the code both drivers run.

The fused kernels (:mod:`learning.kernels`) call these inside their loops; the
step-by-step agent (:mod:`learning.agent`) calls the very same compiled
functions from Python, one event at a time. Every random number either driver
uses is drawn inside these functions (or :func:`draw_start`) from the one
injected generator, so equal seeds give equal runs.

Draw order per step: ``act`` (one ``random()``, then ``integers(0, nA)`` when
exploring or ``integers(0, n_ties)`` on a greedy tie; SARSA-RS draws nothing
when it replays the action chosen at the previous update), then ``update``
(SARSA-RS: the next action's draws unless terminated; Dyna-Q: ``n_planning``
``integers(0, n_seen)``). Per episode: ``draw_start`` first (one ``integers``).

Calling convention, for speed (measured on paper-50, st-ql): the agent state
is passed as its ten arrays (``*state``), not as the tuple (numba passes a
tuple field by field to a non-inlined callee: 4x slower), and ``kind`` is an
argument: the kernels pass it as a constant into these ``inline="always"``
functions, so LLVM folds the switch away (2.5x faster than reading it from
``ivar``). Called from Python, they compile once with ``kind`` a runtime int.
"""

from __future__ import annotations

import math

from numba import njit

from learning import kinds as K
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


@njit(cache=True, inline="always")
def draw_start(rng, start_states):
    """The episode's start state: ``start_states[rng.integers(0, len)]``."""
    return start_states[rng.integers(0, start_states.shape[0])]


@njit(cache=True, inline="always")
def act(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng):
    """The behaviour policy's action at s (epsilon-greedy around the method's greedy choice)."""
    eps = par[K.P_EPS]
    if kind == K.SARSARS:
        a = ivar[K.I_PENDING]
        if a >= 0:
            ivar[K.I_PENDING] = -1
            return a
    elif kind == K.HAQL:
        if rng.random() < eps:
            return rng.integers(0, q.shape[1])
        return haql_greedy(q, s, imap[s, 0], par[K.P_XI], par[K.P_BETA_H], par[K.P_ETA], rng)
    elif kind == K.RNQL:
        net_row(w, feat, s, fmap)
        return eps_greedy(fmap, 0, eps, rng)
    return eps_greedy(q, s, eps, rng)


@njit(cache=True, inline="always")
def exploit_action(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s):
    """The method's own exploitation policy, no exploration, ties to the lowest index."""
    if kind == K.HAQL:
        return haql_first(q, s, imap[s, 0], par[K.P_XI], par[K.P_BETA_H], par[K.P_ETA])
    if kind == K.RNQL:
        net_row(w, feat, s, fmap)
        return argmax_first(fmap, 0)
    return argmax_first(q, s)


@njit(cache=True, inline="always")
def _rnhql_update(ivar, fvar, par, q, w, e, feat, fmap, ilist, s, a, r, s2, terminated):
    """RNH-QL: TD(lambda) on V_NN, then Q-learning + F = gamma*Phi(s') - Phi(s).

    Phi(s') is V_NN(s') evaluated as s' is entered, with the weights before this
    step's V_NN update, and cached (fvar[F_PHI]) until s' is left; Phi(goal) = 0.
    """
    gamma = par[K.P_GAMMA]
    greedy = is_greedy(q, s, a)
    phi_s2 = 0.0 if terminated else value(feat, s2, w)
    if ivar[K.I_TRAIN_V] != 0:
        td_lambda(w, e, feat, s, r, phi_s2, greedy, gamma, par[K.P_LAMBDA],
                  fvar[K.F_STEP_V])
    f = 0.0
    if ivar[K.I_SHAPING] != 0:
        f = gamma * phi_s2 - fvar[K.F_PHI]
        record_shaping(ivar, fvar, f)
    if par[K.P_QMODE] == K.QMODE_LAMBDA:
        q_lambda(q, fmap, ilist, ivar, s, a, r, s2, terminated, par[K.P_ALPHA], gamma,
                 par[K.P_LAMBDA], 1e-8, f)
    else:
        q_learning(q, s, a, r, s2, terminated, par[K.P_ALPHA], gamma, f)
    fvar[K.F_PHI] = phi_s2


@njit(cache=True, inline="always")
def update(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
           truncated, rng):
    """Learn from (s, a, r, s'). ``truncated`` steps bootstrap like any non-terminal step."""
    alpha, gamma = par[K.P_ALPHA], par[K.P_GAMMA]
    if kind == K.QL or kind == K.HAQL:
        q_learning(q, s, a, r, s2, terminated, alpha, gamma, 0.0)
    elif kind == K.RNHQL:
        _rnhql_update(ivar, fvar, par, q, w, e, feat, fmap, ilist, s, a, r, s2, terminated)
    elif kind == K.PFH:
        f = static_shaping(feat, s, s2, terminated, gamma)
        record_shaping(ivar, fvar, f)
        q_learning(q, s, a, r, s2, terminated, alpha, gamma, f)
    elif kind == K.SARSARS:
        a2 = -1
        if not terminated:
            a2 = eps_greedy(q, s2, par[K.P_EPS], rng)
        sarsa_rs(q, w, imap, ivar, fvar, s, a, r, s2, a2, terminated, alpha,
                 gamma, par[K.P_OMEGA], par[K.P_ALPHA_V])
        ivar[K.I_PENDING] = a2
    elif kind == K.QLAMBDA:
        q_lambda(q, fmap, ilist, ivar, s, a, r, s2, terminated, alpha, gamma,
                 par[K.P_LAMBDA], par[K.P_TRACE_MIN], 0.0)
    elif kind == K.DYNA:
        dyna_q(q, imap, fmap, ilist, ivar, s, a, r, s2, terminated, alpha, gamma,
               int(par[K.P_NPLAN]), rng)
    elif kind == K.RNQL:
        q_lambda_net(w, e, feat, s, a, r, s2, terminated, alpha, gamma, par[K.P_LAMBDA],
                     par[K.P_QSCALE], fmap)


@njit(cache=True, inline="always")
def begin_episode(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0):
    """Reset per-episode state: traces, pending action, SMDP sums, shaping flags, Phi(s0)."""
    ivar[K.I_PENDING] = -1
    ivar[K.I_NF] = 0
    fvar[K.F_FSUM] = 0.0
    fvar[K.F_FSQ] = 0.0
    fvar[K.F_R] = 0.0
    fvar[K.F_GK] = 1.0
    if kind == K.QLAMBDA or (kind == K.RNHQL and par[K.P_QMODE] == K.QMODE_LAMBDA):
        clear_traces(fmap, ilist, ivar)
    elif kind == K.RNQL or kind == K.RNHQL:
        e[:] = 0.0
    if kind == K.RNHQL:
        ep = ivar[K.I_EPISODE]
        ivar[K.I_SHAPING] = 1 if ep >= par[K.P_WARMUP] else 0
        ivar[K.I_TRAIN_V] = 1 if ep < par[K.P_FREEZE] else 0
        fvar[K.F_PHI] = value(feat, s0, w)


@njit(cache=True, inline="always")
def end_episode(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist):
    """Close the episode: shaping mean/std into fvar[F_FMEAN/F_FSTD], count it."""
    n = ivar[K.I_NF]
    if n > 0:
        mean = fvar[K.F_FSUM] / n
        fvar[K.F_FMEAN] = mean
        fvar[K.F_FSTD] = math.sqrt(max(fvar[K.F_FSQ] / n - mean * mean, 0.0))
    else:
        fvar[K.F_FMEAN] = 0.0
        fvar[K.F_FSTD] = 0.0
    ivar[K.I_EPISODE] += 1
