"""The swept-disc guard in compiled code: Chipmunk's segment queries over the static shapes.

:func:`sim.physics.reference.world.sweep_alpha` asks Chipmunk (``bb_query``, then
``shape.segment_query`` with the disc's radius per candidate) how far a disc can move along
a segment before it touches a wall, a circle or a blocked cell's box: 30-50 us a call
from Python, and once per drive leg on a large map where few legs repeat. This module
holds the same static shapes as arrays, indexed by a uniform grid of arena cells, and
answers the same question in compiled code with Chipmunk's own formulas
(``CircleSegmentQuery``, ``SegmentSegmentQuery``, ``PolySegmentQuery`` of chipmunk2d
7.0.3, written out below): the same fraction to rounding (tested against Chipmunk on
thousands of random segments, within 1e-12), and shapes the disc already overlaps at the
start (Chipmunk reports those at alpha 0 or not at all) are skipped the same way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from sim.physics.kernel.state import BORROWS
from sim.physics.static import merged_boxes
from sim.scenario import Scenario


@dataclass(frozen=True)
class StaticGeometry:
    """The static shapes of :func:`sim.physics.static.static_shapes`, as arrays."""

    circles: np.ndarray  # float64[K, 3]: x, y, radius [m]
    walls: np.ndarray  # float64[4, 5]: ax, ay, bx, by, radius [m] (thick segments)
    boxes: np.ndarray  # float64[M, 4]: x0, y0, x1, y1 [m] (blocked-cell runs)
    cell_m: float  # index cell size [m]
    nx: int
    ny: int
    start: np.ndarray  # int64[nx*ny + 1]: CSR offsets of the index
    items: np.ndarray  # int64[...]: circle ids (0..K-1) and box ids (K..K+M-1) per cell


def static_geometry(sc: Scenario) -> StaticGeometry:
    """The scenario's walls, circles and blocked-cell runs, with a grid index of arena cells."""
    w, h, t = sc.width_m, sc.height_m, sc.cell_size_m
    walls = np.array([(-t, -t, w + t, -t, t), (w + t, -t, w + t, h + t, t),
                      (w + t, h + t, -t, h + t, t), (-t, h + t, -t, -t, t)], dtype=np.float64)
    circles = np.array([(o.x_m, o.y_m, o.radius_m) for o in sc.obstacles],
                       dtype=np.float64).reshape(-1, 3)
    c = sc.cell_size_m
    boxes = np.array([(ix0 * c, iy * c, (ix1 + 1) * c, (iy + 1) * c)
                      for iy, ix0, ix1 in merged_boxes(sc.blocked_cells)],
                     dtype=np.float64).reshape(-1, 4)
    nx, ny = sc.nx, sc.ny
    bbs = np.concatenate([
        np.stack([circles[:, 0] - circles[:, 2], circles[:, 1] - circles[:, 2],
                  circles[:, 0] + circles[:, 2], circles[:, 1] + circles[:, 2]], axis=1),
        boxes]) if len(circles) or len(boxes) else np.zeros((0, 4))
    lo = np.clip(np.floor(bbs[:, :2] / c).astype(np.int64), 0, [nx - 1, ny - 1])
    hi = np.clip(np.floor(bbs[:, 2:] / c).astype(np.int64), 0, [nx - 1, ny - 1])
    counts = np.zeros(nx * ny + 1, dtype=np.int64)
    cells_of: list[np.ndarray] = []
    for k in range(len(bbs)):
        gx, gy = np.meshgrid(np.arange(lo[k, 0], hi[k, 0] + 1), np.arange(lo[k, 1], hi[k, 1] + 1))
        cells = (gy * nx + gx).ravel()
        cells_of.append(cells)
        np.add.at(counts, cells + 1, 1)
    start = np.cumsum(counts)
    items = np.zeros(int(start[-1]), dtype=np.int64)
    fill = start[:-1].copy()
    for k, cells in enumerate(cells_of):
        items[fill[cells]] = k
        fill[cells] += 1
    return StaticGeometry(circles, walls, boxes, c, nx, ny, start, items)


@njit(cache=True, inline="always")
def _circle_alpha(cx, cy, r1, ax, ay, bx, by, r2):
    """CircleSegmentQuery: fraction of a->b at which a disc of r2 touches a circle (inf: none)."""
    dax, day = ax - cx, ay - cy
    dbx, dby = bx - cx, by - cy
    rsum = r1 + r2
    da_da = dax * dax + day * day
    da_db = dax * dbx + day * dby
    qa = da_da - 2.0 * da_db + (dbx * dbx + dby * dby)
    qb = da_db - da_da
    det = qb * qb - qa * (da_da - rsum * rsum)
    if qa <= 0.0:  # a segment too short to resolve against its distance (C gets nan: no hit)
        return math.inf
    if det >= 0.0:
        t = (-qb - math.sqrt(det)) / qa
        if 0.0 <= t <= 1.0:
            return t
    return math.inf


@njit(cache=True, inline="always")
def _segment_alpha(sax, say, sbx, sby, sr, ax, ay, bx, by, r2):
    """SegmentSegmentQuery against a thick segment (Chipmunk's normal: rperp of a->b)."""
    dx, dy = sbx - sax, sby - say
    ln = math.sqrt(dx * dx + dy * dy)
    nx, ny = dy / ln, -dx / ln
    d = (sax - ax) * nx + (say - ay) * ny
    r = sr + r2
    fnx, fny = (-nx, -ny) if d > 0.0 else (nx, ny)
    offx, offy = fnx * r - ax, fny * r - ay
    seg_ax, seg_ay = sax + offx, say + offy
    seg_bx, seg_by = sbx + offx, sby + offy
    deltax, deltay = bx - ax, by - ay
    if (deltax * seg_ay - deltay * seg_ax) * (deltax * seg_by - deltay * seg_bx) <= 0.0:
        d_offset = d + (-r if d > 0.0 else r)
        ad = -d_offset
        bd = (deltax * nx + deltay * ny) - d_offset
        if ad * bd < 0.0:
            return ad / (ad - bd)
        return math.inf
    if r != 0.0:
        t1 = _circle_alpha(sax, say, sr, ax, ay, bx, by, r2)
        t2 = _circle_alpha(sbx, sby, sr, ax, ay, bx, by, r2)
        return t1 if t1 < t2 else t2
    return math.inf


@njit(cache=True, inline="always")
def _box_alpha(x0, y0, x1, y1, ax, ay, bx, by, r2):
    """PolySegmentQuery on the box (x0,y0)-(x1,y0)-(x1,y1)-(x0,y1), poly radius 0."""
    vx = (x0, x1, x1, x0)
    vy = (y0, y0, y1, y1)
    alpha = math.inf
    found = False
    for i in range(4):
        j = (i + 3) % 4  # the previous vertex: plane i runs from v[j] to v[i]
        ex, ey = vx[i] - vx[j], vy[i] - vy[j]
        ln = math.sqrt(ex * ex + ey * ey)
        nx, ny = ey / ln, -ex / ln
        an = ax * nx + ay * ny
        d = an - (vx[i] * nx + vy[i] * ny) - r2
        if d < 0.0:
            continue
        bn = bx * nx + by * ny
        if -10e-6 < an - bn < 10e-6:  # Munk2D: divisor near zero, skip the face
            continue
        t = d / (an - bn)
        if t < 0.0 or 1.0 < t:
            continue
        px, py = ax + (bx - ax) * t, ay + (by - ay) * t
        dt = nx * py - ny * px
        dt_min = nx * vy[j] - ny * vx[j]
        dt_max = nx * vy[i] - ny * vx[i]
        if dt_min <= dt <= dt_max:
            alpha = t  # Chipmunk keeps the last face that qualifies
            found = True
    if not found:
        alpha = 1.0  # Chipmunk's blank answer; a vertex hit must beat it
    best = alpha
    if r2 > 0.0:
        for i in range(4):
            tc = _circle_alpha(vx[i], vy[i], 0.0, ax, ay, bx, by, r2)
            if tc < best:
                best = tc
                found = True
    return best if found else math.inf


@njit(cache=True, inline="always")
def _segment_distance(px, py, ax, ay, bx, by):
    """Distance from p to the segment a-b (cpClosetPointOnSegment)."""
    dx, dy = ax - bx, ay - by
    ln2 = dx * dx + dy * dy
    t = 0.0 if ln2 == 0.0 else min(max((dx * (px - bx) + dy * (py - by)) / ln2, 0.0), 1.0)
    cx, cy = bx + dx * t, by + dy * t
    return math.hypot(px - cx, py - cy)


@njit(cache=True, inline="always")
def _box_distance(px, py, x0, y0, x1, y1):
    """Signed distance from p to the box (negative inside)."""
    if x0 <= px <= x1 and y0 <= py <= y1:
        return -min(px - x0, x1 - px, py - y0, y1 - py)
    dx = max(x0 - px, 0.0, px - x1)
    dy = max(y0 - py, 0.0, py - y1)
    return math.hypot(dx, dy)


# What one static shape does to a query: a wall (index into ``walls``) or an item of the
# grid index (a circle id, or K + a box id), folded into the query's answer so far.

@njit(cache=True, inline="always")
def _sweep_wall(walls, k, radius, ax, ay, bx, by, best):
    # cpShapeSegmentQuery first asks whether the disc at the start already touches the shape
    # (a point query): then it reports alpha 0, which the guard skips
    if _segment_distance(ax, ay, walls[k, 0], walls[k, 1], walls[k, 2],
                         walls[k, 3]) - walls[k, 4] <= radius:
        return best
    t = _segment_alpha(walls[k, 0], walls[k, 1], walls[k, 2], walls[k, 3], walls[k, 4],
                       ax, ay, bx, by, radius)
    return t if 0.0 < t < best else best


@njit(cache=True, inline="always")
def _sweep_item(circles, boxes, k, radius, ax, ay, bx, by, best):
    n_circles = circles.shape[0]
    if k < n_circles:
        if math.hypot(ax - circles[k, 0], ay - circles[k, 1]) - circles[k, 2] <= radius:
            return best
        t = _circle_alpha(circles[k, 0], circles[k, 1], circles[k, 2], ax, ay, bx, by, radius)
    else:
        m = k - n_circles
        if _box_distance(ax, ay, boxes[m, 0], boxes[m, 1], boxes[m, 2], boxes[m, 3]) <= radius:
            return best
        t = _box_alpha(boxes[m, 0], boxes[m, 1], boxes[m, 2], boxes[m, 3], ax, ay, bx, by,
                       radius)
    return t if 0.0 < t < best else best


@njit(cache=True, inline="always")
def _overlap_wall(walls, k, radius, x, y, _bx, _by, deepest):
    d = radius - (_segment_distance(x, y, walls[k, 0], walls[k, 1], walls[k, 2], walls[k, 3])
                  - walls[k, 4])
    return d if d > deepest else deepest


@njit(cache=True, inline="always")
def _overlap_item(circles, boxes, k, radius, x, y, _bx, _by, deepest):
    n_circles = circles.shape[0]
    if k < n_circles:
        d = radius - (math.hypot(x - circles[k, 0], y - circles[k, 1]) - circles[k, 2])
    else:
        m = k - n_circles
        d = radius - _box_distance(x, y, boxes[m, 0], boxes[m, 1], boxes[m, 2], boxes[m, 3])
    return d if d > deepest else deepest


WALL_SKIP_M = 1e-9  # a wall's box this much beyond a query's is beyond its reach [m]


@njit(cache=True, inline="always")
def _wall_beyond(walls, k, x0, y0, x1, y1):
    """Whether thick wall ``k`` lies wholly outside the box (x0, y0)-(x1, y1) (a query's
    reach), by more than WALL_SKIP_M: then no disc in that box touches or sweeps into it,
    and folding it in changes no answer (4 comparisons instead of a segment distance: a
    robot away from the arena's edge asks about 4 walls at every query)."""
    t = walls[k, 4] + WALL_SKIP_M
    return (max(walls[k, 0], walls[k, 2]) + t < x0 or min(walls[k, 0], walls[k, 2]) - t > x1
            or max(walls[k, 1], walls[k, 3]) + t < y0
            or min(walls[k, 1], walls[k, 3]) - t > y1)


@njit(cache=True, inline="always")
def _fold_shapes(wall, item, out, circles, walls, boxes, cell_m, nx, ny, start, items, seen,
                 stamp, radius, ax, ay, bx, by):
    """``out`` folded by ``wall`` over the walls, then by ``item`` over each shape of the
    index (once: ``seen``/``stamp``) in the cells a disc of ``radius`` on a -> b can reach.
    ``wall`` and ``item`` are compiled functions: numba compiles one loop per pair, as
    fast as the loop written out for each query."""
    for k in range(walls.shape[0]):
        if _wall_beyond(walls, k, min(ax, bx) - radius, min(ay, by) - radius,
                        max(ax, bx) + radius, max(ay, by) + radius):
            continue
        out = wall(walls, k, radius, ax, ay, bx, by, out)
    gx0 = min(max(int(math.floor((min(ax, bx) - radius) / cell_m)), 0), nx - 1)  # noqa: RUF046 (numba)
    gy0 = min(max(int(math.floor((min(ay, by) - radius) / cell_m)), 0), ny - 1)  # noqa: RUF046 (numba)
    gx1 = min(max(int(math.floor((max(ax, bx) + radius) / cell_m)), 0), nx - 1)  # noqa: RUF046 (numba)
    gy1 = min(max(int(math.floor((max(ay, by) + radius) / cell_m)), 0), ny - 1)  # noqa: RUF046 (numba)
    for gy in range(gy0, gy1 + 1):
        for gx in range(gx0, gx1 + 1):
            cell = gy * nx + gx
            for p in range(start[cell], start[cell + 1]):
                k = items[p]
                if seen[k] == stamp:
                    continue
                seen[k] = stamp
                out = item(circles, boxes, k, radius, ax, ay, bx, by, out)
    return out


@njit(**BORROWS)
def sweep_fraction(circles, walls, boxes, cell_m, nx, ny, start, items, seen, stamp,
                   radius, ax, ay, bx, by):
    """Fraction of (ax, ay) -> (bx, by) a disc of ``radius`` sweeps before touching a static
    shape, skipping hits at 0 (shapes it overlaps at the start); inf when it touches none.
    ``seen`` (int64[K+M]) and ``stamp`` dedupe candidates; pass a new stamp per call."""
    return _fold_shapes(_sweep_wall, _sweep_item, math.inf, circles, walls, boxes, cell_m, nx,
                        ny, start, items, seen, stamp, radius, ax, ay, bx, by)


@njit(**BORROWS)
def overlap_depth(circles, walls, boxes, cell_m, nx, ny, start, items, seen, stamp, radius,
                  x, y):
    """Deepest overlap [m] of a disc of ``radius`` at (x, y) with any static shape (0: none);
    the point-query distances :func:`sweep_fraction` uses."""
    return _fold_shapes(_overlap_wall, _overlap_item, 0.0, circles, walls, boxes, cell_m, nx,
                        ny, start, items, seen, stamp, radius, x, y, x, y)


class Sweeper:
    """:func:`sweep_fraction` over one scenario's static geometry (Python entry point)."""

    def __init__(self, sc: Scenario) -> None:
        self.geometry = g = static_geometry(sc)
        self.seen = np.zeros(len(g.circles) + len(g.boxes), dtype=np.int64)
        self.stamp = 0

    def fraction(self, radius: float, ax: float, ay: float, bx: float, by: float) -> float:
        g = self.geometry
        self.stamp += 1
        return sweep_fraction(g.circles, g.walls, g.boxes, g.cell_m, g.nx, g.ny, g.start,
                              g.items, self.seen, self.stamp, radius, ax, ay, bx, by)
