"""Ctrl-C: a sweep stops within 2 s, keeps its finished runs, and --resume completes it.

Each command runs in its own process group and receives SIGINT on the whole
group, as a terminal's Ctrl-C does (workers included).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from scenarios.recording.file import verify_recording

CLI = [sys.executable, "-m", "scenarios.cli"]


def start(args: list[str], cwd: Path) -> subprocess.Popen:
    # SIGINT back to its default in the child: a test run started in the background of a
    # non-interactive shell inherits SIGINT ignored, and Python then never raises on it
    return subprocess.Popen([*CLI, *args], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
                            env={**os.environ, "PYTHONPATH": str(Path(__file__).parent.parent)})


def wait_for(cond, timeout: float) -> bool:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if cond():
            return True
        time.sleep(0.05)
    return False


def interrupt(proc: subprocess.Popen) -> tuple[int, float, str]:
    """SIGINT to the process group; (exit status, seconds until it ended, stderr)."""
    t0 = time.monotonic()
    os.killpg(proc.pid, signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    return proc.returncode, time.monotonic() - t0, err


def strip_timings(x):
    if isinstance(x, dict):
        return {k: strip_timings(v) for k, v in x.items() if "wall_time" not in k}
    if isinstance(x, list):
        return [strip_timings(v) for v in x]
    return x


def resume_gives_the_whole_sweep(sweep: list[str], out: Path, tmp_path: Path,
                                 *extra: str) -> None:
    """``--resume`` finishes the interrupted sweep in ``out`` (``extra``: more of its
    arguments) with the results.json one uninterrupted sweep writes."""
    resumed = subprocess.run([*CLI, *sweep, "--out", str(out), *extra, "--resume"],
                             cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    whole = subprocess.run([*CLI, *sweep, "--out", str(tmp_path / "whole")], cwd=tmp_path,
                           capture_output=True, text=True, timeout=300)
    assert whole.returncode == 0, whole.stderr
    a = json.loads((out / "results.json").read_text())
    b = json.loads((tmp_path / "whole" / "results.json").read_text())
    assert strip_timings(a) == strip_timings(b)


def test_ctrl_c_stops_a_recorded_sweep_and_resume_completes_it(tmp_path):
    sweep = ["compare", "paper-40", "--methods", "rn-ql,st-ql", "--seeds", "6",
             "--episodes", "1500", "--jobs", "2"]
    out, rec = tmp_path / "out", tmp_path / "cmp.rrd"
    proc = start([*sweep, "--out", str(out), "--record", str(rec)], tmp_path)
    partial = out / "runs.partial.jsonl"
    assert wait_for(lambda: partial.exists() and partial.read_text().count("\n") >= 1, 120)
    code, took, err = interrupt(proc)
    assert code == 130, err
    assert took <= 2.0, f"took {took:.2f} s to stop"
    assert "interrupted" in err
    finished = partial.read_text().count("\n")
    assert 1 <= finished < 12
    assert not (out / "results.json").exists()
    assert rec.exists() and verify_recording(rec)[0]

    resume_gives_the_whole_sweep(sweep, out, tmp_path, "--record", str(rec))
    assert verify_recording(rec)[0]


def test_ctrl_c_stops_physics_training(tmp_path):
    # compile the step agent's kernels into numba's disk cache first: the subject here is
    # Ctrl-C during training, not during a cold JIT compile (minutes of LLVM on CI)
    from scenarios.cli import main

    assert main(["train", "paper-40", "--method", "st-ql", "--world", "physics",
                 "--episodes", "1"]) == 0
    # (the fused physics step trains 30,000 episodes at exact in 1.5 s: a run at noisy, whose
    # greedy tests are drives too, lasts)
    proc = start(["train", "paper-40", "--method", "st-ql", "--world", "physics",
                  "--fidelity", "noisy", "--episodes", "20000"], tmp_path)
    assert wait_for(lambda: proc.poll() is not None, 4.0) is False  # still training
    code, took, err = interrupt(proc)
    assert code == 130, err
    assert took <= 2.0, f"took {took:.2f} s to stop"
    assert "Traceback" not in err


def test_ctrl_c_stops_a_batched_physics_sweep_and_resume_completes_it(tmp_path):
    # warm numba's disk cache for the batched learners and world (not the subject here)
    from scenarios.cli import main

    warm = ["compare", "paper-40", "--methods", "st-ql,haql", "--seeds", "1", "--episodes",
            "2", "--world", "physics", "--jobs", "1"]
    assert main([*warm, "--out", str(tmp_path / "warm")]) == 0
    sweep = ["compare", "paper-40", "--methods", "st-ql,haql", "--seeds", "2", "--episodes",
             "3000", "--world", "grid,physics", "--jobs", "1", "--rewards", "goal-only"]
    out = tmp_path / "out"
    proc = start([*sweep, "--out", str(out)], tmp_path)
    partial = out / "runs.partial.jsonl"
    # the grid runs finish first; then the physics runs train as one batch
    assert wait_for(lambda: partial.exists() and partial.read_text().count("\n") >= 4, 120)
    time.sleep(0.3)
    code, took, err = interrupt(proc)
    assert code == 130, err
    assert took <= 2.0, f"took {took:.2f} s to stop"
    assert "Traceback" not in err
    assert partial.read_text().count("\n") == 4  # the batch was not finished: nothing of it
    resume_gives_the_whole_sweep(sweep, out, tmp_path)


def _take_lock(out: str, barrier, results) -> None:
    from scenarios.sweep.outdir import OutDirError, sweep_lock

    barrier.wait()
    try:
        with sweep_lock(Path(out)):
            time.sleep(0.5)
        results.put("held")
    except OutDirError:
        results.put("refused")


def test_simultaneous_sweeps_into_one_directory_one_wins(tmp_path):
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    for _ in range(5):
        out = tmp_path / f"o{_}"
        out.mkdir()
        barrier, results = ctx.Barrier(6), ctx.Queue()
        procs = [ctx.Process(target=_take_lock, args=(str(out), barrier, results))
                 for _ in range(6)]
        for p in procs:
            p.start()
        for p in procs:
            p.join(10)
        got = sorted(results.get(timeout=5) for _ in procs)
        assert got == ["held"] + ["refused"] * 5


def test_sigterm_cleans_up_like_ctrl_c_and_exits_143(tmp_path):
    sweep = ["compare", "paper-40", "--methods", "rn-ql,st-ql", "--seeds", "4", "--episodes",
             "1500", "--jobs", "2"]
    out = tmp_path / "out"
    proc = start([*sweep, "--out", str(out)], tmp_path)
    partial = out / "runs.partial.jsonl"
    assert wait_for(lambda: partial.exists() and partial.read_text().count("\n") >= 1, 120)
    t0 = time.monotonic()
    os.kill(proc.pid, signal.SIGTERM)  # to the main process only, as `timeout` does
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 143, err
    assert time.monotonic() - t0 <= 2.0
    assert "terminated" in err and "Traceback" not in err
    assert partial.read_text().count("\n") >= 1  # finished runs kept
    assert not (out / ".rnhql-sweep.lock").exists()


def test_workers_end_when_the_parent_is_killed(tmp_path):
    import re

    sweep = ["compare", "paper-40", "--methods", "rn-ql", "--seeds", "4", "--episodes",
             "3000", "--jobs", "2", "--out", str(tmp_path / "out")]
    proc = start(sweep, tmp_path)

    def children() -> list[int]:
        kids = Path(f"/proc/{proc.pid}/task/{proc.pid}/children")
        return [int(p) for p in re.findall(r"\d+", kids.read_text())] if kids.exists() else []

    def alive(pid: int) -> bool:
        try:  # a zombie (state Z) has ended; it waits only to be reaped by init
            return Path(f"/proc/{pid}/stat").read_text().split()[2] != "Z"
        except (FileNotFoundError, ProcessLookupError, IndexError):
            return False

    try:
        # killed the moment the workers exist: some may not have run their initializer yet
        assert wait_for(lambda: len(children()) >= 2, 60)
        workers = children()
        os.kill(proc.pid, signal.SIGKILL)
        assert wait_for(lambda: not any(alive(w) for w in workers), 10), \
            "workers outlived their parent"
        proc.communicate(timeout=30)  # no worker holds the pipes any more
    finally:  # a failure here must not leave runs going on into the next tests
        if proc.poll() is None or any(alive(w) for w in children()):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()


def test_a_worker_orphaned_before_its_initializer_ends_at_once():
    """The death signal is armed in the initializer, after the fork: a parent killed in
    between is caught by the parent-pid check instead."""
    code = ("import os; from scenarios.sweep.backends import _ignore_sigint; "
            "_ignore_sigint(parent=os.getppid() + 1_000_000); print('not ended')")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60, cwd=Path(__file__).parent.parent)
    assert done.returncode == 1 and "not ended" not in done.stdout, done
    code = ("import os; from scenarios.sweep.backends import _ignore_sigint; "
            "_ignore_sigint(parent=os.getppid()); print('kept')")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60, cwd=Path(__file__).parent.parent)
    assert done.returncode == 0 and "kept" in done.stdout, done


def test_ctrl_c_while_the_command_starts_is_one_line(tmp_path):
    for delay in (0.1, 0.3, 0.6):  # during the imports of numpy, numba, pymunk, the CLI
        proc = start(["train", "paper-40", "--method", "st-ql", "--world", "physics",
                      "--episodes", "50"], tmp_path)
        time.sleep(delay)
        code, _, err = interrupt(proc)
        assert code == 130, err
        assert "Traceback" not in err and "Exception ignored" not in err, err


def test_ctrl_c_after_the_summary_still_leaves_a_whole_recording(tmp_path):
    sweep = ["compare", "paper-40", "--methods", "st-ql,haql", "--seeds", "2", "--episodes",
             "300", "--jobs", "1"]
    for delay in (0.0, 0.8):  # while figures are drawn, while the recording is merged
        out, rec = tmp_path / f"o{delay}", tmp_path / f"c{delay}.rrd"
        proc = start([*sweep, "--out", str(out), "--record", str(rec)], tmp_path)
        assert wait_for(lambda out=out: (out / "summary.md").exists(), 120)
        time.sleep(delay)
        code, _, err = interrupt(proc)
        assert code in (0, 130), err
        assert "Traceback" not in err
        assert rec.exists() and verify_recording(rec)[0]
        assert rec.stat().st_size > 100_000  # the runs are in it, not only a header


_SIGNAL_INSIDE_LLVM = """
import signal, sys
import numpy as np
from numba.core import codegen
{guard}
raw = codegen.CPUCodeLibrary._object_getbuffer_hook
def getbuffer(cls, module):  # LLVM's callback into Python (ctypes) as a kernel is finalised
    signal.raise_signal({sig})
    x = [i for i in range(100)]  # bytecode: a pending handler runs here, in the callback
    return raw(module)
codegen.CPUCodeLibrary._object_getbuffer_hook = classmethod(getbuffer)
import numba
if {terminate}:
    def stop(sig, frame):
        raise SystemExit(143)
    signal.signal(signal.SIGTERM, stop)
@numba.njit
def kernel(a):
    return a.sum() * 2.0
try:
    print(kernel(np.ones(3)))
except KeyboardInterrupt:
    print("interrupted after the compile", file=sys.stderr)
    sys.exit(130)
print("ran on", file=sys.stderr)
sys.exit(0)
"""


def _signal_inside_llvm(sig: int, guarded: bool) -> subprocess.CompletedProcess:
    guard = ("from scenarios.signals import hold_stop_signals_while_compiling\n"
             "hold_stop_signals_while_compiling()" if guarded else "")
    code = _SIGNAL_INSIDE_LLVM.format(guard=guard, sig=int(sig),
                                      terminate=sig == signal.SIGTERM)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, preexec_fn=lambda: signal.signal(signal.SIGINT,
                                                                        signal.SIG_DFL),
                          env={**os.environ, "PYTHONPATH": str(Path(__file__).parent.parent)})


def test_a_signal_inside_llvms_callback_is_dropped_without_the_guard():
    """The failure the guard is for (CI: a Ctrl-C during a cold sweep's compile ended in a
    segmentation fault): the KeyboardInterrupt raised in LLVM's callback is printed and
    dropped, and the compile goes on without it (or crashes)."""
    done = _signal_inside_llvm(signal.SIGINT, guarded=False)
    assert done.returncode != 130 and "Exception ignored" in done.stderr, done.stderr


def test_a_signal_during_a_compile_is_acted_on_as_the_compile_ends():
    for sig, code in ((signal.SIGINT, 130), (signal.SIGTERM, 143)):
        done = _signal_inside_llvm(sig, guarded=True)
        assert done.returncode == code, done.stderr
        assert "Exception ignored" not in done.stderr and "ran on" not in done.stderr
