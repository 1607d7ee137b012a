"""The two drivers run one set of rules: same seed, same tables and weights.

The fused kernel trains on ``env.unwrapped.model``; the step agent plays
``rnhql/GridRoute-v0`` through gymnasium. Both draw starts, exploration, ties
and planning from one generator in the same order, so after 50 episodes every
state array must be bit-identical, and so must the per-episode results.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import sim.envs  # noqa: F401  (registers rnhql/GridRoute-v0)
from learning import METHODS, RNHQL, geometry_of, init_state, make_agent, run_env_episodes
from learning.kernels import run_episodes
from learning.methods import RNHQLPlus

EPISODES = 50


@pytest.fixture(scope="module")
def env():
    e = gym.make("rnhql/GridRoute-v0")
    yield e
    e.close()


CONFIGS = [cls() for cls in METHODS.values()] + [
    RNHQL(warmup_episodes=20, freeze_after_episodes=40),  # shaping and freezing inside 50 eps
    # rnh-ql+ ingredients one by one (the default is in METHODS above)
    RNHQLPlus(leak_free=1, normalise=1), RNHQLPlus(lam_q=0.8, n_planning=2),
    RNHQLPlus(v_target=0, rebase=0, warmup_episodes=20, freeze_after_episodes=40),
    RNHQLPlus(v_target=2, spacing=0, cutoff=0),
]


@pytest.mark.parametrize("cfg", CONFIGS, ids=[f"{c.cli}-{i}" for i, c in enumerate(CONFIGS)])
def test_kernel_equals_step_agent(env, cfg):
    model = env.unwrapped.model
    geom = geometry_of(model)
    rng_k = np.random.default_rng(2024)
    st = init_state(cfg, geom, rng_k)
    out = (np.zeros(EPISODES, np.int32), np.zeros(EPISODES), np.zeros(EPISODES, bool),
           np.zeros(EPISODES), np.zeros(EPISODES))
    run_episodes(st, model, EPISODES, rng_k, out)

    rng_a = np.random.default_rng(2024)
    agent = make_agent(cfg, geom, rng_a)
    log = run_env_episodes(agent, env, EPISODES)

    for name, a, b in zip(st._fields, st, agent.state, strict=True):
        assert np.array_equal(a, b), f"{cfg.cli}: state slot {name} differs"
    np.testing.assert_array_equal(out[0], log.steps)
    np.testing.assert_array_equal(out[1], log.returns)
    np.testing.assert_array_equal(out[2], log.success)
    np.testing.assert_array_equal(out[3], log.shaping_mean)
    assert rng_k.bit_generator.state == rng_a.bit_generator.state
    assert agent.episodes_done == EPISODES


def test_step_agent_without_start_states_uses_env_start(env):
    model = env.unwrapped.model
    geom = geometry_of(model)
    from dataclasses import replace

    agent = make_agent(METHODS["st-ql"](), replace(geom, start_states=None),
                       np.random.default_rng(0))
    log = run_env_episodes(agent, env, 2)
    assert log.steps.shape == (2,) and agent.episodes_done == 2
