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
    names the holder's pid for the message; a file naming another live process whose
    ``flock`` is not held (a sweep of an older rnhql) is respected too. A link planted
    under the lock's name is removed, never followed.
    """
    import fcntl

    from sim.files import open_own_file

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
        owner = _owner(fd)
        try:
            same = os.fstat(fd).st_ino == os.stat(lock).st_ino
        except FileNotFoundError:  # its holder removed it as we opened it: try again
            same = False
        if not same:
            os.close(fd)
            continue
        if owner and owner != os.getpid() and _alive(owner):
            os.close(fd)
            raise OutDirError(str(out_dir), flag, f"is in use by another sweep (pid {owner})",
                              "wait for it to finish or pick another directory")
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
