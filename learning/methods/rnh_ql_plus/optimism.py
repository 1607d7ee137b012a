"""RNH-QL+'s optimistic value: what the agent assumes the moves it has not tried are worth.

The agent keeps a free-space model (:mod:`learning.parts.free_space`, shared with HAQL):
every move it has not seen fail is assumed free, and a state is valued by the
route to G that assumption allows:

    y(s) = r_free * (1 - gamma^(d-1)) / (1 - gamma) + gamma^(d-1) * r_goal,

d = the BFS distance from s to G over the moves not known to fail, r_goal the
reward seen on entering G (until G is first reached, :func:`goal_reward`'s optimistic
stand-in), r_free the reward seen on the last free move (0 under goal-only
rewards). A state with no such route is worth wandering forever,
r_free / (1 - gamma) (0 if that is not positive).

The values are cached (``y``) and stamped with the two rewards they were
computed with; :func:`ensure_values` refreshes them where the model can change,
so a read is a load.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit


class Optimism(NamedTuple):
    y: np.ndarray  # float64[nS]; the cached optimistic values
    stamp: np.ndarray  # float64[2]; (r_goal, r_free) they were computed with; [0] = -1: stale
    r_goal: np.ndarray  # float64[1]; the reward seen on entering G (0: not seen yet)
    r_free: np.ndarray  # float64[1]; the reward seen on the last free move


def new_optimism(n_s: int) -> Optimism:
    return Optimism(np.zeros(n_s), np.array([-1.0, 0.0]), np.zeros(1), np.zeros(1))


@njit(cache=True, inline="always")
def goal_reward(r_goal_seen, r_free_seen, gamma):
    """r_G of the model: the reward seen on entering G; until then an optimistic stand-in,
    one more than wandering forever on free moves (r_free / (1 - gamma) + 1; 1 when a free
    move earns nothing or less), so that y falls with the distance to G under any reward
    scheme. (A stand-in of 1 under the paper's +1 per free move made y *rise* with the
    distance and drove the agent away from a G it had not reached yet.)"""
    if r_goal_seen[0] > 0.0:
        return r_goal_seen[0]
    r_free = r_free_seen[0]
    return r_free / (1.0 - gamma) + 1.0 if r_free > 0.0 else 1.0


@njit(cache=True)
def refresh_values(y, stamp, r_goal_seen, r_free_seen, dist, queue, gamma):
    """Fill the cache of y from the BFS distances and the rewards seen, and stamp it with
    those rewards. O(states); runs after a BFS and when a reward of the model changes.
    The reachable states are walked in the BFS queue's order, where the distance never
    falls, so the power gamma^(d-1) is taken once per distance, not once per state (it
    was 60% of the cost: 40 us a refresh on paper-50)."""
    g = gamma
    r_free = r_free_seen[0]
    r_goal = goal_reward(r_goal_seen, r_free_seen, gamma)
    wander = r_free / (1.0 - g) if r_free > 0.0 else 0.0
    n_reach = 0
    for s in range(dist.shape[0]):
        if dist[s] < 0:
            y[s] = wander
        else:
            n_reach += 1
    d_prev = -1
    v = 0.0
    for i in range(n_reach):  # the queue holds the reachable states, G first
        s = queue[i]
        d = dist[s]
        if d != d_prev:
            d_prev = d
            if d == 0:
                v = 0.0
            else:
                gd = g ** (d - 1)
                v = r_free * (1.0 - gd) / (1.0 - g) + gd * r_goal
        y[s] = v
    stamp[0] = r_goal
    stamp[1] = r_free


@njit(cache=True)
def ensure_values(y, stamp, r_goal_seen, r_free_seen, dist, queue, gamma):
    """Refresh the cache of y if it is stale: computed with other rewards than those now
    in force, or stamped -1 by a new BFS. Runs where the model can change (a real step,
    the start of an episode, a read-out), never in the reads themselves: a call with
    arrays inside a hot read cost it ~15x (measured: 37 ns against 2.3 ns a read).
    Takes the arrays of :class:`Optimism` and of the free space (``distance``, ``queue``)."""
    if stamp[1] != r_free_seen[0] or stamp[0] != goal_reward(r_goal_seen, r_free_seen, gamma):
        refresh_values(y, stamp, r_goal_seen, r_free_seen, dist, queue, gamma)


@njit(cache=True, inline="always")
def mark_stale(stamp):
    """The BFS distances changed: the next :func:`ensure_values` refreshes the cache
    (``stamp`` is :attr:`Optimism.stamp`)."""
    stamp[0] = -1.0  # never a goal reward in force (those are > 0)


@njit(cache=True, inline="always")
def observe_rewards(r_goal_seen, r_free_seen, r, terminated, clean):
    """Remember the reward of entering G and of a free move (the optimistic model's
    rewards, :attr:`Optimism.r_goal` and :attr:`Optimism.r_free`); True if either changed
    (the cache of y is then stale). ``clean``: the move arrived without a bump
    (:func:`learning.parts.move_reading.read_move`); an arrival paid the bump's reward is not a
    free move (with carried pose r_free would otherwise flip with every grazing arrival,
    and the potential with it)."""
    if terminated:
        if r > r_goal_seen[0]:
            r_goal_seen[0] = r
            return True
    elif clean and r_free_seen[0] != r:
        r_free_seen[0] = r
        return True
    return False


@njit(cache=True)
def revalue(y, stamp, dist, changed, gamma):
    """y(s) for the repaired states only (every one still has a route: a repair that cut
    one re-ran the BFS and returned ``[-1]``, and the caller marks the cache stale)."""
    if stamp[0] < 0.0:
        return
    r_goal = stamp[0]
    r_free = stamp[1]
    for i in range(changed.shape[0]):
        s = changed[i]
        d = dist[s]
        if d == 0:
            y[s] = 0.0
        else:
            gd = gamma ** (d - 1)
            y[s] = r_free * (1.0 - gd) / (1.0 - gamma) + gd * r_goal
