"""Bad input to the physics envs: clear typed errors, not tracebacks from deep inside Pymunk."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import sim.envs  # noqa: F401  (registers the ids)
from sim.errors import ScenarioError
from sim.maps.layouts import chain
from sim.physics.envs.diffdrive import DiffDriveEnv
from sim.physics.envs.route import PhysicsRouteEnv
from sim.physics.static import PhysicsConfig
from sim.scenario import Circle, Robot, Scenario

OPEN = Scenario(name="open", width_m=10.0, height_m=10.0, start=(1, 1), goal=(8, 8))
ENVS = [PhysicsRouteEnv, DiffDriveEnv]


@pytest.mark.parametrize("env_cls", ENVS)
def test_open_scenario_object_is_accepted(env_cls):
    env = env_cls(OPEN)
    env.reset(seed=0)


@pytest.mark.parametrize("env_cls", ENVS)
@pytest.mark.parametrize("robot", [Robot(radius_m=0.5), Robot(radius_m=0.3, clearance_m=0.2),
                                   Robot(radius_m=2.0)])
def test_robot_too_large_for_a_cell(env_cls, robot):
    with pytest.raises(ScenarioError, match=r"robot\.radius_m.*does not fit"):
        env_cls(dataclasses.replace(OPEN, robot=robot))


@pytest.mark.parametrize("env_cls", ENVS)
def test_start_cut_off_for_the_inflated_robot(env_cls):
    # the start cell's centre is 0.3 m from the circle: free for a point, not for the robot
    sc = dataclasses.replace(OPEN, obstacles=(Circle(1.5, 2.3, 0.5),))
    with pytest.raises(ScenarioError, match=r"start.*blocked for the robot"):
        env_cls(sc)


@pytest.mark.parametrize("env_cls", ENVS)
def test_goal_enclosed_by_posts_is_unreachable(env_cls):
    # a ring of posts around G whose gaps a point could pass but the inflated robot cannot
    posts = (chain((6.5, 6.5), (10.0, 6.5), 0.3, 1.0)
             + chain((6.5, 6.5), (6.5, 10.0), 0.3, 1.0))
    sc = dataclasses.replace(OPEN, obstacles=posts)
    with pytest.raises(ScenarioError, match=r"goal.*cannot be reached"):
        env_cls(sc)


@pytest.mark.parametrize("env_cls", ENVS)
def test_goal_blocked(env_cls):
    sc = dataclasses.replace(OPEN, blocked_cells=((8, 8),))
    with pytest.raises(ScenarioError, match="goal"):
        env_cls(sc)


def test_unknown_scenario_name_and_bad_render_mode():
    with pytest.raises(ScenarioError, match="not a named scenario"):
        gym.make("rnhql/PhysicsRoute-v0", scenario="no-such-scenario")
    with pytest.raises(ValueError, match="render_mode"):
        PhysicsRouteEnv(OPEN, render_mode="human")
    with pytest.raises(ValueError, match="render_mode"):
        DiffDriveEnv(OPEN, render_mode="human")


@pytest.mark.parametrize("env_cls", ENVS)
def test_bad_physics_config(env_cls):
    with pytest.raises(ValueError, match=r"PhysicsConfig\.dt_s"):
        env_cls(OPEN, config=PhysicsConfig(dt_s=-0.1))


def test_step_before_reset_and_bad_heading():
    with pytest.raises(gym.error.ResetNeeded):
        PhysicsRouteEnv(OPEN).step(0)
    with pytest.raises(gym.error.ResetNeeded):
        DiffDriveEnv(OPEN).step(np.zeros(2, dtype=np.float32))
    with pytest.raises(ValueError, match="heading"):
        DiffDriveEnv(OPEN).reset(options={"heading": float("nan")})
    with pytest.raises(ValueError, match="options"):
        PhysicsRouteEnv(OPEN).reset(options={"start": 10_000})


@pytest.mark.parametrize("config", [{"friction": float("nan")}, {"substeps": 10**7},
                                    {"dt_s": 1e-9}, {"timeout_s": 1e9}])
def test_physics_settings_that_crash_or_hang_are_refused(config):
    """friction=nan aborted the interpreter inside Chipmunk; a 1e-9 s step or 10^7 substeps
    ran a primitive for minutes."""
    import gymnasium as gym

    import sim  # noqa: F401

    with pytest.raises(ValueError, match="PhysicsConfig"):
        gym.make("rnhql/PhysicsRoute-v0", scenario="paper-40", config=config)


def test_a_vector_env_has_a_bounded_number_of_robots():
    import gymnasium as gym

    import sim  # noqa: F401

    with pytest.raises(ValueError, match=r"num_envs: must be an int in 1\.\.4,096"):
        gym.make_vec("rnhql/PhysicsRoute-v0", num_envs=100_000,
                     vectorization_mode="vector_entry_point", scenario="paper-40")
