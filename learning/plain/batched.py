"""A plain learner that acts on a whole batch of runs in one call.

Why: a Python learner called once per robot per primitive pays the interpreter's price
for every one of them (``scenarios/bench/plain.py``); numpy or torch pay their own fixed
cost per call. A learner that declares ``batched = True`` is built once for the runs of a
lock-step physics batch (seeds x robots) and answers for all of them at once::

    class MyBatchedLearner:
        batched = True
        def __init__(self, n_states, n_actions, rngs): ...   # one Generator per run
        def act_batch(self, runs, states) -> actions: ...    # int arrays, one per run asked
        def update_batch(self, runs, states, actions, rewards, next_states, terminal): ...
        def greedy(self, run, state) -> int: ...             # the policy graded, no draws
        def episode_start_batch(self, runs): ...             # optional
        def greedy_all(self, run) -> actions: ...            # optional: every state's

``runs`` are the indices (into ``rngs``) of the runs the call is about: each run keeps its
own stream (``rngs[run]``) and its own starts, so a learner that draws per run what a
per-run learner draws runs the same runs (common random numbers;
``tests/plain_learners/st_ql_batched.py`` equals ``st-ql`` figure for figure). A grid run
is a batch of one (:class:`OneRun`). A learner may expose ``q`` as
``float[runs, n_states, n_actions]``; recordings then show run i's table.
"""

from __future__ import annotations

import inspect
from typing import Any

import numpy as np


class LearnerAnswerError(ValueError):
    """What a batched learner answered is not one action per run asked (raised as the
    run's :class:`learning.plain.learner.LearnerError` by the caller)."""


def is_batched(cls: Any) -> bool:
    return bool(getattr(cls, "batched", False))


def check_batched(cls: type, label: str) -> None:
    """Refuse a class that declares ``batched`` but lacks what a batched learner has."""
    missing = [m for m in ("act_batch", "update_batch", "greedy")
               if not callable(getattr(cls, m, None))]
    if missing:
        raise ValueError(f"{label} declares batched = True but has no {', '.join(missing)}: "
                         "a batched learner defines act_batch(runs, states), update_batch("
                         "runs, states, actions, rewards, next_states, terminal) and "
                         "greedy(run, state)")
    check_methods(cls, label, {"act_batch": "runs, states", "greedy": "run, state",
                               "update_batch": "runs, states, actions, rewards, "
                                               "next_states, terminal"})


def check_methods(cls: type, label: str, params: dict[str, str]) -> None:
    """Each method of ``params`` takes (self, its parameters): a ValueError naming the one
    that does not. One that has no signature to read (a builtin) is left to its first run."""
    for meth, names in params.items():
        try:
            inspect.signature(getattr(cls, meth)).bind(None, *range(names.count(",") + 1))
        except TypeError:
            raise ValueError(f"{label}.{meth} must take (self, {names})") from None
        except ValueError:
            pass


def actions_of(answer: Any, k: int, n_actions: int) -> np.ndarray:
    """``act_batch``'s answer as int64[k], or :class:`LearnerAnswerError` saying why not:
    integers only (a float array is not rounded), one per run asked, each in range."""
    a = np.asarray(answer) if not isinstance(answer, np.ndarray) else answer
    if a.shape != (k,) or a.dtype.kind not in "iu":
        raise LearnerAnswerError(f"returned {_short(answer)}, not {k} integer actions (one "
                                 "per run asked)")
    a = a.astype(np.int64, copy=False)
    if np.count_nonzero(a.view(np.uint64) >= n_actions):  # one test: negatives wrap high
        bad = np.flatnonzero((a < 0) | (a >= n_actions))
        raise LearnerAnswerError(f"returned action {a[bad[0]]!r} for the run at position "
                                 f"{int(bad[0])}, not an action in 0..{n_actions - 1}")
    return a


def _short(x: Any) -> str:
    text = repr(x)
    return text if len(text) <= 80 else text[:77] + "..."


class OneRun:
    """Run ``run`` of a batched learner, seen through the per-run protocol (``act``,
    ``update``, ``greedy``, ``episode_start``, ``q``): a grid run, a policy read for
    grading, a recording's Q table."""

    def __init__(self, batch: Any, run: int, n_actions: int) -> None:
        self.batch, self.run, self.n_actions = batch, int(run), int(n_actions)
        self._runs = np.array([self.run], dtype=np.int64)
        self._start = getattr(batch, "episode_start_batch", None)
        if self._start is not None:
            self.episode_start = self._episode_start
        self.label = type(batch).__qualname__

    @property
    def q(self) -> Any:
        q = getattr(self.batch, "q", None)
        return q[self.run] if isinstance(q, np.ndarray) and q.ndim == 3 else None

    def act(self, s: int) -> int:
        return int(actions_of(self.batch.act_batch(self._runs, np.array([s])), 1,
                              self.n_actions)[0])

    def update(self, s: int, a: int, r: float, s2: int, terminal: bool) -> None:
        self.batch.update_batch(self._runs, np.array([s]), np.array([a]), np.array([r]),
                                np.array([s2]), np.array([terminal]))

    def greedy(self, s: int) -> Any:
        return self.batch.greedy(self.run, s)

    def greedy_all(self) -> Any:
        """Every state's greedy action in one call (the batch's ``greedy_all``), or None."""
        fn = getattr(self.batch, "greedy_all", None)
        return None if fn is None else fn(self.run)

    def _episode_start(self) -> None:
        self._start(self._runs)

    def __repr__(self) -> str:
        return f"run {self.run} of {type(self.batch).__qualname__}"
