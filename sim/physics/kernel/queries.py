"""What the physics kernel (:mod:`sim.physics.kernel.primitive`) asks of the static geometry and of
the robot's own sensors, one robot at a time: the swept-disc fraction of a step, the
disc's overlap depth, whether a step comes within ``CHECK_MARGIN_M`` of a shape it was
clear of (for the steps whose sweep cannot tell), the clear ball and box inside which
steps need neither (above ``exact``), and dead reckoning (``localisation``).

Kept apart from the kernel's stepping so each file has one job: the kernel decides what
a robot does in a step; these answer where the shapes are.
"""

from __future__ import annotations

import math

from numba import njit

from sim.physics.kernel.state import BORROWS
from sim.physics.kernel.sweep import (
    _box_distance,
    _fold_shapes,
    _segment_distance,
    _wall_beyond,
    overlap_depth,
    sweep_fraction,
)
from sim.physics.motion import cell_of

CHECK_MARGIN_M = 1e-6  # steps ending this close to a surface ask Chipmunk [m]
CLEAR_MARGIN_M = 1e-3  # a step this far from every surface needs no sweep (new_clear_region) [m]


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
def in_clear_region(rb, x1, y1):
    """Whether the step from the pose to (x1, y1) lies in the robot's clear ball or its
    clear box (:func:`new_clear_region`)."""
    # squared distances (no hypot): the ball keeps CLEAR_MARGIN_M from every shape, so a
    # rounding-level difference at its rim only decides whether a sweep that finds nothing
    # is run
    r2 = rb.clear_r * rb.clear_r
    dx0, dy0, dx1, dy1 = rb.x - rb.clear_x, rb.y - rb.clear_y, x1 - rb.clear_x, y1 - rb.clear_y
    if rb.clear_r > 0.0 and dx0 * dx0 + dy0 * dy0 < r2 and dx1 * dx1 + dy1 * dy1 < r2:
        return True
    return (rb.box_x0 < rb.x < rb.box_x1 and rb.box_x0 < x1 < rb.box_x1
            and rb.box_y0 < rb.y < rb.box_y1 and rb.box_y0 < y1 < rb.box_y1)


@njit(**BORROWS)
def new_clear_region(rb, p, g, s):
    """The robot's clear ball and clear box from its pose: every centre in either leaves the
    disc at least CLEAR_MARGIN_M from every static shape. A step whose start and end lie in
    one of them sweeps a segment in it (both are convex): the sweep finds no surface
    (alpha = inf) and no touch check can fire (they look within 1e-6 m), so skipping both
    changes nothing; above ``exact`` most steps run in free space, and one query per
    region replaces a sweep per step.

    The ball: centres within the pose's clearance (up to one cell) less the margin. The
    box: the square of centres within a cell of the pose, cut by each shape's bounding box
    until every shape is at least ``R`` = radius + margin from it along x or along y (then
    it is at least that far in the plane: a bound, never an overlap), each cut on the side
    that keeps the pose and the larger part. In a corridor the ball's radius is the
    clearance to its walls, a few steps of travel; the box runs along the corridor.
    """
    s.counters[0] += 1
    x, y, r = rb.x, rb.y, p.radius_m
    big = r + CLEAR_MARGIN_M
    look = p.cell_m + big  # shapes that can come within `big` of the box's square (the
    #                        ball's reach, r + cell, is shorter)
    # the fold's state: nearest surface (from r + cell: beyond it is beyond), the box, and
    # `big` carried along for the cuts
    out = (r + p.cell_m, x - p.cell_m, y - p.cell_m, x + p.cell_m, y + p.cell_m, big)
    nearest, x0, y0, x1, y1, _ = _fold_shapes(_region_wall, _region_item, out, g.circles,
                                              g.walls, g.boxes, p.cell_m, p.nx, p.ny,
                                              g.grid_start, g.grid_items, s.seen,
                                              s.counters[0], look, x, y, x, y)
    rb.clear_x, rb.clear_y = x, y
    rb.clear_r = nearest - r - CLEAR_MARGIN_M
    rb.box_x0, rb.box_y0, rb.box_x1, rb.box_y1 = x0, y0, x1, y1


@njit(cache=True, inline="always")
def _region_wall(walls, k, _radius, x, y, _bx, _by, out):
    """:func:`new_clear_region`'s fold over wall ``k``: its distance, its bounding box's cut."""
    w = walls
    nearest, x0, y0, x1, y1, big = out
    d = _segment_distance(x, y, w[k, 0], w[k, 1], w[k, 2], w[k, 3]) - w[k, 4]
    x0, y0, x1, y1 = _cut((x0, y0, x1, y1), min(w[k, 0], w[k, 2]) - w[k, 4],
                          min(w[k, 1], w[k, 3]) - w[k, 4], max(w[k, 0], w[k, 2]) + w[k, 4],
                          max(w[k, 1], w[k, 3]) + w[k, 4], x, y, big)
    return min(nearest, d), x0, y0, x1, y1, big


@njit(cache=True, inline="always")
def _region_item(circles, boxes, k, _radius, x, y, _bx, _by, out):
    """... over grid item ``k`` (a circle, or a box after the circles)."""
    nearest, x0, y0, x1, y1, big = out
    n_circles = circles.shape[0]
    if k < n_circles:
        c = circles[k]
        d = math.hypot(x - c[0], y - c[1]) - c[2]
        x0, y0, x1, y1 = _cut((x0, y0, x1, y1), c[0] - c[2], c[1] - c[2], c[0] + c[2],
                              c[1] + c[2], x, y, big)
    else:
        e = boxes[k - n_circles]
        d = _box_distance(x, y, e[0], e[1], e[2], e[3])
        x0, y0, x1, y1 = _cut((x0, y0, x1, y1), e[0], e[1], e[2], e[3], x, y, big)
    return min(nearest, d), x0, y0, x1, y1, big


@njit(cache=True, inline="always")
def _cut(b, sx0, sy0, sx1, sy1, x, y, big):
    """Box ``b`` (x0, y0, x1, y1) cut so that the shape inside the bounding box ``s`` is at
    least ``big`` from it along x or y, keeping (x, y) inside; empty when it cannot."""
    x0, y0, x1, y1 = b
    if x1 <= x0:
        return b
    if max(sx0 - x1, x0 - sx1) >= big or max(sy0 - y1, y0 - sy1) >= big:
        return b  # far enough already
    best, out = -1.0, (x, y, x, y)  # no cut keeps the pose: empty
    if sx0 - big > x:  # the shape lies to the right of the pose: cut x1
        area = (sx0 - big - x0) * (y1 - y0)
        if area > best:
            best, out = area, (x0, y0, sx0 - big, y1)
    if sx1 + big < x:  # ... to the left
        area = (x1 - sx1 - big) * (y1 - y0)
        if area > best:
            best, out = area, (sx1 + big, y0, x1, y1)
    if sy0 - big > y:  # ... above
        area = (x1 - x0) * (sy0 - big - y0)
        if area > best:
            best, out = area, (x0, y0, x1, sy0 - big)
    if sy1 + big < y:  # ... below
        area = (x1 - x0) * (y1 - sy1 - big)
        if area > best:
            best, out = area, (x0, sy1 + big, x1, y1)
    return out


@njit(cache=True, inline="always")
def new_touch(p, g, s, x0, y0, x1, y1, boxes_only):
    """Whether the disc at (x1, y1) comes within CHECK_MARGIN_M of a shape (or a box) it did
    not overlap at (x0, y0) (point-query distances), for steps whose sweep cannot tell."""
    r, m = p.radius_m, CHECK_MARGIN_M
    for k in range(0 if boxes_only else g.walls.shape[0]):
        if _wall_beyond(g.walls, k, x1 - r - m, y1 - r - m, x1 + r + m, y1 + r + m):
            continue  # (the test below asks for a touch at (x1, y1))
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
