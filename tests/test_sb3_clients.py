"""Stable-Baselines3 through its public API only: its ``check_env`` for every id, fidelity
and reward scheme, the ``model.predict`` -> ``env.step`` loop, and the ``VecEnv`` adapter
over the native vector envs. Skipped without ``rnhql[sb3]``."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

sb3 = pytest.importorskip("stable_baselines3")

from stable_baselines3 import DQN, PPO  # noqa: E402
from stable_baselines3.common.env_checker import check_env  # noqa: E402
from stable_baselines3.common.vec_env import DummyVecEnv  # noqa: E402

import sim  # noqa: E402, F401  (registers the ids)
from sim.physics.fidelity import PRESETS  # noqa: E402
from sim.scenario import REWARD_SCHEMES, Circle, Scenario  # noqa: E402

IDS = ["rnhql/GridRoute-v0", "rnhql/PhysicsRoute-v0", "rnhql/DiffDrive-v0"]
SMALL = Scenario("small", 6.0, 6.0, (1, 1), (4, 4), obstacles=(Circle(3.0, 2.0, 0.6),),
                 steps_per_episode=15)


def _wheel_level(name: str) -> bool:
    """A rung DiffDrive takes: wheel noise only (it refuses the primitive-level knobs)."""
    f = PRESETS[name]
    return not (f.biased or f.open_loop or f.localisation or f.latency or f.slips)


@pytest.mark.parametrize("rewards", list(REWARD_SCHEMES))
@pytest.mark.parametrize(("env_id", "fidelity"),
                         [("rnhql/GridRoute-v0", None)]
                         + [("rnhql/PhysicsRoute-v0", f) for f in PRESETS]
                         + [("rnhql/DiffDrive-v0", f) for f in PRESETS if _wheel_level(f)])
def test_sb3_check_env_every_id_fidelity_and_scheme(env_id, fidelity, rewards):
    kw = {} if fidelity is None else {"fidelity": fidelity}
    check_env(gym.make(env_id, scenario="paper-40", rewards=rewards, **kw), warn=True)


def _model(env_id, env):
    if env_id == "rnhql/DiffDrive-v0":
        return PPO("MlpPolicy", env, n_steps=32, batch_size=32, seed=0, device="cpu")
    return DQN("MlpPolicy", env, learning_starts=10, seed=0, device="cpu")


@pytest.mark.parametrize("env_id", IDS)
def test_predict_step_loop_runs_as_in_the_sb3_docs(env_id):
    kw = {"steps_per_episode": 30} if env_id == "rnhql/DiffDrive-v0" else {}
    env = gym.make(env_id, scenario=SMALL, **kw)
    model = _model(env_id, env)
    obs, _ = env.reset(seed=0)
    ends = 0
    for _ in range(80):
        action, _ = model.predict(obs, deterministic=False)
        if env_id == "rnhql/DiffDrive-v0":
            action = action.astype(np.float64) * 3.0  # numpy's default dtype, out of range
        obs, reward, terminated, truncated, _info = env.step(action)
        assert env.observation_space.contains(obs) and isinstance(reward, float)
        if terminated or truncated:
            ends += 1
            obs, _ = env.reset()
    assert ends >= 1


@pytest.mark.parametrize("env_id", IDS[1:])
def test_adapter_equals_dummy_vec_env(env_id):
    """SB3VecEnv over the native vector env == SB3's DummyVecEnv over the single envs."""
    from sim.sb3_vec import SB3VecEnv

    n = 3
    kw = {"scenario": SMALL}
    if env_id == "rnhql/DiffDrive-v0":
        kw["steps_per_episode"] = 20
    fast = SB3VecEnv(gym.make_vec(env_id, n, vectorization_mode="vector_entry_point",
                                  autoreset_mode="SameStep", **kw))
    slow = DummyVecEnv([lambda: gym.make(env_id, **kw) for _ in range(n)])
    fast.seed(4)
    slow.seed(4)
    o1, o2 = fast.reset(), slow.reset()
    np.testing.assert_allclose(o1, o2, atol=1e-6)
    rng = np.random.default_rng(0)
    dones = 0
    for _ in range(40):
        if env_id == "rnhql/DiffDrive-v0":
            a = rng.uniform(-0.2, 1.0, (n, 2)).astype(np.float32)
        else:
            a = rng.integers(0, 4, n)
        f, s = fast.step(a), slow.step(a)
        np.testing.assert_allclose(f[0], s[0], atol=1e-5)
        np.testing.assert_allclose(f[1], s[1])
        np.testing.assert_array_equal(f[2], s[2])
        for i in np.flatnonzero(s[2]):
            dones += 1
            np.testing.assert_allclose(f[3][i]["terminal_observation"],
                                       s[3][i]["terminal_observation"], atol=1e-5)
            assert f[3][i]["TimeLimit.truncated"] == s[3][i]["TimeLimit.truncated"]
            assert f[3][i]["state"] == s[3][i]["state"]
    assert dones >= 2
    fast.close()


def test_adapter_answers_shared_attributes_and_resets_one_robot():
    """get_attr answers what DummyVecEnv answers; env_method("reset", indices=[i]) on a native
    vector env resets robot i alone."""
    from sim.sb3_vec import SB3VecEnv

    native = SB3VecEnv(gym.make_vec("rnhql/PhysicsRoute-v0", 3,
                                    vectorization_mode="vector_entry_point", scenario=SMALL,
                                    autoreset_mode="SameStep"))
    dummy = DummyVecEnv([lambda: gym.make("rnhql/PhysicsRoute-v0", scenario=SMALL)] * 3)
    for attr in ("scenario", "rewards", "steps_per_episode", "fidelity"):
        assert native.get_attr(attr) == dummy.get_attr(attr), attr
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        native.get_attr("nothing")
    start = native.reset()
    moved = native.step(np.array([0, 0, 0]))[0]
    assert (moved != start).all()
    (obs, info), = native.env_method("reset", indices=[1])
    now = native.venv.unwrapped._obs
    assert obs == start[1] and info["state"] == start[1]
    assert now[1] == start[1] and now[0] == moved[0] and now[2] == moved[2]


def test_adapter_refuses_other_autoreset_modes():
    from sim.sb3_vec import SB3VecEnv

    with pytest.raises(ValueError, match="SAME_STEP"):
        SB3VecEnv(gym.make_vec("rnhql/PhysicsRoute-v0", 2,
                               vectorization_mode="vector_entry_point", scenario=SMALL))


@pytest.mark.slow
def test_dqn_learns_through_the_adapter_briefly():
    from sim.sb3_vec import SB3VecEnv

    venv = SB3VecEnv(gym.make_vec("rnhql/PhysicsRoute-v0", 4,
                                  vectorization_mode="vector_entry_point",
                                  autoreset_mode="SameStep", scenario=SMALL))
    model = DQN("MlpPolicy", venv, learning_starts=50, seed=0, device="cpu")
    model.learn(400)
    assert model.num_timesteps >= 400
