from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import sim.envs  # noqa: F401  (registers the ids)


def test_check_env_passes():
    env = gym.make("rnhql/GridRoute-v0", render_mode="rgb_array")
    check_env(env.unwrapped)


def rollout(seed, n=400):
    env = gym.make("rnhql/GridRoute-v0")
    obs, _ = env.reset(seed=seed, options={"start": "random"})
    actions = np.random.default_rng(seed).integers(4, size=n)
    out = [obs]
    for a in actions:
        obs, r, term, trunc, _ = env.step(int(a))
        out.append((obs, r, term, trunc))
        if term or trunc:
            obs, _ = env.reset(options={"start": "random"})
            out.append(obs)
    return out


def test_same_seed_same_rollout():
    assert rollout(3) == rollout(3)
    assert rollout(3) != rollout(4)


def test_reset_options_and_time_limit():
    env = gym.make("rnhql/GridRoute-v0")
    m = env.unwrapped.model
    assert env.reset(seed=0)[0] == m.start
    assert env.reset(options={"start": int(m.start_states[3])})[0] == m.start_states[3]
    with pytest.raises(ValueError, match="options"):
        env.reset(options={"start": "nowhere"})
    env.reset(options={"start": "S"})
    for _ in range(599):
        *_, trunc, _ = env.step(2)
        assert not trunc
    assert env.step(2)[3]  # truncated at 600, not terminated


def test_invalid_action_raises():
    env = gym.make("rnhql/GridRoute-v0").unwrapped
    env.reset(seed=0)
    with pytest.raises(AssertionError):
        env.step(4)
    with pytest.raises(AssertionError):
        env.step(-1)


def test_render_draws_map_agent_and_path():
    env = gym.make("rnhql/GridRoute-v0", render_mode="rgb_array")
    env.reset(seed=0)
    first = env.render()
    for _ in range(10):
        env.step(3)
    img = env.render()
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    assert (img != first).any()
