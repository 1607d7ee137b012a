"""Atomic file writes (a temp file beside the target, then ``os.replace``), and input reads.

A full disk, Ctrl-C or a killed process must never leave half a file under the
real name, and an error must name the file the user asked for, not a temp file.
The one helper for ``sim`` and ``scenarios`` (``learning`` may not import ``sim``
and keeps its own for checkpoints). An input file that cannot be read raises the
reader's :class:`sim.errors.InputError` (one line naming the file and the fix).

Only a regular file is ever replaced. A rename over a device node (``/dev/null``, a
terminal), a FIFO, or a ``/dev/stdout``-style symlink would swap the user's node for a
regular file (as root, the system's own), so those are *written through*: the bytes are
written into the node as into a pipe (``/dev/full`` then reports a full disk like any
other), and a ``/dev/stdout``-style path into the open descriptor it names. A symlink
to a regular file is followed: its target is replaced, the link kept.
Anything else that is not a regular file (a folder, a socket, a block device) is refused
with one line. Inputs are read only from regular files (a FIFO would block until someone
writes to it, ``/dev/zero`` never ends) and only up to :data:`MAX_INPUT_BYTES`.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from sim.errors import InputError

_UMASK = os.umask(0)  # read once at import: os.umask can only be read by setting it
os.umask(_UMASK)
FILE_MODE = 0o666 & ~_UMASK  # what open() would have given a new file

# The largest input file read (a scenario, map, .scen): a 4096 x 4096 map, the largest
# arena allowed, is 16.8 MB; four times that is no input rnhql can use.
MAX_INPUT_BYTES = 64 * 1024 * 1024


class OutputError(InputError):
    """An output path that cannot take a file: a folder, a socket, a block device."""


# a file system with less free space than this is full for rnhql's purposes: a part file,
# a results.json or a figure does not fit, and a writer that just died died of it
FULL_BELOW_BYTES = 256 * 1024


def no_space_left(path: str | Path) -> bool:
    """Whether the file system holding ``path`` (or its nearest existing parent) is full:
    how a writer that failed without saying why (Rerun's file writer, a pool worker that
    died) is told apart from one that failed for another reason."""
    p = Path(path)
    while not p.exists() and p != p.parent:
        p = p.parent
    try:
        st = os.statvfs(p)
    except OSError:
        return False
    return st.f_bavail * st.f_frsize < FULL_BELOW_BYTES


def node_kind(path: str | Path) -> str:
    """What ``path`` is, following symlinks: "missing", "regular", "directory", "device"
    (a character device), "fifo" (a named or anonymous pipe) or "other"."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "missing"
    except OSError:  # a dangling or looping link, an unreadable folder: let the write say
        return "missing"
    if stat.S_ISREG(mode):
        return "regular"
    if stat.S_ISDIR(mode):
        return "directory"
    if stat.S_ISCHR(mode):
        return "device"
    if stat.S_ISFIFO(mode):
        return "fifo"
    return "other"


def check_output(path: str | Path, flag: str = "output") -> None:
    """Raise :class:`OutputError` (one line) when ``path`` can never take a file: empty, a
    folder, a socket or block device. Called before any work by the CLI; the writers call it
    again at the end."""
    if str(path) == "":
        raise OutputError("command line", flag, "is an empty path", "name a file")
    kind = node_kind(path)
    if kind == "directory":
        raise OutputError(str(path), flag, "is a directory, not a file",
                          f"name a file, e.g. {Path(path) / 'out'}")
    if kind == "other":
        raise OutputError(str(path), flag, "is a socket or block device, not a file",
                          "name a regular file")


_FD_LINK = re.compile(r"^/(?:proc/(?:self|thread-self|\d+)/fd|dev/fd)/(\d+)$")


def fd_link(path: str | Path) -> int | None:
    """The file descriptor a ``/dev/stdout``-style path stands for (``/dev/stdout``,
    ``/dev/fd/N``, ``/proc/self/fd/N``, or a symlink to one), else None. Such a path is
    this process's own open file: replacing what it resolves to (a shell's ``> out.txt``)
    would swap the file under the shell's redirection, and opening it anew would write
    from offset 0 over what was printed; so it is written to the descriptor itself."""
    p = str(path)
    for _ in range(40):  # the kernel's own limit on a chain of links
        m = _FD_LINK.match(p)
        if m is not None:
            fd = int(m.group(1))
            return fd if m.group(0).startswith(("/dev/fd", "/proc/self", "/proc/thread")) \
                or m.group(0).startswith(f"/proc/{os.getpid()}/") else None
        try:
            target = os.readlink(p)
        except OSError:
            return None
        p = os.path.join(os.path.dirname(p), target)
        p = os.path.normpath(p)
    return None


def _write_to_fd(src: Path, fd: int, path: Path) -> None:
    """Append the temp file ``src`` to the open descriptor ``fd`` (after what Python has
    printed to it so far)."""
    import sys

    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    try:
        with open(src, "rb") as f, open(os.dup(fd), "wb") as out:
            shutil.copyfileobj(f, out)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror, str(path)) from None


def _write_through(src: Path, path: Path) -> None:
    """Copy the finished temp file ``src`` into the device or pipe ``path``. A FIFO nobody
    reads is refused at once rather than blocking (a non-blocking open: ENXIO)."""
    fd = fd_link(path)
    if fd is not None:
        _write_to_fd(src, fd, path)
        return
    try:
        fd = os.open(path, os.O_WRONLY | os.O_NONBLOCK)
    except OSError as exc:
        if exc.errno == errno.ENXIO:
            raise OutputError(str(path), "output", "is a FIFO no process reads",
                              "start its reader first, or name a regular file") from None
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    try:
        os.set_blocking(fd, True)
        with open(src, "rb") as f, open(fd, "wb", closefd=False) as out:
            shutil.copyfileobj(f, out)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    finally:
        os.close(fd)


def _real_target(path: Path) -> Path:
    """Where a write to ``path`` lands: the target of a symlink (so the link survives)."""
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def move_into_place(tmp: str | Path, path: str | Path) -> None:
    """``os.replace(tmp, path)``; on failure ``tmp`` is removed and the OSError names ``path``.
    A device or FIFO at ``path`` is written through instead (see the module's doc).

    For a temp file someone else wrote under a name of its own (a recording's
    ``.part``); :func:`atomic_path` makes and names the temp file itself.
    """
    try:
        kind = node_kind(path)
        check_output(path)
        if kind in ("device", "fifo") or fd_link(path) is not None:
            _write_through(Path(tmp), Path(path))
            Path(tmp).unlink(missing_ok=True)
            return
        os.replace(tmp, _real_target(Path(path)))
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


@contextlib.contextmanager
def atomic_path(path: str | Path, follow: bool = True) -> Iterator[Path]:
    """A temp path beside ``path`` to write to; it becomes ``path`` when the block ends.

    The parent folder is created. If the block raises, the temp file is removed
    and ``path`` is untouched (an OSError then names ``path``). The file gets the
    mode ``open()`` would give (``mkstemp`` alone leaves 0600). A device or FIFO at
    ``path`` is written through, the temp file then in the system's temp folder.

    ``follow=False``: a file the tool names itself inside an output folder (results,
    summaries, figures): a symlink found at ``path`` is replaced, never written through,
    so a link planted in a shared folder cannot send the write elsewhere. A path the user
    named keeps ``follow=True``: their link survives and its target is written.
    """
    path = Path(path)
    if not follow and path.is_symlink():
        path.unlink()  # the link only, never its target
    check_output(path)
    through = node_kind(path) in ("device", "fifo") or fd_link(path) is not None
    if not follow and through:
        raise OSError(errno.EEXIST, "a device or FIFO stands where the tool writes its own "
                      "file; remove it", str(path))
    target = _real_target(path)
    try:
        if through:
            fd, name = tempfile.mkstemp(prefix="rnhql-", suffix=".tmp")
        else:
            target.parent.mkdir(parents=True, exist_ok=True)
            fd, name = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.",
                                        suffix=".tmp")
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        if through:
            _write_through(tmp, path)
            tmp.unlink(missing_ok=True)
        else:
            os.chmod(tmp, FILE_MODE)
            os.replace(tmp, target)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def atomic_write_bytes(path: str | Path, data: bytes, follow: bool = True) -> None:
    """Write ``data`` to ``path`` atomically (:func:`atomic_path`)."""
    with atomic_path(path, follow) as tmp:
        tmp.write_bytes(data)


def atomic_write_text(path: str | Path, text: str, follow: bool = True) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically (:func:`atomic_path`)."""
    with atomic_path(path, follow) as tmp:
        tmp.write_text(text, encoding="utf-8")


def open_own_file(path: str | Path, flags: int, mode: int = 0o644) -> int:
    """``os.open`` of a file the tool names itself in an output folder, never through a
    link someone planted there: a symlink (``O_NOFOLLOW``) or a hard link (a name whose file
    has other names, ``st_nlink > 1``, would write into another file) at ``path`` is removed
    first and the file created afresh; one planted after that check is refused. Returns
    the descriptor."""
    path = Path(path)
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        st = None
    if st is not None and (stat.S_ISLNK(st.st_mode) or st.st_nlink > 1):
        path.unlink()  # the link's name only: what it points at is left alone
    fd = os.open(path, flags | os.O_NOFOLLOW, mode)
    if os.fstat(fd).st_nlink > 1:  # linked between the check and the open
        os.close(fd)
        raise OutputError(str(path), "output", "is a hard link to another file (planted "
                          "in the output folder)", "remove it, or write elsewhere")
    return fd


def read_input(path: Path, error: type[InputError], kind: str, fix: str,
               limit: int = MAX_INPUT_BYTES) -> bytes:
    """The bytes of an input file; a missing or unreadable file, a folder, anything but a
    regular file, or a file over ``limit`` bytes raises ``error`` naming it (``kind``: what
    a folder is not, e.g. "a map"; ``fix``: what to pass instead of a folder)."""
    if str(path) in ("", "."):
        raise error("command line", "file", "is an empty path", "name a file")
    node = node_kind(path)
    if node == "directory":
        raise error(str(path), "file", f"is a directory, not {kind}", fix)
    if node in ("device", "fifo", "other"):
        what = {"device": "a device", "fifo": "a FIFO (it would wait for a writer)",
                "other": "a socket or block device"}[node]
        raise error(str(path), "file", f"is {what}, not a regular file",
                    f"copy the content into a file and pass that ({kind})")
    try:
        with open(path, "rb") as f:
            data = f.read(limit + 1)
    except FileNotFoundError:
        raise error(str(path), "file", "does not exist", "check the path") from None
    except IsADirectoryError:
        raise error(str(path), "file", f"is a directory, not {kind}", fix) from None
    except PermissionError:
        raise error(str(path), "file", "cannot be read (permission denied)",
                    "check the file's permissions") from None
    except OSError as exc:
        raise error(str(path), "file", f"cannot be read ({exc.strerror})",
                    "check the path") from None
    if len(data) > limit:
        raise error(str(path), "file", f"is larger than the limit of {limit:,} bytes",
                    f"pass a smaller file ({kind})")
    return data
