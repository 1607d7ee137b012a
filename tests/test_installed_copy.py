"""What needs the source tree says so in one line where it is missing (an installed copy,
``pip install .``, has no docs/results or tests/data): ``rnhql report`` and the
``--artifact`` options, before any work."""

from __future__ import annotations

import pytest

from scenarios import artifacts


@pytest.fixture
def installed_copy(tmp_path, monkeypatch):
    monkeypatch.setattr(artifacts, "GOLDEN", tmp_path / "tests" / "data" / "golden_sweep.json")
    monkeypatch.setattr(artifacts, "RESULTS_DIR", tmp_path / "docs" / "results")


@pytest.mark.parametrize("argv", [
    ["report"],
    ["report", "--dry-run"],
    ["optimum", "paper-40", "--artifact", "x"],
    ["aliasing", "paper-40", "--out", "OUT", "--artifact", "x"],
])
def test_artifact_commands_refuse_in_one_line_without_the_source_tree(installed_copy, argv,
                                                                       capsys, tmp_path):
    from scenarios.cli import main

    argv = [str(tmp_path / "out") if a == "OUT" else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "needs the project's source tree" in err
    assert "run it from a clone of the repository" in err
    assert not (tmp_path / "out").exists()  # refused before any work


def test_a_study_refuses_its_artifact_without_the_source_tree(installed_copy, capsys):
    import argparse

    with pytest.raises(SystemExit) as stop:
        artifacts.check_artifact_name(argparse.ArgumentParser(prog="study"), "seed7")
    assert stop.value.code == 2
    assert "needs the project's source tree" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["../../x", "a/b", "UPPER", ""])
def test_an_artifact_name_never_escapes_docs_results(name):
    from sim.errors import InputError

    with pytest.raises(InputError, match="is not a name"):
        artifacts.check_artifact_target(name)


def test_a_users_sim_py_is_named_not_mysterious(tmp_path):
    """A sim.py beside the user's script hides rnhql's sim package: the import of the library
    says so in one line, naming the file and the fix."""
    import os
    import subprocess
    import sys

    from tests.conftest import REPO

    (tmp_path / "sim.py").write_text("x = 1\n")
    (tmp_path / "script.py").write_text("from scenarios import api\n")
    proc = subprocess.run([sys.executable, "script.py"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(REPO)})
    assert proc.returncode == 1
    assert f"{tmp_path / 'sim.py'} hides rnhql's 'sim' package" in proc.stderr
    assert "rename that file" in proc.stderr
