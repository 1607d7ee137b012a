"""A sweep's resume state read back like any input: checked, and one line when it is damaged.

``runs.partial.jsonl`` (a line per finished run) and ``results.json`` (a finished sweep)
are what ``--resume`` trusts to skip runs; the lock file says who owns the folder. Each
can be damaged (an edit, a disk error, a folder created under its name) and before this
module a damaged one surfaced as a traceback, or worse, as a NaN in the summary. Now a
file that is not what rnhql wrote raises :class:`ResumeStateError` (an input error: one
line, exit 2) naming the file, the line and how to repair it. The one exception is a torn
*last* line of ``runs.partial.jsonl``: a process killed mid-write leaves exactly that,
and the run on it is simply run again.
"""

from __future__ import annotations

import json
import math
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

from scenarios.sweep.outdir import LOCK_NAME, OutDirError

PARTIAL = "runs.partial.jsonl"
RESULTS = "results.json"
# the largest resume file read: a 10,000-seed sweep's partial runs are far below it
MAX_STATE_BYTES = 1024 * 1024 * 1024


class ResumeStateError(OutDirError):
    """A resume file (partial runs, results, lock) that is not what rnhql wrote."""


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number rnhql writes")


def _finite(value: Any) -> bool:
    """Whether every number in ``value`` (nested) is finite (``json`` reads 1e999 as inf)."""
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, dict):
        return all(_finite(v) for v in value.values())
    if isinstance(value, list):
        return all(_finite(v) for v in value)
    return True


def parse_record(text: str) -> dict[str, Any]:
    """One finished run from a line of JSON; ValueError says why it is not one."""
    try:
        rec = json.loads(text, parse_constant=_refuse_constant)
    except RecursionError:
        raise ValueError("nested too deeply") from None
    if not isinstance(rec, dict):
        raise ValueError(f"holds {type(rec).__name__}, not a run's record")
    if not isinstance(rec.get("key"), str) or not rec["key"]:
        raise ValueError("has no run key")
    if not _finite(rec):
        raise ValueError("holds a non-finite number")
    return rec


_INT, _NUM = (int,), (int, float)
# what a comparison's summary and figures read of each run: field -> (types, None allowed)
COMPARE_FIELDS: dict[str, tuple[tuple[type, ...], bool]] = {
    "method": ((str,), False), "world": ((str,), False), "seed": (_INT, False),
    "final_route_length": (_INT, False), "optimal_route_length": (_INT, False),
    "final_route_optimal": ((bool,), False), "episodes_to_stable_optimal": (_INT, True),
    "episodes_to_optimal": (_INT, True), "optimal_test_fraction": (_NUM, True),
    "epsilon_route_length": (_NUM, True), "success_rate": (_NUM, False),
    "reward_per_step": (_NUM, False), "reward_per_step_last_10pct": (_NUM, False),
    "wall_time_s": (_NUM, False), "env_steps": (_INT, False),
    "optimal_action_fraction": (_NUM, False),
}
COMPARE_SERIES = ("steps_per_episode", "return_per_episode", "success_per_episode",
                  "test_episodes", "test_route_length")  # lists of numbers


def check_compare_record(rec: dict[str, Any]) -> None:
    """A comparison's run holds every field its summary and figures read, each of its type;
    ValueError names the first that does not (a hand-edited run surfaced as a traceback in
    the summary)."""
    check_summary_fields(rec)
    for name in COMPARE_SERIES:
        v = rec.get(name)
        if not isinstance(v, list) or not all(isinstance(x, _NUM) for x in v):
            raise ValueError(f"field {name!r} is not a list of numbers")


def check_summary_fields(rec: dict[str, Any]) -> None:
    """The fields of a run the summary reads (a study that keeps no per-episode series
    checks only these)."""
    for name, (types, nullable) in COMPARE_FIELDS.items():
        if name not in rec:
            raise ValueError(f"has no field {name!r}")
        v = rec[name]
        if v is None and nullable:
            continue
        if not isinstance(v, types) or (isinstance(v, bool) and bool not in types):
            raise ValueError(f"field {name!r} is {v!r}, not a {types[-1].__name__}")


def check_state_file(path: Path, flag: str = "--out") -> None:
    """Refuse a resume file's name taken by something that is not a regular file (a folder
    named ``results.json``): rnhql would fail on it only after every run."""
    if (path.exists() or path.is_symlink()) and not path.is_file():
        raise ResumeStateError(str(path), flag, "is not a regular file (a folder or device "
                               "under the name of rnhql's own file)",
                               f"remove or rename it, or use a new {flag}")


def check_out_files(out_dir: Path, flag: str = "--out") -> None:
    """Every file a sweep writes into ``out_dir`` (and its lock) is a regular file or absent;
    checked before any work."""
    for name in (PARTIAL, RESULTS, "summary.md", LOCK_NAME):
        check_state_file(out_dir / name, flag)


def _read_text(path: Path) -> str:
    check_state_file(path, "--resume")
    try:
        size = path.stat().st_size
        if size > MAX_STATE_BYTES:
            raise ResumeStateError(str(path), "--resume", f"is {size:,} bytes, more than the "
                                   f"limit {MAX_STATE_BYTES:,}", "use a new --out")
        raw = path.read_bytes()
    except OSError as exc:
        raise ResumeStateError(str(path), "--resume", f"cannot be read ({exc.strerror})",
                               "check its permissions, or use a new --out") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise ResumeStateError(str(path), f"line {line}", "is not UTF-8 text",
                               "delete that line (its run is run again) or the file, then "
                               "run again with --resume") from None


def finished_compare(out_dir: Path, check: Callable[[dict[str, Any]], None] =
                     check_compare_record) -> dict[str, dict[str, Any]]:
    """The runs of a finished comparison in ``out_dir`` (its ``results.json``), by key; a
    ``results.json`` that is not one of rnhql's (``check`` says what a run must hold) is
    refused with one line."""
    path = out_dir / RESULTS
    if not path.exists() and not path.is_symlink():
        return {}
    text = _read_text(path)
    fix = (f"move {path} away (the runs it holds are then run again) or use a new --out")
    try:
        doc = json.loads(text, parse_constant=_refuse_constant)
    except (ValueError, RecursionError) as exc:
        raise ResumeStateError(str(path), "--resume", f"is not valid JSON ({exc})",
                               fix) from None
    runs = doc.get("runs") if isinstance(doc, dict) else None
    if not isinstance(runs, list):
        raise ResumeStateError(str(path), "runs", "is missing: not an rnhql results file", fix)
    done: dict[str, dict[str, Any]] = {}
    for i, rec in enumerate(runs):
        try:
            rec = parse_record(json.dumps(rec, allow_nan=True))
            check(rec)
        except ValueError as exc:
            raise ResumeStateError(str(path), f"runs[{i}]", str(exc), fix) from None
        done[rec["key"]] = rec
    return done


Finished = Callable[[Path], dict[str, dict[str, Any]]]


def read_partial(out_dir: Path, finished: Finished | None = None,
                 check: Callable[[dict[str, Any]], None] | None = None
                 ) -> dict[str, dict[str, Any]]:
    """Finished runs, by key: those of a finished sweep (``finished``; by default its
    ``results.json``), then those of an interrupted one. So ``--resume`` after a sweep that
    finished re-runs nothing of it (an extended sweep runs only what is new). A torn last
    line (a write cut short) is ignored; any other line that is not a run (``check`` says
    what a run holds: by default a comparison's whole record, nothing for a study with its
    own ``finished``) is refused."""
    path = out_dir / PARTIAL
    if check is None and finished is None:  # a comparison keeps whole records
        check = check_compare_record
    done = (finished or finished_compare)(out_dir)
    if not path.exists() and not path.is_symlink():
        return done
    text = _read_text(path)
    lines = text.split("\n")
    for i, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            rec = parse_record(line)
            if check is not None:
                check(rec)
        except ValueError as exc:
            if i == len(lines):  # no newline after it: the write was cut short
                continue
            raise ResumeStateError(str(path), f"line {i}", str(exc),
                                   "delete that line (its run is run again) or the file, "
                                   "then run again with --resume") from None
        done[rec["key"]] = rec
    return done


def tidy_parts(record: str | None, finished: int) -> str | None:
    """Remove what ``--resume`` cannot use: half-written ``.part`` files, and the whole parts
    folder when no finished run's recording is in it. The folder kept, or None."""
    if record is None:
        return None
    parts = Path(record + ".parts")
    if not parts.is_dir():
        return None
    for half in parts.glob("*.part"):
        half.unlink(missing_ok=True)
    if finished and any(parts.glob("*.rrd")):
        return str(parts)
    shutil.rmtree(parts, ignore_errors=True)
    return None
