"""Stable-Baselines3 PPO drives the DiffDrive robot's wheels from S to G.

The arena is 10 m x 10 m with a 1 m-radius pillar between S (cell 1,1) and G (cell 8,8);
the agent sets the two wheel speeds every 0.1 s and sees its pose, speed, and the vector
to the goal. What makes it work (measured, see docs/python-api.md):

- reward ``goal-only`` (+100 in G, -1 per 0.1 s in contact, 0 otherwise), the ids'
  default: ``paper``'s +1 per cell change teaches driving in circles;
- random starts while training (``start="random"``): episodes that begin near G pay
  early, and "drive towards the goal vector, round the pillar" carries over to S;
- 8 robots in one Pymunk Space through the native vector env and ``sim.sb3_vec``;
- episodes of 300 periods (30 s), gamma 0.99, ``TIMESTEPS`` below, seeds 0, 1, 2.

Run as pasted: ``python examples/sb3_ppo_diffdrive.py`` (``pip install rnhql[sb3]``);
``RNHQL_EXAMPLE_SCALE=0.01`` shrinks the budget (CI does, to check it runs).
"""

import os

import gymnasium as gym
import numpy as np
from stable_baselines3 import PPO

import sim  # noqa: F401  (registers the rnhql/ ids)
from sim.sb3_vec import SB3VecEnv
from sim.scenario import Circle, Scenario

TIMESTEPS = int(300_000 * float(os.environ.get("RNHQL_EXAMPLE_SCALE", "1")))
SEEDS = [int(s) for s in os.environ.get("RNHQL_EXAMPLE_SEEDS", "0").split(",")]
ARENA = Scenario("pillar-10", width_m=10.0, height_m=10.0, start=(1, 1), goal=(8, 8),
                 obstacles=(Circle(5.0, 5.0, 1.0),))
PERIODS = 300  # control periods of 0.1 s per episode


def train(seed: int) -> PPO:
    venv = SB3VecEnv(gym.make_vec("rnhql/DiffDrive-v0", 8,
                                  vectorization_mode="vector_entry_point", scenario=ARENA,
                                  steps_per_episode=PERIODS, autoreset_mode="SameStep",
                                  start="random"))
    model = PPO("MlpPolicy", venv, n_steps=256, batch_size=256, gamma=0.99, seed=seed,
                device="cpu", verbose=0)
    return model.learn(TIMESTEPS)


def drive_from_s(model: PPO, seed: int) -> tuple[bool, int, float]:
    """The greedy policy from S: (reached G, control periods, metres driven)."""
    env = gym.make("rnhql/DiffDrive-v0", scenario=ARENA, steps_per_episode=PERIODS)
    obs, info = env.reset(seed=seed)
    xy, metres = info["pose"][:2], 0.0
    for k in range(1, PERIODS + 1):
        action, _ = model.predict(obs, deterministic=True)
        obs, _, terminated, truncated, info = env.step(action)
        metres += float(np.hypot(*(info["pose"][:2] - xy)))
        xy = info["pose"][:2]
        if terminated or truncated:
            return terminated, k, metres
    return False, PERIODS, metres


if __name__ == "__main__":
    for seed in SEEDS:
        reached, periods, metres = drive_from_s(train(seed), seed)
        print(f"seed {seed}: {TIMESTEPS} steps of PPO -> from S "
              f"{'reached G' if reached else 'did not reach G'} in {periods} periods "
              f"({periods / 10:.1f} s, {metres:.1f} m)")
