"""A plain learner written as a numba ``jitclass``: the same protocol, run inside a compiled
episode loop.

Why: a Python learner pays two interpreter calls a step (about 85 x slower than the
compiled methods in the grid, ``scenarios/bench/plain.py``). A ``@jitclass`` with the same
``__init__(n_states, n_actions, rng)``, ``act``, ``update``, ``greedy`` and optional
``episode_start`` needs nothing registered in the package: :func:`run_episodes` is one
``@njit`` loop that numba specialises on the learner's class when the run starts, so its
``act`` and ``update`` are compiled into the loop. The loop is compiled with
``cache=False``: numba's on-disk cache keys a function by its own file, and a user's class
changing under the same name must never meet a stale kernel there. A jitclass may hold the
run's ``rng`` as a field (``numba.typeof(np.random.default_rng())``); numba draws from the
same stream as Python, so a port that draws what a compiled method draws runs the same run.

An action out of range stops the loop and is reported as the run's failure (numba does
not check indices: an action of 4 would read another row's memory). A class that does not
compile is refused before any run (:func:`check_compiles`), in one line that names its
file and line (:func:`compile_message`), not numba's page of typing traces.
"""

from __future__ import annotations

import re
from pathlib import Path
from types import FunctionType
from typing import Any

import numpy as np
from numba import njit
from numba.core.errors import NumbaError


def is_jitclass(cls: Any) -> bool:
    """Whether ``cls`` is a numba ``@jitclass`` (its instances run inside compiled loops)."""
    try:
        from numba.experimental.jitclass.base import JitClassType
    except ImportError:  # pragma: no cover - numba without jitclass
        return False
    return isinstance(cls, JitClassType)


def is_jit_learner(learner: Any) -> bool:
    """Whether ``learner`` is an instance of a ``@jitclass``."""
    return hasattr(learner, "_numba_type_")


def _has_episode_start(learner: Any) -> bool:
    return "episode_start" in learner._numba_type_.class_type.methods


@njit(inline="always")
def draw_start(rng, start_states):
    """The episode's start state, drawn as the compiled methods draw it:
    ``start_states[rng.integers(0, len)]`` (the same stream, the same starts)."""
    return start_states[rng.integers(0, start_states.shape[0])]


@njit(inline="always")
def begin(learner):
    """The template's episode-start call: replaced by :func:`_start_hook` or
    :func:`_no_start_hook` when the loop is compiled for a class."""
    raise NotImplementedError("compiled code only")


@njit(inline="always")
def _start_hook(learner):
    learner.episode_start()


@njit(inline="always")
def _no_start_hook(learner):
    pass


def _loop(learner, next_state, reward, terminal, starts, max_steps, n, start_rng,
          steps, returns, success, first, trace):
    """Episodes ``first .. first + n - 1`` as :func:`learning.drivers.plain_train._episodes`
    runs them (a template: compiled with ``begin`` the learner's ``episode_start`` or
    nothing). Returns (env steps, -1, 0), or on an action out of range (steps so far, the
    state, the action)."""
    n_actions = next_state.shape[1]
    tracing = trace.shape[0] > 0
    total = 0
    for i in range(n):
        s = draw_start(start_rng, starts)
        if tracing:
            trace[i, 0] = s
        begin(learner)
        ret = 0.0
        t = 0
        done = False
        while t < max_steps:
            a = learner.act(s)
            if a < 0 or a >= n_actions:
                return total + t, s, a
            s2 = next_state[s, a]
            r = reward[s, a]
            done = terminal[s2]
            t += 1
            learner.update(s, a, r, s2, done)
            ret += r
            s = s2
            if tracing:
                trace[i, t] = s
            if done:
                break
        steps[first + i] = t
        returns[first + i] = ret
        success[first + i] = done
        total += t
    return total, -1, 0


_LOOPS: dict[bool, Any] = {}


def _compiled_loop(with_start: bool) -> Any:
    loop = _LOOPS.get(with_start)
    if loop is None:
        names = dict(_loop.__globals__, begin=_start_hook if with_start else _no_start_hook)
        fn = FunctionType(_loop.__code__, names, _loop.__name__)
        loop = _LOOPS[with_start] = njit(cache=False)(fn)
    return loop


def run_episodes(learner: Any, model: Any, n: int, start_rng: np.random.Generator,
                 arrays: dict[str, np.ndarray], first: int,
                 trace: np.ndarray) -> tuple[int, int, int]:
    """``n`` episodes of a jitclass learner on ``model``: (env steps, bad state, bad action);
    the bad state is -1 when every action was in range."""
    loop = _compiled_loop(_has_episode_start(learner))
    out = loop(learner, model.next_state, model.reward, model.terminal, model.start_states,
               int(model.max_steps), int(n), start_rng, arrays["steps"], arrays["returns"],
               arrays["success"], int(first), trace)
    return int(out[0]), int(out[1]), int(out[2])


def _walk(learner, next_state, terminal, start, max_steps, route):
    """The greedy test from ``start`` (as :func:`learning.plain.learner.greedy_walk`): (length
    or -1, states written to ``route``, bad state or -1, bad action)."""
    n_actions = next_state.shape[1]
    seen = np.zeros(next_state.shape[0], dtype=np.bool_)
    s = start
    route[0] = s
    seen[s] = True
    for t in range(max_steps):
        a = learner.greedy(s)
        if a < 0 or a >= n_actions:
            return -1, t + 1, s, a
        s2 = next_state[s, a]
        route[t + 1] = s2
        if terminal[s2]:
            return t + 1, t + 2, -1, 0
        if seen[s2]:
            return -1, t + 2, -1, 0
        seen[s2] = True
        s = s2
    return -1, max_steps + 1, -1, 0


def _table(learner, n_states, n_actions, out):
    """Every state's greedy action into ``out``: (bad state or -1, bad action)."""
    for s in range(n_states):
        a = learner.greedy(s)
        out[s] = a
        if a < 0 or a >= n_actions:
            return s, a
    return -1, 0


_READS: dict[str, Any] = {}


def _read(fn: Any) -> Any:
    if fn.__name__ not in _READS:
        _READS[fn.__name__] = njit(cache=False)(fn)
    return _READS[fn.__name__]


def greedy_walk(learner: Any, next_state: np.ndarray, terminal: np.ndarray, start: int,
                max_steps: int) -> tuple[int, list[int], int, int]:
    """The greedy test of a jitclass learner, compiled: (length or -1, states, bad state or
    -1, bad action)."""
    route = np.empty(max_steps + 2, dtype=np.int64)
    length, n, bad_s, bad_a = _read(_walk)(learner, next_state, terminal, int(start),
                                           int(max_steps), route)
    return int(length), route[:n].tolist(), int(bad_s), int(bad_a)


def greedy_table(learner: Any, n_states: int,
                 n_actions: int) -> tuple[np.ndarray, int, int]:
    """int64[n_states], every state's greedy action, compiled; (table, bad state or -1, bad
    action)."""
    out = np.empty(n_states, dtype=np.int64)
    bad_s, bad_a = _read(_table)(learner, int(n_states), int(n_actions), out)
    return out, int(bad_s), int(bad_a)


def copied(learner: Any, cls: Any, n_states: int, n_actions: int) -> Any:
    """A deep copy of a jitclass learner of class ``cls`` (numba's instances cannot be
    pickled, so ``copy.deepcopy`` fails on them): a new instance, built for the same arena,
    then every field of the spec set to a deep copy of the original's (arrays copied,
    Generators at the same point of their streams). A field that is itself a jitclass
    instance is refused: its class cannot be read back from it."""
    import copy

    fresh = cls(n_states, n_actions, np.random.default_rng(0))
    for name in learner._numba_type_.class_type.struct:
        value = getattr(learner, name)
        if is_jit_learner(value):
            raise ValueError(f"{cls.__name__}.{name} holds a jitclass instance: a warm start "
                             "cannot copy it; hold its fields in the learner itself")
        setattr(fresh, name, copy.deepcopy(value))
    return fresh


# ------------------------------------------------------------------ a class that does not compile

_HERE = str(Path(__file__).resolve().parent)
_BOILERPLATE = ("Failed in ", "- Resolution failure", "During:", "None", "<source elided>")
_AT = re.compile(r" at (\S+) \((\d+)\)$")


def compile_message(exc: NumbaError) -> str:
    """numba's typing or lowering error as one line: the first thing it says is wrong, and
    the first place in the learner's own code it points at (``at FILE:LINE``)."""
    what, where, in_source = "", "", False
    for raw in str(exc).splitlines():
        line = raw.strip()
        if line.startswith("File "):
            in_source = True  # the source excerpt that follows, up to a blank line
        elif not line:
            in_source = False
        elif in_source:
            continue
        elif line.startswith("During:"):
            m = _AT.search(line)
            if m and not where and not m.group(1).startswith(_HERE):
                where = f" at {m.group(1)}:{m.group(2)}"
        elif not what and not line.startswith(_BOILERPLATE):
            what = line
    return (what or type(exc).__name__) + where


def check_compiles(cls: Any, label: str) -> None:
    """Build ``cls`` on a two-cell arena and compile every loop it runs in (the episodes, the
    greedy walk and table), doing no work: a ValueError in one line when numba refuses it,
    before any run starts. The arrays have the dtypes of the grid model
    (:class:`learning.geometry.TabularMDP`) and the drivers' episode logs, so the runs reuse
    what this compiled (``cache=False``: in this process only)."""
    try:
        learner = cls(2, 4, np.random.default_rng(0))
    except NumbaError as exc:
        raise ValueError(f"{label}(n_states, n_actions, rng) does not compile as a "
                         f"@jitclass: {compile_message(exc)}") from None
    except Exception as exc:
        raise ValueError(f"{label}(2, 4, rng) raised {type(exc).__name__}: {exc}") from None
    nxt, terminal = np.zeros((2, 4), np.int32), np.zeros(2, np.bool_)
    try:
        run_episodes(learner, _NoModel(nxt, np.zeros((2, 4)), terminal,
                                       np.zeros(1, np.int32), 0),
                     0, np.random.default_rng(0),
                     {"steps": np.zeros(0, np.int32), "returns": np.zeros(0),
                      "success": np.zeros(0, np.bool_)}, 0, np.zeros((0, 1), np.int32))
        greedy_walk(learner, nxt, terminal, 0, 0)
        greedy_table(learner, 0, 4)
    except NumbaError as exc:
        raise ValueError(f"{label} does not compile in the training loop: "
                         f"{compile_message(exc)}; a @jitclass's act, update and greedy must "
                         "type under numba (numba.readthedocs.io, 'Supported Python "
                         "features')") from None


class _NoModel:
    """A model to compile against: the loop's arrays, no episodes to run."""

    def __init__(self, next_state, reward, terminal, start_states, max_steps):
        self.next_state, self.reward, self.terminal = next_state, reward, terminal
        self.start_states, self.max_steps = start_states, max_steps
