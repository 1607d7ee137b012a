"""RNH-QL+'s planned updates: shaped Q updates on pairs of the learned model (Dyna), drawn
uniformly (:func:`plan`) or by priority (:func:`sweep`, prioritized sweeping).

Each takes arrays, not the state (see :mod:`learning.methods.rnh_ql_plus.rules` on why a hook
reads a named tuple's fields once, at its top).
"""

from __future__ import annotations

from numba import njit

from learning.parts.free_space import back_move
from learning.parts.move_model import pair_of, replay_draws_failure
from learning.parts.priority_queue import pop, push
from learning.parts.tabular import draw_below, q_learning, row_max

HOOK = dict(cache=True, inline="always")
SWEEP_MIN = 1e-2  # sweeping: pairs whose relative TD error is below this are not queued (1e-4:
# 2.5x the time per step on the 256² maze for no fewer episodes; 1e-1: 3x the episodes)


@njit(**HOOK)
def replay(j, succ, to_goal, reward, works, fails, r_fail, rng):
    """(s, a, s', terminated, r) of a planned replay of the flat pair j: its stored outcome,
    or staying put with ``r_fail`` when a pair seen both to work and to fail draws its
    failure (:func:`learning.parts.move_model.replay_draws_failure`)."""
    ps, pa = pair_of(j, succ.shape[1])
    ps2 = succ[ps, pa]
    pterm = to_goal[ps, pa]
    pr = reward[ps, pa]
    if replay_draws_failure(works[ps, pa], fails[ps, pa], rng):
        ps2 = ps
        pterm = False
        pr = r_fail[0]
    return ps, pa, ps2, pterm, pr


@njit(**HOOK)
def model_shaping(y, scale, gamma, s, s2, terminated):
    """F = gamma * Phi(s') - Phi(s) of a replayed step, Phi = scale * y, Phi(G) = 0."""
    p2 = 0.0 if terminated else scale * y[s2]
    return gamma * p2 - scale * y[s]


@njit(**HOOK)
def plan(par, q, y, succ, to_goal, reward, works, fails, seen, n_seen, r_fail, shaping,
         n_updates, rng):
    """``n_updates`` Q updates on seen pairs drawn uniformly, each replaying a drawn outcome
    with the shaping term of Phi = scale * y (when ``shaping``)."""
    gamma = par.gamma
    alpha = par.alpha
    scale = par.scale
    n = n_seen[0]
    for _ in range(n_updates):
        ps, pa, ps2, pterm, pr = replay(seen[draw_below(rng, n)], succ, to_goal, reward,
                                        works, fails, r_fail, rng)
        pf = model_shaping(y, scale, gamma, ps, ps2, pterm) if shaping else 0.0
        q_learning(q, ps, pa, pr, ps2, pterm, alpha, gamma, pf)


@njit(cache=True)
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


@njit(cache=True)
def sweep(par, q, y, succ, to_goal, reward, works, fails, r_fail, nb, key, pair, where, size,
          s, shaping, rng):
    """Prioritized sweeping: queue the pairs into s, then up to ``n_planning`` shaped updates
    of the queued pairs, largest relative TD error first, each queueing the pairs into its
    own state. Returns the updates made (the rest of the budget goes to uniform replays).
    Phi is scale * y."""
    gamma = par.gamma
    alpha = par.alpha
    scale = par.scale
    queue_into(q, succ, to_goal, reward, nb, y, key, pair, where, size, s, gamma, scale,
               shaping)
    done = 0
    while done < par.n_planning:
        j = pop(key, pair, where, size)
        if j < 0:
            break
        ps, pa, ps2, pterm, pr = replay(j, succ, to_goal, reward, works, fails, r_fail, rng)
        pf = model_shaping(y, scale, gamma, ps, ps2, pterm) if shaping else 0.0
        q_learning(q, ps, pa, pr, ps2, pterm, alpha, gamma, pf)
        queue_into(q, succ, to_goal, reward, nb, y, key, pair, where, size, ps, gamma, scale,
                   shaping)
        done += 1
    return done
