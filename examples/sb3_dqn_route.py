"""Stable-Baselines3 DQN finds the route on rooms-102, on the grid and in the physics world.

Settings that work (measured, see docs/python-api.md): reward ``goal-only`` (the ids'
default; with the paper's +1 per free step DQN at gamma 0.99 learns to wander for +600),
gamma 0.95, random starts while training (``start="random"``, the paper's protocol),
learning rate 1e-3, target network every 1000 steps, epsilon down to 0.05 over 50k steps.
Every ``CHECK_EVERY`` steps the greedy policy drives from S; training stops once it
reaches G (DQN's greedy route swings between found and lost from check to check; this
keeps the first that finds it), at most ``TIMESTEPS`` steps. The route is compared with
the BFS optimum (38 moves).

Run as pasted: ``python examples/sb3_dqn_route.py`` (``pip install rnhql[sb3]``);
``RNHQL_EXAMPLE_SCALE=0.01`` shrinks the budget (CI does, to check it runs).
"""

import os

import gymnasium as gym
import torch
from stable_baselines3 import DQN
from stable_baselines3.common.callbacks import BaseCallback

import sim  # noqa: F401  (registers the rnhql/ ids)

CHECK_EVERY = 10_000  # steps between greedy drives from S
TIMESTEPS = int(150_000 * float(os.environ.get("RNHQL_EXAMPLE_SCALE", "1")))
SCENARIO = "rooms-102"
torch.set_num_threads(1)  # a 64-unit MLP: more threads only contend


def greedy_route(model: DQN, env_id: str) -> int | None:
    """Moves of the greedy policy from S to G (None: G not reached)."""
    env = gym.make(env_id, scenario=SCENARIO)
    obs, _ = env.reset(seed=0)
    for moves in range(1, env.unwrapped.steps_per_episode + 1):
        action, _ = model.predict(obs, deterministic=True)
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated:
            return moves
        if truncated:
            return None
    return None


class StopWhenRouteFound(BaseCallback):
    """Every ``CHECK_EVERY`` steps: the greedy route from S; stop once it reaches G."""

    def __init__(self, env_id: str) -> None:
        super().__init__()
        self.env_id, self.next_check = env_id, CHECK_EVERY

    def _on_step(self) -> bool:
        if self.num_timesteps < self.next_check:
            return True
        self.next_check += CHECK_EVERY
        return greedy_route(self.model, self.env_id) is None


for env_id in ("rnhql/GridRoute-v0", "rnhql/PhysicsRoute-v0"):
    env = gym.make(env_id, scenario=SCENARIO, start="random")
    model = DQN("MlpPolicy", env, gamma=0.95, learning_rate=1e-3, learning_starts=1000,
                target_update_interval=1000, exploration_fraction=1 / 3, seed=0, device="cpu")
    model.learn(TIMESTEPS, callback=StopWhenRouteFound(env_id))
    moves = greedy_route(model, env_id)
    optimum = env.unwrapped.model.optimal_route_length
    print(f"{env_id}: DQN, {model.num_timesteps} steps -> greedy route from S "
          f"{'did not reach G' if moves is None else f'{moves} moves'} (optimum {optimum})")
