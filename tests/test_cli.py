from __future__ import annotations

import pytest

from scenarios.cli import main
from tests.conftest import MAPS


def test_scenarios_lists_builtins_with_optimal_lengths(capsys):
    assert main(["scenarios"]) == 0
    out = capsys.readouterr().out
    for name in ("paper-40", "paper-50", "zigzag-50", "arena"):
        assert name in out
    line = next(line for line in out.splitlines() if line.startswith("paper-50"))
    assert "2500" not in line and " 80 " in line


def test_check_a_good_map(capsys):
    assert main(["scenarios", "--check", str(MAPS / "arena.map"), "--start", "3,43",
                 "--goal", "45,5"]) == 0
    assert "OK" in capsys.readouterr().out


@pytest.mark.parametrize(("argv", "words"), [
    (["scenarios", "--check", "missing.toml"], "does not exist"),
    (["scenarios", "--check", str(MAPS / "arena.map")], "needs a start and a goal"),
    (["scenarios", "--check", str(MAPS / "arena.map"), "--start", "3;43", "--goal", "1,1"],
     "expected X,Y"),
    (["scenarios", "--check", str(MAPS / "arena.map"), "--start", "0,0", "--goal", "45,5"],
     "blocked"),
])
def test_bad_input_prints_one_line_and_exits_2(capsys, argv, words):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
