"""One run on its own, with what a single run offers beyond a sweep's: a checkpoint to save or
resume (compiled methods' grid runs), and a recording of every detail.

:func:`train_single` is what ``rnhql train`` and :func:`scenarios.api.train` run. Its
record equals the sweep's record of the same spec (the same streams: a run of
``rnhql compare`` with that seed), so a run here and in a comparison agree.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from learning.drivers.checkpoint import Checkpoint, checkpoint_bytes, load_checkpoint
from learning.drivers.plain_train import train_grid
from learning.drivers.train import epsilon_route_lengths
from learning.geometry import geometry_of
from learning.streams import streams
from scenarios.runs.physics import log_final, train_physics
from scenarios.runs.spec import (
    RunOutcome,
    RunSpec,
    layout_digest,
    make_config,
    run_record,
    scenario_digest,
)
from scenarios.runs.warm import Carried, carried_of, pretrain_in_grid
from sim.files import atomic_write_bytes
from sim.grid import TabularModel
from sim.scenario import Scenario


def train_single(spec: RunSpec, sc: Scenario, model: TabularModel, *,
                 save: str | Path | None = None, resume: str | Path | None = None,
                 record: str | None = None, record_every: int = 10,
                 record_values_every: int = 300, init: Carried | None = None,
                 announce: Callable[[int | None], None] | None = None
                 ) -> tuple[dict[str, Any], Carried]:
    """Train ``spec`` (its scenario already loaded as ``sc``, ``model``): its record, and what
    the trained learner carries into another world (``init`` of a next run).

    ``init``: a warm start for a physics run (:class:`scenarios.runs.warm.Carried`, checked
    by the caller): its learner and start streams continue; ``spec.pretrain`` > 0 trains
    that grid phase here first, as a sweep does. ``announce``: called once the checkpoint
    to resume is loaded and checked, before any training, with its episodes (or None)."""
    cfg = make_config(spec.method, spec.overrides)
    problem = {"scenario": scenario_digest(*spec.problem), "rewards": sc.rewards.label(),
               "layout": layout_digest(spec.scenario, spec.start, spec.goal),
               "world": spec.world}  # (a warm start says which world it learned in)
    if spec.world == "physics":
        problem["fidelity"] = spec.fidelity_spec.label
    rs = streams(spec.seed)  # the same streams as a run of `rnhql compare`
    rng, start_rng = rs.learner, rs.starts
    if init is not None:
        rng, start_rng = init.generators(rng, start_rng)
    checkpoint = None
    if resume:
        checkpoint = load_checkpoint(resume, spec.method, model.n_states, geometry_of(model))
        checkpoint.check_problem(problem)
    if announce is not None:
        announce(None if checkpoint is None else int(checkpoint.episodes))
    recorder = plan = observer = None
    if record is not None:
        # lazy: scenarios.recording (rerun) costs 270 ms at import; only a recorded run needs it
        from scenarios.recording.hooks import GridRecorder, RecordPlan
        from scenarios.recording.recorder import Recorder

        plan = RecordPlan(spec.episodes, every=record_every, values_every=record_values_every)
        recorder = Recorder.create(record, sc, model, method=spec.method, config=cfg,
                                   seed=spec.seed, world=spec.world,
                                   fidelity=(spec.fidelity_spec.label
                                             if spec.world == "physics" else None))
        observer = GridRecorder(recorder, plan)
    try:
        if spec.pretrain and spec.world == "physics":  # the grid phase first, recorded too
            init = pretrain_in_grid(spec.method, cfg, model, spec.pretrain, spec.test_every,
                                    rng, start_rng, _phase_recorder(recorder, spec, sc, model,
                                                                    cfg, record_every,
                                                                    record_values_every))
        if spec.world == "grid":
            result = train_grid(cfg, model, spec.episodes, rng, spec.test_every,
                                observer=observer, start_rng=start_rng, resume=checkpoint)
            if save:
                ck = Checkpoint.of_result(result, rng, start_rng)
                ck.problem = problem
                atomic_write_bytes(save, checkpoint_bytes(ck))
        else:
            result = train_physics(cfg, sc, model, spec.episodes, rng, spec.test_every,
                                   recorder=recorder, plan=plan, start_rng=start_rng,
                                   fidelity=spec.fidelity_spec, noise_rng=rs.physics,
                                   grading_seed=spec.seed, init=init)
            if save:  # (no per-episode metrics: a physics agent's state may count a grid
                #      phase's episodes too; its streams, for a next rung's warm start)
                ck = Checkpoint(result.config, result.state, rng.bit_generator.state,
                                int(result.env_steps),
                                start_rng_state=start_rng.bit_generator.state)
                ck.problem = problem
                atomic_write_bytes(save, checkpoint_bytes(ck))
            if recorder is not None:
                log_final(recorder, result)
        if recorder is not None and spec.world == "grid":
            recorder.log_route("final route", result.final_route)
    finally:
        if recorder is not None:
            recorder.close()  # also on Ctrl-C: the recording keeps what was logged
    # the paper's epsilon-greedy test on the evaluation stream, as `rnhql compare` runs it
    if spec.world == "grid":
        eps_routes = epsilon_route_lengths(result.state, model, cfg.eps, rs.evaluation)
    else:
        eps_routes = result.grader.epsilon_routes(result.agent.state, cfg.eps, rs.evaluation)
    carried = carried_of(spec.method, result, rng, start_rng, spec.world,
                         spec.fidelity_spec.label if spec.world == "physics" else None,
                         problem["layout"], int(model.n_states), "init (a Run)",
                         sc.rewards.label())
    return run_record(spec, cfg, RunOutcome.of(result, eps_routes)), carried


def _phase_recorder(recorder: Any, spec: RunSpec, sc: Scenario, model: TabularModel, cfg: Any,
                    every: int, values_every: int) -> Any:
    """The grid phase of a pretrained run, recorded into the run's own recording under
    ``grid_phase/`` (its map, curves, routes and heat maps; the rung's phase is the
    recording's top level): both phases in one file."""
    if recorder is None:
        return None
    from scenarios.recording.hooks import GridRecorder, RecordPlan
    from scenarios.recording.recorder import Recorder

    phase = Recorder.create(None, sc, model, method=spec.method, config=cfg, seed=spec.seed,
                            world="grid", prefix="grid_phase", file=recorder.file,
                            blueprint=False)
    return GridRecorder(phase, RecordPlan(spec.pretrain, every=every,
                                          values_every=values_every))
