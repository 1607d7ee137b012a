"""A full disk: one line, exit 1, nothing half-written and no temp files left behind.

Uses a 2 MB tmpfs mounted for the test (needs root and ``mount``; skipped with the reason
otherwise), filled so that only a few kilobytes remain.
"""

from __future__ import annotations

import contextlib
import shutil
import subprocess
import sys
import uuid
from pathlib import Path

import pytest

CLI = [sys.executable, "-m", "scenarios.cli"]
REPO = Path(__file__).resolve().parent.parent


@contextlib.contextmanager
def _tmpfs(options: str, why: str):
    mnt = Path("/tmp") / f"rnhql-tmpfs-{uuid.uuid4().hex[:8]}"
    mnt.mkdir()
    if shutil.which("mount") is None or subprocess.run(
            ["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(mnt)],
            capture_output=True).returncode != 0:
        mnt.rmdir()
        pytest.skip(f"cannot mount a small tmpfs here (needs root): {why} untested")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", str(mnt)], capture_output=True)
        mnt.rmdir()


@pytest.fixture
def full_disk():
    with _tmpfs("size=2m", "full-disk paths") as mnt:
        with open(mnt / "filler", "wb") as f:
            f.write(b"\0" * (2048 - 40) * 1024)
        yield mnt


def _run(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([*CLI, *args], cwd=cwd, capture_output=True, text=True, timeout=300,
                          env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin",
                               "HOME": str(cwd)})


def _leftovers(root: Path) -> list[str]:
    return [p.name for p in root.rglob("*") if p.name.endswith((".tmp", ".part"))]


@pytest.mark.parametrize("args", [
    ["compare", "paper-40", "--methods", "st-ql", "--seeds", "2", "--episodes", "200",
     "--jobs", "1", "--out", "{mnt}/out"],
    ["train", "paper-40", "--method", "st-ql", "--episodes", "200", "--record",
     "{mnt}/run.rrd"],
    ["train", "paper-40", "--method", "rnh-ql", "--episodes", "5", "--save", "{mnt}/a.npz"],
])
def test_a_full_disk_is_one_line_and_leaves_nothing_half_written(full_disk, tmp_path, args):
    got = _run([a.replace("{mnt}", str(full_disk)) for a in args], tmp_path)
    assert got.returncode == 1, got.stderr
    assert "Traceback" not in got.stderr
    errors = [line for line in got.stderr.splitlines() if line.startswith("rnhql")]
    assert len(errors) == 1 and "Fix:" in errors[0], got.stderr
    assert str(full_disk) in errors[0]  # names the file, not a temp file
    assert _leftovers(full_disk) == []
    assert not (full_disk / "run.rrd").exists() and not (full_disk / "a.npz").exists()


@pytest.fixture
def read_only():
    with _tmpfs("size=1m,ro", "read-only paths") as mnt:
        yield mnt


@pytest.mark.parametrize("args", [
    ["train", "paper-40", "--method", "st-ql", "--episodes", "5", "--json", "{mnt}/r.json"],
    ["train", "paper-40", "--method", "st-ql", "--episodes", "5", "--save", "{mnt}/a.npz"],
    ["compare", "paper-40", "--methods", "st-ql", "--seeds", "1", "--episodes", "5",
     "--out", "{mnt}/out"],
    ["train", "paper-40", "--method", "st-ql", "--episodes", "5", "--record"],  # cwd: {mnt}
])
def test_a_read_only_file_system_is_one_line_before_any_work(read_only, args):
    cwd = read_only if args[-1] == "--record" else read_only.parent
    got = _run([a.replace("{mnt}", str(read_only)) for a in args], cwd)
    assert got.returncode in (1, 2), got.stderr
    assert "Traceback" not in got.stderr
    errors = [line for line in got.stderr.splitlines() if line.startswith("rnhql")]
    assert len(errors) == 1 and "Fix:" in errors[0], got.stderr
    assert "env steps" not in got.stdout  # refused before training, not after it


def test_a_full_numba_cache_is_one_line_naming_it(full_disk, tmp_path):
    """NUMBA_CACHE_DIR on a full disk: numba's own write error names no file, and read as
    "an output file"; it names the cache and the fix."""
    got = subprocess.run([*CLI, "train", "paper-40", "--method", "st-ql", "--episodes", "5"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=600,
                         env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin",
                              "HOME": str(tmp_path), "NUMBA_CACHE_DIR": str(full_disk)})
    assert got.returncode == 1, got.stderr
    assert "Traceback" not in got.stderr
    errors = [line for line in got.stderr.splitlines() if line.startswith("rnhql")]
    assert len(errors) == 1 and "numba's kernel cache" in errors[0], got.stderr
    assert str(full_disk) in errors[0] and "NUMBA_CACHE_DIR" in errors[0]
