"""RNH-QL+'s rules and agent events.

The architecture is RNH-QL's: a Q-table below, a potential above that shapes
the Q update with F = gamma * Phi(s') - Phi(s), Phi(goal) = 0. What changes
(each a config field, see :class:`learning.rnh_ql_plus.config.RNHQLPlus`):

* the potential (``v_target``, a :class:`~learning.rnh_ql_plus.config.Potential`):
  the paper's V_NN by TD(lambda) on rewards; V_NN toward the table's own value or
  its log; V_NN toward the log of the optimistic model's value y(s); **Phi = y(s)
  itself, no network (the default)**; or y(s) * exp(V_NN(s)), V_NN learning a
  residual of at most 0;
* ``lookahead``: an untried action is valued by one step of look-ahead on Phi
  in the optimistic model (Wiewiora's look-ahead advice), so the agent heads
  for G along the route it believes free instead of trying actions in index
  order;
* the lattice is tied to the map (a centre every ``spacing`` cells) and the
  features are **sparse** (:mod:`learning.rnh_ql_plus.features`): a step costs
  O(M), not O(K), on any map size; ``leak_free`` supports grow by flood fill
  along moves seen to succeed;
* ``rebase``: when Phi(s) changes, row s's tried actions are shifted so Q + Phi
  is unchanged (off by default: when the optimistic model learns of a wall,
  Phi falls and so should the values learned through it);
* a learned model (:mod:`learning.move_model`: a move's successor and how often
  it failed) drives ``n_planning`` shaped Q updates per step (Dyna), and
  ``lam_q`` adds Watkins Q(lambda) traces to the real step.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from learning.free_space import back_move, bfs_distances, distances_change, repair_distances
from learning.known_routes import known_distances, known_move
from learning.move_model import (
    never_worked,
    note_pair,
    observe_outcome,
    pair_of,
    replay_draws_failure,
)
from learning.priority_queue import pop, push
from learning.rnh_ql_plus.config import Potential
from learning.rnh_ql_plus.features import leak_free_edge, leak_free_enter
from learning.rnh_ql_plus.optimism import (
    ensure_values,
    goal_reward,
    mark_stale,
    observe_rewards,
    revalue,
)
from learning.tabular import (
    argmax_drawn,
    argmax_first,
    draw_below,
    eps_greedy,
    is_greedy,
    q_learning,
    row_max,
)
from learning.tally import begin_tally, record_shaping
from learning.traces import clear_traces, q_lambda

HOOK = dict(cache=True, inline="always")
# Paths the default configuration never takes on a step (V_NN fits, TD(lambda), the
# potential as a function, re-basing) stay real calls: inlined at each of their ~15 call
# sites they made the rnh-ql+ kernel take minutes to compile.
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
    """TD(lambda) on env rewards with Watkins cutting (learning.rbf.td_lambda, sparse phi)."""
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


# GENERAL is a compile-time constant of each hook: True here; False in the lean copies of
# the hooks (:func:`lean_hooks`) that a state holding LeanParams compiles. numba removes a
# branch on a constant before it counts references, with the array reads only that branch
# needed; a branch that never runs but is not removed costs its arrays' reference counts
# on every step (measured: ~5 ns per array, ~140 ns a step for the ablation's switches).
GENERAL = True


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


@njit(**HOOK)
def action_values(par, q, out, y, phi_row, w, on, centre, succ, nb, goal, r_free, r_goal,
                  direct, based, s):
    """Row s's action values (in re-based units, Q + Phi - Phi(s)) into the scratch row
    ``out[0]``: a tried action its Q; an untried one one step of look-ahead in the
    optimistic model, r_free + gamma * Phi(neighbour) - Phi(s) (r_goal - Phi(s) into G,
    -inf off the arena). ``direct``: Phi is scale * y (:func:`model_phi`); ``based``: rows
    are re-based."""
    based = based if GENERAL else False
    direct = direct if GENERAL else True
    scale = par.scale
    if direct:
        phi_s = scale * y[s]
    elif based:
        phi_s = phi_row[s]
    else:
        phi_s = potential(par, w, on, centre, y, s)
    for a in range(q.shape[1]):
        if succ[s, a] >= 0:
            out[0, a] = q[s, a]
            continue
        u = nb[s, a]
        if u < 0:
            out[0, a] = -np.inf
        elif u == goal:
            out[0, a] = r_goal - phi_s
        else:
            phi_u = scale * y[u] if direct else potential(par, w, on, centre, y, u)
            out[0, a] = r_free + par.gamma * phi_u - phi_s


# Every hook below first reads each array it or its callees use into a local, one field per
# statement, before any branch or loop; callees inside branches get arrays, never the state.
# numba reference-counts each read of a named tuple's field, and prunes the count only
# where the read is on every path through the hook: a read inside a branch costs two atomic
# operations per call even when the branch never runs (measured: the rnh-ql+ kernel at 0.7M
# env steps/s with reads in branches, 5M+ with them hoisted). Nested tuples (``st.model``,
# ``st.free``) are read through once, at the top, for the same reason.


@njit(**HOOK)
def act(st, s, rng):
    """Epsilon-greedy; with look-ahead, greedy over :func:`action_values` (ties drawn)."""
    par = st.par
    q = st.q
    values = st.values
    shaping = st.shaping
    y = st.opt.y
    r_goal_seen = st.opt.r_goal
    r_free_seen = st.opt.r_free
    phi_row = st.phi_row
    w = st.w
    on = st.feat.on
    centre = st.feat.centre
    succ = st.model.successor
    nb = st.free.neighbour
    goal = st.free.goal[0]
    direct = model_phi(par) if GENERAL else True
    based = par.rebase if GENERAL else False
    if not (par.lookahead and shaping[0]):
        a = eps_greedy(q, s, par.eps, rng)
    elif rng.random() < par.eps:
        a = draw_below(rng, q.shape[1])
    else:
        action_values(par, q, values, y, phi_row, w, on, centre, succ, nb, goal,
                      r_free_seen[0], goal_reward(r_goal_seen, r_free_seen, par.gamma),
                      direct, based, s)
        a = argmax_drawn(values, 0, rng)
    return a


@njit(**HOOK)
def exploit(st, s):
    """Greedy test policy, ties to the lowest index: with ``known_route``, the first move of
    a shortest route over moves seen to work, where s has one; else with look-ahead over
    :func:`action_values`; else over tried actions (re-based rows), or over Q."""
    par = st.par
    q = st.q
    values = st.values
    shaping = st.shaping
    y = st.opt.y
    r_goal_seen = st.opt.r_goal
    r_free_seen = st.opt.r_free
    phi_row = st.phi_row
    w = st.w
    on = st.feat.on
    centre = st.feat.centre
    succ = st.model.successor
    nb = st.free.neighbour
    goal = st.free.goal[0]
    works = st.model.works
    known_d = st.known.distance
    known_q = st.known.queue
    known_stale = st.known.stale
    direct = model_phi(par) if GENERAL else True
    based = par.rebase if GENERAL else False
    a = -1
    if par.known_route:
        if known_stale[0]:
            known_distances(nb, works, known_d, known_q, goal)
            known_stale[0] = False
        a = known_move(nb, works, known_d, s)
    if a >= 0:
        pass
    elif par.lookahead and shaping[0]:
        if based:
            rebase(par, q, w, on, centre, y, phi_row, succ, s)
        action_values(par, q, values, y, phi_row, w, on, centre, succ, nb, goal,
                      r_free_seen[0], goal_reward(r_goal_seen, r_free_seen, par.gamma),
                      direct, based, s)
        a = argmax_first(values, 0)
    elif based and tried_max(q, succ, s) > -np.inf:
        a = tried_argmax(q, succ, s)
    else:
        a = argmax_first(q, s)
    return a


# ---------------------------------------------------------------- agent events


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


@njit(**HOOK)
def plan(par, q, w, on, centre, y, phi_row, succ, to_goal, reward, works, fails, seen, n_seen,
         r_fail, direct, based, shaping, n_updates, rng):
    """``n_updates`` shaped Q updates on seen pairs drawn uniformly, each replaying a drawn
    outcome."""
    gamma = par.gamma
    alpha = par.alpha
    scale = par.scale
    based = based if GENERAL else False
    direct = direct if GENERAL else True
    n = n_seen[0]
    n_a = q.shape[1]
    for _ in range(n_updates):
        ps, pa = pair_of(seen[draw_below(rng, n)], n_a)
        ps2 = succ[ps, pa]
        pterm = to_goal[ps, pa]
        pr = reward[ps, pa]
        if replay_draws_failure(works[ps, pa], fails[ps, pa], rng):
            ps2 = ps
            pterm = False
            pr = r_fail[0]
        pf = 0.0
        if based:
            p1 = rebase(par, q, w, on, centre, y, phi_row, succ, ps)
            p2 = 0.0 if pterm else rebase(par, q, w, on, centre, y, phi_row, succ, ps2)
            pf = gamma * p2 - p1
        elif shaping and direct:
            p2 = 0.0 if pterm else scale * y[ps2]
            pf = gamma * p2 - scale * y[ps]
        elif GENERAL and shaping:
            p2 = 0.0 if pterm else potential(par, w, on, centre, y, ps2)
            pf = gamma * p2 - potential(par, w, on, centre, y, ps)
        q_learning(q, ps, pa, pr, ps2, pterm, alpha, gamma, pf)


SWEEP_MIN = 1e-2  # sweeping: pairs whose relative TD error is below this are not queued (1e-4:
# 2.5x the time per step on the 256² maze for no fewer episodes; 1e-1: 3x the episodes)


@njit(**COLD)
def queue_into(q, succ, to_goal, reward, nb, y, key, pair, where, size, s, gamma, scale,
               shaping):
    """Queue the seen pairs that lead into s (the moves from its neighbours, and s's own
    bumps) by their TD error relative to the size of their value, |Phi| + |Q|: the values
    along a route of ~1000 moves span ~20 orders of magnitude under gamma = 0.95, so an
    absolute error would only ever serve the pairs near G."""
    n_a = q.shape[1]
    v = gamma * row_max(q, s)
    phi_s = scale * y[s] if shaping else 0.0
    for c in range(2 * n_a):
        if c < n_a:
            p = nb[s, c]
            if p < 0:
                continue
            b = back_move(c)
        else:
            p = s
            b = c - n_a
        if succ[p, b] != s or to_goal[p, b]:
            continue
        phi_p = scale * y[p] if shaping else 0.0
        delta = reward[p, b] + gamma * phi_s - phi_p + v - q[p, b]
        rel = abs(delta) / (abs(phi_p) + abs(q[p, b]) + 1e-300)
        if rel > SWEEP_MIN:
            push(key, pair, where, size, p * n_a + b, rel)


@njit(**COLD)
def sweep(par, q, y, succ, to_goal, reward, works, fails, r_fail, nb, key, pair, where, size,
          s, shaping, rng):
    """Prioritized sweeping: queue the pairs into s, then up to ``n_planning`` shaped updates
    of the queued pairs, largest relative TD error first, each queueing the pairs into its
    own state. Returns the updates made (the rest of the budget goes to uniform replays)."""
    gamma = par.gamma
    alpha = par.alpha
    scale = par.scale
    n_a = q.shape[1]
    queue_into(q, succ, to_goal, reward, nb, y, key, pair, where, size, s, gamma, scale,
               shaping)
    done = 0
    while done < par.n_planning:
        j = pop(key, pair, where, size)
        if j < 0:
            break
        ps, pa = pair_of(j, n_a)
        ps2 = succ[ps, pa]
        pterm = to_goal[ps, pa]
        pr = reward[ps, pa]
        if replay_draws_failure(works[ps, pa], fails[ps, pa], rng):
            ps2 = ps
            pterm = False
            pr = r_fail[0]
        pf = 0.0
        if shaping:
            p2 = 0.0 if pterm else scale * y[ps2]
            pf = gamma * p2 - scale * y[ps]
        q_learning(q, ps, pa, pr, ps2, pterm, alpha, gamma, pf)
        queue_into(q, succ, to_goal, reward, nb, y, key, pair, where, size, ps, gamma, scale,
                   shaping)
        done += 1
    return done


@njit(**COLD)
def repair_model(nb, blocked, dist, queue, goal, y, stamp, gamma, s):
    """A new wall at s changed distances: repair them and the values of the states whose
    distance changed (O(those states)); after a repair that fell back to a full BFS, mark
    the values stale."""
    changed = repair_distances(nb, blocked, dist, queue, goal, s)
    if changed[0] < 0:
        mark_stale(stamp)
    else:
        revalue(y, stamp, dist, changed, gamma)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """Real step: F from the cached Phi(s) and Phi(s'); Q(-lambda) update; V_NN update;
    model (and leak-free supports) update; ``n_planning`` shaped model updates."""
    par = st.par
    q = st.q
    w = st.w
    v_trace = st.v_trace
    phi_row = st.phi_row
    step_v = st.step_v
    phi_here = st.phi_here
    shaping_on = st.shaping
    train_on = st.train_v
    f_sum = st.tally.f_sum
    f_sq = st.tally.f_sq
    n_shaped = st.tally.n_shaped
    trace_e = st.traces.e
    trace_pairs = st.traces.pairs
    trace_n = st.traces.n
    on = st.feat.on
    base = st.feat.base
    centre = st.feat.centre
    preds = st.feat.preds
    anchor = st.feat.anchor
    stack = st.feat.stack
    succ = st.model.successor
    to_goal = st.model.to_goal
    reward = st.model.reward
    works = st.model.works
    fails = st.model.fails
    seen = st.model.seen
    n_seen = st.model.n_seen
    r_fail = st.model.r_fail
    nb = st.free.neighbour
    blocked = st.free.blocked
    dist = st.free.distance
    queue = st.free.queue
    goal = st.free.goal[0]
    y = st.opt.y
    stamp = st.opt.stamp
    r_goal_seen = st.opt.r_goal
    r_free_seen = st.opt.r_free
    known_stale = st.known.stale
    sweep_key = st.sweep.key
    sweep_pair = st.sweep.pair
    sweep_where = st.sweep.where
    sweep_size = st.sweep.size
    gamma = par.gamma
    shaping = shaping_on[0]
    based = (shaping and par.rebase) if GENERAL else False
    direct = model_phi(par) if GENERAL else True  # Phi read as scale * y
    scale = par.scale
    vt = par.v_target if GENERAL else OPTIMISTIC
    optimistic = (vt >= LOG_OPTIMISTIC) if GENERAL else True
    leak_free = par.leak_free if GENERAL else False
    traces_on = (par.lam_q > 0.0) if GENERAL else False
    train_v = train_on[0] if GENERAL else False
    if based:
        rebase(par, q, w, on, centre, y, phi_row, succ, s)
    stale = observe_rewards(r_goal_seen, r_free_seen, s, r, s2, terminated)
    # model first: a new move may join s' to supports before Phi(s') is read
    was_fail = blocked[s, a]
    first_work = works[s, a] == 0
    if note_pair(succ, seen, n_seen, s, a) and leak_free and s2 != s:
        leak_free_edge(on, base, centre, preds, anchor, stack, succ, s, s2, par.normalise)
    observe_outcome(succ, to_goal, reward, works, fails, r_fail, s, a, r, s2, terminated,
                    s2 == nb[s, a])
    now_fail = never_worked(succ, works, s, a)
    if first_work and works[s, a] > 0:
        known_stale[0] = True  # a move worked for the first time: known routes may shorten
    blocked[s, a] = now_fail
    # the optimistic model changed: a move now known to fail (BFS only if a distance
    # changes), or one known to fail that moved after all (noisy physics worlds; on the
    # grid and at the exact fidelity a move's outcome never changes)
    if optimistic and now_fail != was_fail and (
            was_fail or distances_change(nb, dist, blocked, s, a)):
        if was_fail:  # a wall that moved after all (noisy worlds): distances may fall
            bfs_distances(nb, blocked, dist, queue, goal)
            mark_stale(stamp)
        else:
            repair_model(nb, blocked, dist, queue, goal, y, stamp, gamma, s)
        stale = True
    if stale and optimistic:
        ensure_values(y, stamp, r_goal_seen, r_free_seen, dist, queue, gamma)
    if leak_free and not terminated:
        leak_free_enter(on, base, centre, preds, anchor, stack, succ, s2, par.normalise)
    if terminated:
        phi_s2 = 0.0
    elif direct:
        phi_s2 = scale * y[s2]
    else:
        phi_s2 = potential(par, w, on, centre, y, s2)
    if based and not terminated:
        phi_s2 = rebase(par, q, w, on, centre, y, phi_row, succ, s2)
    if train_v and vt == TD_REWARDS:  # V_NN(s') only where TD(lambda) needs it
        v2 = 0.0 if terminated else v_of(w, on, centre, s2)
        v_td_lambda(w, v_trace, on, centre, s, r, v2, is_greedy(q, s, a), gamma, par.lam,
                    step_v[0])
    f = 0.0
    if shaping:
        phi_s = phi_row[s] if based else phi_here[0]
        f = gamma * phi_s2 - phi_s
    record_shaping(f_sum, f_sq, n_shaped, f, shaping)
    if traces_on:
        q_lambda(q, trace_e, trace_pairs, trace_n, s, a, r, s2, terminated, par.alpha, gamma,
                 par.lam_q, par.trace_min, f)
    else:
        q_learning(q, s, a, r, s2, terminated, par.alpha, gamma, f)
    if train_v and vt != TD_REWARDS and vt != OPTIMISTIC:
        fit_v(par, q, w, on, centre, y, succ, phi_row, phi_here, step_v, s, shaping, based, rng)
    n_uniform = par.n_planning
    if par.sweeping:
        n_uniform -= sweep(par, q, y, succ, to_goal, reward, works, fails, r_fail, nb,
                           sweep_key, sweep_pair, sweep_where, sweep_size, s, shaping, rng)
    plan(par, q, w, on, centre, y, phi_row, succ, to_goal, reward, works, fails, seen, n_seen,
         r_fail, direct, based, shaping, n_uniform, rng)
    phi_here[0] = phi_s2


@njit(**HOOK)
def begin(st, s0):
    """Reset traces and per-episode sums; shaping on from ``warmup``; V_NN frozen from
    ``freeze``; anchor s0's centre (leak-free); cache Phi(s0)."""
    par = st.par
    q = st.q
    w = st.w
    v_trace = st.v_trace
    phi_row = st.phi_row
    phi_here = st.phi_here
    shaping_on = st.shaping
    train_on = st.train_v
    tally = st.tally
    trace_e = st.traces.e
    trace_pairs = st.traces.pairs
    trace_n = st.traces.n
    on = st.feat.on
    base = st.feat.base
    centre = st.feat.centre
    preds = st.feat.preds
    anchor = st.feat.anchor
    stack = st.feat.stack
    succ = st.model.successor
    dist = st.free.distance
    queue = st.free.queue
    y = st.opt.y
    stamp = st.opt.stamp
    r_goal_seen = st.opt.r_goal
    r_free_seen = st.opt.r_free
    episode = st.tally.episode
    vt = par.v_target if GENERAL else OPTIMISTIC
    begin_tally(tally)
    if vt >= LOG_OPTIMISTIC:  # the first episode, or a state changed from outside
        ensure_values(y, stamp, r_goal_seen, r_free_seen, dist, queue, par.gamma)
    if GENERAL and vt == TD_REWARDS:
        v_trace[:] = 0.0
    if GENERAL and par.lam_q > 0.0:
        clear_traces(trace_e, trace_pairs, trace_n)
    ep = episode[0]
    shaping_on[0] = ep >= par.warmup
    train_on[0] = ep < par.freeze
    if GENERAL and par.leak_free:
        leak_free_enter(on, base, centre, preds, anchor, stack, succ, s0, par.normalise)
    if GENERAL and shaping_on[0] and par.rebase:
        phi_here[0] = rebase(par, q, w, on, centre, y, phi_row, succ, s0)
    elif GENERAL:
        phi_here[0] = potential(par, w, on, centre, y, s0)
    else:
        phi_here[0] = par.scale * y[s0]


@njit(cache=True)
def potential_table(st, out):
    """out[s] = Phi(s) for every state (the recorder's potential panel)."""
    par = st.par
    if par.v_target >= LOG_OPTIMISTIC:
        ensure_values(st.opt.y, st.opt.stamp, st.opt.r_goal, st.opt.r_free, st.free.distance,
                      st.free.queue, par.gamma)
    for s in range(out.shape[0]):
        out[s] = potential(par, st.w, st.feat.on, st.feat.centre, st.opt.y, s)


def lean_hooks() -> dict[str, object]:
    """The hooks' Python functions compiled with GENERAL = False: what a state holding
    :class:`~learning.rnh_ql_plus.config.LeanParams` inlines (see :mod:`learning.hooks`)."""
    import types as pytypes

    env = dict(globals())
    env["GENERAL"] = False

    def copy(name: str):
        fn = globals()[name].py_func
        return pytypes.FunctionType(fn.__code__, env, fn.__name__, fn.__defaults__,
                                    fn.__closure__)

    for helper in ("action_values", "plan"):  # the hooks below call these lean copies
        env[helper] = njit(inline="always")(copy(helper))
    return {name: copy(name) for name in ("act", "update", "begin", "exploit")}
