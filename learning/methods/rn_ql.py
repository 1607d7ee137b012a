"""RN-QL (``rn-ql``): Q from four 2-10-1 sigmoid nets (one per action, :mod:`learning.parts.mlp`)
over the normalised cell centre, learned by Watkins Q(lambda) with gradient traces."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import MethodConfig, params_tuple
from learning.geometry import Geometry
from learning.parts import mlp
from learning.parts.tabular import argmax_first, eps_greedy
from learning.parts.tally import Tally, begin_tally, new_tally

HOOK = dict(cache=True, inline="always")
HIDDEN = 10  # the paper's 2-10-1 nets


Params = params_tuple("Params", __name__, lam=float, q_scale=float)


@dataclass(frozen=True)
class RNQL(MethodConfig):
    """Q from four 2-10-1 sigmoid nets (one per action) over the normalised cell centre.

    Watkins Q(lambda) with gradient traces (accumulating), cut when the action
    taken is non-greedy. The nets predict Q / q_scale: with Q ~ 100 an unscaled
    linear output would need weights ~100, which makes the hidden-layer
    gradients ~100x larger and saturates the sigmoids.
    """

    name: ClassVar[str] = "RN-QL"
    cli: ClassVar[str] = "rn-ql"
    lam: float = 0.85  # trace decay lambda
    q_scale: float = 100.0  # Q = q_scale * net output [reward units]
    init_range: float = 0.5  # initial weights ~ U(-init_range, init_range)

    params_type: ClassVar[type] = Params


class State(NamedTuple):
    par: Params
    tally: Tally
    w: np.ndarray  # float64[nA * (4H + 1)]; the nets' weights (learning.parts.mlp)
    e: np.ndarray  # float64[like w]; their gradient traces
    x: np.ndarray  # float64[nS, 2]; each state's input, the cell centre in [0, 1]^2 (derived)
    row: np.ndarray  # float64[1, nA]; scratch: the nets' outputs at one state
    hidden: np.ndarray  # float64[nA, H]; scratch: their hidden activations there (derived)
    row_of: np.ndarray  # int64[1]; the state whose outputs row and hidden hold for the
    #                     current weights, -1 for none (derived)


DERIVED = ("x", "hidden", "row_of")


def init_state(cfg: RNQL, geom: Geometry, rng: np.random.Generator) -> State:
    """Draws the initial weights from ``rng`` (one ``uniform`` call)."""
    w = mlp.init_weights(geom.n_actions, HIDDEN, cfg.init_range, rng)
    return State(cfg.params(), new_tally(), w, np.zeros_like(w),
                 mlp.normalised_inputs(geom.coords, geom.bounds_m),
                 np.zeros((1, geom.n_actions)), np.zeros((geom.n_actions, HIDDEN)),
                 np.full(1, -1, dtype=np.int64))


@njit(**HOOK)
def act(st, s, rng):
    """Epsilon-greedy on the nets' Q(s, .) (kept for :func:`update` at s)."""
    mlp.net_row(st.w, st.x, s, st.row, st.hidden)
    st.row_of[0] = s
    return eps_greedy(st.row, 0, st.par.eps, rng)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    p = st.par
    mlp.q_lambda_net(st.w, st.e, st.x, s, a, r, s2, terminated, p.alpha, p.gamma, p.lam,
                     p.q_scale, st.row, st.hidden, st.row_of)


@njit(**HOOK)
def begin(st, s0):
    begin_tally(st.tally)
    st.e[:] = 0.0


@njit(**HOOK)
def exploit(st, s):
    mlp.net_row(st.w, st.x, s, st.row, st.hidden)
    st.row_of[0] = s
    return argmax_first(st.row, 0)


@njit(cache=True)
def _net_table(w, x, scratch, hid, out):
    for s in range(out.shape[0]):
        mlp.net_row(w, x, s, scratch, hid)
        out[s, :] = scratch[0, :]


def n_states(st: State) -> int:
    return int(st.x.shape[0])


def q_table(st: State) -> np.ndarray:
    """float64[nS, nA]: the nets evaluated at every state, in reward units."""
    out = np.zeros((st.x.shape[0], st.row.shape[1]))
    _net_table(st.w, st.x, np.zeros_like(st.row), np.zeros_like(st.hidden), out)
    return out * st.par.q_scale
