"""A sweep's batched runs as tasks: physics runs that share a problem train together, as the
sub-envs of one vector env (:func:`scenarios.runs.physics.train_physics_runs`), and a
batched plain learner's grid runs (:mod:`learning.plain.batched`) step together in one
lock-step batch (:func:`run_grid_batch`).

Recorded physics runs batch with the rest: a recording taps its run's sub-env. A grid run
recorded in full runs alone (its recorder follows one run), as a batch of one: each run
keeps its streams, so its record is the one it would have had alone.
"""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from typing import Any

from learning.drivers.plain_batch_train import train_plain_batch
from learning.drivers.train import epsilon_route_lengths
from learning.methods.registry import is_located
from learning.plain.batched import is_batched
from learning.plain.learner import PlainConfig
from learning.streams import streams
from scenarios.runs.physics import RecordedRun, RunGroup, log_final, train_physics_runs
from scenarios.runs.physics_grading import Grader
from scenarios.runs.spec import RunOutcome, load, make_config, method_class, run_record
from scenarios.runs.warm import pretrain_in_grid

# ------------------------------------------------------------------ sweeps

MAX_BATCH = 64  # robots per batch: beyond this a batched step gains little, and a sweep
#                 split into more tasks saves finished runs sooner and balances workers


def batchable(spec: Any) -> bool:
    """Physics runs train in batches (recorded ones too: a recording taps a sub-env)."""
    return spec.world == "physics"


def plan_tasks(specs: Sequence[Any], jobs: int = 1) -> list[list[int]]:
    """Spec indices per task: each grid run alone, but a batched learner's grid runs of one
    problem, budget and cadence together (:mod:`scenarios.runs.grid_batch`); physics runs
    that share a problem, budget and test cadence together, dealt round-robin (by seed, then method)
    into at least ``jobs`` tasks of at most :data:`MAX_BATCH` runs.

    Single runs go seed by seed (every method's first seed, then every method's second):
    on a cold numba cache the workers then compile different methods' kernels side by
    side instead of each compiling the same one (measured on the main command: see
    README). Results do not depend on the order: each run has its own seeds, and
    results.json lists runs in spec order. Plain-Python learners batch apart from the
    compiled methods: every batched step waits for its slowest learner, and a compiled
    method's batch must not run at a Python learner's pace (``scenarios.bench.plain``)."""
    tasks: list[list[int]] = []
    groups: dict[tuple[Any, ...], list[int]] = {}
    singles: list[int] = []
    for i, sp in enumerate(specs):
        if grid_batchable(sp):  # a batched learner's grid runs: lock-step, one method
            groups.setdefault(grid_batch_key(sp), []).append(i)
        elif batchable(sp):
            groups.setdefault((sp.problem, sp.episodes, sp.test_every, sp.fidelity_spec,
                               in_python(sp.method)), []).append(i)
        else:
            singles.append(i)
    tasks += [[i] for i in sorted(singles, key=lambda i: (specs[i].seed, i))]
    for idx in groups.values():
        idx = sorted(idx, key=lambda i: (specs[i].seed, i))
        n_tasks = max(min(jobs, len(idx)), -(-len(idx) // MAX_BATCH))
        tasks += [t for t in (idx[k::n_tasks] for k in range(n_tasks)) if t]
    return tasks


def in_python(method: str) -> bool:
    """Whether ``method`` is a plain-Python learner (:mod:`learning.plain.learner`)."""
    return is_located(method) and issubclass(method_class(method), PlainConfig)


def run_physics_batch(specs: Sequence[Any]) -> list[dict[str, Any]]:
    """Train physics specs (one problem, budget and test cadence) as one batch; their
    results.json records, in spec order."""
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
        # a pretrained run's grid phase first, on its own streams (which then continue)
        init = [pretrain_in_grid(method, cfg, model, specs[i].pretrain, specs[i].test_every,
                                 r.learner, r.starts) if specs[i].pretrain else None
                for i, r in zip(idx, rs, strict=True)]
        groups.append(RunGroup(cfg, [r.learner for r in rs], [r.starts for r in rs],
                               [r.physics for r in rs], [specs[i].seed for i in idx],
                               init if any(c is not None for c in init) else None))
        members.append(idx)
        cfgs.append(cfg)
    order = [i for idx in members for i in idx]  # run number in the loop -> spec index
    with contextlib.ExitStack() as stack:
        recorded = {}
        for run, i in enumerate(order):
            rec = _open_recorder(specs[i], cfgs[_group_of(members, i)], sc, model, stack)
            if rec is not None:
                recorded[run] = rec
        results = train_physics_runs(sc, model, groups, first.episodes, first.test_every,
                                     fidelity=first.fidelity_spec, recorded=recorded)
        records: list[dict[str, Any] | None] = [None] * len(specs)
        run = 0
        for idx, cfg, group_results in zip(members, cfgs, results, strict=True):
            for i, res in zip(idx, group_results, strict=True):
                if run in recorded:
                    log_final(recorded[run].recorder, res)
                run += 1
                eps_routes = res.grader.epsilon_routes(res.agent.state, cfg.eps,
                                                       evaluation[i])
                records[i] = run_record(specs[i], cfg, RunOutcome.of(res, eps_routes))
    return [r for r in records if r is not None]


def _group_of(members: list[list[int]], i: int) -> int:
    return next(g for g, idx in enumerate(members) if i in idx)


def _open_recorder(spec: Any, cfg: Any, sc: Any, model: Any,
                   stack: contextlib.ExitStack) -> RecordedRun | None:
    """The recorder of a spec recorded in full (curves-only runs record nothing here: the
    comparison logs their curves from the record)."""
    opts = spec.recording
    if opts is None or not opts.detail:
        return None
    # lazy: scenarios.recording (rerun) costs 270 ms in every run's process
    from scenarios.recording.hooks import RecordPlan
    from scenarios.recording.recorder import Recorder

    plan = RecordPlan(spec.episodes, every=max(1, opts.every),
                      values_every=max(1, opts.values_every), detail=opts.detail)
    rec = stack.enter_context(Recorder.create(
        opts.path, sc, model, method=spec.method, config=cfg, seed=spec.seed,
        world=spec.world, prefix=opts.prefix, recording_id=opts.recording_id,
        blueprint=not opts.prefix, with_scene=opts.detail,
        fidelity=spec.fidelity_spec.label))
    return RecordedRun(rec, plan)


# ------------------------------------------------------------------ batched grid runs

def grid_batchable(spec: Any) -> bool:
    """A grid run of a batched plain learner, not recorded in full."""
    if spec.world != "grid" or (spec.recording is not None and spec.recording.detail):
        return False
    if not is_located(spec.method):
        return False
    cls = method_class(spec.method)
    return issubclass(cls, PlainConfig) and is_batched(cls.learner)


def grid_batch_key(spec: Any) -> tuple[Any, ...]:
    """Grid runs with equal keys train in one lock-step batch (one learner object)."""
    return ("grid", spec.problem, spec.episodes, spec.test_every, spec.method, spec.overrides)


def run_grid_batch(specs: Sequence[Any]) -> list[dict[str, Any]]:
    """Train grid specs of one batched learner (one problem, budget, cadence) together; their
    results.json records, in spec order."""
    first = specs[0]
    if any(grid_batch_key(sp) != grid_batch_key(first) for sp in specs):
        raise ValueError("a grid batch needs one method, problem, budget and test cadence")
    sc, model = load(*first.problem)
    cfg = make_config(first.method, first.overrides)
    rs = [streams(sp.seed) for sp in specs]
    results = train_plain_batch(cfg, model, first.episodes, [r.learner for r in rs],
                                first.test_every, [r.starts for r in rs])
    records = []
    for sp, r, res in zip(specs, rs, results, strict=True):
        # the paper's test, on its own stream so it never changes the training run
        eps_routes = epsilon_route_lengths(res.state, model, cfg.eps, r.evaluation)
        extras = (Grader(sc, sp.fidelity_spec).final(res.state, sp.seed).extras
                  if sp.drive_final else None)
        records.append(run_record(sp, cfg, RunOutcome.of(res, eps_routes, extras)))
    return records
