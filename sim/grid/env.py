"""``rnhql/GridRoute-v0``: the paper's gridded route world as a gymnasium env."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from sim.grid.model import build_model
from sim.render import AGENT, PATH, MapCanvas
from sim.scenario import Scenario
from sim.scenario_io import resolve_scenario


def start_state_from_options(options: dict[str, Any] | None, model: Any,
                             np_random: np.random.Generator) -> int:
    """Resolve ``reset(options={"start": ...})``: ``"S"`` (default), ``"random"`` or a state.

    ``"random"`` draws uniformly from the free cells that reach the goal, with
    the env's own generator (seeded by ``reset(seed=...)``).
    """
    start = (options or {}).get("start", "S")
    if isinstance(start, str):
        if start == "S":
            return int(model.start)
        if start == "random":
            return int(model.start_states[np_random.integers(len(model.start_states))])
        raise ValueError(f"options['start'] must be 'S', 'random' or a state index, got {start!r}")
    s = int(start)
    if not (0 <= s < model.n_states) or model.distance_to_goal[s] < 0:
        raise ValueError(f"options['start'] = {s} is not a free state that reaches the goal")
    return s


class GridRouteEnv(gym.Env):
    """The paper's 4-connected grid route world.

    ## Description
    A robot (a point on the grid, inflated by the scenario's robot radius when
    the occupancy is rasterised) moves from the start cell S to the goal cell G
    of a scenario (see ``rnhql scenarios``) among circular obstacles.

    ## Action Space
    ``Discrete(4)``: 0 up (+y), 1 down (-y), 2 left (-x), 3 right (+x).

    ## Observation Space
    ``Discrete(nx * ny)``: the cell index ``iy * nx + ix`` (every cell is a
    state; blocked ones are never reached).

    ## Reward
    The scenario's scheme (paper default): +100 for entering G, -1 for a bump
    (a move into an obstacle, a blocked cell or a wall; the agent stays),
    +1 for any other move.

    ## Starting State
    S, or with ``reset(options={"start": "random"})`` a uniformly drawn free
    cell that reaches G; ``{"start": s}`` starts at state ``s``.

    ## Episode End
    Terminated on entering G. Truncated by ``TimeLimit`` after
    ``max_episode_steps`` (600 as registered, the paper's episode length).

    ## Arguments
    ``scenario``: a built-in name, a ``.toml`` path or a :class:`Scenario`.
    ``render_mode``: ``None`` or ``"rgb_array"`` (map, agent and its path).
    ``env.unwrapped.model`` is the :class:`sim.grid.TabularModel`.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012

    def __init__(self, scenario: str | Scenario = "paper-50",
                 render_mode: str | None = None) -> None:
        self.scenario = scenario if isinstance(scenario, Scenario) else resolve_scenario(scenario)
        self.model = build_model(self.scenario)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self.observation_space = spaces.Discrete(self.model.n_states)
        self.action_space = spaces.Discrete(4)
        # Python lists: indexing them is several times cheaper than numpy scalars
        self._next = self.model.next_state.tolist()
        self._reward = self.model.reward.tolist()
        self._goal = self.model.goal
        self._s = self.model.start
        self._path: list[int] = []
        self._canvas: MapCanvas | None = None

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[int, dict[str, Any]]:
        super().reset(seed=seed)
        self._s = start_state_from_options(options, self.model, self.np_random)
        self._path = [self._s]
        return self._s, {}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        if not (action.__class__ is int or isinstance(action, np.integer)) or not 0 <= action < 4:
            raise AssertionError(f"{action!r} ({type(action)}) invalid")
        s = self._s
        ns = self._next[s][action]
        self._s = ns
        if self.render_mode is not None:
            self._path.append(ns)
        return ns, self._reward[s][action], ns == self._goal, False, {}

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        if self._canvas is None:
            self._canvas = MapCanvas(self.scenario, self.model.blocked)
        img = self._canvas.background.copy()
        pts = self.model.coords[np.asarray(self._path, dtype=np.int64)]
        self._canvas.polyline(img, pts, PATH)
        x, y = self.model.coords[self._s]
        self._canvas.disc(img, x, y, self.scenario.robot.radius_m, AGENT)
        return img
