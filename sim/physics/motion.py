"""The robot's motion, one definition shared by the oracle and the fast path: the diff drive's
kinematics, a command as the wheels deliver it above ``exact`` (wheel noise, the per-run
bias, latency's lag, slip events), the cell of a pose, a leg's plan and commands, the
end-of-leg test, and what a primitive did.

Compiled functions (numba, no pymunk) below both worlds that drive primitives: the
reference (:mod:`sim.physics.reference.controller`, one robot, every step through
Chipmunk) and the batched kernel (:mod:`sim.physics.kernel.primitive`) call these, so
their plans agree bit for bit; which is also why the oracle-vs-kernel test cannot catch an
error here, and ``tests/test_motion_analytic.py`` holds each to a closed-form model.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from sim.physics.drive_profiles import profile_index

# ------------------------------------------------------------------ the wheels


@njit(cache=True)
def wheels_to_twist(v_left_m_s: float, v_right_m_s: float,
                    wheel_base_m: float) -> tuple[float, float]:
    """Wheel rim speeds [m/s] -> (forward speed [m/s], yaw rate [rad/s])."""
    return 0.5 * (v_left_m_s + v_right_m_s), (v_right_m_s - v_left_m_s) / wheel_base_m


@njit(cache=True)
def twist_to_wheels(v_m_s: float, omega_rad_s: float,
                    wheel_base_m: float) -> tuple[float, float]:
    """(forward speed [m/s], yaw rate [rad/s]) -> (left, right) wheel rim speeds [m/s]."""
    half = 0.5 * omega_rad_s * wheel_base_m
    return v_m_s - half, v_m_s + half


@njit(cache=True)
def wheel_twist(vx: float, vy: float, omega: float, heading: float, w_now: float, dt_s: float,
                period_s: float, e_left: float, e_right: float, wheel_noise: float,
                wheel_base_m: float, gain_left: float = 1.0, gain_right: float = 1.0,
                base_k: float = 1.0) -> tuple[float, float, float]:
    """A commanded twist as a diff drive delivers it above ``exact``: each wheel's speed times
    ``1 + wheel_noise * e`` (``e_left``, ``e_right`` the robot's next two normals) and its
    per-run gain (``gain_left``, ``gain_right``: the wheel-diameter bias), yawing about the
    true wheelbase (``base_k`` times the nominal one the command was computed with), and the
    motion along the arc the robot turns through while the twist is held
    (:func:`held_twist_velocity`: from ``heading`` [rad], yawing ``w_now`` [rad/s] now; a
    diff drive cannot move sideways). With gains and ``base_k`` 1 the arithmetic is the
    unbiased one, bit for bit."""
    vl, vr = twist_to_wheels(math.hypot(vx, vy), omega, wheel_base_m)
    return wheels_twist(vl, vr, heading, w_now, dt_s, period_s, e_left, e_right, wheel_noise,
                        wheel_base_m, gain_left, gain_right, base_k, 1.0, 1.0)


@njit(cache=True, inline="always")
def wheels_twist(vl: float, vr: float, heading: float, w_now: float, dt_s: float,
                 period_s: float, e_left: float, e_right: float, wheel_noise: float,
                 wheel_base_m: float, gain_left: float, gain_right: float, base_k: float,
                 slip_left: float, slip_right: float) -> tuple[float, float, float]:
    """:func:`wheel_twist` from the wheels' speeds [m/s] the motors drive (after any lag),
    each also times its slip factor (1: no slip)."""
    if wheel_noise > 0.0:
        vl *= 1.0 + wheel_noise * e_left
        vr *= 1.0 + wheel_noise * e_right
    if slip_left != 1.0 or slip_right != 1.0:
        vl *= slip_left
        vr *= slip_right
    if gain_left != 1.0 or gain_right != 1.0 or base_k != 1.0:
        vl *= gain_left
        vr *= gain_right
        wheel_base_m *= base_k
    v, w = wheels_to_twist(vl, vr, wheel_base_m)
    vx, vy = held_twist_velocity(v, w, heading, w_now, dt_s, period_s)
    return vx, vy, w


@njit(cache=True, inline="always")
def held_twist_velocity(v: float, w: float, heading: float, w_now: float, dt_s: float,
                        period_s: float) -> tuple[float, float]:
    """The world-frame velocity [m/s] that, held for a control period, moves the robot along
    the chord of the arc a twist (``v`` [m/s], ``w`` [rad/s]) turns through: so a held twist
    ends every period on its continuous arc, exactly.

    Why a chord: both worlds step a body velocity set once per period (Chipmunk does not turn
    a linear velocity with the body), and the joints hand the new twist to the robot one
    physics step late, so it is driven from the step after the command, while the robot is
    still yawing ``w_now`` for that step. Its heading then runs from ``heading + w_now dt_s``
    over ``w period_s``; the chord of that arc points half-way through it and is
    ``sinc(w period_s / 2)`` of the arc's length. ``period_s`` 0: the velocity of the instant
    (no turn within the period). With ``w`` and ``w_now`` 0 the arithmetic is the straight
    line's, bit for bit."""
    if w != 0.0 or w_now != 0.0:
        half = 0.5 * w * period_s
        heading = heading + w_now * dt_s + half
        if half != 0.0:
            v *= math.sin(half) / half
    return v * math.cos(heading), v * math.sin(heading)


@njit(cache=True, inline="always")
def arc_of_chord(chord_m: float, yaw_rad: float) -> float:
    """The length [m] of the arc that turns through ``yaw_rad`` between the ends of a chord
    ``chord_m`` long: what the wheels travelled on a step that :func:`held_twist_velocity`
    drove along the chord (the encoders read the arc)."""
    half = 0.5 * yaw_rad
    return chord_m if half == 0.0 else chord_m * half / math.sin(half)


@njit(cache=True, inline="always")
def lag_wheel(command: float, speed: float, keep: float) -> float:
    """A wheel's speed after one control period of a first-order lag toward ``command``
    (``keep = exp(-period / tau)``; 0: the command at once)."""
    return command + (speed - command) * keep


@njit(cache=True, inline="always")
def slip_step(left_s: float, z: float, start_p: float, duration_s: float, period_s: float,
              fraction: float) -> tuple[float, float]:
    """One control period of a wheel's slip events: (the factor its speed is delivered with,
    the slip time left after the period [s]). ``z``: the wheel's normal for the period,
    turned into a uniform (a slip starts when it is below ``start_p``); drawn every period
    whether or not the wheel slips, so the stream's layout does not depend on the slips."""
    if left_s > 1e-9:  # a slip under way
        return fraction, left_s - period_s
    if 0.5 * math.erfc(-z / math.sqrt(2.0)) < start_p:
        return fraction, duration_s - period_s
    return 1.0, 0.0


# Turns smaller than this are skipped [rad]: after a drive the heading equals the
# bearing up to rounding (~1e-13 rad), and a "turn" of that size would still cost
# two control periods (command + stop).
MIN_TURN_RAD = 1e-9

# With latency a leg's commands end before its wheels do: the controller holds a stop until
# the commands in flight are delivered and both wheels turn slower than this [m/s] (a
# first-order lag delivers the whole commanded travel once it settles), then checks the
# target. At 1 cm/s the drift still to come is 1.5 mm and 0.6 degrees at tau = 0.2 s.
SETTLE_M_S = 0.01


# ------------------------------------------------------------------ kinematics


@njit(cache=True, inline="always")
def wrap_angle(a_rad: float) -> float:
    """Angle wrapped into [-pi, pi)."""
    return (a_rad + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True, inline="always")
def cell_of(x_m: float, y_m: float, cell_m: float, nx: int, ny: int) -> tuple[int, int]:
    """The cell (ix, iy) holding the point, clamped into the grid (as Discretiser.cell_of)."""
    ix = min(max(int(math.floor(x_m / cell_m)), 0), nx - 1)  # noqa: RUF046 (numba)
    iy = min(max(int(math.floor(y_m / cell_m)), 0), ny - 1)  # noqa: RUF046 (numba)
    return ix, iy


# ------------------------------------------------------------------ one leg


class Leg(NamedTuple):
    """One leg of a primitive: turn in place (``nturn`` periods, then a stop period), then
    drive straight (``ndrive`` periods, then a stop period); either may be absent (0)."""

    nturn: int  # periods of the turn's profile
    tsign: float  # +1 counter-clockwise, -1 clockwise
    tscale: float  # scale of the turn table's row
    ndrive: int  # periods of the drive's profile
    dscale: float  # scale of the drive table's row
    ex: float  # drive direction (unit)
    ey: float
    dist: float  # drive length [m] (0: no drive)


@njit(cache=True, inline="always")
def plan_leg(x: float, y: float, th: float, tx: float, ty: float, heading: float,
             tol_m: float, period_s: float, turn_sums: np.ndarray, drive_sums: np.ndarray,
             split_turn_rad: float = math.inf) -> Leg:
    """From the pose (x, y, th): turn to face the target (tx, ty) and drive to it when it is
    further than ``tol_m``; otherwise only turn to ``heading``. Nothing to do: both 0.

    A turn larger than ``split_turn_rad`` is a leg of its own, the drive planned after it
    (with latency: a drive begun while the wheels still turn would leave the line; the
    controller lets the turn settle first, :data:`SETTLE_M_S`)."""
    dx, dy = tx - x, ty - y
    dist = math.hypot(dx, dy)
    drive = dist > tol_m
    turn = wrap_angle((math.atan2(dy, dx) if drive else heading) - th)
    nturn, tsign, tscale = 0, 1.0, 0.0
    if abs(turn) > MIN_TURN_RAD:
        total = abs(turn) / period_s
        n = profile_index(turn_sums, total)
        if n < 0:
            raise ValueError("turn longer than the profile table")
        nturn, tscale = n + 1, total / turn_sums[n]
        tsign = -1.0 if turn < 0.0 else 1.0
    if not drive or abs(turn) > split_turn_rad:
        return Leg(nturn, tsign, tscale, 0, 0.0, 0.0, 0.0, 0.0)
    total = dist / period_s
    n = profile_index(drive_sums, total)
    if n < 0:
        raise ValueError("drive longer than the profile table")
    return Leg(nturn, tsign, tscale, n + 1, total / drive_sums[n], dx / dist, dy / dist, dist)


@njit(cache=True, inline="always")
def leg_command(leg: Leg, k: int, turn_caps: np.ndarray, drive_caps: np.ndarray
                ) -> tuple[float, float, float]:
    """Control-body twist (vx [m/s], vy [m/s], omega [rad/s]) of period ``k`` of the leg;
    nan past its end. (Tables as arrays, not :class:`Profiles`: numba increfs every array of
    a tuple argument at each call, and this runs once per control period.)"""
    if leg.nturn > 0:
        if k < leg.nturn:
            return 0.0, 0.0, leg.tsign * (turn_caps[leg.nturn - 1, k] * leg.tscale)
        if k == leg.nturn:
            return 0.0, 0.0, 0.0
        k -= leg.nturn + 1
    if leg.ndrive > 0:
        if k < leg.ndrive:
            u = drive_caps[leg.ndrive - 1, k] * leg.dscale
            return u * leg.ex, u * leg.ey, 0.0
        if k == leg.ndrive:
            return 0.0, 0.0, 0.0
    return math.nan, math.nan, math.nan


@njit(cache=True)
def plan_commands(x: float, y: float, th: float, tx: float, ty: float, heading: float,
                  tol_m: float, period_s: float, turn_caps: np.ndarray, turn_sums: np.ndarray,
                  drive_caps: np.ndarray, drive_sums: np.ndarray,
                  split_turn_rad: float = math.inf) -> tuple[Leg, np.ndarray]:
    """:func:`plan_leg` and every :func:`leg_command` of it (float64[n, 3]) in one call."""
    leg = plan_leg(x, y, th, tx, ty, heading, tol_m, period_s, turn_sums, drive_sums,
                   split_turn_rad)
    n = (leg.nturn + 1 if leg.nturn > 0 else 0) + (leg.ndrive + 1 if leg.ndrive > 0 else 0)
    cmds = np.empty((n, 3))
    for k in range(cmds.shape[0]):
        cmds[k, 0], cmds[k, 1], cmds[k, 2] = leg_command(leg, k, turn_caps, drive_caps)
    return leg, cmds


@njit(cache=True, inline="always")
def at_target(x: float, y: float, th: float, tx: float, ty: float, heading: float,
              tol_m: float, tol_rad: float) -> bool:
    """A leg that ends here has reached the primitive's target centre and heading."""
    return math.hypot(tx - x, ty - y) <= tol_m and abs(wrap_angle(th - heading)) <= tol_rad


# ------------------------------------------------------------------ the primitive


class PrimitiveOutcome(NamedTuple):
    """What motion primitives did: one robot's (the reference, :meth:`PrimitiveController.run`:
    Python scalars) or a batch's (:meth:`sim.physics.kernel.batch.RouteBatch.step`: one entry per
    robot, arrays; inactive robots zeros). The contact records and the trajectory stay with
    the world that drove them (``world.contacts``, ``world.trajectory``; ``batch.contacts[i]``,
    ``batch.trajectory(i)``)."""

    state: Any  # int: Discretiser.state_of the final pose
    bumped: Any  # bool: a contact began (exact: the robot is back on its start cell centre)
    reached: Any  # bool: ended within tolerance of the target centre and heading
    timeout: Any  # bool: gave up at PhysicsConfig.timeout_s
    steps: Any  # int: physics steps driven
    contacts: Any  # int: contacts that began
    cell: Any = None  # int: the true cell of the final pose (``state`` is the believed one
    #   with localisation; the reference, which has none, gives the state)
