"""The robot's motion (:mod:`sim.physics.motion`) held to closed-form models.

The oracle and the kernel both call these functions, so the test that holds the two worlds
equal (tests/test_physics_batch.py) cannot see an error in them: here each is checked
against the diff drive's textbook kinematics, a first-order lag's closed form, the normal
distribution's quantile, and a unicycle integrated by hand.
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np
import pytest

from sim.physics.drive_profiles import DriveLimits, profiles
from sim.physics.motion import (
    at_target,
    cell_of,
    held_twist_velocity,
    lag_wheel,
    plan_commands,
    slip_step,
    twist_to_wheels,
    wheel_twist,
    wheels_to_twist,
    wrap_angle,
)
from sim.scenario import Robot

BASE = 0.5  # wheelbase [m]


def test_the_diff_drive_equations_by_hand():
    # v = (vl + vr) / 2, omega = (vr - vl) / b: 0.2 and 0.4 m/s on a 0.5 m base
    assert wheels_to_twist(0.2, 0.4, BASE) == pytest.approx((0.3, 0.4))
    assert twist_to_wheels(0.3, 0.4, BASE) == pytest.approx((0.2, 0.4))
    assert twist_to_wheels(0.0, 2.0, BASE) == pytest.approx((-0.5, 0.5))  # turn in place


def test_a_delivered_twist_is_each_wheel_scaled_then_recombined():
    """Noise e, gains g and the true wheelbase k b, worked by hand for one command."""
    heading, sigma, el, er, gl, gr, k = 0.3, 0.05, 1.2, -0.7, 0.98, 1.02, 1.1
    vl, vr = 0.3 - 0.5 * 0.4 * BASE, 0.3 + 0.5 * 0.4 * BASE  # 0.2, 0.4
    vl_true, vr_true = vl * (1 + sigma * el) * gl, vr * (1 + sigma * er) * gr
    v, w = (vl_true + vr_true) / 2, (vr_true - vl_true) / (k * BASE)
    got = wheel_twist(0.3 * math.cos(heading), 0.3 * math.sin(heading), 0.4, heading, 0.0,
                      0.0, 0.0, el, er, sigma, BASE, gl, gr, k)
    assert got == pytest.approx((v * math.cos(heading), v * math.sin(heading), w), rel=1e-12)
    # with no noise and unit gains the command comes back as it was sent
    assert wheel_twist(0.3, 0.0, 0.4, 0.0, 0.0, 0.0, 0.0, el, er, 0.0, BASE) == pytest.approx(
        (0.3, 0.0, 0.4))


def test_a_held_twist_moves_along_its_arcs_chord():
    """v = 0.4 m/s, w = 0.8 rad/s held for T = 0.5 s from heading 0.3, the robot yawing
    0.2 rad/s for the step of dt = 0.1 s before the twist reaches it: the arc turns from
    0.3 + 0.02 through 0.4 rad; its chord is 2 (v/w) sin(0.2) long, pointing at 0.52."""
    vx, vy = held_twist_velocity(0.4, 0.8, 0.3, 0.2, 0.1, 0.5)
    chord = 2.0 * (0.4 / 0.8) * math.sin(0.2)  # [m], travelled in T
    assert (vx * 0.5, vy * 0.5) == pytest.approx(
        (chord * math.cos(0.52), chord * math.sin(0.52)), rel=1e-12)
    # the chord's end is the arc's end: x = (v/w)(sin(th1) - sin(th0)), as integrated
    th0, th1 = 0.32, 0.72
    assert vx * 0.5 == pytest.approx((0.4 / 0.8) * (math.sin(th1) - math.sin(th0)), rel=1e-12)
    assert vy * 0.5 == pytest.approx(-(0.4 / 0.8) * (math.cos(th1) - math.cos(th0)), rel=1e-12)
    # a straight drive is the straight line's arithmetic, bit for bit
    assert held_twist_velocity(0.4, 0.0, 0.3, 0.0, 0.1, 0.5) == (
        0.4 * math.cos(0.3), 0.4 * math.sin(0.3))


def test_a_blind_biased_drive_ends_on_its_continuous_arc():
    """A noise-free open-loop drive of one cell with a per-run wheel-ratio bias, in the
    batched kernel: its cross-track error equals the continuous arc's, (1 - cos(k L)) / k,
    to 1e-6 of it (the study's figure, :func:`blind_arc`, on 16 robots)."""
    from scenarios.studies.ladder.primitives import blind_arc

    lo, median, hi = (blind_arc(16, 3)["cross_track_over_arc"][i] for i in (1, 0, 2))
    assert abs(median - 1.0) < 1e-6 and abs(lo - 1.0) < 1e-6 and abs(hi - 1.0) < 1e-6


def test_the_lag_is_a_first_order_filter():
    """n periods toward a step from rest: c (1 - keep^n), keep = exp(-T / tau)."""
    period, tau, c = 0.05, 0.2, 0.4
    keep = math.exp(-period / tau)
    speed = 0.0
    for n in range(1, 30):
        speed = lag_wheel(c, speed, keep)
        assert speed == pytest.approx(c * (1 - keep ** n), rel=1e-12)
    assert lag_wheel(c, 0.1, 0.0) == c  # no lag: the command at once


def test_a_slip_starts_below_its_probability_and_lasts_its_duration():
    p, duration, period, fraction = 0.1, 0.3, 0.05, 0.4
    z_at = NormalDist().inv_cdf(p)  # a slip starts when Phi(z) < p
    assert slip_step(0.0, z_at - 1e-6, p, duration, period, fraction) == \
        pytest.approx((fraction, duration - period))
    assert slip_step(0.0, z_at + 1e-6, p, duration, period, fraction) == (1.0, 0.0)
    left, periods = duration - period, 1
    while left > 1e-9:  # under way, whatever the draw
        factor, left = slip_step(left, 5.0, p, duration, period, fraction)
        assert factor == fraction
        periods += 1
    assert periods == round(duration / period)


def test_cells_angles_and_the_end_of_a_leg():
    assert cell_of(2.5, 0.99, 1.0, 4, 3) == (2, 0)
    assert cell_of(-0.1, 7.0, 1.0, 4, 3) == (0, 2)  # clamped into the grid
    for a in np.linspace(-10, 10, 41):
        w = wrap_angle(a)
        assert -math.pi <= w < math.pi and math.isclose(math.cos(w), math.cos(a), abs_tol=1e-12)
    assert at_target(1.001, 2.0, 0.01, 1.0, 2.0, 0.0, 0.005, 0.02)
    assert not at_target(1.01, 2.0, 0.0, 1.0, 2.0, 0.0, 0.005, 0.02)
    assert not at_target(1.0, 2.0, 0.05, 1.0, 2.0, 0.0, 0.005, 0.02)


@pytest.mark.parametrize(("start", "target"), [
    ((0.5, 0.5, 0.0), (1.5, 0.5)),  # straight ahead
    ((0.5, 0.5, 0.0), (0.5, 1.5)),  # a quarter turn, then a cell
    ((0.5, 0.5, 0.3), (-0.5, 0.5)),  # most of a half turn
    ((0.52, 0.47, 1.0), (0.5, -0.5)),  # off the centre: the drive is not cardinal
])
def test_a_legs_commands_drive_a_unicycle_onto_its_target(start, target):
    """A leg turns in place, then drives straight: a unicycle integrated period by period
    (exact for those two motions) ends on the target, facing it, and no command exceeds
    the wheels' limits."""
    robot = Robot()
    lim = DriveLimits.from_robot(robot)
    period = 0.05
    tables = profiles(lim, period, 1.0)
    x, y, th = start
    leg, cmds = plan_commands(x, y, th, *target, 0.0, 1e-6, period, *tables)
    assert leg.nturn > 0 or abs(wrap_angle(math.atan2(target[1] - y, target[0] - x) - th)) < 1e-9
    for vx, vy, w in cmds:
        assert not (w and (vx or vy))  # one motion at a time
        vl, vr = twist_to_wheels(math.hypot(vx, vy), w, robot.wheel_base_m)
        assert max(abs(vl), abs(vr)) <= robot.max_wheel_speed_m_s * (1 + 1e-9)
        x, y, th = x + vx * period, y + vy * period, th + w * period
    assert (x, y) == pytest.approx(target, abs=1e-9)
    assert wrap_angle(th - math.atan2(target[1] - start[1], target[0] - start[0])) == \
        pytest.approx(0.0, abs=1e-9)
    assert np.all(cmds[-1] == 0.0)  # the leg ends with a stop
