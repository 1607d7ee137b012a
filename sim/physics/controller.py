"""Differential-drive kinematics and the controller that drives one grid action.

Pure part (no pymunk): wheel speeds <-> twist, angle wrapping, and minimal-time
*discrete* velocity profiles. The controller (:class:`PrimitiveController`)
turns a grid action into a motion primitive and drives it in a
:class:`sim.physics.PhysicsWorld`.

Why discrete profiles: the control loop updates the wheel commands once per
control period ``T``; a wheel may change speed by at most ``a_max * T`` between
two periods and never exceed ``v_max``. For a distance ``D`` the profile is the
fewest periods ``n`` whose largest admissible trapezoid covers ``D``, scaled
down uniformly so it covers ``D`` exactly (scaling keeps every limit). The
physics robot tracks the control body exactly while the joints' force limits
are not reached (see :mod:`sim.physics`), so in free space a primitive lands on
the cell centre to rounding error with no feedback; feedback is only needed
when something disturbed the robot, and the controller re-plans from the
measured pose in that case.

A primitive: turn in place to face the centre of the neighbouring cell (this
*is* the action's cardinal heading when the robot stands on its cell centre,
and it keeps the drive a straight line when it does not), stop, drive straight
to that centre, stop. It ends within ``tolerance_m`` / ``tolerance_rad`` of the
centre / the cardinal heading, at a contact, or at ``timeout_s``.

Return to start after a contact: the robot is *placed* back on the centre of
the cell it started from, at rest, keeping its heading, once the motion has
stopped. Driving back would retrace the segment it just drove (free by
construction up to the contact), doubling the cost of every bump without
telling the learner anything; the grid world's semantics ("the agent stays")
is what the placement reproduces. The space is not rebuilt: a placement is not
a reset, and the same action sequence still replays bit for bit.
"""

from __future__ import annotations

import math
from bisect import bisect_left
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

from sim.grid.actions import ACTION_DELTAS, ACTION_HEADINGS
from sim.grid.discretiser import Discretiser

if TYPE_CHECKING:
    from sim.physics.world import Contact, PhysicsConfig, PhysicsWorld
    from sim.scenario import Robot, Scenario

_STOP = (0.0, 0.0, 0.0)
# Turns smaller than this are skipped [rad]: after a drive the heading equals the
# bearing up to rounding (~1e-13 rad), and a "turn" of that size would still cost
# two control periods (command + stop).
MIN_TURN_RAD = 1e-9


# ------------------------------------------------------------------ kinematics


def wheels_to_twist(v_left_m_s: float, v_right_m_s: float,
                    wheel_base_m: float) -> tuple[float, float]:
    """Wheel rim speeds [m/s] -> (forward speed [m/s], yaw rate [rad/s])."""
    return 0.5 * (v_left_m_s + v_right_m_s), (v_right_m_s - v_left_m_s) / wheel_base_m


def twist_to_wheels(v_m_s: float, omega_rad_s: float,
                    wheel_base_m: float) -> tuple[float, float]:
    """(forward speed [m/s], yaw rate [rad/s]) -> (left, right) wheel rim speeds [m/s]."""
    half = 0.5 * omega_rad_s * wheel_base_m
    return v_m_s - half, v_m_s + half


def wrap_angle(a_rad: float) -> float:
    """Angle wrapped into [-pi, pi)."""
    return (a_rad + math.pi) % (2.0 * math.pi) - math.pi


def rate_limit(current: float, target: float, max_delta: float) -> float:
    """``target`` moved no further than ``max_delta`` from ``current``."""
    return min(max(target, current - max_delta), current + max_delta)


@dataclass(frozen=True)
class DriveLimits:
    """The robot's wheel limits and what they imply for pure drives and pure turns."""

    v_max_m_s: float  # wheel rim speed limit [m/s]
    a_max_m_s2: float  # wheel rim acceleration limit [m/s^2]
    wheel_base_m: float  # [m]

    @classmethod
    def from_robot(cls, robot: Robot) -> DriveLimits:
        return cls(robot.max_wheel_speed_m_s, robot.max_wheel_accel_m_s2, robot.wheel_base_m)

    @property
    def omega_max_rad_s(self) -> float:
        """Turn-in-place yaw rate limit (wheels at -v_max, +v_max) [rad/s]."""
        return 2.0 * self.v_max_m_s / self.wheel_base_m

    @property
    def alpha_max_rad_s2(self) -> float:
        """Turn-in-place yaw acceleration limit [rad/s^2]."""
        return 2.0 * self.a_max_m_s2 / self.wheel_base_m


# ------------------------------------------------------------- discrete profiles


class ProfileTable:
    """Minimal-period profiles for one speed limit and one per-period speed change.

    ``caps[n-1]`` is the largest admissible profile of ``n`` periods,
    ``u_k = min(v_max, k*dv, (n+1-k)*dv)`` (from rest, back to rest), and
    ``sums[n-1]`` its sum. Both are grown lazily and cached, so a profile costs
    a bisection and one scaled copy: no per-call search in the hot loop.
    """

    def __init__(self, v_max: float, dv: float) -> None:
        if not (v_max > 0 and dv > 0):
            raise ValueError(f"limits must be positive, got v_max={v_max}, dv={dv}")
        self.v_max, self.dv = v_max, dv
        self.caps: list[list[float]] = []
        self.sums: list[float] = []

    def _grow(self, total: float) -> None:
        while not self.sums or self.sums[-1] < total:
            n = len(self.caps) + 1
            caps = [min(self.v_max, k * self.dv, (n + 1 - k) * self.dv) for k in range(1, n + 1)]
            self.caps.append(caps)
            self.sums.append(math.fsum(caps))

    def profile(self, total: float) -> list[float]:
        """Speeds, one per period, summing to ``total`` (>= 0): distance / period."""
        if total <= 0.0:
            return []
        if not self.sums or self.sums[-1] < total:
            self._grow(total)
        n = bisect_left(self.sums, total)
        scale = total / self.sums[n]
        return [c * scale for c in self.caps[n]]


# ------------------------------------------------------------------ the primitive


class PrimitiveResult(NamedTuple):
    """What one motion primitive did (the env turns this into reward and info)."""

    state: int  # Discretiser.state_of the final pose
    bumped: bool  # a contact began; the robot was placed back on its start cell centre
    reached: bool  # ended within tolerance of the target centre and heading
    timeout: bool  # gave up at PhysicsConfig.timeout_s
    steps: int  # physics steps driven
    duration_s: float  # simulated time [s]
    contacts: tuple[Contact, ...]  # contacts that began during the primitive
    trajectory: list[tuple[float, float, float]]  # start pose, then the pose after each step


class PrimitiveController:
    """Drives grid actions as motion primitives; one per scenario and config, any world.

    The plan for one leg (turn, stop, drive, stop) is a list of control-body
    twists, one per control period, executed by :meth:`PhysicsWorld.drive` in
    one tight loop. Before a drive the world casts the robot's disc along the
    straight leg once; that is the time-of-impact guard that keeps a step from
    carrying the disc deeper than ``contact_depth_m`` into anything (Chipmunk
    has no continuous collision detection of its own). The profile tables are
    kept across worlds, so building one controller per env (not per episode)
    keeps their caches warm.
    """

    def __init__(self, scenario: Scenario, config: PhysicsConfig) -> None:
        self.disc = Discretiser.from_scenario(scenario)
        self.limits = lim = DriveLimits.from_robot(scenario.robot)
        self.config = config
        period = config.control_period_s
        self._period = period
        self._drive = ProfileTable(lim.v_max_m_s, lim.a_max_m_s2 * period)
        self._turn = ProfileTable(lim.omega_max_rad_s, lim.alpha_max_rad_s2 * period)
        self._tol_m = config.tolerance_m
        self._tol_rad = config.tolerance_rad
        self._timeout_steps = math.ceil(config.timeout_s / config.dt_s - 1e-9)

    def plan_leg(self, pose: tuple[float, float, float], target: tuple[float, float],
                 heading: float) -> tuple[list[tuple[float, float, float]], float]:
        """Twists (vx [m/s], vy [m/s], omega [rad/s]) per control period, and the drive length.

        Turns to face ``target`` and drives to it when it is further than the
        tolerance; otherwise only turns to ``heading``. Each motion ends with a
        zero twist: the step that stops the robot.
        """
        x, y, th = pose
        dx, dy = target[0] - x, target[1] - y
        dist = math.hypot(dx, dy)
        drive = dist > self._tol_m
        turn = wrap_angle((math.atan2(dy, dx) if drive else heading) - th)
        ws = self._turn.profile(abs(turn) / self._period) if abs(turn) > MIN_TURN_RAD else []
        if turn < 0.0:
            cmds = [(0.0, 0.0, -w) for w in ws]
        else:
            cmds = [(0.0, 0.0, w) for w in ws]
        if cmds:
            cmds.append(_STOP)
        if not drive:
            return cmds, 0.0
        ex, ey = dx / dist, dy / dist
        cmds += [(u * ex, u * ey, 0.0) for u in self._drive.profile(dist / self._period)]
        cmds.append(_STOP)
        return cmds, dist

    def run(self, world: PhysicsWorld, action: int) -> PrimitiveResult:
        """Drive grid ``action`` from the robot's current pose (see the module doc)."""
        disc = self.disc
        pose = world.pose
        ix, iy = disc.cell_of(pose[0], pose[1])
        dx, dy = ACTION_DELTAS[action]
        target = disc.cell_centre(ix + dx, iy + dy)
        heading = ACTION_HEADINGS[action]
        traj = [pose]
        steps0 = world.steps
        n_contacts0 = len(world.contacts)
        bumped = reached = False
        while True:
            cmds, dist = self.plan_leg(pose, target, heading)
            if not cmds:  # nothing left to do (only when already exactly on target)
                reached = True
                break
            guard = (world.cast_free_distance(pose[0], pose[1], target[0], target[1], dist)
                     if dist > 0.0 else None)
            bumped = world.drive(cmds, guard, traj)
            pose = world.pose
            if bumped:
                sx, sy = disc.cell_centre(ix, iy)
                world.place(sx, sy, pose[2])
                pose = world.pose
                break
            if (math.hypot(target[0] - pose[0], target[1] - pose[1]) <= self._tol_m
                    and abs(wrap_angle(pose[2] - heading)) <= self._tol_rad):
                reached = True
                break
            if world.steps - steps0 >= self._timeout_steps:
                break
        steps = world.steps - steps0
        return PrimitiveResult(
            state=disc.state_of(pose[0], pose[1]), bumped=bumped, reached=reached,
            timeout=not (bumped or reached), steps=steps, duration_s=steps * world.config.dt_s,
            contacts=tuple(world.contacts[n_contacts0:]), trajectory=traj)
