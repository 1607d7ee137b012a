"""``rnhql/GridRoute-v0``: the paper's gridded route world as a gymnasium env."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from sim.env_args import (
    INTEGER_KINDS,
    SCENARIO_REWARDS,
    SpecOwnLimit,
    check_num_envs,
    discrete_action,
    discrete_actions,
    env_scenario,
    episode_limit,
)
from sim.grid.model import build_model
from sim.render import AGENT, PATH, MapCanvas
from sim.scenario import Rewards, Scenario


def start_state(value: Any, model: Any, fld: str) -> int:
    """A start state: an integer (int or numpy integer, not a bool) naming a free state
    that reaches the goal. The one rule for ``start=``, ``options["start"]`` and the
    vector envs' ``options["starts"]``."""
    if not isinstance(value, int | np.integer) or isinstance(value, bool):
        raise ValueError(f"{fld} must be 'S', 'random' or a state index (an int), got "
                         f"{value!r}")
    s = int(value)
    if not (0 <= s < model.n_states) or model.distance_to_goal[s] < 0:
        raise ValueError(f"{fld} = {s} is not a free state that reaches the goal; pick one "
                         "of env.unwrapped.model.start_states")
    return s


def check_start(start: Any, model: Any) -> str | int:
    """An env's ``start=`` argument (where a ``reset()`` without a ``start`` option begins):
    ``"S"``, ``"random"`` or a free state that reaches the goal."""
    if isinstance(start, str):
        if start not in ("S", "random"):
            raise ValueError(f"start must be 'S', 'random' or a state index, got {start!r}")
        return start
    return start_state(start, model, "start")


def start_state_from_options(options: dict[str, Any] | None, model: Any,
                             np_random: np.random.Generator, default: str | int = "S") -> int:
    """Resolve ``reset(options={"start": ...})``: ``"S"``, ``"random"`` or a state; without
    the option, ``default`` (the env's ``start=`` argument, ``"S"`` unless given).

    ``"random"`` draws uniformly from the free cells that reach the goal, with
    the env's own generator (seeded by ``reset(seed=...)``). Training from random starts
    is the paper's protocol; ``start="random"`` gives it to clients (Stable-Baselines3's
    autoresets) that call ``reset()`` without options.
    """
    start = (options or {}).get("start", default)
    if isinstance(start, str):
        if start == "S":
            return int(model.start)
        if start == "random":
            return int(model.start_states[np_random.integers(len(model.start_states))])
        raise ValueError(f"options['start'] must be 'S', 'random' or a state index, got {start!r}")
    return start_state(start, model, "options['start']")


def starts_option(starts: Any, mask: np.ndarray, model: Any) -> np.ndarray:
    """A vector env's ``reset(options={"starts": ...})``: int64[num_envs], a start state per
    sub-env (``len(mask)`` integers; floats are refused, not truncated), each entry ``mask``
    resets a free state that reaches the goal (:func:`start_state`; the others are not read).
    """
    n = len(mask)
    try:
        a = np.asarray(starts)
    except (TypeError, ValueError):  # a ragged list
        a = np.asarray(None)
    if a.dtype.kind not in INTEGER_KINDS or a.shape != (n,):
        raise ValueError(f"options['starts'] must be {n} integer states (int[{n}], one per "
                         f"sub-env), got {starts!r}; pass e.g. np.full({n}, "
                         "env.unwrapped.model.start, dtype=np.int64)")
    for i in np.flatnonzero(mask):
        start_state(a[i], model, f"options['starts'][{i}]")
    return a.astype(np.int64)


class GridRouteEnv(SpecOwnLimit, gym.Env):
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
    ``goal`` for entering G, ``bump`` for a move into an obstacle, a blocked cell or a
    wall (the agent stays), ``step`` for any other move, from the scheme ``rewards``
    names. Made by id (``gymnasium.make``, ``make_vec``) the scheme is ``goal-only``
    (+100, -1, 0): with the paper's +1 per free step a deep-RL learner at gamma = 0.99
    learns to wander (600 free steps pay more than G). ``rewards="paper"`` is the paper's
    scheme; ``rewards="scenario"`` the scenario's own ``[rewards]`` table (the default
    when the class is built directly, as the CLI's runs do).

    ## Starting State
    S, or with ``reset(options={"start": "random"})`` a uniformly drawn free
    cell that reaches G; ``{"start": s}`` starts at state ``s``. ``start=`` at
    construction sets what a ``reset()`` without the option does (``"random"``: the
    paper's training protocol, for clients that reset without options).

    ## Episode End
    Terminated on entering G. Truncated after the scenario's ``steps_per_episode`` moves
    (600 for the paper's maps, 1704 for ``ost003d``), or ``steps_per_episode`` if given.
    ``gymnasium.make(..., max_episode_steps=n)`` adds a ``TimeLimit`` on top.

    ## Info
    ``state`` (int, the cell, as the observation) and ``bumped`` (bool, the move hit
    something and the agent stayed); the same keys after ``reset`` and in vector envs.

    ## Arguments
    ``scenario``: a built-in name, a ``.toml`` path, a :class:`Scenario` (or its fields
    as a dict, what a spec's JSON round trip leaves).
    ``rewards``: ``"scenario"``, ``"paper"``, ``"goal-only"``, ``"step-cost"``,
    ``"goal=100,bump=-1,step=0"`` or a :class:`Rewards`.
    ``steps_per_episode``: moves per episode (default: the scenario's).
    ``start``: ``"S"``, ``"random"`` or a state, for resets without a ``start`` option.
    ``render_mode``: ``None`` or ``"rgb_array"`` (map, agent and its path).
    ``env.unwrapped.model`` is the :class:`sim.grid.TabularModel` of the scheme it pays.

    ``gymnasium.make("rnhql/GridRoute-v0", scenario="rooms-102", rewards="paper")``
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012

    def __init__(self, scenario: str | Scenario = "paper-50",
                 render_mode: str | None = None, rewards: str | Rewards = SCENARIO_REWARDS,
                 steps_per_episode: int | None = None, start: str | int = "S") -> None:
        self.scenario = env_scenario(scenario, rewards)
        self.rewards = self.scenario.rewards
        self.steps_per_episode = episode_limit(steps_per_episode,
                                               self.scenario.steps_per_episode)
        self.model = build_model(self.scenario)
        self.start = check_start(start, self.model)
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
        self._elapsed = 0
        self._started = False
        self._path: list[int] = []
        self._canvas: MapCanvas | None = None

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[int, dict[str, Any]]:
        super().reset(seed=seed)
        self._s = start_state_from_options(options, self.model, self.np_random, self.start)
        self._path = [self._s]
        self._elapsed = 0
        self._started = True
        return self._s, {"state": self._s, "bumped": False}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        if action.__class__ is not int or not 0 <= action < 4:  # the fast path takes ints
            action = discrete_action(action, 4)
        if not self._started:
            raise gym.error.ResetNeeded("call reset() before step()")
        s = self._s
        ns = self._next[s][action]
        self._s = ns
        self._elapsed += 1
        if self.render_mode is not None:
            self._path.append(ns)
        return (ns, self._reward[s][action], ns == self._goal,
                self._elapsed >= self.steps_per_episode, {"state": ns, "bumped": ns == s})

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


class GridVectorEnv(gym.vector.SyncVectorEnv):
    """N :class:`GridRouteEnv` stepped in turn (gymnasium's ``SyncVectorEnv``), whose batch
    of actions is checked as the physics vector envs check theirs
    (:func:`sim.env_args.discrete_actions`: integers, not floats or objects cast to them)."""

    def step(self, actions: Any) -> tuple[Any, ...]:
        return super().step(discrete_actions(actions, 4, self.num_envs))


def grid_vector_env(num_envs: int, **kwargs: Any) -> gym.vector.SyncVectorEnv:
    """``gymnasium.make_vec("rnhql/GridRoute-v0", num_envs=N)``: N grid envs stepped in turn,
    N bounded as the physics vector envs bound theirs (100,000 copies once ran out of
    memory instead of refusing)."""
    num_envs = check_num_envs(num_envs)
    vector = {k: kwargs.pop(k) for k in ("autoreset_mode", "copy", "observation_mode")
              if k in kwargs}
    return GridVectorEnv([lambda: GridRouteEnv(**kwargs)] * num_envs, **vector)
