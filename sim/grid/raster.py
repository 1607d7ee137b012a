"""Rasterising a scenario: which cells the robot fits in, which moves it can drive, how far G is.

The one place where circles meet cells, used by validation (:mod:`sim.scenario_io`)
and by the grid model (:mod:`sim.grid.model`). Cost grows with the map, never with
cells x obstacles: each circle is stamped onto the cells of its bounding box
(grown by the robot's inflation, plus one cell for swept moves), so a 512 x 512
arena with 3,000 circles builds in well under a second.

Rules (unchanged from the dense formulation they replace, bit for bit):

- a cell is *blocked* when a disc of radius ``robot.radius_m + clearance_m`` at
  its centre would touch a circle (centre distance < r + inflation), a blocked
  map cell (its square) or an arena wall;
- a move from a free cell to a free neighbour succeeds unless the disc swept
  along the segment between the two centres comes within r + inflation of a
  circle's centre.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from sim.grid.actions import ACTION_DELTAS
from sim.grid.discretiser import Discretiser
from sim.grid.planning import bfs_distances, free_moves
from sim.scenario import Scenario


def segment_distance(px: np.ndarray, py: np.ndarray, ax: np.ndarray, ay: np.ndarray,
                     bx: np.ndarray, by: np.ndarray) -> np.ndarray:
    """Distance from points p to segments a-b (broadcasting)."""
    abx, aby = bx - ax, by - ay
    t = np.clip(((px - ax) * abx + (py - ay) * aby) / (abx * abx + aby * aby), 0.0, 1.0)
    return np.hypot(px - (ax + t * abx), py - (ay + t * aby))


def circle_array(sc: Scenario) -> np.ndarray:
    """float64[k, 3]: the circles as (x, y, r) rows [m]."""
    if not sc.obstacles:
        return np.zeros((0, 3))
    return np.array([(o.x_m, o.y_m, o.radius_m) for o in sc.obstacles], dtype=np.float64)


def _box(lo_m: float, hi_m: float, c: float, n: int) -> tuple[int, int]:
    """Index range [i0, i1) of the cells whose centre (i + 0.5) c may lie in [lo, hi].

    One cell of slack on each side: the exact test that follows decides, so the
    box only has to be conservative.
    """
    i0 = max(0, math.floor(lo_m / c - 0.5) - 1)
    i1 = min(n, math.ceil(hi_m / c - 0.5) + 2)
    return i0, i1


def near_pairs(sc: Scenario, circ: np.ndarray, margin_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(state, circle) index pairs with the cell centre within r + inflation + margin.

    Only the cells of each circle's bounding box are looked at: O(sum of the
    circles' areas in cells), not O(cells x circles).
    """
    c, nx, ny = sc.cell_size_m, sc.nx, sc.ny
    infl = sc.robot.inflation_m
    s_parts, k_parts = [], []
    for k in range(circ.shape[0]):
        x, y, r = circ[k]
        reach = r + infl
        ix0, ix1 = _box(x - reach - margin_m, x + reach + margin_m, c, nx)
        iy0, iy1 = _box(y - reach - margin_m, y + reach + margin_m, c, ny)
        if ix0 >= ix1 or iy0 >= iy1:
            continue
        ix = np.arange(ix0, ix1)
        iy = np.arange(iy0, iy1)
        cx = (ix + 0.5) * c  # the same arithmetic as Discretiser.centres(): bit-identical
        cy = (iy + 0.5) * c
        d = np.hypot(cx[None, :] - x, cy[:, None] - y)
        jy, jx = np.nonzero(d < reach + margin_m)
        s_parts.append((iy[jy] * nx + ix[jx]).astype(np.int64))
        k_parts.append(np.full(jy.size, k, dtype=np.int64))
    if not s_parts:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate(s_parts), np.concatenate(k_parts)


def occupancy(sc: Scenario) -> np.ndarray:
    """bool[ny, nx]: True where a robot disc at the cell centre would touch something.

    ``inflation < cell/2`` (validated) means neighbouring map squares and walls
    can never be reached from a centre, but they are checked anyway so the rule
    holds for any scenario.
    """
    blocked = np.zeros(sc.nx * sc.ny, dtype=bool)
    circ = circle_array(sc)
    if circ.shape[0]:
        s_idx, _ = near_pairs(sc, circ, 0.0)
        blocked[s_idx] = True
    return with_squares_and_walls(sc, blocked)


def with_squares_and_walls(sc: Scenario, blocked: np.ndarray) -> np.ndarray:
    """bool[ny, nx]: the cells ``blocked`` (bool[nS], what the circles block), the blocked
    map squares (and, for a disc that reaches a neighbouring square, every 4-neighbour),
    and the cells whose disc crosses an arena wall."""
    infl = sc.robot.inflation_m
    if sc.blocked_cells:
        cells = np.asarray(sc.blocked_cells, dtype=np.int64).reshape(-1, 2)
        blocked[cells[:, 1] * sc.nx + cells[:, 0]] = True
        if infl >= sc.cell_size_m / 2:  # a disc this large could reach a neighbouring square
            sq = blocked.reshape(sc.ny, sc.nx).copy()
            grown = sq.copy()
            grown[1:] |= sq[:-1]
            grown[:-1] |= sq[1:]
            grown[:, 1:] |= sq[:, :-1]
            grown[:, :-1] |= sq[:, 1:]
            blocked = grown.ravel()
    xy = Discretiser.from_scenario(sc).centres()
    wall = np.minimum.reduce([xy[:, 0], xy[:, 1], sc.width_m - xy[:, 0], sc.height_m - xy[:, 1]])
    blocked |= wall < infl
    return blocked.reshape(sc.ny, sc.nx)


def passable_moves(sc: Scenario, blocked: np.ndarray) -> np.ndarray:
    """bool[nS, 4]: which moves succeed, given the inflated occupancy ``blocked[ny, nx]``."""
    nx = sc.nx
    ok = free_moves(~blocked.reshape(sc.ny, nx))
    circ = circle_array(sc)
    if circ.shape[0]:
        # a segment of length c from a centre can only come within `reach` of a
        # circle if that centre is within reach + c: test those pairs only
        s_idx, k_idx = near_pairs(sc, circ, sc.cell_size_m)
        reach = circ[:, 2] + sc.robot.inflation_m
        c = sc.cell_size_m
        px = (s_idx % nx + 0.5) * c
        py = (s_idx // nx + 0.5) * c
        for a, (dx, dy) in enumerate(ACTION_DELTAS):
            d = segment_distance(circ[k_idx, 0], circ[k_idx, 1], px, py, px + dx * c,
                                 py + dy * c)
            ok[s_idx[d < reach[k_idx]], a] = False
    return ok


@lru_cache(maxsize=16)
def rasterise(sc: Scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(blocked[ny,nx], passable[nS,4], distance_to_goal[nS]) of a scenario, read-only.

    Cached because validation and model building both need it; a Scenario is
    frozen and hashable, so the cache key is the whole problem.
    """
    blocked = occupancy(sc)
    ok = passable_moves(sc, blocked)
    dist = bfs_distances(ok, sc.nx, sc.goal)
    for arr in (blocked, ok, dist):
        arr.setflags(write=False)
    return blocked, ok, dist
