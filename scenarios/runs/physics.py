"""Physics training (``--world physics``): one loop for every physics run.

Every physics run, alone or one of a sweep's, recorded or not, is trained by
:func:`train_physics_runs`: the runs are the sub-envs of one
:class:`sim.physics.envs.vector.PhysicsRouteVectorEnv` (N robots in one Pymunk Space; a single
run is ``num_envs=1``), their learners the rows of one
:class:`learning.drivers.batch_agent.BatchAgent` per method and config. The loop is CleanRL's
``act -> step -> update``; the route problem's rules (reward, termination at G, the time
limit, each run's noise stream) are the env's. The env runs with autoreset ``DISABLED``:
the loop resets a run's sub-env when its episode ends, with a start cell drawn from the
run's own start stream (as the grid kernels draw it), and a run that has finished its
episodes is simply not reset again. A recorded run is a tap on its sub-env
(:class:`scenarios.recording.hooks.EpisodeTaps`), so recorded runs batch with the rest.

Each run is the run it would be alone with its seed: its robot is the single-robot
world, its agent draws from its own learner stream in the same order, its start cells
come from its own start stream (tested record for record). Only the wall time differs:
a batched step's time is shared among the runs it advanced.

Greedy tests every ``test_every`` episodes, and the final policy, are graded in the
world the run trained in (:mod:`scenarios.runs.physics_grading`).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

from learning.compiled.generator_handle import handles
from learning.compiled.readout import greedy_actions
from learning.drivers.agent import StepAgent
from learning.drivers.batch_agent import BatchAgent
from learning.drivers.train import TrainResult
from learning.geometry import geometry_of
from learning.plain.learner import PlainBatchAgent, is_plain
from scenarios.runs.physics_fused import FusedRuns, Rules, jit_driver
from scenarios.runs.physics_grading import FinalGrade, Grader, final_policy_label
from scenarios.runs.work import add_episodes
from scenarios.signals import sigint_handled_by
from sim.grid import TabularModel
from sim.physics.envs.vector import PhysicsRouteVectorEnv
from sim.physics.models.optimum import continuous_optimum_m
from sim.physics.sigint import take_deferred
from sim.scenario import Scenario

TEST_BATCH = 16  # periodic tests above exact driven together, one env [tests]


@dataclass(frozen=True)
class RunGroup:
    """Runs of one method and config: one learner, one start and one noise stream per run."""

    cfg: Any
    learner_rngs: Sequence[np.random.Generator]
    start_rngs: Sequence[np.random.Generator]
    noise_rngs: Sequence[np.random.Generator] | None = None  # the physics streams (noise)
    grading_seeds: Sequence[int] | None = None  # each run's rollout seed (common across
    #                                             methods: the run's seed)
    init: Sequence[Any] | None = None  # each run's warm start (scenarios.runs.warm.Carried),
    #                                    or None: a fresh learner


@dataclass(frozen=True)
class RecordedRun:
    """Where run ``i`` of the loop is recorded: its recorder and what to record in full."""

    recorder: Any  # scenarios.recording.recorder.Recorder
    plan: Any  # scenarios.recording.hooks.RecordPlan


@dataclass(eq=False)
class PhysicsTrainResult(TrainResult):
    """A finished physics run: the one record of what a run measured
    (:class:`learning.drivers.train.TrainResult`), with the agent that learned and how the
    physics world graded it."""

    agent: StepAgent | None = None  # the learner (its state is ``state``)
    graded: TabularModel | None = None  # the physics world's own exact model (moves the disc
    #   can drive)
    grader: Grader | None = None  # how the run was graded (its world and fidelity)
    final_rollouts: Any = None  # sim.physics.models.rollouts.Rollouts of the final policy
    world_extras: dict[str, Any] = field(default_factory=dict)


def continuous_optimum_rounded(sc: Scenario) -> float | None:
    """The disc's any-angle S-G path length [m] (:mod:`sim.physics.models.optimum`), for records."""
    v = continuous_optimum_m(sc)
    return None if v is None else round(v, 4)


class StopFlag:
    """Ctrl-C during physics training: the first sets a flag that the loop turns into a
    ``KeyboardInterrupt`` between batched steps, in plain Python (a signal acted on inside
    a compiled call's argument handling or a Chipmunk query can crash the process or be
    lost); a second raises at once."""

    def __init__(self) -> None:
        self.requested = False

    def request(self, _sig: int, _frame: Any) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True


def sigint_to(stopper: StopFlag) -> contextlib.AbstractContextManager[None]:
    """SIGINT goes to ``stopper.request`` while the block runs (main thread only)."""
    return sigint_handled_by(stopper.request)


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

    def arrays(self, i: int, done: int) -> dict[str, np.ndarray]:
        """Run ``i``'s first ``done`` episodes, as a recording's curves want them."""
        return {"steps": self.steps[i, :done], "returns": self.returns[i, :done],
                "success": self.success[i, :done], "shaping_mean": self.shaping_mean[i, :done],
                "shaping_std": self.shaping_std[i, :done], "wall_time_s": self.wall[i, :done]}


def train_physics_runs(sc: Scenario, model: TabularModel, groups: Sequence[RunGroup],
                       n_episodes: int, test_every: int = 10, fidelity: Any = None,
                       recorded: dict[int, RecordedRun] | None = None,
                       split: dict[str, float] | None = None, fused: bool = True
                       ) -> list[list[PhysicsTrainResult]]:
    """Train every run of every group at once; results per group, per run.

    ``recorded[i]`` records run ``i`` (runs are numbered group by group). ``split``, if
    given, receives the wall time [s] of the parts of the loop: ``learner`` (act and
    update), ``kernel`` (the world's compiled call), ``chipmunk`` (casts and contact
    checks), ``episodes`` (ends, greedy tests, starts), ``driver`` (the rest of the loop)
    and ``final`` (final grading), plus ``primitives``, and ``fused``: the compiled calls
    that drive unrecorded runs of compiled learners whole (:mod:`scenarios.runs.physics_fused`;
    ``fused=False`` steps them in lock-step with the rest, as before: the same runs).
    """
    recorded = dict(recorded or {})
    if recorded:  # only then: scenarios.recording (rerun) costs 270 ms to import
        from scenarios.recording.hooks import ChunkLogger, EpisodeTaps
    geom = geometry_of(model)
    starts = np.asarray(geom.start_states)
    agents, bounds = [], []
    lo = 0
    for g in groups:
        agents.append(batch_agent(g.cfg, geom, list(g.learner_rngs), list(g.start_rngs),
                                  g.init))
        bounds.append((lo, lo + len(g.learner_rngs)))
        lo += len(g.learner_rngs)
    n = lo
    start_h = handles([r for g in groups for r in g.start_rngs])
    world = PhysicsRouteVectorEnv(n, sc, max_episode_steps=sc.steps_per_episode,
                                  fidelity=fidelity, autoreset_mode=AutoresetMode.DISABLED,
                                  trajectories=bool(recorded), contact_records=bool(recorded),
                                  lean_infos=not recorded)  # a tap reads the full infos
    noise = [r for g in groups for r in (g.noise_rngs or [None] * len(g.learner_rngs))]
    for i, r in enumerate(noise):
        if r is not None:
            world.set_noise_rng(i, r)
    grading_seeds = [s for g in groups
                     for s in (g.grading_seeds or [0] * len(g.learner_rngs))]
    grader = Grader(sc, world.fidelity)
    carried = [c for g in groups for c in (g.init or [None] * len(g.learner_rngs))]
    init_grades = _grade_carried(grader, carried, grading_seeds, geom.n_actions)
    env = EpisodeTaps(world, sorted(recorded)) if recorded else world
    views = {i: ChunkLogger(r.recorder, r.plan) for i, r in recorded.items()}
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
        for i, r in recorded.items():
            if which[i]:
                env.arm(i, r.plan.wants(int(done[i])))
        env.reset(options={"reset_mask": which, "starts": s})

    pending: list[tuple[int, np.ndarray, int]] = []  # tests due: (run, policy, episode)

    def run_tests(count: int) -> None:
        """The first ``count`` tests due, driven together (Grader.tests)."""
        batch = pending[:count]
        del pending[:count]
        out = grader.tests([table for _, table, _ in batch],
                           [grading_seeds[i] for i, _, _ in batch], [e for _, _, e in batch])
        for (i, _, e), (length, _) in zip(batch, out, strict=True):
            logs.tests_e[i].append(e)
            logs.tests_l[i].append(length)

    def test_due(i: int, ag: Any, k: int) -> None:
        """Run ``i`` (row ``k`` of ``ag``) ended an episode whose greedy test is due."""
        if grader.in_rollouts and i not in views:
            # the policy now; driven with other runs' tests (run_tests)
            pending.append((i, greedy_actions(ag.state(k)), int(done[i])))
            return
        length, route = grader.test(ag.state(k), grading_seeds[i], int(done[i]))
        logs.tests_e[i].append(int(done[i]))
        logs.tests_l[i].append(length)
        if i in views:
            views[i].after_chunk(int(done[i]), logs.arrays(i, done[i]), ag.state(k), route)

    clock = time.perf_counter
    t_learn = t_world = t_ep = t_fused = 0.0
    t_start = clock()
    stop = StopFlag()
    with sigint_to(stop):
        start_episodes(active)
        # runs of compiled learners that are not recorded: one compiled call drives many
        # primitives of each (scenarios.runs.physics_fused); the rest step in lock-step below
        loop = {"s": s, "a": a, "t": t, "ret": ret, "contacts": contacts, "done": done,
                "wall": wall}
        drivers = fused_groups(agents, bounds, recorded, world.batch, start_h, starts,
                             _rules(sc, model, world), n_episodes, test_every,
                             loop) if fused else []
        while any(f.live for _, f in drivers):
            for ag, f in drivers:
                if not f.live:
                    continue
                t0 = clock()
                due, _, ended_n = f.drive()
                t1 = clock()
                t_fused += t1 - t0
                if ended_n:
                    add_episodes(ended_n, physics=True)
                for k in due:
                    test_due(f.b0 + k, ag, k)
                    f.tested(k)
                t_ep += clock() - t1
            t1 = clock()
            while len(pending) >= TEST_BATCH:
                run_tests(TEST_BATCH)
            t_ep += clock() - t1
            if stop.requested or take_deferred():
                raise KeyboardInterrupt
        for _, f in drivers:
            f.write_logs(logs)
            active[f.b0:f.b0 + f.agent.n] &= ~f.mine
            parked = np.zeros(n, bool)
            parked[f.b0:f.b0 + f.agent.n] = f.mine
            world.park(parked)
        # groups with a run still training (a finished group's calls would do nothing: in a
        # sweep's long tail, most groups are done); renewed when a run finishes
        live = [(ag, b0, b1) for ag, (b0, b1) in zip(agents, bounds, strict=True)]
        while active.any():
            t0 = clock()
            for ag, b0, b1 in live:
                a[b0:b1] = ag.act(active[b0:b1], s[b0:b1])
            t1 = clock()
            s2, r, term, trunc, info = env.step(a)
            t2 = clock()
            t += active
            ret += r
            contacts += info["contacts"]
            t3 = clock()
            for ag, b0, b1 in live:
                ag.update(active[b0:b1], s[b0:b1], a[b0:b1], r[b0:b1], s2[b0:b1],
                          term[b0:b1], trunc[b0:b1])
            t4 = clock()
            np.copyto(s, s2, where=active)
            wall[active] += (t4 - t0) / active.sum()
            t_learn += (t1 - t0) + (t4 - t3)
            t_world += t2 - t1
            ended = term | trunc
            if ended.any():
                for ag, (b0, b1) in zip(agents, bounds, strict=True):
                    sub = ended[b0:b1]
                    if not sub.any():
                        continue
                    ag.end_episode(sub)
                    add_episodes(int(np.count_nonzero(sub)), physics=True)
                    fmean, fstd = ag.last_shaping()
                    for k in np.flatnonzero(sub):
                        i = b0 + int(k)
                        e = int(done[i])
                        logs.steps[i, e] = t[i]
                        logs.returns[i, e], logs.success[i, e] = ret[i], term[i]
                        logs.shaping_mean[i, e], logs.shaping_std[i, e] = fmean[k], fstd[k]
                        logs.wall[i, e], logs.contacts[i, e] = wall[i], contacts[i]
                        logs.sim_time[i, e] = info["time_s"][i]
                        done[i] = e + 1
                        t[i], ret[i], wall[i], contacts[i] = 0, 0.0, 0.0, 0
                        if i in recorded:
                            env.log_to(i, recorded[i].recorder, e)
                        if done[i] % test_every == 0 or done[i] == n_episodes:
                            test_due(i, ag, int(k))
                        if done[i] == n_episodes:
                            active[i] = False
                            live = [(g, b0, b1) for g, b0, b1 in live if active[b0:b1].any()]
                while len(pending) >= TEST_BATCH:
                    run_tests(TEST_BATCH)
                start_episodes(ended & active)
                t_ep += clock() - t4
            if stop.requested or take_deferred():
                raise KeyboardInterrupt
        t5 = clock()
        if pending:
            run_tests(len(pending))
        t_ep += clock() - t5
    t_loop = clock() - t_start
    runs = [(ag.step_agent(k), b0 + k) for ag, (b0, b1) in zip(agents, bounds, strict=True)
            for k in range(b1 - b0)]
    finals = iter(grader.finals([agent.state for agent, _ in runs],
                                [grading_seeds[i] for _, i in runs]))
    results: list[list[PhysicsTrainResult]] = []
    for b0, b1 in bounds:
        results.append([_result(agent, next(finals), i, logs, grader, model,
                                carried[i], init_grades.get(i))
                        for agent, i in runs[b0:b1]])
    if split is not None:
        b = world.batch
        split.update(learner=t_learn, kernel=b.kernel_s, chipmunk=b.chipmunk_s, fused=t_fused,
                     episodes=t_ep, driver=t_loop - t_learn - t_world - t_ep - t_fused,
                     world_python=t_world - b.kernel_s - b.chipmunk_s,
                     final=clock() - t_start - t_loop, primitives=float(logs.steps.sum()))
    return results


def fused_groups(agents: list[Any], bounds: list[tuple[int, int]], recorded: dict[int, Any],
                 batch: Any, start_h: np.ndarray, starts: np.ndarray, rules: Rules,
                 n_episodes: int, test_every: int, loop: dict[str, np.ndarray]
                 ) -> list[tuple[Any, FusedRuns]]:
    """(agent, its fused runs) for each group of compiled learners (or of a ``@jitclass``
    learner's) with unrecorded runs."""
    out = []
    for ag, (b0, b1) in zip(agents, bounds, strict=True):
        rows = np.array([k for k in range(b1 - b0) if b0 + k not in recorded], np.int64)
        jit = getattr(ag, "jit", False)  # runs of a @jitclass learner: its own compiled loop
        if (isinstance(ag, BatchAgent) or jit) and rows.size:
            out.append((ag, FusedRuns(ag, rows, b0, batch, start_h[b0:b1], starts, rules,
                                      n_episodes, test_every, loop,
                                      jit_driver(ag.jit_with_start) if jit else None)))
    return out


def _rules(sc: Scenario, model: TabularModel, world: PhysicsRouteVectorEnv) -> Rules:
    """The env's rules as :func:`scenarios.runs.physics_fused.drive_runs` reads them."""
    rw = sc.rewards
    return Rules(int(model.goal), float(rw.goal), float(rw.bump), float(rw.step),
                 int(sc.steps_per_episode), float(world.batch.config.dt_s))


def batch_agent(cfg: Any, geom: Any, learner_rngs: list[np.random.Generator],
                start_rngs: list[np.random.Generator], init: Sequence[Any] | None = None
                ) -> Any:
    """The learners of one group: compiled rows (:class:`BatchAgent`), or plain-Python
    learners (:class:`learning.plain.learner.PlainBatchAgent`) with the same calls; ``init``:
    each run's warm start (:class:`scenarios.runs.warm.Carried`) or None."""
    starting = None if init is None else [None if c is None else c.starting_learner()
                                          for c in init]
    if is_plain(cfg):
        return PlainBatchAgent(cfg, geom, learner_rngs, start_rngs, starting)
    return BatchAgent(cfg, geom, learner_rngs, starting)


def _grade_carried(grader: Grader, carried: list[Any], seeds: list[int], n_actions: int
                   ) -> dict[int, FinalGrade]:
    """The policies warm-started runs begin with, graded at the rung as a final policy is
    (the same drives): what the lower world's policy is worth here before any robot time."""
    which = [i for i, c in enumerate(carried) if c is not None]
    if not which:
        return {}
    grades = grader.finals([carried[i].policy_state(n_actions) for i in which],
                           [seeds[i] for i in which])
    return dict(zip(which, grades, strict=True))


def _result(agent: StepAgent, final: FinalGrade, i: int, logs: _Logs, grader: Grader,
            model: TabularModel, carried: Any = None, init_grade: FinalGrade | None = None
            ) -> PhysicsTrainResult:
    warm = {}
    if carried is not None and init_grade is not None:
        warm = {"pretrain": {**carried.phase,
                             "policy_route_length": int(init_grade.length),
                             "policy": init_grade.extras["final_policy"]}}
    extras = {"grid_optimal_route_length": model.optimal_route_length,
              "physics_optimal_route_length": grader.exact.optimal_route_length,
              "continuous_optimal_route_m": continuous_optimum_rounded(grader.scenario),
              "contacts_per_episode": logs.contacts[i].tolist(),
              "sim_time_per_episode_s": np.round(logs.sim_time[i], 4).tolist(),
              "robot_seconds": round(float(logs.sim_time[i].sum()), 4),
              **final.extras, **warm}
    steps = logs.steps[i]
    return PhysicsTrainResult(
        config=agent.cfg, state=agent.state, episodes=len(steps), env_steps=int(steps.sum()),
        agent=agent, steps=steps, returns=logs.returns[i], success=logs.success[i],
        shaping_mean=logs.shaping_mean[i], shaping_std=logs.shaping_std[i],
        wall_time_s=logs.wall[i], test_episodes=np.asarray(logs.tests_e[i]),
        test_route_length=np.asarray(logs.tests_l[i]),
        optimal_length=grader.exact.optimal_route_length, final_route=final.route,
        final_route_length=final.length,
        optimal_action_fraction=final.optimal_action_fraction, graded=grader.exact,
        grader=grader, final_rollouts=final.rollouts, world_extras=extras)


def train_physics(cfg: Any, sc: Scenario, model: TabularModel, n_episodes: int,
                  rng: np.random.Generator, test_every: int = 10,
                  recorder: Any = None, plan: Any = None,
                  start_rng: np.random.Generator | None = None, fidelity: Any = None,
                  noise_rng: np.random.Generator | None = None,
                  grading_seed: int = 0, init: Any = None) -> PhysicsTrainResult:
    """One physics run: :func:`train_physics_runs` with one sub-env.

    ``rng`` is the learner's stream, ``start_rng`` the start cells' (default ``rng``):
    with :func:`learning.streams.streams` a grid run and a physics run of one seed
    start their episodes in the same cells. ``init``: a warm start
    (:class:`scenarios.runs.warm.Carried`).
    """
    group = RunGroup(cfg, [rng], [rng if start_rng is None else start_rng],
                     None if noise_rng is None else [noise_rng], [grading_seed],
                     None if init is None else [init])
    recorded = {0: RecordedRun(recorder, plan)} if recorder is not None else None
    return train_physics_runs(sc, model, [group], n_episodes, test_every, fidelity,
                              recorded)[0][0]


def log_final(recorder: Any, res: PhysicsTrainResult) -> None:
    """The final policy on a recording's map: one drive of it, every physics step, labelled
    with what its rollouts achieved at the run's fidelity."""
    r = res.final_rollouts
    path = r.path if r is not None and len(r.path) else None
    recorder.log_route("final route", res.final_route, path_m=path,
                       label=final_policy_label(res.grader.fidelity, r, res.final_route_length))
