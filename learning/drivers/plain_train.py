"""A plain-Python learner trained on a tabular model: the fused kernel's loop, in Python.

:func:`train_plain` is :func:`learning.drivers.train.train_tabular` for a learner of
:mod:`learning.plain.learner`: the same episodes (starts drawn from the start stream with
``integers(0, len(starts))``, as the kernels draw them), the same time limit and
bootstrapping rule, the same greedy test from S every ``test_every`` episodes, and the
same :class:`learning.drivers.train.TrainResult`. Only the speed differs: each step is two Python
calls into the learner (``rnhql bench`` style figures: ``scenarios/bench/plain.py``), unless
the learner is a numba ``@jitclass``: its episodes then run in one compiled loop
(:mod:`learning.plain.compiled`).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from learning.compiled.kernels import NO_TRACE
from learning.drivers.train import (
    TrainObserver,
    TrainResult,
    episode_arrays,
    finished,
    train_tabular,
)
from learning.geometry import TabularMDP, geometry_of
from learning.plain.compiled import is_jit_learner
from learning.plain.compiled import run_episodes as compiled_episodes
from learning.plain.learner import (
    PlainAgent,
    PlainConfig,
    checked_action,
    greedy_walk,
    is_plain,
    learner_calls,
    new_learner,
    snapshot,
)


def _episodes(learner, model: TabularMDP, n: int, start_rng: np.random.Generator,
              arrays: dict[str, np.ndarray], first: int, trace: np.ndarray) -> int:
    """Episodes ``first .. first + n - 1``, as :func:`learning.compiled.kernels._episodes`
    runs them."""
    next_state, reward, terminal = model.next_state, model.reward, model.terminal
    starts = model.start_states
    n_actions = int(next_state.shape[1])
    max_steps = int(model.max_steps)
    act, update = learner.act, learner.update
    begin = getattr(learner, "episode_start", None)
    tracing = trace.shape[0] > 0
    total = 0
    for i in range(n):
        s = int(starts[start_rng.integers(0, starts.shape[0])])
        if tracing:
            trace[i, 0] = s
        if begin is not None:
            begin()
        ret, t, done = 0.0, 0, False
        while t < max_steps:
            a = act(s)
            if type(a) is not int or not 0 <= a < n_actions:
                a = checked_action(learner, s, a, n_actions)
            s2 = int(next_state[s, a])
            r = float(reward[s, a])
            done = bool(terminal[s2])
            t += 1
            update(s, a, r, s2, done)
            ret += r
            s = s2
            if tracing:
                trace[i, t] = s
            if done:
                break
        arrays["steps"][first + i] = t
        arrays["returns"][first + i] = ret
        arrays["success"][first + i] = done
        total += t
    return total


def train_plain(cfg: PlainConfig, model: TabularMDP, n_episodes: int, rng: np.random.Generator,
                test_every: int = 10, observer: TrainObserver | None = None,
                start_rng: np.random.Generator | None = None) -> TrainResult:
    """Train a fresh ``cfg.learner(n_states, n_actions, rng)`` for ``n_episodes`` episodes.

    ``rng`` is the learner's stream; starts come from ``start_rng`` (default ``rng``).
    ``result.state`` is the final greedy policy as a :mod:`learning.plain.policy`;
    ``result.learner`` the trained learner itself.
    """
    if test_every < 1:
        raise ValueError(f"test_every must be >= 1, got {test_every}")
    geom = geometry_of(model)
    learner = new_learner(cfg, geom, rng)
    start_rng = rng if start_rng is None else start_rng
    arrays = episode_arrays(n_episodes)
    tests_e: list[int] = []
    tests_l: list[int] = []
    done = env_steps = 0
    n_states, n_actions = geom.n_states, geom.n_actions
    compiled = is_jit_learner(learner)  # a @jitclass: its episodes run in a compiled loop
    while done < n_episodes:
        n = min(test_every - done % test_every, n_episodes - done)
        trace = NO_TRACE
        if observer is not None and observer.trace_chunk(done, n):
            trace = np.full((n, int(model.max_steps) + 1), -1, dtype=np.int32)
        t0 = time.perf_counter()
        with learner_calls(learner):  # its failure is the run's, said in one line
            if compiled:
                steps, bad_s, bad_a = compiled_episodes(learner, model, n, start_rng,
                                                        arrays, done, trace)
                if bad_s >= 0:
                    checked_action(learner, bad_s, bad_a, n_actions)  # raises, naming it
                env_steps += steps
            else:
                env_steps += _episodes(learner, model, n, start_rng, arrays, done, trace)
        arrays["wall_time_s"][done:done + n] = (time.perf_counter() - t0) / n
        done += n
        with learner_calls(learner):
            test = greedy_walk(learner, model.next_state, model.terminal, int(model.start),
                               int(model.max_steps))
        tests_e.append(done)
        tests_l.append(test[0])
        if observer is not None:  # (an observer that says it reads no state gets None)
            wants = getattr(observer, "wants_state", True)
            observer.after_chunk(done - n, n, trace if trace.shape[0] else None, arrays,
                                 snapshot(learner, cfg, n_states, n_actions) if wants
                                 else None, test)
    st = snapshot(learner, cfg, n_states, n_actions)
    result = finished(cfg, st, model, done, env_steps, arrays, tests_e, tests_l)
    result.agent = PlainAgent(cfg, learner, st)  # type: ignore[attr-defined]
    return result


def train_grid(cfg: Any, model: TabularMDP, n_episodes: int, rng: np.random.Generator,
               test_every: int = 10, observer: TrainObserver | None = None,
               start_rng: np.random.Generator | None = None,
               resume: Any = None) -> TrainResult:
    """A grid run of any learner: the one place that chooses between a plain-Python learner
    (:func:`train_plain`) and a compiled method (:func:`learning.drivers.train.train_tabular`,
    the only one that resumes a checkpoint)."""
    if is_plain(cfg):
        if resume is not None:
            raise ValueError(f"{cfg.name} is a plain-Python learner: it has no checkpoint "
                             "to resume")
        return train_plain(cfg, model, n_episodes, rng, test_every, observer, start_rng)
    return train_tabular(cfg, model, n_episodes, rng, test_every, resume=resume,
                         observer=observer, start_rng=start_rng)
