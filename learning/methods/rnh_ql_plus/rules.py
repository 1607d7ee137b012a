"""RNH-QL+'s rules and agent events.

The architecture is RNH-QL's: a Q-table below, a potential above that shapes
the Q update with F = gamma * Phi(s') - Phi(s), Phi(goal) = 0. Here the potential
is the optimistic model's value, Phi = scale * y (:mod:`learning.methods.rnh_ql_plus.optimism`),
and (see :class:`learning.methods.rnh_ql_plus.config.RNHQLPlus`):

* ``lookahead``: an untried action is valued by one step of look-ahead on Phi
  in the optimistic model (Wiewiora's look-ahead advice), so the agent heads
  for G along the route it believes free instead of trying actions in index
  order;
* a learned model (:mod:`learning.parts.move_model`: a move's successor and how often
  it failed) drives ``n_planning`` shaped Q updates per step (Dyna,
  :mod:`learning.methods.rnh_ql_plus.planning`), uniformly or by priority (``sweeping``);
* ``known_route``: the greedy test follows a shortest route over moves seen to work.

A move "works" when it arrives in the neighbour it heads for without a bump, read from
its reward (:mod:`learning.parts.move_reading`): with carried pose a grazing move can arrive
and be paid the bump, and counting it as working made the greedy routes bump.

The ablation's variants (network potentials, re-based rows, Q traces, leak-free
features) are :mod:`learning.methods.rnh_ql_plus_ablation`, which builds on these rules.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from learning.methods.rnh_ql_plus.optimism import (
    ensure_values,
    goal_reward,
    mark_stale,
    observe_rewards,
    revalue,
)
from learning.methods.rnh_ql_plus.planning import plan, sweep
from learning.parts.coverage import coverage_move
from learning.parts.free_space import bfs_distances, distances_change, repair_distances
from learning.parts.known_routes import known_distances, known_move, reliable
from learning.parts.move_model import never_worked, note_pair, observe_outcome
from learning.parts.move_reading import read_move
from learning.parts.tabular import argmax_drawn, argmax_first, draw_below, eps_greedy, q_learning
from learning.parts.tally import begin_tally, record_shaping

HOOK = dict(cache=True, inline="always")


@njit(**HOOK)
def untried_value(u, goal, phi_s, phi_u, r_free, r_goal, gamma):
    """An untried move's value by one step of look-ahead in the optimistic model, relative to
    Phi(s): r_free + gamma * Phi(u) - Phi(s) into a free neighbour u; r_goal - Phi(s) into
    G; -inf off the arena (u < 0)."""
    if u < 0:
        return -np.inf
    if u == goal:
        return r_goal - phi_s
    return r_free + gamma * phi_u - phi_s


@njit(**HOOK)
def action_values(par, q, out, y, succ, nb, goal, r_free, r_goal, s, bonus):
    """Row s's action values (Q + Phi - Phi(s)) into the scratch row ``out[0]``: a tried
    action its Q; an untried one :func:`untried_value` plus ``bonus`` (the behaviour's
    ``untried_bonus``; the test's 0)."""
    scale = par.scale
    phi_s = scale * y[s]
    for a in range(q.shape[1]):
        if succ[s, a] >= 0:
            out[0, a] = q[s, a]
        else:
            u = nb[s, a]
            out[0, a] = untried_value(u, goal, phi_s, scale * y[max(u, 0)], r_free, r_goal,
                                      par.gamma) + bonus


@njit(**HOOK)
def model_values(par, out, y, blocked, nb, goal, r_free, r_goal, s):
    """Row s's action values in the optimistic model (``model_acting``) into ``out[0]``:
    every move, tried or not, :func:`untried_value` (one step of look-ahead on Phi into the
    cell it heads for); a move the model holds blocked -inf."""
    scale = par.scale
    phi_s = scale * y[s]
    for a in range(out.shape[1]):
        u = nb[s, a]
        if blocked[s, a]:
            out[0, a] = -np.inf
        else:
            out[0, a] = untried_value(u, goal, phi_s, scale * y[max(u, 0)], r_free, r_goal,
                                      par.gamma)


@njit(**HOOK)
def model_move(nb, blocked, dist, works, fails, s):
    """``model_test``'s move: into the neighbour the optimistic model holds nearest G, ties
    to a move seen to work, then to the lowest index (-1: every move blocked)."""
    best, best_d, best_works = -1, -1, False
    for a in range(nb.shape[1]):
        u = nb[s, a]
        if u < 0 or blocked[s, a] or dist[u] < 0:
            continue
        ok = reliable(works, fails, s, a)
        if best < 0 or dist[u] < best_d or (dist[u] == best_d and ok and not best_works):
            best, best_d, best_works = a, dist[u], ok
    return best


@njit(**HOOK)
def known_route_move(nb, works, fails, known_d, known_q, known_stale, goal, s):
    """The first move of a shortest route from s over moves seen to work (-1: s has none),
    the routes brought up to date first if a move's standing changed since."""
    if known_stale[0]:
        known_distances(nb, works, fails, known_d, known_q, goal)
        known_stale[0] = False
    return known_move(nb, works, fails, known_d, s)


# Every hook below first reads each array it or its callees use into a local, one field per
# statement, before any branch or loop; callees inside branches get arrays, never the state.
# numba reference-counts each read of a named tuple's field, and prunes the count only
# where the read is on every path through the hook: a read inside a branch costs two atomic
# operations per call even when the branch never runs (measured: the rnh-ql+ kernel at 0.7M
# env steps/s with reads in branches, 5M+ with them hoisted). Nested tuples (``st.model``,
# ``st.free``) are read through once, at the top, for the same reason.


@njit(**HOOK)
def act(st, s, rng):
    """The coverage walk's move while the episode has coverage steps left
    (``explore_steps``); else epsilon-greedy: with look-ahead, greedy over
    :func:`action_values` (ties drawn), or over :func:`model_values` with
    ``model_acting``."""
    par = st.par
    q = st.q
    values = st.values
    shaping = st.shaping
    y = st.opt.y
    r_goal_seen = st.opt.r_goal
    r_free_seen = st.opt.r_free
    succ = st.model.successor
    nb = st.free.neighbour
    blocked = st.free.blocked
    goal = st.free.goal[0]
    cover_d = st.coverage.distance
    cover_q = st.coverage.queue
    cover_left = st.coverage.left
    cover_done = st.coverage.done
    cover_mark = st.coverage.mark
    cover_first = st.coverage.first
    cover_searches = st.coverage.searches
    a = -1
    if cover_left[0] > 0 and not cover_done[0]:
        a = coverage_move(nb, blocked, succ, goal, cover_d, cover_q, cover_done, cover_mark,
                          cover_first, cover_searches, s, rng)
        cover_left[0] -= 1
    if a < 0:  # no move yet
        if not (par.lookahead and shaping[0]):
            a = eps_greedy(q, s, par.eps, rng)
        elif rng.random() < par.eps:
            a = draw_below(rng, q.shape[1])
        else:
            r_goal = goal_reward(r_goal_seen, r_free_seen, par.gamma)
            if par.model_acting:
                model_values(par, values, y, blocked, nb, goal, r_free_seen[0], r_goal, s)
            else:
                action_values(par, q, values, y, succ, nb, goal, r_free_seen[0], r_goal, s,
                              par.bonus)
            a = argmax_drawn(values, 0, rng)
    return a


@njit(**HOOK)
def exploit(st, s):
    """Greedy test policy, ties to the lowest index: with ``known_route``, the first move of
    a shortest route over moves seen to work, where s has one; with ``model_test``, the
    optimistic model's move (:func:`model_move`) where s has no known route or a longer
    one than the model's; else with look-ahead over :func:`action_values`; else over Q."""
    par = st.par
    q = st.q
    values = st.values
    shaping = st.shaping
    y = st.opt.y
    r_goal_seen = st.opt.r_goal
    r_free_seen = st.opt.r_free
    succ = st.model.successor
    works = st.model.works
    fails = st.model.fails
    nb = st.free.neighbour
    goal = st.free.goal[0]
    known_d = st.known.distance
    known_q = st.known.queue
    known_stale = st.known.stale
    blocked = st.free.blocked
    dist = st.free.distance
    a = -1
    if par.known_route:
        a = known_route_move(nb, works, fails, known_d, known_q, known_stale, goal, s)
    if par.model_test and (a < 0 or known_d[s] != dist[s]):
        a = model_move(nb, blocked, dist, works, fails, s)
    if a < 0:  # no move yet
        if par.lookahead and shaping[0]:
            action_values(par, q, values, y, succ, nb, goal, r_free_seen[0],
                          goal_reward(r_goal_seen, r_free_seen, par.gamma), s, 0.0)
            a = argmax_first(values, 0)
        else:
            a = argmax_first(q, s)
    return a


# ---------------------------------------------------------------- agent events


@njit(cache=True)
def repair_model(nb, blocked, dist, queue, goal, y, stamp, gamma, s):
    """A new wall at s changed distances: repair them and the values of the states whose
    distance changed (O(those states)); after a repair that fell back to a full BFS, mark
    the values stale."""
    changed = repair_distances(nb, blocked, dist, queue, goal, s)
    if changed[0] < 0:
        mark_stale(stamp)
    else:
        revalue(y, stamp, dist, changed, gamma)


@njit(cache=True)
def revise_optimism(nb, blocked, dist, queue, goal, y, stamp, r_goal_seen, r_free_seen, s, a,
                    was_fail, now_fail, stale, gamma):
    """The optimistic model after a step that changed what it rests on: a move now known to
    fail (BFS only if a distance changes), one known to fail that moved after all (noisy
    physics worlds; on the grid and at the exact fidelity a move's outcome never changes),
    or a reward (``stale``). A real call, made only then (rnh-ql+ and its ablation share it;
    the steps before it stay written out in each hook: as an inlined helper taking the
    model's arrays they cost the kernel ~8 % of its speed, measured; again on paper-50 at
    n_planning 0: -6 % inlined, taking the arrays or the state (numba reference-counts each
    array an inlined helper takes or reads again, per call), -25 % as a real call)."""
    if now_fail != was_fail and (was_fail or distances_change(nb, dist, blocked, s, a)):
        if was_fail:  # a wall that moved after all (noisy worlds): distances may fall
            bfs_distances(nb, blocked, dist, queue, goal)
            mark_stale(stamp)
        else:
            repair_model(nb, blocked, dist, queue, goal, y, stamp, gamma, s)
        stale = True
    if stale:
        ensure_values(y, stamp, r_goal_seen, r_free_seen, dist, queue, gamma)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """Real step: the model learns it; F from the cached Phi(s) and Phi(s'); Q update;
    ``n_planning`` shaped model updates (by priority first with ``sweeping``)."""
    par = st.par
    q = st.q
    phi_here = st.phi_here
    shaping_on = st.shaping
    f_sum = st.tally.f_sum
    f_sq = st.tally.f_sq
    n_shaped = st.tally.n_shaped
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
    clean = read_move(r_stay, r_clean, s, r, s2, terminated)
    stale = observe_rewards(r_goal_seen, r_free_seen, r, terminated, clean)
    was_fail = blocked[s, a]
    was_reliable = reliable(works, fails, s, a)
    note_pair(succ, seen, n_seen, s, a)
    observe_outcome(succ, to_goal, reward, works, fails, r_fail, s, a, r, s2, terminated,
                    clean and s2 == nb[s, a])
    now_fail = never_worked(succ, works, s, a)
    if reliable(works, fails, s, a) != was_reliable:
        known_stale[0] = True  # a move's standing changed: known routes may change
    blocked[s, a] = now_fail
    if stale or now_fail != was_fail:  # the optimistic model's ground changed
        revise_optimism(nb, blocked, dist, queue, goal, y, stamp, r_goal_seen, r_free_seen, s,
                        a, was_fail, now_fail, stale, gamma)
    phi_s2 = 0.0 if terminated else par.scale * y[s2]
    f = gamma * phi_s2 - phi_here[0] if shaping else 0.0
    record_shaping(f_sum, f_sq, n_shaped, f, shaping)
    q_learning(q, s, a, r, s2, terminated, par.alpha, gamma, f)
    n_uniform = par.n_planning
    if par.sweeping:
        n_uniform -= sweep(par, q, y, succ, to_goal, reward, works, fails, r_fail, nb,
                           sweep_key, sweep_pair, sweep_where, sweep_size, s, shaping, rng)
    plan(par, q, y, succ, to_goal, reward, works, fails, seen, n_seen, r_fail, shaping,
         n_uniform, rng)
    phi_here[0] = phi_s2


@njit(**HOOK)
def begin(st, s0):
    """Reset the per-episode sums; shaping on from ``warmup``; the values of y brought up
    to date (the first episode, or a state changed from outside); cache Phi(s0)."""
    par = st.par
    tally = st.tally
    phi_here = st.phi_here
    shaping_on = st.shaping
    dist = st.free.distance
    queue = st.free.queue
    y = st.opt.y
    stamp = st.opt.stamp
    r_goal_seen = st.opt.r_goal
    r_free_seen = st.opt.r_free
    episode = st.tally.episode
    cover_left = st.coverage.left
    begin_tally(tally)
    cover_left[0] = par.explore_steps
    ensure_values(y, stamp, r_goal_seen, r_free_seen, dist, queue, par.gamma)
    shaping_on[0] = episode[0] >= par.warmup
    phi_here[0] = par.scale * y[s0]


@njit(cache=True)
def potential_table(st, out):
    """out[s] = Phi(s) for every state (the recorder's potential panel)."""
    par = st.par
    ensure_values(st.opt.y, st.opt.stamp, st.opt.r_goal, st.opt.r_free, st.free.distance,
                  st.free.queue, par.gamma)
    for s in range(out.shape[0]):
        out[s] = par.scale * st.opt.y[s]
