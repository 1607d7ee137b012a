"""Routing each agent event to its rule family: the one code path both drivers run.

Two doors onto the same per-family functions of :mod:`learning.steps`:

* ``act``, ``update``, ``begin_episode``, ``end_episode``, ``exploit_action``
  are compiled functions the step agent (:mod:`learning.agent`) calls from
  Python with the family id ``kind`` as a run-time int (a switch);
* ``act_k``, ``update_k``, ``begin_k`` are for compiled callers:
  given ``kind`` as a compile-time constant (the kernels' per-family wrappers),
  numba types and inlines only that family's function, so a kernel holds no
  switch and compiles only its own rules (cold compile ~3 s per family instead
  of 5-8 s with every family's rules inlined behind a switch).

Every random number either driver uses is drawn inside these functions (or
:func:`draw_start`) from the one injected generator, so equal seeds give equal
runs. Draw order per step: ``act`` (one ``random()``, then ``integers(0, nA)``
when exploring or ``integers(0, n_ties)`` on a greedy tie; SARSA-RS draws
nothing when it replays the action chosen at its last update), then ``update``
(SARSA-RS: the next action's draws unless terminated; Dyna-Q and RNH-QL+: ``n_planning``
``draw_below(n_seen)``, one ``random()`` each; RNH-QL+'s look-ahead ``act`` draws its
exploring move and ties the same way). Per episode: ``draw_start`` first (one ``integers``).

The agent state is passed as its ten arrays (``*state``): a tuple argument is
passed field by field to a compiled callee, which measured 4x slower.
"""

from __future__ import annotations

import math

from numba import njit, types
from numba.extending import overload

from learning import kinds as K
from learning import steps as S
from learning.rules_plus import act_plus, begin_plus, exploit_plus, update_plus

_ACT = {K.SARSARS: S.act_sarsars, K.HAQL: S.act_haql, K.RNQL: S.act_rnql}
_ACT[K.RNHQLP] = act_plus
_EXPLOIT = {K.HAQL: S.exploit_haql, K.RNQL: S.exploit_rnql}
_EXPLOIT[K.RNHQLP] = exploit_plus
_UPDATE = {K.QL: S.update_ql, K.HAQL: S.update_haql, K.PFH: S.update_pfh,
           K.RNHQL: S.update_rnhql, K.SARSARS: S.update_sarsars, K.QLAMBDA: S.update_qlambda,
           K.DYNA: S.update_dyna, K.RNQL: S.update_rnql}
_UPDATE[K.RNHQLP] = update_plus
_BEGIN = {K.QLAMBDA: S.begin_qlambda, K.RNQL: S.begin_rnql, K.RNHQL: S.begin_rnhql}
_BEGIN[K.RNHQLP] = begin_plus


@njit(cache=True, inline="always")
def draw_start(rng, start_states):
    """The episode's start state: ``start_states[rng.integers(0, len)]``."""
    return start_states[rng.integers(0, start_states.shape[0])]


# ---------------------------------------------------------------- run-time switches (Python)


@njit(cache=True)
def act(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng):
    """The behaviour policy's action at s (epsilon-greedy around the method's greedy choice)."""
    if kind == K.SARSARS:
        return S.act_sarsars(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng)
    if kind == K.HAQL:
        return S.act_haql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng)
    if kind == K.RNQL:
        return S.act_rnql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng)
    if kind == K.RNHQLP:
        return act_plus(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng)
    return S.act_eps_greedy(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng)


@njit(cache=True)
def exploit_action(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s):
    """The method's own exploitation policy, no exploration, ties to the lowest index."""
    if kind == K.HAQL:
        return S.exploit_haql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s)
    if kind == K.RNQL:
        return S.exploit_rnql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s)
    if kind == K.RNHQLP:
        return exploit_plus(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s)
    return S.exploit_q(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s)


@njit(cache=True)
def update(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
           truncated, rng):
    """Learn from (s, a, r, s'). ``truncated`` steps bootstrap like any non-terminal step."""
    if kind == K.QL:
        S.update_ql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated, rng)
    elif kind == K.HAQL:
        S.update_haql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                      rng)
    elif kind == K.RNHQL:
        S.update_rnhql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                       rng)
    elif kind == K.PFH:
        S.update_pfh(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                     rng)
    elif kind == K.SARSARS:
        S.update_sarsars(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2,
                         terminated, rng)
    elif kind == K.QLAMBDA:
        S.update_qlambda(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2,
                         terminated, rng)
    elif kind == K.DYNA:
        S.update_dyna(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                      rng)
    elif kind == K.RNQL:
        S.update_rnql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                      rng)
    elif kind == K.RNHQLP:
        update_plus(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
                    rng)


@njit(cache=True)
def begin_episode(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0):
    """Reset per-episode state: traces, pending action, SMDP sums, shaping flags, Phi(s0)."""
    if kind == K.QLAMBDA:
        S.begin_qlambda(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0)
    elif kind == K.RNQL:
        S.begin_rnql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0)
    elif kind == K.RNHQL:
        S.begin_rnhql(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0)
    elif kind == K.RNHQLP:
        begin_plus(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0)
    else:
        S.begin_plain(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0)


@njit(cache=True, inline="always")
def end_episode(ivar, fvar):
    """Close the episode: shaping mean/std into fvar[F_FMEAN/F_FSTD], count it."""
    n = ivar[K.I_NF]
    if n > 0:
        mean = fvar[K.F_FSUM] / n
        fvar[K.F_FMEAN] = mean
        fvar[K.F_FSTD] = math.sqrt(max(fvar[K.F_FSQ] / n - mean * mean, 0.0))
    else:
        fvar[K.F_FMEAN] = 0.0
        fvar[K.F_FSTD] = 0.0
    ivar[K.I_EPISODE] += 1


# ---------------------------------------------------------------- compile-time selection


def _family(kind, table, default):
    """The family's function when ``kind`` is a compile-time constant, else None (numba then
    retries the call with the constant's literal type; a run-time kind does not type)."""
    if isinstance(kind, types.IntegerLiteral):
        return table.get(kind.literal_value, default)
    return None


def act_k(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng):
    raise NotImplementedError("compiled code only; from Python call act()")


def update_k(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
             rng):
    raise NotImplementedError("compiled code only; from Python call update()")


def begin_k(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0):
    raise NotImplementedError("compiled code only; from Python call begin_episode()")


@overload(act_k, inline="always")
def _act_k(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng):
    f = _family(kind, _ACT, S.act_eps_greedy)
    if f is None:
        return None
    return lambda kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng: f(
        ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng)


@overload(update_k, inline="always")
def _update_k(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, terminated,
              rng):
    f = _family(kind, _UPDATE, None)
    if f is None:
        return None
    return lambda kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, \
        terminated, rng: f(ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2,
                           terminated, rng)


@overload(begin_k, inline="always")
def _begin_k(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0):
    f = _family(kind, _BEGIN, S.begin_plain)
    if f is None:
        return None
    return lambda kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0: f(
        ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s0)
