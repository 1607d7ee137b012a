"""A sweep's grid runs of a batched plain learner, trained in lock-step as one task.

A batched learner (:mod:`learning.plain.batched`) pays one call per step for all its runs
only if its runs step together: the seeds of one method, problem, budget and test cadence
are one task (:func:`scenarios.runs.physics_batch.plan_tasks` groups them), trained by
:func:`learning.drivers.plain_batch_train.train_plain_batch`. Each run keeps its streams,
so its record is the one it would have had alone. A run recorded in full runs alone (its
recorder follows one run), as a batch of one.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from learning.drivers.plain_batch_train import train_plain_batch
from learning.drivers.train import epsilon_route_lengths
from learning.plain.batched import is_batched
from learning.plain.learner import PlainConfig
from learning.streams import streams
from scenarios.runs.physics_grading import Grader
from scenarios.runs.spec import RunOutcome, load, make_config, method_class, run_record


def grid_batchable(spec: Any) -> bool:
    """A grid run of a batched plain learner, not recorded in full."""
    if spec.world != "grid" or (spec.recording is not None and spec.recording.detail):
        return False
    from learning.methods.registry import is_located

    if not is_located(spec.method):
        return False
    cls = method_class(spec.method)
    return issubclass(cls, PlainConfig) and is_batched(cls.learner)


def batch_key(spec: Any) -> tuple[Any, ...]:
    """Grid runs with equal keys train in one lock-step batch (one learner object)."""
    return ("grid", spec.problem, spec.episodes, spec.test_every, spec.method, spec.overrides)


def run_grid_batch(specs: Sequence[Any]) -> list[dict[str, Any]]:
    """Train grid specs of one batched learner (one problem, budget, cadence) together; their
    results.json records, in spec order."""
    first = specs[0]
    if any(batch_key(sp) != batch_key(first) for sp in specs):
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
