"""The dense O(cells x circles) rasteriser sim.grid.raster replaced: the reference it must match.

Kept only for tests (``tests/test_raster.py``): every cell against every circle,
no bounding boxes, no cleverness. The blocked map squares and the arena walls are
:func:`sim.grid.raster.with_squares_and_walls`, which the rewrite left as they were.
"""

from __future__ import annotations

import numpy as np

from sim.grid.actions import ACTION_DELTAS
from sim.grid.discretiser import Discretiser
from sim.grid.raster import with_squares_and_walls


def dense_occupancy(sc) -> np.ndarray:
    """bool[ny, nx]: True where a robot disc at the cell centre would touch something.

    The disc has radius ``robot.radius_m + robot.clearance_m``. It touches a
    circle when the centre distance is below the sum of radii, a blocked map
    cell when it reaches into that cell's square, an arena wall when it
    crosses it. ``inflation < cell/2`` (validated) means neighbouring squares
    and walls can never be reached from a centre, but they are checked anyway
    so the rule holds for any scenario.
    """
    infl = sc.robot.inflation_m
    self = Discretiser.from_scenario(sc)
    xy = self.centres()
    blocked = np.zeros(self.n_states, dtype=bool)
    if sc.obstacles:
        circ = np.array([(o.x_m, o.y_m, o.radius_m) for o in sc.obstacles])
        d = np.hypot(xy[:, :1] - circ[None, :, 0], xy[:, 1:] - circ[None, :, 1])
        blocked |= (d < circ[None, :, 2] + infl).any(axis=1)
    return with_squares_and_walls(sc, blocked)


def _segment_distance(px: np.ndarray, py: np.ndarray, ax: np.ndarray, ay: np.ndarray,
                      bx: np.ndarray, by: np.ndarray) -> np.ndarray:
    """Distance from points p to segments a-b (broadcasting)."""
    abx, aby = bx - ax, by - ay
    t = np.clip(((px - ax) * abx + (py - ay) * aby) / (abx * abx + aby * aby), 0.0, 1.0)
    return np.hypot(px - (ax + t * abx), py - (ay + t * aby))


def dense_passable_moves(sc, blocked: np.ndarray) -> np.ndarray:
    """bool[nS, 4]: which moves succeed, given the inflated occupancy ``blocked[ny, nx]``."""
    nx, ny = sc.nx, sc.ny
    xy = Discretiser.from_scenario(sc).centres()
    iy, ix = np.divmod(np.arange(nx * ny), nx)
    free = ~blocked.ravel()
    ok = np.zeros((nx * ny, 4), dtype=bool)
    for a, (dx, dy) in enumerate(ACTION_DELTAS):
        tx, ty = ix + dx, iy + dy
        inside = (tx >= 0) & (tx < nx) & (ty >= 0) & (ty < ny)
        t = np.where(inside, ty * nx + tx, 0)
        ok[:, a] = inside & free & free[t]
    if sc.obstacles:
        circ = np.array([(o.x_m, o.y_m, o.radius_m) for o in sc.obstacles])
        reach = circ[:, 2] + sc.robot.inflation_m
        # a segment of length c starting at a centre can only come within `reach`
        # of a circle if that centre is within reach + c: test those pairs only
        d_centre = np.hypot(xy[:, :1] - circ[None, :, 0], xy[:, 1:] - circ[None, :, 1])
        s_idx, k_idx = np.nonzero(d_centre < reach[None, :] + sc.cell_size_m)
        p = xy[s_idx]
        for a, (dx, dy) in enumerate(ACTION_DELTAS):
            end = p + np.array([dx, dy]) * sc.cell_size_m
            d = _segment_distance(circ[k_idx, 0], circ[k_idx, 1], p[:, 0], p[:, 1],
                                  end[:, 0], end[:, 1])
            ok[s_idx[d < reach[k_idx]], a] = False
    return ok
