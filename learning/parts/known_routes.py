"""Known routes: every cell's shortest route to G over the moves the agent has seen work.

An optimistic agent acts on the free-space assumption (a move it has not tried
is free), which is what makes it explore; but a greedy test that trusts the same
assumption walks into the first untried move that is a wall. On a 256 x 256 city
map (``Berlin_1_256``, a 516-move optimum) RNH-QL+'s greedy route flipped between
the optimum and "no G" for over a thousand episodes after first finding it: the
route's cells had untried moves valued by look-ahead, and its tried moves were
ranked by Q values still catching up with a potential that moved under them.

A route over moves *seen to work* has neither problem. The moves seen to work
only grow, so the known distance of a cell only falls, and once the optimal
route has been walked the known route from S is optimal and stays so. This is
what a model-based agent exploits (certainty equivalence over what it knows),
while it keeps acting optimistically. Cells with no known route fall back to
the method's own greedy choice.

A move "works" when it arrives in the neighbour it heads for without a bump
(:mod:`learning.parts.move_reading`), and it is on a known route while it has worked
more often than it failed: its most likely outcome is a clean arrival. On the
grid and at ``exact`` a move always works or always fails, so this is "seen to
work once". With wheel noise one unlucky bump does not take a move off the routes
for ever (the next clean arrivals put it back), and a move that bumps most times
is not trusted because it got through once. The claim above then holds for the
moves' most likely outcomes, which is all a noisy world offers.

The distances are one BFS back from G over those moves, re-run only when a move's
standing changes and a greedy choice is asked for: O(states) per test, nothing
per training step but a flag.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from learning.parts.free_space import bfs_distances


class KnownRoutes(NamedTuple):
    distance: np.ndarray  # int32[nS]; moves to G over moves seen to work (-1: none known)
    queue: np.ndarray  # int32[nS]; the BFS order (cells with a known route, G first)
    stale: np.ndarray  # bool[1]; a move's standing (:func:`reliable`) changed since the BFS


def new_known_routes(n_s: int) -> KnownRoutes:
    return KnownRoutes(np.full(n_s, -1, np.int32), np.zeros(n_s, np.int32),
                       np.ones(1, np.bool_))


@njit(cache=True, inline="always")
def reliable(works, fails, s, a):
    """The move has arrived cleanly more often than it failed (its counts in the move
    model, :mod:`learning.parts.move_model`)."""
    return works[s, a] > fails[s, a]


@njit(cache=True)
def known_distances(nb, works, fails, dist, queue, goal):
    """The free space's BFS from G (:func:`learning.parts.free_space.bfs_distances`) with every
    move that is not :func:`reliable` counted as blocked (a move that works reaches
    ``nb[u, a]``). Runs once per greedy test at most, so the mask it builds costs nothing
    on a step."""
    bfs_distances(nb, works <= fails, dist, queue, goal)


@njit(cache=True, inline="always")
def known_move(nb, works, fails, dist, s):
    """The first move (lowest index) from s along a shortest known route; -1 if s has none
    (the distances must be fresh: see :func:`known_distances`)."""
    d = dist[s]
    if d <= 0:
        return -1
    for a in range(nb.shape[1]):
        u = nb[s, a]
        if u >= 0 and reliable(works, fails, s, a) and dist[u] == d - 1:
            return a
    return -1
