"""Stable-Baselines3 on the native physics vector env: N robots in one Pymunk Space.

``sim.sb3_vec.SB3VecEnv`` turns a gymnasium vector env in the ``SameStep`` autoreset mode
into SB3's ``VecEnv``. This script times it against SB3's ``DummyVecEnv`` over N single
envs (the same robots, the same actions: the numbers it prints are the speed-up), then
trains DQN through it.

Run as pasted: ``python examples/sb3_vec_env.py`` (``pip install rnhql[sb3]``);
``RNHQL_EXAMPLE_SCALE=0.01`` shrinks it.
"""

import os
import time

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import DQN
from stable_baselines3.common.vec_env import DummyVecEnv

import sim  # noqa: F401  (registers the rnhql/ ids)
from sim.sb3_vec import SB3VecEnv

SCALE = float(os.environ.get("RNHQL_EXAMPLE_SCALE", "1"))
torch.set_num_threads(1)  # a 64-unit MLP: more threads only contend
N, SCENARIO = 16, "rooms-102"
KW = {"scenario": SCENARIO, "start": "random", "fidelity": "exact"}


def steps_per_s(venv, steps: int) -> float:
    venv.seed(0)
    venv.reset()
    rng = np.random.default_rng(0)
    for _ in range(5):  # load the compiled primitive kernel before timing
        venv.step(rng.integers(0, 4, N))
    t0 = time.perf_counter()
    for _ in range(steps):
        venv.step(rng.integers(0, 4, N))
    return steps * N / (time.perf_counter() - t0)


native = SB3VecEnv(gym.make_vec("rnhql/PhysicsRoute-v0", N,
                                vectorization_mode="vector_entry_point",
                                autoreset_mode="SameStep", **KW))
dummy = DummyVecEnv([lambda: gym.make("rnhql/PhysicsRoute-v0", **KW) for _ in range(N)])
steps = max(5, int(300 * SCALE))
fast, slow = steps_per_s(native, steps), steps_per_s(dummy, steps)
print(f"{N} robots: SB3VecEnv {fast:,.0f} primitives/s, DummyVecEnv {slow:,.0f} "
      f"primitives/s ({fast / slow:.1f}x)")

model = DQN("MlpPolicy", native, gamma=0.95, learning_starts=500, seed=0, device="cpu")
model.learn(max(100, int(50_000 * SCALE)))
print(f"DQN through SB3VecEnv: {model.num_timesteps} steps trained")
