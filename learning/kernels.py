"""Fused numba loops over a tabular model: training episodes, greedy tests, policy checks.

:func:`run_episodes` picks a compiled loop per rule family: each is a two-line
``cache=True`` wrapper that inlines the shared loop with its family id as a
compile-time constant, so :mod:`learning.dispatch` selects that family's
functions while compiling and each loop holds only its own rules. numba cannot
read a clock, so wall time is measured from Python around calls of
:func:`run_episodes` (see :mod:`learning.train`).

numba's cache sees only the defining file of each function, and these loops
inline code from other modules: :mod:`learning.jitcache` drops the package's
cache whenever any ``learning/*.py`` changed.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from learning import kinds as K
from learning.dispatch import act_k, begin_k, draw_start, end_episode, exploit_action, update_k
from learning.kinds import DYNA, HAQL, PFH, QL, QLAMBDA, RNHQL, RNHQLP, RNQL, SARSARS
from learning.state import AgentState


@njit(cache=True, inline="always")
def _episodes(kind, st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    ivar, fvar, par, q, w, e, feat, imap, fmap, ilist = st
    tracing = trace.shape[0] > 0
    next_state, reward, terminal, start_states = mdp
    out_steps, out_return, out_success, out_fmean, out_fstd = out
    total = 0
    for i in range(n_episodes):
        s = draw_start(start_rng, start_states)
        if tracing:
            trace[i, 0] = s
        begin_k(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s)
        ret = 0.0
        t = 0
        done = False
        while t < max_steps:
            a = act_k(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, rng)
            s2 = next_state[s, a]
            r = reward[s, a]
            done = terminal[s2]
            t += 1
            update_k(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s, a, r, s2, done,
                     rng)
            ret += r
            s = s2
            if tracing:
                trace[i, t] = s
            if done:
                break
        end_episode(ivar, fvar)
        out_steps[i] = t
        out_return[i] = ret
        out_success[i] = done
        out_fmean[i] = fvar[K.F_FMEAN]
        out_fstd[i] = fvar[K.F_FSTD]
        total += t
    return total


# nogil: the loops touch no Python objects, so another thread (the Rerun recorder
# encoding recorded episodes) can run on a second core while they train.
# Family ids are imported names, not ``K.QL``: numba types a global int as a literal
# (which learning.dispatch needs to pick the family), a module attribute as int64.
@njit(cache=True, nogil=True)
def _episodes_ql(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    return _episodes(QL, st, mdp, max_steps, n_episodes, rng, start_rng, out, trace)


@njit(cache=True, nogil=True)
def _episodes_rnql(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    return _episodes(RNQL, st, mdp, max_steps, n_episodes, rng, start_rng, out, trace)


@njit(cache=True, nogil=True)
def _episodes_pfh(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    return _episodes(PFH, st, mdp, max_steps, n_episodes, rng, start_rng, out, trace)


@njit(cache=True, nogil=True)
def _episodes_sarsars(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    return _episodes(SARSARS, st, mdp, max_steps, n_episodes, rng, start_rng, out, trace)


@njit(cache=True, nogil=True)
def _episodes_haql(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    return _episodes(HAQL, st, mdp, max_steps, n_episodes, rng, start_rng, out, trace)


@njit(cache=True, nogil=True)
def _episodes_rnhql(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    return _episodes(RNHQL, st, mdp, max_steps, n_episodes, rng, start_rng, out, trace)


@njit(cache=True, nogil=True)
def _episodes_qlambda(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    return _episodes(QLAMBDA, st, mdp, max_steps, n_episodes, rng, start_rng, out, trace)


@njit(cache=True, nogil=True)
def _episodes_dyna(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    return _episodes(DYNA, st, mdp, max_steps, n_episodes, rng, start_rng, out, trace)


@njit(cache=True, nogil=True)
def _episodes_rnhqlp(st, mdp, max_steps, n_episodes, rng, start_rng, out, trace):
    return _episodes(RNHQLP, st, mdp, max_steps, n_episodes, rng, start_rng, out, trace)


EPISODE_LOOPS = {K.QL: _episodes_ql, K.RNQL: _episodes_rnql, K.PFH: _episodes_pfh,
                 K.SARSARS: _episodes_sarsars, K.HAQL: _episodes_haql, K.RNHQL: _episodes_rnhql,
                 K.QLAMBDA: _episodes_qlambda, K.DYNA: _episodes_dyna}
EPISODE_LOOPS[K.RNHQLP] = _episodes_rnhqlp


NO_TRACE = np.zeros((0, 0), dtype=np.int32)


def run_episodes(st: AgentState, model, n_episodes: int, rng: np.random.Generator,
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
    loop = EPISODE_LOOPS[int(st.ivar[K.I_KIND])]
    mdp = (model.next_state, model.reward, model.terminal, model.start_states)
    return int(loop(st, mdp, int(model.max_steps), int(n_episodes), rng,
                    rng if start_rng is None else start_rng, out, trace))


@njit(cache=True)
def greedy_route(st, next_state, terminal, start, max_steps, route):
    """Follow the exploitation policy from ``start`` for at most ``max_steps`` steps.

    Writes the visited states to ``route`` (length >= max_steps + 1) and returns
    (route length in steps or -1 if no terminal state was reached, states written).
    A deterministic policy in a deterministic MDP that revisits a state (a bump
    included) loops forever, so the test stops there with -1.
    """
    ivar, fvar, par, q, w, e, feat, imap, fmap, ilist = st
    kind = ivar[K.I_KIND]
    seen = np.zeros(next_state.shape[0], dtype=np.bool_)
    s = start
    route[0] = s
    seen[s] = True
    for t in range(max_steps):
        s2 = next_state[s, exploit_action(kind, ivar, fvar, par, q, w, e, feat, imap, fmap,
                                          ilist, s)]
        route[t + 1] = s2
        if terminal[s2]:
            return t + 1, t + 2
        if seen[s2]:
            return -1, t + 2
        seen[s2] = True
        s = s2
    return -1, max_steps + 1


@njit(cache=True)
def on_shortest_fraction(st, next_state, distance, states):
    """Fraction of ``states`` whose exploitation action moves one BFS step closer to the goal."""
    ivar, fvar, par, q, w, e, feat, imap, fmap, ilist = st
    kind = ivar[K.I_KIND]
    good = 0
    for i in range(states.shape[0]):
        s = states[i]
        a = exploit_action(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s)
        if distance[next_state[s, a]] == distance[s] - 1:
            good += 1
    return good / max(states.shape[0], 1)


@njit(cache=True)
def epsilon_rollouts(st, next_state, terminal, start, max_steps, eps, n, rng):
    """Route lengths of ``n`` rollouts from ``start`` with the epsilon-greedy learning policy.

    The paper's own test ("put the agent at S and let it search with its learning
    policy"), *without* learning: the agent is not updated, so the rollouts never
    change the trained agent or the strict greedy test. Each step: with
    probability ``eps`` a uniformly random action, else the exploitation action.
    A rollout that does not reach a terminal state in ``max_steps`` gives -1.
    Draws only from ``rng`` (the run's evaluation stream).
    """
    ivar, fvar, par, q, w, e, feat, imap, fmap, ilist = st
    kind = ivar[K.I_KIND]
    n_actions = next_state.shape[1]
    out = np.full(n, -1, dtype=np.int64)
    for i in range(n):
        s = start
        for t in range(max_steps):
            if rng.random() < eps:
                a = rng.integers(0, n_actions)
            else:
                a = exploit_action(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, s)
            s = next_state[s, a]
            if terminal[s]:
                out[i] = t + 1
                break
    return out
