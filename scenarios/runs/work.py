"""Work done across a sweep's processes, in episodes: what progress and its estimate read.

A sweep's progress counted in finished runs stands still while a physics batch (every
physics run of a sweep, one task) or a long run trains, and its estimate counted the first
run's compilation as work. Each training loop adds the episodes it finishes to one
counter shared by every worker process (:func:`share` in each worker, from the pool's
initializer), so :class:`scenarios.runs.backends.Progress` can say how much of the
sweep's episodes are done and estimate the rest from the recent rate.

The counter's lock is shared by the processes, and a worker ended by a signal (the sweep
ends its workers mid-run) can die holding it: so the count is read without the lock (an
aligned 8-byte integer is read whole), and a worker waits for the lock at most
:data:`LOCK_WAIT_S` (progress is a display; a sweep must never wait on it).
"""

from __future__ import annotations

import multiprocessing
from typing import Any

_counter: Any = None  # a multiprocessing.Value("q") while a sweep runs, else None
LOCK_WAIT_S = 1.0  # a worker waits this long for the counter's lock, then counts nothing [s]


def new_counter() -> Any:
    """A counter of episodes that worker processes can share (passed to the pool's
    initializer)."""
    return multiprocessing.Value("q", 0)


def share(counter: Any) -> None:
    """Make ``counter`` this process's episode counter (None: count nothing)."""
    global _counter
    _counter = counter


def add_episodes(n: int) -> None:
    """``n`` more episodes finished in this process (a no-op outside a sweep)."""
    c = _counter
    if c is None or not n:
        return
    lock = c.get_lock()
    if lock.acquire(timeout=LOCK_WAIT_S):
        try:
            c.get_obj().value += n
        finally:
            lock.release()


def episodes(counter: Any) -> int:
    """The episodes ``counter`` holds, read without its lock (see the module's doc)."""
    return int(counter.get_obj().value)


class CountingObserver:
    """A grid training observer that counts episodes per chunk and forwards to ``inner``
    (the recorder's observer, or None)."""

    def __init__(self, inner: Any = None) -> None:
        self.inner = inner

    def trace_chunk(self, done: int, n: int) -> bool:
        return self.inner is not None and self.inner.trace_chunk(done, n)

    def after_chunk(self, start: int, n: int, *args: Any) -> None:
        add_episodes(n)
        if self.inner is not None:
            self.inner.after_chunk(start, n, *args)
