"""What the physics kernel (:mod:`sim.physics.kernel.primitive`) asks of the static geometry and of
the robot's own sensors, one robot at a time: the swept-disc fraction of a step, the
disc's overlap depth, whether a step comes within ``CHECK_MARGIN_M`` of a shape it was
clear of (for the steps whose sweep cannot tell), the clear ball inside which steps need
neither (above ``exact``), and dead reckoning (``localisation``).

Kept apart from the kernel's stepping so each file has one job: the kernel decides what
a robot does in a step; these answer where the shapes are.
"""

from __future__ import annotations

import math

from numba import njit

from sim.physics.kernel.sweep import (
    _box_distance,
    _fold_shapes,
    _segment_distance,
    overlap_depth,
    sweep_fraction,
)
from sim.physics.reference.controller import cell_of

CHECK_MARGIN_M = 1e-6  # steps ending this close to a surface ask Chipmunk [m]
CLEAR_MARGIN_M = 1e-3  # a step this far from every surface needs no sweep (new_clear_ball) [m]


@njit(cache=True)
def odometry(rb, p):
    """Dead reckoning over the control period that just ended (:mod:`sim.physics.fidelity`,
    ``localisation``). The body's travel ``odo_d`` [m] and yaw ``odo_th`` [rad] as its wheels
    drove them (a slide along a surface that holds the disc turns no wheel; wheels that
    push against it do turn), as each wheel's encoder reads it through the nominal
    geometry (the per-run bias shows as UMBmark's systematic drift), split into
    rotate-translate-rotate with the odometry motion model's noise (the period's normals
    o1..o3), composed onto the estimate."""
    half = 0.5 * rb.odo_th * p.wheel_base_m * rb.base_k  # half the wheels' travel difference
    d_l, d_r = (rb.odo_d - half) / rb.gain_l, (rb.odo_d + half) / rb.gain_r  # the encoders
    trans = 0.5 * (d_l + d_r)
    rot = 0.5 * (d_r - d_l) / p.wheel_base_m  # half the rotation: before and after
    s_rot = math.sqrt(p.odometry_rot_rot * rot * rot + p.odometry_rot_trans * trans * trans)
    s_trans = math.sqrt(p.odometry_trans_trans * trans * trans
                        + p.odometry_trans_rot * 2.0 * rot * rot)
    r1 = rot + s_rot * rb.o1
    t = trans + s_trans * rb.o2
    r2 = rot + s_rot * rb.o3
    rb.bx += t * math.cos(rb.bth + r1)
    rb.by += t * math.sin(rb.bth + r1)
    rb.bth += r1 + r2
    rb.odo_d = rb.odo_th = 0.0


@njit(cache=True, inline="always")
def in_clear_ball(rb, x1, y1):
    """Whether the step from the pose to (x1, y1) lies in the robot's clear ball."""
    # squared distances (no hypot): the ball keeps CLEAR_MARGIN_M from every shape, so a
    # rounding-level difference at its rim only decides whether a sweep that finds nothing
    # is run
    r2 = rb.clear_r * rb.clear_r
    dx0, dy0, dx1, dy1 = rb.x - rb.clear_x, rb.y - rb.clear_y, x1 - rb.clear_x, y1 - rb.clear_y
    return rb.clear_r > 0.0 and dx0 * dx0 + dy0 * dy0 < r2 and dx1 * dx1 + dy1 * dy1 < r2


@njit(cache=True)
def new_clear_ball(rb, p, g, s):
    """The robot's clear ball from its pose: every centre within ``clear_r`` of it leaves the
    disc at least CLEAR_MARGIN_M from every static shape (its clearance there, up to one
    cell, less the margin). A step whose start and end lie in it sweeps a segment in it
    (a ball is convex): the sweep finds no surface (alpha = inf) and no touch check can
    fire (they look within 1e-6 m), so skipping both changes nothing; above ``exact``
    most steps run in free space, and one point query per ball replaces a sweep per step.
    """
    s.counters[0] += 1
    reach = p.radius_m + p.cell_m  # the query looks this far: shapes beyond it are beyond
    c = _fold_shapes(_clear_wall, _clear_item, reach, g.circles, g.walls, g.boxes, p.cell_m,
                     p.nx, p.ny, g.grid_start, g.grid_items, s.seen, s.counters[0],
                     reach, rb.x, rb.y, rb.x, rb.y)
    rb.clear_x, rb.clear_y = rb.x, rb.y
    rb.clear_r = c - p.radius_m - CLEAR_MARGIN_M


@njit(cache=True, inline="always")
def _clear_wall(walls, k, _radius, x, y, _bx, _by, nearest):
    """The nearest surface [m] from the centre (x, y), folding in wall ``k``."""
    d = _segment_distance(x, y, walls[k, 0], walls[k, 1], walls[k, 2], walls[k, 3]) - walls[k, 4]
    return d if d < nearest else nearest


@njit(cache=True, inline="always")
def _clear_item(circles, boxes, k, _radius, x, y, _bx, _by, nearest):
    n_circles = circles.shape[0]
    if k < n_circles:
        d = math.hypot(x - circles[k, 0], y - circles[k, 1]) - circles[k, 2]
    else:
        m = k - n_circles
        d = _box_distance(x, y, boxes[m, 0], boxes[m, 1], boxes[m, 2], boxes[m, 3])
    return d if d < nearest else nearest


@njit(cache=True, inline="always")
def new_touch(p, g, s, x0, y0, x1, y1, boxes_only):
    """Whether the disc at (x1, y1) comes within CHECK_MARGIN_M of a shape (or a box) it did
    not overlap at (x0, y0) (point-query distances), for steps whose sweep cannot tell."""
    r, m = p.radius_m, CHECK_MARGIN_M
    for k in range(0 if boxes_only else g.walls.shape[0]):
        w = g.walls[k]
        if (_segment_distance(x1, y1, w[0], w[1], w[2], w[3]) - w[4] - r < m
                and _segment_distance(x0, y0, w[0], w[1], w[2], w[3]) - w[4] - r > -m):
            return True
    s.counters[0] += 1
    ix0, iy0 = cell_of(x1 - r - m, y1 - r - m, p.cell_m, p.nx, p.ny)
    ix1, iy1 = cell_of(x1 + r + m, y1 + r + m, p.cell_m, p.nx, p.ny)
    for gy in range(iy0, iy1 + 1):
        for gx in range(ix0, ix1 + 1):
            cell = gy * p.nx + gx
            for q in range(g.grid_start[cell], g.grid_start[cell + 1]):
                k = g.grid_items[q]
                if s.seen[k] != s.counters[0] and (k >= g.circles.shape[0] or not boxes_only):
                    s.seen[k] = s.counters[0]
                    if clearance(p, g, k, x1, y1) < m and clearance(p, g, k, x0, y0) > -m:
                        return True
    return False


@njit(cache=True, inline="always")
def clearance(p, g, k, x, y):
    """Clearance [m] of the disc at (x, y) from grid item ``k`` (circles, then boxes)."""
    if k < g.circles.shape[0]:
        c = g.circles[k]
        return math.hypot(x - c[0], y - c[1]) - c[2] - p.radius_m
    b = g.boxes[k - g.circles.shape[0]]
    return _box_distance(x, y, b[0], b[1], b[2], b[3]) - p.radius_m


@njit(cache=True, inline="always")
def sweep_step(p, g, s, ax, ay, bx, by):
    s.counters[0] += 1
    return sweep_fraction(g.circles, g.walls, g.boxes, p.cell_m, p.nx, p.ny, g.grid_start,
                          g.grid_items, s.seen, s.counters[0], p.radius_m, ax, ay, bx, by)


@njit(cache=True, inline="always")
def depth_at(p, g, s, x, y):
    s.counters[0] += 1
    return overlap_depth(g.circles, g.walls, g.boxes, p.cell_m, p.nx, p.ny, g.grid_start,
                         g.grid_items, s.seen, s.counters[0], p.radius_m, x, y)


@njit(cache=True, inline="always")
def within(p, g, s, x, y, margin):
    """Whether the disc at (x, y) is closer than ``margin`` [m] to any static shape (the
    bumper's release band): the overlap of a disc ``margin`` larger."""
    s.counters[0] += 1
    return overlap_depth(g.circles, g.walls, g.boxes, p.cell_m, p.nx, p.ny, g.grid_start,
                         g.grid_items, s.seen, s.counters[0], p.radius_m + margin, x, y) > 0.0
