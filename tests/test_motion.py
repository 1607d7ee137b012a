from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sim.grid.actions import ACTION_DELTAS, ACTION_HEADINGS
from sim.physics.drive_profiles import DriveLimits, ProfileTable, rate_limit
from sim.physics.reference.controller import (
    PrimitiveController,
    twist_to_wheels,
    wheels_to_twist,
    wrap_angle,
)
from sim.physics.reference.world import PhysicsConfig, PhysicsWorld
from sim.scenario import Robot, Scenario

speeds = st.floats(-5.0, 5.0, allow_nan=False)
EMPTY = Scenario(name="empty", width_m=6.0, height_m=6.0, start=(2, 2), goal=(4, 4))
# compiled functions: load (or compile) them before hypothesis times its examples
wheels_to_twist(0.0, 0.0, 1.0), twist_to_wheels(0.0, 0.0, 1.0), wrap_angle(0.0)


@given(speeds, speeds, st.floats(0.05, 2.0))
def test_wheels_twist_round_trip(vl, vr, base):
    v, om = wheels_to_twist(vl, vr, base)
    back = twist_to_wheels(v, om, base)
    assert back == pytest.approx((vl, vr), abs=1e-9)


def test_pure_turn_and_pure_drive():
    assert wheels_to_twist(1.0, 1.0, 0.4) == (1.0, 0.0)
    assert wheels_to_twist(-1.0, 1.0, 0.4) == (0.0, 5.0)  # counter-clockwise
    assert twist_to_wheels(0.0, 5.0, 0.4) == (-1.0, 1.0)


@given(st.floats(-100.0, 100.0, allow_nan=False))
def test_wrap_angle_range_and_equivalence(a):
    w = wrap_angle(a)
    assert -math.pi <= w < math.pi
    assert math.cos(w) == pytest.approx(math.cos(a), abs=1e-9)
    assert math.sin(w) == pytest.approx(math.sin(a), abs=1e-9)


def test_rate_limit():
    assert rate_limit(0.0, 1.0, 0.4) == 0.4
    assert rate_limit(0.0, -1.0, 0.4) == -0.4
    assert rate_limit(0.9, 1.0, 0.4) == 1.0


def test_drive_limits_from_robot():
    lim = DriveLimits.from_robot(Robot(wheel_base_m=0.4, max_wheel_speed_m_s=1.0,
                                       max_wheel_accel_m_s2=4.0))
    assert lim.omega_max_rad_s == 5.0 and lim.alpha_max_rad_s2 == 20.0


@given(st.floats(1e-6, 60.0), st.floats(0.1, 3.0), st.floats(0.05, 2.0))
def test_profile_is_minimal_exact_and_within_limits(total, v_max, dv):
    table = ProfileTable(v_max, dv)
    u = table.profile(total)
    assert math.fsum(u) == pytest.approx(total, rel=1e-12)
    padded = [0.0, *u, 0.0]  # from rest, back to rest
    assert max(u) <= v_max * (1 + 1e-12)
    assert max(abs(b - a) for a, b in itertools.pairwise(padded)) <= dv * (1 + 1e-12)
    n = len(u)
    if n > 1:  # one period fewer cannot cover the distance
        assert table.sums[n - 2] < total
    assert table.profile(0.0) == []


def test_profile_rejects_bad_limits():
    with pytest.raises(ValueError):
        ProfileTable(0.0, 1.0)


def wheel_commands(cmds, base):
    """Per-period wheel speeds of a plan: drives along the twist's direction, turns in place."""
    out = [(0.0, 0.0)]
    for vx, vy, om in cmds:
        out.append(twist_to_wheels(math.hypot(vx, vy), om, base))
    return out


@pytest.mark.parametrize("heading", [0.0, 0.3, math.pi, -2.0, 40.0])
@pytest.mark.parametrize("action", range(4))
def test_plan_respects_wheel_limits_and_stops(action, heading):
    cfg = PhysicsConfig()
    ctl = PrimitiveController(EMPTY, cfg)
    rb = EMPTY.robot
    target = (2.5 + (action == 3) - (action == 2), 2.5 + (action == 0) - (action == 1))
    cmds, dist = ctl.plan_leg((2.5, 2.5, heading), target, ACTION_HEADINGS[action])
    assert dist == pytest.approx(1.0)
    assert cmds[-1] == (0.0, 0.0, 0.0)
    wheels = wheel_commands(cmds, rb.wheel_base_m)
    dv = rb.max_wheel_accel_m_s2 * cfg.control_period_s
    for (l0, r0), (l1, r1) in itertools.pairwise(wheels):
        assert abs(l1) <= rb.max_wheel_speed_m_s + 1e-12
        assert abs(r1) <= rb.max_wheel_speed_m_s + 1e-12
        assert abs(l1 - l0) <= dv + 1e-12 and abs(r1 - r0) <= dv + 1e-12
    # the drive displacement adds up to the leg
    sx = sum(c[0] for c in cmds) * cfg.control_period_s
    sy = sum(c[1] for c in cmds) * cfg.control_period_s
    assert (2.5 + sx, 2.5 + sy) == pytest.approx(target, abs=1e-12)


@pytest.mark.parametrize("action", range(4))
def test_primitive_lands_on_the_neighbouring_centre(action):
    cfg = PhysicsConfig()
    world = PhysicsWorld(EMPTY, cfg, (2.5, 2.5, 0.0))
    res = PrimitiveController(EMPTY, cfg).run(world, action)
    dx, dy = ACTION_DELTAS[action]
    x, y, th = world.pose
    assert (x, y) == pytest.approx((2.5 + dx, 2.5 + dy), abs=1e-9)
    assert wrap_angle(th - ACTION_HEADINGS[action]) == pytest.approx(0.0, abs=1e-9)
    assert res.reached and not res.bumped and not res.timeout
    assert res.state == (2 + dy) * EMPTY.nx + 2 + dx
    assert len(world.trajectory) == res.steps + 1 and world.trajectory[0] == (2.5, 2.5, 0.0)
    assert res.contacts == 0 and world.time_s == pytest.approx(res.steps * cfg.dt_s)
    assert world.velocity == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)  # at rest


def test_no_turn_when_already_facing():
    cfg = PhysicsConfig()
    world = PhysicsWorld(EMPTY, cfg, (2.5, 2.5, 0.0))
    ctl = PrimitiveController(EMPTY, cfg)
    first = ctl.run(world, 3)  # faces +x already: drive only
    second = ctl.run(world, 3)
    assert first.steps == second.steps
    third = ctl.run(world, 2)  # 180 degree turn first
    assert third.steps > first.steps


def test_feedback_recovers_from_poor_tracking_or_times_out():
    # traction far below what the plan needs: the open-loop plan falls short, the
    # controller re-plans from the measured pose until it is within tolerance or out of time
    weak = PhysicsConfig(traction_margin=0.6)
    world = PhysicsWorld(EMPTY, weak, (2.5, 2.5, 0.0))
    res = PrimitiveController(EMPTY, weak).run(world, 0)
    x, y, th = world.pose
    assert res.reached and res.steps > 2 * PrimitiveController(EMPTY, PhysicsConfig()).run(
        PhysicsWorld(EMPTY, PhysicsConfig(), (2.5, 2.5, 0.0)), 0).steps  # needed re-planning
    assert math.hypot(x - 2.5, y - 3.5) <= weak.tolerance_m
    assert abs(wrap_angle(th - math.pi / 2)) <= weak.tolerance_rad
    hopeless = dataclasses.replace(weak, traction_margin=0.01, timeout_s=3.0)
    world = PhysicsWorld(EMPTY, hopeless, (2.5, 2.5, 0.0))
    res = PrimitiveController(EMPTY, hopeless).run(world, 0)
    assert res.timeout and not res.reached and not res.bumped
    assert res.steps * hopeless.dt_s >= hopeless.timeout_s


def test_pose_is_exact_after_many_primitives():
    cfg = PhysicsConfig()
    world = PhysicsWorld(EMPTY, cfg, (2.5, 2.5, 0.0))
    ctl = PrimitiveController(EMPTY, cfg)
    rng = np.random.default_rng(0)
    for a in rng.integers(4, size=300).tolist():
        ctl.run(world, a)
        x, y, _ = world.pose
        assert abs(x - round(x - 0.5) - 0.5) < 1e-9 and abs(y - round(y - 0.5) - 0.5) < 1e-9
