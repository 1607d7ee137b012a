"""One run, or one task of a sweep, in this process: the entry point every backend calls.

A grid run trains with the fused kernels (:func:`run_one`); physics runs train as a batch
of sub-envs (:mod:`scenarios.runs.physics_batch`), a single one as a batch of one.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from learning.drivers.plain_train import train_grid
from learning.drivers.train import epsilon_route_lengths
from learning.streams import streams
from scenarios.runs.physics_batch import (
    batchable,
    grid_batchable,
    run_grid_batch,
    run_physics_batch,
)
from scenarios.runs.physics_grading import Grader
from scenarios.runs.spec import (
    WORLDS,
    ExperimentError,
    RunOutcome,
    RunSpec,
    load,
    make_config,
    run_record,
)
from scenarios.runs.work import CountingObserver, warm_up
from sim.grid import TabularModel
from sim.scenario import Scenario


def run_task(specs: Sequence[Any]) -> list[dict[str, Any]]:
    """One task of :func:`scenarios.runs.physics_batch.plan_tasks`: a single run, a
    physics batch, or a batched learner's grid runs."""
    with warm_up(sp.method for sp in specs):
        if grid_batchable(specs[0]):  # a batched learner's grid runs, in lock-step
            return run_grid_batch(specs)
        if len(specs) == 1 and not batchable(specs[0]):
            return [run_one(specs[0])]
        return run_physics_batch(specs)


def run_one(spec: RunSpec) -> dict[str, Any]:
    """Train one run in this process and return its results.json record."""
    sc, model = load(*spec.problem)
    cfg = make_config(spec.method, spec.overrides)
    if spec.world not in WORLDS:
        raise ExperimentError("command line", "--world", f"unknown world {spec.world!r}",
                              f"use one of: {', '.join(WORLDS)}")
    if spec.world == "physics":  # one physics loop: a single run is a batch of one
        return run_physics_batch([spec])[0]
    opts = spec.recording
    if opts is None or not opts.detail:
        # a curves-only run of a comparison records nothing itself: the comparison logs its
        # curves from this record when it gathers the recording (a stream and a part file
        # per run cost ~0.05 s each, a quarter of a 0.2 s run)
        return run_record(spec, cfg, _train(spec, sc, model, cfg))
    # lazy: scenarios.recording (rerun) costs 270 ms in every run's process
    from scenarios.recording.hooks import RecordPlan
    from scenarios.recording.recorder import Recorder

    plan = RecordPlan(spec.episodes, every=max(1, opts.every),
                      values_every=max(1, opts.values_every), detail=opts.detail)
    with Recorder.create(opts.path, sc, model, method=spec.method, config=cfg,
                         seed=spec.seed, world=spec.world, prefix=opts.prefix,
                         recording_id=opts.recording_id, blueprint=not opts.prefix,
                         with_scene=opts.detail,
                         fidelity=None) as rec:
        outcome = _train(spec, sc, model, cfg, rec, plan)
        if opts.detail:
            rec.log_route("final route", outcome.result.final_route)
        return run_record(spec, cfg, outcome)


def _train(spec: RunSpec, sc: Scenario, model: TabularModel, cfg: Any, recorder: Any = None,
           plan: Any = None) -> RunOutcome:
    """A grid run (physics runs go through :mod:`scenarios.runs.physics_batch`)."""
    rs = streams(spec.seed)  # starts, learner, evaluation: independent (common random numbers)
    rng = rs.learner

    observer = None
    if recorder is not None:
        # lazy: scenarios.recording (rerun) costs 270 ms in every run's process
        from scenarios.recording.hooks import GridRecorder

        observer = GridRecorder(recorder, plan)

    result = train_grid(cfg, model, spec.episodes, rng, test_every=spec.test_every,
                   observer=CountingObserver(observer), start_rng=rs.starts)
    # the paper's test, on its own stream so it never changes the training run
    eps_routes = epsilon_route_lengths(result.state, model, cfg.eps, rs.evaluation)
    extras = None
    if spec.drive_final:  # the grid-learned policy, graded in the physics world
        extras = Grader(sc, spec.fidelity_spec).final(result.state, spec.seed).extras
    return RunOutcome.of(result, eps_routes, extras)
