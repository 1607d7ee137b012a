"""``rnhql report``: stale artifacts listed, a refresh that runs their commands."""

from __future__ import annotations

import sys

import pytest

from scenarios.artifacts import (
    artifact_names,
    behaviour_digests,
    legacy_tables,
    load_artifact,
    stale_parts,
)
from scenarios.cli import report
from scenarios.cli.app import main


def test_report_lists_every_artifact_and_every_table_typed_by_hand(capsys):
    assert main(["report"]) == 0
    out = capsys.readouterr().out
    for name in artifact_names():
        assert name in out
    for page, command in legacy_tables():
        assert f"{page}: {command}" in out


def test_a_dry_refresh_names_the_stale_commands_and_runs_nothing(capsys, monkeypatch):
    """Every artifact made stale (a behaviour digest changed): the refresh plans each
    command, and with --dry-run starts none of them."""
    changed = {k: "changed" for k in behaviour_digests()}
    monkeypatch.setattr(report, "behaviour_digests", lambda: changed)
    ran = []
    monkeypatch.setattr(report.subprocess, "call", lambda *a, **k: ran.append(a) or 0)
    assert main(["report", "--refresh", "--dry-run"]) == 0
    out = capsys.readouterr().out
    # not the timings that depend on no method's behaviour (the tour), unless already stale
    names = [n for n in artifact_names() if load_artifact(n)["behaviour"]
             or stale_parts(load_artifact(n))]
    assert f"refresh: {len(names)} stale artifact(s)" in out
    stale_lines = [ln for ln in out.splitlines()
                   if ln.split(" | ")[0] in names and "STALE" in ln]
    assert len(stale_lines) == len(names)
    assert ran == []


def test_report_lists_every_docs_figure_with_its_artifacts(capsys):
    from scenarios.artifacts.figures import FIGURES

    assert main(["report"]) == 0
    out = capsys.readouterr().out
    for fig in FIGURES:
        assert f"{fig.path} | {', '.join(fig.artifacts)} |" in out


@pytest.mark.parametrize("command, head", [
    ("rnhql optimum paper-50 --fidelity noisy", [sys.executable, "-m", "scenarios.cli",
                                                  "optimum"]),
    ("python -m scenarios.bench.memory --artifact x", [sys.executable, "-m",
                                                        "scenarios.bench.memory"]),
])
def test_an_artifacts_command_runs_with_this_interpreter(command, head):
    assert report.argv_of(command)[:len(head)] == head


def test_a_damaged_artifact_is_one_row_and_exit_1_never_a_traceback(tmp_path, monkeypatch,
                                                                   capsys):
    """Bad JSON, a missing format or behaviour, a folder named *.json, wall_s a string."""
    import json as _json

    from scenarios.artifacts import RESULTS_DIR, ArtifactError, load_artifact
    from scenarios.cli import main as cli_main
    from scenarios.cli import report

    good = _json.loads((RESULTS_DIR / "oracle.paper-50.json").read_text())
    (tmp_path / "bad-json.x.json").write_text("{bad")
    (tmp_path / "folder.x.json").mkdir()
    for name, damage in (("no-format.x", lambda d: d.pop("format")),
                         ("no-behaviour.x", lambda d: d.pop("behaviour")),
                         ("wall-text.x", lambda d: d.update(wall_s="x"))):
        doc = _json.loads(_json.dumps(good))
        damage(doc)
        (tmp_path / f"{name}.json").write_text(_json.dumps(doc))
    names = ["bad-json.x", "folder.x", "no-format.x", "no-behaviour.x", "wall-text.x"]
    for name in names:
        with pytest.raises(ArtifactError, match=name):
            load_artifact(name, tmp_path)
    monkeypatch.setattr(report, "artifact_names", lambda: names)
    monkeypatch.setattr(report, "load_artifact", lambda n: load_artifact(n, tmp_path))
    assert cli_main(["report"]) == 1
    out = capsys.readouterr()
    assert out.out.count("DAMAGED") == 5 and "Traceback" not in out.err
