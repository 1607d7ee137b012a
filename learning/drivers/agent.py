"""The step-by-step driver: an agent for any gymnasium ``Discrete`` env, and its episode loop.

The agent holds the same named state the fused kernels train, and each event
calls the same compiled hook the kernels inline (:mod:`learning.compiled.hooks`), with
the same generator, so a run through an env
and a kernel run with the same seed end with identical tables and weights.
Use this driver where there is no tabular model (the physics env); use
:func:`learning.drivers.train.train_tabular` where there is (100x+ faster).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

from learning.compiled import hooks
from learning.compiled.generator_handle import handle
from learning.compiled.hooks import draw_start
from learning.compiled.named_state import episodes_done
from learning.compiled.state_box import box_of
from learning.config import MethodConfig
from learning.drivers.state import init_state
from learning.geometry import Geometry

# Each takes the state's box (learning.compiled.state_box): one reference to unbox per call.


@njit(cache=True)
def _act(box, s, h):
    return hooks.act_h(box.state, s, h)


@njit(cache=True)
def _update(box, s, a, r, s2, terminated, h):
    hooks.update_h(box.state, s, a, r, s2, terminated, h)


@njit(cache=True)
def _begin(box, s0):
    hooks.begin_row(box.state, s0)


@njit(cache=True)
def _end(box):
    hooks.end(box.state)


@njit(cache=True)
def _exploit(box, s):
    return hooks.exploit_call(box.state, s)


class StepAgent:
    """One learner, driven one event at a time.

    Per episode: ``begin_episode(s0)``; then ``a = act(s)`` and
    ``update(s, a, r, s2, terminated, truncated)`` per step; then
    ``end_episode()``. ``greedy_action(s)`` is the method's exploitation policy
    (no exploration, ties to the lowest index), as used in greedy tests.
    """

    def __init__(self, cfg: MethodConfig, geometry: Geometry, rng: np.random.Generator,
                 state=None) -> None:
        self.cfg = cfg
        self.geometry = geometry
        self.rng = rng
        self.state = init_state(cfg, geometry, rng) if state is None else state
        self._h = handle(rng)  # the generator, passed to compiled code without unboxing

    @property
    def state(self):
        """The learner's named state (tables, weights). Assigning a new one re-boxes it."""
        return self._state

    @state.setter
    def state(self, st) -> None:
        self._state = st
        self._box = box_of(st)  # the same arrays, one reference for compiled calls

    @property
    def episodes_done(self) -> int:
        return episodes_done(self.state)

    @property
    def last_shaping(self) -> tuple[float, float]:
        """(mean, std) of the shaping terms of the last finished episode."""
        tally = self.state.tally
        return float(tally.f_mean[0]), float(tally.f_std[0])

    def begin_episode(self, s0: int) -> None:
        """Start an episode in state ``s0`` (RNH-QL caches Phi(s0) here)."""
        _begin(self._box, int(s0))

    def act(self, s: int) -> int:
        """The behaviour (exploring) action at ``s``; draws from the agent's generator."""
        return int(_act(self._box, int(s), self._h))

    def update(self, s: int, a: int, r: float, s2: int, terminated: bool,
               truncated: bool) -> None:
        """Learn from one transition; bootstraps from ``s2`` unless ``terminated`` (a
        truncated step bootstraps like any other, so ``truncated`` changes nothing)."""
        _update(self._box, int(s), int(a), float(r), int(s2), bool(terminated), self._h)

    def end_episode(self) -> None:
        _end(self._box)

    def greedy_action(self, s: int) -> int:
        return int(_exploit(self._box, int(s)))


def make_agent(cfg: MethodConfig, geometry: Geometry, rng: np.random.Generator) -> StepAgent:
    """A fresh agent; RN-QL draws its initial weights from ``rng`` here."""
    return StepAgent(cfg, geometry, rng)


@dataclass(frozen=True)
class EpisodeLog:
    """Per-episode results of :func:`run_env_episodes` (env rewards only, no shaping)."""

    steps: np.ndarray  # int32[n]
    returns: np.ndarray  # float64[n]
    success: np.ndarray  # bool[n]; terminated (reached the goal)
    shaping_mean: np.ndarray  # float64[n]
    shaping_std: np.ndarray  # float64[n]


def run_env_episodes(agent: StepAgent, env: Any, n_episodes: int,
                     rng: np.random.Generator | None = None) -> EpisodeLog:
    """Run ``n_episodes`` episodes of ``agent`` on a gymnasium env.

    The start state is drawn exactly as the kernels draw it,
    ``draw_start(rng, geometry.start_states)``, and passed as
    ``env.reset(options={"start": s})`` (without ``start_states``, the env's
    own start is used). ``rng`` defaults to the agent's generator, which is what
    makes the run match a kernel run with the same seed; the env's generator is
    never used.
    """
    rng = agent.rng if rng is None else rng
    starts = agent.geometry.start_states
    out = EpisodeLog(np.zeros(n_episodes, np.int32), np.zeros(n_episodes),
                     np.zeros(n_episodes, bool), np.zeros(n_episodes), np.zeros(n_episodes))
    for i in range(n_episodes):
        if starts is not None:
            s, _ = env.reset(options={"start": int(draw_start(rng, starts))})
        else:
            s, _ = env.reset()
        s = int(s)
        agent.begin_episode(s)
        t, ret, terminated, truncated = 0, 0.0, False, False
        while not (terminated or truncated):
            a = agent.act(s)
            s2, r, terminated, truncated, _ = env.step(a)
            agent.update(s, a, r, int(s2), terminated, truncated)
            s = int(s2)
            t += 1
            ret += float(r)
        agent.end_episode()
        out.steps[i], out.returns[i], out.success[i] = t, ret, terminated
        out.shaping_mean[i], out.shaping_std[i] = agent.last_shaping
    return out
