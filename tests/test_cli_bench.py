"""``rnhql bench`` reaches every benchmark module (the heavy measurements stubbed out)."""

from __future__ import annotations

import json

from scenarios.bench import grid, learners, physics
from scenarios.cli.app import main


def test_bench_runs_each_section_and_prints_nested_figures(monkeypatch, capsys):
    monkeypatch.setattr(grid, "run_bench", lambda: {"build_ms": 5.5})
    monkeypatch.setattr(learners, "run_bench",
                        lambda: {"st_ql": 4.8e7, "planning": {"rnh_ql_plus_planning10": 7e5}})
    monkeypatch.setattr(physics, "run_bench", lambda: {"moves_per_s": 900.0})
    assert main(["bench", "--physics"]) == 0
    out = capsys.readouterr().out
    assert "[foundation]" in out and "[learning]" in out and "[physics]" in out
    assert "planning.rnh_ql_plus_planning10" in out and "700,000" in out
    assert main(["bench", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["learning"]["planning"] == {"rnh_ql_plus_planning10": 7e5}
    assert "physics" not in got
