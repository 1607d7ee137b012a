"""A policy trained elsewhere, graded as rnhql grades its own: Stable-Baselines3 DQN learns the
grid route, then ``scenarios.api.grade`` drives its greedy policy from S in the physics world
at ``exact``, ``noisy`` and ``uncalibrated`` (50 drives each, own noise streams), beside V*
(the optimum at each rung).

Run as pasted: ``python examples/sb3_graded.py`` (``pip install rnhql[sb3]``; about two
minutes); ``RNHQL_EXAMPLE_SCALE=0.01`` shrinks the budget (CI does).
"""

import os

import gymnasium as gym
import torch
from stable_baselines3 import DQN

import sim  # noqa: F401  (registers the rnhql/ ids)
from scenarios import api
from sim.scenario import Circle, Scenario

SCALE = float(os.environ.get("RNHQL_EXAMPLE_SCALE", "1"))
TIMESTEPS = max(200, round(60_000 * SCALE))
torch.set_num_threads(1)  # a 64-unit MLP: more threads only contend

# a 12 m x 12 m arena with three pillars, built in Python
WORLD = Scenario(name="three-pillars", width_m=12.0, height_m=12.0, start=(1, 1),
                 goal=(10, 10), obstacles=(Circle(4.0, 4.0, 1.2), Circle(8.0, 7.0, 1.5),
                                           Circle(3.0, 9.0, 1.0)), steps_per_episode=200)

env = gym.make("rnhql/GridRoute-v0", scenario=WORLD, start="random")
model = DQN("MlpPolicy", env, gamma=0.95, learning_rate=1e-3, learning_starts=500,
            target_update_interval=500, exploration_fraction=0.3, seed=0, device="cpu")
model.learn(TIMESTEPS)


def policy(state: int) -> int:
    """DQN's greedy action in a cell (grade calls it once per cell)."""
    return int(model.predict(state, deterministic=True)[0])


print(f"DQN, {TIMESTEPS} steps on the grid of {WORLD.name}")
for fidelity in ("exact", "noisy", "uncalibrated"):
    g = api.grade(policy, WORLD, fidelity=fidelity, drives=50, seed=0)
    opt = g.optimum
    v = ("—" if opt is None or opt.expected_primitives is None
         else f"{opt.expected_primitives:.1f}")
    print(f"  {g}; V*(S) {v} primitives")
