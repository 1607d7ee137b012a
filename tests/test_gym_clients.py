"""Every id through Gymnasium's own clients: its checker, its Sync/Async vector envs (through
autoresets and terminations at different steps, in every autoreset mode), pickle and
deepcopy mid-episode, spec JSON round trips, ``rewards=``, ``fidelity=`` and the
scenario's episode length."""

from __future__ import annotations

import copy
import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AsyncVectorEnv, AutoresetMode, SyncVectorEnv

import sim  # noqa: F401  (registers the ids)
from sim.env_args import InvalidAction
from sim.errors import ScenarioError
from sim.physics.fidelity import PRESETS
from sim.scenario import REWARD_SCHEMES, Circle, Rewards, Scenario
from sim.scenario_io import resolve_scenario

IDS = ["rnhql/GridRoute-v0", "rnhql/PhysicsRoute-v0", "rnhql/DiffDrive-v0"]
PHYSICS_IDS = IDS[1:]
MODES = [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP, AutoresetMode.DISABLED]
# a small open arena with one obstacle: episodes end (G reached, time limit) at different
# steps for different sub-envs within a few dozen steps
SMALL = Scenario("small", 6.0, 6.0, (1, 1), (4, 4), obstacles=(Circle(3.0, 2.0, 0.6),),
                 steps_per_episode=12)


def _policy(env_id: str, obs: np.ndarray, rng: np.random.Generator, n: int) -> np.ndarray:
    """Actions that reach G now and then: mostly up/right (DiffDrive: a noisy steer towards
    the goal, float64 as numpy hands them over)."""
    if env_id == "rnhql/DiffDrive-v0":
        bearing = np.arctan2(obs[:, 7], obs[:, 6]) - np.arctan2(obs[:, 3], obs[:, 2])
        turn = np.clip(np.sin(bearing) + rng.normal(0, 0.8, n), -1, 1) * 0.5
        return np.clip(np.stack([0.5 - turn, 0.5 + turn], axis=1), -1, 1)
    return np.where(rng.random(n) < 0.7, rng.choice([0, 3], n), rng.integers(0, 4, n))


def _kwargs(env_id: str) -> dict:
    kw = {"scenario": SMALL, "start": "random"}  # autoresets start anywhere too
    if env_id == "rnhql/DiffDrive-v0":
        kw["steps_per_episode"] = 25  # 2.5 s: some episodes reach G, others time out
    return kw


# ---------------------------------------------------------------- checkers


@pytest.mark.parametrize("rewards", [*REWARD_SCHEMES, "scenario"])
@pytest.mark.parametrize(("env_id", "fidelity"),
                         [("rnhql/GridRoute-v0", None)]
                         + [(i, f) for i in PHYSICS_IDS for f in PRESETS])
def test_gymnasium_check_env_every_id_fidelity_and_scheme(env_id, fidelity, rewards):
    kw = {"rewards": rewards, "render_mode": "rgb_array"}
    if fidelity is not None:
        kw["fidelity"] = fidelity
    if "DiffDrive" in env_id and fidelity is not None and (
            PRESETS[fidelity].biased or PRESETS[fidelity].hidden_state):
        # wheel speeds in: the knobs that act on primitives do not apply, and it says so
        with pytest.raises(ValueError, match="DiffDrive-v0 takes wheel speeds"):
            gym.make(env_id, scenario="paper-40", **kw)
        return
    env = gym.make(env_id, scenario="paper-40", **kw)
    check_env(env.unwrapped)
    u = env.unwrapped
    expected = (Rewards() if rewards == "scenario" else Rewards.preset(rewards))
    assert u.rewards == expected and u.scenario.rewards == expected
    if fidelity is not None:
        assert u.fidelity == PRESETS[fidelity]


# ---------------------------------------------------------------- vector envs


def _sync_and_async_agree(env_id: str, mode: AutoresetMode, steps: int = 70) -> int:
    """Gymnasium's SyncVectorEnv and AsyncVectorEnv over the single env, and the native
    vector env where there is one, step for step; returns how many episodes ended."""
    n, seed = 3, 7
    kw = _kwargs(env_id)
    venvs = [gym.make_vec(env_id, n, vectorization_mode="sync",
                          vector_kwargs={"autoreset_mode": mode}, **kw),
             gym.make_vec(env_id, n, vectorization_mode="async",
                          vector_kwargs={"autoreset_mode": mode}, **kw)]
    if env_id != "rnhql/GridRoute-v0":
        venvs.append(gym.make_vec(env_id, n, vectorization_mode="vector_entry_point",
                                  autoreset_mode=mode, **kw))
    assert isinstance(venvs[0], SyncVectorEnv) and isinstance(venvs[1], AsyncVectorEnv)
    for v in venvs:
        assert v.metadata["autoreset_mode"] == mode
    opts = {"start": "random"}
    firsts = [v.reset(seed=seed, options=opts) for v in venvs]
    for obs, info in firsts[1:]:
        np.testing.assert_allclose(obs, firsts[0][0], atol=1e-6)
        assert set(info) == set(firsts[0][1])
    rng = np.random.default_rng(seed)
    ended_total, ended_at = 0, set()
    ref_obs = firsts[0][0]
    for k in range(steps):
        acts = _policy(env_id, ref_obs, rng, n)
        outs = [v.step(acts) for v in venvs]
        ref_obs, ref_r, ref_te, ref_tr, ref_info = outs[0]
        for obs, r, te, tr, info in outs[1:]:
            np.testing.assert_allclose(obs, ref_obs, atol=1e-5)
            np.testing.assert_allclose(r, ref_r)
            np.testing.assert_array_equal(te, ref_te)
            np.testing.assert_array_equal(tr, ref_tr)
            assert set(info) == set(ref_info), set(info) ^ set(ref_info)
            for key, val in ref_info.items():
                if key == "final_obs":
                    for a, b in zip(info[key], val, strict=True):
                        assert (a is None) == (b is None)
                        if a is not None:
                            np.testing.assert_allclose(a, b, atol=1e-5)
                elif key == "final_info":
                    for kk in val:
                        np.testing.assert_allclose(info[key][kk], val[kk], atol=1e-5)
                else:
                    np.testing.assert_allclose(info[key], val, atol=1e-5, err_msg=key)
        ended = ref_te | ref_tr
        if ended.any():
            ended_at.add(k)
        ended_total += int(ended.sum())
        if mode == AutoresetMode.SAME_STEP and ended.any():
            assert ref_info["_final_obs"].tolist() == ended.tolist()
        if mode == AutoresetMode.DISABLED and ended.any():  # the caller resets them
            for v in venvs:
                ref_obs = v.reset(options={"reset_mask": ended, **opts})[0]
    for v in venvs:
        v.close()
    assert len(ended_at) >= 3  # episodes ended at several different steps
    return ended_total


@pytest.mark.parametrize("mode", MODES, ids=[m.value for m in MODES])
@pytest.mark.parametrize("env_id", IDS)
def test_sync_async_and_native_vector_envs_agree_through_autoresets(env_id, mode):
    assert _sync_and_async_agree(env_id, mode) >= 6


def test_native_vector_env_defaults_follow_the_id():
    v = gym.make_vec("rnhql/PhysicsRoute-v0", 2, vectorization_mode="vector_entry_point",
                     scenario="ost003d")
    assert v.unwrapped.rewards == Rewards.preset("goal-only")
    assert v.unwrapped.max_episode_steps == 1704  # the scenario's, not 600
    with pytest.raises(ValueError, match="autoreset_mode"):
        gym.make_vec("rnhql/DiffDrive-v0", 2, vectorization_mode="vector_entry_point",
                     autoreset_mode="sometimes")


# ---------------------------------------------------------------- copies


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
@pytest.mark.parametrize("env_id", IDS)
def test_pickle_and_deepcopy_mid_episode_continue_identically(env_id, how):
    kw = {"fidelity": "noisy"} if env_id != "rnhql/GridRoute-v0" else {}
    env = gym.make(env_id, scenario="paper-40", **kw)
    env.reset(seed=3, options={"start": "random"})
    rng = np.random.default_rng(3)
    acts = [env.action_space.sample() for _ in range(40)]
    env.action_space.seed(3)
    for a in acts[:20]:
        env.step(a)
    twin = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    for a in acts[20:]:
        a = a if env_id == "rnhql/DiffDrive-v0" else int(rng.integers(4))
        one, two = env.step(a), twin.step(a)
        np.testing.assert_array_equal(one[0], two[0])
        assert one[1:4] == two[1:4]
        assert one[4].keys() == two[4].keys()


# ---------------------------------------------------------------- specs and arguments


@pytest.mark.parametrize("env_id", IDS)
def test_spec_json_round_trip_with_a_scenario_object(env_id):
    sc = resolve_scenario("paper-40")
    env = gym.make(env_id, scenario=sc, rewards=Rewards.preset("step-cost"))
    spec = EnvSpec.from_json(env.spec.to_json())
    again = gym.make(spec)
    assert again.unwrapped.scenario == env.unwrapped.scenario
    assert again.unwrapped.rewards == Rewards.preset("step-cost")
    a = env.action_space.sample()
    np.testing.assert_array_equal(env.reset(seed=1)[0], again.reset(seed=1)[0])
    assert env.step(a)[1:4] == again.step(a)[1:4]


def test_rewards_argument_and_default():
    g = gym.make("rnhql/GridRoute-v0", scenario="paper-40").unwrapped
    assert g.rewards.scheme == "goal-only"  # made by id: goal-only
    assert float(g.model.reward[g.model.reward > 0].min()) == 100.0  # no pay for wandering
    p = gym.make("rnhql/GridRoute-v0", scenario="paper-40", rewards="paper").unwrapped
    assert p.rewards == Rewards()
    c = gym.make("rnhql/PhysicsRoute-v0", scenario="paper-40",
                 rewards="goal=10,bump=-2,step=0").unwrapped
    assert (c.rewards.goal, c.rewards.bump, c.rewards.step) == (10, -2, 0)
    with pytest.raises(ScenarioError, match="unknown reward scheme"):
        gym.make("rnhql/DiffDrive-v0", rewards="lots")
    with pytest.raises(ScenarioError, match="fidelity"):
        gym.make("rnhql/DiffDrive-v0", fidelity="perfect")
    with pytest.raises(ScenarioError, match="steps_per_episode"):
        gym.make("rnhql/GridRoute-v0", steps_per_episode=0)
    with pytest.raises(ScenarioError, match=r"scenario\.robot\.wheels"):
        gym.make("rnhql/GridRoute-v0", scenario={**_asdict(SMALL), "robot": {"wheels": 3}})


def _asdict(sc: Scenario) -> dict:
    import dataclasses

    return dataclasses.asdict(sc)


@pytest.mark.parametrize("env_id", IDS)
def test_scenario_episode_length_is_honoured(env_id):
    env = gym.make(env_id, scenario=SMALL)
    u = env.unwrapped
    expected = (SMALL.steps_per_episode if env_id != "rnhql/DiffDrive-v0"
                else 12 * 10)  # 12 cells of 1 m at 1 m/s, in 0.1 s periods
    assert u.steps_per_episode == expected
    env.reset(seed=0)
    stay = np.zeros(2) if env_id == "rnhql/DiffDrive-v0" else 2  # stand still / bump west
    for k in range(expected):
        *_, term, trunc, _ = env.step(stay)
        assert not term and trunc == (k == expected - 1)
    assert gym.make(env_id, scenario="ost003d").unwrapped.steps_per_episode >= 1704


def test_diffdrive_fidelity_is_applied():
    exact = gym.make("rnhql/DiffDrive-v0", scenario="paper-40", fidelity="exact")
    noisy = gym.make("rnhql/DiffDrive-v0", scenario="paper-40", fidelity="noisy")
    assert noisy.unwrapped.fidelity.wheel_noise > 0
    runs = []
    for env in (exact, noisy, noisy):
        env.reset(seed=5)
        for _ in range(30):
            obs, *_ = env.step(np.array([0.8, 0.8]))
        runs.append(obs)
    assert abs(runs[0][3]) < 1e-6  # exact: straight ahead, heading unchanged
    assert abs(runs[1][3]) > 1e-4  # noisy: wheels deliver unequal speeds, it turns
    np.testing.assert_array_equal(runs[1], runs[2])  # deterministic per seed


# ---------------------------------------------------------------- actions, reset, info


@pytest.mark.parametrize("env_id", IDS[:2])
def test_discrete_actions_as_clients_pass_them(env_id):
    env = gym.make(env_id, scenario="paper-40")
    env.reset(seed=0)
    for a in (3, np.int64(3), np.array(3), np.array([3]), np.int32(2)):
        env.step(a)
    for bad in (np.array(1.0), np.array([1, 2]), 4, True, "up"):
        with pytest.raises(InvalidAction):
            env.step(bad)


def test_diffdrive_accepts_float64_and_clips():
    env = gym.make("rnhql/DiffDrive-v0", scenario="paper-40").unwrapped
    env.reset(seed=0)
    for _ in range(10):
        *_, info = env.step(np.array([5.0, 5.0]))  # float64 beyond the limit: driven at 1 m/s
    np.testing.assert_allclose(info["wheels"], [1.0, 1.0])
    with pytest.raises(InvalidAction, match="finite"):
        env.step(np.array([np.inf, 0.0]))
    with pytest.raises(InvalidAction, match="shape"):
        env.step(np.zeros(3))


@pytest.mark.parametrize("env_id", IDS)
def test_start_argument_sets_where_bare_resets_begin(env_id):
    env = gym.make(env_id, scenario="paper-40", start="random")
    m = env.unwrapped.model
    starts = {int(env.reset(seed=k)[1]["state"]) for k in range(8)}
    assert len(starts) > 4 and starts <= set(m.start_states.tolist())
    assert env.reset(options={"start": "S"})[1]["state"] == m.start  # the option wins
    with pytest.raises(ValueError, match="start"):
        gym.make(env_id, scenario="paper-40", start="anywhere")


def test_grid_step_before_reset_raises():
    env = gym.make("rnhql/GridRoute-v0", disable_env_checker=True).unwrapped
    with pytest.raises(gym.error.ResetNeeded):
        env.step(0)


INFO_KEYS = {
    "rnhql/GridRoute-v0": {"state", "bumped"},
    "rnhql/PhysicsRoute-v0": {"state", "bumped", "reached", "timeout", "steps", "contacts",
                              "pose", "time_s"},
    "rnhql/DiffDrive-v0": {"state", "bumped", "in_contact", "contacts", "pose", "time_s",
                           "wheels"},
}


@pytest.mark.parametrize("env_id", IDS)
def test_info_keys_are_the_same_after_reset_step_and_in_vector_envs(env_id):
    env = gym.make(env_id, scenario="paper-40")
    _, info0 = env.reset(seed=0)
    *_, info1 = env.step(env.action_space.sample())
    assert set(info0) == set(info1) == INFO_KEYS[env_id]
    for k in info0:
        assert np.asarray(info0[k]).shape == np.asarray(info1[k]).shape
    assert info1["state"] == (env.unwrapped.disc.state_of(*info1["pose"][:2])
                              if env_id != "rnhql/GridRoute-v0" else info1["state"])
    if env_id != "rnhql/GridRoute-v0":
        v = gym.make_vec(env_id, 2, vectorization_mode="vector_entry_point",
                         scenario="paper-40")
        _, vinfo = v.reset(seed=0)
        assert {k for k in vinfo if not k.startswith("_")} == INFO_KEYS[env_id]


@pytest.mark.parametrize("env_id", ["rnhql/GridRoute-v0", "rnhql/PhysicsRoute-v0",
                                    "rnhql/DiffDrive-v0"])
def test_the_spec_says_the_limit_the_env_truncates_at(env_id):
    """A client that reads env.spec.max_episode_steps sees the scenario's limit (the env
    truncates itself there; make adds no TimeLimit)."""
    import gymnasium as gym

    env = gym.make(env_id, scenario="ost003d" if env_id != "rnhql/DiffDrive-v0" else "paper-40",
                   steps_per_episode=17)
    assert env.spec.max_episode_steps == env.unwrapped.steps_per_episode == 17
    inner = env
    while hasattr(inner, "env"):
        assert type(inner).__name__ != "TimeLimit"
        inner = inner.env
