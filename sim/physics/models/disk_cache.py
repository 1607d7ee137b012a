"""The disk cache of the models built by driving: one mechanism for all of them.

The physics world's tabular model (:mod:`sim.physics.models.transition`) and the stochastic model at
a fidelity (:mod:`sim.physics.models.build`) take seconds to minutes of driving, so
each is kept in ``$XDG_CACHE_HOME/rnhql/<kind>/<key>.npz`` (``~/.cache`` without
``XDG_CACHE_HOME``), ``key`` a digest of everything the model depends on, written
atomically. ``RNHQL_NO_DISK_CACHE=1`` turns the disk cache off.

A cache file is an input like any other and is checked before it is used
(:func:`cached`): it must be a regular file within the model's size limit that loads
(not truncated, not a folder, a zip of plain arrays), hold exactly the arrays written
with the format and key it was written for, match the SHA-256 of its arrays
(:func:`content_digest`: names, dtypes, shapes and bytes), and pass the model's own check
of shapes and values. A file that fails any of it is rebuilt and rewritten, never
trusted (a tampered model would grade a policy on moves the robot cannot make), and one
line on stderr says which file and why.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.files import atomic_path

Arrays = dict[str, np.ndarray]
_HEADER = ("format", "key", "sha256")  # what every cache file holds besides the arrays


@dataclass(frozen=True)
class CacheKind:
    """One kind of cached model."""

    folder: str  # the cache's folder under $XDG_CACHE_HOME/rnhql
    format: str  # written into every file; a new layout is a new format (and new keys)
    arrays: tuple[str, ...]  # the arrays a file holds, by name
    what: str  # what a file holds, for the message, e.g. "physics-model"


def disk_cache_on() -> bool:
    return os.environ.get("RNHQL_NO_DISK_CACHE", "") in ("", "0")


def cache_dir(kind: CacheKind) -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "rnhql" / kind.folder


def content_digest(arrays: Mapping[str, np.ndarray]) -> str:
    """SHA-256 of arrays as stored: each one's name, dtype, shape and bytes, by name."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.asarray(arrays[name])
        h.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def _read(path: Path, kind: CacheKind, key: str, max_bytes: int) -> Arrays | str | None:
    """The arrays in ``path``; a reason it cannot be used; None when there is no file."""
    if not os.path.lexists(path):
        return None
    if path.is_symlink() or not path.is_file():
        return "it is not a regular file"
    try:
        if path.stat().st_size > max_bytes:
            return f"it is larger than such a model can be ({max_bytes:,} bytes)"
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as data:
            if set(data.files) != {*_HEADER, *kind.arrays}:
                return "it does not hold the arrays of this cache"
            if sum(i.file_size for i in data.zip.infolist()) > max_bytes:
                return f"its arrays are larger than such a model can be ({max_bytes:,} bytes)"
            if str(data["format"]) != kind.format or str(data["key"]) != key:
                return "it was written for another format or key"
            arrays = {a: data[a] for a in kind.arrays}
            stored = str(data["sha256"])
    except Exception as exc:  # BadZipFile, a torn header, unreadable ...: any failure rebuilds
        return f"it does not load ({type(exc).__name__})"
    if stored != content_digest(arrays):
        return "its content does not match its SHA-256"
    return arrays


def _write(path: Path, kind: CacheKind, key: str, arrays: Arrays) -> None:
    """Write the file, in place of whatever is under its name (a folder, a link, a pipe:
    the cache's own name; a pipe or device would otherwise be written through)."""
    try:
        if path.is_symlink() or (os.path.lexists(path) and not path.is_dir()
                                 and not path.is_file()):
            path.unlink()
        elif path.is_dir():
            shutil.rmtree(path)
        with atomic_path(path) as tmp, open(tmp, "wb") as f:
            np.savez(f, format=np.array(kind.format), key=np.array(key),
                     sha256=np.array(content_digest(arrays)), **arrays)
    except (OSError, ValueError):  # a read-only home, a full disk: the model still works
        pass  # (and the in-process caches keep it)


def _say(line: str) -> None:
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):  # stderr gone (a closed terminal): the rebuild goes on
        pass


def cached(kind: CacheKind, key: str, build: Callable[[], Arrays],
           check: Callable[[Arrays], str | None], max_bytes: int) -> Arrays:
    """The arrays of the model ``key``: from its cache file when that passes every check
    (the module's doc; ``check`` is the model's own, a reason or None), else ``build()``,
    written to the cache. A file that was there but failed says so on stderr."""
    if not disk_cache_on():
        return build()
    path = cache_dir(kind) / f"{key}.npz"
    got = _read(path, kind, key, max_bytes)
    if isinstance(got, dict):
        why = check(got)
        if why is None:
            return got
        got = why
    if got is not None:
        _say(f"rnhql: {kind.what} cache {path} cannot be used ({got}); rebuilding it")
    arrays = build()
    _write(path, kind, key, arrays)
    return arrays
