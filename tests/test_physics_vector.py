"""``make_vec("rnhql/PhysicsRoute-v0", vectorization_mode="vector_entry_point")``: a gymnasium
VectorEnv whose sub-env i is the single env with its seed."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, VectorEnv

import sim  # noqa: F401  (registers the ids)
from sim.physics.envs.vector import PhysicsRouteVectorEnv


def _make(n, **kw):
    return gym.make_vec("rnhql/PhysicsRoute-v0", num_envs=n,
                        vectorization_mode="vector_entry_point", scenario="paper-40", **kw)


def test_make_vec_returns_the_batched_world():
    env = _make(3)
    assert isinstance(env.unwrapped, PhysicsRouteVectorEnv) and isinstance(env, VectorEnv)
    assert env.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    assert env.single_action_space == gym.spaces.Discrete(4)
    assert env.single_observation_space.n == env.unwrapped.model.n_states
    assert env.observation_space.shape == (3,) and env.action_space.shape == (3,)
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs) and info["_pose"].all()
    obs, rew, term, trunc, info = env.step(env.action_space.sample())
    assert obs.shape == rew.shape == term.shape == trunc.shape == (3,)
    assert info["pose"].shape == (3, 3)
    env.close()


def test_sub_env_equals_the_single_env_with_its_seed_through_autoresets():
    n, seed, horizon = 4, 11, 25
    venv = _make(n, max_episode_steps=horizon)
    singles = [gym.make("rnhql/PhysicsRoute-v0", scenario="paper-40",
                        max_episode_steps=horizon) for _ in range(n)]
    opts = {"start": "random"}
    obs, _ = venv.reset(seed=seed, options=opts)
    single_obs = [e.reset(seed=seed + i, options=opts)[0] for i, e in enumerate(singles)]
    assert obs.tolist() == single_obs
    rng = np.random.default_rng(0)
    ended = np.zeros(n, bool)
    episodes_ended = 0
    for _ in range(120):
        acts = rng.integers(0, 4, n)
        obs, rew, term, trunc, info = venv.step(acts)
        for i, e in enumerate(singles):
            if ended[i]:  # NEXT_STEP: this step reset sub-env i and ignored its action
                o, _ = e.reset()  # autoreset_options=None: a bare reset (start at S)
                assert (obs[i], rew[i], term[i], trunc[i]) == (o, 0.0, False, False)
                continue
            o, r, te, tr, inf = e.step(int(acts[i]))
            assert (obs[i], rew[i], term[i], trunc[i]) == (o, r, te, tr)
            assert info["bumped"][i] == inf["bumped"] and info["steps"][i] == inf["steps"]
            assert info["contacts"][i] == inf["contacts"]
            np.testing.assert_allclose(info["pose"][i], inf["pose"], atol=1e-12)
        ended = term | trunc
        episodes_ended += int(ended.sum())
    assert episodes_ended >= n  # every sub-env went through at least one autoreset


def test_bad_actions_and_sizes_are_errors():
    venv = _make(2)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match=r"0\.\.3"):
        venv.step(np.array([0, 7]))
    with pytest.raises(ValueError, match="num_envs"):
        PhysicsRouteVectorEnv(0, scenario="paper-40")
    with pytest.raises(ValueError, match="seeds"):
        venv.reset(seed=[1, 2, 3])


def test_diffdrive_vector_env_sub_env_equals_single_env():
    n, seed, horizon = 3, 5, 150
    venv = gym.make_vec("rnhql/DiffDrive-v0", num_envs=n, vectorization_mode="vector_entry_point",
                        scenario="paper-40", max_episode_steps=horizon)
    assert venv.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    assert venv.single_action_space.shape == (2,) and venv.action_space.shape == (n, 2)
    singles = [gym.make("rnhql/DiffDrive-v0", scenario="paper-40", max_episode_steps=horizon)
               for _ in range(n)]
    opts = {"start": "random"}
    obs, _ = venv.reset(seed=seed, options=opts)
    for i, e in enumerate(singles):
        np.testing.assert_array_equal(obs[i], e.reset(seed=seed + i, options=opts)[0])
    rng = np.random.default_rng(1)
    vmax = float(venv.single_action_space.high[0])
    ended = np.zeros(n, bool)
    contacts = 0
    for k in range(200):
        acts = rng.uniform(-vmax, vmax, (n, 2)).astype(np.float32)
        if k % 10:  # mostly full speed ahead: reach walls and obstacles, push into them
            acts[:] = vmax
        obs, rew, term, trunc, info = venv.step(acts)
        for i, e in enumerate(singles):
            if ended[i]:
                o, _ = e.reset()
                np.testing.assert_array_equal(obs[i], o)
                continue
            o, r, te, tr, inf = e.step(acts[i])
            np.testing.assert_allclose(obs[i], o, atol=1e-6)
            assert (rew[i], term[i], trunc[i]) == (r, te, tr)
            assert info["contacts"][i] == inf["contacts"]
            np.testing.assert_allclose(info["pose"][i], inf["pose"], atol=1e-9)
            contacts += inf["contacts"]
        ended = term | trunc
    assert contacts > 0  # the robots did touch walls or obstacles


def test_primitive_metres_is_each_sub_envs_trajectory_length():
    """The graded drives' metres come from one call over every robot: the sum of the steps'
    lengths of each sub-env's trajectory, bumps and robots at rest included."""
    from sim.physics.fidelity import parse_fidelity

    env = PhysicsRouteVectorEnv(5, "paper-40", fidelity=parse_fidelity("noisy"),
                                trajectories=True)
    for k in range(5):
        env.set_noise_rng(k, np.random.default_rng(k))
    env.reset(seed=3, options={"start": "random"})
    rng = np.random.default_rng(1)
    moved = 0.0
    for _ in range(40):
        env.step(rng.integers(0, 4, 5))
        got = env.primitive_metres()
        for i in range(5):
            traj = env.trajectory(i)
            want = float(np.hypot(*np.diff(traj[:, :2], axis=0).T).sum())
            assert got[i] == pytest.approx(want, rel=1e-12, abs=1e-15)
        moved += got.sum()
    assert moved > 1.0
    env.close()
