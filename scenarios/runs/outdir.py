"""The output directory of a sweep: checked before any work, and held by one sweep at a time.

Two sweeps writing into one directory would interleave ``runs.partial.jsonl``
and overwrite each other's ``results.json``; a lock file naming the owner's pid
prevents it. A lock whose process is gone (a sweep killed with SIGKILL) is
stale and taken over.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

from sim.errors import InputError

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


PID_MAX = 4_194_304  # Linux's largest pid (pid_max's ceiling); other systems are lower


def _alive(pid: int) -> bool:
    """Whether ``pid`` is a live process. Not a pid at all (0, negative: a process *group*
    to ``kill``; beyond any pid) counts as gone: a lock holding it is junk, not an owner."""
    if not 0 < pid <= PID_MAX:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's live process
        return True
    return True


@contextlib.contextmanager
def sweep_lock(out_dir: Path, flag: str = "--out") -> Iterator[None]:
    """Hold ``out_dir`` for this process; refuse if a live process holds it."""
    from sim.files import open_own_file

    lock = out_dir / LOCK_NAME
    mine = out_dir / f"{LOCK_NAME}.{os.getpid()}"
    # never through a link or file planted under this name (it would be truncated to a pid)
    mine.unlink(missing_ok=True)
    fd = open_own_file(mine, os.O_WRONLY | os.O_CREAT | os.O_EXCL)
    with os.fdopen(fd, "w") as helper:
        helper.write(f"{os.getpid()}\n")
    try:
        for _ in range(2):
            try:  # a hard link appears atomically *with* its content: never an empty lock
                os.link(mine, lock)
            except FileExistsError:
                if lock.is_symlink():  # planted: never read or honoured through a link
                    lock.unlink()
                    continue
                if lock.is_dir() or (lock.exists() and not lock.is_file()):
                    raise OutDirError(str(lock), flag, "is not a lock file (a folder or device "
                                      "under the lock's name)",
                                      f"remove it if no sweep is running: rm -r {lock}") from None
                try:
                    owner = int(lock.read_bytes().decode("ascii").strip() or "0")
                except (OSError, ValueError):  # junk (UnicodeDecodeError is a ValueError)
                    owner = 0
                if owner and owner != os.getpid() and _alive(owner):
                    raise OutDirError(str(out_dir), flag,
                                      f"is in use by another sweep (pid {owner})",
                                      "wait for it to finish or pick another directory") from None
                lock.unlink(missing_ok=True)  # stale: its owner is gone
                continue
            break
        else:
            raise OutDirError(str(out_dir), flag, "lock file keeps reappearing",
                              f"remove {lock} if no sweep is running")
    finally:
        mine.unlink(missing_ok=True)
    try:
        yield
    finally:
        lock.unlink(missing_ok=True)
