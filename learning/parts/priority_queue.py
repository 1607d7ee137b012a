"""An indexed max-heap of state-action pairs, for prioritized sweeping (Moore & Atkeson 1993).

A pair is in the heap at most once (``where[j]`` is its slot, -1 if absent): pushing a
pair already queued raises its priority to the larger of the two instead of adding a
second entry. All arrays are allocated once (capacity: every pair), so a push or a pop
is O(log n) and allocates nothing.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit


class PairQueue(NamedTuple):
    key: np.ndarray  # float64[cap]; the priorities, heap-ordered (largest first)
    pair: np.ndarray  # int32[cap]; the flat pair s * nA + a in each slot
    where: np.ndarray  # int32[nS * nA]; the slot of each pair (-1: not queued)
    size: np.ndarray  # int64[1]; pairs queued


def new_pair_queue(n_pairs: int, n_counters: int = 1) -> PairQueue:
    """An empty queue for ``n_pairs`` pairs (``new_pair_queue(0, 0)``: no queue at all, for
    a learner that does not sweep)."""
    return PairQueue(np.zeros(n_pairs), np.zeros(n_pairs, np.int32),
                     np.full(n_pairs, -1, np.int32), np.zeros(n_counters, np.int64))


@njit(cache=True)
def _swap(key, pair, where, i, j):
    key[i], key[j] = key[j], key[i]
    pair[i], pair[j] = pair[j], pair[i]
    where[pair[i]] = i
    where[pair[j]] = j


@njit(cache=True)
def _up(key, pair, where, i):
    while i > 0:
        parent = (i - 1) >> 1
        if key[parent] >= key[i]:
            return
        _swap(key, pair, where, i, parent)
        i = parent


@njit(cache=True)
def _down(key, pair, where, size, i):
    while True:
        left = 2 * i + 1
        if left >= size:
            return
        big = left
        if left + 1 < size and key[left + 1] > key[left]:
            big = left + 1
        if key[i] >= key[big]:
            return
        _swap(key, pair, where, i, big)
        i = big


@njit(cache=True)
def push(key, pair, where, size, j, priority):
    """Queue pair ``j`` with ``priority`` (if queued already: the larger priority)."""
    i = where[j]
    if i >= 0:
        if priority > key[i]:
            key[i] = priority
            _up(key, pair, where, i)
        return
    n = size[0]
    key[n] = priority
    pair[n] = j
    where[j] = n
    size[0] = n + 1
    _up(key, pair, where, n)


@njit(cache=True)
def pop(key, pair, where, size):
    """The queued pair of largest priority, removed (-1 if the queue is empty)."""
    n = size[0]
    if n == 0:
        return -1
    top = pair[0]
    where[top] = -1
    n -= 1
    size[0] = n
    if n > 0:
        key[0] = key[n]
        pair[0] = pair[n]
        where[pair[0]] = 0
        _down(key, pair, where, n, 0)
    return top


@njit(cache=True)
def place(key, pair, where, size, j, priority):
    """Queue pair ``j`` with exactly ``priority``, raised or lowered if it is queued already
    (an incremental search re-keys a cell whose estimate rose as well as one whose fell)."""
    i = where[j]
    if i < 0:
        push(key, pair, where, size, j, priority)
        return
    old = key[i]
    key[i] = priority
    if priority > old:
        _up(key, pair, where, i)
    elif priority < old:
        _down(key, pair, where, size[0], i)


@njit(cache=True)
def drop(key, pair, where, size, j):
    """Take pair ``j`` out of the queue (nothing if it is not queued)."""
    i = where[j]
    if i < 0:
        return
    where[j] = -1
    n = size[0] - 1
    size[0] = n
    if i == n:
        return
    moved = pair[n]  # the last slot's pair fills the hole, then sifts either way
    key[i] = key[n]
    pair[i] = moved
    where[moved] = i
    _up(key, pair, where, i)
    _down(key, pair, where, n, where[moved])
