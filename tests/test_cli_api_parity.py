"""One door: every subcommand that runs something is a shell over one library call, so the
same inputs give the same figures from ``rnhql X`` and from ``rnhql.X`` (``compare``:
tests/test_api.py::test_api_and_cli_write_the_same_results; ``--fidelity exact`` against a
scenario's own rung: tests/test_one_door.py)."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest

import rnhql
from scenarios.cli import main
from tests.test_api import same_runs


def test_train(tmp_path, capsys):
    out = tmp_path / "run.json"
    assert main(["train", "paper-40", "--method", "q-opt", "--episodes", "20", "--seed", "3",
                 "--set", "eps=0.2", "--json", str(out)]) == 0
    run = rnhql.train("paper-40", "q-opt", episodes=20, seed=3, settings={"eps": 0.2})
    assert same_runs(json.loads(out.read_text()), dict(run.record)) == []
    assert "q-opt" in capsys.readouterr().out.lower()


def test_optimum(capsys):
    opt = rnhql.optimum("paper-40", fidelity="exact", rollouts=3)
    assert main(["optimum", "paper-40", "--fidelity", "exact", "--rollouts", "3"]) == 0
    out = capsys.readouterr().out
    assert f"V*(S)       {opt.expected_primitives:.2f} expected primitives" in out
    assert f"{opt.model.states:,} states" in out and f"{opt.model.sweeps} sweeps" in out
    assert f"P(G) {opt.driven.p_goal:.4f}" in out
    assert f"exact       {opt.physics_route_length} primitives" in out


def test_route_in_both_worlds(tmp_path, capsys):
    agent = tmp_path / "a.npz"
    rnhql.train("paper-40", "q-opt", episodes=200, seed=0, save=agent)
    for world in ("grid", "physics"):
        r = rnhql.route(agent, "paper-40", world=world, with_optimum=False)
        assert main(["route", "paper-40", "--agent", str(agent), "--world", world]) == 0
        out = capsys.readouterr().out
        shown = "G not reached" if r.length < 0 else f"{r.length} moves"
        assert f"greedy route: {shown}" in out, world
        assert f"BFS optimum: {len(r.optimal_cells) - 1} moves" in out
        if world == "physics":
            assert f"P(G) {r.p_goal:.2f}" in out and r.grade.drives == 1  # exact: one drive


def test_aliasing(tmp_path):
    got = rnhql.aliasing("paper-40", fidelity="noisy", repeats=2, seed=4)
    assert main(["aliasing", "paper-40", "--fidelity", "noisy", "--repeats", "2", "--seed",
                 "4", "--out", str(tmp_path)]) == 0
    cli = json.loads((tmp_path / "aliasing.json").read_text())
    lib = {k: v for k, v in got.record.items() if k != "seconds"}
    assert {k: v for k, v in cli.items() if k != "seconds"} == json.loads(json.dumps(lib))
    assert got.multi_outcome_fraction == cli["multi_outcome_fraction"] > 0
    assert np.nanmax(got.heat_map) > 0


@pytest.mark.skipif(importlib.util.find_spec("irsim") is None,
                    reason="IR-SIM is the crosscheck extra")
def test_crosscheck(tmp_path):
    got = rnhql.crosscheck("paper-40", pairs=6, drives=1, policies={"grid optimal": "optimal"})
    assert main(["crosscheck", "paper-40", "--pairs", "6", "--drives", "1", "--policy",
                 "optimal", "--json", str(tmp_path / "c.json")]) == 0
    cli = json.loads((tmp_path / "c.json").read_text())
    lib = got.as_dict()
    for d in (cli, lib):
        d.pop("seconds")
    assert cli == json.loads(json.dumps(lib))
    assert set(got.strata) >= {"grid-blocked", "free-near-obstacle", "free-open", "all"}
