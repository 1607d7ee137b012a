"""Fused numba loops over a tabular model: training episodes, greedy tests, policy checks.

Each loop is one source function that numba compiles once per method, holding only
that method's rules, so a run compiles only the methods it uses. The training loop
takes the method's hooks as its own globals (:func:`_episodes_of`); the read-outs call
them through :mod:`learning.compiled.hooks`, which resolves them from the state's type.
numba cannot read a clock, so wall time is measured from Python around calls of
:func:`run_episodes` (see :mod:`learning.drivers.train`).

numba's cache sees only the defining file of each function, and these loops
inline code from other modules: :mod:`learning.jitcache` drops the package's
cache whenever any ``learning/*.py`` changed.
"""

from __future__ import annotations

from types import FunctionType

import numpy as np
from numba import njit

from learning.compiled.hooks import act, begin, draw_start, end, exploit_call, update
from learning.methods.registry import family_of_state


def _episodes(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    """The training loop, a template: :func:`_episodes_of` compiles it once per method with
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
_EPISODES_OF: dict[type, object] = {}  # a state's class -> its compiled training loop


def _episodes_of(st):
    """:func:`_episodes` compiled for ``st``'s method, its hooks (``act``, ``update``,
    ``begin``: njit functions with ``inline="always"``) in its globals, so numba inlines
    them in its untyped passes. Through the typed overloads of
    :mod:`learning.compiled.hooks` numba also compiles each inlined hook on its own first
    ("make sure it can be compiled") and types the loop's inlined code twice: the
    same machine code for a third more compiling (``rnh-ql+`` cold: 23.5 -> 15.5 s of CPU;
    the README's main command cold: 71 -> 53 s; see BENCHMARKS.md). One dispatcher per
    method, all cached under ``_episodes``' name in this file's cache: the state's class in
    each signature tells them apart."""
    kind = type(st)
    kernel = _EPISODES_OF.get(kind)
    if kernel is None:
        family = family_of_state(st)
        names = dict(_episodes.__globals__, act=family.act, update=family.update,
                     begin=family.begin)
        fn = FunctionType(_episodes.__code__, names, _episodes.__name__)
        fn.__qualname__, fn.__module__ = _episodes.__qualname__, _episodes.__module__
        fn.__doc__ = _episodes.__doc__
        kernel = _EPISODES_OF[kind] = njit(cache=True, nogil=True)(fn)
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
    return int(_episodes_of(st)(st, mdp, int(model.max_steps), int(n_episodes), rng,
                    rng if start_rng is None else start_rng, out, trace))


ROUTE, SHORTEST, ROLLOUTS, POLICY = 0, 1, 2, 3  # what :func:`_read_policy` reads


@njit(cache=True)
def _read_policy(st, what, next_state, terminal, distance, states, start, max_steps, eps, n,
                 rng, route):
    """The method's exploitation policy read one of four ways (``what``): the greedy route
    from ``start`` (:func:`greedy_route`), the share of ``states`` whose action is a BFS step
    toward G (:func:`on_shortest_fraction`), ``n`` epsilon-greedy rollouts
    (:func:`epsilon_rollouts`), or the action of every state written to ``route``
    (:func:`policy_table`). One compiled entry point per method, not four: each entry
    costs a method ~1-3 s of compilation on a cold cache whatever its size (the state's
    unboxing, numba's passes), so the three loops share one. Returns (length, states
    written, fraction, rollout lengths), the fields ``what`` does not read left 0 / empty.
    """
    out = np.full(n if what == ROLLOUTS else 0, -1, dtype=np.int64)
    if what == POLICY:
        for s in range(route.shape[0]):
            route[s] = exploit_call(st, s)
        return 0, route.shape[0], 0.0, out
    if what == ROUTE:
        seen = np.zeros(next_state.shape[0], dtype=np.bool_)
        s = start
        route[0] = s
        seen[s] = True
        for t in range(max_steps):
            s2 = next_state[s, exploit_call(st, s)]
            route[t + 1] = s2
            if terminal[s2]:
                return t + 1, t + 2, 0.0, out
            if seen[s2]:
                return -1, t + 2, 0.0, out
            seen[s2] = True
            s = s2
        return -1, max_steps + 1, 0.0, out
    if what == SHORTEST:
        good = 0
        for i in range(states.shape[0]):
            s = states[i]
            a = exploit_call(st, s)
            if distance[next_state[s, a]] == distance[s] - 1:
                good += 1
        return 0, 0, good / max(states.shape[0], 1), out
    n_actions = next_state.shape[1]
    for i in range(n):
        s = start
        for t in range(max_steps):
            if rng.random() < eps:
                a = rng.integers(0, n_actions)
            else:
                a = exploit_call(st, s)
            s = next_state[s, a]
            if terminal[s]:
                out[i] = t + 1
                break
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


def greedy_route(st, next_state, terminal, start, max_steps, route):
    """Follow the exploitation policy from ``start`` for at most ``max_steps`` steps.

    Writes the visited states to ``route`` (length >= max_steps + 1) and returns
    (route length in steps or -1 if no terminal state was reached, states written).
    A deterministic policy in a deterministic MDP that revisits a state (a bump
    included) loops forever, so the test stops there with -1.
    """
    length, written, _, _ = _read_policy(st, ROUTE, next_state, terminal, _NO_STATES,
                                         _NO_STATES, start, max_steps, 0.0, 0, _IDLE_RNG, route)
    return length, written


def policy_table(st, n_states: int) -> np.ndarray:
    """int64[n_states]: the exploitation action of every state (ties to the lowest index)."""
    table = np.zeros(int(n_states), dtype=np.int32)
    _read_policy(st, POLICY, _NO_ROUTE_NEXT, _NO_TERMINAL, _NO_STATES, _NO_STATES, 0, 0, 0.0, 0,
                 _IDLE_RNG, table)
    return table.astype(np.int64)


def on_shortest_fraction(st, next_state, distance, states):
    """Fraction of ``states`` whose exploitation action moves one BFS step closer to the goal."""
    return _read_policy(st, SHORTEST, next_state, _NO_TERMINAL, distance, states, 0, 0, 0.0, 0,
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
    return _read_policy(st, ROLLOUTS, next_state, terminal, _NO_STATES, _NO_STATES, start,
                        max_steps, eps, n, rng, _NO_ROUTE)[3]
