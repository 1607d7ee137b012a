"""Your own learner in plain Python: a class, no numba, run by the same machinery as the
compiled methods.

The protocol (checked by :func:`check_learner`, with a message naming what is missing)::

    class MyLearner:
        name = "MY-QL"                          # optional: how tables name it
        eps = 0.1                               # optional: epsilon of the paper's test
        def __init__(self, n_states, n_actions, rng): ...   # rng: the run's Generator
        def act(self, state) -> int: ...        # the behaviour policy (may explore)
        def update(self, state, action, reward, next_state, terminal) -> None: ...
        def greedy(self, state) -> int: ...     # the policy graded (no exploration)
        def episode_start(self) -> None: ...    # optional

``rng`` is the run's learner stream (:func:`learning.streams.streams`), and episode
starts come from the run's start stream, as for every compiled method: a learner that
draws what a compiled method draws, in the same order, runs the same run (a Python port
of ST-QL equals ``st-ql`` figure for figure, grid and physics: tests). ``terminal`` is
True on entering G only; a step cut by the episode's time limit bootstraps like any
other. ``greedy`` must not draw random numbers: tests of the policy never move a run.
A learner may expose ``q`` (``float[n_states, n_actions]``); recordings then show it.

A learner is named where it lives, ``"mypkg.mymodule:MyLearner"``
(``rnhql compare SCENARIO --methods rnh-ql+,mypkg.mymodule:MyLearner``), or passed as the
class to :mod:`scenarios.api`. Its grid runs go through
:func:`learning.drivers.plain_train.train_plain`, its physics runs through
:class:`PlainBatchAgent` in the physics loop; its policy is graded as a
:mod:`learning.plain.policy`.
"""

from __future__ import annotations

import contextlib
import inspect
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np
from numba.core.errors import NumbaError

from learning.config import MethodConfig
from learning.geometry import Geometry
from learning.plain import compiled
from learning.plain.batched import (
    LearnerAnswerError,
    OneRun,
    actions_of,
    check_batched,
    check_methods,
    is_batched,
)
from learning.plain.compiled import is_jit_learner
from learning.plain.policy import State, policy_state

PAPER_EPS = 0.1  # the paper's epsilon, for the epsilon-greedy test of a learner without one


class PlainLearner(Protocol):
    """What a plain-Python learner provides (see the module's docstring)."""

    def act(self, state: int) -> int: ...

    def update(self, state: int, action: int, reward: float, next_state: int,
               terminal: bool) -> None: ...

    def greedy(self, state: int) -> int: ...


@dataclass(frozen=True)
class PlainConfig(MethodConfig):
    """The config of a plain-Python learner: which class, and the epsilon of the paper's
    epsilon-greedy test (the class's ``eps``, else the paper's 0.1). It has no fields to
    ``--set``: the learner's own settings are the learner's."""

    learner: ClassVar[type] = object

    @classmethod
    def settable(cls) -> tuple[str, ...]:
        return ()

    def record_fields(self) -> dict[str, object]:
        return {"learner": self.cli, "eps": self.eps}

    @classmethod
    def from_fields(cls, values: dict[str, object]) -> PlainConfig:
        return cls(eps=float(values.get("eps", cls().eps)))  # type: ignore[arg-type]


_CONFIGS: dict[str, type[PlainConfig]] = {}
_CLASSES: dict[str, type] = {}  # learner classes passed as objects, by where they live


def located_name(cls: type) -> str:
    """``"module:Qualname"``: how a sweep names a learner class across processes."""
    return f"{cls.__module__}:{cls.__qualname__}"


def remember(cls: type) -> str:
    """Name a learner class passed as an object (a script's, a notebook's) and keep it, so
    this process and the workers it forks resolve the name without importing it."""
    check_learner(cls)
    where = located_name(cls)
    _CLASSES[where] = cls
    _CONFIGS.pop(where, None)
    return where


def known_class(where: str) -> type | None:
    return _CLASSES.get(where)


class LearnerClassError(ValueError):
    """A learner class that cannot run as a plain learner (found, but not to the protocol):
    its fix is in the class, not in the name that found it."""


def check_learner(cls: Any, where: str | None = None) -> None:
    """Refuse what cannot run as a plain learner, saying what is missing and how to add it
    (a :class:`LearnerClassError`)."""
    try:
        _check_learner(cls, where or getattr(cls, "__qualname__", repr(cls)))
    except LearnerClassError:
        raise
    except ValueError as exc:
        raise LearnerClassError(str(exc)) from None


def _check_learner(cls: Any, label: str) -> None:
    if not isinstance(cls, type):
        raise ValueError(f"{label} is not a class: a plain learner is a class built as "
                         "Cls(n_states, n_actions, rng) with act, update and greedy")
    if is_batched(cls):
        check_batched(cls, label)
        return
    missing = [m for m in ("act", "update", "greedy") if not callable(getattr(cls, m, None))]
    if missing:
        raise ValueError(f"{label} has no {', '.join(missing)}: a plain learner defines "
                         "act(state) -> int, update(state, action, reward, next_state, "
                         "terminal) and greedy(state) -> int")
    try:
        inspect.signature(cls).bind(0, 4, None)
    except TypeError:
        raise ValueError(f"{label}({inspect.signature(cls)}) cannot be built as "
                         f"{cls.__name__}(n_states, n_actions, rng)") from None
    except ValueError:  # no signature to read (a builtin): let the first run say
        pass
    check_methods(cls, label, {"act": "state", "greedy": "state",
                               "update": "state, action, reward, next_state, terminal"})
    if compiled.is_jitclass(cls):
        compiled.check_compiles(cls, label)


def plain_config(cls: Any, where: str) -> type[PlainConfig]:
    """The config class of the learner class ``cls`` named ``where`` (one per name)."""
    if where not in _CONFIGS:
        check_learner(cls, where)
        eps = float(getattr(cls, "eps", PAPER_EPS))
        if not 0.0 <= eps <= 1.0:
            raise LearnerClassError(f"{where}.eps = {eps!r} must be in [0, 1] (the epsilon of the "
                             "paper's epsilon-greedy test)")
        name = str(getattr(cls, "name", cls.__name__))
        _CONFIGS[where] = dataclass(frozen=True)(type(
            f"{cls.__name__}Config", (PlainConfig,),
            {"__module__": __name__, "name": name, "cli": where, "learner": cls,
             "__annotations__": {"eps": float}, "eps": eps}))
    return _CONFIGS[where]


def is_plain(cfg: Any) -> bool:
    return isinstance(cfg, PlainConfig)


def new_learner(cfg: PlainConfig, geometry: Geometry, rng: np.random.Generator) -> Any:
    """One run's learner (a batched learner's batch of one, seen as one run)."""
    cls, n_states, n_actions = type(cfg).learner, int(geometry.n_states), \
        int(geometry.n_actions)
    if is_batched(cls):
        return OneRun(cls(n_states, n_actions, [rng]), 0, n_actions)
    return cls(n_states, n_actions, rng)


def learner_label(learner: Any) -> str:
    """The learner's class as messages name it (a batched learner's run: its class)."""
    return getattr(learner, "label", None) or type(learner).__qualname__


class LearnerError(ValueError):
    """A plain-Python learner of the user's failed: what it was asked, what it answered or
    raised, and where (a run that fails, reported as one; never our traceback)."""


@contextlib.contextmanager
def learner_calls(learner: Any) -> Iterator[None]:
    """Calls of ``learner`` in the block: an exception it raises, or ``sys.exit`` it calls,
    becomes a :class:`LearnerError` naming its class and the file and line it came from (a
    learner's exit would otherwise end the command as if it had done its work)."""
    try:
        yield
    except (LearnerError, KeyboardInterrupt):
        raise
    except LearnerAnswerError as exc:  # a batched learner's answer, checked by actions_of
        raise LearnerError(f"{learner_label(learner)}.act_batch {exc}") from None
    except NumbaError as exc:  # a @jitclass that numba refuses (check_compiles: up front)
        raise LearnerError(f"{learner_label(learner)} does not compile: "
                           f"{compiled.compile_message(exc)}") from None
    except SystemExit as exc:
        raise LearnerError(f"{learner_label(learner)} called sys.exit({exc.code!r}) "
                           f"{_where(exc)}; a learner must not exit") from None
    except Exception as exc:
        raise LearnerError(f"{learner_label(learner)} raised {type(exc).__name__}: {exc} "
                           f"{_where(exc)}") from None


def _where(exc: BaseException) -> str:
    """``at FILE:LINE`` of the innermost frame of ``exc``'s traceback."""
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    return "" if tb is None else f"at {tb.tb_frame.f_code.co_filename}:{tb.tb_lineno}"


def checked_action(learner: Any, s: int, a: Any, n_actions: int, what: str = "act") -> int:
    """``a`` as an int action, or a :class:`LearnerError` naming the learner, the state and
    the value."""
    # an int (numpy's too), nothing coerced: not a float, a text, a bool or an array
    k = int(a) if isinstance(a, int | np.integer) and not isinstance(a, bool | np.bool_) \
        else -1
    if not 0 <= k < n_actions:
        raise LearnerError(f"{learner_label(learner)}.{what}({s}) returned {a!r}, not an "
                           f"action in 0..{n_actions - 1}")
    return k


def greedy_table(learner: Any, n_states: int, n_actions: int) -> np.ndarray:
    """int64[nS]: the learner's greedy action in every state."""
    if is_jit_learner(learner):  # a @jitclass: read in compiled code, checked all the same
        out, bad_s, bad_a = compiled.greedy_table(learner, n_states, n_actions)
        if bad_s >= 0:
            checked_action(learner, bad_s, bad_a, n_actions, "greedy")  # raises, naming it
        return out
    whole = getattr(learner, "greedy_all", None)
    table = whole() if whole is not None else None
    if table is not None:  # a batched learner's run, read in one call: checked all the same
        try:
            return actions_of(table, n_states, n_actions)
        except LearnerAnswerError as exc:
            raise LearnerError(f"{learner_label(learner)}.greedy_all {exc}") from None
    out = np.empty(n_states, dtype=np.int64)
    greedy = learner.greedy
    for s in range(n_states):
        out[s] = checked_action(learner, s, greedy(s), n_actions, "greedy")
    return out


def snapshot(learner: Any, cfg: PlainConfig, n_states: int, n_actions: int) -> State:
    """The learner's greedy policy now, as a state the compiled readers grade (and its
    ``q`` for recordings, when it has one of the right shape)."""
    q = getattr(learner, "q", None)
    q = np.asarray(q, dtype=np.float64) if isinstance(q, np.ndarray) else None
    if q is not None and q.shape != (n_states, n_actions):
        q = None
    return policy_state(greedy_table(learner, n_states, n_actions), q, n_actions, cfg.eps)


def greedy_walk(learner: Any, next_state: np.ndarray, terminal: np.ndarray, start: int,
                max_steps: int) -> tuple[int, list[int]]:
    """The greedy test from ``start``, asking the learner only along the route: (length or
    -1, states). Stops on a revisit as :func:`learning.compiled.kernels.greedy_route` does."""
    n_actions = next_state.shape[1]
    if is_jit_learner(learner):  # a @jitclass: walked in compiled code
        length, states, bad_s, bad_a = compiled.greedy_walk(learner, next_state, terminal,
                                                            start, max_steps)
        if bad_s >= 0:
            checked_action(learner, bad_s, bad_a, n_actions, "greedy")
        return length, states
    s = int(start)
    route, seen = [s], {s}
    for t in range(max_steps):
        s2 = int(next_state[s, checked_action(learner, s, learner.greedy(s), n_actions,
                                              "greedy")])
        route.append(s2)
        if terminal[s2]:
            return t + 1, route
        if s2 in seen:
            return -1, route
        seen.add(s2)
        s = s2
    return -1, route


@dataclass(eq=False)
class PlainAgent:
    """A trained plain learner and its greedy policy as a gradable state (``state``)."""

    cfg: PlainConfig
    learner: Any
    state: State


class PlainBatchAgent:
    """N plain learners in the physics loop, with :class:`learning.drivers.batch_agent.BatchAgent`'s
    calls: each learner draws from its own stream, and each run's starts from its own start
    stream, in the order the compiled agents draw them. A batched learner
    (:mod:`learning.plain.batched`) is built once for the N runs and called once per step."""

    def __init__(self, cfg: PlainConfig, geometry: Geometry, rngs: list[np.random.Generator],
                 start_rngs: list[np.random.Generator], learners: list | None = None) -> None:
        self.cfg, self.geometry = cfg, geometry
        self.n_states, self.n_actions = int(geometry.n_states), int(geometry.n_actions)
        cls = type(cfg).learner
        self.batch = None
        if is_batched(cls):
            if learners is not None and any(x is not None for x in learners):
                raise ValueError(f"{cfg.cli} is a batched learner: a warm start carries one "
                                 "run's learner, which it cannot continue; train it from "
                                 "scratch at the rung")
            self.batch = cls(self.n_states, self.n_actions, list(rngs))
            self.learners = [OneRun(self.batch, i, self.n_actions) for i in range(len(rngs))]
        else:
            # a warm start continues the learner object itself (its state is its own)
            given = list(learners) if learners is not None else [None] * len(rngs)
            self.learners = [new_learner(cfg, geometry, r) if x is None else x
                             for r, x in zip(rngs, given, strict=True)]
        self.start_rngs = list(start_rngs)
        self.n = len(self.learners)
        self._out = np.zeros(self.n, dtype=np.int64)
        self._starts_hook = [getattr(x, "episode_start", None) for x in self.learners]
        # @jitclass learners: their unrecorded runs are driven by the compiled physics loop
        # (scenarios.runs.physics_fused.jit_driver), which reads them behind one box
        self.jit = bool(self.learners) and all(is_jit_learner(x) for x in self.learners)
        self.jit_with_start = self.jit and compiled._has_episode_start(self.learners[0])

    def refuse_action(self, i: int, s: int, a: int) -> None:
        """Run ``i``'s learner answered ``a`` at ``s`` in the compiled loop: a
        :class:`LearnerError` naming it (the loop stopped before using it)."""
        checked_action(self.learners[i], s, a, self.n_actions)

    def state(self, i: int) -> State:
        return snapshot(self.learners[i], self.cfg, self.n_states, self.n_actions)

    def step_agent(self, i: int) -> PlainAgent:
        return PlainAgent(self.cfg, self.learners[i], self.state(i))

    def last_shaping(self) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros(self.n), np.zeros(self.n)

    def draw_starts(self, _handles: np.ndarray, starts: np.ndarray,
                    active: np.ndarray) -> np.ndarray:
        out = np.zeros(self.n, dtype=np.int64)
        for i in np.flatnonzero(active):
            out[i] = starts[self.start_rngs[i].integers(0, starts.shape[0])]
        return out

    def begin_episode(self, active: np.ndarray, s0: np.ndarray) -> None:
        with learner_calls(self.learners[0]):
            if self.batch is not None:
                hook = getattr(self.batch, "episode_start_batch", None)
                if hook is not None:
                    hook(np.flatnonzero(active))
                return
            for i in np.flatnonzero(active):
                hook = self._starts_hook[i]
                if hook is not None:
                    hook()

    def act(self, active: np.ndarray, s: np.ndarray) -> np.ndarray:
        out = self._out
        with learner_calls(self.learners[0]):
            if self.batch is not None:
                runs = np.flatnonzero(active)
                out[runs] = actions_of(self.batch.act_batch(runs, s[runs]), runs.size,
                                       self.n_actions)
                return out
            for i in np.flatnonzero(active):
                learner, si = self.learners[i], int(s[i])
                out[i] = checked_action(learner, si, learner.act(si), self.n_actions)
        return out

    def update(self, active: np.ndarray, s: np.ndarray, a: np.ndarray, r: np.ndarray,
               s2: np.ndarray, terminated: np.ndarray, truncated: np.ndarray) -> None:
        with learner_calls(self.learners[0]):
            if self.batch is not None:
                runs = np.flatnonzero(active)
                self.batch.update_batch(runs, s[runs], a[runs], r[runs], s2[runs],
                                        terminated[runs])
                return
            for i in np.flatnonzero(active):
                self.learners[i].update(int(s[i]), int(a[i]), float(r[i]), int(s2[i]),
                                        bool(terminated[i]))

    def end_episode(self, active: np.ndarray) -> None:
        pass
