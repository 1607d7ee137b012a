"""One door: the command and the library run the same thing for the same inputs, the
library's errors reach the command in flag words, and ``import rnhql`` is the face."""

from __future__ import annotations

import json

import gymnasium
import pytest

import rnhql
from scenarios.cli import main
from scenarios.cli.args import FLAG_OF, flag_words
from sim.errors import InputError

UNTIMED = ("wall_time_s", "wall_time_per_episode_s")


def test_an_explicit_fidelity_exact_wins_over_the_scenarios_own_in_cli_and_api(tmp_path,
                                                                               capsys):
    """The divergence the issue found: a scenario whose [physics] table says noisy, trained
    with --fidelity exact, ran at noisy from the command and at exact from Python."""
    path = tmp_path / "noisy.toml"
    path.write_text('name = "t"\nstart = [1, 1]\ngoal = [8, 8]\n[arena]\nwidth_m = 10.0\n'
                    'height_m = 10.0\n[physics]\nfidelity = "noisy"\n')
    assert main(["train", str(path), "--method", "st-ql", "--world", "physics", "--fidelity",
                 "exact", "--episodes", "3", "--json", str(tmp_path / "cli.json")]) == 0
    assert "physics fidelity      exact" in capsys.readouterr().out
    cli = json.loads((tmp_path / "cli.json").read_text())
    lib = dict(rnhql.train(str(path), "st-ql", world="physics", fidelity="exact",
                           episodes=3).record)
    assert cli["fidelity"] == lib["fidelity"] == "exact"
    assert [k for k in cli if k not in UNTIMED and cli[k] != lib[k]] == []
    # without the flag both take the scenario's own
    assert rnhql.train(str(path), "st-ql", world="physics", episodes=1).fidelity == "noisy"


def test_library_errors_read_in_flag_words():
    err = InputError("scenarios.api.compare", "pretrain", "has episodes 'x'",
                     "pass e.g. pretrain=('grid', 300)")
    said = flag_words(err)
    assert str(said) == ("command line: --pretrain: has episodes 'x'. Fix: pass e.g. "
                         "--pretrain grid:300")
    said = flag_words(InputError("scenarios.api.train", "settings['eps']", "is 'a'",
                                 "pass e.g. settings={'eps': 0.2}"))
    assert said.field == "--set['eps']"
    other = InputError("maze.toml", "goal", "is in a wall", "move it")
    assert flag_words(other) is other  # a file's error names the file, not a flag
    assert set(FLAG_OF.values()) <= {"scenario"} | {v for v in FLAG_OF.values()
                                                     if v.startswith("--")}


def test_the_command_says_a_bad_pretrain_in_its_flags(capsys, tmp_path):
    assert main(["compare", "paper-40", "--methods", "haql", "--world", "physics",
                 "--pretrain", "grid:0", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rnhql: error: command line: --pretrain: has 0 episodes, not a whole "
                          "number in 1..")
    assert err.endswith("Fix: pass e.g. --pretrain grid:300")
    assert "scenarios.api" not in err and "pretrain=" not in err


def test_import_rnhql_is_the_face():
    assert rnhql.train is rnhql.compare.__globals__["train"]  # the library's own calls
    assert set(rnhql.RUNGS) >= {"exact", "noisy", "slip", "localised"}
    assert all(i in gymnasium.registry for i in rnhql.ENV_IDS)
    world = rnhql.Scenario(name="face-10", width_m=10.0, height_m=10.0, start=(1, 1),
                           goal=(8, 8), obstacles=(rnhql.Circle(5.0, 5.0, 1.0),))
    cmp = rnhql.compare(world, ["rnh-ql+"], seeds=2, episodes=30, jobs=1)
    assert isinstance(cmp, rnhql.Comparison) and "best: rnh-ql+" in cmp.summary()
    with pytest.raises(rnhql.InputError, match="episodes"):
        rnhql.train(world, episodes=0)
