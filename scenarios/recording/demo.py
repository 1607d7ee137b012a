"""A synthetic training run, for recording tests, screenshots and demos (no learner needed).

``python -m scenarios.recording.demo out.rrd [--scenario paper-50] [--episodes 300]
[--world grid|physics]`` writes one.

Training episodes are random walks from S that drift towards the goal more and
more (so early episodes wander for the full 600 steps and late ones are near
the BFS route); "learned" values are the exact V*/Q* of the model plus noise
that shrinks with the episode. Everything is seeded.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from scenarios.recording.recorder import Recorder
from scenarios.script_args import arg, parse, positional
from sim.grid import TabularModel, build_model
from sim.grid.planning import bfs_route, value_iteration
from sim.scenario import Scenario
from sim.scenario_io import resolve_scenario


def walk(model: TabularModel, rng: np.random.Generator, greedy_p: float) -> np.ndarray:
    """States of one episode: greedy (shortest-route) move with prob. greedy_p, else random."""
    d = model.distance_to_goal
    s = model.start
    out = [s]
    for _ in range(model.max_steps):
        if model.terminal[s]:
            break
        if rng.random() < greedy_p:
            nxt = model.next_state[s]
            a = int(np.flatnonzero(d[nxt] == d[s] - 1)[0])
        else:
            a = int(rng.integers(4))
        s = int(model.next_state[s, a])
        out.append(s)
    return np.asarray(out, dtype=np.int64)


def record_synthetic(path: str | Path | None, sc: Scenario, model: TabularModel, *,
                     episodes: int = 200, record_every: int = 10, values_every: int = 50,
                     seed: int = 0, method: str = "rnh-ql", world: str = "grid",
                     recorder: Recorder | None = None, **create_kw) -> dict:
    """Record a synthetic run; returns what was logged (for round-trip checks)."""
    rng = np.random.default_rng(seed)
    rec = recorder or Recorder.create(path, sc, model, method=method, seed=seed, world=world,
                                      config={"alpha": 0.1, "gamma": 0.95, "episodes": episodes,
                                              "synthetic": True}, **create_kw)
    v_star, q_star = value_iteration(model.next_state, model.reward, model.terminal, 0.95)
    logged: dict[int, np.ndarray] = {}
    steps, success, returns = [], [], []
    with rec:
        for ep in range(episodes):
            states = walk(model, rng, greedy_p=min(0.95, 0.3 + 0.9 * ep / episodes))
            n = len(states) - 1
            steps.append(n)
            success.append(bool(model.terminal[states[-1]]))
            returns.append(float(n - 1 + (100.0 if success[-1] else 0.0)))
            if ep % record_every == 0:
                poses = sim_t = contacts = contact_steps = None
                if world == "physics":  # jittered poses, heading along the motion
                    xy = model.coords[states] + rng.normal(0, 0.05, (len(states), 2))
                    d = np.diff(xy, axis=0, append=xy[-1:] + (xy[-1:] - xy[-2:-1]))
                    poses = np.column_stack([xy, np.arctan2(d[:, 1], d[:, 0])])
                    sim_t = 0.5 * np.arange(len(states))
                    contact_steps = np.flatnonzero(states[1:] == states[:-1]) + 1
                    contacts = xy[contact_steps]
                rec.log_episode_trajectory(ep, states, poses=poses, sim_time_s=sim_t,
                                           contacts=contacts, contact_steps=contact_steps)
                logged[ep] = states
            if (ep + 1) % values_every == 0:
                noise = 30.0 * (1 - ep / episodes)
                q = q_star + rng.normal(0, noise + 1e-3, q_star.shape)
                rec.log_values(ep, q, v_nn=v_star + rng.normal(0, noise + 1e-3, v_star.shape))
                lo = ep + 1 - values_every
                rec.log_episode_metrics(
                    np.arange(lo, ep + 1), steps[lo:], success[lo:], returns[lo:],
                    wall_time_s=np.full(values_every, 2e-4),
                    shaping_mean=rng.normal(0.2, 0.05, values_every),
                    shaping_std=np.abs(rng.normal(0.5, 0.1, values_every)))
        greedy = walk(model, rng, greedy_p=1.0)
        rec.log_episode_trajectory(episodes, greedy, kind="greedy-test")
        rec.log_route("final route", greedy)
        logged[episodes] = greedy
    route = bfs_route(model.next_state, model.distance_to_goal, model.start)
    return {"trajectories": logged, "route": route, "recorder": rec}


@dataclass(frozen=True)
class Args:
    out: str = positional("the recording to write (.rrd)")
    scenario: str = arg("paper-50", "scenario name or file")
    episodes: int = arg(300, "synthetic episodes")
    world: str = arg("grid", "whose trajectories to draw", choices=("grid", "physics"))


def main(argv: list[str] | None = None) -> None:
    a = parse(Args, __doc__, argv)
    sc = resolve_scenario(a.scenario)
    record_synthetic(a.out, sc, build_model(sc), episodes=a.episodes, world=a.world)
    print(a.out)


if __name__ == "__main__":
    main()
