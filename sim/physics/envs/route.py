"""Gymnasium env ``rnhql/PhysicsRoute-v0`` over the Pymunk world (``rnhql/DiffDrive-v0``,
the wheels handed to the agent, is :mod:`sim.physics.envs.diffdrive`).

``PhysicsRouteEnv`` is the grid route problem driven for real: same spaces,
same reward scheme, same ``reset`` options as :class:`sim.grid.env.GridRouteEnv`,
but every action is a motion primitive (:mod:`sim.physics.reference.controller`) and the
next state is the cell the robot's measured pose lies in. ``DiffDriveEnv`` hands the wheels to
the agent. Both keep one :class:`sim.physics.PhysicsWorld` and respawn the robot
per reset (the static shapes are built once; replays equal a fresh world, tested).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from sim.env_args import (
    SCENARIO_REWARDS,
    SpecOwnLimit,
    config_arg,
    discrete_action,
    env_scenario,
    episode_limit,
    fidelity_arg,
)
from sim.grid import build_model
from sim.grid.discretiser import Discretiser
from sim.grid.env import check_start, start_state_from_options
from sim.physics.envs.parts import Trail, info_pose
from sim.physics.fidelity import Fidelity
from sim.physics.kernel.batch import RobotView, RouteBatch
from sim.physics.reference.world import PhysicsConfig
from sim.physics.static import Contact
from sim.scenario import Rewards, Scenario


class PhysicsRouteEnv(SpecOwnLimit, gym.Env):
    """The grid route problem, each move driven by a diff-drive robot in Pymunk.

    ## Description
    A differential-drive disc robot (the scenario's radius, mass, wheel base
    and wheel limits) moves among the scenario's circular obstacles, blocked
    map cells and arena walls. Each action is a motion primitive: turn in place
    towards the centre of the neighbouring cell, drive there, stop (within
    2 cm / 2 degrees, or a timeout). At the ``exact`` fidelity a contact aborts the
    primitive and the robot is placed back, at rest, on the centre of the cell it started
    from; ``fidelity`` adds wheel noise and a robot that stays where a contact left it.

    ## Action Space
    ``Discrete(4)``: 0 up (+y), 1 down (-y), 2 left (-x), 3 right (+x). An int, a numpy
    integer or an integer array of one value (what ``model.predict`` returns).

    ## Observation Space
    ``Discrete(nx * ny)``: the cell ``iy * nx + ix`` that the robot's measured
    pose lies in (``Discretiser.state_of``), as in ``rnhql/GridRoute-v0``.

    ## Reward
    From the scheme ``rewards`` names: ``goal`` when the primitive ends in the goal
    cell; ``bump`` when a contact began during it (a move into an obstacle, a blocked
    cell or out of the arena always makes one; the robot stays); ``step`` otherwise.
    Made by id (``gymnasium.make``, ``make_vec``) the scheme is ``goal-only`` (+100, -1,
    0), so a deep-RL learner is not paid to wander; ``rewards="paper"`` is the paper's
    (+1 per free step), ``rewards="scenario"`` the scenario's own (the default when the
    class is built directly). Grid cells that are blocked only for the *inflated* robot
    may be entered when the real disc fits: physics decides.

    ## Starting State
    The centre of S heading +x, or with ``reset(options={"start": "random"})`` a
    uniformly drawn free cell that reaches G; ``{"start": s}`` starts at state s.
    ``start=`` at construction: what a ``reset()`` without the option does.

    ## Episode End
    Terminated on entering G. Truncated after the scenario's ``steps_per_episode``
    primitives (or ``steps_per_episode`` if given).

    ## Info
    The same keys after ``reset`` and ``step``, and in every vector form: ``state``
    (int, the cell), ``bumped`` (a contact began), ``reached`` (the primitive ended on
    its target), ``timeout``, ``steps`` (physics steps the primitive took), ``contacts``
    (int, how many contacts began), ``pose`` (float64[3]: x [m], y [m], heading [rad]
    in [-pi, pi)) and ``time_s`` (simulated since reset). The poses of the last
    primitive's physics steps are :meth:`trajectory`; the contact records since reset
    :meth:`contact_records`.

    ## Arguments
    ``scenario``: a built-in name, a ``.toml`` path, a :class:`Scenario` or its fields as
    a dict. ``rewards``: ``"scenario"``, a preset name, ``"goal=100,bump=-1,step=0"`` or a
    :class:`Rewards`. ``fidelity``: ``"exact"``, ``"noisy"``, ``"rough"``,
    ``"noisy,wheel_noise=0.1"`` or a :class:`Fidelity` (default: the scenario's
    ``[physics]`` table, else ``exact``). ``steps_per_episode``: primitives per episode.
    ``render_mode``: ``None`` or ``"rgb_array"`` (map, trail, robot, contacts).
    ``config``: a :class:`sim.physics.PhysicsConfig` (time step, tolerances).
    ``start``: ``"S"``, ``"random"`` or a state, for resets without a ``start`` option.
    ``env.unwrapped.model`` is the grid's :class:`sim.grid.TabularModel`.

    ``gymnasium.make("rnhql/PhysicsRoute-v0", scenario="rooms-102", fidelity="noisy")``
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012

    def __init__(self, scenario: str | Scenario = "paper-50", render_mode: str | None = None,
                 config: PhysicsConfig | None = None,
                 fidelity: Fidelity | str | None = None,
                 rewards: str | Rewards = SCENARIO_REWARDS,
                 steps_per_episode: int | None = None, start: str | int = "S") -> None:
        self.scenario = env_scenario(scenario, rewards)
        self.rewards = self.scenario.rewards
        self.steps_per_episode = episode_limit(steps_per_episode,
                                               self.scenario.steps_per_episode)
        self.fidelity = fidelity_arg(fidelity, self.scenario)
        self._noise_rng: np.random.Generator | None = None
        self.model = build_model(self.scenario)
        self.start = check_start(start, self.model)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self.config = config_arg(config, PhysicsConfig())
        self.observation_space = spaces.Discrete(self.model.n_states)
        self.action_space = spaces.Discrete(4)
        self.disc = Discretiser.from_scenario(self.scenario)
        self._goal = self.model.goal
        self.world: RobotView | None = None
        self._batch: RouteBatch | None = None
        self._action = np.zeros(1, dtype=np.int64)
        self._s = self.model.start
        self._elapsed = 0
        self._trail: Trail | None = None

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[int, dict[str, Any]]:
        super().reset(seed=seed)
        s = start_state_from_options(options, self.model, self.np_random, self.start)
        x, y = self.disc.state_centre(s)
        if self._batch is None:  # a batch of one robot: the same world as the vector env's
            self._batch = RouteBatch(self.scenario, 1, self.config, trajectories=True,
                                     fidelity=self.fidelity)
            self.world = RobotView(self._batch, 0)
        if self._noise_rng is None and (seed is not None or self._batch._noise_rngs[0] is None):
            self._batch.set_noise_rng(0, self.np_random)  # the env's own stream
        self._batch.place(0, x, y, 0.0)  # static shapes kept; the robot's state all new
        self._s = s
        self._elapsed = 0
        pose = (x, y, 0.0)
        if self.render_mode is not None:
            if self._trail is None:
                self._trail = Trail(self.scenario, self.model.blocked)
            self._trail.chunks = [np.array([pose])]
        return s, {"state": s, "bumped": False, "reached": True, "timeout": False,
                   "steps": 0, "contacts": 0, "pose": info_pose(*pose), "time_s": 0.0}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        action = discrete_action(action, 4)
        batch = self._batch
        if batch is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        self._action[0] = action
        n_before = len(batch.contacts[0])
        out = batch.step(self._action)
        s = int(out.state[0])
        self._s = s
        self._elapsed += 1
        bumped = bool(out.bumped[0])
        at_goal = int(out.cell[0]) == self._goal  # the true cell (s: the believed one)
        reward = float(self.rewards.of_moves(bumped, at_goal))
        if self._trail is not None:
            self._trail.chunks.append(batch.trajectory(0))
        info = {"state": s, "bumped": bumped, "reached": bool(out.reached[0]),
                "timeout": bool(out.timeout[0]), "steps": int(out.steps[0]),
                "contacts": len(batch.contacts[0]) - n_before,
                "pose": info_pose(*batch.pose(0)), "time_s": batch.time_s(0)}
        return s, reward, at_goal, self._elapsed >= self.steps_per_episode, info

    def trajectory(self) -> np.ndarray:
        """float64[n, 3]: the pose before the last primitive, then after each physics step
        of it (x [m], y [m], heading [rad], not wrapped)."""
        if self._batch is None:
            raise gym.error.ResetNeeded("call reset() before trajectory()")
        return self._batch.trajectory(0)

    def contact_records(self) -> list[Contact]:
        """Every contact that began since the last reset, in order (the last step's are the
        last ``info["contacts"]``)."""
        return [] if self._batch is None else list(self._batch.contacts[0])

    def set_noise_rng(self, rng: np.random.Generator) -> None:
        """Draw the wheel noise from ``rng`` instead of the env's own stream (a sweep gives
        each run its own physics stream, see :func:`learning.streams.streams`)."""
        self._noise_rng = rng
        if self._batch is None:
            self._batch = RouteBatch(self.scenario, 1, self.config, trajectories=True,
                                     fidelity=self.fidelity)
            self.world = RobotView(self._batch, 0)
        self._batch.set_noise_rng(0, rng)

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array" or self.world is None or self._trail is None:
            return None
        return self._trail.draw(self.world.pose, self.world.contacts)


