"""RNH-QL (``rnh-ql``), the paper's method: a Q-table below, a Gaussian RBF network V_NN
above (:mod:`learning.parts.rbf`), and the Q update shaped by F = gamma * V_NN(s') - V_NN(s).

V_NN is trained by TD(lambda) on the env rewards from the first episode, with traces
cut on non-greedy actions; shaping starts after ``warmup_episodes``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from learning.config import MethodConfig
from learning.geometry import Geometry
from learning.parts import rbf
from learning.parts.tabular import eps_greedy, exploit_q, is_greedy, q_learning
from learning.parts.tally import Tally, begin_tally, new_tally, record_shaping

HOOK = dict(cache=True, inline="always")


@dataclass(frozen=True)
class RNHQL(MethodConfig):
    """RNH-QL: Q-table + Gaussian RBF network V_NN giving dynamic potential shaping.

    V_NN(s) = w . phi(s) over k x k Gaussian centres (cell-centred lattice over
    the arena, width = lattice spacing), trained by TD(lambda) from the first
    episode with traces cut on non-greedy actions (a non-greedy step leaves w
    unchanged). From episode ``warmup_episodes`` on, the Q update adds
    F = gamma * Phi(s') - Phi(s), Phi = V_NN evaluated when a state is entered
    (Devlin & Kudenko 2012), Phi(goal) = 0.

    The V_NN step is ``beta / mean_s |phi(s)|^2`` (normalised LMS): a constant, so
    this is plain linear TD(lambda), and with sigma = spacing |phi|^2 ~ pi, so
    beta = 0.1 moves V(s) by ~10% of the TD error per visit, ~50% with the
    trace's 1/(1 - gamma*lambda) ~ 5 revisits: stable.
    """

    name: ClassVar[str] = "RNH-QL"
    cli: ClassVar[str] = "rnh-ql"
    lam: float = 0.85  # V_NN trace decay lambda
    k: int = 10  # RBF centres per axis (k * k in all), the paper's 10 x 10
    spacing_m: float = 0.0  # > 0: a centre every spacing_m metres per axis instead of k x k
    beta: float = 0.1  # V_NN step per unit of mean squared feature norm
    warmup_episodes: int = 300  # shaping starts at this 0-based episode index
    freeze_after_episodes: int | None = None  # stop training V_NN from this episode (None: never)

    def params(self) -> Params:
        freeze = math.inf if self.freeze_after_episodes is None else self.freeze_after_episodes
        return Params(float(self.eps), float(self.alpha), float(self.gamma), float(self.lam),
                      float(self.warmup_episodes), float(freeze))


class Params(NamedTuple):
    eps: float
    alpha: float
    gamma: float
    lam: float
    warmup: float  # shaping from this episode on
    freeze: float  # V_NN trained before this episode (inf: always)


class State(NamedTuple):
    par: Params
    tally: Tally
    q: np.ndarray  # float64[nS, nA]
    w: np.ndarray  # float64[K]; V_NN weights
    e: np.ndarray  # float64[K]; their traces
    phi: np.ndarray  # float64[nS, K]; the Gaussian features of every state (derived)
    step_v: np.ndarray  # float64[1]; V_NN step size, beta / mean |phi|^2 (derived)
    phi_here: np.ndarray  # float64[1]; the potential cached when the current state was entered
    shaping: np.ndarray  # bool[1]; F is added to the Q update this episode
    train_v: np.ndarray  # bool[1]; V_NN learns this episode


DERIVED = ("phi", "step_v")


def init_state(cfg: RNHQL, geom: Geometry, rng: np.random.Generator) -> State:
    phi = rbf.rbf_features(geom.coords, geom.bounds_m,
                           *rbf.lattice_size(geom.bounds_m, cfg.k, cfg.spacing_m))
    k = phi.shape[1]
    step_v = cfg.beta / float(np.mean(np.sum(phi * phi, axis=1)))
    return State(cfg.params(), new_tally(), np.zeros((geom.n_states, geom.n_actions)),
                 np.zeros(k), np.zeros(k), phi, np.array([step_v]), np.zeros(1),
                 np.zeros(1, np.bool_), np.zeros(1, np.bool_))


@njit(**HOOK)
def act(st, s, rng):
    return eps_greedy(st.q, s, st.par.eps, rng)


@njit(**HOOK)
def update(st, s, a, r, s2, terminated, rng):
    """TD(lambda) on V_NN, then Q-learning + F = gamma*Phi(s') - Phi(s).

    Phi(s') is V_NN(s') evaluated as s' is entered, with the weights before this
    step's V_NN update, and cached (``phi_here``) until s' is left; Phi(goal) = 0.
    """
    p = st.par
    q = st.q
    w = st.w
    e = st.e
    phi = st.phi
    step_v = st.step_v
    phi_here = st.phi_here
    f_sum = st.tally.f_sum
    f_sq = st.tally.f_sq
    n_shaped = st.tally.n_shaped
    shaping = st.shaping[0]
    gamma = p.gamma
    greedy = is_greedy(q, s, a)
    phi_s2 = 0.0 if terminated else rbf.value(phi, s2, w)
    if st.train_v[0]:
        rbf.td_lambda(w, e, phi, s, r, phi_s2, greedy, gamma, p.lam, step_v[0])
    f = 0.0
    if shaping:
        f = gamma * phi_s2 - phi_here[0]
    record_shaping(f_sum, f_sq, n_shaped, f, shaping)
    q_learning(q, s, a, r, s2, terminated, p.alpha, gamma, f)
    phi_here[0] = phi_s2


@njit(**HOOK)
def begin(st, s0):
    """Clear V_NN traces; shaping on from episode ``warmup``; V_NN frozen from ``freeze``;
    cache Phi(s0)."""
    begin_tally(st.tally)
    st.e[:] = 0.0
    ep = st.tally.episode[0]
    st.shaping[0] = ep >= st.par.warmup
    st.train_v[0] = ep < st.par.freeze
    st.phi_here[0] = rbf.value(st.phi, s0, st.w)


exploit = exploit_q


def potential(st: State) -> np.ndarray:
    """float64[nS]: V_NN over every state."""
    return st.phi @ st.w
