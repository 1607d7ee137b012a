"""A plain Gymnasium loop over the three rnhql ids, single and vectorised.

Run as pasted: ``python examples/gym_loop.py`` (only rnhql's own dependencies).
``RNHQL_EXAMPLE_SCALE=0.1`` shortens it.
"""

import os

import gymnasium as gym
import numpy as np

import sim  # noqa: F401  (registers rnhql/GridRoute-v0, rnhql/PhysicsRoute-v0, rnhql/DiffDrive-v0)

STEPS = max(20, int(2000 * float(os.environ.get("RNHQL_EXAMPLE_SCALE", "1"))))

# One env, random actions. The ids pay goal-only by default (+100 in G, -1 per bump, 0 per
# free move); rewards="paper" is the paper's scheme, fidelity= the physics world's realism.
env = gym.make("rnhql/PhysicsRoute-v0", scenario="rooms-102", fidelity="noisy")
obs, info = env.reset(seed=0)
episodes, bumps, ret = 0, 0, 0.0
for _ in range(STEPS):
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    bumps += info["bumped"]
    ret += reward
    if terminated or truncated:
        episodes += 1
        obs, info = env.reset()
print(f"PhysicsRoute: {STEPS} primitives, {episodes} episodes ended, {bumps} bumps, "
      f"return {ret:g}; the robot is at {np.round(info['pose'], 2)} (x m, y m, heading rad)")

# The grid's own planner for comparison: the tabular model behind the env.
grid = gym.make("rnhql/GridRoute-v0", scenario="rooms-102")
print(f"GridRoute: {grid.unwrapped.model.n_states} states, optimal route "
      f"{grid.unwrapped.model.optimal_route_length} moves")

# Eight robots in one Pymunk Space; a vector env autoresets (here: in the same step).
venv = gym.make_vec("rnhql/DiffDrive-v0", num_envs=8, vectorization_mode="vector_entry_point",
                    scenario="paper-40", steps_per_episode=100, autoreset_mode="SameStep")
obs, info = venv.reset(seed=0)
ended = 0
for _ in range(max(1, STEPS // 10)):
    actions = np.tile([0.8, 1.0], (8, 1))  # float64 wheel speeds [m/s]: a gentle left curve
    obs, rewards, terminated, truncated, info = venv.step(actions)
    ended += int((terminated | truncated).sum())
print(f"DiffDrive x8: {ended} episodes ended; contacts this step {info['contacts'].tolist()}")
venv.close()
