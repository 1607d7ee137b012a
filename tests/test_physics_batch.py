"""The batched physics world is the reference world at every fidelity: same cells, bumps,
contacts and step counts, poses within 1e-9 m, whatever else shares the batch."""

from __future__ import annotations

import numpy as np
import pytest

from sim.grid import build_model
from sim.physics.fidelity import PRESETS, parse_fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.physics.reference.controller import PrimitiveController
from sim.physics.reference.world import PhysicsWorld
from sim.physics.static import PhysicsConfig
from sim.scenario_io import resolve_scenario

# Every fidelity: rounding differences between the kernel's float64 and Chipmunk's (1e-16
# per step) do not grow over 250-primitive episodes (the controller's feedback contracts
# them). Measured over 160k primitives per fidelity on five maps: worst pose 3e-18 m at
# exact, 3e-12 m with wheel noise, 2e-10 m at noisy, 4e-10 m at rough (the surface's hold
# and the bumper included); 1e-9 m holds for all of them.
POSE_TOL_M = 1e-9
# Latency carries each wheel's speed from period to period, so a rounding difference lives on
# through the settle instead of being contracted by the feedback at once: worst 2.5e-9 m
# (heading, rad) over paper-40's 2500 primitives, typically 1e-13.
LATENCY_POSE_TOL_M = 1e-8


# every rung the reference drives (read from the ladder, so a new rung joins); the bias,
# open-loop and localisation knobs live in the kernel alone and are held to their analytic
# models (tests/test_ladder_knobs.py)
REFERENCE_RUNGS = [k for k, f in PRESETS.items()
                   if not (f.biased or f.open_loop or f.localisation)]


@pytest.mark.parametrize("fid", [*REFERENCE_RUNGS, "wheel_noise=0.05"])
# the arena's walls-only map in the slow run: paper-40's circles and walls cover the same
# contact code, and the default run keeps within CI's budget
@pytest.mark.parametrize("name", ["paper-40", pytest.param("arena", marks=pytest.mark.slow)])
def test_batch_robot_equals_the_reference_world(name, fid):
    """Every step through cpSpaceStep (the reference: PhysicsWorld + PrimitiveController) vs
    the compiled kernel + Chipmunk checks, with the same actions and the same noise seed:
    cells, bumped / reached / timeout, step and contact counts, contact records, resting,
    the pose and the whole trajectory, field by field."""
    sc = resolve_scenario(name)
    model = build_model(sc)
    cfg, fidelity = PhysicsConfig(), parse_fidelity(fid)
    rng = np.random.default_rng(7)
    world = PhysicsWorld(sc, cfg)
    ctl = PrimitiveController(sc, cfg, fidelity)
    batch = RouteBatch(sc, 1, cfg, trajectories=True, fidelity=fidelity)
    starts = model.start_states
    tol = LATENCY_POSE_TOL_M if fidelity.latency else POSE_TOL_M
    bumps = contacts = resting_starts = resting_bumps = 0
    for k in range(2500):
        if k % 250 == 0:  # a new episode from a random start cell, a new noise stream
            s0 = int(rng.choice(starts))
            x, y = batch.disc.state_centre(s0)
            world.respawn((x, y, 0.0))
            batch.place(0, x, y, 0.0)
            noise_seed = int(rng.integers(1 << 30))
            noise = np.random.default_rng(noise_seed)
            batch.set_noise_rng(0, np.random.default_rng(noise_seed))
        a = int(rng.integers(0, 4))
        was_resting = world.resting
        n_world, n_batch = len(world.contacts), len(batch.contacts[0])
        ref = ctl.run(world, a, noise)
        out = batch.step(np.array([a]))
        assert ref == tuple(int(v[0]) for v in out), k
        assert bool(batch.robots[0]["resting"]) == world.resting, k
        np.testing.assert_allclose(batch.pose(0), world.pose, rtol=0, atol=tol)
        np.testing.assert_allclose(batch.trajectory(0), np.array(world.trajectory), rtol=0,
                                   atol=tol)
        got = sorted(batch.contacts[0][n_batch:])
        want = sorted(world.contacts[n_world:])
        assert [(c.step, c.kind) for c in got] == [(c.step, c.kind) for c in want], k
        for c, d in zip(got, want, strict=True):
            np.testing.assert_allclose(c[2:], d[2:], rtol=0, atol=tol)
        bumps += ref.bumped
        contacts += ref.contacts
        # a bump without a new contact is the bumper pressed home by a robot that rested
        # (within bumper_release_m of a surface: the switch was still held)
        assert not (ref.bumped and ref.contacts == 0) or was_resting, k
        resting_starts += was_resting
        resting_bumps += was_resting and ref.bumped
    assert bumps > 50 and contacts >= 0.8 * bumps  # the test saw plenty of bumps
    if fidelity.carried_pose:  # ... and primitives from a resting pose: slides, turns, bumps
        assert resting_starts > 50 and 20 < resting_bumps < resting_starts


def test_the_joints_limit_the_velocity_change_as_in_the_reference_world():
    """Three physics steps per control period: the first step of each period asks the joints
    for 3 a_max dt of speed change, more than their force limits give (2 a_max dt); the robot
    lags the control body there, in Chipmunk and in the kernel alike (heading included)."""
    sc = resolve_scenario("arena")
    cfg = PhysicsConfig(dt_s=0.05, substeps=3)
    world, ctl, batch = PhysicsWorld(sc, cfg), PrimitiveController(sc, cfg), RouteBatch(sc, 1, cfg)
    rng = np.random.default_rng(1)
    for _ in range(300):
        a = int(rng.integers(0, 4))
        ref = ctl.run(world, a)
        out = batch.step(np.array([a]))
        assert ref == tuple(int(v[0]) for v in out)
        np.testing.assert_allclose(batch.pose(0), world.pose, rtol=0, atol=POSE_TOL_M)


def test_a_robot_in_a_batch_is_the_single_robot():
    """Eight robots with their own actions in one Space == eight batches of one."""
    sc = resolve_scenario("paper-50")
    model = build_model(sc)
    rng = np.random.default_rng(3)
    n = 8
    batch = RouteBatch(sc, n)
    singles = [RouteBatch(sc, 1) for _ in range(n)]
    for k in range(400):
        if k % 100 == 0:
            for i, s0 in enumerate(rng.choice(model.start_states, n)):
                x, y = batch.disc.state_centre(int(s0))
                batch.place(i, x, y, 0.0)
                singles[i].place(0, x, y, 0.0)
        acts = rng.integers(0, 4, n)
        active = rng.random(n) < 0.8  # some robots sit a step out
        out = batch.step(acts, active)
        for i in np.flatnonzero(active):
            one = singles[i].step(acts[i:i + 1])
            assert (out.state[i], out.bumped[i], out.steps[i], out.contacts[i]) == (
                one.state[0], one.bumped[0], one.steps[0], one.contacts[0])
            assert batch.pose(i) == singles[i].pose(0)  # bit for bit
        assert not out.steps[~active].any()


def test_robots_never_touch_each_other():
    sc = resolve_scenario("paper-50")
    batch = RouteBatch(sc, 2)
    x, y = batch.disc.cell_centre(*sc.start)
    batch.place(0, x, y)
    batch.place(1, x, y)  # the same spot
    out = batch.step(np.array([3, 2]))
    assert not out.bumped.any() and out.contacts.sum() == 0


def test_bad_batch_size_is_an_error():
    with pytest.raises(ValueError, match="n_robots"):
        RouteBatch(resolve_scenario("paper-50"), 0)


def test_a_reused_rollout_env_must_record_trajectories_when_a_path_is_wanted():
    from sim.physics.models.rollouts import drive_policy, rollout_env

    sc = resolve_scenario("paper-40")
    fid = parse_fidelity("exact")
    assert not RouteBatch(sc, 1).records_trajectories
    assert RouteBatch(sc, 1, trajectories=True).records_trajectories
    plain = rollout_env(sc, 2, fid)
    assert not plain.batch.records_trajectories
    policy = np.zeros(sc.nx * sc.ny, dtype=np.int64)
    with pytest.raises(ValueError, match="trajectories"):
        drive_policy(sc, policy, fid, 2, keep_path=True, env=plain)
    assert rollout_env(sc, 2, fid, trajectories=True).batch.records_trajectories


def test_place_many_equals_place_robot_by_robot():
    """The V* builder's array placement leaves every record as place() does (bias kept)."""
    sc = resolve_scenario("paper-40")
    fid = parse_fidelity("uncalibrated")
    one, many = (RouteBatch(sc, 6, fidelity=fid) for _ in range(2))
    rng = np.random.default_rng(2)
    actions = rng.integers(0, 4, 6)
    for b in (one, many):
        for i in range(6):
            b.set_noise_rng(i, np.random.default_rng(i))  # draws each robot's bias
        b.step(actions)  # records full of a primitive's state
    idx = np.array([4, 1, 3])
    xs, ys, ths = rng.uniform(1, 9, 3), rng.uniform(1, 9, 3), rng.uniform(-3, 3, 3)
    resting = np.array([True, False, True])
    for k, i in enumerate(idx):
        one.place(int(i), xs[k], ys[k], ths[k], resting=bool(resting[k]))
    many.place_many(idx, xs, ys, ths, resting)
    assert one.robots.tobytes() == many.robots.tobytes()
    assert [len(c) for c in one.contacts] == [len(c) for c in many.contacts]


@pytest.mark.parametrize("fid", ["localised", "noisy"])
def test_the_noise_buffer_s_chunking_never_changes_a_run(fid, monkeypatch):
    """Normals are drawn in chunks that start short and double within each block of
    NOISE_BLOCK; a primitive that needs more than its block has left starts the next block.
    Drawing each block whole (the first chunk NOISE_BLOCK long) gives the same run, with
    5 normals a period (localised: wheels and odometry) as with 2."""
    import sim.physics.kernel.batch as batch_module

    sc = resolve_scenario("maze-1")
    starts = build_model(sc).start_states

    def run() -> bytes:
        b = RouteBatch(sc, 3, fidelity=parse_fidelity(fid))
        rng = np.random.default_rng(4)
        for i in range(3):
            b.set_noise_rng(i, np.random.default_rng(50 + i))
        out = []
        for k in range(600):
            if k % 200 == 0:
                for i, s0 in enumerate(rng.choice(starts, 3)):
                    b.place(i, *b.disc.state_centre(int(s0)), 0.0)
            out.append(b.step(rng.integers(0, 4, 3)).state.tobytes() + b.robots.tobytes())
        return b"".join(out)

    short = run()
    monkeypatch.setattr(batch_module, "FIRST_NOISE_BLOCK", batch_module.NOISE_BLOCK)
    assert run() == short


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_a_copied_noisy_batch_draws_from_its_own_generators(how):
    """Compiled refills read each robot's generator through a handle (its state's address):
    a copy must get handles to its own generators. With the original's, the copy drew
    the original's normals (diverging from it within a few refills) and advanced them."""
    import copy
    import pickle

    sc = resolve_scenario("paper-40")
    batch = RouteBatch(sc, 2, fidelity=parse_fidelity("noisy"))
    for i in range(2):
        batch.set_noise_rng(i, np.random.default_rng(i))
        x, y = batch.disc.state_centre(int(build_model(sc).start_states[10 * i]))
        batch.place(i, x, y, 0.0)
    rng = np.random.default_rng(5)
    for _ in range(20):
        batch.step(rng.integers(0, 4, 2))
    twin = pickle.loads(pickle.dumps(batch)) if how == "pickle" else copy.deepcopy(batch)
    before = [r.bit_generator.state for r in batch._noise_rngs]
    acts = rng.integers(0, 4, (200, 2))
    for a in acts:  # the copy alone first: the original's generators must not move
        twin.step(a)
    assert [r.bit_generator.state for r in batch._noise_rngs] == before
    for a in acts:
        batch.step(a)
    np.testing.assert_array_equal(batch.poses(), twin.poses())
