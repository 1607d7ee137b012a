"""Benchmarks of the learners: kernel throughput, the paper protocol, JIT cold start.

Run: ``python -m scenarios.bench.learners`` (prints JSON). Measures, on paper-50:

* env steps/s of the fused kernels for st-ql and rnh-ql (100 centres), training
  3000 episodes from scratch (the paper protocol's mix of long exploring and
  short goal-reaching episodes), best of ``repeats``, JIT warm;
* the same Q-learning as a plain Python loop over ``gymnasium.make`` (the
  foundation's reference loop) and the speed-up of the kernel over it;
* a bare numba Q-learning loop with the same semantics (random start,
  epsilon-greedy with random ties from a Generator) written as one function:
  the practical limit, and the fraction of it the st-ql kernel reaches;
* env steps/s of the step-by-step rnh-ql agent driving GridRoute-v0 through
  gymnasium (the driver the physics world uses);
* seconds per seed of the paper protocol (rnh-ql, 3000 episodes, greedy test
  every 10 episodes) through :func:`learning.drivers.train.train_tabular`;
* env steps/s of rnh-ql+ and dyna-q at several planning budgets;
* JIT cold start: a fresh process with an empty ``NUMBA_CACHE_DIR`` trains one
  episode of rnh-ql (compile), then a second fresh process does the same with
  the cache the first one filled.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

import gymnasium as gym
import numpy as np
from numba import njit

import sim.envs  # noqa: F401  (registers the ids)
from learning import (
    METHODS,
    RNHQL,
    geometry_of,
    init_state,
    make_agent,
    run_env_episodes,
    train_tabular,
)
from learning.compiled.kernels import run_episodes
from scenarios.bench.grid import python_q_learning_steps_per_s
from scenarios.runs.spec import load
from sim.grid import build_model
from sim.scenario_io import resolve_scenario

EPISODES = 3000


def kernel_steps_per_s(method: str, model, episodes: int = EPISODES, repeats: int = 3,
                       seed: int = 0, **fields) -> float:
    """Best-of-``repeats`` env steps/s of a fresh agent trained ``episodes`` episodes
    (``fields`` override the method's config)."""
    geom = geometry_of(model)
    best = 0.0
    for r in range(repeats + 1):  # the first pass only warms the JIT
        rng = np.random.default_rng(seed)
        st = init_state(METHODS[method](**fields), geom, rng)
        n = episodes if r else 1
        out = (np.zeros(n, np.int32), np.zeros(n), np.zeros(n, bool), np.zeros(n), np.zeros(n))
        t0 = time.perf_counter()
        steps = run_episodes(st, model, n, rng, out)
        dt = time.perf_counter() - t0
        if r:
            best = max(best, steps / dt)
    return best


@njit(cache=True)
def _bare_q_learning(q, next_state, reward, terminal, starts, max_steps, episodes, rng):
    eps, alpha, gamma = 0.1, 0.1, 0.95
    n_a = q.shape[1]
    total = 0
    for _ in range(episodes):
        s = starts[rng.integers(0, starts.shape[0])]
        for _t in range(max_steps):
            if rng.random() < eps:
                a = rng.integers(0, n_a)
            else:
                best = q[s, 0]
                a = 0
                ties = 1
                for b in range(1, n_a):
                    if q[s, b] > best:
                        best, a, ties = q[s, b], b, 1
                    elif q[s, b] == best:
                        ties += 1
                if ties > 1:
                    k = rng.integers(0, ties)
                    for b in range(n_a):
                        if q[s, b] == best:
                            if k == 0:
                                a = b
                                break
                            k -= 1
            s2 = next_state[s, a]
            target = reward[s, a]
            if not terminal[s2]:
                m = q[s2, 0]
                for b in range(1, n_a):
                    m = max(m, q[s2, b])
                target += gamma * m
            q[s, a] += alpha * (target - q[s, a])
            total += 1
            s = s2
            if terminal[s2]:
                break
    return total


def bare_steps_per_s(model, episodes: int = EPISODES, repeats: int = 3) -> float:
    best = 0.0
    args = (model.next_state, model.reward, model.terminal, model.start_states, model.max_steps)
    for r in range(repeats + 1):
        q = np.zeros(model.next_state.shape)
        rng = np.random.default_rng(0)
        t0 = time.perf_counter()
        steps = _bare_q_learning(q, *args, episodes if r else 1, rng)
        if r:
            best = max(best, steps / (time.perf_counter() - t0))
    return best


def step_agent_steps_per_s(scenario: str, method: str = "rnh-ql", episodes: int = 20) -> float:
    """Env steps/s of the step-by-step agent driving GridRoute-v0 through gymnasium."""
    env = gym.make("rnhql/GridRoute-v0", scenario=scenario)
    agent = make_agent(METHODS[method](), geometry_of(env.unwrapped.model),
                       np.random.default_rng(0))
    run_env_episodes(agent, env, 1)  # JIT warm-up
    t0 = time.perf_counter()
    log = run_env_episodes(agent, env, episodes)
    return float(log.steps.sum() / (time.perf_counter() - t0))


def paper_protocol_s_per_seed(model, seeds: int = 3) -> float:
    """Median wall seconds of train_tabular(rnh-ql, 3000 episodes, test every 10), JIT warm."""
    train_tabular(RNHQL(), model, 10, np.random.default_rng(99))
    times = []
    for seed in range(seeds):
        t0 = time.perf_counter()
        train_tabular(RNHQL(), model, EPISODES, np.random.default_rng(seed), test_every=10)
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


_COLD = """
import time
t0 = time.perf_counter()
import numpy as np
from learning import RNHQL, train_tabular
from sim.grid import build_model
from sim.scenario_io import resolve_scenario
m = build_model(resolve_scenario("paper-50"))
t1 = time.perf_counter()
train_tabular(RNHQL(), m, 1, np.random.default_rng(0))
print(time.perf_counter() - t1, t1 - t0)
"""


def cold_start_s() -> dict[str, float]:
    """Seconds to the first rnh-ql episode in a fresh process: empty JIT cache, then filled."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        res = []
        for _ in range(2):
            out = subprocess.run([sys.executable, "-c", _COLD], env=env, check=True,
                                 capture_output=True, text=True).stdout.split()
            res.append((float(out[0]), float(out[1])))
    return {"jit_cold_s": res[0][0], "jit_cached_s": res[1][0], "import_s": res[1][1]}


def train_steps_per_s(method: str, model, episodes: int = EPISODES, seeds: int = 3,
                      **fields) -> float:
    """Median over seeds 0..seeds-1 of env steps / kernel seconds of
    :func:`learning.drivers.train.train_tabular` (greedy tests included, JIT warm)."""
    cfg = METHODS[method](**fields)
    train_tabular(cfg, model, 2, np.random.default_rng(0))  # warm the JIT
    rates = []
    for seed in range(seeds):
        run = train_tabular(cfg, model, episodes, np.random.default_rng(seed))
        rates.append(run.env_steps / float(np.sum(run.wall_time_s)))
    return float(np.median(rates))


def planning_steps_per_s(scenario: str = "paper-50", rewards: str = "goal-only") -> dict:
    """Env steps/s of rnh-ql+ (target: >= 2M on paper-50) at 10 (its default),
    3 and 0 shaped planning updates per step, and of dyna-q at 5 (its default) and 10,
    under the rewards the route-learning targets use: the kernel alone (seed 0, best of
    3) and through train_tabular (median of seeds 0-2), which differ with the seeds'
    mix of long exploring episodes."""
    _, model = load(scenario, None, None, rewards)
    rows = [("rnh_ql_plus", "rnh-ql+", n) for n in (10, 3, 0)]
    rows += [("dyna_q", "dyna-q", n) for n in (5, 10)]
    out: dict = {"rewards": rewards}
    for key, method, n in rows:
        out[f"{key}_planning{n}_kernel_steps_per_s"] = kernel_steps_per_s(method, model,
                                                                          n_planning=n)
        out[f"{key}_planning{n}_train_steps_per_s"] = train_steps_per_s(method, model,
                                                                        n_planning=n)
    return out


def run_bench(scenario: str = "paper-50", python_steps: int = 300_000) -> dict:
    model = build_model(resolve_scenario(scenario))
    st_ql = kernel_steps_per_s("st-ql", model)
    py = python_q_learning_steps_per_s(gym.make("rnhql/GridRoute-v0", scenario=scenario),
                                       python_steps, reset_options={"start": "random"})
    bare = bare_steps_per_s(model)
    return {
        "scenario": scenario,
        "st_ql_kernel_steps_per_s": st_ql,
        "rnh_ql_kernel_steps_per_s": kernel_steps_per_s("rnh-ql", model),
        "python_gym_q_steps_per_s": py,
        "kernel_speedup_over_python": st_ql / py,
        "bare_numba_q_steps_per_s": bare,
        "st_ql_fraction_of_bare": st_ql / bare,
        "step_agent_gym_steps_per_s": step_agent_steps_per_s(scenario),
        "paper_protocol_s_per_seed": paper_protocol_s_per_seed(model),
        **cold_start_s(),
        "planning": planning_steps_per_s(scenario),
    }


if __name__ == "__main__":
    print(json.dumps(run_bench(), indent=2))
