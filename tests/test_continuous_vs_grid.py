"""Both worlds, same methods and seeds, tiny budgets."""

from __future__ import annotations

import json

from scenarios.cli import main
from scenarios.experiments import continuous_vs_grid


def test_continuous_vs_grid_writes_table_and_overlay(tmp_path, capsys):
    out = tmp_path / "cvg"
    assert continuous_vs_grid.main(["paper-40", "--methods", "st-ql", "--seeds", "1",
                                    "--episodes", "4", "--jobs", "1", "--out", str(out)]) == 0
    text = (out / "continuous_vs_grid.md").read_text()
    assert "| st-ql | grid | 1 |" in text and "| st-ql | physics | 1 |" in text
    assert (out / "overlay.png").stat().st_size > 5000
    data = json.loads((out / "results.json").read_text())
    assert data["world"] == "grid,physics"
    physics = next(r for r in data["runs"] if r["world"] == "physics")
    grid = next(r for r in data["runs"] if r["world"] == "grid")
    assert len(physics["contacts_per_episode"]) == 4
    # both worlds drive their final greedy policy in physics
    for run in (grid, physics):
        assert {"physics_route_metres", "physics_route_contacts", "physics_route_xy"} <= set(run)


def test_compare_cli_with_both_worlds(tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", "paper-40", "--methods", "rnh-ql", "--seeds", "1", "--episodes",
                 "3", "--world", "grid,physics", "--jobs", "1", "--out", str(out)]) == 0
    data = json.loads((out / "results.json").read_text())
    assert sorted(r["world"] for r in data["runs"]) == ["grid", "physics"]
    assert set(data["summary"]["rnh-ql"]) == {"grid", "physics"}
