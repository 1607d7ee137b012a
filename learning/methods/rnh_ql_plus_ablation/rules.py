"""The RNH-QL+ ablation's rules and agent events: rnh-ql+'s
(:mod:`learning.methods.rnh_ql_plus.rules`, whose pieces these call), with the switches
the ablation measured, every one compiled in:

* the potential (``v_target``, a
  :class:`~learning.methods.rnh_ql_plus_ablation.config.Potential`):
  the paper's V_NN by TD(lambda) on rewards; V_NN toward the table's own value or
  its log; V_NN toward the log of the optimistic model's value y(s); Phi = y(s)
  itself, no network (rnh-ql+'s); or y(s) * exp(V_NN(s)), V_NN learning a residual of
  at most 0 (:mod:`learning.methods.rnh_ql_plus_ablation.potential`);
* the lattice is tied to the map (a centre every ``spacing`` cells) and the
  features are sparse (:mod:`learning.methods.rnh_ql_plus_ablation.features`): a step costs
  O(M), not O(K), on any map size; ``leak_free`` supports grow by flood fill
  along moves seen to succeed;
* ``rebase``: when Phi(s) changes, row s's tried actions are shifted so Q + Phi
  is unchanged (off by default: when the optimistic model learns of a wall,
  Phi falls and so should the values learned through it);
* ``lam_q`` adds Watkins Q(lambda) traces to the real step.

Each hook reads its state's fields once, at its top (see :mod:`learning.methods.rnh_ql_plus.rules`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from learning.methods.rnh_ql_plus.optimism import ensure_values, goal_reward, observe_rewards
from learning.methods.rnh_ql_plus.planning import plan as plus_plan
from learning.methods.rnh_ql_plus.planning import replay, sweep
from learning.methods.rnh_ql_plus.rules import action_values as plus_action_values
from learning.methods.rnh_ql_plus.rules import (
    known_route_move,
    revise_optimism,
    untried_value,
)
from learning.methods.rnh_ql_plus_ablation.features import leak_free_edge, leak_free_enter
from learning.methods.rnh_ql_plus_ablation.potential import (
    LOG_OPTIMISTIC,
    OPTIMISTIC,
    TD_REWARDS,
    fit_v,
    model_phi,
    potential,
    rebase,
    tried_argmax,
    tried_max,
    v_of,
    v_td_lambda,
)
from learning.parts.known_routes import reliable
from learning.parts.move_model import never_worked, note_pair, observe_outcome
from learning.parts.move_reading import read_move
from learning.parts.tabular import (
    argmax_drawn,
    argmax_first,
    draw_below,
    eps_greedy,
    is_greedy,
    q_learning,
)
from learning.parts.tally import begin_tally, record_shaping
from learning.parts.traces import clear_traces, q_lambda

HOOK = dict(cache=True, inline="always")


@njit(**HOOK)
def action_values(par, q, out, y, phi_row, w, on, centre, succ, nb, goal, r_free, r_goal,
                  direct, based, s):
    """Row s's action values (in re-based units, Q + Phi - Phi(s)) into the scratch row
    ``out[0]``: rnh-ql+'s (:func:`learning.methods.rnh_ql_plus.rules.action_values`) when ``direct``
    (Phi is scale * y, :func:`model_phi`); else a tried action its Q, an untried one
    :func:`~learning.methods.rnh_ql_plus.rules.untried_value` on :func:`potential` (``based``: rows
    are re-based, Phi(s) is the row's)."""
    if direct:
        plus_action_values(par, q, out, y, succ, nb, goal, r_free, r_goal, s, 0.0)
    else:
        phi_s = phi_row[s] if based else potential(par, w, on, centre, y, s)
        for a in range(q.shape[1]):
            u = nb[s, a]
            if succ[s, a] >= 0:
                out[0, a] = q[s, a]
            else:
                out[0, a] = untried_value(u, goal, phi_s,
                                          potential(par, w, on, centre, y, max(u, 0)), r_free,
                                          r_goal, par.gamma)


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
    direct = model_phi(par)
    based = par.rebase
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
    fails = st.model.fails
    known_d = st.known.distance
    known_q = st.known.queue
    known_stale = st.known.stale
    direct = model_phi(par)
    based = par.rebase
    a = -1
    if par.known_route:
        a = known_route_move(nb, works, fails, known_d, known_q, known_stale, goal, s)
    if a < 0:  # no move yet
        if par.lookahead and shaping[0]:
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


@njit(**HOOK)
def plan(par, q, w, on, centre, y, phi_row, succ, to_goal, reward, works, fails, seen, n_seen,
         r_fail, direct, based, shaping, n_updates, rng):
    """``n_updates`` shaped Q updates on seen pairs drawn uniformly, each replaying a drawn
    outcome: rnh-ql+'s (:func:`learning.methods.rnh_ql_plus.planning.plan`) when Phi is scale * y
    or shaping is off; else shaped by :func:`potential` or by re-based rows (``based``)."""
    if direct or not shaping:
        plus_plan(par, q, y, succ, to_goal, reward, works, fails, seen, n_seen, r_fail,
                  shaping, n_updates, rng)
    else:
        gamma = par.gamma
        n = n_seen[0]
        for _ in range(n_updates):
            ps, pa, ps2, pterm, pr = replay(seen[draw_below(rng, n)], succ, to_goal, reward,
                                            works, fails, r_fail, rng)
            if based:
                p1 = rebase(par, q, w, on, centre, y, phi_row, succ, ps)
                p2 = 0.0 if pterm else rebase(par, q, w, on, centre, y, phi_row, succ, ps2)
            else:
                p1 = potential(par, w, on, centre, y, ps)
                p2 = 0.0 if pterm else potential(par, w, on, centre, y, ps2)
            q_learning(q, ps, pa, pr, ps2, pterm, par.alpha, gamma, gamma * p2 - p1)


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
    r_stay = st.reading.r_stay
    r_clean = st.reading.r_clean
    sweep_key = st.sweep.key
    sweep_pair = st.sweep.pair
    sweep_where = st.sweep.where
    sweep_size = st.sweep.size
    gamma = par.gamma
    shaping = shaping_on[0]
    based = shaping and par.rebase
    direct = model_phi(par)  # Phi read as scale * y
    scale = par.scale
    vt = par.v_target
    optimistic = vt >= LOG_OPTIMISTIC
    leak_free = par.leak_free
    traces_on = par.lam_q > 0.0
    train_v = train_on[0]
    if based:
        rebase(par, q, w, on, centre, y, phi_row, succ, s)
    # model first: a new move may join s' to supports before Phi(s') is read
    clean = read_move(r_stay, r_clean, s, r, s2, terminated)
    stale = observe_rewards(r_goal_seen, r_free_seen, r, terminated, clean)
    was_fail = blocked[s, a]
    was_reliable = reliable(works, fails, s, a)
    if note_pair(succ, seen, n_seen, s, a) and leak_free and s2 != s:
        leak_free_edge(on, base, centre, preds, anchor, stack, succ, s, s2, par.normalise)
    observe_outcome(succ, to_goal, reward, works, fails, r_fail, s, a, r, s2, terminated,
                    clean and s2 == nb[s, a])
    now_fail = never_worked(succ, works, s, a)
    if reliable(works, fails, s, a) != was_reliable:
        known_stale[0] = True  # a move's standing changed: known routes may change
    blocked[s, a] = now_fail
    if optimistic and (stale or now_fail != was_fail):
        revise_optimism(nb, blocked, dist, queue, goal, y, stamp, r_goal_seen, r_free_seen, s,
                        a, was_fail, now_fail, stale, gamma)
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
    vt = par.v_target
    begin_tally(tally)
    if vt >= LOG_OPTIMISTIC:  # the first episode, or a state changed from outside
        ensure_values(y, stamp, r_goal_seen, r_free_seen, dist, queue, par.gamma)
    if vt == TD_REWARDS:
        v_trace[:] = 0.0
    if par.lam_q > 0.0:
        clear_traces(trace_e, trace_pairs, trace_n)
    ep = episode[0]
    shaping_on[0] = ep >= par.warmup
    train_on[0] = ep < par.freeze
    if par.leak_free:
        leak_free_enter(on, base, centre, preds, anchor, stack, succ, s0, par.normalise)
    if shaping_on[0] and par.rebase:
        phi_here[0] = rebase(par, q, w, on, centre, y, phi_row, succ, s0)
    else:
        phi_here[0] = potential(par, w, on, centre, y, s0)


@njit(cache=True)
def potential_table(st, out):
    """out[s] = Phi(s) for every state (the recorder's potential panel)."""
    par = st.par
    if par.v_target >= LOG_OPTIMISTIC:
        ensure_values(st.opt.y, st.opt.stamp, st.opt.r_goal, st.opt.r_free, st.free.distance,
                      st.free.queue, par.gamma)
    for s in range(out.shape[0]):
        out[s] = potential(par, st.w, st.feat.on, st.feat.centre, st.opt.y, s)
