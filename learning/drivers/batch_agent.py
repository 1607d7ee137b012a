"""N learners of one method, driven together: one compiled call per event for all of them.

The physics world steps many robots at once (:mod:`sim.physics.kernel.batch`); its learners must
keep up. A :class:`BatchAgent` stacks the agents' states (every array of the method's
named state gains a leading axis of N, :func:`learning.compiled.named_state.stack`) and passes
their generators as handles (:mod:`learning.compiled.generator_handle`), so ``act``, ``update``,
``begin`` and ``end`` for all N agents are one compiled call each, which calls the same
hooks the step agent and the kernels call (:mod:`learning.compiled.hooks`) on agent i's row.
Each agent draws from its own generator in the same order as a :class:`StepAgent`
would, so agent ``i`` of a batch ends with the same tables as a step agent run alone
with its seed (tested).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from learning.compiled import hooks
from learning.compiled.generator_handle import generator_from, handles
from learning.compiled.named_state import copy_state, row, row_view, stack
from learning.compiled.state_box import box_of
from learning.config import MethodConfig
from learning.drivers.agent import StepAgent
from learning.drivers.state import carried_state, init_state
from learning.geometry import Geometry


@njit(cache=True)
def _draw_starts(start_handles, starts, active, out):
    for i in range(out.shape[0]):
        if active[i]:
            out[i] = hooks.draw_start(generator_from(start_handles[i]), starts)


# Each takes the stacked state's box (learning.compiled.state_box): one reference to unbox per call.


@njit(cache=True)
def _begin(box, active, s0):
    st = box.state
    for i in range(s0.shape[0]):
        if active[i]:
            hooks.begin_row(row(st, i), s0[i])


@njit(cache=True)
def _act(box, rng_handles, active, s, out):
    st = box.state
    for i in range(s.shape[0]):
        if active[i]:
            out[i] = hooks.act_h(row(st, i), s[i], rng_handles[i])


@njit(cache=True)
def _update(box, rng_handles, active, s, a, r, s2, terminated):
    st = box.state
    for i in range(s.shape[0]):
        if active[i]:
            hooks.update_h(row(st, i), s[i], a[i], r[i], s2[i], terminated[i],
                           rng_handles[i])


@njit(cache=True)
def _end(box, active):
    st = box.state
    for i in range(active.shape[0]):
        if active[i]:
            hooks.end(row(st, i))


class BatchAgent:
    """N agents of one method and geometry, each with its own generator.

    ``rngs[i]`` is agent ``i``'s learner stream (RN-QL draws its initial weights from
    it here, as :func:`learning.drivers.agent.make_agent` does). ``init[i]``, if given and
    not None, is the state agent ``i`` starts from (a warm start: a learner trained in
    another world, :func:`learning.drivers.state.carried_state`); nothing is drawn for it.
    Every event takes an ``active`` mask: agents whose runs have finished sit out.
    """

    def __init__(self, cfg: MethodConfig, geometry: Geometry,
                 rngs: list[np.random.Generator], init: list | None = None) -> None:
        self.cfg, self.geometry, self.rngs = cfg, geometry, list(rngs)
        self.n = len(self.rngs)
        init = list(init) if init is not None else [None] * self.n
        self.states = stack([init_state(cfg, geometry, r) if st is None
                             else carried_state(cfg, st)
                             for r, st in zip(self.rngs, init, strict=True)])
        self._box = box_of(self.states)  # the same arrays, one reference for compiled calls
        self._handles = handles(self.rngs)
        self._out = np.zeros(self.n, dtype=np.int64)

    def state(self, i: int):
        """Agent ``i``'s state (views into the stacked arrays)."""
        return row_view(self.states, i)

    def step_agent(self, i: int) -> StepAgent:
        """Agent ``i`` as a :class:`StepAgent` with its own copy of the state."""
        return StepAgent(self.cfg, self.geometry, self.rngs[i], copy_state(self.state(i)))

    def episodes_done(self) -> np.ndarray:
        return self.states.tally.episode[:, 0].copy()

    def last_shaping(self) -> tuple[np.ndarray, np.ndarray]:
        tally = self.states.tally
        return tally.f_mean[:, 0].copy(), tally.f_std[:, 0].copy()

    def draw_starts(self, start_rngs_handles: np.ndarray, starts: np.ndarray,
                    active: np.ndarray) -> np.ndarray:
        out = np.zeros(self.n, dtype=np.int64)
        _draw_starts(start_rngs_handles, starts, active, out)
        return out

    def begin_episode(self, active: np.ndarray, s0: np.ndarray) -> None:
        _begin(self._box, active, s0)

    def act(self, active: np.ndarray, s: np.ndarray) -> np.ndarray:
        out = self._out
        _act(self._box, self._handles, active, s, out)
        return out

    def update(self, active: np.ndarray, s: np.ndarray, a: np.ndarray, r: np.ndarray,
               s2: np.ndarray, terminated: np.ndarray, truncated: np.ndarray) -> None:
        """``truncated`` steps bootstrap like any other (kept for the env's signature)."""
        _update(self._box, self._handles, active, s, a, r, s2, terminated)

    def end_episode(self, active: np.ndarray) -> None:
        _end(self._box, active)
