"""``--resume`` keeps a finished run only when the record says what its key says: a
``results.json`` whose ``method`` was edited is refused, not shown under a fake name."""

from __future__ import annotations

import json

import pytest

from scenarios.cli.app import main

ARGS = ["compare", "paper-40", "--methods", "st-ql", "--seeds", "2", "--episodes", "10"]


@pytest.mark.parametrize("field, value", [("method", "my-fake-method"), ("seed", 7),
                                          ("world", "physics")])
def test_an_edited_run_is_refused_on_resume(tmp_path, capsys, field, value):
    out = tmp_path / "o"
    assert main([*ARGS, "--out", str(out)]) == 0
    results = out / "results.json"
    doc = json.loads(results.read_text())
    doc["runs"][0][field] = value
    results.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main([*ARGS, "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"with {field} {value!r}" in err and "edited" in err
    assert json.loads(results.read_text()) == doc  # nothing rewritten


def test_an_unedited_finished_sweep_resumes_with_nothing_to_run(tmp_path, capsys):
    out = tmp_path / "o"
    assert main([*ARGS, "--out", str(out)]) == 0
    capsys.readouterr()
    assert main([*ARGS, "--out", str(out), "--resume"]) == 0
    assert "2 of 2 runs already finished" in capsys.readouterr().err
