"""N learners of one method, driven together: one compiled call per event for all of them.

The physics world steps many robots at once (:mod:`sim.physics.batch`); its learners must
keep up. A :class:`BatchAgent` stacks the agents' states (each of the ten
:class:`learning.state.AgentState` arrays gains a leading axis of N) and passes their
generators as handles (:mod:`learning.generator_handle`), so ``act``, ``update``,
``begin`` and ``end`` for all N agents are one compiled call each, which calls the same
per-agent functions the step agent and the kernels call (:mod:`learning.dispatch`).
Each agent draws from its own generator in the same order as a :class:`StepAgent`
would, so agent ``i`` of a batch ends with the same tables as a step agent run alone
with its seed (tested).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from learning import dispatch
from learning import kinds as K
from learning.agent import StepAgent
from learning.generator_handle import generator_from, handles
from learning.geometry import Geometry
from learning.methods import MethodConfig
from learning.state import AgentState, init_state


@njit(cache=True)
def _draw_starts(start_handles, starts, active, out):
    for i in range(out.shape[0]):
        if active[i]:
            out[i] = dispatch.draw_start(generator_from(start_handles[i]), starts)


@njit(cache=True)
def _begin(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, active, s0):
    for i in range(s0.shape[0]):
        if active[i]:
            dispatch.begin_episode(kind, ivar[i], fvar[i], par[i], q[i], w[i], e[i], feat[i],
                                   imap[i], fmap[i], ilist[i], s0[i])


@njit(cache=True)
def _act(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, rng_handles, active, s, out):
    for i in range(s.shape[0]):
        if active[i]:
            out[i] = dispatch.act(kind, ivar[i], fvar[i], par[i], q[i], w[i], e[i], feat[i],
                                  imap[i], fmap[i], ilist[i], s[i],
                                  generator_from(rng_handles[i]))


@njit(cache=True)
def _update(kind, ivar, fvar, par, q, w, e, feat, imap, fmap, ilist, rng_handles, active, s, a,
            r, s2, terminated, truncated):
    for i in range(s.shape[0]):
        if active[i]:
            dispatch.update(kind, ivar[i], fvar[i], par[i], q[i], w[i], e[i], feat[i], imap[i],
                            fmap[i], ilist[i], s[i], a[i], r[i], s2[i], terminated[i],
                            truncated[i], generator_from(rng_handles[i]))


@njit(cache=True)
def _end(ivar, fvar, active):
    for i in range(active.shape[0]):
        if active[i]:
            dispatch.end_episode(ivar[i], fvar[i])


class BatchAgent:
    """N agents of one method and geometry, each with its own generator.

    ``rngs[i]`` is agent ``i``'s learner stream (RN-QL draws its initial weights from
    it here, as :func:`learning.agent.make_agent` does). Every event takes an ``active``
    mask: agents whose runs have finished sit out.
    """

    def __init__(self, cfg: MethodConfig, geometry: Geometry,
                 rngs: list[np.random.Generator]) -> None:
        self.cfg, self.geometry, self.rngs = cfg, geometry, list(rngs)
        self.n = len(self.rngs)
        self.kind = int(cfg.kind)
        one = [init_state(cfg, geometry, r) for r in self.rngs]
        self.arrays = tuple(np.ascontiguousarray(np.stack([getattr(st, f) for st in one]))
                            for f in AgentState._fields)
        self._handles = handles(self.rngs)
        self._out = np.zeros(self.n, dtype=np.int64)

    def state(self, i: int) -> AgentState:
        """Agent ``i``'s state (views into the stacked arrays)."""
        return AgentState(*(a[i] for a in self.arrays))

    def step_agent(self, i: int) -> StepAgent:
        """Agent ``i`` as a :class:`StepAgent` with its own copy of the state."""
        return StepAgent(self.cfg, self.geometry, self.rngs[i],
                         AgentState(*(a[i].copy() for a in self.arrays)))

    def episodes_done(self) -> np.ndarray:
        return self.arrays[0][:, K.I_EPISODE].copy()

    def last_shaping(self) -> tuple[np.ndarray, np.ndarray]:
        fvar = self.arrays[1]
        return fvar[:, K.F_FMEAN].copy(), fvar[:, K.F_FSTD].copy()

    def draw_starts(self, start_rngs_handles: np.ndarray, starts: np.ndarray,
                    active: np.ndarray) -> np.ndarray:
        out = np.zeros(self.n, dtype=np.int64)
        _draw_starts(start_rngs_handles, starts, active, out)
        return out

    def begin_episode(self, active: np.ndarray, s0: np.ndarray) -> None:
        _begin(self.kind, *self.arrays, active, s0)

    def act(self, active: np.ndarray, s: np.ndarray) -> np.ndarray:
        out = self._out
        _act(self.kind, *self.arrays, self._handles, active, s, out)
        return out

    def update(self, active: np.ndarray, s: np.ndarray, a: np.ndarray, r: np.ndarray,
               s2: np.ndarray, terminated: np.ndarray, truncated: np.ndarray) -> None:
        _update(self.kind, *self.arrays, self._handles, active, s, a, r, s2, terminated,
                truncated)

    def end_episode(self, active: np.ndarray) -> None:
        _end(self.arrays[0], self.arrays[1], active)
