"""Gymnasium envs over the Pymunk world: ``rnhql/PhysicsRoute-v0`` and ``rnhql/DiffDrive-v0``.

``PhysicsRouteEnv`` is the grid route problem driven for real: same spaces,
same reward scheme, same ``reset`` options as :class:`sim.grid.env.GridRouteEnv`,
but every action is a motion primitive (:mod:`sim.physics.controller`) and the next state is
the cell the robot's measured pose lies in. ``DiffDriveEnv`` hands the wheels to
the agent. Both keep one :class:`sim.physics.PhysicsWorld` and respawn the robot
per reset (the static shapes are built once; replays equal a fresh world, tested).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from sim.env_args import (
    SCENARIO_REWARDS,
    box_action,
    config_arg,
    discrete_action,
    env_scenario,
    episode_limit,
    fidelity_arg,
    scenario_arg,
)
from sim.grid import build_model
from sim.grid.discretiser import Discretiser
from sim.grid.env import check_start, start_state_from_options
from sim.physics.batch import RobotView, RouteBatch
from sim.physics.controller import DriveLimits, rate_limit, wheels_to_twist, wrap_angle
from sim.physics.fidelity import Fidelity
from sim.physics.static import Contact
from sim.physics.world import PhysicsConfig, PhysicsWorld, SharedSpace
from sim.render import AGENT, PATH, MapCanvas
from sim.scenario import Rewards, Scenario

# DiffDrive: 4 physics steps of 25 ms per 0.1 s control period, and Chipmunk's default
# positional correction (nothing is ever placed there; contacts persist while the agent
# pushes, so overlaps are pushed out instead of only being bounded).
DIFFDRIVE_CONFIG = PhysicsConfig(dt_s=0.025, substeps=4, collision_bias=(1.0 - 0.1) ** 60)
CONTACT = (240, 140, 0)


def _scenario(scenario: str | Scenario) -> Scenario:
    """Resolve a name/path (validated on load) or validate a given :class:`Scenario`.

    A physics world cannot be built for a robot that does not fit its cells,
    so bad input stops here with a :class:`sim.errors.ScenarioError`.
    """
    return scenario_arg(scenario)


def diffdrive_periods(sc: Scenario, config: PhysicsConfig) -> int:
    """DiffDrive's episode length [control periods] from the scenario's ``steps_per_episode``
    [moves]: the time to drive that many cells straight at full wheel speed. (A move on the
    grid is one cell; the budget in time is what lets the same scenario bound both.)"""
    seconds = sc.steps_per_episode * sc.cell_size_m / sc.robot.max_wheel_speed_m_s
    return max(1, math.ceil(seconds / config.control_period_s - 1e-9))


def _pose(x: float, y: float, th: float) -> np.ndarray:
    """An info ``pose``: float64[3] (x [m], y [m], heading [rad] in [-pi, pi))."""
    return np.array((x, y, wrap_angle(th)))


class _Trail:
    """Render helper: the map, a trail of substep positions, the robot and its heading."""

    def __init__(self, sc: Scenario, blocked: np.ndarray) -> None:
        self.canvas = MapCanvas(sc, blocked)
        self.sc = sc
        self.chunks: list[np.ndarray] = []

    def draw(self, pose: tuple[float, float, float], contacts: list[Any]) -> np.ndarray:
        cv = self.canvas
        img = cv.background.copy()
        if self.chunks:
            pts = np.concatenate(self.chunks)[:, :2]
            cols = np.clip((pts[:, 0] * cv.px_per_m).astype(int), 0, cv.w - 1)
            rows = np.clip(((self.sc.height_m - pts[:, 1]) * cv.px_per_m).astype(int), 0,
                           cv.h - 1)
            img[rows, cols] = PATH
        for c in contacts[-50:]:
            cv.disc(img, c.x_m, c.y_m, 0.6 / cv.px_per_m, CONTACT)
        x, y, th = pose
        r = max(self.sc.robot.radius_m, 3.0 / cv.px_per_m)  # visible at any scale
        cv.disc(img, x, y, r, AGENT)
        cv.polyline(img, np.array([[x, y], [x + r * math.cos(th), y + r * math.sin(th)]]),
                    (255, 255, 255))
        return img


class PhysicsRouteEnv(gym.Env):
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
        self._trail: _Trail | None = None

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
                self._trail = _Trail(self.scenario, self.model.blocked)
            self._trail.chunks = [np.array([pose])]
        return s, {"state": s, "bumped": False, "reached": True, "timeout": False,
                   "steps": 0, "contacts": 0, "pose": _pose(*pose), "time_s": 0.0}

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
        reward = float(self.rewards.of_moves(bumped, s == self._goal))
        if self._trail is not None:
            self._trail.chunks.append(batch.trajectory(0))
        info = {"state": s, "bumped": bumped, "reached": bool(out.reached[0]),
                "timeout": bool(out.timeout[0]), "steps": int(out.steps[0]),
                "contacts": len(batch.contacts[0]) - n_before,
                "pose": _pose(*batch.pose(0)), "time_s": batch.time_s(0)}
        return s, reward, s == self._goal, self._elapsed >= self.steps_per_episode, info

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


class DiffDriveEnv(gym.Env):
    """Continuous control of the diff-drive robot: wheel speeds in, pose out.

    ## Description
    The robot of ``rnhql/PhysicsRoute-v0`` without primitives: the agent sets
    the two wheel rim speeds, held for one control period (0.1 s by default:
    4 physics steps of 25 ms). Each physics step the wheels move towards the
    command by at most ``max_wheel_accel * dt`` (the scenario's limits), and
    the robot keeps driving into or along whatever it touches.

    ## Action Space
    ``Box(-v_max, v_max, (2,), float32)``: left and right wheel speed [m/s],
    ``v_max`` = ``robot.max_wheel_speed_m_s``. Any real dtype is accepted (float64 is
    what numpy and most clients hand over); a command beyond ``v_max`` drives at
    ``v_max`` (clipped, as a motor would); a non-finite one is an error.

    ## Observation Space
    ``Box((8,), float32)``: x, y [m]; cos, sin of the heading; forward speed
    [m/s] and yaw rate [rad/s] (measured, clipped to the wheel limits); goal
    centre minus position, x and y [m] (world frame).

    ## Reward
    Per control period, from the scheme ``rewards`` names: ``goal`` when the robot's
    cell is G (terminates); else ``bump`` for every period spent in contact (a contact
    began during it, or the disc still touches a wall, obstacle or blocked cell at its
    end: pushing into a wall keeps costing); else ``step`` if the robot changed cell;
    else 0. Made by id the scheme is ``goal-only`` (+100, -1, 0): with ``step`` > 0 a
    policy learns to drive in circles across cell borders (every change pays, revisits
    included). ``rewards="paper"`` is the paper's, ``rewards="scenario"`` the scenario's
    own (the default when the class is built directly).

    ## Starting State
    As ``PhysicsRoute-v0`` (``options={"start": ...}``), heading +x unless
    ``options={"heading": rad}``.

    ## Episode End
    Terminated when the robot's centre enters the goal cell. Truncated after
    ``steps_per_episode`` control periods; by default the time to drive the scenario's
    ``steps_per_episode`` cells straight at full wheel speed (paper-50: 600 cells of
    1 m at 1 m/s, 6000 periods of 0.1 s).

    ## Fidelity
    ``fidelity`` (default: the scenario's ``[physics]`` table, else ``exact``): its
    ``wheel_noise`` multiplies each wheel's command by ``1 + wheel_noise * e`` every
    control period (``e`` standard normal from the env's generator, seeded by
    ``reset(seed=...)``), the rule the primitives use. ``carried_pose`` and
    ``bumper_travel_m`` shape how a *primitive* ends at a contact; DiffDrive has no
    primitives and nothing ever places the robot back, so they do not apply.

    ## Info
    The same keys after ``reset`` and ``step``, and in every vector form: ``state`` (int,
    the cell the pose lies in), ``bumped`` (a contact began this period), ``in_contact``
    (what the reward read), ``contacts`` (int, how many began), ``pose`` (float64[3]: x
    [m], y [m], heading [rad] in [-pi, pi)), ``time_s`` (simulated since reset) and
    ``wheels`` (float64[2], the wheel speeds reached [m/s]). :meth:`trajectory` is the
    period's pose after each physics step; :meth:`contact_records` the records.

    ## Arguments
    ``scenario``, ``rewards``, ``fidelity``, ``start`` as ``PhysicsRoute-v0``.
    ``steps_per_episode``: control periods per episode. ``render_mode``: ``None`` or
    ``"rgb_array"``. ``config``: a :class:`sim.physics.PhysicsConfig` (``substeps``
    physics steps per action).

    ``gymnasium.make("rnhql/DiffDrive-v0", scenario="paper-40", steps_per_episode=500)``
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012

    def __init__(self, scenario: str | Scenario = "paper-50", render_mode: str | None = None,
                 config: PhysicsConfig | None = None, shared: SharedSpace | None = None,
                 fidelity: Fidelity | str | None = None,
                 rewards: str | Rewards = SCENARIO_REWARDS,
                 steps_per_episode: int | None = None, start: str | int = "S") -> None:
        self.scenario = sc = env_scenario(scenario, rewards)
        self.rewards = sc.rewards
        self.fidelity = fidelity_arg(fidelity, sc)
        self._shared = shared  # the vector env's Space (None: a Space of its own)
        self.model = build_model(sc)
        self.start = check_start(start, self.model)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self.config = config_arg(config, DIFFDRIVE_CONFIG)
        self.steps_per_episode = episode_limit(steps_per_episode,
                                               diffdrive_periods(sc, self.config))
        self.limits = lim = DriveLimits.from_robot(sc.robot)
        self.disc = Discretiser.from_scenario(sc)
        vmax = np.float32(lim.v_max_m_s)
        self.action_space = spaces.Box(-vmax, vmax, shape=(2,), dtype=np.float32)
        self._act_low = self.action_space.low.astype(np.float64)
        self._act_high = self.action_space.high.astype(np.float64)
        w, h, wmax = sc.width_m, sc.height_m, lim.omega_max_rad_s
        self._obs_low = np.array([0, 0, -1, -1, -vmax, -wmax, -w, -h], dtype=np.float32)
        self._obs_high = np.array([w, h, 1, 1, vmax, wmax, w, h], dtype=np.float32)
        self.observation_space = spaces.Box(self._obs_low, self._obs_high, dtype=np.float32)
        self.goal_xy = self.disc.cell_centre(*sc.goal)
        self.world: PhysicsWorld | None = None
        self._wheels = (0.0, 0.0)
        self._target = (0.0, 0.0)  # wheel speeds commanded for this period [m/s]
        self._period_traj: list[tuple[float, float, float]] = []
        self._contacts_before = 0
        self._cell = self.model.start
        self._elapsed = 0
        self._trail: _Trail | None = None

    def _obs(self) -> np.ndarray:
        assert self.world is not None
        x, y, th = self.world.pose
        vx, vy, om = self.world.velocity
        c, s = math.cos(th), math.sin(th)
        obs = np.array([x, y, c, s, vx * c + vy * s, om, self.goal_xy[0] - x,
                        self.goal_xy[1] - y], dtype=np.float32)
        return np.clip(obs, self._obs_low, self._obs_high)

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        s = start_state_from_options(options, self.model, self.np_random, self.start)
        heading = float((options or {}).get("heading", 0.0))
        if not math.isfinite(heading):
            raise ValueError(f"options['heading'] must be finite, got {heading!r}")
        x, y = self.disc.state_centre(s)
        if self.world is None:
            self.world = PhysicsWorld(self.scenario, self.config, (x, y, heading),
                                      shared=self._shared)
        else:
            self.world.respawn((x, y, heading))
        self._wheels = (0.0, 0.0)
        self._cell = s
        self._elapsed = 0
        self._period_traj = [(x, y, heading)]
        if self.render_mode is not None:
            if self._trail is None:
                self._trail = _Trail(self.scenario, self.model.blocked)
            self._trail.chunks = [np.array([(x, y, heading)])]
        return self._obs(), {"state": s, "bumped": False, "in_contact": False, "contacts": 0,
                             "pose": _pose(x, y, heading), "time_s": 0.0,
                             "wheels": np.zeros(2)}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        self.begin_period(action)
        world = self.world
        assert world is not None
        for _ in range(self.config.substeps):
            self.command_substep()
            world._fn[0](world._S, self.config.dt_s)
            world.after_step(self._period_traj)
        return self.end_period()

    # One control period in three parts, so the vector env can step many robots' worlds
    # in one shared Space between the second and the third: begin_period, then per
    # physics step command_substep / (the Space steps) / world.after_step, then end_period.
    def begin_period(self, action: np.ndarray) -> None:
        a = box_action(action, self._act_low, self._act_high)
        world = self.world
        if world is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        left, right = float(a[0]), float(a[1])
        sigma = self.fidelity.wheel_noise
        if sigma > 0.0:  # the wheels deliver the command with a gain error (see ## Fidelity)
            e = self.np_random.standard_normal(2)
            left, right = left * (1.0 + sigma * e[0]), right * (1.0 + sigma * e[1])
        self._target = (left, right)
        self._period_traj = [world.pose]
        self._contacts_before = len(world.contacts)

    def command_substep(self) -> None:
        """Move the wheels towards the command, set the control body's twist, clamp the step."""
        world, lim = self.world, self.limits
        assert world is not None
        dv = lim.a_max_m_s2 * self.config.dt_s
        vl, vr = self._wheels
        vl, vr = rate_limit(vl, self._target[0], dv), rate_limit(vr, self._target[1], dv)
        self._wheels = (vl, vr)
        v, om = wheels_to_twist(vl, vr, lim.wheel_base_m)
        th = world.pose[2]
        world.set_twist(v * math.cos(th), v * math.sin(th), om)
        world.before_step()

    def end_period(self) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        world = self.world
        assert world is not None
        vl, vr = self._wheels
        x, y, th = world.pose
        cell = self.disc.state_of(x, y)
        began = len(world.contacts) - self._contacts_before
        terminated = cell == self.model.goal
        rw = self.rewards
        in_contact = began > 0 or world.touching()
        if terminated:
            reward = rw.goal
        elif in_contact:
            reward = rw.bump
        elif cell != self._cell:
            reward = rw.step
        else:
            reward = 0.0
        self._cell = cell
        self._elapsed += 1
        if self._trail is not None:
            self._trail.chunks.append(np.array(self._period_traj))
        info = {"state": cell, "bumped": began > 0, "in_contact": in_contact,
                "contacts": began, "pose": _pose(x, y, th), "time_s": world.time_s,
                "wheels": np.array((vl, vr))}
        return (self._obs(), float(reward), terminated,
                self._elapsed >= self.steps_per_episode, info)

    def trajectory(self) -> np.ndarray:
        """float64[n, 3]: the pose before the last control period, then after each physics
        step of it (x [m], y [m], heading [rad], not wrapped)."""
        return np.array(self._period_traj)

    def contact_records(self) -> list[Contact]:
        """Every contact that began since the last reset, in order."""
        return [] if self.world is None else list(self.world.contacts)

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array" or self.world is None or self._trail is None:
            return None
        return self._trail.draw(self.world.pose, self.world.contacts)
