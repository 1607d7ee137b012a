"""Work done across a sweep's processes, in episodes: what progress and its estimate read.

A sweep's progress counted in finished runs stands still while a physics batch (every
physics run of a sweep, one task) or a long run trains, and its estimate counted the first
run's compilation as work. Each training loop adds the episodes it finishes to one
counter shared by every worker process (:func:`share` in each worker, from the pool's
initializer), so :class:`scenarios.sweep.backends.Progress` can say how much of the
sweep's episodes are done and estimate the rest from the recent rate.

The same shared block counts the workers that are *warming up*: running the first task
of a method in their process, which on a cold numba cache is mostly compiling (tens of
seconds for some methods, during which the other worker's episodes flow at a rate no
later minute will see). While any worker warms up, the estimate is withheld and its
rate window restarts (:meth:`Progress.eta_s`): a time left extrapolated from a compile
was 8x too long on the main command.

The block's lock is shared by the processes, and a worker ended by a signal (the sweep
ends its workers mid-run) can die holding it: so the counts are read without the lock (an
aligned 8-byte integer is read whole), and a worker waits for the lock at most
:data:`LOCK_WAIT_S` (progress is a display; a sweep must never wait on it).
"""

from __future__ import annotations

import contextlib
import multiprocessing
from collections.abc import Iterable, Iterator
from typing import Any

EPISODES, WARMING, PHYSICS = 0, 1, 2  # slots of the shared block: episodes (every world),
#                                      workers warming up, physics episodes among them
LOCK_WAIT_S = 1.0  # a worker waits this long for the block's lock, then counts nothing [s]

_shared: Any = None  # a multiprocessing.Array("q", 2) while a sweep runs, else None
_warm: set[str] = set()  # methods whose first task ran in this process
_warming_here = False  # this process counts in the WARMING slot right now


def new_counter() -> Any:
    """The block of counters worker processes share (passed to the pool's initializer):
    episodes finished, workers warming up, physics episodes finished."""
    return multiprocessing.Array("q", 3)


def share(counter: Any) -> None:
    """Make ``counter`` this process's shared block (None: count nothing). A process that
    joins a sweep warms every method up again: its kernels are not loaded yet."""
    global _shared, _warming_here
    _shared = counter
    _warm.clear()
    _warming_here = False


def episodes(counter: Any) -> int:
    """The episodes ``counter`` holds, read without its lock (see the module's doc)."""
    return int(counter.get_obj()[EPISODES])


def physics_episodes(counter: Any) -> int:
    """The physics episodes ``counter`` holds (a part of :func:`episodes`)."""
    return int(counter.get_obj()[PHYSICS])


def warming(counter: Any) -> int:
    """How many processes are in the first task of a method right now (read without the
    lock)."""
    return int(counter.get_obj()[WARMING])


def _add(slot: int, n: int) -> None:
    c = _shared
    if c is None or not n:
        return
    lock = c.get_lock()
    if lock.acquire(timeout=LOCK_WAIT_S):
        try:
            c.get_obj()[slot] += n
        finally:
            lock.release()


def add_episodes(n: int, physics: bool = False) -> None:
    """``n`` more episodes finished in this process (a no-op outside a sweep); ``physics``:
    physics episodes, which cost hundreds of times a grid episode, so progress estimates
    each world from its own rate. The first episodes of a warming task end its warm-up: its
    training kernel is compiled by then (the greedy-test loops compile within its first
    chunk too)."""
    _end_warming()
    _add(EPISODES, n)
    if physics:
        _add(PHYSICS, n)


def _end_warming() -> None:
    global _warming_here
    if _warming_here:
        _warming_here = False
        _add(WARMING, -1)


@contextlib.contextmanager
def warm_up(methods: Iterable[str]) -> Iterator[None]:
    """Count this process as warming up while a task runs the first time any of
    ``methods`` runs here, until its first episodes finish (or the task ends)."""
    global _warming_here
    new = set(methods) - _warm
    if new and _shared is not None and not _warming_here:
        _warm.update(new)
        _warming_here = True
        _add(WARMING, 1)
    try:
        yield
    finally:
        _end_warming()


class CountingObserver:
    """A grid training observer that counts episodes per chunk and forwards to ``inner``
    (the recorder's observer, or None)."""

    def __init__(self, inner: Any = None) -> None:
        self.inner = inner

    @property
    def wants_state(self) -> bool:
        """Whether ``after_chunk`` reads the learner's state (a plain learner's costs a
        greedy call per cell to build)."""
        return self.inner is not None

    def trace_chunk(self, done: int, n: int) -> bool:
        return self.inner is not None and self.inner.trace_chunk(done, n)

    def after_chunk(self, start: int, n: int, *args: Any) -> None:
        add_episodes(n)
        if self.inner is not None:
            self.inner.after_chunk(start, n, *args)
