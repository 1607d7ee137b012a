from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import sim.envs  # noqa: F401  (registers the ids)
from sim.physics.envs.diffdrive import DiffDriveEnv
from sim.physics.envs.route import PhysicsRouteEnv
from sim.physics.static import CollisionType

IDS = ["rnhql/PhysicsRoute-v0", "rnhql/DiffDrive-v0"]


@pytest.mark.parametrize("env_id", IDS)
def test_check_env_passes(env_id):
    env = gym.make(env_id, render_mode="rgb_array")
    check_env(env.unwrapped)


def test_route_env_mirrors_the_grid_env():
    grid = gym.make("rnhql/GridRoute-v0").unwrapped
    phys = gym.make("rnhql/PhysicsRoute-v0").unwrapped
    assert phys.observation_space == grid.observation_space
    assert phys.action_space == grid.action_space == gym.spaces.Discrete(4)
    assert np.array_equal(phys.model.next_state, grid.model.next_state)
    assert phys.scenario == grid.scenario
    m = phys.model
    s, info = phys.reset(seed=0)
    assert s == m.start and info["pose"].tolist() == [*m.coords[m.start], 0.0]
    assert phys.reset(options={"start": int(m.start_states[7])})[0] == m.start_states[7]
    with pytest.raises(ValueError, match="options"):
        phys.reset(options={"start": "nowhere"})
    draws = {phys.reset(options={"start": "random"})[0] for _ in range(20)}
    assert len(draws) > 10 and draws <= set(m.start_states.tolist())


def test_route_env_rewards_and_info():
    env = PhysicsRouteEnv("paper-50")
    m, rw = env.model, env.scenario.rewards
    env.reset(seed=0, options={"start": m.start})  # S = (5, 5); cells to the left are free
    for _ in range(5):
        s, r, term, trunc, info = env.step(2)
        assert r == rw.step and not info["bumped"] and info["reached"]
    assert s == 5 * m.nx  # cell (0, 5)
    s2, r, term, trunc, info = env.step(2)  # into the west wall
    assert (s2, r, term, trunc) == (s, rw.bump, False, False)
    assert info["bumped"] and info["contacts"] == 1
    assert env.contact_records()[-1].kind is CollisionType.WALL
    traj = env.trajectory()
    assert traj.ndim == 2 and traj.shape[1] == 3 and len(traj) == info["steps"] + 1
    assert info["pose"][:2] == pytest.approx(tuple(m.coords[s]))
    assert info["time_s"] > 0
    # one move from a neighbour of G into G: goal reward, terminated
    g = m.goal
    nb = next(int(t) for t in range(m.n_states) for a in range(4)
              if m.next_state[t, a] == g and t != g)
    a = next(a for a in range(4) if m.next_state[nb, a] == g)
    env.reset(options={"start": nb})
    s, r, term, trunc, _ = env.step(a)
    assert (s, r, term, trunc) == (g, rw.goal, True, False)


@pytest.mark.parametrize("bad", [4, -1, 1.5, "up", None, np.int64(7)])
def test_route_env_invalid_actions_raise(bad):
    env = gym.make("rnhql/PhysicsRoute-v0").unwrapped
    env.reset(seed=0)
    with pytest.raises(AssertionError):
        env.step(bad)


@pytest.mark.parametrize("bad", [np.array([0.1], dtype=np.float32),
                                 np.array([np.nan, 0.0], dtype=np.float32)])
def test_diffdrive_invalid_actions_raise(bad):
    env = gym.make("rnhql/DiffDrive-v0").unwrapped
    env.reset(seed=0)
    with pytest.raises(AssertionError):
        env.step(bad)


def rollout(env_id, seed, n=120):
    env = gym.make(env_id)
    obs, _ = env.reset(seed=seed, options={"start": "random"})
    env.action_space.seed(seed)
    out = [np.asarray(obs).tolist()]
    for _ in range(n):
        obs, r, term, trunc, _info = env.step(env.action_space.sample())
        out.append((np.asarray(obs).tolist(), r, term, trunc,
                    env.unwrapped.trajectory().tolist()))
        if term or trunc:
            obs, _ = env.reset(options={"start": "random"})
            out.append(np.asarray(obs).tolist())
    return out


@pytest.mark.parametrize("env_id", IDS)
def test_same_seed_same_run_bit_for_bit(env_id):
    assert rollout(env_id, 11) == rollout(env_id, 11)
    assert rollout(env_id, 11) != rollout(env_id, 12)


def test_time_limit_truncates_route_env():
    env = gym.make("rnhql/PhysicsRoute-v0")
    env.reset(seed=0)
    for _ in range(599):
        *_, trunc, _ = env.step(2)  # mostly bumps into the west wall
        assert not trunc
    assert env.step(2)[3]


@pytest.mark.parametrize("env_id", IDS)
def test_render_draws_robot_and_trail(env_id):
    env = gym.make(env_id, render_mode="rgb_array")
    env.reset(seed=0)
    first = env.render()
    env.action_space.seed(0)
    for _ in range(15):
        env.step(env.action_space.sample())
    img = env.render()
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    assert img.shape == first.shape and (img != first).any()
    assert gym.make(env_id).unwrapped.render() is None  # no render_mode: nothing drawn


def test_diffdrive_drives_observes_and_bumps():
    env = DiffDriveEnv("paper-50")
    obs, info = env.reset(seed=0, options={"start": "S", "heading": np.pi})
    assert env.observation_space.contains(obs)
    x0 = obs[0]
    full = np.array([1.0, 1.0], dtype=np.float32)
    bumps, rewards = 0, []
    for _ in range(80):  # 8 s at full speed towards the west wall, 5 m away
        obs, r, _term, _trunc, info = env.step(full)
        rewards.append(r)
        bumps += info["contacts"]
        assert env.observation_space.contains(obs)
        assert env.trajectory().shape == (env.config.substeps + 1, 3)
    assert obs[0] < x0 and bumps >= 1 and env.scenario.rewards.bump in rewards
    assert env.scenario.rewards.step in rewards  # cells changed on the way
    assert obs[4] == pytest.approx(0.0, abs=0.05)  # stalled against the wall
    assert env.world.overlap_m() <= 0.01
    x_wall = obs[0]
    for _ in range(15):  # 1.5 s in reverse (0.5 s of it to swing the wheels from +1 to -1):
        obs, *_ = env.step(-full)  # the wall does not hold the robot back
    assert obs[0] - x_wall == pytest.approx(1.125, abs=0.03) and obs[4] == pytest.approx(-1.0)


def test_diffdrive_reaches_goal_and_terminates():
    env = DiffDriveEnv("paper-50")
    m = env.model
    g = m.goal
    nb = int(m.next_state[g - 1, 3]) == g and g - 1  # the cell left of G, if the move is free
    assert nb, "test assumes the cell left of the goal is free"
    env.reset(seed=0, options={"start": nb, "heading": 0.0})
    for _ in range(30):
        _obs, r, term, _trunc, _ = env.step(np.array([0.5, 0.5], dtype=np.float32))
        if term:
            break
    assert term and r == env.scenario.rewards.goal


def test_diffdrive_penalises_every_period_spent_pushing_into_a_wall():
    env = DiffDriveEnv("paper-50")
    env.reset(seed=0, options={"start": "S", "heading": np.pi})
    full = np.array([1.0, 1.0], dtype=np.float32)
    began, rewards = [], []
    for _ in range(80):
        _obs, r, _t, _tr, info = env.step(full)
        began.append(info["contacts"])
        rewards.append((r, info["in_contact"]))
    first = next(i for i, n in enumerate(began) if n)
    # after the contact began the robot keeps pushing: every later period costs a bump
    pushing = rewards[first + 1:]
    assert len(pushing) > 10 and all(c for _, c in pushing)
    assert all(r == env.scenario.rewards.bump for r, _ in pushing)
    assert sum(began[first + 1:]) < len(pushing)  # not because new contacts kept beginning


def test_importing_sim_registers_the_ids_in_a_fresh_process():
    import subprocess
    import sys

    code = ("import gymnasium as gym, sim; gym.register_envs(sim); "
            "ids = [i for i in gym.registry if i.startswith('rnhql/')]; print(sorted(ids)); "
            "e = gym.make('sim.envs:rnhql/GridRoute-v0', scenario='paper-40'); "
            "print(e.reset(seed=1)[0] == e.reset(seed=1)[0])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120).stdout.splitlines()
    assert out[0] == str(sorted(["rnhql/DiffDrive-v0", "rnhql/GridRoute-v0",
                                 "rnhql/PhysicsRoute-v0"]))
    assert out[1] == "True"
