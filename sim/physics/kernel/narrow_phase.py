"""Chipmunk's narrow phase for the robot's disc against the static shapes, in compiled code.

Where a step of the kernel (:mod:`sim.physics.kernel.primitive`) may have begun a contact, the
question used to go back to Python: put the robot's shape at its pose, ask Chipmunk's
``cpSpaceShapeQuery`` which static shapes it touches (and, for a robot resting against a
surface, which it touched before the step), book each new one as a
:class:`sim.physics.static.Contact`. That round trip (body sync, the query, the contact
point sets read back through cffi) was 15-20 us a check, and a policy that presses a wall
checks every primitive: most of a graded drive's time.

:func:`contacts_began` answers the same question with Chipmunk's own collision formulas
(chipmunk2d 7.0.3 ``cpCollision.c``: ``CircleToCircle``, ``CircleToSegment`` written out;
``CircleToPoly``'s GJK reduces, for a disc whose centre is outside an axis-aligned box, to
the box's closest point), over the candidates of the same grid index the sweeps use:

* a circle or a wall touches when ``distsq < mindist**2``, as Chipmunk computes both, so
  the decision is Chipmunk's to the bit;
* a box touches when the distance is ``<= r`` (Chipmunk's ``<=``); GJK's distance may
  differ from the closest point's by rounding, so a box within :data:`TOUCH_BAND_M` of
  touching, a disc centre inside a box or on a circle's centre, or more than
  :data:`CONTACTS_MAX` new contacts, hand the check back to Chipmunk (``-1``): decisions
  are never the compiled code's guess.

The booked contact's point, normal and depth are Chipmunk's formulas too (point on the
robot's surface, unit normal from the robot, depth = -(p_b - p_a) . n); tested against
Chipmunk's shape query on random poses and against the reference world's contacts.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from sim.physics.kernel.state import BORROWS

CONTACTS_MAX = 8  # contacts one check books in compiled code (more: Chipmunk decides)
TOUCH_BAND_M = 1e-12  # a box this close to touching: Chipmunk's GJK decides [m]
CONTACT_FIELDS = 7  # a booked contact: step, kind, x, y, normal x, normal y, depth
KIND_OBSTACLE, KIND_WALL, KIND_CELL = 2, 3, 4  # sim.physics.static.CollisionType values
_AMBIGUOUS, _CLEAR, _TOUCH = -1, 0, 1


def contact_buffer(n_robots: int) -> np.ndarray:
    """float64[n_robots, CONTACTS_MAX, CONTACT_FIELDS]: each robot's contacts of its last
    check, for the caller to book."""
    return np.zeros((n_robots, CONTACTS_MAX, CONTACT_FIELDS))


@njit(cache=True, inline="always")
def _round(x, y, r, qx, qy, qr, out, row):
    """The robot's disc against a round shape of radius ``qr`` about (qx, qy):
    ``CircleToCircle`` (a circle's centre) and the tail of ``CircleToSegment`` (the segment's
    closest point): touch, clear or ambiguous (coincident centres); on a touch with
    ``row >= 0`` the contact's point, normal and depth go to out[row]."""
    mindist = r + qr
    dx, dy = qx - x, qy - y
    distsq = dx * dx + dy * dy
    if not distsq < mindist * mindist:
        return _CLEAR
    dist = math.sqrt(distsq)
    if dist == 0.0:
        return _AMBIGUOUS
    if row >= 0:
        inv = 1.0 / dist
        nx, ny = dx * inv, dy * inv
        _write(out, row, x + nx * r, y + ny * r, qx + nx * -qr, qy + ny * -qr, nx, ny)
    return _TOUCH


@njit(cache=True, inline="always")
def _segment(x, y, r, ax, ay, bx, by, sr, out, row):
    """``CircleToSegment(robot, wall)`` (no tangents set: no endcap rejection)."""
    sdx, sdy = bx - ax, by - ay
    t = (sdx * (x - ax) + sdy * (y - ay)) / (sdx * sdx + sdy * sdy)
    t = min(max(t, 0.0), 1.0)
    return _round(x, y, r, ax + sdx * t, ay + sdy * t, sr, out, row)


@njit(cache=True, inline="always")
def _box(x, y, r, x0, y0, x1, y1, out, row):
    """``CircleToPoly(robot, box)`` for a centre outside the box: the closest point; a
    distance within TOUCH_BAND_M of r, or a centre inside, is Chipmunk's to decide."""
    qx, qy = min(max(x, x0), x1), min(max(y, y0), y1)
    dx, dy = qx - x, qy - y
    dist = math.sqrt(dx * dx + dy * dy)
    if dist == 0.0 or abs(dist - r) <= TOUCH_BAND_M:
        return _AMBIGUOUS
    if dist > r:
        return _CLEAR
    if row >= 0:
        nx, ny = dx / dist, dy / dist
        _write(out, row, x + nx * r, y + ny * r, qx, qy, nx, ny)
    return _TOUCH


@njit(cache=True, inline="always")
def _write(out, row, pax, pay, pbx, pby, nx, ny):
    out[row, 2], out[row, 3] = pax, pay
    out[row, 4], out[row, 5] = nx, ny
    out[row, 6] = -((pbx - pax) * nx + (pby - pay) * ny)


@njit(cache=True, inline="always")
def _touches(g, k, x, y, r, out, row):
    """Grid item ``k`` (circles, then boxes) against the disc at (x, y)."""
    n_circles = g.circles.shape[0]
    if k < n_circles:
        c = g.circles[k]
        return _round(x, y, r, c[0], c[1], c[2], out, row)
    b = g.boxes[k - n_circles]
    return _box(x, y, r, b[0], b[1], b[2], b[3], out, row)


@njit(**BORROWS)
def contacts_began(rb, p, g, s, out):
    """The contacts robot ``rb``'s last step began, as ``RouteBatch``'s Chipmunk check books
    them: every static shape the disc touches now that it did not touch before the step when
    it rested against one (unless the step pressed the bumper home: then all it touches).
    Rows of ``out`` (:func:`contact_buffer`) get step, kind, point, normal, depth; returns
    how many, or -1 when Chipmunk must decide (see the module doc)."""
    x, y, r = rb.x, rb.y, p.radius_m
    only_new = rb.resting and not rb.forced
    n = 0
    for k in range(g.walls.shape[0]):
        w = g.walls[k]
        row = n if n < CONTACTS_MAX else -1
        hit = _segment(x, y, r, w[0], w[1], w[2], w[3], w[4], out, row)
        if hit == _CLEAR:
            continue
        if hit == _AMBIGUOUS or row < 0:
            return -1
        if only_new:
            before = _segment(rb.px, rb.py, r, w[0], w[1], w[2], w[3], w[4], out, -1)
            if before == _AMBIGUOUS:
                return -1
            if before == _TOUCH:
                continue
        out[n, 1] = KIND_WALL
        n += 1
    s.counters[0] += 1
    stamp = s.counters[0]
    gx0 = min(max(int(math.floor((x - r) / p.cell_m)), 0), p.nx - 1)  # noqa: RUF046 (numba)
    gy0 = min(max(int(math.floor((y - r) / p.cell_m)), 0), p.ny - 1)  # noqa: RUF046 (numba)
    gx1 = min(max(int(math.floor((x + r) / p.cell_m)), 0), p.nx - 1)  # noqa: RUF046 (numba)
    gy1 = min(max(int(math.floor((y + r) / p.cell_m)), 0), p.ny - 1)  # noqa: RUF046 (numba)
    for gy in range(gy0, gy1 + 1):
        for gx in range(gx0, gx1 + 1):
            cell = gy * p.nx + gx
            for q in range(g.grid_start[cell], g.grid_start[cell + 1]):
                k = g.grid_items[q]
                if s.seen[k] == stamp:
                    continue
                s.seen[k] = stamp
                row = n if n < CONTACTS_MAX else -1
                hit = _touches(g, k, x, y, r, out, row)
                if hit == _CLEAR:
                    continue
                if hit == _AMBIGUOUS or row < 0:
                    return -1
                if only_new:
                    before = _touches(g, k, rb.px, rb.py, r, out, -1)
                    if before == _AMBIGUOUS:
                        return -1
                    if before == _TOUCH:
                        continue
                out[n, 1] = KIND_OBSTACLE if k < g.circles.shape[0] else KIND_CELL
                n += 1
    for j in range(n):
        out[j, 0] = rb.steps
    return n
