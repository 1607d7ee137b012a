"""What a learner may know about the world, taken duck-typed (learning never imports sim).

Two shapes of input:

* :class:`TabularMDP` is the sim/learning seam, a deterministic grid MDP as plain
  arrays (``sim.grid.TabularModel`` satisfies it). The fused kernels train on it.
* :class:`Geometry` is the little a step-by-step agent needs to build its
  features and heuristics for *any* ``Discrete`` env: cell centres, the goal,
  the arena bounds. It carries no dynamics, so the same agent can drive the
  physics env.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

# the learners' actions, in order: up (+y), down (-y), left (-x), right (+x), as (dx, dy) in
# cells. The world's own order is sim.grid.actions.ACTION_DELTAS; a model that carries its
# order (``action_deltas``) is checked against this one where the two meet (geometry_of).
ACTION_DELTAS = ((0, 1), (0, -1), (-1, 0), (1, 0))


class TabularMDP(Protocol):
    """A deterministic episodic MDP over grid cells (see ``sim.grid.TabularModel``)."""

    next_state: np.ndarray  # int32[nS, nA]
    reward: np.ndarray  # float64[nS, nA]
    terminal: np.ndarray  # bool[nS]; the goal only
    coords: np.ndarray  # float64[nS, 2]; cell centres [m]
    start_states: np.ndarray  # int32[k]; states an episode may start from
    start: int  # S
    goal: int  # G
    distance_to_goal: np.ndarray  # int32[nS]; BFS moves to G, -1 blocked/unreachable
    cell_size_m: float  # [m]
    bounds_m: tuple[float, float, float, float]  # (xmin, ymin, xmax, ymax) [m]
    max_steps: int  # episode length limit [steps]


@dataclass(frozen=True, eq=False)
class Geometry:
    """Static knowledge a learner builds features/heuristics from (no dynamics)."""

    coords: np.ndarray  # float64[nS, 2]; cell centre of each state [m]
    goal: int  # goal state index
    bounds_m: tuple[float, float, float, float]  # (xmin, ymin, xmax, ymax) of the arena [m]
    n_states: int
    n_actions: int  # 4: up (+y), down (-y), left (-x), right (+x)
    cell_size_m: float = 1.0  # grid pitch [m]; Manhattan distances are counted in cells
    start_states: np.ndarray | None = None  # int32[k]; random episode starts (None: env's own)
    # bool[nS]: the cells free in a map given in advance (None: no map). Only a method that
    # assumes such a prior reads it (abstraction-ql's coarse map); every other learner
    # learns the map from its bumps.
    map_prior: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.coords.shape != (self.n_states, 2):
            raise ValueError(f"coords must have shape ({self.n_states}, 2), "
                             f"got {self.coords.shape}")
        if not 0 <= self.goal < self.n_states:
            raise ValueError(f"goal {self.goal} is not a state index below {self.n_states}")
        if self.n_actions != 4:
            raise ValueError(f"the grid learners need 4 actions, got {self.n_actions}")

    @property
    def cells(self) -> np.ndarray:
        """int64[nS, 2]: (ix, iy) of each state, from its centre."""
        xmin, ymin = self.bounds_m[0], self.bounds_m[1]
        origin = np.array([xmin, ymin])
        return np.floor((self.coords - origin) / self.cell_size_m).astype(np.int64)


def geometry_of(model: TabularMDP) -> Geometry:
    """The :class:`Geometry` of a tabular model (what a step agent on its env may know).
    A model whose actions run in another order than the learners' is refused."""
    deltas = getattr(model, "action_deltas", ACTION_DELTAS)
    if tuple(map(tuple, deltas)) != ACTION_DELTAS:
        raise ValueError(f"the model's actions {deltas} are not the learners' order "
                         f"{ACTION_DELTAS} (up, down, left, right as (dx, dy))")
    return Geometry(coords=np.asarray(model.coords, dtype=np.float64), goal=int(model.goal),
                    bounds_m=tuple(float(b) for b in model.bounds_m),
                    n_states=int(model.next_state.shape[0]),
                    n_actions=int(model.next_state.shape[1]),
                    cell_size_m=float(model.cell_size_m),
                    start_states=np.asarray(model.start_states, dtype=np.int32),
                    map_prior=_map_of(model))


def _map_of(model: TabularMDP) -> np.ndarray | None:
    """bool[nS]: the cells with a route to G (the map a method with a prior is told), or
    None for a model that does not say (a hand-built one without distances)."""
    distance = getattr(model, "distance_to_goal", None)
    return None if distance is None else np.asarray(distance) >= 0
