"""Exact planners, the ground truth every learning metric is measured against.

* :func:`bfs_distances` / :func:`bfs_route`: 4-connected shortest routes over the
  grid world's passable moves (what the learners can do).
* :func:`astar`: A* with a binary heap on a plain blocked grid, 4-connected
  (Manhattan) or 8-connected (octile, no corner cutting), to check maps against
  the Moving AI ``.scen`` optimal lengths.
* :func:`value_iteration`: exact V*, Q* of the tabular model under its rewards.
"""

from __future__ import annotations

import heapq
import math

import numpy as np

# Action order shared by the grid world and the learners: up, down, left, right.
ACTION_DELTAS = ((0, 1), (0, -1), (-1, 0), (1, 0))
OPPOSITE = (1, 0, 3, 2)


def bfs_distances(passable: np.ndarray, nx: int, goal: tuple[int, int]) -> np.ndarray:
    """int32[nS]: moves from each state to ``goal`` (-1 where unreachable).

    ``passable[s, a]`` says move ``a`` from ``s`` succeeds. Moves between free
    cells are symmetric, so a BFS outward from the goal along reversed moves
    gives every state's distance to it. Layer by layer with numpy: O(states)
    work plus a small constant per layer, so a 1024 x 1024 map takes
    milliseconds, not the seconds of a per-state Python loop.
    """
    n = passable.shape[0]
    dist = np.full(n, -1, dtype=np.int32)
    g = goal[1] * nx + goal[0]
    dist[g] = 0
    steps = np.array([dy * nx + dx for dx, dy in ACTION_DELTAS], dtype=np.int64)
    frontier = np.array([g], dtype=np.int64)
    d = 0
    while frontier.size:
        d += 1
        reached = []
        for a in range(4):
            # v reaches u by the opposite move, which is passable iff u -> v is
            u = frontier[passable[frontier, a]]
            v = u + steps[a]
            reached.append(v[dist[v] < 0])
        frontier = np.unique(np.concatenate(reached))
        dist[frontier] = d
    return dist


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
