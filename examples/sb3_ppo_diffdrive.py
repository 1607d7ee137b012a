"""Stable-Baselines3 PPO drives the DiffDrive robot's wheels from S to G.

The arena is 10 m x 10 m with a 1 m-radius pillar between S (cell 1,1) and G (cell 8,8);
the agent sets the two wheel speeds every 0.1 s and sees its pose, speed and the vector
to the goal. What makes it work:

- reward ``goal-only`` (+100 in G, -1 per 0.1 s in contact, 0 otherwise), the ids'
  default (the paper's +1 per cell change teaches driving in circles), plus
  potential-based shaping ``gamma * phi(s') - phi(s)`` with ``phi`` minus the grid's BFS
  distance to G in cells (:class:`RouteShaping`; Ng et al. 1999: the optimal policy is
  unchanged, the way round the pillar is signposted);
- random starts while training (``start="random"``), greedy test from S;
- smooth exploration (``use_sde=True``: gSDE, a noise that changes every 4 periods, not
  every 0.1 s, so a random policy drives somewhere instead of shaking in place) and
  rewards scaled by ``VecNormalize``;
- 8 envs, episodes of 300 periods (30 s), gamma 0.99; every ``CHECK_EVERY`` steps the
  greedy policy drives from S (exact physics, no shaping) and training stops once it
  reaches G (:class:`StopWhenGreedyReachesG`), at most ``TIMESTEPS`` steps. PPO's greedy
  policy still swings between reaching G and not from one check to the next; this keeps
  the first one that does.

Run as pasted: ``python examples/sb3_ppo_diffdrive.py`` (``pip install rnhql[sb3]``);
``RNHQL_EXAMPLE_SCALE=0.01`` shrinks the budget (CI does, to check it runs) and
``RNHQL_EXAMPLE_SEEDS=0,1,2`` trains several seeds.
"""

import os

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

import sim  # noqa: F401  (registers the rnhql/ ids)
from sim.scenario import Circle, Scenario

CHECK_EVERY = 20_000  # steps between greedy drives from S
TIMESTEPS = int(400_000 * float(os.environ.get("RNHQL_EXAMPLE_SCALE", "1")))
SEEDS = [int(s) for s in os.environ.get("RNHQL_EXAMPLE_SEEDS", "0").split(",")]
ARENA = Scenario("pillar-10", width_m=10.0, height_m=10.0, start=(1, 1), goal=(8, 8),
                 obstacles=(Circle(5.0, 5.0, 1.0),))
PERIODS = 300  # control periods of 0.1 s per episode
GAMMA = 0.99
torch.set_num_threads(1)  # a 64-unit MLP: more threads only contend


class RouteShaping(gym.Wrapper):
    """Adds ``gamma * phi(s') - phi(s)``, ``phi(s)`` = minus the BFS distance from the
    robot's cell to G (cells, round obstacles; 0 in G). Potential-based, so the policy it
    leads to is optimal for the env's own reward too."""

    def __init__(self, env: gym.Env, gamma: float = GAMMA) -> None:
        super().__init__(env)
        self.gamma = gamma
        self.dist = env.unwrapped.model.distance_to_goal.astype(float)
        self.phi = 0.0

    def _phi(self, info: dict) -> float:
        return -float(max(self.dist[int(info["state"])], 0.0))

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self.phi = self._phi(info)
        return obs, info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        phi = 0.0 if terminated else self._phi(info)
        shaped = reward + self.gamma * phi - self.phi
        self.phi = phi
        return obs, shaped, terminated, truncated, info


def make_env() -> gym.Env:
    return RouteShaping(gym.make("rnhql/DiffDrive-v0", scenario=ARENA, start="random",
                                 steps_per_episode=PERIODS))


class StopWhenGreedyReachesG(BaseCallback):
    """Every ``CHECK_EVERY`` steps: drive the greedy policy from S; stop once it reaches G."""

    def __init__(self, seed: int) -> None:
        super().__init__()
        self.seed, self.next_check = seed, CHECK_EVERY

    def _on_step(self) -> bool:
        if self.num_timesteps < self.next_check:
            return True
        self.next_check += CHECK_EVERY
        return not drive_from_s(self.model, self.seed)[0]


def train(seed: int) -> PPO:
    venv = VecNormalize(DummyVecEnv([make_env for _ in range(8)]), norm_obs=False,
                        norm_reward=True, gamma=GAMMA)
    model = PPO("MlpPolicy", venv, n_steps=256, batch_size=256, gamma=GAMMA,
                use_sde=True, sde_sample_freq=4, seed=seed, device="cpu", verbose=0)
    return model.learn(TIMESTEPS, callback=StopWhenGreedyReachesG(seed))


def drive_from_s(model: PPO, seed: int) -> tuple[bool, int, float]:
    """The greedy policy from S, unshaped env: (reached G, control periods, metres)."""
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
        model = train(seed)
        reached, periods, metres = drive_from_s(model, seed)
        print(f"seed {seed}: {model.num_timesteps} steps of PPO -> from S "
              f"{'reached G' if reached else 'did not reach G'} in {periods} periods "
              f"({periods / 10:.1f} s, {metres:.1f} m)")
