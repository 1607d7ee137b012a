"""Benchmarks of the foundation: building a scenario, and GridRoute-v0 through gymnasium.

Run: ``python -m scenarios.bench.grid`` (or ``rnhql bench``). The gymnasium
figure uses a plain Python tabular Q-learning loop over ``gymnasium.make`` (all
wrappers on), the way a user would write it; CliffWalking-v1 runs the same
loop as a reference point for this machine.
"""

from __future__ import annotations

import json
import time

import gymnasium as gym
import numpy as np

import sim.envs  # noqa: F401  (registers the ids)
from sim.grid import build_model
from sim.grid.raster import rasterise
from sim.scenario_io import resolve_scenario


def time_build(name: str = "paper-50", repeats: int = 30) -> float:
    """Median seconds to load, lay out, rasterise, BFS and export a scenario (cold cache)."""
    times = []
    for _ in range(repeats):
        rasterise.cache_clear()
        t0 = time.perf_counter()
        build_model(resolve_scenario(name))
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def python_q_learning_steps_per_s(env: gym.Env, steps: int = 300_000, seed: int = 0,
                                  reset_options: dict | None = None) -> float:
    """Env steps per second of epsilon-greedy Q-learning written as a plain Python loop."""
    rng = np.random.default_rng(seed)
    q = [[0.0] * env.action_space.n for _ in range(env.observation_space.n)]
    s, _ = env.reset(seed=seed, options=reset_options)
    t0 = time.perf_counter()
    for _ in range(steps):
        if rng.random() < 0.1:
            a = int(rng.integers(4))
        else:
            qs = q[s]
            a = qs.index(max(qs))
        s2, r, term, trunc, _ = env.step(a)
        target = r if term else r + 0.95 * max(q[s2])
        q[s][a] += 0.1 * (target - q[s][a])
        s = s2
        if term or trunc:
            s, _ = env.reset(options=reset_options)
    return steps / (time.perf_counter() - t0)


def run_bench(steps: int = 300_000) -> dict:
    return {
        "build_paper50_ms": 1000 * time_build("paper-50"),
        "gridroute_python_q_steps_per_s": python_q_learning_steps_per_s(
            gym.make("rnhql/GridRoute-v0"), steps, reset_options={"start": "random"}),
        "cliffwalking_python_q_steps_per_s": python_q_learning_steps_per_s(
            gym.make("CliffWalking-v1"), steps),
    }


if __name__ == "__main__":
    print(json.dumps(run_bench(), indent=2))
