"""--record on the commands: recordings verify, and recording never changes a run."""

from __future__ import annotations

import json
from pathlib import Path

from scenarios.cli import main
from scenarios.recording.recorder import verify_recording
from scenarios.runs.run import run_one
from scenarios.runs.spec import RecordOptions, RunSpec


def test_recorded_run_equals_unrecorded_run(tmp_path):
    plain = run_one(RunSpec("paper-40", "rnh-ql", 2, 40))
    recorded = run_one(RunSpec("paper-40", "rnh-ql", 2, 40,
                               recording=RecordOptions(str(tmp_path / "r.rrd"), every=3)))
    for rec in (plain, recorded):
        rec.pop("wall_time_s")
        rec.pop("wall_time_per_episode_s")
    assert plain == recorded
    ok, msg = verify_recording(tmp_path / "r.rrd")
    assert ok, msg


def test_train_route_compare_record(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["train", "paper-40", "--method", "rnh-ql", "--episodes", "20", "--save", "a.npz",
                 "--record"]) == 0
    assert main(["route", "paper-40", "--agent", "a.npz", "--record", "route.rrd"]) == 0
    assert main(["compare", "paper-40", "--methods", "st-ql,rnh-ql", "--seeds", "1",
                 "--episodes", "20", "--jobs", "1", "--out", "cmp", "--record", "cmp.rrd"]) == 0
    for path in ("recordings/paper-40-rnh-ql-grid-s0.rrd", "route.rrd", "cmp.rrd"):
        ok, msg = verify_recording(tmp_path / path)
        assert ok, (path, msg)
    assert not (tmp_path / "cmp.rrd.parts").exists()
    assert json.loads((tmp_path / "cmp" / "results.json").read_text())["episodes"] == 20


def test_physics_train_record(tmp_path, capsys):
    out = tmp_path / "p.rrd"
    assert main(["train", "paper-40", "--world", "physics", "--episodes", "3", "--record",
                 str(out), "--record-every", "2"]) == 0
    ok, msg = verify_recording(out)
    assert ok, msg


def test_bad_record_path_exits_2(capsys):
    assert main(["train", "paper-40", "--episodes", "2", "--record", "x.txt"]) == 2
    assert "does not end in .rrd" in capsys.readouterr().err


def test_comparison_records_first_seeds_in_full_and_the_rest_as_curves(tmp_path):
    from scenarios.sweep.run import (
        SweepRecording,
        gather_parts,
        make_specs,
        with_recording,
    )

    specs = make_specs("paper-40", ["st-ql", "rnh-ql"], [0, 1, 2], 5, ["grid"])
    rec = with_recording(specs, SweepRecording(str(tmp_path / "c.rrd"), every=10,
                                               detail_seeds=2))
    assert {(s.seed, s.recording.detail) for s in rec} == {(0, True), (1, True), (2, False)}
    assert len({s.recording.recording_id for s in rec}) == 1
    assert {s.recording.prefix for s in rec if s.method == "st-ql"} == {
        "runs/st-ql/s0", "runs/st-ql/s1", "runs/st-ql/s2"}
    assert [s.key for s in rec] == [s.key for s in specs]  # recording is not part of a run
    out = run_one(rec[2])  # a curves-only run writes no part: its record carries its curves
    assert out["seed"] == 2 and not Path(rec[2].recording.path).exists()
    full = next(r for r in rec if r.method == "st-ql" and r.seed == 0)
    records = [run_one(full), out]
    merged = gather_parts([full, rec[2]], str(tmp_path / "c.rrd"), records=records)
    ok, msg = verify_recording(merged)
    assert ok, msg
    from tests.test_recording import read_table

    table = read_table(merged, ["/runs/st-ql/s2/metrics/steps/**"], "episode")
    assert table.num_rows > 0  # the curves-only run's curves, logged from its record
