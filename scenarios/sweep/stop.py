"""A sweep stopped by Ctrl-C, SIGTERM or SIGHUP: what is kept, what is said, what is removed.

The runs finished so far stay in ``runs.partial.jsonl`` and the recording holds them (its
parts stay for ``--resume`` to merge at the end), and one line says so. Nothing is left
that ``--resume`` cannot use: half-written parts go, the parts folder goes when no
finished run's recording is in it, and when no run had finished at all there is nothing
to resume: the empty ``runs.partial.jsonl`` goes too, as does the output folder when
this sweep created it and it is empty, and the line says to run the command again.
Stopped while the finished runs are merged into the recording (SIGTERM, SIGHUP: Ctrl-C
there only says so), the parts stay for ``--resume`` to merge, and the line says so.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator, Sequence
from pathlib import Path

from scenarios.runs.spec import RunSpec
from scenarios.sweep.recording import SweepRecording, gather_parts
from scenarios.sweep.resume_state import PARTIAL, Finished, read_partial, tidy_parts


def interrupted(err: BaseException) -> bool:
    """Whether ``err`` was caused by a Ctrl-C (a KeyboardInterrupt in its cause chain)."""
    seen = set()
    e: BaseException | None = err
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return False


@contextlib.contextmanager
def finishing(record: str) -> Iterator[None]:
    """While the finished runs are merged into the recording (seconds), a first Ctrl-C only
    says so; a second one abandons the recording (its partial file removed) with 130."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pressed = [False]

    def on_sigint(_sig: int, _frame: object) -> None:
        if pressed[0]:
            Path(record + ".part").unlink(missing_ok=True)
            os._exit(130)
        pressed[0] = True
        print("\nrnhql: all runs are finished; writing the recording (a few seconds). Ctrl-C "
              "again abandons it", file=sys.stderr)

    old = signal.signal(signal.SIGINT, on_sigint)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def tell(line: str) -> None:
    """A line on stderr that may be gone (SIGHUP: the terminal closed, writes fail with
    EIO): what is kept must be kept all the same."""
    with contextlib.suppress(OSError, ValueError):
        print(line, file=sys.stderr, flush=True)


@contextlib.contextmanager
def removed_if_left_empty(out_dir: Path) -> Iterator[None]:
    """An output folder this sweep creates is removed again when the sweep is stopped and
    nothing was kept in it (only ever an empty folder)."""
    made = not os.path.lexists(out_dir)
    try:
        yield
    except KeyboardInterrupt:
        if made:
            with contextlib.suppress(OSError):
                out_dir.rmdir()
        raise


def keep_finished(specs: Sequence[RunSpec], out_dir: Path,
                  recording: SweepRecording | None, finished: Finished | None) -> None:
    """After Ctrl-C: say what was kept, write the recording of the runs done so far, remove
    what ``--resume`` cannot use (the module's doc). A second Ctrl-C while this runs exits
    at once (status 130)."""
    main = threading.current_thread() is threading.main_thread()
    old = signal.signal(signal.SIGINT, lambda *_: os._exit(130)) if main else None
    try:
        done = read_partial(out_dir, finished)
        over = [s for s in specs if s.key in done]
        parts = tidy_parts(None if recording is None else recording.path, len(over))
        if not over:
            (out_dir / PARTIAL).unlink(missing_ok=True)
            tell(f"\ninterrupted: none of the {len(specs)} runs had finished, so nothing was "
                 "kept; run the command again")
            return
        tell(f"\ninterrupted: {len(over)} of {len(specs)} runs finished, kept in "
             f"{out_dir / PARTIAL}; finish with the same command and --resume")
        if recording is not None and over:
            gather_parts(over, recording.path, keep_parts=True,
                         records=list(done.values()))
            tell(f"recording of the finished runs: {recording.path}"
                 + (f" (their parts stay in {parts}/ for --resume)" if parts else ""))
    finally:
        if main:
            signal.signal(signal.SIGINT, old)


def merge_stopped(record: str) -> None:
    """Stopped while every run's recording was being merged (the results are written)."""
    tell(f"\ninterrupted while writing the recording: every run finished and its results "
         f"are written; the recording's parts stay in {record}.parts/: run the same command "
         "with --resume to merge them")
