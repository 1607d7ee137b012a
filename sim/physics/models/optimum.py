"""The continuous optimum: how long the disc's shortest collision-free path from S to G is.

The grid's optimum counts 4-connected moves between cell centres; the robot could take
any path. This module searches any-angle paths with Theta* (Nash et al. 2007) over the
centres of the cells where the disc fits, 8-connected, with an exact line-of-sight test:
the robot's disc swept along the straight segment touches nothing
(:func:`sim.physics.kernel.sweep.sweep_fraction`, Chipmunk's segment queries over the static
shapes). The result is the length [m] of a path the disc can really drive, so it is an
*upper bound* on the continuous optimum; Theta* paths on grids are typically within a
few percent of the true shortest path (they bend only at cell centres near corners of
obstacles). The straight-line distance S-G is the matching lower bound.
"""

from __future__ import annotations

import heapq
import math
from functools import lru_cache

import numpy as np

from sim.physics.kernel.sweep import overlap_depth, static_geometry, sweep_fraction
from sim.scenario import Scenario

_NEIGHBOURS = ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1))


def continuous_optimum_m(sc: Scenario) -> float | None:
    """Length [m] of the Theta* path of the robot's disc from S's centre to G's; None if the
    disc cannot reach G."""
    return _cached(sc)


@lru_cache(maxsize=16)
def _cached(sc: Scenario) -> float | None:
    g = static_geometry(sc)
    seen = np.zeros(len(g.circles) + len(g.boxes), dtype=np.int64)
    stamp = [0]
    r = sc.robot.radius_m
    c = sc.cell_size_m
    nx, ny = sc.nx, sc.ny

    def centre(s: int) -> tuple[float, float]:
        return ((s % nx) + 0.5) * c, ((s // nx) + 0.5) * c

    fits = np.zeros(nx * ny, dtype=bool)
    for s in range(nx * ny):
        x, y = centre(s)
        stamp[0] += 1
        fits[s] = overlap_depth(g.circles, g.walls, g.boxes, g.cell_m, g.nx, g.ny, g.start,
                                g.items, seen, stamp[0], r, x, y) <= 0.0

    def sight(a: int, b: int) -> bool:
        (x0, y0), (x1, y1) = centre(a), centre(b)
        stamp[0] += 1
        return sweep_fraction(g.circles, g.walls, g.boxes, g.cell_m, g.nx, g.ny, g.start,
                              g.items, seen, stamp[0], r, x0, y0, x1, y1) == math.inf

    def dist(a: int, b: int) -> float:
        (x0, y0), (x1, y1) = centre(a), centre(b)
        return math.hypot(x1 - x0, y1 - y0)

    start = sc.start[1] * nx + sc.start[0]
    goal = sc.goal[1] * nx + sc.goal[0]
    if not (fits[start] and fits[goal]):
        return None
    cost = np.full(nx * ny, math.inf)
    parent = np.full(nx * ny, -1, dtype=np.int64)
    closed = np.zeros(nx * ny, dtype=bool)
    cost[start] = 0.0
    parent[start] = start
    heap = [(dist(start, goal), start)]
    while heap:
        _, s = heapq.heappop(heap)
        if closed[s]:
            continue
        if s == goal:
            return float(cost[s])
        closed[s] = True
        sx, sy = s % nx, s // nx
        for dx, dy in _NEIGHBOURS:
            tx, ty = sx + dx, sy + dy
            if not (0 <= tx < nx and 0 <= ty < ny):
                continue
            t = ty * nx + tx
            if closed[t] or not fits[t] or not sight(s, t):
                continue
            p = parent[s]
            if p != s and sight(p, t):  # Theta*: connect t straight to s's parent
                new, via = cost[p] + dist(p, t), p
            else:
                new, via = cost[s] + dist(s, t), s
            if new < cost[t]:
                cost[t] = new
                parent[t] = via
                heapq.heappush(heap, (new + dist(t, goal), t))
    return None
