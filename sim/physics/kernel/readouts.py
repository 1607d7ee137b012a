"""What a batched step reports, read off every robot's record in one compiled pass
(:class:`sim.physics.kernel.batch.RouteBatch`): the primitive's outcome and its path length. A
Python expression per field over the robots was a measurable part of each step.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def outcome(robots, active):
    """The fields of :class:`PrimitiveOutcome` (zero / False for robots not ``active``): one
    compiled pass instead of seven array expressions a step."""
    n = robots.shape[0]
    state, cell = np.zeros(n, np.int64), np.zeros(n, np.int64)
    steps, contacts = np.zeros(n, np.int64), np.zeros(n, np.int64)
    bumped, reached = np.zeros(n, np.bool_), np.zeros(n, np.bool_)
    timeout = np.zeros(n, np.bool_)
    for i in range(n):
        if active[i]:
            rb = robots[i]
            state[i], bumped[i], reached[i], timeout[i] = rb.state, rb.bumped, rb.reached, \
                rb.timeout
            steps[i], contacts[i], cell[i] = rb.steps - rb.steps0, rb.ncontact, rb.tstate
    return state, bumped, reached, timeout, steps, contacts, cell


@njit(cache=True)
def path_lengths(start, traj, ntraj, out):
    """out[i] = the length of robot i's polyline start[i], traj[i, :ntraj[i]] [m]."""
    for i in range(out.shape[0]):
        x, y, total = start[i, 0], start[i, 1], 0.0
        for k in range(ntraj[i]):
            total += math.hypot(traj[i, k, 0] - x, traj[i, k, 1] - y)
            x, y = traj[i, k, 0], traj[i, k, 1]
        out[i] = total
