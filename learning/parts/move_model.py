"""A learned model of moves that may fail: what Dyna-Q and RNH-QL+ plan with.

On the grid, and in the physics world at the ``exact`` fidelity, a move from a
cell either always works or always fails, and a model that stores the last
outcome of each (s, a) is the world. With wheel noise and carried pose a move
beside an obstacle can fail once and work most of the time. A last-outcome
model then flips between "wall" and "free" with every failure: Dyna-Q replays
the failure until the move works again, and RNH-QL+'s optimistic model re-runs
its BFS, its potential moving under the Q-table each time (measured on
``paper-50`` at ``noisy``: greedy tests that flip between the optimal route and
"no G" to the last episode, 2 of 10 seeds ending with no route).

This model keeps, per (s, a), two outcomes and how often each was seen:

* the move working (the caller says what that is: RNH-QL+ asks that it reach
  the neighbour it heads for, Dyna-Q that it move at all), to the successor
  it was last seen to work to (or G), with its reward; a move that has worked
  once keeps that successor through later failures, so "known to fail" means
  "never seen to work" (a wall stays a wall, and a free move that fails now
  and then stays free);
* failing, replayed as staying put with the reward of the last failure (a
  failure that drifted into another cell is replayed as staying: an
  approximation, rare at the ``noisy`` preset). Until the move first works,
  the stored outcome is its last failure itself.

Planning draws an outcome with the frequencies seen (a sample model: the
replayed updates average to the expected backup, as Dyna's do in a stochastic
world). When only one outcome was ever seen, which is every pair of a
deterministic world, no number is drawn and the model is exactly the
last-outcome model: runs at ``exact`` are bit-for-bit those of before.

The model's arrays are named in :class:`MoveModel`; it also lists the pairs seen,
which planning draws from uniformly (Sutton & Barto 8.2).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

INLINE = dict(cache=True, inline="always")
COUNT_CAP = 1 << 30  # a pair's two counts are halved when their sum reaches this (int32)


class MoveModel(NamedTuple):
    successor: np.ndarray  # int32[nS, nA]; where the move was last seen to work to (-1: unseen)
    to_goal: np.ndarray  # bool[nS, nA]; that successor is G's entry (the episode ended)
    reward: np.ndarray  # float64[nS, nA]; the reward of that outcome
    works: np.ndarray  # int32[nS, nA]; times the move was seen to work
    fails: np.ndarray  # int32[nS, nA]; times it was seen to fail
    seen: np.ndarray  # int32[nS * nA]; flat pairs s * nA + a in the order first seen
    n_seen: np.ndarray  # int64[1]; how many of ``seen`` are in use
    r_fail: np.ndarray  # float64[1]; the reward of the last failure (its replayed reward)


def new_move_model(n_s: int, n_a: int) -> MoveModel:
    return MoveModel(np.full((n_s, n_a), -1, dtype=np.int32), np.zeros((n_s, n_a), np.bool_),
                     np.zeros((n_s, n_a)), np.zeros((n_s, n_a), np.int32),
                     np.zeros((n_s, n_a), np.int32), np.zeros(n_s * n_a, np.int32),
                     np.zeros(1, np.int64), np.zeros(1))


@njit(**INLINE)
def note_pair(successor, seen, n_seen, s, a):
    """Add (s, a) to the pairs planning draws from, if it is new; True if it was.

    The helpers here take the model's arrays, not the model: a hook reads them from its
    state once, at its top (see :mod:`learning.methods.rnh_ql_plus.rules` for why)."""
    if successor[s, a] >= 0:
        return False
    seen[n_seen[0]] = s * successor.shape[1] + a
    n_seen[0] += 1
    return True


@njit(**INLINE)
def observe_outcome(successor, to_goal, reward, works, fails, r_fail, s, a, r, s2, terminated,
                    worked):
    """Record the real step s -a-> s2 (reward r) in the model. ``worked``: the move did
    what it is for (RNH-QL+: reached the neighbour it heads for; Dyna-Q: moved at all)."""
    if works[s, a] + fails[s, a] >= COUNT_CAP:  # int32: halve, keeping the rate and any 0
        works[s, a] = (works[s, a] + 1) // 2
        fails[s, a] = (fails[s, a] + 1) // 2
    if worked:
        works[s, a] += 1
    else:
        fails[s, a] += 1
        r_fail[0] = r
        if works[s, a] > 0:
            return  # seen to work before: the successor stays; this was a failure among works
    successor[s, a] = s2
    to_goal[s, a] = terminated
    reward[s, a] = r


@njit(**INLINE)
def never_worked(successor, works, s, a):
    """Tried, and never seen to work (the optimistic model's wall)."""
    return successor[s, a] >= 0 and works[s, a] == 0


@njit(**INLINE)
def pair_of(j, n_a):
    """(s, a) of the flat pair j = s * n_a + a."""
    if n_a == 4:  # the grid's four moves: shifts, not two integer divisions
        return j >> 2, j & 3
    return j // n_a, j % n_a


@njit(**INLINE)
def replay_draws_failure(n_ok, n_fail, rng):
    """Whether a planned replay of a seen pair (its counts of works and failures) draws the
    failure outcome (stay put, ``r_fail``) instead of the stored one. Only a pair seen both
    to work and to fail draws (one ``rng.random()``), with the frequency failures were seen;
    a pair that never worked replays its stored failure, one that never failed its
    success."""
    if n_ok == 0 or n_fail == 0:
        return False
    return rng.random() * (n_ok + n_fail) < n_fail
