"""The features every plain learner has as a Python one does, checked the same way for each
kind (``@jitclass``, batched): a recorded run, a sweep that resumes, physics graded by drives."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from scenarios import api


def check_recorded(learner: str, world: str, folder: Path) -> None:
    rrd = folder / "run.rrd"
    run = api.train("paper-40", learner, episodes=10, world=world, record=rrd)
    assert run.recording == rrd and rrd.stat().st_size > 10_000
    assert run.record["config"]["learner"] == learner


def check_resumes_and_graded(learner: str, folder: Path, capsys: Any) -> None:
    def sweep(resume: bool) -> Any:
        return api.compare("paper-40", [learner], worlds=("grid", "physics"), seeds=2,
                           episodes=10, jobs=1, out=folder / "sweep", resume=resume)

    first = sweep(False)
    phys = first.of(learner, "physics")
    assert len(phys) == 2 and all(0.0 <= r.record["final_policy"]["p_goal"] <= 1.0
                                  and r.record["final_policy"]["rollouts"] > 0 for r in phys)
    capsys.readouterr()
    again = sweep(True)
    assert "4 of 4 runs already finished" in capsys.readouterr().err
    assert [dict(r.record) for r in again.runs] == [dict(r.record) for r in first.runs]
