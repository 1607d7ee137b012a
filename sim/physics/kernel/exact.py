"""The kernel's legs at ``exact`` (:mod:`sim.physics.kernel.primitive`): a drive leg's swept-disc
guard, cached per (cell, action) for legs that start on their cell centre, and the one
physics step that stops at it; with the integration every fidelity's step shares.

At ``exact`` a primitive's outcome is a function of its cell and action, so one guard per
leg (cast with Chipmunk's segment-query formulas, :mod:`sim.physics.kernel.sweep`) replaces a
sweep per step. Split from the kernel so each file has one job.
"""

from __future__ import annotations

import math

from numba import njit

from sim.physics.kernel.queries import CHECK_MARGIN_M, sweep_step
from sim.physics.kernel.state import BORROWS

CENTRE_TOL_M = 1e-9  # a leg starting this close to its cell centre uses the cached guard [m]


@njit(cache=True, inline="always")
def integrate(rb, vx, vy, p):
    """Position integrates first, with the velocity the last solve left (or the guard's)."""
    rb.px, rb.py, rb.pth = rb.x, rb.y, rb.th
    rb.x = rb.px + vx * p.dt
    rb.y = rb.py + vy * p.dt
    rb.th = rb.pth + rb.w * p.dt
    rb.steps += 1


@njit(cache=True, inline="always")
def guard_leg(rb, p, guards):
    """At ``exact``, a drive leg's guard (how far the disc may go from the leg's start) when
    the cache holds it: for legs that start on their cell centre, per (cell, action). False:
    cast it (:func:`cast_guard`). Above ``exact`` every step has its own guard."""
    cx, cy = (rb.cell_x + 0.5) * p.cell_m, (rb.cell_y + 0.5) * p.cell_m
    if not (abs(rb.x - cx) <= CENTRE_TOL_M and abs(rb.y - cy) <= CENTRE_TOL_M):
        return False
    free = guards[rb.cell_y * p.nx + rb.cell_x, rb.action]
    if math.isnan(free):
        return False
    set_guard(rb, p, free)
    return True


@njit(**BORROWS)
def cast_guard(rb, p, g, s):
    """Cast the leg's guard: from the exact cell centre when on it (then cached), else from
    the pose."""
    cx, cy = (rb.cell_x + 0.5) * p.cell_m, (rb.cell_y + 0.5) * p.cell_m
    on_centre = abs(rb.x - cx) <= CENTRE_TOL_M and abs(rb.y - cy) <= CENTRE_TOL_M
    x0, y0 = (cx, cy) if on_centre else (rb.x, rb.y)
    alpha = sweep_step(p, g, s, x0, y0, rb.tx, rb.ty)
    free = math.inf if alpha == math.inf else alpha * math.hypot(rb.tx - x0, rb.ty - y0)
    s.counters[1] += 1
    if on_centre:
        s.guards[rb.cell_y * p.nx + rb.cell_x, rb.action] = free
    set_guard(rb, p, free)


@njit(cache=True, inline="always")
def set_guard(rb, p, free):
    rb.free = free
    rb.gx, rb.gy = rb.x, rb.y
    rb.limit = math.inf if free == math.inf else free + p.depth_m


@njit(cache=True)
def step_exact(rb, p):
    """One physics step at ``exact``: the leg's guard, integrate; True when Chipmunk must say
    whether a contact began (the step ended at the guard's surface)."""
    vx, vy = rb.vx, rb.vy
    if rb.limit < math.inf:
        done = (rb.x - rb.gx) * rb.ex + (rb.y - rb.gy) * rb.ey
        if done + p.dt * (vx * rb.ex + vy * rb.ey) > rb.limit:
            u = max(rb.limit - done, 0.0) / p.dt
            vx, vy = u * rb.ex, u * rb.ey
            rb.vx, rb.vy = vx, vy
    integrate(rb, vx, vy, p)
    if rb.limit < math.inf:
        return (rb.x - rb.gx) * rb.ex + (rb.y - rb.gy) * rb.ey > rb.free - CHECK_MARGIN_M
    return False
