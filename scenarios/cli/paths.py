"""The command line's output paths, checked before any work: empty paths, folders where a
file goes, device nodes and FIFOs (written through, never replaced), unwritable folders,
and the default recording's file name.

Every check raises :class:`sim.errors.InputError` (one line naming the flag and the fix);
:mod:`scenarios.cli.app` prints it and exits 2.
"""

from __future__ import annotations

import argparse
import os
import re
from pathlib import Path

from scenarios.runs.spec import ExperimentError
from sim.errors import InputError
from sim.files import check_output, node_kind

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
