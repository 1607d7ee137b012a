"""Ctrl-C in the scenarios layer: one way to route SIGINT for the length of a block.

Long loops (physics training) turn the first Ctrl-C into a flag they act on between
steps; a file being finished ignores it for that moment. Either way SIGINT is only
rerouted from the main thread, and not where it is ignored on purpose (a pool worker:
its parent owns Ctrl-C), and the old handler is always restored.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Callable, Iterator
from typing import Any

Handler = Callable[[int, Any], Any] | int


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
