"""A compiled (``@jitclass``) and a batched plain learner have every feature a Python
learner has: a recorded run, a sweep that resumes, physics runs graded by their final
policy's drives (issue 65). Their figures against the compiled ``st-ql`` are
``tests/test_compiled_learner.py`` and ``tests/test_batched_learner.py``."""

from __future__ import annotations

import pytest

from scenarios import api

JIT = "tests.plain_learners.st_ql_jit:STQLJit"
BATCHED = "tests.plain_learners.st_ql_batched:STQLBatched"


@pytest.mark.parametrize("learner", [JIT, BATCHED])
@pytest.mark.parametrize("world", ["grid", "physics"])
def test_a_compiled_or_batched_learners_run_is_recorded(tmp_path, learner, world):
    rrd = tmp_path / "run.rrd"
    run = api.train("paper-40", learner, episodes=10, world=world, record=rrd)
    assert run.recording == rrd and rrd.stat().st_size > 10_000
    assert run.record["config"]["learner"] == learner


@pytest.mark.parametrize("learner", [JIT, BATCHED])
def test_a_sweep_of_a_compiled_or_batched_learner_resumes_and_grades_physics(
        tmp_path, capsys, learner):
    out = tmp_path / "sweep"
    first = api.compare("paper-40", [learner], worlds=("grid", "physics"), seeds=2,
                        episodes=10, jobs=1, out=out)
    phys = first.of(learner, "physics")
    assert len(phys) == 2 and all(0.0 <= r.record["final_policy"]["p_goal"] <= 1.0
                                  and r.record["final_policy"]["rollouts"] > 0 for r in phys)
    capsys.readouterr()
    again = api.compare("paper-40", [learner], worlds=("grid", "physics"), seeds=2,
                        episodes=10, jobs=1, out=out, resume=True)
    assert "4 of 4 runs already finished" in capsys.readouterr().err
    assert [dict(r.record) for r in again.runs] == [dict(r.record) for r in first.runs]
