"""What a Gymnasium client hands the envs: bad input is one clear error naming the argument
(not silently coerced), and the valid forms the issue found refused are accepted."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec

import sim  # registers the ids (sim.__file__ is used too)
from sim.env_args import InvalidAction

IDS = ["rnhql/GridRoute-v0", "rnhql/PhysicsRoute-v0", "rnhql/DiffDrive-v0"]
SCENARIO = "paper-40"
PAPER40_TOML = Path(sim.__file__).resolve().parent / "builtin" / "paper-40.toml"


def _vec(env_id: str, n: int = 2, **kw):
    return gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        scenario=SCENARIO, **kw)


def test_heading_option_takes_only_finite_real_numbers():
    env = gym.make("rnhql/DiffDrive-v0", scenario=SCENARIO).unwrapped
    for bad in ("1.0", True, np.bool_(True), np.array(1.0), None, float("nan"), float("inf")):
        with pytest.raises(ValueError, match=r"options\['heading'\]"):
            env.reset(seed=0, options={"heading": bad})
    for good in (1, 0.5, np.float32(0.5), np.int64(2), np.float64(-1.0)):
        _, info = env.reset(seed=0, options={"heading": good})
        assert info["pose"][2] == pytest.approx(float(good), abs=1e-6)
    env.step(np.zeros(2))


def test_object_and_float_action_arrays_are_refused_not_cast():
    single = gym.make("rnhql/DiffDrive-v0", scenario=SCENARIO).unwrapped
    single.reset(seed=0)
    for bad in (np.array([0.1, 0.2], dtype=object), [0.1, "0.2"], np.array([True, False])):
        with pytest.raises(InvalidAction, match=r"action must be numbers.*dtype"):
            single.step(bad)
    for good in (np.array([0.1, 0.2]), np.array([0.1, 0.2], np.float32), [0.1, 0.2],
                 np.array([0, 1])):  # SB3's float64, the space's float32, a list, ints
        single.step(good)

    for env_id in ("rnhql/GridRoute-v0", "rnhql/PhysicsRoute-v0"):
        venv = _vec(env_id)
        venv.reset(seed=0)
        for bad in (np.array([1, 2], dtype=object), np.array([1.0, 2.0], dtype=object),
                    np.array([1.0, 2.0]), np.array([True, False])):
            with pytest.raises(InvalidAction, match="actions must be 2 integers"):
                venv.step(bad)
        for good in (np.array([1, 2]), np.array([1, 2], np.int32), [3, 0]):
            venv.step(good)
        venv.close()

    dvenv = _vec("rnhql/DiffDrive-v0")
    dvenv.reset(seed=0)
    with pytest.raises(InvalidAction, match=r"actions must be numbers.*dtype object"):
        dvenv.step(np.zeros((2, 2), dtype=object))
    dvenv.step(np.zeros((2, 2)))
    dvenv.close()


def test_starts_option_needs_integer_free_states_that_reach_the_goal():
    venv = _vec("rnhql/PhysicsRoute-v0")
    m = venv.unwrapped.model
    blocked = int(np.flatnonzero(m.distance_to_goal < 0)[0])
    ok = [int(m.start_states[0]), int(m.start_states[1])]
    with pytest.raises(ValueError, match=r"options\['starts'\] must be 2 integer states"):
        venv.reset(options={"starts": [3.7, 5.0]})
    with pytest.raises(ValueError, match=r"options\['starts'\] must be 2 integer states"):
        venv.reset(options={"starts": ok[:1]})
    with pytest.raises(ValueError, match=r"options\['starts'\]\[0\] = .* free state"):
        venv.reset(options={"starts": [blocked, ok[1]]})
    with pytest.raises(ValueError, match=r"options\['starts'\]\[1\] = .* free state"):
        venv.reset(options={"starts": [ok[0], m.n_states]})
    obs, _ = venv.reset(options={"starts": np.array(ok)})
    assert obs.tolist() == ok
    # an entry the mask does not reset is not read
    obs, _ = venv.reset(options={"starts": [blocked, ok[0]],
                                 "reset_mask": np.array([False, True])})
    assert obs.tolist() == [ok[0], ok[0]]
    venv.step(np.array([0, 0]))
    venv.close()


@pytest.mark.parametrize("env_id", IDS[1:])
def test_reset_mask_is_one_bool_per_sub_env(env_id):
    venv = _vec(env_id, 3)
    venv.reset(seed=0)
    for bad in (np.array([True]), np.ones(4, bool), np.array([2, 0, 1]),
                np.array([1.0, 0.0, 1.0]), np.ones((3, 1), bool), "yes", None):
        with pytest.raises(ValueError, match=r"options\['reset_mask'\] must be 3 booleans"):
            venv.reset(options={"reset_mask": bad})
    for good in (np.array([True, False, True]), [1, 0, 0], np.array([0, 1, 1], np.int8)):
        venv.reset(options={"reset_mask": good})
    venv.step(venv.action_space.sample())
    venv.close()


@pytest.mark.parametrize("env_id", IDS)
def test_a_path_scenario_and_a_numpy_num_envs_are_accepted(env_id):
    env = gym.make(env_id, scenario=PAPER40_TOML)
    assert env.unwrapped.scenario.name == gym.make(env_id, scenario=SCENARIO) \
        .unwrapped.scenario.name
    env.reset(seed=0)
    env.step(env.action_space.sample())
    again = gym.make(EnvSpec.from_json(env.spec.to_json()))  # the spec holds it as a str
    again.reset(seed=0)
    venv = gym.make_vec(env_id, num_envs=np.int64(2), vectorization_mode="vector_entry_point",
                        scenario=PAPER40_TOML)
    assert venv.num_envs == 2 and type(venv.num_envs) is int
    venv.reset(seed=0)
    venv.step(venv.action_space.sample())
    venv.close()
