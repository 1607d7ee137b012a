"""Greedy drives of table policies, many primitives per compiled call.

A graded drive (:mod:`sim.physics.models.rollouts`) was a Python round trip per primitive:
the actions looked up, the world's step (its kernel call, outcome pass, the env's rules
and info), the tallies in numpy. Above ``exact`` the periodic greedy tests of a physics
run are such drives (ten per test), and they cost as much as the training between them.
Here each robot drives its policy (``tables[owner[k]]``, an action per state) from where
it was placed until it reaches G or spends its ``limit`` of primitives, robot by robot,
with the kernel's own functions (:func:`sim.physics.kernel.primitive.begin_one`,
:func:`~sim.physics.kernel.primitive.advance_one`). Its normals are refilled in compiled code
(:mod:`sim.physics.kernel.noise`); a robot hands back to Python only to have a contact
settled by Chipmunk, as the batched step does, so every drive is the drive the env would
give (tested against it).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from sim.physics import sigint
from sim.physics.drive_profiles import Profiles
from sim.physics.kernel.noise import refill_one
from sim.physics.kernel.primitive import advance_one, begin_one
from sim.physics.kernel.state import Geometry, Params, Scratch, Status


@njit(cache=True)
def drive_tables(robots, noise, npos, nend, nblock, noise_h, traj, contacts, booked, pt,
                 prof_t, geo_t, st, tables, owner, state, running, rules, tallies, routes,
                 metres, start_xy, shown, path, npath, poses, best, misses, override):
    """Drive every ``running`` robot until G, its limit, or the caller is needed.

    ``rules``: int64[4] = goal state, primitives per drive at most, ``n`` > 0 when only
    each policy's median and its rollout 0 are wanted (:func:`_median_decided`; robots
    ``j*n .. j*n + n - 1`` are policy ``j``'s rollouts, ``best`` int64[m, n // 2 + 1] and
    ``misses`` int64[m] its bookkeeping, ``best`` filled with ``limit + 1``), and the
    primitives this call drives at most (0: no bound): a call that returns for that leaves
    its robot between two primitives, and the next call goes on from there. ``override``
    int64[limit, N] or ``[0, 0]``: robot k's primitive j takes ``override[j, k]`` where
    that is >= 0 instead of its policy's action (an epsilon-greedy drive). ``state[k]``:
    robot k's state (observed), updated per primitive; ``tallies`` int64[5, N]: primitives,
    contacts, bumps, reached (0/1), physics steps at the drive's end; ``routes[k, j]`` the
    state after primitive j (``routes[k, 0]`` is the caller's), when ``routes`` has columns;
    ``metres[k]`` the path length [m] when ``metres`` has robots (``traj`` must have room:
    each primitive's steps summed from its start pose, ``start_xy[k]``, as
    :func:`sim.physics.kernel.readouts.path_lengths` sums them). A robot ``k`` with
    ``shown[k] = j >= 0`` appends each primitive's trajectory to ``path[j, :npath[j]]``
    (its start pose, then the pose after every step, heading not wrapped: the env's
    ``trajectory``) and its pose after the primitive to ``poses[j, n]`` (heading wrapped as
    the env's ``info["pose"]``). Wheel noise is refilled here, from each robot's generator
    handle ``noise_h[k]`` (:mod:`sim.physics.kernel.noise`). Returns how many running
    robots wait for the caller (a ``CHECK`` for Chipmunk), plus one when the call's budget
    ran out.
    """
    p, prof, g, sc = Params(*pt), Profiles(*prof_t), Geometry(*geo_t), Scratch(*st)
    goal, limit, median_n, budget = rules[0], rules[1], rules[2], rules[3]
    waiting = driven = 0
    for k in range(robots.shape[0]):
        if not running[k]:
            continue
        rb = robots[k]
        while True:
            if rb.status == Status.DONE or rb.status == Status.IDLE:
                if budget and driven >= budget:  # the call's share is driven: back to
                    return waiting + 1  # Python (Ctrl-C); the next call goes on from here
                if median_n and k % median_n and _median_decided(
                        best[owner[k]], misses[owner[k]], median_n, tallies[0, k]):
                    tallies[4, k] = rb.steps  # cut: counted as a miss, as it cannot matter
                    running[k] = False
                    break
                start_xy[k, 0], start_xy[k, 1], start_xy[k, 2] = rb.x, rb.y, rb.th
                a = tables[owner[k], state[k]]
                if override.shape[0] and override[tallies[0, k], k] >= 0:
                    a = override[tallies[0, k], k]
                begin_one(rb, a, p.cell_m, p.nx, p.ny, p.localisation)
            advance_one(k, robots, noise, npos, nend, traj, contacts, booked, p, prof, g, sc)
            if rb.status == Status.NOISE:
                refill_one(k, noise, npos, nend, nblock, noise_h)
                continue
            if rb.status != Status.DONE:
                waiting += 1
                break
            booked[k] = 0
            driven += 1
            n = tallies[0, k] + 1
            tallies[0, k] = n
            tallies[1, k] += rb.ncontact
            tallies[2, k] += rb.bumped
            state[k] = rb.state
            if metres.shape[0]:
                x, y, total = start_xy[k, 0], start_xy[k, 1], 0.0
                for j in range(rb.ntraj):
                    total += math.hypot(traj[k, j, 0] - x, traj[k, j, 1] - y)
                    x, y = traj[k, j, 0], traj[k, j, 1]
                metres[k] += total
            if routes.shape[1]:
                routes[k, n] = rb.state
            j = shown[k]
            if j >= 0:
                m = npath[j]
                path[j, m, 0], path[j, m, 1], path[j, m, 2] = (start_xy[k, 0], start_xy[k, 1],
                                                               start_xy[k, 2])
                for r in range(rb.ntraj):
                    path[j, m + 1 + r, 0], path[j, m + 1 + r, 1] = traj[k, r, 0], traj[k, r, 1]
                    path[j, m + 1 + r, 2] = traj[k, r, 2]
                npath[j] = m + 1 + rb.ntraj
                poses[j, n, 0], poses[j, n, 1] = rb.x, rb.y
                poses[j, n, 2] = (rb.th + math.pi) % (2.0 * math.pi) - math.pi
            if rb.tstate == goal or n >= limit:
                tallies[3, k] = rb.tstate == goal
                tallies[4, k] = rb.steps
                running[k] = False
                if median_n:
                    _book_drive(best[owner[k]], misses, owner[k], n, rb.tstate == goal)
                break
    return waiting


@njit(cache=True, inline="always")
def _median_decided(best, missed, n, driven):
    """Whether a policy's median primitives to G (``n`` rollouts, a miss counting as
    infinite, numpy's median: the mean of sorted values ``(n - 1) // 2`` and ``n // 2``)
    is settled whatever a drive that has ``driven`` primitives so far does next: half of
    the rollouts (``n - n // 2``) already missed (the median is a miss), or ``n // 2 + 1``
    already reached G in at most ``driven`` primitives (this drive, longer or a miss, sorts
    after them). A periodic test reads only its median and rollout 0: its other drives
    stop here (10 drives of a policy that cannot reach G cost 5)."""
    return missed >= n - n // 2 or best[n // 2] <= driven


@njit(cache=True, inline="always")
def _book_drive(best, misses, j, length, reached):
    """A drive of policy ``j`` ended: a miss, or its length among the ``best.size``
    shortest (kept sorted)."""
    if not reached:
        misses[j] += 1
        return
    m = best.shape[0]
    if length >= best[m - 1]:
        return
    q = m - 1
    while q > 0 and best[q - 1] > length:
        best[q] = best[q - 1]
        q -= 1
    best[q] = length


_NO_OVERRIDE = np.zeros((0, 0), np.int64)
CALL_PRIMITIVES = 16384  # primitives a call drives at most: ~0.1 s, the bound on Ctrl-C


def drive_batch(batch, tables: np.ndarray, owner: np.ndarray, state: np.ndarray, goal: int,
                limit: int, keep_routes: bool, measure_metres: bool, shown: list[int],
                median_of: int = 0, override: np.ndarray | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray],
                           list[np.ndarray]]:
    """Every robot of ``batch`` (placed, each with a noise stream of its own that nothing
    else reads) drives ``tables[owner[k]]`` from ``state[k]``: (tallies int64[5, N] as
    :func:`drive_tables` fills them, routes int64[N, limit + 1] or ``[N, 0]``, metres
    float64[N] or ``[0]``, then per robot of ``shown`` its trajectories concatenated and
    its poses after each primitive). ``median_of`` = n > 0: robots ``j*n ..`` are policy
    ``j``'s n rollouts, and only each policy's median and rollout 0 are wanted: a drive
    that cannot change the median is cut, not reached (:func:`_median_decided`).
    ``override``: actions that replace the policy's (:func:`drive_tables`)."""
    running = np.ones(batch.n, np.bool_)
    n = batch.n
    tallies = np.zeros((5, n), np.int64)
    routes = np.zeros((n, limit + 1 if keep_routes else 0), np.int64)
    if keep_routes:
        routes[:, 0] = state
    metres = np.zeros(n if measure_metres else 0)
    rules = np.array([goal, limit, median_of, CALL_PRIMITIVES], np.int64)
    policies = int(owner.max()) + 1 if n else 0
    best = np.full((policies if median_of else 0, median_of // 2 + 1), limit + 1, np.int64)
    misses = np.zeros(policies, np.int64)
    args = (batch.robots, batch._noise, batch._npos, batch._nend, batch._nblock, batch._noise_h,
            batch._traj, batch._booked_rows, batch._booked, *batch._args)
    status, start_xy = batch.r.status, np.zeros((n, 3))
    row = np.full(n, -1, np.int64)
    row[shown] = np.arange(len(shown))
    per_primitive = batch._traj.shape[1] + 1 if shown else 0
    path = np.zeros((len(shown), limit * per_primitive, 3))
    npath = np.zeros(len(shown), np.int64)
    poses = np.zeros((len(shown), limit + 1, 3))
    while drive_tables(*args, tables, owner, state, running, rules, tallies, routes, metres,
                       start_xy, row, path, npath, poses, best, misses,
                       _NO_OVERRIDE if override is None else override):
        for k in np.flatnonzero(running & (status == int(Status.CHECK))):
            batch._check(int(k))
        sigint.raise_if_deferred()
    sigint.raise_if_deferred()
    return (tallies, routes, metres, [path[j, :npath[j]] for j in range(len(shown))],
            [poses[j, 1:tallies[0, k] + 1] for j, k in enumerate(shown)])
