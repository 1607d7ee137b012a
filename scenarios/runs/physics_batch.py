"""Physics training in batches: the runs of a sweep as the robots of one Pymunk Space.

:func:`train_physics_batch` trains several groups of runs at once (a group: one method and
config, several seeds), every run one robot of a :class:`sim.physics.batch.RouteBatch`
and one agent of its group's :class:`learning.batch_agent.BatchAgent`. Per batched step
there is one compiled call per group for ``act``, one for the world (plus Chipmunk where a
leg needs a cast or a step may touch) and one per group for ``update``.

Each run is exactly the run :func:`scenarios.runs.physics.train_physics` makes alone with
its seed (tested, record for record): its robot is the single-robot world, its agent
draws from its own learner stream in the same order, its start cells come from its own
start stream, the greedy tests run after the same episodes on the same physics model.
Only the wall time differs: a batched step's time is shared among the runs it advanced.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from learning.batch_agent import BatchAgent
from learning.generator_handle import handles
from learning.geometry import geometry_of
from learning.train import greedy_test, shortest_fraction
from scenarios.runs.physics import (
    PhysicsTrainResult,
    continuous_optimum_rounded,
    drive_greedy,
    sigint_to,
)
from sim.grid import TabularModel
from sim.physics.batch import RouteBatch
from sim.scenario import Scenario


@dataclass(frozen=True)
class RunGroup:
    """Runs of one method and config: one learner and one start stream per run."""

    cfg: Any
    learner_rngs: Sequence[np.random.Generator]
    start_rngs: Sequence[np.random.Generator]
    noise_rngs: Sequence[np.random.Generator] | None = None  # the physics streams (noise)


class _Stop:
    """Ctrl-C sets a flag; the loop raises KeyboardInterrupt between batched steps (a signal
    inside a compiled call or a Chipmunk query is never acted on there). Installed by the
    single driver's :func:`scenarios.runs.physics.sigint_to`."""

    def __init__(self) -> None:
        self.requested = False

    def request(self, _sig: int, _frame: Any) -> None:
        if self.requested:
            raise KeyboardInterrupt  # a second Ctrl-C: now
        self.requested = True


class _Logs:
    """Per-run, per-episode arrays, filled as episodes end."""

    def __init__(self, n: int, episodes: int) -> None:
        self.steps = np.zeros((n, episodes), np.int32)
        self.returns = np.zeros((n, episodes))
        self.success = np.zeros((n, episodes), bool)
        self.shaping_mean = np.zeros((n, episodes))
        self.shaping_std = np.zeros((n, episodes))
        self.wall = np.zeros((n, episodes))
        self.contacts = np.zeros((n, episodes), np.int64)
        self.sim_time = np.zeros((n, episodes))
        self.tests_e: list[list[int]] = [[] for _ in range(n)]
        self.tests_l: list[list[int]] = [[] for _ in range(n)]


def train_physics_batch(sc: Scenario, model: TabularModel, groups: Sequence[RunGroup],
                        n_episodes: int, test_every: int = 10,
                        split: dict[str, float] | None = None,
                        fidelity: Any = None) -> list[list[PhysicsTrainResult]]:
    """Train every run of every group in one batch; results per group, per run.

    ``split``, if given, receives the wall time [s] of the parts of the loop: ``learner``
    (act and update), ``kernel`` (the world's compiled call), ``chipmunk`` (casts and
    contact checks), ``episodes`` (ends, greedy tests, starts), ``driver`` (the rest of
    the loop) and ``final`` (final greedy routes, driven routes), plus ``primitives``.
    """
    from sim.physics.model import physics_model

    graded = physics_model(sc)
    geom = geometry_of(model)
    starts = np.asarray(geom.start_states)
    agents, bounds = [], []
    lo = 0
    for g in groups:
        agents.append(BatchAgent(g.cfg, geom, list(g.learner_rngs)))
        bounds.append((lo, lo + len(g.learner_rngs)))
        lo += len(g.learner_rngs)
    n = lo
    start_h = handles([r for g in groups for r in g.start_rngs])
    world = RouteBatch(sc, n, fidelity=fidelity)
    noise = [r for g in groups for r in (g.noise_rngs or [None] * len(g.learner_rngs))]
    for i, r in enumerate(noise):
        if r is not None:
            world.set_noise_rng(i, r)
    rw = sc.rewards
    goal, max_steps = model.goal, sc.steps_per_episode
    logs = _Logs(n, n_episodes)
    s = np.zeros(n, np.int64)
    a = np.zeros(n, np.int64)
    t = np.zeros(n, np.int64)
    ret = np.zeros(n)
    wall = np.zeros(n)
    contacts = np.zeros(n, np.int64)
    done = np.zeros(n, np.int64)
    active = np.ones(n, bool)

    def start_episodes(which: np.ndarray) -> None:
        for ag, (b0, b1) in zip(agents, bounds, strict=True):
            sub = which[b0:b1]
            if sub.any():
                s0 = ag.draw_starts(start_h[b0:b1], starts, sub)
                s[b0:b1][sub] = s0[sub]
                ag.begin_episode(sub, s[b0:b1])
        for i in np.flatnonzero(which):
            x, y = world.disc.state_centre(int(s[i]))
            world.place(int(i), x, y, 0.0)

    clock = time.perf_counter
    t_learn = t_world = t_ep = 0.0
    t_start = clock()
    stop = _Stop()
    with sigint_to(stop):
        start_episodes(active)
        while active.any():
            t0 = clock()
            for ag, (b0, b1) in zip(agents, bounds, strict=True):
                a[b0:b1] = ag.act(active[b0:b1], s[b0:b1])
            t1 = clock()
            out = world.step(a, active)
            t2 = clock()
            s2 = out.state
            term = active & (s2 == goal)
            r = np.where(out.bumped, rw.bump, np.where(term, rw.goal, rw.step))
            t += active
            ret += np.where(active, r, 0.0)
            contacts += out.contacts
            trunc = active & (t >= max_steps)  # TimeLimit: also on a step that terminates
            t3 = clock()
            for ag, (b0, b1) in zip(agents, bounds, strict=True):
                ag.update(active[b0:b1], s[b0:b1], a[b0:b1], r[b0:b1], s2[b0:b1],
                          term[b0:b1], trunc[b0:b1])
            t4 = clock()
            np.copyto(s, s2, where=active)
            wall[active] += (t4 - t0) / active.sum()
            t_learn += (t1 - t0) + (t4 - t3)
            t_world += t2 - t1
            ended = term | trunc
            if ended.any():
                _end_episodes(ended, agents, bounds, logs, world, graded, done, t, ret, term,
                              wall, contacts, n_episodes, test_every, active)
                start_episodes(ended & active)
                t_ep += clock() - t4
            if stop.requested:
                raise KeyboardInterrupt
    t_loop = clock() - t_start
    results: list[list[PhysicsTrainResult]] = []
    for ag, (b0, b1) in zip(agents, bounds, strict=True):
        results.append([_result(ag, k, b0 + k, logs, sc, model, graded, n_episodes, fidelity)
                        for k in range(b1 - b0)])
    if split is not None:
        split.update(learner=t_learn, kernel=world.kernel_s, chipmunk=world.chipmunk_s,
                     episodes=t_ep, driver=t_loop - t_learn - t_world - t_ep,
                     world_python=t_world - world.kernel_s - world.chipmunk_s,
                     final=clock() - t_start - t_loop, primitives=float(logs.steps.sum()))
    return results


def _end_episodes(ended, agents, bounds, logs, world, graded, done, t, ret, term, wall,
                  contacts, n_episodes, test_every, active) -> None:
    for ag, (b0, b1) in zip(agents, bounds, strict=True):
        sub = ended[b0:b1]
        if not sub.any():
            continue
        ag.end_episode(sub)
        fmean, fstd = ag.last_shaping()
        for k in np.flatnonzero(sub):
            i = b0 + k
            e = done[i]
            logs.steps[i, e], logs.returns[i, e], logs.success[i, e] = t[i], ret[i], term[i]
            logs.shaping_mean[i, e], logs.shaping_std[i, e] = fmean[k], fstd[k]
            logs.wall[i, e], logs.contacts[i, e] = wall[i], contacts[i]
            logs.sim_time[i, e] = world.time_s(int(i))
            done[i] = e + 1
            t[i], ret[i], wall[i], contacts[i] = 0, 0.0, 0.0, 0
            if done[i] % test_every == 0 or done[i] == n_episodes:
                logs.tests_e[i].append(int(done[i]))
                logs.tests_l[i].append(greedy_test(ag.state(int(k)), graded)[0])
            if done[i] == n_episodes:
                active[i] = False


def _result(ag: BatchAgent, k: int, i: int, logs: _Logs, sc: Scenario, model: TabularModel,
            graded: TabularModel, n_episodes: int, fidelity: Any = None) -> PhysicsTrainResult:
    agent = ag.step_agent(k)
    length, route = greedy_test(agent.state, graded)
    driven = drive_greedy(agent, sc, fidelity=fidelity)
    extras = {"grid_optimal_route_length": model.optimal_route_length,
              "physics_optimal_route_length": graded.optimal_route_length,
              "continuous_optimal_route_m": continuous_optimum_rounded(sc),
              "contacts_per_episode": logs.contacts[i].tolist(),
              "sim_time_per_episode_s": np.round(logs.sim_time[i], 4).tolist(),
              **driven.extras()}
    return PhysicsTrainResult(
        agent=agent, steps=logs.steps[i], returns=logs.returns[i], success=logs.success[i],
        shaping_mean=logs.shaping_mean[i], shaping_std=logs.shaping_std[i],
        wall_time_s=logs.wall[i], test_episodes=np.asarray(logs.tests_e[i]),
        test_route_length=np.asarray(logs.tests_l[i]),
        optimal_length=graded.optimal_route_length, final_route=route,
        final_route_length=length,
        optimal_action_fraction=shortest_fraction(agent.state, graded), driven=driven,
        graded=graded, world_extras=extras)


# ------------------------------------------------------------------ sweeps

MAX_BATCH = 64  # robots per batch: beyond this a batched step gains little, and a sweep
#                 split into more tasks saves finished runs sooner and balances workers


def batchable(spec: Any) -> bool:
    """Physics runs without a recording train in batches (a recording taps one env)."""
    return spec.world == "physics" and spec.recording is None


def plan_tasks(specs: Sequence[Any], jobs: int = 1) -> list[list[int]]:
    """Spec indices per task: each grid or recorded run alone; physics runs that share a
    problem, budget and test cadence together, dealt round-robin (by seed, then method)
    into at least ``jobs`` tasks of at most :data:`MAX_BATCH` runs.

    Single runs go seed by seed (every method's first seed, then every method's second):
    on a cold numba cache the workers then compile different methods' kernels side by
    side instead of each compiling the same one (measured on the main command: see
    README). Results do not depend on the order: each run has its own seeds, and
    results.json lists runs in spec order."""
    tasks: list[list[int]] = []
    groups: dict[tuple[Any, ...], list[int]] = {}
    singles: list[int] = []
    for i, sp in enumerate(specs):
        if batchable(sp):
            groups.setdefault((sp.problem, sp.episodes, sp.test_every, sp.fidelity_spec),
                              []).append(i)
        else:
            singles.append(i)
    tasks += [[i] for i in sorted(singles, key=lambda i: (specs[i].seed, i))]
    for idx in groups.values():
        idx = sorted(idx, key=lambda i: (specs[i].seed, i))
        n_tasks = max(min(jobs, len(idx)), -(-len(idx) // MAX_BATCH))
        tasks += [t for t in (idx[k::n_tasks] for k in range(n_tasks)) if t]
    return tasks


def run_physics_batch(specs: Sequence[Any]) -> list[dict[str, Any]]:
    """Train physics specs (one problem, budget and test cadence) as one batch; their
    results.json records, in spec order."""
    from learning.streams import streams
    from learning.train import epsilon_route_lengths
    from scenarios.runs.spec import RunOutcome, load, make_config, run_record

    first = specs[0]
    if any((sp.problem, sp.episodes, sp.test_every, sp.fidelity_spec) !=
           (first.problem, first.episodes, first.test_every, first.fidelity_spec)
           for sp in specs):
        raise ValueError("a physics batch needs one problem, budget, test cadence, fidelity")
    sc, model = load(*first.problem)
    by_config: dict[tuple[str, Any], list[int]] = {}
    for i, sp in enumerate(specs):
        by_config.setdefault((sp.method, sp.overrides), []).append(i)
    groups, members, cfgs, evaluation = [], [], [], {}
    for (method, overrides), idx in by_config.items():
        cfg = make_config(method, overrides)
        rs = [streams(specs[i].seed) for i in idx]
        for i, r in zip(idx, rs, strict=True):
            evaluation[i] = r.evaluation
        groups.append(RunGroup(cfg, [r.learner for r in rs], [r.starts for r in rs],
                               [r.physics for r in rs]))
        members.append(idx)
        cfgs.append(cfg)
    results = train_physics_batch(sc, model, groups, first.episodes, first.test_every,
                                  fidelity=first.fidelity_spec)
    records: list[dict[str, Any] | None] = [None] * len(specs)
    for idx, cfg, group_results in zip(members, cfgs, results, strict=True):
        for i, res in zip(idx, group_results, strict=True):
            eps_routes = epsilon_route_lengths(res.agent.state, res.graded, cfg.eps,
                                               evaluation[i])
            records[i] = run_record(specs[i], cfg, RunOutcome.of(res, eps_routes))
    return [r for r in records if r is not None]


def run_task(specs: Sequence[Any]) -> list[dict[str, Any]]:
    """One task of :func:`plan_tasks`: a single run, or a physics batch."""
    from scenarios.runs.spec import run_one

    if len(specs) == 1 and not batchable(specs[0]):
        return [run_one(specs[0])]
    return run_physics_batch(specs)
