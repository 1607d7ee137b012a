"""The paper's gridded route world and the tabular model the learners train on.

Every cell of the arena is a state (``s = iy * nx + ix``); blocked cells are
states that nothing reaches, which keeps the index a pure function of the pose
for the physics world. Actions: 0 up (+y), 1 down (-y), 2 left (-x), 3 right (+x)
(:mod:`sim.grid.actions`).

A move succeeds when the target cell is in the arena, free for the inflated
robot, and the robot's swept disc along the straight segment between the two
centres clears every circle (so the route the grid allows is one the physics
robot can drive). Otherwise it is a *bump*: the agent stays, reward ``bump``.
Entering the goal gives ``goal`` and terminates; any other move gives ``step``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim.grid.actions import ACTION_DELTAS
from sim.grid.discretiser import Discretiser
from sim.grid.raster import rasterise
from sim.scenario import Scenario


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
    def action_deltas(self) -> tuple[tuple[int, int], ...]:
        """(dx, dy) of each action, in order (the learners check it: learning.geometry)."""
        return ACTION_DELTAS

    @property
    def n_actions(self) -> int:
        return int(self.next_state.shape[1])

    @property
    def optimal_route_length(self) -> int:
        """BFS moves from S to G."""
        return int(self.distance_to_goal[self.start])


def episode_starts(free: np.ndarray, start: int, s_share: float) -> np.ndarray:
    """int32: the states an episode's start is drawn from, uniformly. The free cells that
    reach G, and with ``s_share`` > 0 the start S repeated so that it is drawn with that
    probability (the draw stays one uniform index, in every world and learner)."""
    free = free.astype(np.int32)
    if s_share <= 0.0:
        return free
    extra = round(s_share * len(free) / (1.0 - s_share))
    return np.concatenate([free, np.full(extra, start, np.int32)])


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
    # a blocked move is a bump and stays put, so it never enters G
    reward = np.asarray(rw.of_moves(bumped=~ok, at_goal=next_state == goal), dtype=np.float64)
    reward[goal] = 0.0  # G is terminal: nothing is earned from it
    terminal = np.zeros(n, dtype=bool)
    terminal[goal] = True
    next_state[goal] = goal
    start_states = episode_starts(np.flatnonzero(dist > 0), disc.index(*sc.start),
                                  sc.s_start_share)
    for arr in (next_state, reward, terminal, start_states):
        arr.setflags(write=False)
    coords = disc.centres()
    coords.setflags(write=False)
    return TabularModel(next_state=next_state, reward=reward, terminal=terminal, coords=coords,
                        start_states=start_states, start=disc.index(*sc.start), goal=goal,
                        distance_to_goal=dist, blocked=blocked, nx=nx, ny=sc.ny,
                        cell_size_m=sc.cell_size_m, bounds_m=(0.0, 0.0, sc.width_m, sc.height_m),
                        max_steps=sc.steps_per_episode)
