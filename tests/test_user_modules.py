"""A learner module of the user's own that misbehaves as it imports: one line naming the
module (its file and line), exit 2; never a traceback, never a silent exit 0."""

from __future__ import annotations

import pytest

from scenarios.cli import main

MODULES = {
    "synerr_mod": ("def f(:\n", "synerr_mod.py:1: invalid syntax"),
    "raiser_mod": ("raise RuntimeError('boom')\n", "raised RuntimeError: boom at"),
    "exits_mod": ("import sys\nsys.exit(0)\n", "called sys.exit(0)"),
}


@pytest.mark.parametrize("name", sorted(MODULES))
def test_a_module_that_fails_to_import_is_one_line(name, tmp_path, monkeypatch, capsys):
    source, says = MODULES[name]
    (tmp_path / f"{name}.py").write_text(source)
    monkeypatch.syspath_prepend(str(tmp_path))
    assert main(["train", "paper-40", "--method", f"{name}:X", "--episodes", "2"]) == 2
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err and err.count("\n") == 1, err


@pytest.mark.parametrize("where", ["..mod:X", ".mod:X", "/tmp/x.py:X", "dir/mod:X"])
def test_a_relative_name_or_a_path_is_refused_with_the_fix(where, capsys):
    assert main(["train", "paper-40", "--method", where, "--episodes", "2"]) == 2
    err = capsys.readouterr().err
    assert "is not a module name" in err and "PYTHONPATH" in err and "Traceback" not in err


LEARNERS = '''
import sys


class Base:
    name = "base"

    def __init__(self, n_states, n_actions, rng):
        pass

    def update(self, s, a, r, s2, terminated):
        pass

    def greedy(self, s):
        return 0


class Four(Base):
    def act(self, s):
        return 4


class Exits(Base):
    def act(self, s):
        sys.exit(3)


class Raises(Base):
    def act(self, s):
        raise ValueError("bad state")
'''


@pytest.mark.parametrize(("cls", "says"), [
    ("Four", "returned 4, not an action in 0..3"),
    ("Exits", "Exits called sys.exit(3) at"),
    ("Raises", "Raises raised ValueError: bad state at"),
])
@pytest.mark.parametrize("world", ["grid", "physics"])
def test_a_learner_that_fails_mid_run_fails_the_run_in_one_line(cls, says, world, tmp_path,
                                                                 monkeypatch, capsys):
    """Not a traceback, not a silent exit with the learner's code: the run failed, exit 1."""
    (tmp_path / "bad_learners.py").write_text(LEARNERS)
    monkeypatch.syspath_prepend(str(tmp_path))
    assert main(["train", "paper-40", "--method", f"bad_learners:{cls}", "--episodes", "2",
                 "--world", world]) == 1
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err and "the run failed" in err, err
