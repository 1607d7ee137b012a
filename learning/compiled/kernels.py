"""Fused numba loops over a tabular model: training episodes, greedy tests, policy checks.

Each loop is one source function that numba compiles once per method, holding only
that method's rules, so a run compiles only the methods it uses. The training loop
and the read-outs take the method's hooks as their own globals (:func:`compiled_for`).
numba cannot read a clock, so wall time is measured from Python around calls of
:func:`run_episodes` (see :mod:`learning.drivers.train`).

numba's cache sees only the defining file of each function, and these loops
inline code from other modules: :mod:`learning.jitcache` drops the package's
cache whenever any ``learning/*.py`` changed.
"""

from __future__ import annotations

from collections.abc import Callable
from types import FunctionType
from typing import Any

import numpy as np
from numba import njit

from learning.compiled.hooks import act, begin, draw_start, end, exploit, update
from learning.compiled.pipeline import TemplateCompiler
from learning.methods.registry import family_of_state


def _episodes(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    """The training loop, a template: :func:`compiled_for` compiles it once per method with
    that method's ``act``, ``update`` and ``begin`` (here the names of the dispatching
    hooks). nogil: it touches no Python objects, so another thread (the Rerun recorder
    encoding recorded episodes) can run on a second core while it trains."""
    tracing = trace.shape[0] > 0
    next_state, reward, terminal, start_states = mdp
    out_steps, out_return, out_success, out_fmean, out_fstd = out
    total = 0
    for i in range(n_episodes):
        s = draw_start(start_rng, start_states)
        if tracing:
            trace[i, 0] = s
        begin(st, s)
        ret = 0.0
        t = 0
        done = False
        while t < max_steps:
            a = act(st, s, rng)
            s2 = next_state[s, a]
            r = reward[s, a]
            done = terminal[s2]
            t += 1
            update(st, s, a, r, s2, done, rng)
            ret += r
            s = s2
            if tracing:
                trace[i, t] = s
            if done:
                break
        end(st)
        out_steps[i] = t
        out_return[i] = ret
        out_success[i] = done
        out_fmean[i] = st.tally.f_mean[0]
        out_fstd[i] = st.tally.f_std[0]
        total += t
    return total


NO_TRACE = np.zeros((0, 0), dtype=np.int32)
_COMPILED: dict[tuple[str, type], Any] = {}  # (template, a state's class) -> its dispatcher


def compiled_for(template: Callable, st: Any, **jit: Any) -> Any:
    """``template`` compiled for ``st``'s method: a copy of the function whose globals
    ``act``, ``update``, ``begin`` and ``exploit`` are that method's own hooks (njit
    functions with ``inline="always"``), so numba inlines them in its untyped passes.

    Why not the overloads of :mod:`learning.compiled.hooks`, which pick the hooks from the
    state's type while typing: numba then also compiles each inlined hook on its own first
    ("make sure it can be compiled") and types the inlined code twice, the same machine
    code for a third more compiling on a cold cache (``rnh-ql+``: 23.5 -> 15.5 s of CPU;
    the README's main command cold 71 -> 53 s; BENCHMARKS.md). One dispatcher per
    template and method, all cached under the template's name in this file's cache: the
    state's class in each signature tells them apart."""
    key = (template.__name__, type(st))
    kernel = _COMPILED.get(key)
    if kernel is None:
        family = family_of_state(st)
        names = dict(template.__globals__, act=family.act, update=family.update,
                     begin=family.begin, exploit=family.exploit)
        fn = FunctionType(template.__code__, names, template.__name__)
        fn.__qualname__, fn.__module__ = template.__qualname__, template.__module__
        fn.__doc__ = template.__doc__
        kernel = _COMPILED[key] = njit(cache=True, pipeline_class=TemplateCompiler, **jit)(fn)
    return kernel


def run_episodes(st, model, n_episodes: int, rng: np.random.Generator,
                 out: tuple[np.ndarray, ...], trace: np.ndarray = NO_TRACE,
                 start_rng: np.random.Generator | None = None) -> int:
    """Train ``n_episodes`` episodes in place on the tabular ``model``; returns env steps.

    ``out`` = (steps int32, return float64, success bool, shaping mean, shaping
    std), each with >= n_episodes entries; episode i writes index i. An episode
    starts at ``draw_start(start_rng, model.start_states)`` and ends on entering
    a terminal state or after ``model.max_steps`` steps (a truncation: the last
    update still bootstraps). Returns count env rewards only, never shaping.

    ``rng`` is the learner's stream (exploration, ties, planning); ``start_rng``
    the start cells' stream (default: ``rng`` itself). With a start stream of
    its own, every method trained with one seed sees the same start sequence
    (common random numbers), whatever it draws for exploration.

    ``trace`` (int32[n_episodes, max_steps + 1], optional) receives each
    episode's states: ``trace[i, k]`` is the state after k moves. It costs one
    store per step and draws nothing, so a traced run equals an untraced one.
    """
    mdp = (model.next_state, model.reward, model.terminal, model.start_states)
    train = compiled_for(_episodes, st, nogil=True)
    return int(train(st, mdp, int(model.max_steps), int(n_episodes), rng,
                     rng if start_rng is None else start_rng, out, trace))


ROUTE, SHORTEST, ROLLOUTS, POLICY = 0, 1, 2, 3  # what :func:`_read_policy` reads


def _read_policy(st, what, next_state, terminal, distance, states, start, max_steps, eps, n,
                 rng, route):
    """The method's exploitation policy read one of four ways (``what``): the greedy route
    from ``start`` (:func:`greedy_route`), the share of ``states`` whose action is a BFS step
    toward G (:func:`on_shortest_fraction`), ``n`` epsilon-greedy rollouts
    (:func:`epsilon_rollouts`), or the action of every state written to ``route``
    (:func:`policy_table`). A template (:func:`compiled_for`): one compiled entry per
    method, not four, and one loop with one call of ``exploit``, since each entry costs a
    method ~0.1-0.3 s of compiling whatever its size and each call site is a copy of the
    method's rules to type (``rnh-ql+`` cold: 3.5 s for four sites called as a compiled
    function, 5.9 s inlined at four sites, 2.3 s inlined at one). Returns (length, states
    written, fraction, rollout lengths), the fields ``what`` does not read left 0 / empty.
    """
    out = np.full(n if what == ROLLOUTS else 0, -1, dtype=np.int64)
    walks = what == ROUTE or what == ROLLOUTS
    seen = np.zeros(next_state.shape[0] if what == ROUTE else 0, dtype=np.bool_)
    if what == POLICY:
        queries = route.shape[0]
    elif what == SHORTEST:
        queries = states.shape[0]
    elif what == ROLLOUTS:
        queries = n if max_steps > 0 else 0
    else:
        queries = 1 if max_steps > 0 else 0
    n_actions = next_state.shape[1]
    length, written, good = -1, 0, 0
    s = start if walks else 0
    if what == ROUTE:
        route[0] = s
        seen[s] = True
        written = 1
    i = 0  # the state (POLICY), the index into states (SHORTEST), the rollout (ROLLOUTS)
    t = 0  # the steps taken on the current walk (ROUTE, ROLLOUTS)
    while i < queries:  # one call site of exploit: each is a copy of the rules to compile
        if what == SHORTEST:
            s = states[i]
        elif what == POLICY:
            s = i
        if what == ROLLOUTS and rng.random() < eps:
            a = rng.integers(0, n_actions)
        else:
            a = exploit(st, s)
        if what == POLICY:
            route[s] = a
            i += 1
        elif what == SHORTEST:
            if distance[next_state[s, a]] == distance[s] - 1:
                good += 1
            i += 1
        elif what == ROUTE:
            s = next_state[s, a]
            t += 1
            route[t] = s
            written = t + 1
            if terminal[s]:
                length = t
                break
            if seen[s] or t == max_steps:
                break
            seen[s] = True
        else:
            s = next_state[s, a]
            t += 1
            if terminal[s] or t == max_steps:
                if terminal[s]:
                    out[i] = t
                i += 1
                t = 0
                s = start
    if what == POLICY:
        return 0, route.shape[0], 0.0, out
    if what == ROUTE:
        return length, (written if max_steps > 0 else 1), 0.0, out
    if what == SHORTEST:
        return 0, 0, good / max(states.shape[0], 1), out
    return 0, 0, 0.0, out


def _unused(dtype: type, read_only: bool) -> np.ndarray:
    """An empty array for an argument a read does not use, typed like the tabular model's own
    (read-only) or the caller's route buffer, so every read shares one compiled signature."""
    a = np.zeros(0, dtype=dtype)
    a.setflags(write=not read_only)
    return a


_NO_STATES, _NO_TERMINAL = _unused(np.int32, True), _unused(np.bool_, True)
_NO_ROUTE_NEXT = np.zeros((0, 4), dtype=np.int32)  # next_state's type, for a policy read
_NO_ROUTE_NEXT.setflags(write=False)
_NO_ROUTE = _unused(np.int32, False)
_IDLE_RNG = np.random.default_rng(0)  # never drawn from: the reads that draw take the caller's


def _read(st):
    return compiled_for(_read_policy, st)


def greedy_route(st, next_state, terminal, start, max_steps, route):
    """Follow the exploitation policy from ``start`` for at most ``max_steps`` steps.

    Writes the visited states to ``route`` (length >= max_steps + 1) and returns
    (route length in steps or -1 if no terminal state was reached, states written).
    A deterministic policy in a deterministic MDP that revisits a state (a bump
    included) loops forever, so the test stops there with -1.
    """
    length, written, _, _ = _read(st)(st, ROUTE, next_state, terminal, _NO_STATES, _NO_STATES,
                                      start, max_steps, 0.0, 0, _IDLE_RNG, route)
    return length, written


def policy_table(st, n_states: int) -> np.ndarray:
    """int64[n_states]: the exploitation action of every state (ties to the lowest index)."""
    table = np.zeros(int(n_states), dtype=np.int32)
    _read(st)(st, POLICY, _NO_ROUTE_NEXT, _NO_TERMINAL, _NO_STATES, _NO_STATES, 0, 0, 0.0, 0,
              _IDLE_RNG, table)
    return table.astype(np.int64)


def on_shortest_fraction(st, next_state, distance, states):
    """Fraction of ``states`` whose exploitation action moves one BFS step closer to the goal."""
    return _read(st)(st, SHORTEST, next_state, _NO_TERMINAL, distance, states, 0, 0, 0.0, 0,
                     _IDLE_RNG, _NO_ROUTE)[2]


def epsilon_rollouts(st, next_state, terminal, start, max_steps, eps, n, rng):
    """Route lengths of ``n`` rollouts from ``start`` with the epsilon-greedy learning policy.

    The paper's own test ("put the agent at S and let it search with its learning
    policy"), *without* learning: the agent is not updated, so the rollouts never
    change the trained agent or the strict greedy test. Each step: with
    probability ``eps`` a uniformly random action, else the exploitation action.
    A rollout that does not reach a terminal state in ``max_steps`` gives -1.
    Draws only from ``rng`` (the run's evaluation stream).
    """
    return _read(st)(st, ROLLOUTS, next_state, terminal, _NO_STATES, _NO_STATES, start,
                     max_steps, eps, n, rng, _NO_ROUTE)[3]
