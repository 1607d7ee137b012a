"""RNH-QL+ (``rnh-ql+``, :class:`learning.methods.RNHQLPlus`): rules and agent events.

Features (lattice, sparse Gaussians, leak-free supports) are in
:mod:`learning.plus_features`; the optimistic model in :mod:`learning.plus_optimism`.

The architecture is RNH-QL's: a Q-table below, a potential above that shapes
the Q update with F = gamma * Phi(s') - Phi(s), Phi(goal) = 0. What changes
(each a config field, see the class docs):

* the potential (``v_target``): 0 the paper's V_NN by TD(lambda) on rewards;
  1 V_NN toward the table's own max_a Q(s, .) + Phi(s); 2 its log; 3 V_NN
  toward the log of the optimistic model's value y(s); **4 (the default)
  Phi = y(s) itself, no network**; 5 Phi = y(s) * exp(V_NN(s)), V_NN learning
  the log of the table's value over y (a residual, at most 0);
* ``lookahead``: an untried action is valued by one step of look-ahead on Phi
  in the optimistic model (Wiewiora's look-ahead advice), so the agent heads
  for G along the route it believes free instead of trying actions in index
  order;
* the lattice is tied to the map (a centre every ``spacing`` cells) and the
  features are **sparse**: each state lists its M nearest centres within
  ``cutoff`` widths, so a step costs O(M), not O(K), on any map size;
* ``leak_free``: a centre's feature is switched on at a cell only once the
  cell is connected to the centre's anchor by moves the agent has seen
  succeed, inside the centre's support window; supports only grow, by a flood
  fill each time a new move is seen, so each (cell, centre) pair is added once;
* ``rebase``: when Phi(s) changes, row s's tried actions are shifted so Q + Phi
  is unchanged (off by default: when the optimistic model learns of a wall,
  Phi falls and so should the values learned through it);
* a learned model (:mod:`learning.move_model`: a move's successor and how often
  it failed) drives ``n_planning`` shaped Q updates per step (Dyna), and
  ``lam_q`` adds Watkins Q(lambda) traces to the real step.

State layout (:class:`learning.state.AgentState` slots), nS states, nA actions,
K centres, M feature slots per state:

==========  ==================================================================
q           Q-table [nS, nA]
w           V_NN weights [K]
e           [K + 2nS + 2]: V_NN traces [:K] (v_target = 0), Phi each row is based on
            [K:K+nS], the optimistic model's y [K+nS:K+2nS] and the two rewards it was
            computed with (learning.plus_optimism)
feat        [nS, 2M]: effective feature values [:, :M], Gaussian values [:, M:]
imap        [nS, 3nA + M]: model s' [:, :nA] (-1 unseen), terminated [:, nA:2nA],
            feature centre ids [:, 2nA:2nA+M], seen predecessors [:, 2nA+M:] (-1)
fmap        [2nS + 1, nA]: model reward [:nS], Q(lambda) traces [nS:2nS], scratch row
ilist       [2nS*nA + K + 3nS*nA + 3nS]: seen pairs, Q-trace list, centre anchors (-1 none),
            arena neighbours, BFS distances, BFS queue (learning.plus_optimism), the
            move model's outcome counts (learning.move_model), flood-fill stack
==========  ==================================================================
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from learning import kinds as K
from learning.move_model import observe_outcome, replay_fails
from learning.plus_features import leak_free_edge, leak_free_enter
from learning.plus_optimism import (
    counts_base,
    distances_change,
    ensure_values,
    goal_reward,
    known_to_fail,
    mark_stale,
    neighbour_base,
    observe_rewards,
    optimistic_bfs,
    optimistic_value,
)
from learning.rules import (
    argmax_drawn,
    argmax_first,
    clear_traces,
    draw_below,
    eps_greedy,
    is_greedy,
    q_lambda,
    q_learning,
    record_shaping,
    row_max,
)

INLINE = dict(cache=True, inline="always")
# Paths the default configuration never takes on a step (V_NN fits, TD(lambda), the
# potential as a function, re-basing) stay real calls: inlined at each of their ~15 call
# sites they made the rnh-ql+ kernel take minutes to compile.
COLD = dict(cache=True)
LOG_FLOOR = 1e-3  # v_target = 2: values below this [reward units] are learned as this
OPT_FLOOR = 1e-12  # v_target = 3: optimistic values below this are learned as this


@njit(**INLINE)
def v_of(w, feat, imap, s):
    """V_NN(s) = sum_m feat[s, m] * w[id[s, m]] over the effective features."""
    m_n = feat.shape[1] // 2
    off = imap.shape[1] - m_n - (imap.shape[1] - m_n) // 3
    v = 0.0
    for m in range(m_n):
        v += feat[s, m] * w[imap[s, off + m]]
    return v


@njit(**COLD)
def v_regress(w, feat, imap, s, target, step):
    """Normalised LMS: w += step * (target - V(s)) * phi(s)."""
    m_n = feat.shape[1] // 2
    off = imap.shape[1] - m_n - (imap.shape[1] - m_n) // 3
    c = step * (target - v_of(w, feat, imap, s))
    for m in range(m_n):
        w[imap[s, off + m]] += c * feat[s, m]


@njit(**COLD)
def v_td_lambda(w, e, feat, imap, s, r, v_s2, greedy, gamma, lam, step):
    """TD(lambda) on env rewards with Watkins cutting (learning.rbf.td_lambda, sparse phi)."""
    if not greedy:
        e[:] = 0.0
        return
    m_n = feat.shape[1] // 2
    off = imap.shape[1] - m_n - (imap.shape[1] - m_n) // 3
    delta = r + gamma * v_s2 - v_of(w, feat, imap, s)
    gl = gamma * lam
    for i in range(w.shape[0]):  # e's tail caches potentials, not traces
        e[i] *= gl
    for m in range(m_n):
        e[imap[s, off + m]] += feat[s, m]
    c = step * delta
    for i in range(w.shape[0]):
        w[i] += c * e[i]


# ---------------------------------------------------------------- leak-free supports


@njit(**COLD)
def potential(fvar, par, w, e, feat, imap, ilist, s):
    """Phi(s) = scale * V_NN(s); scale * exp(V_NN(s)) when V_NN learns log values
    (v_target 2, 3); scale * y(s), the optimistic model's value itself, with no network
    (v_target 4, the reference row of the ablation)."""
    vt = par[K.PP_VTARGET]
    if vt == 4.0:
        return par[K.PP_SCALE] * optimistic_value(e, w.shape[0], imap.shape[0], s)
    v = v_of(w, feat, imap, s)
    if vt == 5.0:  # V_NN learns log(V / y), at most 0: Phi never above the optimistic value
        y = optimistic_value(e, w.shape[0], imap.shape[0], s)
        return par[K.PP_SCALE] * y * math.exp(min(v, 0.0))
    if vt == 2.0 or vt == 3.0:
        v = math.exp(min(v, 50.0))
    return par[K.PP_SCALE] * v


@njit(**INLINE)
def model_phi(par):
    """True when Phi is the optimistic model's value itself (v_target 4, no re-basing): hot
    loops then read scale * y from its cache in ``e`` (from nK + nS on) instead of calling
    :func:`potential`, whose eight array arguments numba reference-counts on every call
    it cannot prune (measured: 37 ns a call against 4 ns for the load)."""
    return par[K.PP_VTARGET] == 4.0 and par[K.PP_REBASE] == 0.0


# ---------------------------------------------------------------- re-based rows


@njit(**COLD)
def rebase(fvar, par, q, w, e, feat, imap, ilist, s):
    """Phi(s) now; row s's tried actions re-based onto it (Q + Phi unchanged), untried ones
    left at 0, i.e. valued at Phi(s). Returns Phi(s)."""
    n_c = w.shape[0]
    phi = potential(fvar, par, w, e, feat, imap, ilist, s)
    d = e[n_c + s] - phi
    if d != 0.0:
        for a in range(q.shape[1]):
            if imap[s, a] >= 0:
                q[s, a] += d
        e[n_c + s] = phi
    return phi


@njit(**INLINE)
def tried_max(q, imap, s):
    """max over the tried actions of Q(s, .) (-inf if none)."""
    m = -np.inf
    for a in range(q.shape[1]):
        if imap[s, a] >= 0 and q[s, a] > m:
            m = q[s, a]
    return m


@njit(**INLINE)
def action_values(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s):
    """Row s's action values (in re-based units, Q + Phi - Phi(s)) into the scratch row
    fmap[2 nS]: a tried action its Q; an untried one one step of look-ahead in the
    optimistic model, r_free + gamma * Phi(neighbour) - Phi(s) (r_goal - Phi(s) into G,
    -inf off the arena). Returns the scratch row's index."""
    n_s, n_a = q.shape[0], q.shape[1]
    n_c = w.shape[0]
    row = 2 * n_s
    direct = model_phi(par)
    scale = par[K.PP_SCALE]
    y0 = n_c + n_s
    if direct:
        phi_s = scale * e[y0 + s]
    elif par[K.PP_REBASE] != 0.0:
        phi_s = e[n_c + s]
    else:
        phi_s = potential(fvar, par, w, e, feat, imap, ilist, s)
    nb0 = neighbour_base(n_s, n_a, n_c)
    for a in range(n_a):
        if imap[s, a] >= 0:
            fmap[row, a] = q[s, a]
            continue
        u = ilist[nb0 + s * n_a + a]
        if u < 0:
            fmap[row, a] = -np.inf
        elif u == ivar[K.I_GOAL]:
            fmap[row, a] = goal_reward(fvar, par) - phi_s
        else:
            phi_u = scale * e[y0 + u] if direct else potential(fvar, par, w, e, feat, imap,
                                                                  ilist, u)
            fmap[row, a] = fvar[K.F_RFREE] + par[K.P_GAMMA] * phi_u - phi_s
    return row


@njit(**INLINE)
def lookahead_on(ivar, par):
    return par[K.PP_LOOKAHEAD] != 0.0 and ivar[K.I_SHAPING] != 0


@njit(**INLINE)
def act_plus(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng):
    """Epsilon-greedy; with look-ahead, greedy over :func:`action_values` (ties drawn)."""
    if not lookahead_on(ivar, par):
        return eps_greedy(q, s, par[K.P_EPS], rng)
    if rng.random() < par[K.P_EPS]:
        return draw_below(rng, q.shape[1])
    row = action_values(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s)
    return argmax_drawn(fmap, row, rng)


@njit(**INLINE)
def exploit_plus(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s):
    """Greedy test policy, ties to the lowest index: with look-ahead over
    :func:`action_values`; else over tried actions (re-based rows), or over Q."""
    if lookahead_on(ivar, par):
        if par[K.PP_REBASE] != 0.0:
            rebase(fvar, par, q, w, e, feat, imap, ilist, s)
        return argmax_first(fmap, action_values(ivar, fvar, par, q, w, e, feat, imap, fmap,
                                                ilist, s))
    a = 0
    if par[K.PP_REBASE] != 0.0:
        m = -np.inf
        for b in range(q.shape[1]):
            if imap[s, b] >= 0 and q[s, b] > m:
                m = q[s, b]
                a = b
        if m > -np.inf:
            return a
    for b in range(1, q.shape[1]):
        if q[s, b] > q[s, a]:
            a = b
    return a


# ---------------------------------------------------------------- agent events


@njit(**INLINE)
def update_plus(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                rng):
    """Real step: F from the cached Phi(s) and Phi(s') = scale * V_NN(s'); Q(-lambda) update;
    V_NN update; model (and leak-free supports) update; ``n_planning`` shaped model updates."""
    n_s, n_a = q.shape[0], q.shape[1]
    gamma = par[K.P_GAMMA]
    alpha = par[K.P_ALPHA]
    shaping = ivar[K.I_SHAPING] != 0
    leak_free = par[K.PP_LEAKFREE] != 0.0
    normalise = par[K.PP_NORMALISE] != 0.0
    based = shaping and par[K.PP_REBASE] != 0.0
    n_c = w.shape[0]
    direct = model_phi(par)  # Phi read as scale * y from e[y0 + s]
    scale = par[K.PP_SCALE]
    y0 = n_c + n_s
    if based:
        rebase(fvar, par, q, w, e, feat, imap, ilist, s)
    vt = par[K.PP_VTARGET]
    stale = observe_rewards(fvar, s, r, s2, terminated)
    # model first: a new move may join s' to supports before Phi(s') is read
    c0 = counts_base(n_s, n_a, n_c)
    was_fail = known_to_fail(imap, ilist, n_s, n_a, n_c, s, a)
    if imap[s, a] < 0:
        ilist[ivar[K.I_NSEEN]] = s * n_a + a
        ivar[K.I_NSEEN] += 1
        if leak_free and s2 != s:
            leak_free_edge(feat, imap, ilist, n_s, n_a, s, s2, normalise)
    worked = s2 == ilist[neighbour_base(n_s, n_a, n_c) + s * n_a + a]
    observe_outcome(imap, fmap, ilist, c0, fvar, n_a, s, a, r, s2, terminated, worked)
    now_fail = known_to_fail(imap, ilist, n_s, n_a, n_c, s, a)
    # the optimistic model changed: a move now known to fail (BFS only if a distance
    # changes), or one known to fail that moved after all (noisy physics worlds; on the
    # grid and at the exact fidelity a move's outcome never changes)
    if vt >= 3.0 and now_fail != was_fail and (was_fail or distances_change(
            imap, ilist, n_s, n_a, n_c, s, a)):
        optimistic_bfs(imap, ilist, n_s, n_a, n_c, ivar[K.I_GOAL])
        mark_stale(e, n_s, n_c)
        stale = True
    if stale and vt >= 3.0:
        ensure_values(fvar, par, ilist, e, feat, imap, n_c)
    if leak_free and not terminated:
        leak_free_enter(feat, imap, ilist, n_s, n_a, s2, normalise)
    if terminated:
        phi_s2 = 0.0
    elif direct:
        phi_s2 = scale * e[y0 + s2]
    else:
        phi_s2 = potential(fvar, par, w, e, feat, imap, ilist, s2)
    if based and not terminated:
        phi_s2 = rebase(fvar, par, q, w, e, feat, imap, ilist, s2)
    train_v = ivar[K.I_TRAIN_V] != 0
    td = vt == 0.0
    if train_v and td:  # V_NN(s') only where TD(lambda) needs it
        v2 = 0.0 if terminated else v_of(w, feat, imap, s2)
        v_td_lambda(w, e, feat, imap, s, r, v2, is_greedy(q, s, a), gamma, par[K.P_LAMBDA],
                    fvar[K.F_STEP_V])
    f = 0.0
    if shaping:
        phi_s = e[n_c + s] if based else fvar[K.F_PHI]
        f = gamma * phi_s2 - phi_s
        record_shaping(ivar, fvar, f)
    if par[K.PP_LAMQ] > 0.0:
        q_lambda(q, fmap[n_s:], ilist[n_s * n_a:], ivar, s, a, r, s2, terminated, alpha, gamma,
                 par[K.PP_LAMQ], par[K.PP_TRACE_MIN], f)
    else:
        q_learning(q, s, a, r, s2, terminated, alpha, gamma, f)
    if train_v and vt == 3.0:  # V_NN learns log y: at s and at n_fit random states
        y = optimistic_value(e, n_c, n_s, s)
        v_regress(w, feat, imap, s, math.log(max(y, OPT_FLOOR)), fvar[K.F_STEP_V])
        for _ in range(int(par[K.PP_NFIT])):
            j = draw_below(rng, n_s)
            y = optimistic_value(e, n_c, n_s, j)
            v_regress(w, feat, imap, j, math.log(max(y, OPT_FLOOR)), fvar[K.F_STEP_V])
    elif train_v and not td and vt != 4.0:
        if based:
            target = tried_max(q, imap, s) + e[n_c + s]
        else:
            target = row_max(q, s)
            if shaping:
                target += fvar[K.F_PHI]
        fit = True
        if vt == 2.0:  # V_NN learns log values: Phi = scale * exp(V_NN)
            target = math.log(max(target, LOG_FLOOR))
        elif vt == 5.0:  # V_NN learns the log of the table's value over the optimistic one
            y = optimistic_value(e, n_c, n_s, s) * par[K.PP_SCALE]
            fit = y > 0.0
            if fit:
                target = math.log(max(target, OPT_FLOOR) / y)
        if fit:
            v_regress(w, feat, imap, s, target, fvar[K.F_STEP_V])
    n_seen = ivar[K.I_NSEEN]
    for _ in range(int(par[K.PP_NPLAN])):
        j = ilist[draw_below(rng, n_seen)]
        if n_a == 4:  # the grid's four moves: shifts, not two integer divisions
            ps = j >> 2
            pa = j & 3
        else:
            ps = j // n_a
            pa = j % n_a
        ps2 = imap[ps, pa]
        pterm = imap[ps, n_a + pa] != 0
        pr = fmap[ps, pa]
        if replay_fails(ilist, c0, n_a, ps, pa, rng):
            ps2, pterm, pr = ps, False, fvar[K.F_RFAIL]
        pf = 0.0
        if based:
            p1 = rebase(fvar, par, q, w, e, feat, imap, ilist, ps)
            p2 = 0.0 if pterm else rebase(fvar, par, q, w, e, feat, imap, ilist, ps2)
            pf = gamma * p2 - p1
        elif shaping and direct:
            p2 = 0.0 if pterm else scale * e[y0 + ps2]
            pf = gamma * p2 - scale * e[y0 + ps]
        elif shaping:
            p2 = 0.0 if pterm else potential(fvar, par, w, e, feat, imap, ilist, ps2)
            pf = gamma * p2 - potential(fvar, par, w, e, feat, imap, ilist, ps)
        q_learning(q, ps, pa, pr, ps2, pterm, alpha, gamma, pf)
    fvar[K.F_PHI] = phi_s2


@njit(**INLINE)
def begin_plus(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0):
    """Reset traces and per-episode sums; shaping on from ``warmup``; V_NN frozen from
    ``freeze``; anchor s0's centre (leak-free); cache Phi(s0)."""
    ivar[K.I_PENDING] = -1
    ivar[K.I_NF] = 0
    if par[K.PP_VTARGET] >= 3.0:  # the first episode, or a state changed from outside
        ensure_values(fvar, par, ilist, e, feat, imap, w.shape[0])
    fvar[K.F_FSUM] = 0.0
    fvar[K.F_FSQ] = 0.0
    n_s, n_a = q.shape[0], q.shape[1]
    if par[K.PP_VTARGET] == 0.0:
        e[:w.shape[0]] = 0.0
    if par[K.PP_LAMQ] > 0.0:
        clear_traces(fmap[n_s:], ilist[n_s * n_a:], ivar)
    ep = ivar[K.I_EPISODE]
    ivar[K.I_SHAPING] = 1 if ep >= par[K.PP_WARMUP] else 0
    ivar[K.I_TRAIN_V] = 1 if ep < par[K.PP_FREEZE] else 0
    if par[K.PP_LEAKFREE] != 0.0:
        leak_free_enter(feat, imap, ilist, n_s, n_a, s0, par[K.PP_NORMALISE] != 0.0)
    if ivar[K.I_SHAPING] != 0 and par[K.PP_REBASE] != 0.0:
        fvar[K.F_PHI] = rebase(fvar, par, q, w, e, feat, imap, ilist, s0)
    else:
        fvar[K.F_PHI] = potential(fvar, par, w, e, feat, imap, ilist, s0)


@njit(cache=True)
def potential_table(fvar, par, w, e, feat, imap, ilist, out):
    """out[s] = Phi(s) for every state (the recorder's potential panel)."""
    if par[K.PP_VTARGET] >= 3.0:
        ensure_values(fvar, par, ilist, e, feat, imap, w.shape[0])
    for s in range(out.shape[0]):
        out[s] = potential(fvar, par, w, e, feat, imap, ilist, s)
