"""Dyna-Q (Sutton 1990, ``dyna-q``): Q-learning plus planning from a learned model of moves.

After each real step, ``n_planning`` Q updates on pairs drawn uniformly from the
pairs seen (Sutton & Barto 8.2), each replaying an outcome drawn from the move
model (:mod:`learning.parts.move_model`; a move "works" when it moved at all without a bump,
read from its reward by :mod:`learning.parts.move_reading`: with carried pose a move that grazed
an obstacle on its way into a cell is paid the bump, and storing that as the move's
outcome replayed a free corridor move as a penalty until it was next tried).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import MethodConfig, params_tuple
from learning.geometry import Geometry
from learning.parts.move_model import (
    MoveModel,
    new_move_model,
    note_pair,
    observe_outcome,
    pair_of,
    replay_draws_failure,
)
from learning.parts.move_reading import MoveReading, new_move_reading, read_move
from learning.parts.tabular import begin_plain, draw_below, eps_greedy, exploit_q, q_learning
from learning.parts.tally import Tally, new_tally

HOOK = dict(cache=True, inline="always")

Params = params_tuple("Params", __name__, n_planning=int)


@dataclass(frozen=True)
class DynaQ(MethodConfig):
    """Dyna-Q (Sutton 1990): Q-learning + planning from a learned deterministic model."""

    name: ClassVar[str] = "DYNA-Q"
    cli: ClassVar[str] = "dyna-q"
    n_planning: int = 5  # simulated Q updates per real step, (s, a) uniform over seen pairs

    params_type: ClassVar[type] = Params


class State(NamedTuple):
    par: Params
    tally: Tally
    q: np.ndarray  # float64[nS, nA]
    model: MoveModel
    reading: MoveReading  # the rewards of a stay and of a clean arrival (bumps from rewards)


# Added after checkpoints were written: a file without them loads the fresh values (no reward
# seen yet), relearnt at the next stay and clean arrival (see learning.drivers.checkpoint).
ADDED = ("reading.r_stay", "reading.r_clean")


def init_state(cfg: DynaQ, geom: Geometry, rng: np.random.Generator) -> State:
    n_s, n_a = geom.n_states, geom.n_actions
    return State(cfg.params(), new_tally(), np.zeros((n_s, n_a)), new_move_model(n_s, n_a),
                 new_move_reading())


@njit(**HOOK)
def act(st, s, rng):
    return eps_greedy(st.q, s, st.par.eps, rng)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """Q-learning, then the model learns (s, a) -> (r, s', terminated), then ``n_planning``
    updates replaying seen pairs. The model's arrays are read once, here (see
    :mod:`learning.methods.rnh_ql_plus.rules` on reads of a named tuple's fields)."""
    p = st.par
    q = st.q
    succ = st.model.successor
    to_goal = st.model.to_goal
    reward = st.model.reward
    works = st.model.works
    fails = st.model.fails
    seen = st.model.seen
    n_seen = st.model.n_seen
    r_fail = st.model.r_fail
    r_stay = st.reading.r_stay
    r_clean = st.reading.r_clean
    alpha = p.alpha
    gamma = p.gamma
    q_learning(q, s, a, r, s2, terminated, alpha, gamma, 0.0)
    note_pair(succ, seen, n_seen, s, a)
    clean = read_move(r_stay, r_clean, s, r, s2, terminated)
    observe_outcome(succ, to_goal, reward, works, fails, r_fail, s, a, r, s2, terminated,
                    clean)
    n = n_seen[0]
    n_a = q.shape[1]
    for _ in range(p.n_planning):
        ps, pa = pair_of(seen[draw_below(rng, n)], n_a)
        if replay_draws_failure(works[ps, pa], fails[ps, pa], rng):
            q_learning(q, ps, pa, r_fail[0], ps, False, alpha, gamma, 0.0)
        else:
            q_learning(q, ps, pa, reward[ps, pa], succ[ps, pa], to_goal[ps, pa], alpha, gamma,
                       0.0)


begin = begin_plain
exploit = exploit_q
