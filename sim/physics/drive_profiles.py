"""The drive's limits and its minimal-time *discrete* velocity profiles (why discrete: see
:mod:`sim.physics.reference.controller`), as tables for compiled code: what a primitive's plan
(:func:`sim.physics.reference.controller.plan_leg`) looks up, built once per robot and period.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numba import njit

if TYPE_CHECKING:
    from sim.scenario import Robot


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

    ``caps[n-1, :n]`` is the largest admissible profile of ``n`` periods,
    ``u_k = min(v_max, k*dv, (n+1-k)*dv)`` (from rest, back to rest), and ``sums[n-1]``
    its sum (``math.fsum``). Built up to ``largest_total`` and grown by :meth:`profile`
    on demand, so a profile costs a bisection (:func:`profile_index`) and a scaled copy.
    """

    def __init__(self, v_max: float, dv: float, largest_total: float = 0.0) -> None:
        if not (v_max > 0 and dv > 0):
            raise ValueError(f"limits must be positive, got v_max={v_max}, dv={dv}")
        self.v_max, self.dv = v_max, dv
        self.caps, self.sums = np.zeros((0, 0)), np.zeros(0)
        self._grow(largest_total)

    def _grow(self, total: float) -> None:
        n = self.sums.size
        while n == 0 or self.sums[n - 1] < total:
            n = max(2 * n, 8)
            caps, sums = np.zeros((n, n)), np.zeros(n)
            for i in range(n):
                k = np.arange(1.0, i + 2)
                caps[i, : i + 1] = np.minimum(np.minimum(self.v_max, k * self.dv),
                                              (i + 2 - k) * self.dv)
                sums[i] = math.fsum(caps[i, : i + 1].tolist())
            self.caps, self.sums = caps, sums

    def profile(self, total: float) -> list[float]:
        """Speeds, one per period, summing to ``total`` (>= 0): distance / period."""
        if total <= 0.0:
            return []
        self._grow(total)
        n = profile_index(self.sums, total)
        scale = total / self.sums[n]
        return [c * scale for c in self.caps[n, : n + 1].tolist()]


class Profiles(NamedTuple):
    """The turn and drive tables of :class:`ProfileTable`, as arrays for compiled code."""

    turn_caps: np.ndarray  # float64[n, n]: yaw-rate profiles [rad/period]
    turn_sums: np.ndarray  # float64[n]
    drive_caps: np.ndarray  # float64[m, m]: speed profiles [m/period]
    drive_sums: np.ndarray  # float64[m]


def profiles(limits: DriveLimits, period_s: float, cell_m: float) -> Profiles:
    """Every table a primitive may need: turns up to 1.01 pi, drives up to 8 cells."""
    drive = ProfileTable(limits.v_max_m_s, limits.a_max_m_s2 * period_s, 8.0 * cell_m / period_s)
    turn = ProfileTable(limits.omega_max_rad_s, limits.alpha_max_rad_s2 * period_s,
                        1.01 * math.pi / period_s)
    return Profiles(turn.caps, turn.sums, drive.caps, drive.sums)


@njit(cache=True, inline="always")
def profile_index(sums: np.ndarray, total: float) -> int:
    """bisect_left(sums, total): the profile of ``index + 1`` periods; -1 if none is long enough."""
    lo, hi = 0, sums.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if sums[mid] < total:
            lo = mid + 1
        else:
            hi = mid
    return lo if lo < sums.shape[0] else -1
