"""Ctrl-C while Chipmunk calls back into Python: deferred to a safe point, never lost.

A physics step runs in C and calls the collision handler (Python) through cffi.
Python delivers a pending SIGINT at the next bytecode, which may be inside that
callback; a ``KeyboardInterrupt`` raised there is swallowed by cffi (printed,
then ignored) or leaves Chipmunk mid-step. So while the physics world exists,
SIGINT goes through :func:`_handler`: inside a callback it only records the
request, and :func:`raise_if_deferred` (called right after the step, where the
callback's contact is flushed) raises the ``KeyboardInterrupt`` in plain Python.
Anywhere else it behaves exactly like Python's default handler.
"""

from __future__ import annotations

import signal
import threading
from types import FrameType
from typing import Any

_deferred = [False]
_callback_codes: set[Any] = set()


def _inside_callback(frame: FrameType | None) -> bool:
    while frame is not None:
        if frame.f_code in _callback_codes or "/pymunk/" in frame.f_code.co_filename:
            return True
        frame = frame.f_back
    return False


def _handler(signum: int, frame: FrameType | None) -> None:
    if _inside_callback(frame):
        _deferred[0] = True
        return
    signal.default_int_handler(signum, frame)


def install(*callbacks: Any) -> None:
    """Route SIGINT through :func:`_handler` (main thread, default handler only: a
    pool worker that ignores SIGINT, or a caller with its own handler, is left alone)."""
    for cb in callbacks:
        _callback_codes.add(getattr(cb, "__func__", cb).__code__)
    if threading.current_thread() is not threading.main_thread():
        return
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _handler)


def raise_if_deferred() -> None:
    """Raise the ``KeyboardInterrupt`` a callback deferred, if any."""
    if _deferred[0]:
        _deferred[0] = False
        raise KeyboardInterrupt


def take_deferred() -> bool:
    """Whether a callback deferred a ``KeyboardInterrupt`` (clearing it): for a caller that
    routes SIGINT its own way from now on (a training loop's stop flag), so a Ctrl-C that
    arrived while the world was being built is not lost when no later step raises it."""
    deferred, _deferred[0] = _deferred[0], False
    return deferred
