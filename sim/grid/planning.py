"""Exact planners, the ground truth every learning metric is measured against.

* :func:`breadth_first`: the one BFS; :func:`bfs_distances` (the grid world's
  passable moves, what the learners can do), :func:`distances_to` (any transition
  table, e.g. the physics world's) and :func:`grid_distances` (a plain free-cell
  grid) are its uses; :func:`bfs_route` walks a shortest route down the distances;
  :func:`far_start_goal` puts a start and goal about a map's diameter apart.
* :func:`astar`: A* with a binary heap on a plain blocked grid, 4-connected
  (Manhattan) or 8-connected (octile, no corner cutting), to check maps against
  the Moving AI ``.scen`` optimal lengths.
* :func:`value_iteration`: exact V*, Q* of the tabular model under its rewards.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable

import numpy as np

from sim.grid.actions import ACTION_DELTAS, N_ACTIONS


def breadth_first(n: int, source: int,
                  expand: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """int32[n]: BFS layer of every state from ``source`` (-1 where never reached).

    The one BFS of the sim side. ``expand(frontier)`` returns the states the
    frontier's states lead to, in any number and order; repeats and states
    already reached are dropped. A layer is expanded as a whole (numpy work per
    layer, not per state), its states in the order they were first found, so a
    caller that acts on each state (driving it) sees a FIFO queue's order.
    """
    dist = np.full(n, -1, dtype=np.int32)
    dist[source] = 0
    frontier = np.array([source], dtype=np.int64)
    d = 0
    while frontier.size:
        d += 1
        found = np.asarray(expand(frontier), dtype=np.int64)
        found = found[dist[found] < 0]
        _, first = np.unique(found, return_index=True)
        frontier = found[np.sort(first)]
        dist[frontier] = d
    return dist


def bfs_distances(passable: np.ndarray, nx: int, goal: tuple[int, int]) -> np.ndarray:
    """int32[nS]: moves from each state to ``goal`` (-1 where unreachable).

    ``passable[s, a]`` says move ``a`` from ``s`` succeeds. Moves between free
    cells are symmetric, so a BFS outward from the goal along reversed moves
    gives every state's distance to it: O(states) work, so a 1024 x 1024 map
    takes milliseconds, not the seconds of a per-state Python loop.
    """
    steps = np.array([dy * nx + dx for dx, dy in ACTION_DELTAS], dtype=np.int64)

    def expand(frontier: np.ndarray) -> np.ndarray:
        # v reaches u by the opposite move, which is passable iff u -> v is
        return np.concatenate([frontier[passable[frontier, a]] + steps[a]
                               for a in range(N_ACTIONS)])

    return breadth_first(passable.shape[0], goal[1] * nx + goal[0], expand)


def free_moves(free: np.ndarray) -> np.ndarray:
    """bool[nS, 4]: which moves join two free cells of ``free[iy, ix]`` inside the grid."""
    ny, nx = free.shape
    iy, ix = np.divmod(np.arange(nx * ny), nx)
    flat = free.ravel()
    ok = np.zeros((nx * ny, N_ACTIONS), dtype=bool)
    for a, (dx, dy) in enumerate(ACTION_DELTAS):
        tx, ty = ix + dx, iy + dy
        inside = (tx >= 0) & (tx < nx) & (ty >= 0) & (ty < ny)
        t = np.where(inside, ty * nx + tx, 0)
        ok[:, a] = inside & flat & flat[t]
    return ok


def grid_distances(free: np.ndarray, source: tuple[int, int]) -> np.ndarray:
    """int32[ny, nx]: 4-connected moves over the free cells of ``free[iy, ix]`` from
    cell ``source`` = (ix, iy) to every cell, -1 where unreachable."""
    return bfs_distances(free_moves(free), free.shape[1], source).reshape(free.shape)


def far_start_goal(free: np.ndarray) -> tuple[tuple[int, int], tuple[int, int], int]:
    """(start, goal, moves) as (row, col) indices of ``free``, about the map's diameter
    apart, so the route crosses the map: a double BFS sweep (the farthest cell from a cell
    of the largest component, then the farthest from that). Eight evenly spaced free
    cells are tried as the first source, and the one reaching most cells is kept, so a
    small island cannot hold the pair."""
    cells = np.argwhere(free)
    if cells.size == 0:
        raise ValueError("the map has no free cell")
    best = None
    for r, c in cells[np.linspace(0, len(cells) - 1, 8).astype(int)]:
        d = grid_distances(free, (int(c), int(r)))  # BFS moves from (row r, col c)
        if best is None or (d >= 0).sum() > (best >= 0).sum():
            best = d
    a = tuple(int(x) for x in np.unravel_index(np.argmax(best), best.shape))
    da = grid_distances(free, a[::-1])
    b = tuple(int(x) for x in np.unravel_index(np.argmax(da), da.shape))
    return b, a, int(da[b])


def corner_start_goal(free: np.ndarray) -> tuple[tuple[int, int], tuple[int, int], int]:
    """(start, goal, moves) as (row, col) indices of ``free``, at opposite corners: S the
    free cell nearest the top-left corner (least row + col; on a tie the upper), G the cell
    S reaches nearest the bottom-right one (most row + col; on a tie the lower). Why
    corners besides the diameter: on open ground the diameter's ends can sit mid-edge,
    while corner to corner every monotone staircase is a shortest route, so shortest
    routes tie in their thousands (the case a judging set must have)."""
    rows, cols = np.nonzero(free)
    if rows.size == 0:
        raise ValueError("the map has no free cell")
    corner = np.lexsort((rows, rows + cols))[0]  # least row + col, then least row
    s = (int(rows[corner]), int(cols[corner]))
    d = grid_distances(free, s[::-1])  # BFS moves from S, (row, col) grid
    rr, cc = np.nonzero(d >= 0)
    far = np.lexsort((rr, rr + cc))[-1]  # most row + col, then most row
    g = (int(rr[far]), int(cc[far]))
    return s, g, int(d[g])


def distances_to(next_state: np.ndarray, goal: int) -> np.ndarray:
    """int32[nS]: moves to ``goal`` along a transition table ``next_state[s, a]``, -1 where
    none. Moves need not be symmetric (the physics world's are not): the BFS runs from the
    goal over the reversed transitions, self-loops (bumps) left out."""
    n = next_state.shape[0]
    src = np.repeat(np.arange(n, dtype=np.int64), next_state.shape[1])
    dst = next_state.astype(np.int64).ravel()
    moves = src != dst
    order = np.argsort(dst[moves], kind="stable")
    preds = src[moves][order]  # predecessors grouped by the state they lead to
    first = np.searchsorted(dst[moves][order], np.arange(n + 1))

    def expand(frontier: np.ndarray) -> np.ndarray:
        lo = first[frontier]
        counts = first[frontier + 1] - lo
        offsets = np.cumsum(counts) - counts
        return preds[np.repeat(lo - offsets, counts) + np.arange(counts.sum())]

    return breadth_first(n, goal, expand)


def bfs_route(next_state: np.ndarray, distance: np.ndarray, start: int) -> list[int]:
    """A shortest route (list of states, start first) by descending BFS distance."""
    if distance[start] < 0:
        return []
    route = [start]
    s = start
    while distance[s] > 0:
        for a in range(next_state.shape[1]):
            t = next_state[s, a]
            if distance[t] == distance[s] - 1:
                s = int(t)
                break
        route.append(s)
    return route


def astar(blocked: np.ndarray, start: tuple[int, int], goal: tuple[int, int],
          connectivity: int = 8) -> tuple[float, list[tuple[int, int]]]:
    """Shortest route on ``blocked[y, x]`` between cells ``(x, y)``; ``(inf, [])`` if none.

    8-connected moves cost sqrt(2) diagonally and may not cut corners (both
    orthogonal neighbours must be free), as in the Moving AI benchmarks.
    """
    if connectivity not in (4, 8):
        raise ValueError(f"connectivity must be 4 or 8, got {connectivity}")
    h, w = blocked.shape
    free = (~blocked).tolist()
    sq2 = math.sqrt(2.0)
    gx, gy = goal
    moves = [(1, 0, 1.0), (-1, 0, 1.0), (0, 1, 1.0), (0, -1, 1.0)]
    if connectivity == 8:
        moves += [(1, 1, sq2), (1, -1, sq2), (-1, 1, sq2), (-1, -1, sq2)]

    def heuristic(x: int, y: int) -> float:
        dx, dy = abs(x - gx), abs(y - gy)
        if connectivity == 4:
            return float(dx + dy)
        return (sq2 - 1.0) * min(dx, dy) + max(dx, dy)

    g_cost = {start: 0.0}
    parent: dict[tuple[int, int], tuple[int, int]] = {}
    heap = [(heuristic(*start), 0.0, start)]
    closed = set()
    while heap:
        _, gc, node = heapq.heappop(heap)
        if node in closed:
            continue
        if node == goal:
            path = [node]
            while node in parent:
                node = parent[node]
                path.append(node)
            return gc, path[::-1]
        closed.add(node)
        x, y = node
        for dx, dy, cost in moves:
            nx_, ny_ = x + dx, y + dy
            if not (0 <= nx_ < w and 0 <= ny_ < h) or not free[ny_][nx_]:
                continue
            if dx and dy and not (free[y][nx_] and free[ny_][x]):
                continue
            ng = gc + cost
            nb = (nx_, ny_)
            if ng < g_cost.get(nb, math.inf) - 1e-12:
                g_cost[nb] = ng
                parent[nb] = node
                heapq.heappush(heap, (ng + heuristic(nx_, ny_), ng, nb))
    return math.inf, []


def value_iteration(next_state: np.ndarray, reward: np.ndarray, terminal: np.ndarray,
                    gamma: float, tol: float = 1e-10,
                    max_iter: int = 100_000) -> tuple[np.ndarray, np.ndarray]:
    """Exact (V*, Q*) of a deterministic tabular MDP; terminal states have V = 0."""
    cont = (~terminal).astype(np.float64)
    v = np.zeros(next_state.shape[0])
    for _ in range(max_iter):
        q = reward + gamma * (v * cont)[next_state]
        q[terminal] = 0.0
        v_new = q.max(axis=1)
        if np.max(np.abs(v_new - v)) < tol:
            v = v_new
            break
        v = v_new
    q = reward + gamma * (v * cont)[next_state]
    q[terminal] = 0.0
    return v, q
