"""Atomic file writes (a temp file beside the target, then ``os.replace``), and input reads.

A full disk, Ctrl-C or a killed process must never leave half a file under the
real name, and an error must name the file the user asked for, not a temp file.
The one helper for ``sim`` and ``scenarios`` (``learning`` may not import ``sim``
and keeps its own for checkpoints). An input file that cannot be read raises the
reader's :class:`sim.errors.InputError` (one line naming the file and the fix).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from sim.errors import InputError

_UMASK = os.umask(0)  # read once at import: os.umask can only be read by setting it
os.umask(_UMASK)
FILE_MODE = 0o666 & ~_UMASK  # what open() would have given a new file


def move_into_place(tmp: str | Path, path: str | Path) -> None:
    """``os.replace(tmp, path)``; on failure ``tmp`` is removed and the OSError names ``path``.

    For a temp file someone else wrote under a name of its own (a recording's
    ``.part``); :func:`atomic_path` makes and names the temp file itself.
    """
    try:
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise OSError(exc.errno, exc.strerror, str(path)) from None


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temp path beside ``path`` to write to; it becomes ``path`` when the block ends.

    The parent folder is created. If the block raises, the temp file is removed
    and ``path`` is untouched (an OSError then names ``path``). The file gets the
    mode ``open()`` would give (``mkstemp`` alone leaves 0600).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, FILE_MODE)
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def atomic_write_bytes(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (:func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def atomic_write_text(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically (:func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def read_input(path: Path, error: type[InputError], kind: str, fix: str) -> bytes:
    """The bytes of an input file; a missing or unreadable file, or a folder, raises
    ``error`` naming it (``kind``: what a folder is not, e.g. "a map"; ``fix``: what to
    pass instead of a folder)."""
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise error(str(path), "file", "does not exist", "check the path") from None
    except IsADirectoryError:
        raise error(str(path), "file", f"is a directory, not {kind}", fix) from None
    except PermissionError:
        raise error(str(path), "file", "cannot be read (permission denied)",
                    "check the file's permissions") from None
