"""Benchmark of the physics world (measured, never asserted).

* primitives per second on one core, through ``gymnasium.make`` (wrappers
  included), through the bare env (a batch of one robot: :mod:`sim.physics.kernel.batch`),
  and through the reference world (every step through ``cpSpaceStep``, the
  Python controller);
* physics steps (``cpSpaceStep``) per primitive, and the reference world's share
  of time in Chipmunk (steps x the cost of one step, measured on its own);
* primitives per second for other time steps (the dt / speed trade-off);
* ``episodes`` of tabular Q-learning (epsilon-greedy, Q0 = 0, the paper's
  alpha/gamma/epsilon) in ``rnhql/PhysicsRoute-v0``: wall time and primitives
  per episode, the number that decides what a full learning run costs.

Run: ``python -m scenarios.bench.physics [--quick] [--scenario NAME]``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

import sim.envs  # noqa: F401  (registers the ids)
from scenarios.script_args import arg, parse
from sim.physics.envs.route import PhysicsRouteEnv
from sim.physics.reference.controller import PrimitiveController
from sim.physics.reference.world import PhysicsConfig, PhysicsWorld
from sim.scenario import Scenario
from sim.scenario_io import resolve_scenario


def step_cost_us(sc: Scenario, cfg: PhysicsConfig, n: int = 200_000) -> float:
    """Cost of one physics step [us] with the robot driving a free circle."""
    x, y = (sc.start[0] + 0.5) * sc.cell_size_m, (sc.start[1] + 0.5) * sc.cell_size_m
    world = PhysicsWorld(sc, cfg, (x, y, 0.0))
    world.set_twist(0.0, 0.0, 1.0)  # turning in place: contact tests run, nothing is hit
    step, space, h = world._fn[0], world._S, cfg.dt_s
    t = time.perf_counter()
    for _ in range(n):
        step(space, h)
    return (time.perf_counter() - t) / n * 1e6


def bench_primitives(sc: Scenario, cfg: PhysicsConfig, n: int, seed: int) -> dict[str, Any]:
    """Random primitives (restarting from random cells every 200) three ways."""
    rng = np.random.default_rng(seed)
    actions = rng.integers(4, size=n).tolist()

    warm = PhysicsRouteEnv(sc, config=cfg)  # load the compiled kernel before timing
    warm.reset(seed=seed)
    warm.step(0)
    env = gym.make("rnhql/PhysicsRoute-v0", scenario=sc, config=cfg)
    env.reset(seed=seed, options={"start": "random"})
    t = time.perf_counter()
    for i, a in enumerate(actions):
        _, _, term, trunc, _ = env.step(a)
        if term or trunc or i % 200 == 199:
            env.reset(options={"start": "random"})
    t_make = time.perf_counter() - t

    bare = PhysicsRouteEnv(sc, config=cfg)
    s, _ = bare.reset(seed=seed, options={"start": "random"})
    steps = bumps = 0
    transitions = []
    deepest = 0.0
    t = time.perf_counter()
    for i, a in enumerate(actions):
        s2, _, term, _, info = bare.step(a)
        transitions.append((s, a, s2))
        s = s2
        steps += info["steps"]
        if info["bumped"]:
            bumps += 1
            deepest = max(deepest, bare.contact_records()[-info["contacts"]].depth_m)
        if term or i % 200 == 199:
            s, _ = bare.reset(options={"start": "random"})
    t_env = time.perf_counter() - t
    tr = np.array(transitions)
    expected = bare.model.next_state[tr[:, 0], tr[:, 1]]
    free = expected != tr[:, 0]

    ctl = PrimitiveController(sc, cfg)
    model = bare.model
    starts = model.start_states[rng.integers(len(model.start_states), size=n // 200 + 1)]
    cache: dict = {}
    world = None
    t = time.perf_counter()
    for i, a in enumerate(actions):
        if i % 200 == 0:
            x, y = model.coords[starts[i // 200]]
            world = PhysicsWorld(sc, cfg, (x, y, 0.0), cast_cache=cache)
        ctl.run(world, a)
    t_ctl = time.perf_counter() - t

    per_step = step_cost_us(sc, cfg)
    return {
        "primitives": n,
        "per_s_gym_make": n / t_make,
        "per_s_env": n / t_env,
        "per_s_reference_world": n / t_ctl,
        "physics_steps_per_primitive": steps / n,
        "sim_s_per_primitive": steps * cfg.dt_s / n,
        "bump_fraction": bumps / n,
        "deepest_contact_m": deepest,
        "agreement_with_grid_all": float((tr[:, 2] == expected).mean()),
        "agreement_with_grid_free_moves": float((tr[:, 2] == expected)[free].mean()),
        "free_move_fraction": float(free.mean()),
        "step_cost_us": per_step,
        # the reference world steps Chipmunk every step: its physics share of the time
        "reference_world_physics_fraction": steps * per_step * 1e-6 / t_ctl,
    }


def bench_dt(sc: Scenario, dts: tuple[float, ...], n: int, seed: int) -> dict[str, Any]:
    """Controller-level primitives/s and steps per primitive for other time steps."""
    out = {}
    actions = np.random.default_rng(seed).integers(4, size=n).tolist()
    x, y = (sc.start[0] + 0.5) * sc.cell_size_m, (sc.start[1] + 0.5) * sc.cell_size_m
    for dt in dts:
        cfg = PhysicsConfig(dt_s=dt)
        ctl, world = PrimitiveController(sc, cfg), PhysicsWorld(sc, cfg, (x, y, 0.0))
        t = time.perf_counter()
        for a in actions:
            ctl.run(world, a)
        el = time.perf_counter() - t
        out[str(dt)] = {"per_s_controller": n / el, "physics_steps_per_primitive": world.steps / n}
    return out


def bench_q_learning(sc: Scenario, cfg: PhysicsConfig, episodes: int, seed: int,
                     epsilon: float = 0.1, alpha: float = 0.1,
                     gamma: float = 0.95) -> dict[str, Any]:
    """Tabular Q-learning from S for ``episodes`` episodes, all in the physics env."""
    env = gym.make("rnhql/PhysicsRoute-v0", scenario=sc, config=cfg)
    n_states = env.observation_space.n
    q = [[0.0] * 4 for _ in range(n_states)]
    rng = np.random.default_rng(seed)
    lengths, successes, bumps = [], 0, 0
    t = time.perf_counter()
    for ep in range(episodes):
        s, _ = env.reset(seed=seed if ep == 0 else None)
        u = rng.random(601).tolist()  # exploration draws for this episode
        k = rng.integers(4, size=601).tolist()  # random actions and tie-breaks
        n = 0
        while True:
            qs = q[s]
            if u[n] < epsilon:
                a = k[n]
            else:
                best = max(qs)
                ties = [i for i in range(4) if qs[i] == best]
                a = ties[k[n] % len(ties)]
            s2, r, term, trunc, info = env.step(a)
            bumps += info["bumped"]
            qs[a] += alpha * ((r if term else r + gamma * max(q[s2])) - qs[a])
            s = s2
            n += 1
            if term or trunc:
                break
        lengths.append(n)
        successes += term
    el = time.perf_counter() - t
    total = int(sum(lengths))
    return {"episodes": episodes, "seconds": el, "primitives": total,
            "primitives_per_episode": total / episodes, "primitives_per_s": total / el,
            "success_fraction": successes / episodes, "bump_fraction": bumps / total,
            "mean_length_last_100": float(np.mean(lengths[-100:])),
            "seconds_per_3000_episodes": el / episodes * 3000}


def run_bench(scenario: str = "paper-50", quick: bool = False, seed: int = 0,
              config: PhysicsConfig | None = None) -> dict[str, Any]:
    """All measurements as one JSON-able dict."""
    sc = resolve_scenario(scenario)
    cfg = config or PhysicsConfig()
    n = 20_000 if quick else 200_000
    return {
        "scenario": scenario,
        "config": dataclasses.asdict(cfg),
        "primitives": bench_primitives(sc, cfg, n, seed),
        "dt_sweep": bench_dt(sc, (0.05, 0.1, 0.125, 0.2), n // 4, seed),
        "q_learning": bench_q_learning(sc, cfg, 100 if quick else 3000, seed),
    }


def _round(x: Any) -> Any:
    if isinstance(x, float):
        return float(f"{x:.4g}") if math.isfinite(x) else x
    if isinstance(x, dict):
        return {k: _round(v) for k, v in x.items()}
    return x


@dataclass(frozen=True)
class Args:
    scenario: str = arg("paper-50", "built-in name or .toml path")
    quick: bool = arg(False, "10x fewer primitives, 100 episodes")
    seed: int = arg(0, "seed of the random primitives and the learners")


if __name__ == "__main__":
    args = parse(Args, __doc__)
    print(json.dumps(_round(run_bench(args.scenario, args.quick, args.seed)), indent=2))
