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

from sim.feasibility import validate
from sim.grid import build_model
from sim.grid.discretiser import Discretiser
from sim.grid.env import start_state_from_options
from sim.physics.batch import RobotView, RouteBatch
from sim.physics.controller import DriveLimits, rate_limit, wheels_to_twist, wrap_angle
from sim.physics.fidelity import Fidelity, parse_fidelity
from sim.physics.world import PhysicsConfig, PhysicsWorld, SharedSpace
from sim.render import AGENT, PATH, MapCanvas
from sim.scenario import Scenario
from sim.scenario_io import resolve_scenario

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
    if isinstance(scenario, Scenario):
        validate(scenario)
        return scenario
    return resolve_scenario(scenario)


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
    2 cm / 2 degrees, or a timeout). A contact aborts the primitive and the
    robot is placed back, at rest, on the centre of the cell it started from.

    ## Action Space
    ``Discrete(4)``: 0 up (+y), 1 down (-y), 2 left (-x), 3 right (+x).

    ## Observation Space
    ``Discrete(nx * ny)``: the cell ``iy * nx + ix`` that the robot's measured
    pose lies in (``Discretiser.state_of``), as in ``rnhql/GridRoute-v0``.

    ## Reward
    The scenario's scheme: ``goal`` (+100) when the primitive ends in the goal
    cell; ``bump`` (-1) when a contact began during it (a move into an
    obstacle, a blocked cell or out of the arena always makes one; the robot
    stays); ``step`` (+1) otherwise. Grid cells that are blocked only for the
    *inflated* robot may be entered when the real disc fits: physics decides.
    (A primitive that times out without a contact, never seen with the
    default config, also gets ``step``, in whatever cell the robot is.)

    ## Starting State
    The centre of S heading +x, or with ``reset(options={"start": "random"})`` a
    uniformly drawn free cell that reaches G; ``{"start": s}`` starts at state s.

    ## Episode End
    Terminated on entering G. Truncated by ``TimeLimit`` after
    ``max_episode_steps`` (600 as registered).

    ## Info
    ``pose`` (x [m], y [m], heading [rad] in [-pi, pi)), ``time_s`` (simulated
    since reset), ``contacts`` (:class:`sim.physics.Contact` records that
    began during the primitive), ``bumped``, ``reached``, ``timeout``,
    ``steps`` (physics steps) and ``trajectory``: float64[n, 3], the start
    pose then the pose after every physics step.

    ## Arguments
    ``scenario``: a built-in name, a ``.toml`` path or a :class:`Scenario`.
    ``render_mode``: ``None`` or ``"rgb_array"`` (map, trail, robot, contacts).
    ``config``: a :class:`sim.physics.PhysicsConfig` (time step, tolerances).
    ``env.unwrapped.model`` is the grid's :class:`sim.grid.TabularModel`.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012

    def __init__(self, scenario: str | Scenario = "paper-50", render_mode: str | None = None,
                 config: PhysicsConfig | None = None,
                 fidelity: Fidelity | str | None = None) -> None:
        self.scenario = _scenario(scenario)
        self.fidelity = (fidelity if isinstance(fidelity, Fidelity)
                         else parse_fidelity(fidelity if fidelity is not None
                                             else self.scenario.physics, "fidelity"))
        self._noise_rng: np.random.Generator | None = None
        self.model = build_model(self.scenario)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self.config = config or PhysicsConfig()
        self.config.validate()
        self.observation_space = spaces.Discrete(self.model.n_states)
        self.action_space = spaces.Discrete(4)
        self.disc = Discretiser.from_scenario(self.scenario)
        self._goal = self.model.goal
        self.world: RobotView | None = None
        self._batch: RouteBatch | None = None
        self._action = np.zeros(1, dtype=np.int64)
        self._s = self.model.start
        self._trail: _Trail | None = None

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[int, dict[str, Any]]:
        super().reset(seed=seed)
        s = start_state_from_options(options, self.model, self.np_random)
        x, y = self.disc.state_centre(s)
        if self._batch is None:  # a batch of one robot: the same world as the vector env's
            self._batch = RouteBatch(self.scenario, 1, self.config, trajectories=True,
                                     fidelity=self.fidelity)
            self.world = RobotView(self._batch, 0)
        if self._noise_rng is None and (seed is not None or self._batch._noise_rngs[0] is None):
            self._batch.set_noise_rng(0, self.np_random)  # the env's own stream
        self._batch.place(0, x, y, 0.0)  # static shapes kept; the robot's state all new
        self._s = s
        pose = (x, y, 0.0)
        if self.render_mode is not None:
            if self._trail is None:
                self._trail = _Trail(self.scenario, self.model.blocked)
            self._trail.chunks = [np.array([pose])]
        return s, {"pose": pose, "time_s": 0.0, "contacts": (), "bumped": False,
                   "reached": True, "timeout": False, "steps": 0,
                   "trajectory": np.array([pose])}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        if not (action.__class__ is int or isinstance(action, np.integer)) or not 0 <= action < 4:
            raise AssertionError(f"{action!r} ({type(action)}) invalid")
        batch = self._batch
        if batch is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        self._action[0] = action
        n_before = len(batch.contacts[0])
        out = batch.step(self._action)
        s = int(out.state[0])
        self._s = s
        bumped = bool(out.bumped[0])
        reward = float(self.scenario.rewards.of_moves(bumped, s == self._goal))
        traj = batch.trajectory(0)
        if self._trail is not None:
            self._trail.chunks.append(traj)
        x, y, th = batch.pose(0)
        info = {"pose": (x, y, wrap_angle(th)), "time_s": batch.time_s(0),
                "contacts": tuple(batch.contacts[0][n_before:]), "bumped": bumped,
                "reached": bool(out.reached[0]), "timeout": bool(out.timeout[0]),
                "steps": int(out.steps[0]), "trajectory": traj}
        return s, reward, s == self._goal, False, info

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
    ``v_max`` = ``robot.max_wheel_speed_m_s``.

    ## Observation Space
    ``Box((8,), float32)``: x, y [m]; cos, sin of the heading; forward speed
    [m/s] and yaw rate [rad/s] (measured, clipped to the wheel limits); goal
    centre minus position, x and y [m] (world frame).

    ## Reward
    Per control period, the scenario's scheme applied to what happened:
    ``goal`` when the robot's cell is G (terminates); else ``bump`` for every
    period spent in contact (a contact began during it, or the disc still
    touches a wall, obstacle or blocked cell at its end: pushing into a wall
    keeps costing); else ``step`` if the robot changed cell; else 0.

    ## Starting State
    As ``PhysicsRoute-v0`` (``options={"start": ...}``), heading +x unless
    ``options={"heading": rad}``.

    ## Episode End
    Terminated when the robot's centre enters the goal cell. Truncated by
    ``TimeLimit`` after ``max_episode_steps`` (2000 periods = 200 s as registered).

    ## Arguments
    ``scenario``: a built-in name, a ``.toml`` path or a :class:`Scenario`.
    ``render_mode``: ``None`` or ``"rgb_array"``. ``config``: a
    :class:`sim.physics.PhysicsConfig` (``substeps`` physics steps per action).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012

    def __init__(self, scenario: str | Scenario = "paper-50", render_mode: str | None = None,
                 config: PhysicsConfig | None = None, shared: SharedSpace | None = None) -> None:
        self.scenario = sc = _scenario(scenario)
        self._shared = shared  # the vector env's Space (None: a Space of its own)
        self.model = build_model(sc)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self.config = config or DIFFDRIVE_CONFIG
        self.config.validate()
        self.limits = lim = DriveLimits.from_robot(sc.robot)
        self.disc = Discretiser.from_scenario(sc)
        vmax = np.float32(lim.v_max_m_s)
        self.action_space = spaces.Box(-vmax, vmax, shape=(2,), dtype=np.float32)
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
        s = start_state_from_options(options, self.model, self.np_random)
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
        if self.render_mode is not None:
            if self._trail is None:
                self._trail = _Trail(self.scenario, self.model.blocked)
            self._trail.chunks = [np.array([(x, y, heading)])]
        return self._obs(), {"pose": (x, y, heading), "time_s": 0.0, "state": s,
                             "contacts": (), "trajectory": np.array([(x, y, heading)])}

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
        assert self.action_space.contains(action), f"{action!r} ({type(action)}) invalid"
        world = self.world
        if world is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        self._target = (float(action[0]), float(action[1]))
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
        contacts = tuple(world.contacts[self._contacts_before:])
        terminated = cell == self.model.goal
        rw = self.scenario.rewards
        in_contact = bool(contacts) or world.touching()
        if terminated:
            reward = rw.goal
        elif in_contact:
            reward = rw.bump
        elif cell != self._cell:
            reward = rw.step
        else:
            reward = 0.0
        self._cell = cell
        arr = np.array(self._period_traj)
        if self._trail is not None:
            self._trail.chunks.append(arr)
        info = {"pose": (x, y, wrap_angle(th)), "time_s": world.time_s, "state": cell,
                "contacts": contacts, "in_contact": in_contact, "wheels": (vl, vr),
                "trajectory": arr}
        return self._obs(), float(reward), terminated, False, info

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array" or self.world is None or self._trail is None:
            return None
        return self._trail.draw(self.world.pose, self.world.contacts)
