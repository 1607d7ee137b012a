"""Under an address-space limit (``ulimit -v``) the command works or says in one line why it
cannot: it never spins in a BLAS import, aborts in LLVM, or loses a run to Rerun's abort."""

from __future__ import annotations

import resource
import subprocess
import sys

import pytest

from scenarios.memory_limit import MIN_BYTES, RECORDING_BYTES

pytestmark = pytest.mark.skipif(not hasattr(resource, "RLIMIT_AS"), reason="POSIX limits")
MiB = 1024 * 1024


def _run(limit: int, argv: list[str], cwd, python: str | None = None):
    def limited() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    cmd = ([sys.executable, "-c", python] if python is not None
           else [sys.executable, "-m", "scenarios.cli", *argv])
    # a hang guard, not a timing: the spin this prevents lasted minutes
    return subprocess.run(cmd, cwd=cwd, preexec_fn=limited, capture_output=True, text=True,
                          timeout=300)


def test_a_limit_too_small_to_compile_is_one_line_before_any_import(tmp_path):
    r = _run(300 * MiB, ["train", "paper-40", "--episodes", "3"], tmp_path)
    assert r.returncode == 1
    assert r.stderr.count("\n") == 1 and "ulimit -v" in r.stderr and "300 MB" in r.stderr
    assert f"{MIN_BYTES // MiB:,} MB" in r.stderr


def test_a_recording_under_a_small_limit_is_refused_before_training(tmp_path):
    limit = (MIN_BYTES + RECORDING_BYTES) // 2
    r = _run(limit, ["train", "paper-40", "--episodes", "3", "--record", "x.rrd"], tmp_path)
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and "--record" in r.stderr and "ulimit -v" in r.stderr
    assert not list(tmp_path.iterdir())  # no recording, no partial file
    r = _run(limit, [], tmp_path, python=(
        "import rnhql\n"
        "try:\n"
        "    rnhql.train('paper-40', episodes=3, record='y.rrd')\n"
        "except ValueError as e:\n"
        "    print(e)\n"))
    assert "record" in r.stdout and "ulimit -v" in r.stdout, r.stderr
    assert not list(tmp_path.iterdir())


def test_a_run_under_a_limit_finishes(tmp_path):
    r = _run(MIN_BYTES + 100 * MiB, ["train", "paper-40", "--method", "rnh-ql+",
                                     "--episodes", "3"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert "env steps" in r.stdout
