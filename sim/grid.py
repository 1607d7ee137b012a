"""The paper's gridded route world and the tabular model the learners train on.

Every cell of the arena is a state (``s = iy * nx + ix``); blocked cells are
states that nothing reaches, which keeps the index a pure function of the pose
for the physics world. Actions: 0 up (+y), 1 down (-y), 2 left (-x), 3 right (+x).

A move succeeds when the target cell is in the arena, free for the inflated
robot, and the robot's swept disc along the straight segment between the two
centres clears every circle (so the route the grid allows is one the physics
robot can drive). Otherwise it is a *bump*: the agent stays, reward ``bump``.
Entering the goal gives ``goal`` and terminates; any other move gives ``step``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from sim.discretiser import Discretiser
from sim.planning import ACTION_DELTAS, bfs_distances
from sim.scenario import Scenario

ACTION_NAMES = ("up", "down", "left", "right")


def _segment_distance(px: np.ndarray, py: np.ndarray, ax: np.ndarray, ay: np.ndarray,
                      bx: np.ndarray, by: np.ndarray) -> np.ndarray:
    """Distance from points p to segments a-b (broadcasting)."""
    abx, aby = bx - ax, by - ay
    t = np.clip(((px - ax) * abx + (py - ay) * aby) / (abx * abx + aby * aby), 0.0, 1.0)
    return np.hypot(px - (ax + t * abx), py - (ay + t * aby))


def passable_moves(sc: Scenario, blocked: np.ndarray) -> np.ndarray:
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


@lru_cache(maxsize=16)
def rasterise(sc: Scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(blocked[ny,nx], passable[nS,4], distance_to_goal[nS]) of a scenario, read-only.

    Cached because validation and model building both need it; a Scenario is
    frozen and hashable, so the cache key is the whole problem.
    """
    blocked = Discretiser.from_scenario(sc).occupancy(sc)
    ok = passable_moves(sc, blocked)
    dist = bfs_distances(ok, sc.nx, sc.goal)
    for arr in (blocked, ok, dist):
        arr.setflags(write=False)
    return blocked, ok, dist


@dataclass(frozen=True, eq=False)
class TabularModel:
    """The sim/learning seam: a deterministic grid MDP as plain arrays."""

    next_state: np.ndarray  # int32[nS, 4]
    reward: np.ndarray  # float64[nS, 4]
    terminal: np.ndarray  # bool[nS]; only the goal
    coords: np.ndarray  # float64[nS, 2]; cell centres [m], what function approximators see
    start_states: np.ndarray  # int32[k]; free cells that reach the goal, goal excluded
    start: int  # state of S
    goal: int  # state of G
    distance_to_goal: np.ndarray  # int32[nS]; BFS moves to G, -1 if unreachable/blocked
    blocked: np.ndarray  # bool[ny, nx]; inflated occupancy
    nx: int
    ny: int
    cell_size_m: float
    bounds_m: tuple[float, float, float, float]  # (xmin, ymin, xmax, ymax) of the arena
    max_steps: int  # steps per episode

    @property
    def n_states(self) -> int:
        return int(self.next_state.shape[0])

    @property
    def n_actions(self) -> int:
        return int(self.next_state.shape[1])

    @property
    def optimal_route_length(self) -> int:
        """BFS moves from S to G."""
        return int(self.distance_to_goal[self.start])


def build_model(sc: Scenario) -> TabularModel:
    """Rasterise ``sc`` and export its grid dynamics. Assumes ``sc`` is validated."""
    disc = Discretiser.from_scenario(sc)
    blocked, ok, dist = rasterise(sc)
    n = disc.n_states
    states = np.arange(n)
    nx = sc.nx
    deltas = np.array([dy * nx + dx for dx, dy in ACTION_DELTAS])
    next_state = np.where(ok, states[:, None] + deltas[None, :], states[:, None]).astype(np.int32)
    goal = disc.index(*sc.goal)
    rw = sc.rewards
    reward = np.where(ok, rw.step, rw.bump)
    reward[next_state == goal] = rw.goal
    reward[goal] = 0.0
    terminal = np.zeros(n, dtype=bool)
    terminal[goal] = True
    next_state[goal] = goal
    start_states = np.flatnonzero(dist > 0).astype(np.int32)
    for arr in (next_state, reward, terminal, start_states):
        arr.setflags(write=False)
    coords = disc.centres()
    coords.setflags(write=False)
    return TabularModel(next_state=next_state, reward=reward, terminal=terminal, coords=coords,
                        start_states=start_states, start=disc.index(*sc.start), goal=goal,
                        distance_to_goal=dist, blocked=blocked, nx=nx, ny=sc.ny,
                        cell_size_m=sc.cell_size_m, bounds_m=(0.0, 0.0, sc.width_m, sc.height_m),
                        max_steps=sc.steps_per_episode)
