"""Physics sweeps in batches give the records the one-run-at-a-time driver gives."""

from __future__ import annotations

import pytest

from learning.methods.registry import METHODS
from scenarios.runs.physics_batch import MAX_BATCH, plan_tasks, run_physics_batch
from scenarios.runs.run import run_one
from scenarios.runs.spec import RecordOptions, RunSpec

WALL = ("wall_time_s", "wall_time_per_episode_s")


def _without_wall(rec):
    return {k: v for k, v in rec.items() if k not in WALL}


@pytest.mark.parametrize("half", [0, 1])
def test_batched_physics_runs_equal_single_runs(half):
    methods = list(METHODS)[half::2]  # every method, in two batches
    specs = [RunSpec("paper-40", m, seed, 20, world="physics", rewards="goal-only")
             for m in methods for seed in (0, 3)]
    batched = run_physics_batch(specs)
    assert len(batched) == len(specs)
    for spec, rec in zip(specs, batched, strict=True):
        assert (rec["method"], rec["seed"]) == (spec.method, spec.seed)
        assert _without_wall(rec) == _without_wall(run_one(spec)), spec.key


def test_plan_tasks_batches_physics_recorded_or_not_and_balances_jobs():
    grid = [RunSpec("paper-40", "st-ql", s, 10) for s in range(3)]
    phys = [RunSpec("paper-40", m, s, 10, world="physics")
            for m in ("st-ql", "haql") for s in range(5)]
    recorded = RunSpec("paper-40", "st-ql", 9, 10, world="physics",
                       recording=RecordOptions("x.rrd"))
    specs = [*grid, *phys, recorded]
    tasks = plan_tasks(specs, jobs=2)
    flat = sorted(i for t in tasks for i in t)
    assert flat == list(range(len(specs)))  # every spec once
    alone = [t for t in tasks if len(t) == 1]
    assert {i for t in alone for i in t} == {0, 1, 2}  # grid runs alone
    batches = [t for t in tasks if len(t) > 1]  # the recorded run batches with the rest
    assert len(batches) == 2 and {len(t) for t in batches} == {5, 6}
    assert any(len(specs) - 1 in t for t in batches)
    many = [RunSpec("paper-40", "st-ql", s, 10, world="physics") for s in range(MAX_BATCH + 1)]
    assert max(len(t) for t in plan_tasks(many, jobs=1)) <= MAX_BATCH
