"""PFH-RL (``pfh-rl``): Q-learning with a static potential field heuristic (Ng 1999 shaping).

Phi(s) = -scale * Manhattan cells to G, from the geometry alone (no obstacles),
so it is the same knowledge an agent would have in the physics world;
F = gamma * Phi(s') - Phi(s), Phi(goal) = 0, which keeps the optimal policy.

The rules are those of any Q-learning shaped by a static potential: a config with a
``potential(geom)`` method of its own brings its Φ and runs on this module (the
reference ``abstraction-ql``, :mod:`learning.methods.references.abstraction_ql`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import BaseParams, MethodConfig
from learning.geometry import Geometry
from learning.parts.tabular import begin_plain, eps_greedy, exploit_q, q_learning
from learning.parts.tally import Tally, new_tally, record_shaping

HOOK = dict(cache=True, inline="always")


@dataclass(frozen=True)
class PFHRL(MethodConfig):
    """Q-learning + static potential shaping (Ng 1999), Phi = -scale * Manhattan cells to G."""

    name: ClassVar[str] = "PFH-RL"
    cli: ClassVar[str] = "pfh-rl"
    scale: float = 1.0  # potential per cell of Manhattan distance [reward units / cell]

    def potential(self, geom: Geometry) -> np.ndarray:
        """float64[nS]: Φ of every cell (the static potential this module shapes with)."""
        return pfh_potential(geom, self.scale)


class State(NamedTuple):
    par: BaseParams
    tally: Tally
    q: np.ndarray  # float64[nS, nA]
    phi: np.ndarray  # float64[nS]; the potential (derived from the geometry)


DERIVED = ("phi",)  # rebuilt from config and geometry, never stored in a checkpoint


def manhattan_cells(geom: Geometry) -> np.ndarray:
    """int64[nS]: Manhattan distance to the goal in cells (ignores obstacles)."""
    cells = geom.cells
    return np.abs(cells - cells[geom.goal]).sum(axis=1)


def pfh_potential(geom: Geometry, scale: float) -> np.ndarray:
    """float64[nS]: Phi(s) = -scale * Manhattan cells to G (so Phi(goal) = 0)."""
    return np.ascontiguousarray(-scale * manhattan_cells(geom).astype(np.float64))


def init_state(cfg: PFHRL, geom: Geometry, rng: np.random.Generator) -> State:
    """``cfg.potential``: PFH-RL's Manhattan field, or another static Φ (module docstring)."""
    return State(cfg.params(), new_tally(), np.zeros((geom.n_states, geom.n_actions)),
                 np.ascontiguousarray(cfg.potential(geom), dtype=np.float64))


@njit(**HOOK)
def act(st, s, rng):
    return eps_greedy(st.q, s, st.par.eps, rng)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    gamma = st.par.gamma
    phi = st.phi  # read before the branch (see learning.methods.rnh_ql_plus.rules)
    p2 = 0.0 if terminated else phi[s2]
    f = gamma * p2 - phi[s]
    record_shaping(st.tally.f_sum, st.tally.f_sq, st.tally.n_shaped, f, True)
    q_learning(st.q, s, a, r, s2, terminated, st.par.alpha, gamma, f)


begin = begin_plain
exploit = exploit_q

