"""The ladder study on tiny budgets: every rung, both places of training, transfer."""

from __future__ import annotations

import json

from scenarios.cli import main
from scenarios.studies.ladder import continuous_vs_grid


def test_ladder_study_writes_table_figure_and_one_comparison_per_rung(tmp_path, capsys):
    out = tmp_path / "cvg"
    assert continuous_vs_grid.main(["--maps", "paper-40", "--rungs", "exact,noisy",
                                    "--methods", "st-ql", "--seeds", "2", "--episodes", "4",
                                    "--repeats", "1", "--jobs", "1", "--out", str(out)]) == 0
    text = (out / "ladder.md").read_text()
    for rung in ("exact", "noisy"):
        assert f"| paper-40 | {rung} |" in text
        assert "| st-ql | grid | " in text and f"| st-ql | {rung} | " in text
        data = json.loads((out / "paper-40" / rung / "results.json").read_text())
        assert {r["world"] for r in data["runs"]} == {"grid", "physics"}
        for run in data["runs"]:  # both places of training drive at the rung
            assert (run["fidelity"] or "exact") == rung
            assert {"physics_route_metres", "physics_route_contacts"} <= set(run)
        assert (out / "paper-40" / rung / "overlay.png").stat().st_size > 5000
    assert (out / "ladder.png").stat().st_size > 10000
    rows = continuous_vs_grid.ladder_rows(
        [dict(map="paper-40", rung=r, aliasing={"multi_outcome_fraction": 0.0},
              results=json.loads((out / "paper-40" / r / "results.json").read_text()))
         for r in ("exact", "noisy")])
    assert {(r["rung"], r["trained"]) for r in rows} == {
        ("exact", "grid"), ("exact", "exact"), ("noisy", "grid"), ("noisy", "noisy")}


def test_compare_cli_with_both_worlds(tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", "paper-40", "--methods", "rnh-ql", "--seeds", "1", "--episodes",
                 "3", "--world", "grid,physics", "--jobs", "1", "--out", str(out)]) == 0
    data = json.loads((out / "results.json").read_text())
    assert sorted(r["world"] for r in data["runs"]) == ["grid", "physics"]
    assert set(data["summary"]["rnh-ql"]) == {"grid", "physics"}
