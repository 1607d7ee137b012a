"""A hard link planted in a shared output folder under a name the tool writes (the sweep's
lock, ``runs.partial.jsonl``, a recording's ``.part``) is never written through: the file
it links to keeps its bytes (issue 66)."""

from __future__ import annotations

import os

from scenarios import api
from sim.files import open_own_file

SECRET = b"someone else's file\n"


def _victim(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_bytes(SECRET)
    return victim


def test_the_opener_never_writes_through_a_hard_link(tmp_path):
    victim = _victim(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    os.link(victim, out / "runs.partial.jsonl")
    fd = open_own_file(out / "runs.partial.jsonl", os.O_WRONLY | os.O_APPEND | os.O_CREAT)
    os.write(fd, b"a record\n")
    os.close(fd)
    assert victim.read_bytes() == SECRET
    assert (out / "runs.partial.jsonl").read_bytes() == b"a record\n"


def test_a_sweep_lock_planted_as_a_hard_link_is_not_written_through(tmp_path):
    victim = _victim(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    os.link(victim, out / ".rnhql-sweep.lock")
    api.compare("paper-40", ["st-ql"], seeds=1, episodes=2, jobs=1, out=out, figures=False)
    assert victim.read_bytes() == SECRET
    assert (out / "results.json").is_file()


def test_a_recording_part_planted_as_a_hard_link_is_not_written_through(tmp_path):
    from scenarios.recording.file import RecordingFile

    victim = _victim(tmp_path)
    os.link(victim, tmp_path / "run.rrd.part")
    rec = RecordingFile(tmp_path / "run.rrd")
    rec.close()
    assert victim.read_bytes() == SECRET
    assert (tmp_path / "run.rrd").stat().st_size > 0
