"""One door onto every method's hooks for compiled callers: ``act``, ``update``, ``begin``,
``exploit``, ``end`` on any method's state.

Each is a numba ``overload`` that, while compiling, looks up the module whose
``State`` the argument is (:data:`learning.methods.registry.FAMILY_OF_STATE`) and inlines
that module's hook. So one source loop (the step and batch agents) compiles once per
method with only that method's rules in it,
and numba's on-disk cache (which cannot key on functions passed as arguments)
keys on the state's type instead. The training loop and the read-outs of
:mod:`learning.compiled.kernels` (and the fused physics loop, through the same
:func:`~learning.compiled.kernels.compiled_for`) take the hooks as their own globals instead
(:func:`~learning.compiled.kernels.compiled_for`): numba compiles an inlined overload's
implementation on its own as well, a third more compiling on a cold cache; the step
agent calls ``begin`` and ``exploit`` through their non-inlined doors
(:func:`begin_row`, :func:`exploit_call`) for the same reason.

Every random number either driver uses is drawn inside the hooks (or
:func:`draw_start`) from the one injected generator, so equal seeds give equal
runs. Draw order per step: ``act`` (one ``random()``, then ``integers(0, nA)``
when exploring or ``integers(0, n_ties)`` on a greedy tie; SARSA-RS draws
nothing when it replays the action chosen at its last update), then ``update``
(SARSA-RS: the next action's draws unless terminated; Dyna-Q and RNH-QL+: one
``random()`` per planned update, plus one where a pair has both worked and
failed). Per episode: ``draw_start`` first (one ``integers``).
"""

from __future__ import annotations

from numba import njit, types
from numba.extending import overload

from learning.compiled.generator_handle import generator_from
from learning.methods.registry import FAMILY_OF_STATE
from learning.parts.tally import end_tally


def _family(st):
    if not isinstance(st, types.BaseNamedTuple) or st.instance_class not in FAMILY_OF_STATE:
        raise TypeError(f"not a learner's state: {st}")
    return FAMILY_OF_STATE[st.instance_class]


@njit(cache=True, inline="always")
def draw_start(rng, start_states):
    """The episode's start state: ``start_states[rng.integers(0, len)]``."""
    return start_states[rng.integers(0, start_states.shape[0])]


def act(st, s, rng):
    """The behaviour policy's action at s (epsilon-greedy around the method's choice)."""
    raise NotImplementedError("compiled code only")


def update(st, s, a, r, s2, terminated, rng):
    """Learn from (s, a, r, s'); bootstraps from s' unless ``terminated`` (a truncated
    step bootstraps like any other)."""
    raise NotImplementedError("compiled code only")


def begin(st, s0):
    """Start an episode in s0 (per-episode resets, the potential of s0)."""
    raise NotImplementedError("compiled code only")


def exploit(st, s):
    """The method's own greedy policy at s, no exploration, ties to the lowest index."""
    raise NotImplementedError("compiled code only")


def _hook(st, name: str):
    """The hook's own body (its Python function), to be inlined: no call between."""
    return getattr(_family(st), name).py_func


def _compiled_hook(st, name: str):
    """The hook as a compiled function, for callers that call it rather than inline it."""
    return getattr(_family(st), name)


@overload(act, inline="always")
def _act(st, s, rng):
    return _hook(st, "act")


@overload(update, inline="always")
def _update(st, s, a, r, s2, terminated, rng):
    return _hook(st, "update")


@overload(begin, inline="always")
def _begin(st, s0):
    return _hook(st, "begin")


@overload(exploit, inline="always")
def _exploit(st, s):
    return _hook(st, "exploit")


def exploit_call(st, s):
    """:func:`exploit` as a real call, not inlined: for loops that run once per greedy test
    or per read-out, not per training step. Inlining the rules at every such call site
    cost each method ~1 s of compilation per loop (rnh-ql+'s: ~3 s) and saved nothing
    measurable."""
    raise NotImplementedError("compiled code only")


@overload(exploit_call)
def _exploit_call(st, s):
    return _hook(st, "exploit")


@njit(cache=True, inline="always")
def end(st):
    """Close the episode: shaping mean and std, one more episode done."""
    end_tally(st.tally)


@njit(cache=True, inline="always")
def shaping(st):
    """The closed episode's shaping terms: (mean, standard deviation)."""
    return st.tally.f_mean[0], st.tally.f_std[0]


# ---------------------------------------------------------------- for the batch agent
# The same hooks, called on agent i's row of a stacked state with agent i's generator
# handle. Not inlined: numba's overload inliner loses writes made through a named tuple
# that a call returned (the row), and a Generator rebuilt from a handle must not cross
# a call; here the row arrives as an argument and the generator is made inside.


def act_h(st, s, h):
    raise NotImplementedError("compiled code only")


def update_h(st, s, a, r, s2, terminated, h):
    raise NotImplementedError("compiled code only")


@overload(act_h)
def _act_h(st, s, h):
    f = _compiled_hook(st, "act")
    return lambda st, s, h: f(st, s, generator_from(h))


@overload(update_h)
def _update_h(st, s, a, r, s2, terminated, h):
    f = _compiled_hook(st, "update")
    return lambda st, s, a, r, s2, terminated, h: f(st, s, a, r, s2, terminated,
                                                    generator_from(h))


def begin_row(st, s0):
    raise NotImplementedError("compiled code only")


@overload(begin_row)
def _begin_row(st, s0):
    f = _compiled_hook(st, "begin")
    return lambda st, s0: f(st, s0)
