"""The RNH-QL+ ablation's upper layer: V_NN over sparse features, the potentials of
:class:`~learning.methods.rnh_ql_plus_ablation.config.Potential`, re-based rows and the
network fits.

Each takes arrays, not the state (see :mod:`learning.methods.rnh_ql_plus.rules`). Paths the
ablation's steps do not all take (V_NN fits, TD(lambda), the potential as a function,
re-basing) stay real calls: inlined at each of their ~15 call sites they made the kernel
take minutes to compile.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from learning.methods.rnh_ql_plus_ablation.config import Potential
from learning.parts.tabular import draw_below, row_max

HOOK = dict(cache=True, inline="always")
COLD = dict(cache=True)
LOG_FLOOR = 1e-3  # LOG_TABLE: values below this [reward units] are learned as this
OPT_FLOOR = 1e-12  # LOG_OPTIMISTIC: optimistic values below this are learned as this
# the potentials as plain ints for compiled comparisons
TD_REWARDS, LOG_TABLE = int(Potential.TD_REWARDS), int(Potential.LOG_TABLE)
LOG_OPTIMISTIC, OPTIMISTIC = int(Potential.LOG_OPTIMISTIC), int(Potential.OPTIMISTIC)
RESIDUAL = int(Potential.RESIDUAL)


# ---------------------------------------------------------------- V_NN over sparse features


@njit(**HOOK)
def v_of(w, on, centre, s):
    """V_NN(s) = sum_m on[s, m] * w[centre[s, m]] over the effective features."""
    v = 0.0
    for m in range(on.shape[1]):
        v += on[s, m] * w[centre[s, m]]
    return v


@njit(**COLD)
def v_regress(w, on, centre, s, target, step):
    """Normalised LMS: w += step * (target - V(s)) * phi(s)."""
    c = step * (target - v_of(w, on, centre, s))
    for m in range(on.shape[1]):
        w[centre[s, m]] += c * on[s, m]


@njit(**COLD)
def v_td_lambda(w, e, on, centre, s, r, v_s2, greedy, gamma, lam, step):
    """TD(lambda) on env rewards with Watkins cutting (learning.parts.rbf.td_lambda, sparse phi)."""
    if not greedy:
        e[:] = 0.0
        return
    delta = r + gamma * v_s2 - v_of(w, on, centre, s)
    gl = gamma * lam
    for i in range(w.shape[0]):
        e[i] *= gl
    for m in range(on.shape[1]):
        e[centre[s, m]] += on[s, m]
    c = step * delta
    for i in range(w.shape[0]):
        w[i] += c * e[i]


@njit(**COLD)
def potential(par, w, on, centre, y, s):
    """Phi(s) = scale * V_NN(s); scale * exp(V_NN(s)) when V_NN learns log values
    (LOG_TABLE, LOG_OPTIMISTIC); scale * y(s), the optimistic model's value itself, with
    no network (OPTIMISTIC, the reference row of the ablation)."""
    vt = par.v_target
    if vt == OPTIMISTIC:
        return par.scale * y[s]
    v = v_of(w, on, centre, s)
    if vt == RESIDUAL:  # V_NN learns log(V / y), at most 0: Phi never above the optimistic value
        return par.scale * y[s] * math.exp(min(v, 0.0))
    if vt == LOG_TABLE or vt == LOG_OPTIMISTIC:
        v = math.exp(min(v, 50.0))
    return par.scale * v


@njit(**HOOK)
def model_phi(par):
    """True when Phi is the optimistic model's value itself (no re-basing): hot loops then
    read scale * y from its cache instead of calling :func:`potential`."""
    return par.v_target == OPTIMISTIC and not par.rebase


# ---------------------------------------------------------------- re-based rows


@njit(**COLD)
def rebase(par, q, w, on, centre, y, phi_row, successor, s):
    """Phi(s) now; row s's tried actions re-based onto it (Q + Phi unchanged), untried ones
    left at 0, i.e. valued at Phi(s). Returns Phi(s)."""
    phi = potential(par, w, on, centre, y, s)
    d = phi_row[s] - phi
    if d != 0.0:
        for a in range(q.shape[1]):
            if successor[s, a] >= 0:
                q[s, a] += d
        phi_row[s] = phi
    return phi


@njit(**HOOK)
def tried_argmax(q, successor, s):
    """argmax over the tried actions of Q(s, .), ties to the lowest index (0 if none)."""
    m = -np.inf
    best = 0
    for a in range(q.shape[1]):
        if successor[s, a] >= 0 and q[s, a] > m:
            m = q[s, a]
            best = a
    return best


@njit(**HOOK)
def tried_max(q, successor, s):
    """max over the tried actions of Q(s, .) (-inf if none)."""
    m = -np.inf
    for a in range(q.shape[1]):
        if successor[s, a] >= 0 and q[s, a] > m:
            m = q[s, a]
    return m


# ---------------------------------------------------------------- V_NN fits


@njit(**COLD)
def fit_v(par, q, w, on, centre, y, succ, phi_row, phi_here, step_v, s, shaping, based, rng):
    """The network variants' V_NN fit at s (and LOG_OPTIMISTIC's ``n_fit`` random states)."""
    vt = par.v_target
    step = step_v[0]
    if vt == LOG_OPTIMISTIC:  # V_NN learns log y: at s and at n_fit random states
        v_regress(w, on, centre, s, math.log(max(y[s], OPT_FLOOR)), step)
        for _ in range(par.n_fit):
            j = draw_below(rng, q.shape[0])
            v_regress(w, on, centre, j, math.log(max(y[j], OPT_FLOOR)), step)
        return
    if based:
        target = tried_max(q, succ, s) + phi_row[s]
    else:
        target = row_max(q, s)
        if shaping:
            target += phi_here[0]
    if vt == LOG_TABLE:  # V_NN learns log values: Phi = scale * exp(V_NN)
        target = math.log(max(target, LOG_FLOOR))
    elif vt == RESIDUAL:  # V_NN learns the log of the table's value over the optimistic one
        yy = y[s] * par.scale
        if not yy > 0.0:
            return
        target = math.log(max(target, OPT_FLOOR) / yy)
    v_regress(w, on, centre, s, target, step)
