"""Ctrl-C in the scenarios layer: one way to route SIGINT for the length of a block.

Long loops (physics training) turn the first Ctrl-C into a flag they act on between
steps; a file being finished ignores it for that moment. Either way SIGINT is only
rerouted from the main thread, and not where it is ignored on purpose (a pool worker:
its parent owns Ctrl-C), and the old handler is always restored. A block whose Python
callbacks drop exceptions (forking a pool's workers) holds Ctrl-C, SIGTERM and SIGHUP
until it ends (:func:`stop_signals_held`), and so does every numba compile in the main
thread, from the moment ``scenarios.runs`` is imported
(:func:`hold_stop_signals_while_compiling`): LLVM calls back into Python while it
compiles, and an exception raised there is dropped.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Callable, Iterator
from typing import Any

Handler = Callable[[int, Any], Any] | int
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


@contextlib.contextmanager
def sigint_handled_by(handler: Handler, *, unless_ignored: bool = True) -> Iterator[None]:
    """SIGINT goes to ``handler`` (a function or ``signal.SIG_IGN``) while the block runs.
    ``unless_ignored``: leave a process that ignores SIGINT (a pool worker) alone."""
    if threading.current_thread() is not threading.main_thread() or (
            unless_ignored and signal.getsignal(signal.SIGINT) is signal.SIG_IGN):
        yield
        return
    old = signal.signal(signal.SIGINT, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


@contextlib.contextmanager
def stop_signals_held() -> Iterator[None]:
    """Ctrl-C, SIGTERM and SIGHUP are noted while the block runs and acted on as it ends
    (their handlers called then: the first one's raises), for a block that runs Python
    callbacks which print an exception and drop it. Forking does: a handler that ran in
    an at-fork callback (logging's, Rerun's) raised there, and the signal was lost (a
    sweep signalled as its pool started ran to its end). A forked child starts with the
    noting handlers too, so a signal to the whole group is harmless in it until its own
    initializer sets its signals. Main thread only; signals that have no Python handler
    (ignored, or default) are left as they are."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    noted: list[tuple[int, Any]] = []
    old = {sig: signal.getsignal(sig) for sig in STOP_SIGNALS}
    held = {sig: h for sig, h in old.items() if callable(h)}
    for sig in held:
        signal.signal(sig, lambda s, frame: noted.append((s, frame)))
    try:
        yield
    finally:
        for sig, h in held.items():
            signal.signal(sig, h)
    for sig, frame in noted[:1]:
        held[sig](sig, frame)


class _HeldWhileCompiling:
    """What numba's compiler-lock listener does: :func:`stop_signals_held` from the moment
    the main thread asks for the lock until it gives the outermost one back. While numba
    compiles or loads a kernel from its disk cache, LLVM calls back into Python through
    ctypes; a ``KeyboardInterrupt`` raised in such a callback is printed and dropped, and
    LLVM goes on with a missing object: "no compiled object yet", or a segmentation fault
    (exit -11, seen in CI on a Ctrl-C during a cold sweep's compile). Held, the signal is
    acted on as the lock is released, in plain Python."""

    def __init__(self) -> None:
        self._depth = 0
        self._held: contextlib.ExitStack | None = None

    def on_start(self, _event: Any) -> None:
        if threading.current_thread() is not threading.main_thread():
            return  # handlers run in the main thread only: never in another's callback
        self._depth += 1
        if self._depth == 1:
            self._held = contextlib.ExitStack()
            self._held.enter_context(stop_signals_held())

    def on_end(self, _event: Any) -> None:
        if threading.current_thread() is not threading.main_thread() or self._depth == 0:
            return
        self._depth -= 1
        if self._depth == 0 and self._held is not None:
            held, self._held = self._held, None
            held.close()  # a held signal's handler runs (and raises) here


_compile_guard: list[Any] = []


def hold_stop_signals_while_compiling() -> None:
    """From now on, Ctrl-C, SIGTERM and SIGHUP that arrive while numba compiles in the main
    thread are acted on when the compile ends (a second or so later), not inside it. Once
    per process (a forked worker inherits it); imports numba."""
    if _compile_guard:
        return
    from numba.core import event

    class Guard(_HeldWhileCompiling, event.Listener):
        pass

    guard = Guard()
    event.register("numba:compiler_lock", guard)
    _compile_guard.append(guard)
