"""What the wheels deliver: the diff drive's kinematics, and a command as the wheels turn it
into motion above ``exact`` (wheel noise, the per-run bias, latency's lag, slip events).

Compiled functions, the one definition of each, called by the reference controller
(:mod:`sim.physics.reference.controller`) and the batched kernel
(:mod:`sim.physics.kernel.primitive`) alike; :class:`WheelState` is what the reference
world carries between control periods where the kernel keeps the same in its records.
"""

from __future__ import annotations

import math

from numba import njit


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
def wheel_twist(vx: float, vy: float, omega: float, heading: float, e_left: float,
                e_right: float, wheel_noise: float, wheel_base_m: float,
                gain_left: float = 1.0, gain_right: float = 1.0, base_k: float = 1.0
                ) -> tuple[float, float, float]:
    """A commanded twist as a diff drive delivers it above ``exact``: each wheel's speed times
    ``1 + wheel_noise * e`` (``e_left``, ``e_right`` the robot's next two normals) and its
    per-run gain (``gain_left``, ``gain_right``: the wheel-diameter bias), yawing about the
    true wheelbase (``base_k`` times the nominal one the command was computed with), and the
    motion along the robot's ``heading`` [rad] (a diff drive cannot move sideways). With
    gains and ``base_k`` 1 the arithmetic is the unbiased one, bit for bit."""
    vl, vr = twist_to_wheels(math.hypot(vx, vy), omega, wheel_base_m)
    return wheels_twist(vl, vr, heading, e_left, e_right, wheel_noise, wheel_base_m,
                        gain_left, gain_right, base_k, 1.0, 1.0)


@njit(cache=True, inline="always")
def wheels_twist(vl: float, vr: float, heading: float, e_left: float, e_right: float,
                 wheel_noise: float, wheel_base_m: float, gain_left: float, gain_right: float,
                 base_k: float, slip_left: float, slip_right: float
                 ) -> tuple[float, float, float]:
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
    return v * math.cos(heading), v * math.sin(heading), w


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


class WheelState:
    """What the motors carry from one control period to the next at the latency and slip
    rungs (:mod:`sim.physics.fidelity`): each wheel's lagged speed [m/s], the wheel commands
    sent and not yet delivered, each wheel's slip time left [s]. All at rest when placed."""

    __slots__ = ("left", "right", "sent", "slip_left", "slip_right")

    def __init__(self) -> None:
        self.left = self.right = 0.0
        self.sent: list[tuple[float, float]] = []
        self.slip_left = self.slip_right = 0.0
