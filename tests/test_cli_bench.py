"""``rnhql bench`` reaches every benchmark module (the heavy measurements stubbed out)."""

from __future__ import annotations

import json

from scenarios.bench import grid, learners, physics, physics_batch
from scenarios.cli.app import main


def test_bench_runs_each_section_and_prints_nested_figures(monkeypatch, capsys):
    monkeypatch.setattr(grid, "run_bench", lambda: {"build_ms": 5.5})
    monkeypatch.setattr(learners, "run_bench",
                        lambda: {"st_ql": 4.8e7, "planning": {"rnh_ql_plus_planning10": 7e5}})
    monkeypatch.setattr(physics, "run_bench", lambda: {"moves_per_s": 900.0})
    monkeypatch.setattr(physics_batch, "run_bench", lambda: {"learning": {"runs": 100}})
    assert main(["bench", "--physics"]) == 0
    out = capsys.readouterr().out
    assert "[foundation]" in out and "[learning]" in out and "[physics]" in out
    assert "[physics_batch]" in out and "learning.runs" in out
    assert "planning.rnh_ql_plus_planning10" in out and "700,000" in out
    assert main(["bench", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["learning"]["planning"] == {"rnh_ql_plus_planning10": 7e5}
    assert "physics" not in got


def test_batch_bench_measures_what_it_says():
    from sim.scenario_io import resolve_scenario

    row = physics_batch.primitives_per_s(resolve_scenario("paper-40"), 3, seconds=0.05)
    assert row["robots"] == 3 and row["primitives_per_s"] > 0
    assert 10 < row["physics_steps_per_primitive"] < 30  # ~18 at dt 0.1 s
    assert 0 <= row["kernel_fraction"] + row["chipmunk_fraction"] <= 1
