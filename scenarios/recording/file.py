"""The file side of a recording: an explicit stream, a ``.part`` file, a safe close.

See :mod:`scenarios.recording.recorder` for the recording API.
"""

from __future__ import annotations

import atexit
import contextlib
import errno
import os
import signal
import subprocess
import threading
import uuid
import warnings
from pathlib import Path
from typing import Protocol

import rerun as rr

from scenarios.recording.viewer import rerun_cli
from scenarios.signals import sigint_handled_by
from sim.errors import InputError
from sim.files import move_into_place, no_space_left


class _Flushable(Protocol):
    prefix: str

    def flush(self) -> None: ...


def verify_recording(path: str | Path, check_footers: bool = True) -> tuple[bool, str]:
    """Run ``rerun rrd verify`` on a file; (ok, combined output)."""
    cmd = [rerun_cli(), "rrd", "verify", f"--check-footers={str(check_footers).lower()}",
           str(path)]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    return out.returncode == 0, (out.stdout + out.stderr).strip()


def _no_sigint() -> contextlib.AbstractContextManager[None]:
    """Ignore Ctrl-C for the moment it takes to finish a file (main thread only)."""
    return sigint_handled_by(signal.SIG_IGN, unless_ignored=False)


FLUSH_TIMEOUT_S = 600.0  # a flush that takes longer has hung (Rerun's writer on a full disk)


FLUSH_STEP_S = 2.0  # the flush is waited for in steps, the disk checked between them


class RecordingWriteError(OSError):
    """The recording could not be written (full disk, file removed); its partial file is gone.
    A full disk is said as such (``errno.ENOSPC``), whatever Rerun's writer reported."""

    def __init__(self, path: Path, cause: BaseException | str) -> None:
        reason = cause if isinstance(cause, str) else (getattr(cause, "strerror", None)
                                                        or str(cause))
        full = no_space_left(path)
        if full:
            reason = os.strerror(errno.ENOSPC)
        super().__init__(errno.ENOSPC if full else errno.EIO,
                         f"{path}: the recording could not be written ({reason}); its partial "
                         "file was removed. Fix: free some space or record elsewhere",
                         str(path))
        self.path = path
        self.reason = reason

    def __reduce__(self):  # a pool worker's error must unpickle in the parent, or the pool
        return _rebuild_write_error, (str(self.path), self.errno, self.strerror)  # breaks


def _rebuild_write_error(path: str, code: int, text: str) -> OSError:
    err = OSError(code, text, path)
    return err


def _flush(stream: rr.RecordingStream, part: Path) -> None:
    """Flush ``stream`` to its file, waiting at most :data:`FLUSH_TIMEOUT_S`; a writer that
    stops because the disk is full raises ENOSPC at once instead of waiting out the limit
    (with Ctrl-C held meanwhile: that was a hang)."""
    waited = 0.0
    while True:
        try:
            stream.flush(timeout_sec=FLUSH_STEP_S)
            return
        except Exception as exc:  # Rerun raises on a timeout or a dead writer
            if no_space_left(part):
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(part)) from None
            waited += FLUSH_STEP_S
            if waited >= FLUSH_TIMEOUT_S or "time" not in str(exc).lower():
                raise


CLOSE_AFTER_FAILURE_S = 5.0  # a stream whose writer already failed gets this long to let go


def _disconnect(stream: rr.RecordingStream, part: Path, limit_s: float) -> None:
    """Disconnect ``stream`` from its file in a helper thread, waiting at most ``limit_s``.

    Why a thread: when Rerun's file writer stops on a full disk while a flush is pending,
    ``disconnect`` waits in Rust for an answer that never comes, with Ctrl-C unheard (seen
    1 run in 5 of a recorded sweep on a full disk). The stuck thread is a daemon and keeps
    the stream alive, so the stream is never dropped (its drop would wait the same way);
    Rerun's own at-exit shutdown is taken off for the same reason.
    """
    failure: list[BaseException] = []

    def work() -> None:
        try:
            stream.disconnect()
        except BaseException as exc:
            failure.append(exc)

    helper = threading.Thread(target=work, name="rnhql-recording-close", daemon=True)
    helper.start()
    waited = 0.0
    while helper.is_alive():
        helper.join(FLUSH_STEP_S)
        waited += FLUSH_STEP_S
        if helper.is_alive() and (waited >= limit_s or no_space_left(part)):
            _ABANDONED.append(helper)
            rr.unregister_shutdown()  # its at-exit flush would wait on this stream forever
            full = no_space_left(part)
            raise OSError(errno.ENOSPC if full else errno.EIO,
                          os.strerror(errno.ENOSPC) if full
                          else "Rerun's writer did not let go of the file", str(part))
    if failure:
        raise failure[0]


_ABANDONED: list[threading.Thread] = []  # closes that never returned (see _disconnect)


class RecordingFile:
    """An explicit RecordingStream with a file sink at ``<path>.part``, renamed on close."""

    def __init__(self, path: str | Path, *, application_id: str = "rnhql",
                 recording_id: str | None = None, recording_name: str | None = None) -> None:
        self.path = Path(path)
        self.part = self.path.with_name(self.path.name + ".part")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.stream = rr.RecordingStream(application_id,
                                         recording_id=recording_id or str(uuid.uuid4()))
        self.stream.set_log_tick_enabled(False)
        self.stream.set_log_time_enabled(False)
        # a name planted where the part goes (a symlink, a hard link to another file) is
        # removed, not written through: the sink then creates the file afresh
        if self.part.is_symlink() or self.part.exists():
            self.part.unlink()
        self.stream.save(self.part)
        if recording_name:
            self.stream.send_recording_name(recording_name)
        self._recorders: list[_Flushable] = []  # flushed before the file is closed
        self._pid = os.getpid()  # a forked child must not finish the parent's file
        self.closed = False
        atexit.register(self.close)

    def close(self) -> None:
        """Flush every attached recorder, write the footer, rename. Safe to call twice."""
        if self.closed or os.getpid() != self._pid:
            return
        self.closed = True
        with _no_sigint():  # a second Ctrl-C must not leave the file half-finished
            for r in self._recorders:
                try:
                    r.flush()
                except Exception as exc:  # keep going: the file must still be finished
                    warnings.warn(f"recording: could not flush {r.prefix or 'run'}: {exc}",
                                  stacklevel=2)
            try:
                _flush(self.stream, self.part)
                _disconnect(self.stream, self.part, FLUSH_TIMEOUT_S)
                if not self.part.exists():
                    raise OSError(errno.EIO, "the recording's file is gone", str(self.part))
                move_into_place(self.part, self.path)
            except Exception as exc:  # e.g. a full disk: Rerun's writer stops
                with contextlib.suppress(Exception):
                    _disconnect(self.stream, self.part, CLOSE_AFTER_FAILURE_S)
                self.part.unlink(missing_ok=True)
                atexit.unregister(self.close)
                if isinstance(exc, InputError):  # the path itself (a FIFO nobody reads): one
                    raise  # line naming it, exit 2, like any other bad output path
                raise RecordingWriteError(self.path, exc) from None
        atexit.unregister(self.close)

    def __enter__(self) -> RecordingFile:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
