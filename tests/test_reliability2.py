"""Ten classes of hostile input: each ends as a valid run or one clear line, and
nothing the user had is lost or replaced.

1 outputs at devices, FIFOs and /dev/stdout-style links are written through, never replaced;
2 a full disk in a sweep (see also test_full_disk.py); 3 empty paths and folders where a
file goes, refused before any work; 4 damaged resume state; 5 the physics-model cache;
6 limits on sizes that drive work or memory; 7 checkpoints; 8 SIGHUP; 9 unchecked values;
10 the compile notice. Most run the CLI's ``main`` in-process with tiny budgets.
"""

from __future__ import annotations

import errno
import json
import os
import pickle
import signal
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from scenarios.cli import main

ROOT = os.geteuid() == 0
needs_root = pytest.mark.skipif(not ROOT, reason="mknod needs root")
TRAIN = ["train", "paper-40", "--method", "st-ql", "--episodes", "5"]
REPO = Path(__file__).resolve().parent.parent


def one_line(capsys, *words: str) -> str:
    """The single stderr line of a refused command, checked to hold ``words``."""
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


class Hang(BaseException):
    """Raised by :func:`alarm`: a BaseException, so no handler of the code under test can
    turn it into a clean-looking error (a TimeoutError is an OSError)."""


@pytest.fixture
def alarm():
    """Fail (instead of hanging the suite) when the block takes more than 30 s."""
    def boom(*_):
        raise Hang("took more than 30 s: a hang")
    old = signal.signal(signal.SIGALRM, boom)
    signal.alarm(30)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, old)


@pytest.fixture(scope="module")
def agent(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("agent") / "a.npz"
    assert main(["train", "paper-50", "--method", "st-ql", "--episodes", "20", "--save",
                 str(path)]) == 0
    return path


# ------------------------------------------------------------------ 1: never replace a node
@needs_root
@pytest.mark.parametrize("flag", ["--json", "--save", "--record"])
def test_an_output_at_a_device_node_is_written_through_not_replaced(tmp_path, flag, capsys):
    node = tmp_path / ("null.rrd" if flag == "--record" else "null")
    os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    assert main([*TRAIN, flag, str(node)]) == 0, capsys.readouterr().err
    assert stat.S_ISCHR(os.lstat(node).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == [node.name]  # no temp left


@needs_root
def test_a_png_at_a_device_node_is_written_through(tmp_path, agent):
    node = tmp_path / "null.png"
    os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    assert main(["route", "paper-50", "--agent", str(agent), "--png", str(node)]) == 0
    assert stat.S_ISCHR(os.lstat(node).st_mode)


@needs_root
def test_a_dev_full_twin_reports_no_space_left(tmp_path, capsys):
    full = tmp_path / "full"
    os.mknod(full, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
    assert main([*TRAIN, "--json", str(full)]) == 1
    line = one_line(capsys, str(full))
    assert "no space left" in line.lower()
    assert stat.S_ISCHR(os.lstat(full).st_mode)


def test_a_stdout_link_writes_into_the_open_stdout(tmp_path, capfd):
    link = tmp_path / "stdout"
    link.symlink_to("/proc/self/fd/1")
    assert main([*TRAIN, "--json", str(link)]) == 0
    out = capfd.readouterr().out
    assert '"key": "paper-40#' in out and "success rate" in out  # both, in one stream
    assert link.is_symlink() and os.readlink(link) == "/proc/self/fd/1"


def test_a_symlink_to_a_file_keeps_the_link_and_replaces_its_target(tmp_path):
    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    assert main([*TRAIN, "--json", str(link)]) == 0
    assert link.is_symlink() and json.loads(target.read_text())["method"] == "st-ql"


def test_a_fifo_with_a_reader_gets_the_bytes_and_one_without_is_one_line(tmp_path, capsys,
                                                                         alarm):
    from sim.files import atomic_write_text

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    time.sleep(0.2)
    atomic_write_text(fifo, "through the pipe")
    reader.join(10)
    assert got == [b"through the pipe"] and stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert main([*TRAIN, "--json", str(fifo)]) == 2  # nobody reads it: refused, no hang
    one_line(capsys, str(fifo), "FIFO")


# ------------------------------------------------------------------ 2: full disk in a sweep
@pytest.fixture
def nearly_full(tmp_path):
    """A 2 MB tmpfs with 60 kB free (needs root and mount; skipped otherwise)."""
    mnt = tmp_path / "mnt"
    mnt.mkdir()
    if not ROOT or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs",
                                   str(mnt)], capture_output=True).returncode != 0:
        pytest.skip("cannot mount a small tmpfs here (needs root)")
    try:
        (mnt / "filler").write_bytes(b"\0" * (2048 - 60) * 1024)
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True)




@pytest.mark.parametrize("jobs", ["1", "2"])
@pytest.mark.parametrize("record", [False, True])
def test_a_full_disk_in_a_sweep_is_one_line_and_keeps_what_finished(nearly_full, tmp_path,
                                                                   jobs, record):
    out = nearly_full / "out"
    argv = ["compare", "paper-40", "--methods", "st-ql,q-lambda", "--seeds", "2",
            "--episodes", "300", "--jobs", jobs, "--out", str(out)]
    if record:
        argv += ["--record", str(nearly_full / "c.rrd")]
    got = subprocess.run([sys.executable, "-m", "scenarios.cli", *argv], cwd=tmp_path,
                         capture_output=True, text=True, timeout=120,
                         env={**os.environ, "PYTHONPATH": str(REPO)})
    assert got.returncode == 1, got.stderr
    errors = [ln for ln in got.stderr.splitlines() if ln.startswith("rnhql")]
    assert len(errors) == 1 and "no space left" in errors[0], got.stderr
    assert "BrokenProcessPool" not in got.stderr and "Traceback" not in got.stderr
    assert str(nearly_full) in errors[0]  # names the file that did not fit
    leftovers = [p.name for p in nearly_full.rglob("*") if p.name.endswith((".tmp", ".part"))]
    assert leftovers == []
    parts = nearly_full / "c.rrd.parts"
    assert not parts.exists() or ("--resume" in errors[0] and str(parts) in errors[0])
    finished = (out / "runs.partial.jsonl").read_text().count("\n")
    assert f"{finished} of 4 runs finished" in errors[0] or (
        finished == 0 and "no run had finished" in errors[0])


def test_a_recording_close_that_never_returns_is_abandoned_not_waited_for(tmp_path,
                                                                          monkeypatch):
    """Rerun's disconnect can wait forever once its writer died on a full disk (it hung a
    recorded sweep 1 run in 5): the close gives up after its limit, one OSError."""
    import rerun as rr

    from scenarios.recording import file as recording_file

    released = threading.Event()
    untied: list[bool] = []

    class StuckStream:
        def disconnect(self) -> None:
            released.wait()

    monkeypatch.setattr(rr, "unregister_shutdown", lambda: untied.append(True))
    monkeypatch.setattr(recording_file, "FLUSH_STEP_S", 0.1)
    began = time.monotonic()
    with pytest.raises(OSError, match="did not let go"):
        recording_file._disconnect(StuckStream(), tmp_path / "x.rrd.part", limit_s=0.3)
    assert time.monotonic() - began < 5 and untied == [True]
    released.set()


def test_a_dead_worker_on_a_full_disk_is_reported_as_the_full_disk(monkeypatch):
    from concurrent.futures.process import BrokenProcessPool

    import sim.files
    from scenarios.runs.spec import RecordOptions, RunSpec
    from scenarios.sweep.backends import disk_full_cause

    spec = RunSpec("paper-40", "st-ql", 0, 5, recording=RecordOptions("/x/c.rrd.parts/a.rrd"))
    monkeypatch.setattr(sim.files, "no_space_left", lambda _p: True)
    err = disk_full_cause(BrokenProcessPool("gone"), spec)
    assert err is not None and err.errno == errno.ENOSPC and err.filename.endswith("a.rrd")
    monkeypatch.setattr(sim.files, "no_space_left", lambda _p: False)
    assert disk_full_cause(BrokenProcessPool("gone"), spec) is None  # another cause: kept


def test_a_recording_error_survives_the_trip_from_a_worker():
    from scenarios.recording.file import RecordingWriteError

    err = RecordingWriteError(Path("/nowhere/c.rrd"), OSError(errno.EIO, "writer died"))
    back = pickle.loads(pickle.dumps(err))  # an unpicklable error broke the whole pool
    assert isinstance(back, OSError) and back.filename == "/nowhere/c.rrd"
    assert "writer died" in back.strerror


# ------------------------------------------------------------------ 3: empty paths, folders
@pytest.mark.parametrize("argv", [
    [*TRAIN, "--save", ""], [*TRAIN, "--json", ""], [*TRAIN, "--resume", ""],
    [*TRAIN, "--record", ""], ["route", "paper-40", "--agent", ""],
    ["compare", "paper-40", "--methods", "st-ql", "--seeds", "1", "--episodes", "5",
     "--out", ""],
    ["scenarios", "--check", ""],
])
def test_an_empty_path_is_an_error(argv, capsys):
    assert main(argv) == 2
    one_line(capsys, "empty path")


def test_save_at_a_folder_fails_before_training(tmp_path, capsys):
    assert main([*TRAIN, "--save", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert "success rate" not in captured.out  # refused before the run, not after it
    assert "is a directory" in captured.err and captured.err.count("\n") == 1


def test_png_at_a_folder_fails_before_routing(tmp_path, agent, capsys):
    folder = tmp_path / "d.png"
    folder.mkdir()
    assert main(["route", "paper-50", "--agent", str(agent), "--png", str(folder)]) == 2
    one_line(capsys, "is a directory")


# ------------------------------------------------------------------ 4: damaged resume state
SWEEP = ["compare", "paper-40", "--methods", "st-ql", "--seeds", "1", "--episodes", "5",
         "--jobs", "1"]


def _damage(out: Path, how: str) -> None:
    out.mkdir()
    partial = out / "runs.partial.jsonl"
    if how in ("[1, 2]", "{}", "null", "17"):
        partial.write_text(how + "\n")
    elif how == "not-utf8":
        partial.write_bytes(b'{"key": "\xff\xfe"}\n')
    elif how == "nan":
        partial.write_text('{"key": "k", "success_rate": NaN}\n')
    elif how == "huge-number":
        partial.write_text('{"key": "k", "success_rate": 1e999}\n')
    elif how == "partial-dir":
        partial.mkdir()
    elif how == "results-dir":
        (out / "results.json").mkdir()
    elif how == "results-junk":
        (out / "results.json").write_text('{"runs": 5}')
    elif how == "lock-dir":
        (out / ".rnhql-sweep.lock").mkdir()


@pytest.mark.parametrize("how", ["[1, 2]", "{}", "null", "17", "not-utf8", "nan",
                                 "huge-number", "partial-dir", "results-dir", "results-junk",
                                 "lock-dir"])
def test_damaged_resume_state_is_one_line_naming_the_file(tmp_path, capsys, how):
    out = tmp_path / "out"
    _damage(out, how)
    assert main([*SWEEP, "--out", str(out), "--resume"]) == 2
    line = one_line(capsys, str(out), "Fix:")
    assert any(n in line for n in ("runs.partial.jsonl", "results.json", ".rnhql-sweep.lock"))


@pytest.mark.parametrize("how", ["partial-dir", "results-dir", "lock-dir"])
def test_a_folder_under_a_sweep_files_name_is_refused_before_any_run(tmp_path, capsys, how):
    out = tmp_path / "out"
    _damage(out, how)
    assert main([*SWEEP, "--out", str(out)]) == 2
    captured = capsys.readouterr()
    assert "progress" not in captured.err and captured.err.count("rnhql: error") == 1


@pytest.mark.parametrize("junk", [b"-5", b"99999999999999999999", b"\xff\xfe", b"0"])
def test_a_junk_lock_is_stale_and_taken_over(tmp_path, junk):
    out = tmp_path / "out"
    out.mkdir()
    (out / ".rnhql-sweep.lock").write_bytes(junk)
    assert main([*SWEEP, "--out", str(out)]) == 0
    assert not (out / ".rnhql-sweep.lock").exists()


def test_a_torn_last_line_is_still_run_again_not_refused(tmp_path):
    from scenarios.sweep.resume_state import read_partial

    (tmp_path / "runs.partial.jsonl").write_text('{"key": "a"}\n{"key": "b", "x": [1, ')
    # a study's partial runs hold a few fields each (a comparison's are checked whole)
    assert list(read_partial(tmp_path, finished=lambda out: {})) == ["a"]


# ------------------------------------------------------------------ 5: the physics-model cache
@pytest.fixture
def tiny_physics(tmp_path, monkeypatch):
    """A 6 x 6 map scenario and an empty cache folder of its own."""
    from sim.physics.models import transition as pm
    from sim.scenario_io import scenario_from_map

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    monkeypatch.delenv("RNHQL_NO_DISK_CACHE", raising=False)
    m = tmp_path / "t.map"
    m.write_text("type octile\nheight 6\nwidth 6\nmap\n" + "......\n" * 2 + ".@@...\n"
                 + "......\n" * 3)
    sc = scenario_from_map(m, (0, 5), (5, 0))
    pm.physics_model.cache_clear()
    fresh = pm.physics_model(sc)
    path = pm.cache_dir() / f"{pm.digest(sc, pm.PhysicsConfig())}.npz"
    assert path.is_file()
    yield sc, fresh, path
    pm.physics_model.cache_clear()


def _rebuilt(sc, path: Path):
    from sim.physics.models import transition as pm

    pm.physics_model.cache_clear()
    return pm.physics_model(sc)


@pytest.mark.parametrize("damage", ["truncate", "junk", "folder", "wrong-digest",
                                    "one-move-route", "wrong-key"])
def test_a_damaged_or_tampered_cache_is_rebuilt_not_believed(tiny_physics, damage):
    from sim.physics.models.disk_cache import content_digest

    sc, fresh, path = tiny_physics
    raw = path.read_bytes()
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    if damage == "truncate":
        path.write_bytes(raw[: len(raw) // 2])
    elif damage == "junk":
        path.write_bytes(b"PK\x03\x04" + bytes(100))
    elif damage == "folder":
        path.unlink()
        path.mkdir()
    else:
        nxt = arrays["next_state"].copy()
        if damage == "wrong-digest":
            nxt[0, 0] = nxt[0, 1]
        elif damage == "one-move-route":  # every move lands on G, with a matching digest
            nxt[:] = fresh.goal
            arrays["sha256"] = np.array(content_digest({"next_state": nxt}))
        else:
            arrays["key"] = np.array("0" * 20)
        arrays["next_state"] = nxt
        with open(path, "wb") as f:
            np.savez(f, **arrays)
    again = _rebuilt(sc, path)
    assert np.array_equal(again.next_state, fresh.next_state)
    assert path.is_file()  # rewritten whole
    with np.load(path) as z:
        assert np.array_equal(z["next_state"], fresh.next_state)


def test_a_sound_cache_is_used_as_is(tiny_physics, monkeypatch):
    from sim.physics.models import transition as pm

    sc, fresh, path = tiny_physics
    monkeypatch.setattr(pm, "drive_transitions", lambda *a: pytest.fail("rebuilt a good cache"))
    assert np.array_equal(_rebuilt(sc, path).next_state, fresh.next_state)


# ------------------------------------------------------------------ 6: limits on sizes
def _toml(tmp_path: Path, text: str) -> str:
    path = tmp_path / "s.toml"
    path.write_text(text)
    return str(path)


BASE = (REPO / "sim/builtin/paper-40.toml").read_text()


@pytest.mark.parametrize(("argv", "words"), [
    (["train", "paper-40", "--method", "dyna-q", "--episodes", "3", "--set",
      "n_planning=1e12"], ("n_planning", "limit 10,000")),
    (["train", "paper-40", "--method", "rnh-ql", "--episodes", "3", "--set", "k=100000"],
     ("k = 100000", "limit 100")),
    (["train", "paper-40", "--method", "sarsa-rs", "--episodes", "3", "--set", "block=1e6"],
     ("block", "limit")),
])
def test_config_sizes_are_limited_and_the_limit_named(argv, words, capsys, alarm):
    assert main(argv) == 2
    one_line(capsys, *words)


def test_physics_steps_per_episode_are_limited(tmp_path, capsys, alarm):
    path = _toml(tmp_path, BASE.replace("steps_per_episode = 600",
                                        "steps_per_episode = 10000000"))
    assert main(["train", path, "--method", "st-ql", "--episodes", "1", "--world",
                 "physics"]) == 2
    one_line(capsys, "steps_per_episode", "100,000")


def test_a_chain_with_a_tiny_spacing_is_refused_at_once(tmp_path, capsys, alarm):
    path = _toml(tmp_path, BASE + "\n[[obstacles.chains]]\nfrom = [0.0, 0.0]\n"
                 "to = [40.0, 40.0]\nradius_m = 0.5\nspacing_m = 1e-9\n")
    assert main([*TRAIN[:1], path, *TRAIN[2:]]) == 2
    one_line(capsys, "spacing_m", "limit")


@pytest.mark.parametrize("target", ["/dev/zero", "fifo.map", "dir.map"])
def test_a_map_that_is_not_a_regular_file_is_refused(tmp_path, capsys, alarm, target):
    os.mkfifo(tmp_path / "fifo.map")
    (tmp_path / "dir.map").mkdir()
    path = _toml(tmp_path, 'name = "m"\nstart = [0, 0]\ngoal = [3, 3]\n'
                 f'[arena]\nmap = "{target}"\n')
    assert main(["train", path, "--method", "st-ql", "--episodes", "3"]) == 2
    one_line(capsys, target.split("/")[-1])


@pytest.mark.parametrize("what", ["scenario", "map", "scen", "agent"])
def test_a_fifo_as_an_input_is_refused_not_waited_on(tmp_path, capsys, alarm, what):
    fifo = tmp_path / {"scenario": "s.toml", "map": "m.map", "scen": "p.scen",
                       "agent": "a.npz"}[what]
    os.mkfifo(fifo)
    argv = {"scenario": ["train", str(fifo), "--method", "st-ql"],
            "map": ["train", str(fifo), "--start", "0,0", "--goal", "3,3", "--method",
                    "st-ql"],
            "scen": ["train", "--scen", str(fifo), "--index", "0", "--method", "st-ql"],
            "agent": ["route", "paper-40", "--agent", str(fifo)]}[what]
    assert main(argv) == 2
    one_line(capsys, str(fifo))


def test_input_files_are_read_up_to_a_limit(tmp_path):
    from sim.errors import MapError
    from sim.files import read_input

    big = tmp_path / "big.map"
    big.write_bytes(b"." * 1001)
    with pytest.raises(MapError, match="larger than the limit of 1,000 bytes"):
        read_input(big, MapError, "a map", "pass a map", limit=1000)


def test_a_map_header_beyond_the_size_limit_is_refused(tmp_path, capsys):
    m = tmp_path / "m.map"
    m.write_text("type octile\nheight 100000000\nwidth 100000000\nmap\n..\n")
    assert main(["train", str(m), "--start", "0,0", "--goal", "1,0", "--method", "st-ql"]) == 2
    one_line(capsys, "limit of 4096")


# ------------------------------------------------------------------ 7: checkpoints
def _edit(agent: Path, tmp_path: Path, edit) -> Path:
    with np.load(agent) as z:
        arrays = {k: z[k] for k in z.files}
    edit(arrays)
    out = tmp_path / "edited.npz"
    np.savez(out, **arrays)
    return out


def _claim_shape(agent: Path, tmp_path: Path, member: str, shape: tuple[int, ...]) -> Path:
    """The agent with ``member``'s .npy header claiming ``shape`` (its data unchanged)."""
    import zipfile

    out = tmp_path / "claims.npz"
    with zipfile.ZipFile(agent) as src, zipfile.ZipFile(out, "w") as dst:
        for info in src.infolist():
            raw = src.read(info.filename)
            if info.filename == f"{member}.npy":
                n = int.from_bytes(raw[8:10], "little")
                head = raw[10:10 + n].decode("latin1")
                start = head.index("'shape': (") + len("'shape': (")
                new = head[:start] + ", ".join(map(str, shape)) + head[head.index(")", start):]
                new = new.rstrip().ljust(n - 1) + "\n"
                raw = raw[:8] + len(new).to_bytes(2, "little") + new.encode("latin1") \
                    + raw[10 + n:]
            dst.writestr(info, raw)
    return out


def test_a_header_claiming_a_huge_array_is_refused_before_allocation(agent, tmp_path, capsys):
    bad = _claim_shape(agent, tmp_path, "state_q", (10**12, 4))
    assert main(["train", "paper-50", "--method", "st-ql", "--episodes", "40", "--resume",
                 str(bad)]) == 2
    one_line(capsys, "state_q", "claims shape")


@pytest.mark.parametrize("value", [np.inf, -np.inf, 1e308])
def test_a_q_table_of_infinities_or_absurd_values_is_refused(agent, tmp_path, capsys, value):
    def edit(a):
        a["state_q"] = a["state_q"].copy()
        a["state_q"][3, 1] = value
    bad = _edit(agent, tmp_path, edit)
    assert main(["route", "paper-50", "--agent", str(bad)]) == 2
    one_line(capsys, "state_q", "infinite values or values beyond")


def test_a_config_asking_for_huge_arrays_is_refused_before_allocation(tmp_path, capsys):
    saved = tmp_path / "r.npz"
    assert main(["train", "paper-40", "--method", "rnh-ql", "--episodes", "3", "--save",
                 str(saved)]) == 0
    capsys.readouterr()

    def edit(a):
        cfg = json.loads(str(a["config"]))
        cfg["k"] = 100000
        a["config"] = np.array(json.dumps(cfg))
    bad = _edit(saved, tmp_path, edit)
    assert main(["route", "paper-40", "--agent", str(bad)]) == 2
    one_line(capsys, "k = 100000", "limit 100")


def test_a_checkpoint_missing_a_metric_is_refused(agent, tmp_path, capsys):
    bad = _edit(agent, tmp_path, lambda a: a.pop("metric_success"))
    assert main(["train", "paper-50", "--method", "st-ql", "--episodes", "40", "--resume",
                 str(bad)]) == 2
    one_line(capsys, "metric_success", "missing")


def test_an_index_array_out_of_range_is_refused_not_indexed_with(tmp_path, capsys):
    """Compiled code indexes with these without bounds checks: dyna-q's count of seen pairs
    at 2**62 crashed the process (found by the fuzz test)."""
    saved = tmp_path / "d.npz"
    assert main(["train", "paper-40", "--method", "dyna-q", "--episodes", "12", "--save",
                 str(saved)]) == 0
    capsys.readouterr()
    for name, value in (("state_model.n_seen", 2**62), ("state_model.successor", -7)):
        def edit(a, name=name, value=value):
            a[name] = a[name].copy()
            a[name].reshape(-1)[-1] = value
        bad = _edit(saved, tmp_path, edit)
        assert main(["train", "paper-40", "--method", "dyna-q", "--episodes", "14",
                     "--resume", str(bad)]) == 2
        one_line(capsys, name, "outside")


def test_a_metric_beyond_any_return_is_refused(agent, tmp_path, capsys):
    def edit(a):
        a["metric_returns"] = a["metric_returns"].copy()
        a["metric_returns"][0] = 1e308
    bad = _edit(agent, tmp_path, edit)
    assert main(["train", "paper-50", "--method", "st-ql", "--episodes", "40", "--resume",
                 str(bad)]) == 2
    one_line(capsys, "metric_returns")


def test_route_checks_the_scenario_the_agent_was_trained_on(agent, capsys):
    assert main(["route", "zigzag-50", "--agent", str(agent)]) == 2  # same size, other map
    one_line(capsys, "problem.layout")
    assert main(["route", "paper-50", "--agent", str(agent), "--rewards", "paper"]) == 0


# ------------------------------------------------------------------ 8: SIGHUP
def _default_signals() -> None:
    """The sweep starts with the default SIGINT and SIGHUP, whatever this test run inherited
    (under ``nohup`` or as a background job they are ignored, and rnhql keeps an ignored
    SIGHUP ignored, as it should)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)


@pytest.mark.parametrize("terminal", ["open", "closed"])
def test_sighup_cleans_up_like_sigterm_and_resume_completes(tmp_path, terminal):
    """``closed``: stderr is gone by the time SIGHUP arrives (a closed terminal: every write
    fails), and what finished must be kept all the same."""
    from scenarios.recording.file import verify_recording

    # long enough that the signal lands mid-sweep on a fast, quiet machine too (at 1500
    # episodes the whole sweep could end before the first finished run was seen)
    sweep = ["compare", "paper-40", "--methods", "rn-ql,st-ql", "--seeds", "4", "--episodes",
             "8000", "--jobs", "2"]
    out = tmp_path / "out"
    rec = tmp_path / "c.rrd"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen([sys.executable, "-m", "scenarios.cli", *sweep, "--out", str(out),
                             "--record", str(rec)], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True, env=env,
                            preexec_fn=_default_signals)
    partial = out / "runs.partial.jsonl"
    t0 = time.monotonic()
    while not (partial.exists() and partial.read_text().count("\n") >= 1):
        assert time.monotonic() - t0 < 120 and proc.poll() is None
        time.sleep(0.05)
    if terminal == "closed":
        proc.stderr.close()
        proc.stdout.close()
    os.killpg(proc.pid, signal.SIGHUP)  # a closed terminal signals the whole group
    try:
        if terminal == "closed":
            proc.wait(timeout=30)
            err = ""
        else:
            _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 129, err
    if terminal == "open":
        assert "hung up" in err and "Traceback" not in err
    assert not (out / ".rnhql-sweep.lock").exists()
    assert rec.exists() and verify_recording(rec)[0]  # the finished runs' recording
    done = subprocess.run([sys.executable, "-m", "scenarios.cli", *sweep, "--out", str(out),
                           "--record", str(rec), "--resume"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr
    assert len(json.loads((out / "results.json").read_text())["runs"]) == 8


# ------------------------------------------------------------------ 9: unchecked values
@pytest.mark.parametrize(("text", "words"), [
    ("x = " + "[" * 5000 + "]" * 5000 + "\n", ("nested too deeply",)),
    (BASE.replace("seed = ", "seed = -") if "seed = " in BASE else "", ("seed",)),
    (BASE.replace("width_m = 40.0", "width_m = " + "1" * 46), ("width_m",)),
    (BASE.replace("[obstacles.random]",
                  "[obstacles]\ncircles = [[1e308, 1e308, 1.0]]\n[obstacles.random]"),
     ("obstacles.circles[0]", "limit")),
])
def test_unchecked_scenario_values_are_one_line(tmp_path, capsys, text, words, alarm):
    assert text, "the base scenario changed: fix the test"
    path = _toml(tmp_path, text)
    assert main(["train", path, "--method", "st-ql", "--episodes", "3"]) == 2
    one_line(capsys, *words)


@pytest.mark.parametrize("argv", [
    ["train", "paper-40", "--method", "rnh-ql", "--episodes", "3", "--set", "k=inf"],
    ["train", "paper-40", "--method", "rnh-ql", "--episodes", "3", "--set", "k=1e30"],
    ["train", "paper-40", "--method", "st-ql", "--episodes", "3", "--set", "alpha=nan"],
    ["train", "paper-40", "--method", "haql", "--episodes", "3", "--set", "xi=1e300"],
    ["aliasing", "paper-40", "--seed", "-1", "--repeats", "1", "--out", "al"],
    ["train", "paper-40", "--method", "st-ql", "--episodes", "3", "--seed", str(2**64)],
])
def test_unchecked_command_line_values_are_one_line(argv, capsys, alarm):
    assert main(argv) == 2
    one_line(capsys, "Fix:")


def test_a_very_long_scenario_name_records_under_a_short_file_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = _toml(tmp_path, BASE.replace('name = "paper-40"', f'name = "{"n" * 5000}"'))
    assert 'name = "nnn' in Path(path).read_text()
    assert main(["train", path, "--method", "st-ql", "--episodes", "3", "--record"]) == 0
    (rec,) = (tmp_path / "recordings").iterdir()
    assert len(rec.name) < 200 and rec.suffix == ".rrd"


# ------------------------------------------------------------------ 10: the compile notice
def test_the_compile_notice_looks_where_numba_caches(tmp_path, monkeypatch):
    from learning.jitcache import kernel_cache_dirs, kernels_cached

    pkg = tmp_path / "learning"
    (pkg / "compiled" / "__pycache__").mkdir(parents=True)
    (pkg / "compiled" / "__pycache__" / "kernels.f-1.py311.nbi").write_bytes(b"")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "nbc"))  # writable, empty
    assert not kernels_cached(pkg)
    (sub,) = kernel_cache_dirs(pkg)
    assert sub.parent == tmp_path / "nbc" and sub.name.startswith("compiled_")
    sub.mkdir(parents=True)
    (sub / "kernels.f-1.py311.nbi").write_bytes(b"")
    assert kernels_cached(pkg)
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(blocker / "nbc"))  # cannot be created: numba
    assert kernels_cached(pkg)  # falls back to __pycache__, and so does the check
