"""Multi-fidelity R-max (``mf-r-max``; Cutler, Walsh & How, "Real-World Reinforcement
Learning via Multifidelity Simulators", IEEE T-RO 2015), over the grid and a physics rung.

Cutler et al. learn in a chain of simulators of rising fidelity with an R-max learner at
each level. Three rules tie the levels, and this module keeps two of them:

1. **Values passed up as optimistic priors.** A move the rung has not learned is valued by
   the level below's value of where it leads, not by R-max's R_max/(1-γ) (here: not by the
   free-space distance Φ of :mod:`.r_max`): at the switch, Φ of every cell becomes its
   cost to G under the grid's learned model, where the grid knows one (it is never below
   the free-space distance, and the rung is no cheaper than the grid: still admissible).
2. **Known moves trusted until the rung contradicts them.** A move the grid knew keeps its
   model at the rung (no robot time spent re-learning it) until the rung shows an outcome
   the model says cannot happen (a bump on a move known free, a clean arrival on one known
   to bump). From then on the move's model is the rung's count of its outcomes, with the
   grid's as a prior worth ``m_rung`` tries (a move known free that bumps once: p̂ = 1/6
   with ``m_rung = 5``), updated at every later try: R-max's "update only on evidence".
   Here this departs from the paper, which makes a contradicted move unknown again, to be
   re-learned from ``m`` tries at the higher level with optimism. Measured first that way
   (maze-1 at ``slip``, seed 0, after 300 grid episodes): in 30 episodes at the rung its
   final policy went from P(G) 0.78 to 0.00, because a reopened move keeps its optimistic
   value for ``m`` tries while the known way back does not, and the greedy policy looped
   between the two. Moves unknown below are learned as R-max learns them (``m`` tries,
   valued by the prior of rule 1 until then).
3. **The switching rule** (up when the level below has converged, down when the rung
   meets moves unknown below) is where this departs: the switch up is the caller's budget
   (``pretrain=("grid", n)`` or ``init=``), and the learner never goes back down. With the
   grid as the only level below, going down could teach the grid nothing: it is
   deterministic and its model is fixed by the map; a move unknown below is explored at the
   rung with the optimism of rule 1.

Before the switch (the grid, or a run with no level below) this is :mod:`.r_max` with
``m`` tries, run for run.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import MethodConfig, params_tuple
from learning.geometry import Geometry
from learning.methods.references import r_max
from learning.methods.references.r_max import Field
from learning.parts.move_reading import MoveReading, read_move
from learning.parts.tabular import begin_plain
from learning.parts.tally import Tally

HOOK = dict(cache=True, inline="always")

Params = params_tuple("Params", __name__, m=int, m_rung=int)


@dataclass(frozen=True)
class MFRMax(MethodConfig):
    """R-max at each level; the grid's values as the rung's optimistic prior, the grid's
    known moves trusted at the rung until contradicted."""

    name: ClassVar[str] = "MF-R-max"
    cli: ClassVar[str] = "mf-r-max"
    eps: float = 0.0  # probability of a uniformly random move (0: R-max's own)
    m: int = 1  # tries after which a move unknown below is known (R-max's m) [tries]
    m_rung: int = 5  # the weight of the grid's model of a move once the rung contradicts it
    #                  [tries]: its outcomes then counted on top of m_rung grid-like tries
    IGNORED: ClassVar[tuple[str, ...]] = ("alpha", "gamma")  # a model is learned, not Q

    params_type: ClassVar[type] = Params

    def __post_init__(self) -> None:
        super().__post_init__()
        if not 1 <= self.m <= self.m_rung:
            raise ValueError(f"MFRMax.m = {self.m}, m_rung = {self.m_rung}: need 1 <= m <= "
                             "m_rung (a move the grid knew must stay known at the rung)")


class State(NamedTuple):
    par: Params
    tally: Tally
    neighbour: np.ndarray  # int32[nS, nA]; the arena cell each move heads for (-1: off)
    phi: np.ndarray  # float64[nS]; the prior cost to G of a cell [moves]: the free-space
    #                  distance, at a rung the grid's cost where it knew one
    tries: np.ndarray  # int32[nS, nA]; tries of each move, up to the level's m
    clean: np.ndarray  # int32[nS, nA]; clean arrivals among those tries
    version: np.ndarray  # int64[1]; the model's version (moves that became known or reopened)
    reading: MoveReading
    cost: np.ndarray  # float64[nS]; scratch, as R-max's
    cost_version: np.ndarray  # int64[1]
    field: Field
    keys: np.ndarray  # float64[nA]
    below: np.ndarray  # int8[nS, nA]; 1: known from the level below, trusted; 2: contradicted
    #                    at the rung, its outcomes counted since (0: R-max's own rule)
    level: np.ndarray  # int64[1]; levels climbed (0: the first world it learned in)


DERIVED = r_max.DERIVED


def init_state(cfg: MFRMax, geom: Geometry, rng: np.random.Generator) -> State:
    base = r_max.init_state(cfg, geom, rng)
    n_s, n_a = geom.n_states, geom.n_actions
    return State(cfg.params(), *base[1:], np.zeros((n_s, n_a), np.int8),
                 np.zeros(1, np.int64))


def carry(st: State) -> State:
    """The switch up a level (before a warm start's first act): every move known below
    becomes trusted, its model worth ``m_rung`` tries (a move a lower rung contradicted keeps
    its counts); Φ the level below's costs to G where it knew one (never below the
    free-space distance)."""
    r_max.current_costs(st, -1)
    m_rung = int(st.par.m_rung)
    counted = st.below == 2  # contradicted at a lower rung: its counts carry as they are
    known = (st.tries >= int(st.par.m)) & ~counted
    st.below[...] = np.where(counted, 2, known.astype(np.int8))
    st.clean[...] = np.where(known, np.where(st.clean > 0, m_rung, 0), st.clean)
    st.tries[...] = np.where(known, m_rung, st.tries)
    st.phi[...] = np.where(np.isfinite(st.cost), np.maximum(st.cost, st.phi), st.phi)
    st.version[0] += 1  # Φ changed everywhere: the next act refreshes every cost
    st.level[0] += 1
    return st


@njit(**HOOK)
def act(st, s, rng):
    return r_max.act(st, s, rng)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """R-max's count for a move not known below; at a rung, a move known below is trusted
    until the rung contradicts it, then its outcomes are counted on top of the grid's model
    (rule 2)."""
    tier = st.below[s, a]
    if tier == 0:
        r_max.update(st, s, a, r, s2, terminated, rng)
        return
    clean = read_move(st.reading.r_stay, st.reading.r_clean, s, r, s2, terminated)
    if tier == 1:
        if clean == (st.clean[s, a] > 0):
            return  # as the level below said: trusted, nothing to learn
        st.below[s, a] = 2
    st.tries[s, a] += 1
    if clean:
        st.clean[s, a] += 1
    st.version[0] += 1  # its cost changed: the costs it touches are repaired
    r_max.model_changed(st, s)


begin = begin_plain


@njit(**HOOK)
def exploit(st, s):
    return r_max.exploit(st, s)


def q_table(st: State) -> np.ndarray:
    return r_max.q_table(st)


def n_states(st: State) -> int:
    return int(st.phi.shape[0])
