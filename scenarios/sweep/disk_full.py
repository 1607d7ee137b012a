"""A full disk in the middle of a sweep: one line that says so, what was kept, and nothing
left behind that ``--resume`` cannot use.

Why a module of its own: a full disk reaches a sweep from several writers (the parent's
``runs.partial.jsonl``, a worker's recording part, the merged recording at the end, a
worker that died of it), each with its own error; the sweep turns every one of them into
the same answer: an ``OSError`` (ENOSPC) naming the file that did not fit, whose text is
the whole line the CLI prints (exit 1), including how many runs finished and where they
are kept. Part files of runs that did not finish are removed; the parts folder stays only
when it holds finished runs' recordings that ``--resume`` merges at the end.
"""

from __future__ import annotations

import errno
from collections.abc import Sequence
from pathlib import Path

from scenarios.runs.spec import RunSpec
from scenarios.sweep.resume_state import PARTIAL, tidy_parts


def disk_full_error(err: OSError, out_dir: Path, specs: Sequence[RunSpec],
                    record: str | None, finished: int, all_runs_done: bool = False
                    ) -> OSError:
    """The one-line error for ``err`` (ENOSPC); cleans the recording's parts folder."""
    where = err.filename or str(out_dir)
    kept = tidy_parts(record, finished)
    if all_runs_done:
        tail = (f"every run finished and {out_dir / 'results.json'} is written; the "
                f"recording's parts are kept in {kept}: free some space and run the same "
                "command with --resume to merge them" if kept else
                f"every run finished and {out_dir / 'results.json'} is written")
    elif finished:
        tail = (f"{finished} of {len(specs)} runs finished and are kept in "
                f"{out_dir / PARTIAL}" + (f" (their recordings in {kept})" if kept else "")
                + ": free some space and run the same command with --resume")
    else:
        tail = "no run had finished: free some space and run the command again"
    text = f"{where}: cannot be written (no space left on device). Fix: {tail}"
    return OSError(errno.ENOSPC, text, where)
