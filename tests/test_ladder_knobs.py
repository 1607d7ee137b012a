"""The fidelity ladder's bias, open-loop, localisation, latency and slip knobs against their
analytic models.

The reference world (PhysicsWorld + PrimitiveController) has wheel noise and carried pose
only; these knobs live in the batched kernel, so each is checked against something other
than itself: the kinematics of a biased diff drive (arc, turn), the propagation of
per-period wheel noise through an open-loop drive, the odometry motion model's predicted
dead-reckoning error, and the fix's error.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.errors import ScenarioError
from sim.grid.actions import ACTION_HEADINGS
from sim.physics.envs.vector import PhysicsRouteVectorEnv
from sim.physics.fidelity import PRESETS, Fidelity, parse_fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.physics.reference.controller import PrimitiveController
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario

RIGHT, UP = ACTION_HEADINGS.index(0.0), ACTION_HEADINGS.index(math.pi / 2)
OPEN = Scenario(name="open", width_m=12.0, height_m=12.0, start=(2, 6), goal=(9, 6))
CENTRE = (4.5, 6.5)  # a cell centre with free space all round


def _batch(fid: str, n: int, seed: int = 0) -> RouteBatch:
    b = RouteBatch(OPEN, n, fidelity=parse_fidelity(fid))
    for i, child in enumerate(np.random.SeedSequence(seed).spawn(n)):
        b.set_noise_rng(i, np.random.default_rng(child))
        b.place(i, *CENTRE, 0.0)
    return b


def _drive_profile() -> np.ndarray:
    """Forward speed [m/s] of each control period of a one-cell drive from a centre facing
    it (the controller's plan: the commands every knob starts from)."""
    ctl = PrimitiveController(OPEN, PhysicsConfig())
    cmds, _ = ctl.plan_leg((*CENTRE, 0.0), (CENTRE[0] + 1.0, CENTRE[1]), 0.0)
    return np.array([math.hypot(vx, vy) for vx, vy, _ in cmds])


def test_presets_say_what_they_are_and_exact_is_unchanged():
    assert PRESETS["exact"] == Fidelity() and PRESETS["exact"].is_exact
    assert PRESETS["noisy"] == Fidelity("noisy", wheel_noise=0.05, carried_pose=True)
    assert PRESETS["uncalibrated"].biased and not PRESETS["uncalibrated"].hidden_state
    assert PRESETS["open-loop"].open_loop and not PRESETS["open-loop"].localisation
    loc = PRESETS["localised"]
    assert loc.localisation and loc.fix_every > 0 and loc.carried_pose
    assert not any(PRESETS[name].is_exact for name in PRESETS if name != "exact")
    with pytest.raises(ScenarioError, match="renamed 'slippery'"):
        parse_fidelity("rough")
    with pytest.raises(ScenarioError, match="fix_every: has no effect without localisation"):
        parse_fidelity("noisy,fix_every=3")
    with pytest.raises(ScenarioError, match="localisation: needs carried_pose"):
        parse_fidelity("localisation=true")
    with pytest.raises(ScenarioError, match="fix_every: expected a whole number"):
        parse_fidelity("localised,fix_every=2.5")
    with pytest.raises(ScenarioError, match="wheel_ratio_sigma: must be in"):
        parse_fidelity("noisy,wheel_ratio_sigma=0.5")
    with pytest.raises(ValueError, match="reference controller drives wheel noise"):
        PrimitiveController(OPEN, PhysicsConfig(), PRESETS["uncalibrated"])
    lat, slip = PRESETS["latency"], PRESETS["slip"]
    assert lat.latency and lat.hidden_state and not lat.slips and lat.carried_pose
    assert slip.slips and slip.hidden_state and not slip.latency and slip.carried_pose
    with pytest.raises(ScenarioError, match="lag_tau_s: needs carried_pose"):
        parse_fidelity("lag_tau_s=0.2")
    with pytest.raises(ScenarioError, match="slip_fraction: has no effect without slip_rate"):
        parse_fidelity("noisy,slip_fraction=0.5")
    with pytest.raises(ScenarioError, match=r"slip_fraction: must be in 0\.0\.\.1\.0"):
        parse_fidelity("slip,slip_fraction=1.5")
    with pytest.raises(ScenarioError, match="command_delay_s: is 10 control periods"):
        RouteBatch(OPEN, 1, fidelity=parse_fidelity("latency,command_delay_s=1.0"))


def test_the_bias_is_drawn_once_per_run_from_the_physics_stream():
    b = _batch("uncalibrated", 3, seed=5)
    gains = [b.bias(i) for i in range(3)]
    assert len(set(gains)) == 3  # each robot its own
    for g_l, g_r, e_b in gains:
        assert g_l + g_r == pytest.approx(2.0)  # the mean diameter is the nominal one
        assert abs(g_r / g_l - 1) < 0.06 and abs(e_b - 1) < 0.06  # 1 % sigma: within 6 sigma
    b.step(np.array([RIGHT] * 3))
    b.place(0, *CENTRE, 0.0)  # a new episode of the same run: the same robot
    assert b.bias(0) == gains[0]
    again = _batch("uncalibrated", 3, seed=5)
    assert [again.bias(i) for i in range(3)] == gains  # deterministic per seed
    assert _batch("noisy", 1).bias(0) == (1.0, 1.0, 1.0)


def _biased_kinematics(pose, cmds, gains, base, period):
    """The diff drive's kinematics, written out: each command's twist as the biased wheels
    deliver it, held for one period along its continuous arc (the unicycle integrated in
    closed form), from the step after the command (the joints hand a twist on one step
    late, as Chipmunk's solve does; one step per period here)."""
    g_l, g_r, e_b = gains
    x, y, th = pose
    v = w = 0.0
    for cvx, cvy, cw in cmds:
        speed = math.hypot(cvx, cvy)
        v_l, v_r = (speed - 0.5 * cw * base) * g_l, (speed + 0.5 * cw * base) * g_r
        nv, nw = 0.5 * (v_l + v_r), (v_r - v_l) / (base * e_b)
        if w == 0.0:
            x, y = x + v * period * math.cos(th), y + v * period * math.sin(th)
        else:
            x += (v / w) * (math.sin(th + w * period) - math.sin(th))
            y -= (v / w) * (math.cos(th + w * period) - math.cos(th))
        th += w * period
        v, w = nv, nw
    return x, y, th


def test_a_biased_open_loop_drive_follows_the_diff_drive_kinematics():
    """Without noise: a turn commanded as phi turns phi / E_b, a drive of L curves by
    (g_r - g_l) L / (b E_b) (both exactly), and the end pose is the discrete kinematics'."""
    fid = "open_loop=true,wheel_ratio_sigma=0.05,wheelbase_sigma=0.05"
    b = _batch(fid, 8, seed=1)
    base, period = OPEN.robot.wheel_base_m, PhysicsConfig().control_period_s
    actions = np.array([RIGHT] * 4 + [UP] * 4)
    out = b.step(actions)
    assert out.reached.all() and not out.bumped.any()
    ctl = PrimitiveController(OPEN, PhysicsConfig())
    for i in range(8):
        gains = b.bias(i)
        g_l, g_r, e_b = gains
        up = actions[i] == UP
        turn = (math.pi / 2) / e_b if up else 0.0
        x, y, th = b.pose(i)
        assert th == pytest.approx(turn + (g_r - g_l) / (base * e_b), abs=1e-9)
        target = (CENTRE[0], CENTRE[1] + 1.0) if up else (CENTRE[0] + 1.0, CENTRE[1])
        cmds, _ = ctl.plan_leg((*CENTRE, 0.0), target, ACTION_HEADINGS[actions[i]])
        want = _biased_kinematics((*CENTRE, 0.0), cmds, gains, base, period)
        assert (x, y, th) == pytest.approx(want, abs=1e-9)
        assert math.hypot(x - target[0], y - target[1]) > 1e-3  # the bias did move it


def test_open_loop_end_pose_spread_is_the_wheel_noise_propagated_through_the_drive():
    """Per-period wheel noise sigma: heading variance T^2 sum 2 sigma^2 u_k^2 / b^2, along-
    track T^2 sum sigma^2 u_k^2 / 2, lateral the heading errors carried over the rest of
    the drive: a period's yaw error turns the chord of its own period by half of it and
    every later period's by all of it (each twist is held along its arc, from the step
    after its command)."""
    sigma, n = 0.05, 2000
    b = _batch(f"wheel_noise={sigma},open_loop=true", n, seed=2)
    out = b.step(np.full(n, RIGHT))
    assert not out.bumped.any()
    pose = b.poses()
    u = _drive_profile()
    T, base = PhysicsConfig().control_period_s, OPEN.robot.wheel_base_m
    var_yaw = (T * u) ** 2 * 2 * sigma**2 / base**2  # of each period's yaw
    after = np.array([T * (0.5 * u[k] + u[k + 1:].sum()) for k in range(u.size)])
    want = {"heading": math.sqrt(var_yaw.sum()),
            "along": math.sqrt(((T * u) ** 2 * sigma**2 / 2).sum()),
            "lateral": math.sqrt((var_yaw * after**2).sum())}
    got = {"heading": pose[:, 2].std(), "along": (pose[:, 0] - CENTRE[0] - 1.0).std(),
           "lateral": (pose[:, 1] - CENTRE[1]).std()}
    for key in want:  # 2000 drives: the std's own sampling error is ~1.6 %
        assert got[key] == pytest.approx(want[key], rel=0.08), key
    assert abs((pose[:, 0] - CENTRE[0] - 1.0).mean()) < 4 * want["along"] / math.sqrt(n)


def test_dead_reckoning_error_grows_as_the_odometry_motion_model_predicts():
    """A straight open-loop drive (the true motion is the commanded one: no wheel noise):
    the estimate's errors have the odometry model's variances, per period of travel d_k:
    along-track alpha3 sum d_k^2, heading 2 alpha2 sum d_k^2 (a rotation before and after
    each translation)."""
    a2, a3, n = 0.01, 0.02, 2000
    b = _batch(f"carried_pose=true,open_loop=true,localisation=true,"
               f"odometry_rot_trans={a2},odometry_trans_trans={a3}", n, seed=3)
    b.step(np.full(n, RIGHT))
    true = b.poses()
    assert np.allclose(true[:, :2], [CENTRE[0] + 1.0, CENTRE[1]], atol=1e-9)
    est = np.array([b.believed_pose(i) for i in range(n)])
    d = PhysicsConfig().control_period_s * _drive_profile()
    assert (est[:, 0] - true[:, 0]).std() == pytest.approx(math.sqrt(a3 * (d**2).sum()),
                                                           rel=0.08)
    assert (est[:, 2] - true[:, 2]).std() == pytest.approx(math.sqrt(2 * a2 * (d**2).sum()),
                                                           rel=0.08)


def test_the_bias_shows_in_odometry_as_umbmark_drift():
    """Encoders read wheel rotation through the nominal geometry: on a biased robot the
    odometry of a drive that truly curves by kappa L says straight, so the estimate's
    heading error is the true curvature's, exactly."""
    b = _batch("carried_pose=true,open_loop=true,localisation=true,wheel_ratio_sigma=0.05,"
               "wheelbase_sigma=0.05", 6, seed=4)
    b.step(np.full(6, RIGHT))
    base = OPEN.robot.wheel_base_m
    for i in range(6):
        g_l, g_r, e_b = b.bias(i)
        assert b.believed_pose(i)[2] == pytest.approx(0.0, abs=1e-9)
        assert b.pose(i)[2] == pytest.approx((g_r - g_l) / (base * e_b), abs=1e-9)


def test_a_fix_resets_the_estimate_to_the_true_pose_within_its_sigma():
    s_m, s_rad, n = 0.05, 0.03, 2000
    b = _batch(f"carried_pose=true,localisation=true,odometry_trans_trans=0.05,fix_every=2,"
               f"fix_sigma_m={s_m},fix_sigma_rad={s_rad}", n, seed=6)
    b.step(np.full(n, RIGHT))  # no fix yet: the odometry's error only
    err1 = np.array([np.subtract(b.believed_pose(i), b.pose(i)) for i in range(n)])
    b.step(np.full(n, UP))  # the second primitive ends in a fix
    err2 = np.array([np.subtract(b.believed_pose(i), b.pose(i)) for i in range(n)])
    assert err1[:, 1].std() < 1e-6 and err1[:, 0].std() > 0.01
    for k, want in ((0, s_m), (1, s_m), (2, s_rad)):
        assert err2[:, k].std() == pytest.approx(want, rel=0.08)
        assert abs(err2[:, k].mean()) < 4 * want / math.sqrt(n)


def test_the_learner_sees_the_believed_cell_and_the_world_ends_the_episode_at_the_true_g():
    """A robot whose estimate is a cell off (a fix of 1 m sigma): its observation is the
    believed cell, its contacts, reward and termination the true cell's."""
    fid = ("carried_pose=true,localisation=true,fix_every=1,fix_sigma_m=0.8")
    env = PhysicsRouteVectorEnv(64, OPEN, fidelity=fid, max_episode_steps=50)
    env.reset(seed=list(range(64)))
    disc = env.batch.disc
    seen_apart = ended = 0
    for _ in range(10):
        obs, reward, term, _, _ = env.step(np.full(64, RIGHT))
        for i in range(64):
            bx, by, _ = env.batch.believed_pose(i)
            x, y, _ = env.batch.pose(i)
            assert obs[i] == disc.state_of(bx, by)
            assert term[i] == (disc.state_of(x, y) == env.model.goal)
            assert (reward[i] == OPEN.rewards.goal) == bool(term[i])
            seen_apart += disc.state_of(bx, by) != disc.state_of(x, y)
        ended += int(term.sum())
    assert seen_apart > 0 and ended > 0


def _open_loop_drive(fid: str, n: int, seed: int = 0) -> RouteBatch:
    """``n`` robots, each with its own stream, driving one cell RIGHT open loop (one leg,
    the plan's commands, no feedback) from a centre facing it."""
    b = RouteBatch(OPEN, n, fidelity=parse_fidelity(f"open_loop=true,carried_pose=true,{fid}"),
                   trajectories=True)
    for i, child in enumerate(np.random.SeedSequence(seed).spawn(n)):
        b.set_noise_rng(i, np.random.default_rng(child))
        b.place(i, *CENTRE, 0.0)
    out = b.step(np.array([RIGHT] * n))
    assert out.reached.all() and not out.bumped.any()
    return b


def test_latency_delivers_each_command_late_and_through_a_first_order_lag():
    """Per step, the robot moves by the speed a first-order lag of the delayed commands gives
    (``s_k = c_k + (s_(k-1) - c_k) exp(-T / tau)``, ``c_k = u_(k - delay)``, then stops held
    until the wheels settle), one step later (positions integrate first): the sampled
    solution of the lag ODE, to rounding. Settled, the lag has delivered the whole cell."""
    from sim.physics.reference.controller import SETTLE_M_S

    period = PhysicsConfig().control_period_s
    u = _drive_profile()
    for tau, delay in ((0.2, 0.1), (0.5, 0.0), (0.0, 0.3)):
        b = _open_loop_drive(f"lag_tau_s={tau},command_delay_s={delay}", 1)
        tr = b.trajectory(0)
        moved = np.hypot(*np.diff(tr[:, :2], axis=0).T)
        n = round(delay / period)
        keep = math.exp(-period / tau) if tau else 0.0
        s, speed, k = [], 0.0, 0
        while k < len(u) or k < len(u) + n or speed > SETTLE_M_S:  # the leg, then settling
            c = u[k - n] if 0 <= k - n < len(u) else 0.0
            speed = c + (speed - c) * keep
            s.append(speed)
            k += 1
        np.testing.assert_allclose(moved, np.concatenate([[0.0], s[:-1]]) * period,
                                   rtol=0, atol=1e-12)
        residual = speed * period / (1.0 - keep)  # the drift still to come after settling
        assert moved.sum() + s[-1] * period + residual * keep == pytest.approx(1.0, abs=1e-9)
        assert moved[:len(u)].sum() < 0.95  # late, lagging wheels: short of the cell in time


def test_slip_events_deliver_the_renewal_models_expected_travel():
    """Each wheel slips as a Poisson process sampled per period, for whole periods: the
    mean path of an open-loop drive is the plan's speeds times each period's expected
    delivered fraction, from the slip's Markov chain (free -> slipping D periods -> free)."""
    rate, frac, dur = 2.0, 0.2, 0.3
    period = PhysicsConfig().control_period_s
    u = _drive_profile()
    n = 1500
    b = _open_loop_drive(f"slip_rate_hz={rate},slip_fraction={frac},slip_duration_s={dur}",
                         n, seed=3)
    got = b.primitive_metres()
    p = -math.expm1(-rate * period)
    d = math.ceil(dur / period - 1e-9)
    left = np.zeros(d)  # P(slip periods left after this one = r), r = 0 .. d-1
    left[0] = 1.0
    expected_factor = []
    for _ in range(len(u)):
        free = left[0]
        slipping = 1.0 - free + free * p
        expected_factor.append(1.0 - (1.0 - frac) * slipping)
        nxt = np.zeros(d)
        nxt[0] = free * (1.0 - p) + left[1] if d > 1 else free * (1.0 - p) + free * p
        if d > 1:
            nxt[1:-1] = left[2:]
            nxt[-1] = free * p
        left = nxt
    want = float(np.sum(u[:-1] * np.array(expected_factor[:-1]))) * period
    se = got.std(ddof=1) / math.sqrt(n)
    assert abs(got.mean() - want) < 4 * se, (got.mean(), want, se)
    assert want < 0.95 and (got < 1.0 - 1e-6).mean() > 0.5  # slips did cost travel
    assert (np.abs(got - 1.0) < 1e-9).any()  # ... and a few drives had none (P about 1 %)


def test_the_bumpers_hysteresis_cuts_the_re_firing_after_a_bump():
    """Wheel noise lifts a resting disc a few mm off the surface (in a turn in place); a
    switch without hysteresis (release 0) fires anew when the next move touches it again.
    With 3 mm of release, P(bump | the move before bumped) falls toward the grid's count;
    moves that follow a free move are not affected."""
    from scenarios.studies.ladder.primitives import drive

    held = drive("paper-40", "noisy", 512, 40, seed=2)
    bare = drive("paper-40", "noisy,bumper_release_m=0", 512, 40, seed=2)
    assert bare["rebump"] > held["rebump"] + 0.04, (bare["rebump"], held["rebump"])
    assert held["rebump"] > held["grid_blocks_after_bump"]  # carried pose: still above it
    assert abs(bare["bump_after_move"] - held["bump_after_move"]) < 0.01


def test_the_primitives_study_measures_every_rung_it_is_given():
    from scenarios.studies.ladder.primitives import drive

    exact = drive("paper-40", "exact", 16, 12, seed=1)
    assert exact["reached"] + exact["bumped"] + exact["timeout"] == pytest.approx(1.0)
    assert exact["end_cross_p95_m"] < 1e-9 and exact["end_heading_p95_rad"] < 1e-9
    noisy = drive("paper-40", "noisy", 16, 12, seed=1)
    assert 1e-4 < noisy["end_cross_p95_m"] < 0.05  # wheel noise, within the controller's reach
    assert drive("paper-40", "noisy", 16, 12, seed=1) == noisy  # deterministic per seed
