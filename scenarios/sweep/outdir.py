"""Output paths, checked before any work, and a sweep's folder held by one sweep at a time.

The command line's paths (:func:`check_empty_paths`, :func:`check_output_file`,
:func:`record_path`): empty paths, folders where a file goes, device nodes and FIFOs
(written through, never replaced), unwritable folders, and the default recording's file
name. Every check raises :class:`sim.errors.InputError` (one line naming the flag and the
fix); :mod:`scenarios.cli.app` prints it and exits 2.

Two sweeps writing into one directory would interleave ``runs.partial.jsonl``
and overwrite each other's ``results.json``; a lock file naming the owner's pid
prevents it. A lock whose process is gone (a sweep killed with SIGKILL) is
stale and taken over.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
from collections.abc import Iterator
from pathlib import Path

from scenarios.memory_limit import recording_refused
from scenarios.runs.spec import ExperimentError
from sim.errors import InputError
from sim.files import check_output, node_kind, open_own_file

LOCK_NAME = ".rnhql-sweep.lock"


class OutDirError(InputError):
    """An output directory that cannot be used: a file, unwritable, or in use."""


def check_out_dir(out_dir: Path, flag: str = "--out") -> Path:
    """Create ``out_dir`` if needed; a one-line error if it is a file or not writable."""
    if out_dir.exists() and not out_dir.is_dir():
        raise OutDirError(str(out_dir), flag, "is a file, not a directory",
                          "pass a directory (it is created if missing)")
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutDirError(str(out_dir), flag, f"cannot be created ({exc.strerror})",
                          "pick a location you can write to") from None
    if not os.access(out_dir, os.W_OK | os.X_OK):
        raise OutDirError(str(out_dir), flag, "is not writable",
                          "pick a location you can write to") from None
    return out_dir


def _owner(fd: int) -> int:
    """The pid a lock file names (0: none or junk)."""
    try:
        text = os.pread(fd, 32, 0).decode("ascii").strip()
        return int(text or "0")
    except (OSError, ValueError):  # junk (UnicodeDecodeError is a ValueError)
        return 0


@contextlib.contextmanager
def sweep_lock(out_dir: Path, flag: str = "--out") -> Iterator[None]:
    """Hold ``out_dir`` for this process; refuse if a live process holds it.

    The lock is a kernel lock (``flock``) on the lock file, held while the sweep runs: only
    one process can hold it at any instant, and the kernel releases it when its process
    dies however it dies, so a stale lock is simply taken (no read-then-remove race: the
    old takeover let two processes in at once in 53 of 200 synchronised trials). The file
    names the holder's pid for the message only: the ``flock`` alone decides, so a file
    naming some live process that holds no lock (pid 1, planted or left over) does not
    block the folder. A link planted under the lock's name is removed, never followed.
    """
    # POSIX only: the package still imports where fcntl is missing
    import fcntl

    lock = out_dir / LOCK_NAME
    for _ in range(3):
        if lock.is_symlink():
            lock.unlink()
        if lock.exists() and not lock.is_file():
            raise OutDirError(str(lock), flag, "is not a lock file (a folder or device "
                              "under the lock's name)",
                              f"remove it if no sweep is running: rm -r {lock}")
        fd = open_own_file(lock, os.O_RDWR | os.O_CREAT)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            owner = _owner(fd)
            os.close(fd)
            raise OutDirError(str(out_dir), flag, "is in use by another sweep"
                              + (f" (pid {owner})" if owner else ""),
                              "wait for it to finish or pick another directory") from None
        try:
            same = os.fstat(fd).st_ino == os.stat(lock).st_ino
        except FileNotFoundError:  # its holder removed it as we opened it: try again
            same = False
        if not same:
            os.close(fd)
            continue
        break
    else:
        raise OutDirError(str(out_dir), flag, "lock file keeps changing",
                          f"remove {lock} if no sweep is running")
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode("ascii"), 0)
        yield
    finally:
        with contextlib.suppress(OSError):  # removed while held: no one can hold it between
            if os.fstat(fd).st_ino == os.stat(lock).st_ino:
                lock.unlink()
        os.close(fd)


# ---------------------------------------------------------------- the command line's paths

MAX_NAME_CHARS = 100  # of a scenario's name in a default recording's file name


# what a bare --record stands for (its default path); an explicit --record '' is an error
RECORD_DEFAULT = "\0default"

# flags whose value names a file or folder: an empty one is an error, never "not given"
PATH_FLAGS = ("scen", "resume", "save", "json", "png", "out", "agent", "check", "record",
              "artifact", "file")


def check_empty_paths(args: argparse.Namespace) -> None:
    """Refuse ``--save ''`` and its kin: an empty path would be ignored (a run whose agent
    is never saved) or mean the current folder (``--out ''`` writing over what is there)."""
    for name in PATH_FLAGS:
        value = getattr(args, name, None)
        if isinstance(value, str) and value.strip() == "":
            flag = name if name == "file" else f"--{name.replace('_', '-')}"
            raise InputError("command line", flag, "is an empty path",
                           f"name a file or folder, or drop {flag}")


def record_path(args: argparse.Namespace, scenario: str, rest: str) -> str | None:
    """``--record`` given: its path, or the default under recordings/; else None."""
    if args.record is None:
        return None
    # a scenario's name is the user's text: never let it climb out of recordings/, and
    # keep the file name within what a file system takes (255 bytes)
    safe = re.sub(r"[^A-Za-z0-9._-]+", "_", scenario).lstrip("._")[:MAX_NAME_CHARS] or "run"
    rest = re.sub(r"[^A-Za-z0-9._+-]+", "_", rest)  # method names keep their "+" (rnh-ql+)
    # (an explicit --record '' never reaches here: check_empty_paths refuses it)
    path = Path(f"recordings/{safe}-{rest}.rrd" if args.record in (RECORD_DEFAULT, "")
                else args.record)
    if path.suffix != ".rrd":
        raise ExperimentError("command line", "--record", f"{path} does not end in .rrd",
                              "name the recording e.g. run.rrd")
    if len(path.name.encode()) > 250:
        raise ExperimentError("command line", "--record", f"the file name is "
                              f"{len(path.name.encode())} bytes, more than a file system takes",
                              "name the recording e.g. run.rrd")
    check_output(path, "--record")  # a folder under the name: refused before any work
    refused = recording_refused()
    if refused is not None:
        raise ExperimentError("command line", "--record", *refused)
    if node_kind(path) in ("device", "fifo"):
        return str(path)  # written through when the recording is finished (sim.files)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ExperimentError(str(path.parent), "--record", f"cannot be created "
                              f"({exc.strerror})", "pick another path") from None
    check_writable(path, "--record")
    return str(path)


def check_output_file(path: Path, flag: str, suffix: str | None = None) -> Path:
    """An output file the command will write at the end: checked before any work."""
    if suffix is not None and path.suffix != suffix:
        raise ExperimentError("command line", flag, f"{path} does not end in {suffix}",
                              f"name the file e.g. out{suffix}")
    if path.is_dir():
        raise ExperimentError("command line", flag, f"{path} is a directory",
                              f"name a file, e.g. {path / ('out' + (suffix or '.json'))}")
    check_output(path, flag)
    if node_kind(path) in ("device", "fifo"):
        return path  # written through at the end (sim.files); its folder is not written
    check_writable(path, flag)
    return path


def check_writable(path: Path, flag: str) -> None:
    if path.is_symlink():
        path = Path(os.path.realpath(path))  # the link's target is what gets replaced
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir() or not os.access(parent, os.W_OK):
        raise ExperimentError("command line", flag, f"cannot write to {parent}/",
                              "create the directory or pick another path")
