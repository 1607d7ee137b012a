"""A shared output folder cannot turn a sweep into a writer of someone else's files: links
planted under the names the tool gives its own files (the lock and its helper, results,
summary, the resume file, figures, the recording's parts) are replaced, never followed."""

from __future__ import annotations

import itertools
import os

from scenarios import api
from scenarios.sweep.outdir import LOCK_NAME


def test_links_planted_in_an_output_folder_are_not_followed(tmp_path):
    out = tmp_path / "shared"
    out.mkdir()
    victims = tmp_path / "victims"
    victims.mkdir()
    names = [f"{LOCK_NAME}.{os.getpid()}", LOCK_NAME, "results.json", "summary.md",
             "runs.partial.jsonl", "steps_per_episode.png", "greedy_test.png"]
    for name in names:
        (victims / name).write_text("precious\n")
        (out / name).symlink_to(victims / name)
    victim_dir = tmp_path / "victim-dir"
    victim_dir.mkdir()
    record = tmp_path / "rec.rrd"
    (tmp_path / "rec.rrd.parts").symlink_to(victim_dir)
    cmp = api.compare("paper-40", ["st-ql"], seeds=1, episodes=10, jobs=1, out=out,
                      record=record)
    for name in names:
        assert (victims / name).read_text() == "precious\n", name
    assert list(victim_dir.iterdir()) == []
    assert (out / "results.json").is_file() and not (out / "results.json").is_symlink()
    assert cmp.runs and record.stat().st_size > 0


def test_a_link_the_user_named_is_still_written_through(tmp_path):
    """--json FILE, --save, --record: a path the user named may be their own link."""
    from sim.files import atomic_write_text

    target = tmp_path / "real.json"
    link = tmp_path / "mine.json"
    link.symlink_to(target)
    atomic_write_text(link, "{}")
    assert link.is_symlink() and target.read_text() == "{}"


def test_report_refresh_runs_only_commands_it_builds_from_study_entry_points():
    """An artifact is data: report --refresh builds its argv from a closed list of study
    entry points, with this interpreter and no shell, and refuses anything else."""
    import sys

    import pytest

    from scenarios.artifacts import artifact_names, load_artifact
    from scenarios.cli.report import argv_of

    for name in artifact_names():  # every committed artifact still refreshes
        argv = argv_of(load_artifact(name)["command"])
        assert argv[0] == sys.executable and argv[1] == "-m"
    assert argv_of("rnhql optimum paper-50 --fidelity noisy --artifact x")[:4] == \
        [sys.executable, "-m", "scenarios.cli", "optimum"]
    for hostile in ["sh -c 'id > PWNED'", "python -m os", "python -c 'import os'",
                    "rnhql view --version", "python -m scenarios.studies.nope",
                    "python -m scenarios.studies.maps.ablation --out /etc",
                    "python -m scenarios.studies.maps.ablation --out ../../x",
                    "python -m scenarios.studies.maps.ablation --out $(id)",
                    "/usr/bin/python -m scenarios.studies.maps.ablation", ""]:
        with pytest.raises(ValueError, match="re-run the study by hand"):
            argv_of(hostile)


def test_a_recording_named_like_a_flag_reaches_the_viewer_as_a_path(tmp_path, monkeypatch):
    from scenarios.cli import view

    monkeypatch.chdir(tmp_path)
    (tmp_path / "--version").write_bytes(b"RRF2")
    seen = []

    class Done:
        def wait(self):
            return 0

    monkeypatch.setattr(view, "spawn", lambda argv: seen.append(argv) or Done())
    monkeypatch.setattr(view, "stop_group", lambda proc: None)
    monkeypatch.setattr(view, "_check_display", lambda path: None)
    from scenarios.cli import main

    assert main(["view", "--", "--version"]) == 0
    assert seen == [[str(tmp_path / "--version")]]


def _contend(out: str, barrier, log: str, rounds: int, planter: bool) -> None:
    """One of many processes: each round a stale lock is planted (a dead pid's), then all
    try the lock at once; each logs how long it held it."""
    import time
    from pathlib import Path

    from scenarios.sweep.outdir import OutDirError, sweep_lock

    for _ in range(rounds):
        if planter:
            (Path(out) / LOCK_NAME).write_text("4194304\n")  # a pid no process has
        barrier.wait()
        try:
            with sweep_lock(Path(out)):
                t0 = time.monotonic()
                time.sleep(0.02)
                t1 = time.monotonic()
            with open(log, "a") as f:
                f.write(f"{t0} {t1}\n")
        except OutDirError:
            pass
        barrier.wait()


def test_no_two_processes_ever_hold_the_sweep_lock(tmp_path):
    """Eight processes released together, fifty times, onto a folder whose lock a dead
    process left each time: never two holders at once (the old read-then-remove takeover
    let two in)."""
    import multiprocessing

    out = tmp_path / "out"
    out.mkdir()
    (out / LOCK_NAME).write_text("4194304\n")  # a pid no process has: stale
    ctx = multiprocessing.get_context("fork")
    n, rounds = 8, 50
    barrier = ctx.Barrier(n)
    logs = [str(tmp_path / f"log{k}") for k in range(n)]
    procs = [ctx.Process(target=_contend, args=(str(out), barrier, logs[k], rounds, k == 0))
             for k in range(n)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(timeout=120)
        assert p.exitcode == 0
    from pathlib import Path

    spans = sorted(tuple(map(float, line.split())) for log in logs if os.path.exists(log)
                   for line in Path(log).read_text().splitlines())
    assert len(spans) >= rounds  # somebody held it every round
    for (_, end), (start, _) in itertools.pairwise(spans):
        assert start >= end  # the next holder began after the last one ended


def test_damaged_runs_in_a_resumed_comparison_are_one_line(tmp_path, capsys):
    """A run edited to hold a string where a number goes, or only its key, is refused in one
    line naming the file and the run (both once ended in a traceback in the summary)."""
    import json

    from scenarios.cli import main

    out = tmp_path / "c"
    argv = ["compare", "paper-40", "--methods", "st-ql", "--seeds", "2", "--episodes", "5",
            "--jobs", "1", "--out", str(out)]
    assert main(argv) == 0
    good = json.loads((out / "results.json").read_text())
    for damage, says in ((lambda r: r.update(success_rate="x"), "field 'success_rate' is 'x'"),
                         (lambda r: [r.pop(k) for k in list(r) if k != "key"],
                          "has no field 'method'")):
        doc = json.loads(json.dumps(good))
        damage(doc["runs"][0])
        (out / "results.json").write_text(json.dumps(doc))
        capsys.readouterr()
        assert main([*argv, "--resume"]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "results.json: runs[0]: " + says in err


def test_running_out_of_memory_is_one_line_and_exit_1(monkeypatch, capsys):
    from scenarios.cli import main, train

    def starve(args):
        raise MemoryError

    monkeypatch.setattr(train, "cmd_train", starve)
    from scenarios.cli import app

    monkeypatch.setattr(app.train, "cmd_train", starve)
    assert main(["train", "paper-40", "--episodes", "1"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "out of memory" in err


def test_a_tampered_checkpoint_is_refused(tmp_path, capsys):
    """An infinite tally sum, or a file whose record of what it was trained on was removed
    (so it would load on any scenario of its size), is refused in one line."""
    import numpy as np

    from scenarios.cli import main

    agent = tmp_path / "a.npz"
    assert main(["train", "paper-40", "--method", "st-ql", "--episodes", "5",
                 "--save", str(agent)]) == 0
    with np.load(agent, allow_pickle=False) as data:
        fields = {k: data[k] for k in data.files}
    assert "state_tally.f_sum" in fields and "problem" in fields
    for name, change, says in (
            ("inf.npz", {"state_tally.f_sum": np.array([np.inf])},
             "field 'state_tally.f_sum' holds infinite values"),
            ("bare.npz", {"problem": None}, "field 'problem' is missing")):
        tampered = {k: v for k, v in {**fields, **change}.items() if v is not None}
        np.savez(tmp_path / name, **tampered)
        capsys.readouterr()
        assert main(["route", "paper-40", "--agent", str(tmp_path / name)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and says in err, err
