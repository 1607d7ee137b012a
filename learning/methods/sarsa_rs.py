"""SARSA-RS (``sarsa-rs``, Grzes & Kudenko 2008): SARSA shaped by a value learned online over
an abstract grid of b x b-cell blocks.

Phi = omega * V(z), V over abstract states learned by SMDP TD: when the abstract
state changes z -> z' after k steps with discounted reward R,
V(z) += alpha_v * (R + gamma^k V(z') - V(z)) (V(z') = 0 on termination).
SARSA draws its next action a' at s' in ``update``; ``act`` then replays it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import MethodConfig, params_tuple
from learning.geometry import Geometry
from learning.parts.tabular import eps_greedy, exploit_q, sarsa
from learning.parts.tally import Tally, begin_tally, new_tally, record_shaping

HOOK = dict(cache=True, inline="always")


Params = params_tuple("Params", __name__, omega=float, alpha_v=float)


@dataclass(frozen=True)
class SarsaRS(MethodConfig):
    """SARSA + shaping Phi = omega * V(z) from an abstract b x b-cell grid (Grzes & Kudenko 2008).

    V over abstract states is learned online by SMDP TD: when the abstract state
    changes z -> z' after k steps with discounted reward R,
    V(z) += alpha_v * (R + gamma^k V(z') - V(z)) (V(z') = 0 on termination).
    """

    name: ClassVar[str] = "SARSA-RS"
    cli: ClassVar[str] = "sarsa-rs"
    block: int = 5  # abstract cell side b [cells]
    omega: float = 1.0  # potential scale omega [dimensionless]
    alpha_v: float = 0.1  # abstract-V learning rate

    params_type: ClassVar[type] = Params


class State(NamedTuple):
    par: Params
    tally: Tally
    q: np.ndarray  # float64[nS, nA]
    v: np.ndarray  # float64[n_z]; the abstract states' values
    z: np.ndarray  # int32[nS]; each state's abstract state (derived from the geometry)
    pending: np.ndarray  # int64[1]; the next action, drawn at the last update (-1: none)
    r_since: np.ndarray  # float64[1]; discounted reward since the abstract state was entered
    g_since: np.ndarray  # float64[1]; gamma^k, k steps since then


DERIVED = ("z",)


def abstract_states(geom: Geometry, block: int) -> tuple[np.ndarray, int]:
    """(z int32[nS], n_z): each cell's block x block abstract cell, row-major."""
    if block < 1:
        raise ValueError(f"SARSA-RS block must be >= 1 cell, got {block}")
    cells = geom.cells
    nbx = -(-(int(cells[:, 0].max()) + 1) // block)
    nby = -(-(int(cells[:, 1].max()) + 1) // block)
    z = (cells[:, 1] // block) * nbx + cells[:, 0] // block
    return np.ascontiguousarray(z.astype(np.int32)), nbx * nby


def init_state(cfg: SarsaRS, geom: Geometry, rng: np.random.Generator) -> State:
    z, n_z = abstract_states(geom, cfg.block)
    return State(cfg.params(), new_tally(), np.zeros((geom.n_states, geom.n_actions)),
                 np.zeros(n_z), z, np.full(1, -1, dtype=np.int64), np.zeros(1), np.ones(1))


@njit(**HOOK)
def act(st, s, rng):
    """Replay the action SARSA chose at its last update (no draws), else epsilon-greedy."""
    pending = st.pending
    a = pending[0]
    if a >= 0:
        pending[0] = -1
        return a
    return eps_greedy(st.q, s, st.par.eps, rng)


@njit(**HOOK)
def _learn(st, s, a, r, s2, a2, terminated):
    """SARSA with F = gamma*omega*V(z(s')) - omega*V(z(s)) (V before this step's update),
    then SMDP TD on the abstract V."""
    p = st.par
    v = st.v
    r_since = st.r_since
    g_since = st.g_since
    zs = st.z[s]
    zs2 = st.z[s2]
    p2 = 0.0 if terminated else p.omega * v[zs2]
    f = p.gamma * p2 - p.omega * v[zs]
    record_shaping(st.tally.f_sum, st.tally.f_sq, st.tally.n_shaped, f, True)
    sarsa(st.q, s, a, r, s2, a2, terminated, p.alpha, p.gamma, f)
    r_since[0] += g_since[0] * r
    g_since[0] *= p.gamma
    if terminated or zs2 != zs:
        target = r_since[0]
        if not terminated:
            target += g_since[0] * v[zs2]
        v[zs] += p.alpha_v * (target - v[zs])
        r_since[0] = 0.0
        g_since[0] = 1.0


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """Draw a' at s' first (unless terminated); SARSA-RS learns with it; act() replays it."""
    q = st.q
    a2 = -1
    if not terminated:
        a2 = eps_greedy(q, s2, st.par.eps, rng)
    _learn(st, s, a, r, s2, a2, terminated)
    st.pending[0] = a2


@njit(**HOOK)
def begin(st, s0):
    begin_tally(st.tally)
    st.pending[0] = -1
    st.r_since[0] = 0.0
    st.g_since[0] = 1.0


exploit = exploit_q

