"""Gymnasium env ``rnhql/DiffDrive-v0``: the diff-drive robot of the route problem with
the wheels handed to the agent (no primitives), in the same Pymunk world.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from sim.env_args import (
    SCENARIO_REWARDS,
    SpecOwnLimit,
    box_action,
    config_arg,
    env_scenario,
    episode_limit,
    fidelity_arg,
    finite_real,
)
from sim.grid import build_model
from sim.grid.discretiser import Discretiser
from sim.grid.env import check_start, start_state_from_options
from sim.physics.drive_profiles import DriveLimits, rate_limit
from sim.physics.envs.parts import Trail, info_pose
from sim.physics.fidelity import Fidelity
from sim.physics.motion import wheels_to_twist
from sim.physics.reference.world import PhysicsConfig, PhysicsWorld, SharedSpace
from sim.physics.static import Contact
from sim.scenario import Rewards, Scenario

# DiffDrive: 4 physics steps of 25 ms per 0.1 s control period, and Chipmunk's default
# positional correction (nothing is ever placed there; contacts persist while the agent
# pushes, so overlaps are pushed out instead of only being bounded).
DIFFDRIVE_CONFIG = PhysicsConfig(dt_s=0.025, substeps=4, collision_bias=(1.0 - 0.1) ** 60)


def diffdrive_periods(sc: Scenario, config: PhysicsConfig) -> int:
    """DiffDrive's episode length [control periods] from the scenario's ``steps_per_episode``
    [moves]: the time to drive that many cells straight at full wheel speed. (A move on the
    grid is one cell; the budget in time is what lets the same scenario bound both.)"""
    seconds = sc.steps_per_episode * sc.cell_size_m / sc.robot.max_wheel_speed_m_s
    return max(1, math.ceil(seconds / config.control_period_s - 1e-9))


class DiffDriveEnv(SpecOwnLimit, gym.Env):
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
        fid = self.fidelity
        if fid.biased or fid.open_loop or fid.localisation or fid.latency or fid.slips:
            raise ValueError(
                f"fidelity {fid.label}: DiffDrive-v0 takes wheel speeds, so the bias, "
                "open-loop, localisation, latency and slip knobs (which act on motion "
                "primitives and what plans them) do not apply; use wheel_noise here, or "
                "PhysicsRoute-v0")
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
        self._trail: Trail | None = None

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
        heading = finite_real((options or {}).get("heading", 0.0), "options['heading']",
                              "pass the start heading in radians, e.g. {'heading': 1.5708}")
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
                self._trail = Trail(self.scenario, self.model.blocked)
            self._trail.chunks = [np.array([(x, y, heading)])]
        return self._obs(), {"state": s, "bumped": False, "in_contact": False, "contacts": 0,
                             "pose": info_pose(x, y, heading), "time_s": 0.0,
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
        in_contact = began > 0 or world.touching()
        reward = self.rewards.of_moves(in_contact, terminated, cell != self._cell)
        self._cell = cell
        self._elapsed += 1
        if self._trail is not None:
            self._trail.chunks.append(np.array(self._period_traj))
        info = {"state": cell, "bumped": began > 0, "in_contact": in_contact,
                "contacts": began, "pose": info_pose(x, y, th), "time_s": world.time_s,
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
